/* pfflip umbrella header and the PETSc-version shim. */
#pragma once

#include <petscsys.h>

#if PETSC_VERSION_LT(3, 19, 0) && !defined(PETSC_SUCCESS)
#define PETSC_SUCCESS ((PetscErrorCode)0)
#endif

#include <pff/core.h>
#include <pff/grid.h>
#include <pff/particles.h>
#include <pff/pressure.h>
#include <pff/flow.h>
#include <pff/io.h>
#include <pff/scene.h>
#include <pff/tallcell.h>
#include <pff/bodies.h>
