/* fluid: a scene defined entirely in YAML (docs/scenes.md): the grid (-grid_*), the fluids
   (-rho_*, -nu_*, -gravity), liquid regions (-liquid_<i>_*) with initial velocities, gas regions
   carved out of them (-gas_<i>_*) and static solids (-solid_<i>_*); everything else in the domain is
   gas. A dam break, a drop into a pool or rising bubbles need no C.

   Besides the common columns (among them the gas volume V_g = sum (1 - phi) V over the fluid cells,
   PffFlowGetPhaseVolumes) the diagnostics CSV has the mean height of the gas particles,
   y_g = sum_p y_p / N_gas. For bubbles in a closed tank y_g is their mean height, so its growth is the
   mean rise (V_g also counts the thin layer at the walls where the truncated kernel lowers phi, y_g
   does not). The final values are printed to 4 and 6 digits, which do not depend on the rank count. */
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

/* Mean height of the gas particles. Collective. */
static PetscErrorCode PffFluidGasHeight(PffFlowScene *fs, PetscReal *yg)
{
  PetscReal         s[2] = {0, 0}; /* sum of gas particle heights, gas particles */
  PffParticles      p;
  PffParticleArrays a;

  PetscFunctionBeginUser;
  PetscCall(PffFlowGetParticles(fs->flow, &p));
  PetscCall(PffParticlesGetArrays(p, &a));
  for (PetscInt i = 0; i < a.n; i++) {
    if (a.type[i] != PFF_PARTICLE_AIR) continue;
    s[0] += a.x[3 * i + 1];
    s[1] += 1;
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, s, 2, MPIU_REAL, MPI_SUM, fs->scene->comm));
  *yg = s[1] > 0 ? s[0] / s[1] : 0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffFluidDiagnose(PffFlowScene *fs, PetscReal t, char row[], size_t len)
{
  PetscReal yg;

  PetscFunctionBeginUser;
  PetscCall(PffFluidGasHeight(fs, &yg));
  PetscCall(PetscSNPrintf(row, len, ",%.9e", (double)yg));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* the gas volume is the driver's, of the final diagnostics row */
static PetscErrorCode PffFluidFinish(PffFlowScene *fs)
{
  PetscReal yg, t;

  PetscFunctionBeginUser;
  PetscCall(PffFluidGasHeight(fs, &yg));
  PetscCall(PffFlowGetTime(fs->flow, &t, NULL));
  PetscCall(PetscPrintf(fs->scene->comm, "fluid: gas volume %.4e  mean gas particle y %.6e  at t %.4e\n",
                        (double)fs->gasVolume, (double)yg, (double)t));
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
  const PffFlowSceneOps ops = {NULL,           PffFluidSetUp,  PffFluidSeed, ",gas_y_mean", PffFluidDiagnose,
                               PffFluidFinish, PffFluidDestroy};

  PetscFunctionBeginUser;
  PetscCall(PetscNew(&fl));
  PetscCall(PffFlowSceneCreate_Private(s, &ops, fl));
  PetscFunctionReturn(PETSC_SUCCESS);
}
