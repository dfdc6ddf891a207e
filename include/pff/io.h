/* io: HDF5 frames (collective, parallel HDF5) with an XDMF sidecar for ParaView, and their reader.
   The layout is documented in docs/file-format.md. */
#pragma once

#include <pff/grid.h>
#include <pff/particles.h>

/* Writes the channels of grid flagged for output (PffGridSetChannelOutput, default all) to <path> (an
   .h5 file) and <path without .h5>.xmf. The file is
   written under a temporary name and renamed, so an existing frame is never left half-written.
   Attributes: time, step, scene, the full option set, git revision, rank and thread counts,
   library versions. Collective. */
PETSC_EXTERN PetscErrorCode PffIOWriteFrame(PffGrid grid, const char path[], PetscReal time, PetscInt step,
                                            const char scene[]);

/* As PffIOWriteFrame, plus the particles (NULL: none) in the group /particles: x and v in single
   precision (enough for viewing), id, type, level, flags, written collectively at rank offsets. The
   sidecar gets a second grid, a Polyvertex of the particles with their type and velocity. Collective. */
PETSC_EXTERN PetscErrorCode PffIOWriteFrameParticles(PffGrid grid, PffParticles particles, const char path[],
                                                     PetscReal time, PetscInt step, const char scene[]);

/* Checkpoint: every channel (whatever its output flag), the particles (NULL: none) in double precision,
   time, step and the caller's nextra extra real values (e.g. the last dt; rank 0's are stored), written
   to <path>.tmp and renamed, so a run killed while writing leaves the previous checkpoint intact. Root
   attribute checkpoint = 1; no XDMF sidecar. Collective. */
PETSC_EXTERN PetscErrorCode PffIOWriteCheckpoint(PffGrid grid, PffParticles particles, const char path[],
                                                 PetscReal time, PetscInt step, PetscInt nextra,
                                                 const PetscReal extra[], const char scene[]);

/* Restart: reads a checkpoint written on any number of ranks into grid (same raster as PffIOReadFrame
   requires, and every channel of the grid must be in the file) and into the empty particle store
   (NULL: the particles are not read): each rank reads an equal slice of the particle rows, appends
   them with PffParticlesAdd and calls PffParticlesMigrate. nextra must equal the number of extra values
   stored; they go to extra. time, step may be NULL. A missing file, a frame that is not a checkpoint,
   or a mismatch is one error naming the file and what is wrong. Collective. */
PETSC_EXTERN PetscErrorCode PffIOReadCheckpoint(PffGrid grid, PffParticles particles, const char path[],
                                                PetscReal *time, PetscInt *step, PetscInt nextra, PetscReal extra[]);
/* The number of extra values a checkpoint holds (0 when it has none), so that a reader can accept
   checkpoints of an older layout. A file that is not a checkpoint is one error naming it. Collective
   on the grid's communicator. */
PETSC_EXTERN PetscErrorCode PffIOGetCheckpointExtraCount(PffGrid grid, const char path[], PetscInt *nextra);

/* Reads a frame written by PffIOWriteFrame (or a checkpoint) into grid, which must have been set up with
   the same block raster (cells, block size, levels per block); it may run on a different number of
   ranks. Every channel flagged for output must be in the file with the same name and kind; a channel
   not flagged is read when the file has it and left untouched otherwise. Particles are not read. A
   missing file or a mismatch is an error naming it. Collective. */
PETSC_EXTERN PetscErrorCode PffIOReadFrame(PffGrid grid, const char path[], PetscReal *time, PetscInt *step);

/* Reads only the per-block level map of a frame (nb[0]*nb[1]*nb[2] entries, -1 inactive), to build a
   grid that matches the file (PffGridSetRefinementMap). *level is allocated with PetscMalloc1. Collective. */
PETSC_EXTERN PetscErrorCode PffIOReadLevels(MPI_Comm comm, const char path[], PetscInt nb[3], PetscInt **level);
