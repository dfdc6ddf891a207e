/* fluid: a scene defined entirely in YAML (docs/scenes.md): the grid (-grid_*), the fluids
   (-rho_*, -nu_*, -gravity), liquid regions (-liquid_<i>_*) with initial velocities, gas regions
   carved out of them (-gas_<i>_*) and static solids (-solid_<i>_*); everything else in the domain is
   gas. A dam break, a drop into a pool or rising bubbles need no C.

   Besides the common columns the diagnostics CSV has the gas volume V_g = sum (1 - phi) V over the
   cells and the mean height of the gas particles, y_g = sum_p y_p / N_gas. For bubbles in a closed
   tank y_g is their mean height, so its growth is the mean rise (V_g also counts the thin layer at
   the walls where the truncated kernel lowers phi, y_g does not). The final values are printed to 4
   and 6 digits, which do not depend on the rank count. */
#include "flowscene.h"
#include "geometry.h"

typedef struct {
  PffGeometry geo;
} PffFluid;

static PetscErrorCode PffFluidSetUp(PffFlowScene *fs)
{
  PffFluid *fl = (PffFluid *)fs->ctx;
  PetscReal lo[3], hi[3];

  PetscFunctionBeginUser;
  PetscCall(PffFlowSceneDomain(fs, lo, hi));
  PetscCall(PffGeometryCreate(fs->scene->comm, &fl->geo));
  PetscCall(PffGeometrySetFromOptions(fl->geo, lo, hi));
  PetscCheck(PffGeometryNumLiquids(fl->geo) > 0, fs->scene->comm, PETSC_ERR_ARG_WRONG,
             "-liquid_0_type is missing: the fluid scene needs at least one liquid region");
  PetscCall(PffGeometryCheck(fl->geo, fs->grid));
  if (PffGeometryNumSolids(fl->geo) > 0) PetscCall(PffFlowSetSolid(fs->flow, PffGeometrySolidDistance, fl->geo));
  PetscCall(PffGeometryView(fl->geo, NULL));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffFluidSeed(const PetscReal x[3], PetscInt *type, PetscReal v[3], void *ctx)
{
  const PffFluid *fl = (const PffFluid *)ctx;

  PetscFunctionBeginUser;
  v[0] = v[1] = v[2] = 0;
  if (PffGeometryNumSolids(fl->geo) > 0 && PffGeometrySolidDistance(x, NULL, fl->geo) < 0)
    *type = -1;
  else
    *type = PffGeometryLiquidAt(fl->geo, x, v) >= 0 ? PFF_PARTICLE_LIQUID : PFF_PARTICLE_AIR;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Gas volume from the cell phase field and mean height of the gas particles. Collective. */
static PetscErrorCode PffFluidGas(PffFlowScene *fs, PetscReal *vol, PetscReal *yg)
{
  PetscInt          nlocal, chPhi;
  PetscReal         s[3] = {0, 0, 0}; /* gas volume, sum of gas particle heights, gas particles */
  PffParticles      p;
  PffParticleArrays a;

  PetscFunctionBeginUser;
  PetscCall(PffFlowGetChannels(fs->flow, &chPhi, NULL, NULL, NULL));
  PetscCall(PffGridGetLocalBlocks(fs->grid, &nlocal));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    float       *phi;
    PetscCall(PffGridGetBlockInfo(fs->grid, lb, &info));
    PetscCall(PffGridGetBlockData(fs->grid, chPhi, lb, 0, &phi));
    const PetscInt n3 = info.n * info.n * info.n;
    PetscReal      g  = 0;
    for (PetscInt c = 0; c < n3; c++) g += 1 - (PetscReal)phi[c];
    s[0] += g * info.h * info.h * info.h;
  }
  PetscCall(PffFlowGetParticles(fs->flow, &p));
  PetscCall(PffParticlesGetArrays(p, &a));
  for (PetscInt i = 0; i < a.n; i++) {
    if (a.type[i] != PFF_PARTICLE_AIR) continue;
    s[1] += a.x[3 * i + 1];
    s[2] += 1;
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, s, 3, MPIU_REAL, MPI_SUM, fs->scene->comm));
  *vol = s[0];
  *yg  = s[2] > 0 ? s[1] / s[2] : 0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffFluidDiagnose(PffFlowScene *fs, PetscReal t, char row[], size_t len)
{
  PetscReal vol, yg;

  PetscFunctionBeginUser;
  PetscCall(PffFluidGas(fs, &vol, &yg));
  PetscCall(PetscSNPrintf(row, len, ",%.9e,%.9e", (double)vol, (double)yg));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffFluidFinish(PffFlowScene *fs)
{
  PetscReal vol, yg, t;

  PetscFunctionBeginUser;
  PetscCall(PffFluidGas(fs, &vol, &yg));
  PetscCall(PffFlowGetTime(fs->flow, &t, NULL));
  PetscCall(PetscPrintf(fs->scene->comm, "fluid: gas volume %.4e  mean gas particle y %.6e  at t %.4e\n", (double)vol,
                        (double)yg, (double)t));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffFluidDestroy(PffFlowScene *fs)
{
  PffFluid *fl = (PffFluid *)fs->ctx;

  PetscFunctionBeginUser;
  PetscCall(PffGeometryDestroy(&fl->geo));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffSceneCreate_Fluid(PffScene s)
{
  PffFluid             *fl;
  const PffFlowSceneOps ops = {NULL,           PffFluidSetUp,  PffFluidSeed, ",gas_volume,gas_y_mean", PffFluidDiagnose,
                               PffFluidFinish, PffFluidDestroy};

  PetscFunctionBeginUser;
  PetscCall(PetscNew(&fl));
  PetscCall(PffFlowSceneCreate_Private(s, &ops, fl));
  PetscFunctionReturn(PETSC_SUCCESS);
}
