/* still_water: a closed box, liquid below y = level * height and gas above, at rest under gravity.
   The exact solution is u = 0 with a hydrostatic pressure; the scene reports the spurious velocity
   (max |u| on the grid after projection and max particle speed) and the drift of the liquid volume. */
#include "flowscene.h"

typedef struct {
  PetscReal level, ratio, height, v0, umaxRun, check;
  PetscInt  resolution;
} PffStill;

static PetscErrorCode PffStillSetFromOptions(PffFlowScene *fs)
{
  PffStill *sw = (PffStill *)fs->ctx;
  char      buf[128];

  PetscFunctionBeginUser;
  PetscOptionsBegin(fs->scene->comm, NULL, "Still-water scene", "PffScene");
  PetscCall(PffOptionsReal("-still_level", "Liquid depth as a fraction of the box height", NULL, sw->level, &sw->level,
                           NULL));
  PetscCall(PffOptionsReal("-still_max_velocity",
                           "Fail when the spurious velocity exceeds this (0: no check; for tests)", NULL, sw->check,
                           &sw->check, NULL));
  PetscCall(PffOptionsReal("-still_ratio", "Density ratio rho_l / rho_g", NULL, sw->ratio, &sw->ratio, NULL));
  PetscCall(PffOptionsInt("-still_resolution", "Cells per axis of the cubic box", NULL, sw->resolution, &sw->resolution,
                          NULL));
  PetscOptionsEnd();
  PetscCheck(sw->level > 0 && sw->level < 1, fs->scene->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-still_level %g is invalid: must be in (0, 1)", (double)sw->level);
  PetscCheck(sw->ratio > 1, fs->scene->comm, PETSC_ERR_ARG_OUTOFRANGE, "-still_ratio %g is invalid: must exceed 1",
             (double)sw->ratio);
  PetscCheck(sw->resolution >= 8 && sw->resolution % 8 == 0 && sw->resolution <= 4096, fs->scene->comm,
             PETSC_ERR_ARG_OUTOFRANGE,
             "-still_resolution %" PetscInt_FMT " is invalid: must be a multiple of 8 in [8, 4096]", sw->resolution);
  PetscCall(PetscSNPrintf(buf, sizeof(buf), "%" PetscInt_FMT, sw->resolution));
  PetscCall(PffFlowSceneDefault("-grid_cells", buf));
  PetscCall(PffFlowSceneDefaultReal("-grid_h", 1.0 / (PetscReal)sw->resolution));
  PetscCall(PffFlowSceneDefaultReal("-grid_block_size", sw->resolution % 16 == 0 ? 16 : 8));
  PetscCall(PffFlowSceneDefaultReal("-rho_liquid", 1000.0));
  PetscCall(PffFlowSceneDefaultReal("-rho_gas", 1000.0 / sw->ratio));
  PetscCall(PffFlowSceneDefault("-gravity", "0,-9.81,0"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffStillSetUp(PffFlowScene *fs)
{
  PffStill *sw = (PffStill *)fs->ctx;
  PetscReal lo[3], hi[3];

  PetscFunctionBeginUser;
  PetscCall(PffFlowSceneDomain(fs, lo, hi));
  sw->height = hi[1] - lo[1];
  sw->level  = lo[1] + sw->level * sw->height; /* from now on the absolute surface height */
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffStillSeed(const PetscReal x[3], PetscInt *type, PetscReal v[3], void *ctx)
{
  const PffStill *sw = (const PffStill *)ctx;

  PetscFunctionBeginUser;
  *type = x[1] < sw->level ? PFF_PARTICLE_LIQUID : PFF_PARTICLE_AIR;
  v[0] = v[1] = v[2] = 0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffStillDiagnose(PffFlowScene *fs, PetscReal t, char row[], size_t len)
{
  PffStill       *sw   = (PffStill *)fs->ctx;
  const PetscReal umax = fs->umaxGrid, vol = fs->liquidVolume;

  PetscFunctionBeginUser;
  if (sw->v0 == 0) sw->v0 = vol;
  sw->umaxRun = PetscMax(sw->umaxRun, umax);
  PetscCall(PetscSNPrintf(row, len, ",%.6e", (double)((vol - sw->v0) / sw->v0)));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffStillFinish(PffFlowScene *fs)
{
  PffStill       *sw   = (PffStill *)fs->ctx;
  const PetscReal umax = fs->umaxGrid, vol = fs->liquidVolume; /* the final row's */
  PetscReal       t;

  PetscFunctionBeginUser;
  PetscCall(PffFlowGetTime(fs->flow, &t, NULL));
  PetscCall(
      PetscPrintf(fs->scene->comm,
                  "still_water: density ratio %g  max spurious |u| over the run %.3e m/s (last step %.3e)  liquid "
                  "volume drift %.3e  at t %.4f s\n",
                  (double)sw->ratio, (double)sw->umaxRun, (double)umax, (double)((vol - sw->v0) / sw->v0), (double)t));
  PetscCheck(sw->check <= 0 || sw->umaxRun <= sw->check, fs->scene->comm, PETSC_ERR_NOT_CONVERGED,
             "still_water: the spurious velocity %.3e exceeds -still_max_velocity %g", (double)sw->umaxRun,
             (double)sw->check);
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffSceneCreate_StillWater(PffScene s)
{
  PffStill             *sw;
  const PffFlowSceneOps ops = {.setfromoptions = PffStillSetFromOptions,
                               .setup          = PffStillSetUp,
                               .seed           = PffStillSeed,
                               .diagHeader     = ",volume_drift",
                               .diagnose       = PffStillDiagnose,
                               .finish         = PffStillFinish};

  PetscFunctionBeginUser;
  PetscCall(PetscNew(&sw));
  sw->level      = 0.5;
  sw->ratio      = 1000;
  sw->resolution = 32;
  PetscCall(PffFlowSceneCreate_Private(s, &ops, sw));
  ((PffFlowScene *)s->data)->tEnd = 1;
  PetscFunctionReturn(PETSC_SUCCESS);
}
