/* Private helpers of the io module: the HDF5 checking macro, attribute helpers, the property lists
   of a collective frame, and the Morton layout of a frame that the writer, the XDMF sidecar and the
   reader share. Only src/io/ (and the io unit test) include this. */
#pragma once

#include <pff.h>
#include <pff/particles.h>
#include <hdf5.h>

#define PFF_FRAME_FORMAT "pfflip-frame"
#define PFF_FRAME_FORMAT_VERSION 1

#if defined(PETSC_USE_64BIT_INDICES)
#define PFF_H5T_NATIVE_PETSCINT H5T_NATIVE_INT64
#else
#define PFF_H5T_NATIVE_PETSCINT H5T_NATIVE_INT32
#endif
#if defined(PETSC_USE_REAL_SINGLE)
#define PFF_H5T_NATIVE_PETSCREAL H5T_NATIVE_FLOAT
#else
#define PFF_H5T_NATIVE_PETSCREAL H5T_NATIVE_DOUBLE
#endif

/* Innermost description on the HDF5 error stack (the most specific one), or "" when it is empty. */
PETSC_INTERN void PffHDF5ErrorMessage_Private(char buf[], size_t len);

/* HDF5 returns a negative value (herr_t, hid_t, htri_t) on failure. Automatic printing is switched
   off (PffIOInitialize_Private), so the message of the innermost HDF5 error goes into the PETSc error
   instead. Use with an assignment to keep a handle: PffCallHDF5(fid = H5Fopen(...)). */
#define PffCallHDF5(...)                                                                                               \
  do {                                                                                                                 \
    if (PetscUnlikely((__VA_ARGS__) < 0)) {                                                                            \
      char pff_h5msg_[256];                                                                                            \
      PffHDF5ErrorMessage_Private(pff_h5msg_, sizeof(pff_h5msg_));                                                     \
      SETERRQ(PETSC_COMM_SELF, PETSC_ERR_LIB, "HDF5 call failed: %s: %s", #__VA_ARGS__, pff_h5msg_);                   \
    }                                                                                                                  \
  } while (0)

/* Switches off HDF5's own error printing (the errors reach PETSc through PffCallHDF5). Idempotent. */
PETSC_INTERN PetscErrorCode PffIOInitialize_Private(void);
/* The communicator of the grid's ranks. */
PETSC_INTERN PetscErrorCode PffIOGetComm_Private(PffGrid grid, MPI_Comm *comm);
/* Collective: fails on every rank with "cannot open frame <path>: ..." unless rank 0 can read path. */
PETSC_INTERN PetscErrorCode PffIOCheckReadable_Private(MPI_Comm comm, const char path[]);
/* File access list for the MPI-IO driver on comm with collective metadata, and a collective transfer list. */
PETSC_INTERN PetscErrorCode PffIOCreateAccessList_Private(MPI_Comm comm, hid_t *fapl);
PETSC_INTERN PetscErrorCode PffIOCreateTransferList_Private(hid_t *dxpl);

/* Attributes. n = 0 writes a scalar, n > 0 a 1-D array of n values. Strings are fixed-length,
   null-terminated ASCII. Every rank of the file's communicator must pass the same values. */
PETSC_INTERN PetscErrorCode PffH5WriteAttribute_Private(hid_t obj, const char name[], hid_t filetype, hid_t memtype,
                                                        hsize_t n, const void *buf);
PETSC_INTERN PetscErrorCode PffH5WriteAttributeString_Private(hid_t obj, const char name[], const char value[]);
/* Reads n values (n = 0: a scalar) converted to memtype; *found is false (and buf untouched) when the
   attribute is missing or holds a different number of values. */
PETSC_INTERN PetscErrorCode PffH5ReadAttribute_Private(hid_t obj, const char name[], hid_t memtype, hsize_t n,
                                                       void *buf, PetscBool *found);
/* Reads a string attribute (fixed or variable length) into a PetscMalloc'ed string, or NULL when it is
   missing or not a string. The caller frees it with PetscFree. */
PETSC_INTERN PetscErrorCode PffH5ReadAttributeString_Private(hid_t obj, const char name[], char **value);
/* Creates a contiguous dataset without fill (every element is written once). */
PETSC_INTERN PetscErrorCode PffH5CreateDataset_Private(hid_t loc, const char name[], hid_t filetype, int rank,
                                                       const hsize_t dims[], hid_t *dset);

/* Where each active block of the grid lives in a frame: Morton position p (0..nactive-1) in the
   /blocks datasets and cells [offset[p], offset[p+1]) in the /fields datasets. Every rank derives
   it from the replicated raster; the owned blocks are listed in Morton order, grouped into runs of
   consecutive positions (one hyperslab each). */
typedef struct {
  PetscInt        nactive;
  const PetscInt *order;  /* [nactive] gids in Morton order, borrowed from the grid */
  PetscInt64     *offset; /* [nactive + 1] first cell of each block in the field datasets */
  PetscInt        nlocal;
  PetscInt       *lpos;   /* [nlocal] Morton position of the owned blocks, increasing */
  PetscInt       *lb;     /* [nlocal] local index of the same block */
  PetscInt       *ln;     /* [nlocal] cells per axis of the same block */
  PetscInt64      ncells; /* owned cells */
  PetscInt        nruns;
  PetscInt       *run; /* [nruns + 1] runs of owned blocks: lpos[run[r]] .. lpos[run[r + 1] - 1] are consecutive */
} PffFrameLayout;

PETSC_INTERN PetscErrorCode PffIOLayoutCreate_Private(PffGrid grid, PffFrameLayout *layout);
PETSC_INTERN PetscErrorCode PffIOLayoutDestroy_Private(PffFrameLayout *layout);
/* Selects the owned blocks' rows in a dataspace of nactive rows (1-D, or 2-D with whole rows). */
PETSC_INTERN PetscErrorCode PffIOSelectBlocks_Private(const PffFrameLayout *layout, hid_t space);
/* Selects the owned blocks' cells in a 1-D dataspace of offset[nactive] cells. */
PETSC_INTERN PetscErrorCode PffIOSelectCells_Private(const PffFrameLayout *layout, hid_t space);
/* A 1-D memory dataspace of n elements, all selected (none when n = 0). */
PETSC_INTERN PetscErrorCode PffIOCreateMemSpace_Private(hsize_t n, hsize_t ncol, hid_t *space);

/* Name of the field dataset of component comp of a channel: name for a cell channel, name_x/_y/_z for a face channel.
 */
PETSC_INTERN PetscErrorCode PffIOFieldName_Private(const char name[], PffChannelKind kind, PetscInt comp, char buf[],
                                                   size_t len);

/* Writes the XDMF sidecar xmfpath describing the frame whose final name has basename h5name; rank 0 only.
   Lists the channels flagged for output, and a Polyvertex grid of the nparticles particles of
   /particles (single precision) when nparticles > 0.
 *err receives 0 or the errno of a failed file operation (the caller reports it collectively). */
PETSC_INTERN PetscErrorCode PffIOWriteXdmf_Private(PffGrid grid, const PffFrameLayout *layout, const char xmfpath[],
                                                   const char h5name[], PetscReal time, PetscInt64 nparticles,
                                                   int *err);

/* The /particles group (particles.c): x, v (N x 3; float64 when dbl, else float32), id, type, level,
   flags, and the attribute count = N; each rank writes its rows at the exclusive prefix sum of the
   local counts. *count receives N. Collective on comm. */
PETSC_INTERN PetscErrorCode PffIOWriteParticles_Private(PffParticles particles, MPI_Comm comm, hid_t file, hid_t dxpl,
                                                        PetscBool dbl, PetscInt64 *count);
/* Checks the /particles group of path; msg stays empty when it is complete and consistent. The same
   result on every rank (collective metadata). */
PETSC_INTERN PetscErrorCode PffIOCheckParticles_Private(hid_t file, const char path[], PetscInt64 *count, char msg[],
                                                        size_t len);
/* Reads an equal slice of the count rows of /particles on each rank, checks type and level against
   grid (one collective error naming the first bad row), appends them to the (empty) store and migrates
   them to their owners. Collective on comm. */
PETSC_INTERN PetscErrorCode PffIOReadParticles_Private(PffParticles particles, PffGrid grid, MPI_Comm comm, hid_t file,
                                                       const char path[], hid_t dxpl, PetscInt64 count);
