/* fluid: a scene defined entirely in YAML (docs/scenes.md): the grid (-grid_*), the fluids
   (-rho_*, -nu_*, -gravity), liquid regions (-liquid_<i>_*) with initial velocities and static
   solids (-solid_<i>_*); everything else in the domain is gas. A dam break or a drop into a pool
   needs no C. */
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
  const PffFlowSceneOps ops = {NULL, PffFluidSetUp, PffFluidSeed, NULL, NULL, NULL, PffFluidDestroy};

  PetscFunctionBeginUser;
  PetscCall(PetscNew(&fl));
  PetscCall(PffFlowSceneCreate_Private(s, &ops, fl));
  PetscFunctionReturn(PETSC_SUCCESS);
}
