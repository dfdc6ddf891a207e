/* Private scene interface: each scene fills these hooks; only src/scenes/ includes this. */
#pragma once

#include <pff.h>

typedef struct {
  PetscErrorCode (*setfromoptions)(PffScene);
  PetscErrorCode (*run)(PffScene);
  PetscErrorCode (*destroy)(PffScene);
} PffSceneOps;

struct _n_PffScene {
  MPI_Comm    comm;
  char        name[64];
  char        outdir[PETSC_MAX_PATH_LEN];
  PffSceneOps ops;
  void       *data;
};

/* Creates -output_dir and checks it on every rank. A scene's run calls it once its input (a restart
   checkpoint included) has been read, so that bad input leaves nothing behind. Collective. */
PETSC_INTERN PetscErrorCode PffSceneMakeOutputDir_Private(PffScene);
PETSC_INTERN PetscErrorCode PffSceneCreate_GridDemo(PffScene);
PETSC_INTERN PetscErrorCode PffSceneCreate_RT3D(PffScene);
PETSC_INTERN PetscErrorCode PffSceneCreate_RTPaper(PffScene);
PETSC_INTERN PetscErrorCode PffSceneCreate_StillWater(PffScene);
PETSC_INTERN PetscErrorCode PffSceneCreate_ShearSphere(PffScene);
PETSC_INTERN PetscErrorCode PffSceneCreate_Fluid(PffScene);
