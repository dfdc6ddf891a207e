/* fluid: a scene defined entirely in YAML (docs/scenes.md): the grid (-grid_*), the fluids
   (-rho_*, -nu_*, -gravity), liquid regions (-liquid_<i>_*) with initial velocities, gas regions
   carved out of them (-gas_<i>_*) and static solids (-solid_<i>_*); everything else in the domain is
   gas. A dam break, a drop into a pool or rising bubbles need no C.

   Besides the common columns (among them the gas volume V_g = sum (1 - phi) V over the fluid cells,
   PffFlowGetPhaseVolumes) the diagnostics CSV has the mean height of the gas particles,
   y_g = sum_p y_p / N_gas. For bubbles in a closed tank y_g is their mean height, so its growth is the
   mean rise (V_g also counts the thin layer at the walls where the truncated kernel lowers phi, y_g
   does not). The final values are printed to 4 and 6 digits, which do not depend on the rank count.
   Then where the liquid is (PffFlowGetLiquidExtent): the largest x and y of a cell with phi >= 1/2 (a
   dam break's front, a splash's crest) and the liquid centroid.

   Static multi-level grids (-fluid_refine surface): the finest level follows the initial liquid
   surface and the level grows by one every -fluid_refine_band block lengths away from it, as
   -grid_refine does for a plane or a sphere:

     level(block) = min(L - 1, floor(dist(block, surface) / (band * block length))),

   with dist a lower bound from PffGeometryLiquidBoxDistance (the CSG signed distance of the liquid
   and gas regions, faces on the domain walls excluded), so a block is never coarser than the exact
   distance asks. The raster then gets the grid's 2:1 grading. Every rank evaluates the same pure
   function of the block box, so the raster does not depend on the rank count. */
#include "flowscene.h"
#include "geometry.h"

typedef enum { PFF_FLUID_REFINE_NONE, PFF_FLUID_REFINE_SURFACE } PffFluidRefineType;
static const char *const PffFluidRefineTypes[] = {"none", "surface", "PffFluidRefineType", "PFF_FLUID_REFINE_", NULL};

typedef struct {
  PffGeometry        geo;
  PffFluidRefineType refine;
  PetscReal          band; /* width of a level band, in block lengths */
} PffFluid;

static PetscErrorCode PffFluidSetFromOptions(PffFlowScene *fs)
{
  PffFluid *fl     = (PffFluid *)fs->ctx;
  PetscEnum refine = (PetscEnum)fl->refine;
  PetscBool bandSet;

  PetscFunctionBeginUser;
  PetscOptionsBegin(fs->scene->comm, NULL, "Fluid scene", "PffScene");
  PetscCall(PffOptionsEnum("-fluid_refine",
                           "Static refinement: none, or surface (finest level at the initial liquid surface, one "
                           "level coarser every -fluid_refine_band block lengths away from it, up to -grid_levels)",
                           NULL, PffFluidRefineTypes, refine, &refine, NULL));
  PetscCall(PffOptionsReal("-fluid_refine_band", "Width of each level band, in block lengths (-fluid_refine surface)",
                           NULL, fl->band, &fl->band, &bandSet));
  PetscOptionsEnd();
  fl->refine = (PffFluidRefineType)refine;
  PetscCheck(fl->band > 0 && PetscIsNormalReal(fl->band), fs->scene->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-fluid_refine_band %g is invalid: must be positive", (double)fl->band);
  PetscCheck(!bandSet || fl->refine == PFF_FLUID_REFINE_SURFACE, fs->scene->comm, PETSC_ERR_ARG_WRONG,
             "-fluid_refine_band has no effect without -fluid_refine surface");
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The PffRefineFn of -fluid_refine surface (ctx = the PffFluid). */
static PetscErrorCode PffFluidRefine(PffGrid grid, const PetscReal lo[3], const PetscReal hi[3], PetscInt *level,
                                     void *ctx)
{
  const PffFluid *fl = (const PffFluid *)ctx;
  PetscInt        nlevels;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetSizes(grid, NULL, &nlevels, NULL, NULL, NULL));
  const PetscReal band = fl->band * (hi[0] - lo[0]), coarsest = (PetscReal)(nlevels - 1);
  const PetscReal dist = PffGeometryLiquidBoxDistance(fl->geo, lo, hi, coarsest * band);
  *level               = (PetscInt)PetscMin(coarsest, PetscFloorReal(dist / band));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The geometry is read before the grid is set up, because -fluid_refine surface places the levels
   by it; its checks on the seed lattice wait for the grid (PffFluidSetUp). */
static PetscErrorCode PffFluidGridSetUp(PffFlowScene *fs)
{
  PffFluid *fl = (PffFluid *)fs->ctx;
  PetscReal lo[3], hi[3];

  PetscFunctionBeginUser;
  PetscCall(PffFlowSceneDomain(fs, lo, hi));
  PetscCall(PffGeometryCreate(fs->scene->comm, &fl->geo));
  PetscCall(PffGeometrySetFromOptions(fl->geo, lo, hi));
  PetscCheck(PffGeometryNumLiquids(fl->geo) > 0, fs->scene->comm, PETSC_ERR_ARG_WRONG,
             "-liquid_0_type is missing: the fluid scene needs at least one liquid region");
  if (fl->refine == PFF_FLUID_REFINE_SURFACE) {
    PetscEnum gridRefine = (PetscEnum)PFF_REFINE_NONE;
    PetscBool set;
    PetscCall(PetscOptionsGetEnum(NULL, NULL, "-grid_refine", PffRefineTypes, &gridRefine, &set));
    PetscCheck(!set || gridRefine == (PetscEnum)PFF_REFINE_NONE, fs->scene->comm, PETSC_ERR_ARG_INCOMP,
               "-fluid_refine surface conflicts with -grid_refine %s: choose one refinement",
               PffRefineTypes[gridRefine]);
    PetscCall(PffGridSetRefinementFunction(fs->grid, PffFluidRefine, fl));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffFluidSetUp(PffFlowScene *fs)
{
  PffFluid *fl = (PffFluid *)fs->ctx;

  PetscFunctionBeginUser;
  PetscCall(PffGeometryCheck(fl->geo, fs->grid));
  if (PffGeometryNumSolids(fl->geo) > 0) PetscCall(PffFlowSetSolid(fs->flow, PffGeometrySolidDistance, fl->geo));
  PetscCall(PffGeometryView(fl->geo, NULL));
  if (fl->refine == PFF_FLUID_REFINE_SURFACE)
    PetscCall(PetscPrintf(fs->scene->comm,
                          "fluid: static refinement at the initial liquid surface, one level per %g block lengths\n",
                          (double)fl->band));
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
    if (PffParticleWordType(a.word[i]) != PFF_PARTICLE_AIR) continue;
    s[0] += a.origin[1] + a.h0 * (PetscReal)a.x[3 * i + 1];
    s[1] += 1;
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, s, 2, MPIU_REAL, MPI_SUM, fs->scene->comm));
  *yg = s[1] > 0 ? s[0] / s[1] : 0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffFluidDiagnose(PffFlowScene *fs, PetscReal t, char row[], size_t len)
{
  PetscReal yg, front[2], c[3];

  PetscFunctionBeginUser;
  PetscCall(PffFluidGasHeight(fs, &yg));
  PetscCall(PffFlowGetLiquidExtent(fs->flow, front, c));
  PetscCall(PetscSNPrintf(row, len, ",%.9e,%.9e,%.9e,%.9e,%.9e,%.9e", (double)yg, (double)front[0], (double)front[1],
                          (double)c[0], (double)c[1], (double)c[2]));
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
  const PffFlowSceneOps ops = {.setfromoptions = PffFluidSetFromOptions,
                               .gridsetup      = PffFluidGridSetUp,
                               .setup          = PffFluidSetUp,
                               .seed           = PffFluidSeed,
                               .diagHeader     = ",gas_y_mean,liquid_x_max,liquid_y_max,liquid_cx,liquid_cy,liquid_cz",
                               .diagnose       = PffFluidDiagnose,
                               .finish         = PffFluidFinish,
                               .destroy        = PffFluidDestroy};

  PetscFunctionBeginUser;
  PetscCall(PetscNew(&fl));
  fl->refine = PFF_FLUID_REFINE_NONE;
  fl->band   = 1;
  PetscCall(PffFlowSceneCreate_Private(s, &ops, fl));
  PetscFunctionReturn(PETSC_SUCCESS);
}
