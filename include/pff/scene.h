/* scenes: the registry of named set-ups that the driver runs (-scene <name>). */
#pragma once

#include <pff/grid.h>

typedef struct _n_PffScene *PffScene;

/* Creates the scene named by -scene (default grid_demo) and reads its options. Collective. */
PETSC_EXTERN PetscErrorCode PffSceneCreate(MPI_Comm comm, PffScene *scene);
PETSC_EXTERN PetscErrorCode PffSceneSetFromOptions(PffScene scene);
/* Builds the grid and fields, runs the steps with output, prints the summary. Collective. */
PETSC_EXTERN PetscErrorCode PffSceneRun(PffScene scene);
PETSC_EXTERN PetscErrorCode PffSceneDestroy(PffScene *scene);
