/* io: HDF5 frames (collective, parallel HDF5) with an XDMF sidecar for ParaView, and their reader.
   The layout is documented in docs/file-format.md. */
#pragma once

#include <pff/grid.h>

/* Writes every channel of grid to <path> (an .h5 file) and <path without .h5>.xmf. The file is
   written under a temporary name and renamed, so an existing frame is never left half-written.
   Attributes: time, step, scene, the full option set, git revision, rank and thread counts,
   library versions. Collective. */
PETSC_EXTERN PetscErrorCode PffIOWriteFrame(PffGrid grid, const char path[], PetscReal time, PetscInt step,
                                            const char scene[]);

/* Reads a frame written by PffIOWriteFrame into grid, which must have been set up with the same
   block raster (cells, block size, levels per block) and the same channels (name, kind); it may run
   on a different number of ranks. A missing file or a mismatch is an error naming it. Collective. */
PETSC_EXTERN PetscErrorCode PffIOReadFrame(PffGrid grid, const char path[], PetscReal *time, PetscInt *step);

/* Reads only the per-block level map of a frame (nb[0]*nb[1]*nb[2] entries, -1 inactive), to build a
   grid that matches the file (PffGridSetRefinementMap). *level is allocated with PetscMalloc1. Collective. */
PETSC_EXTERN PetscErrorCode PffIOReadLevels(MPI_Comm comm, const char path[], PetscInt nb[3], PetscInt **level);
