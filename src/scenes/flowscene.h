/* The shared driver of the fluid scenes: grid and flow set-up, the time loop with progress line and
   per-step CSV diagnostics, frames, checkpoints and the run summary. A scene fills the hooks. */
#pragma once

#include "sceneimpl.h"

typedef struct _PffFlowScene PffFlowScene;

typedef struct {
  /* set defaults of grid/flow options in the database (only where the user set none) and read the
     scene's own options; called before the grid and flow read theirs */
  PetscErrorCode (*setfromoptions)(PffFlowScene *);
  /* after the grid has read its options and before it is set up: what shapes the raster, such as a
     refinement function (PffGridSetRefinementFunction); PffFlowSceneDomain already works here */
  PetscErrorCode (*gridsetup)(PffFlowScene *);
  /* after the grid is set up: the seeding function and anything else (solids, prescribed velocity) */
  PetscErrorCode (*setup)(PffFlowScene *);
  PffSeedFn seed;
  /* extra CSV columns: header names (comma separated, leading comma) and one row's values */
  const char *diagHeader;
  PetscErrorCode (*diagnose)(PffFlowScene *, PetscReal t, char row[], size_t len);
  /* after the last step, once the final diagnostics row is written: final measurements to stdout */
  PetscErrorCode (*finish)(PffFlowScene *);
  /* frees what ctx owns (ctx itself is freed by the driver); may be NULL */
  PetscErrorCode (*destroy)(PffFlowScene *);
} PffFlowSceneOps;

struct _PffFlowScene {
  PffScene        scene;
  PffGrid         grid;
  PffFlow         flow;
  PffFlowSceneOps ops;
  void           *ctx; /* the scene's own data (PetscMalloc'ed; freed by the driver) */

  PetscReal tEnd, outputInterval, timeUnit;
  PetscInt  maxSteps, checkpointEvery;
  PetscBool frames, frameParticles, restarted, checkParticles;
  PetscBool countsCarried; /* the run-start particle counts came from the checkpoint */
  char      restart[PETSC_MAX_PATH_LEN];
  FILE     *diag;
  /* of the latest diagnostics row: max |u| on the grid (PffFlowGetDiagnostics), liquid and gas volume of
     the fluid cells (PffFlowGetPhaseVolumes) */
  PetscReal umaxGrid, liquidVolume, gasVolume;
  /* particle bookkeeping of this run (since the seed or the restart): counts per type at the start
     and at the end, and the gas particles deleted as bubbles in between; set before ops.finish */
  PetscInt64 countStart[PFF_PARTICLE_NTYPES], countEnd[PFF_PARTICLE_NTYPES], bubblesDeletedRun;
  /* narrow-band FLIP: particles deleted below the band and reseeded in it over this run (countStart[liquid] follows
     their difference, so that the count stays exact) */
  PetscInt64 bandDeletedRun, bandSeededRun;
  PetscReal  massStart[PFF_PARTICLE_NTYPES], massEnd[PFF_PARTICLE_NTYPES]; /* particle mass per type */
  /* volume bookkeeping per phase (index PFF_PARTICLE_LIQUID, PFF_PARTICLE_AIR), since the seed: the
     reference volumes V0 (after the seed; carried through checkpoints), the relative drift (V - V0) / V0
     of the latest row, its max |.| over the rows so far (also carried through checkpoints) and the
     bounds -sim_max_volume_drift and -sim_max_gas_volume_drift (0: no check) */
  PetscReal volumeStart[PFF_PARTICLE_NTYPES], drift[PFF_PARTICLE_NTYPES], driftMax[PFF_PARTICLE_NTYPES];
  PetscReal driftBound[PFF_PARTICLE_NTYPES];
};

/* Sets option key to value when the user has not set it (scene defaults derived from physics). */
PETSC_INTERN PetscErrorCode PffFlowSceneDefault(const char key[], const char value[]);
PETSC_INTERN PetscErrorCode PffFlowSceneDefaultReal(const char key[], PetscReal value);
PETSC_INTERN PetscErrorCode PffFlowSceneCreate_Private(PffScene, const PffFlowSceneOps *, void *ctx);
/* Domain box of the grid (also before PffGridSetUp). */
PETSC_INTERN PetscErrorCode PffFlowSceneDomain(PffFlowScene *, PetscReal lo[3], PetscReal hi[3]);
