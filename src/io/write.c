/* PffIOWriteFrame, PffIOWriteFrameParticles (Output stage) and PffIOWriteCheckpoint (restart): one
   HDF5 file per frame or checkpoint, written collectively with MPI-IO by one worker, PffIOWriteFile.
   A frame holds the channels flagged for output (PffGridSetChannelOutput) and, optionally, the
   particles in single precision; a checkpoint holds every channel, the particles in double precision
   and the caller's extra values, and has no XDMF sidecar. The particle group is written in particles.c.

   Every rank writes the rows and cells of the blocks it owns, at their Morton positions (layout.c),
   so the file is the same on any number of ranks except /blocks/owner and the mpi_ranks attribute.
   The file is written as <path>.tmp and renamed by rank 0 once every rank has closed it, and the XDMF
   sidecar likewise, so a crash never leaves a half-written frame under the final name. The layout is
   documented in docs/file-format.md. */
#include <errno.h>
#if defined(__GLIBC__)
#include <malloc.h>
#endif
#include <stdio.h>
#include <string.h>
#if defined(_OPENMP)
#include <omp.h>
#endif
#include "h5util.h"

#if !defined(PFF_GIT_REVISION)
#define PFF_GIT_REVISION "unknown"
#endif

/* Attributes must be identical on every rank, so rank 0's strings are broadcast. *s is PetscMalloc'ed
   on every rank afterwards. */
static PetscErrorCode PffIOBcastString(MPI_Comm comm, char **s)
{
  PetscMPIInt rank, n;
  size_t      len = 0;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) PetscCall(PetscStrlen(*s, &len));
  PetscCallMPI(MPI_Bcast(&len, sizeof(len), MPI_BYTE, 0, comm));
  if (rank != 0) PetscCall(PetscCalloc1(len + 1, s));
  PetscCall(PetscMPIIntCast(len + 1, &n));
  PetscCallMPI(MPI_Bcast(*s, n, MPI_CHAR, 0, comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* What a frame file holds besides the grid; a plain frame is {NULL, PETSC_FALSE, 0, NULL}. */
typedef struct {
  PffParticles     particles;  /* NULL: no /particles group */
  PetscBool        checkpoint; /* every channel, float64 particles, root attribute checkpoint = 1, no sidecar */
  PetscInt         nextra;     /* checkpoint only: the caller's extra values */
  const PetscReal *extra;
} PffIOWriteOptions;

static PetscErrorCode PffIOWriteRootAttributes(MPI_Comm comm, hid_t file, PetscReal time, PetscInt step,
                                               const char scene[], const PffIOWriteOptions *o)
{
  char       *options = NULL, *versions = NULL, *scn = NULL;
  double      t  = (double)time;
  PetscInt64  st = step;
  PetscMPIInt rank, size;
  int         threads = 1, fmtversion = PFF_FRAME_FORMAT_VERSION;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCallMPI(MPI_Comm_size(comm, &size));
  if (rank == 0) {
    PetscCall(PetscOptionsGetAll(NULL, &options));
    PetscCall(PetscMalloc1(1024, &versions));
    PetscCall(PffGetVersionString(versions, 1024));
    PetscCall(PetscStrallocpy(scene ? scene : "", &scn));
#if defined(_OPENMP)
    threads = omp_get_max_threads();
#endif
  }
  PetscCall(PffIOBcastString(comm, &options));
  PetscCall(PffIOBcastString(comm, &versions));
  PetscCall(PffIOBcastString(comm, &scn));
  PetscCallMPI(MPI_Bcast(&t, 1, MPI_DOUBLE, 0, comm));
  PetscCallMPI(MPI_Bcast(&st, 1, MPI_INT64_T, 0, comm));
  PetscCallMPI(MPI_Bcast(&threads, 1, MPI_INT, 0, comm));

  PetscCall(PffH5WriteAttributeString_Private(file, "format", PFF_FRAME_FORMAT));
  PetscCall(PffH5WriteAttribute_Private(file, "format_version", H5T_STD_I32LE, H5T_NATIVE_INT, 0, &fmtversion));
  PetscCall(PffH5WriteAttribute_Private(file, "time", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 0, &t));
  PetscCall(PffH5WriteAttribute_Private(file, "step", H5T_STD_I64LE, H5T_NATIVE_INT64, 0, &st));
  PetscCall(PffH5WriteAttributeString_Private(file, "scene", scn));
  PetscCall(PffH5WriteAttributeString_Private(file, "options", options));
  PetscCall(PffH5WriteAttributeString_Private(file, "git_revision", PFF_GIT_REVISION));
  PetscCall(PffH5WriteAttributeString_Private(file, "versions", versions));
  PetscCall(PffH5WriteAttribute_Private(file, "mpi_ranks", H5T_STD_I32LE, H5T_NATIVE_INT, 0, &size));
  PetscCall(PffH5WriteAttribute_Private(file, "omp_threads", H5T_STD_I32LE, H5T_NATIVE_INT, 0, &threads));
  if (o->checkpoint) {
    const int   one = 1;
    PetscMPIInt nextra;
    double     *extra;

    PetscCall(PetscMPIIntCast(o->nextra, &nextra));
    PetscCall(PffH5WriteAttribute_Private(file, "checkpoint", H5T_STD_I32LE, H5T_NATIVE_INT, 0, &one));
    PetscCall(PffH5WriteAttribute_Private(file, "nextra", H5T_STD_I32LE, H5T_NATIVE_INT, 0, &nextra));
    if (nextra > 0) {
      /* Rank 0's values, so that every rank writes the same attribute. */
      PetscCall(PetscMalloc1(nextra, &extra));
      for (int i = 0; i < nextra; i++) extra[i] = (double)o->extra[i];
      PetscCallMPI(MPI_Bcast(extra, nextra, MPI_DOUBLE, 0, comm));
      PetscCall(PffH5WriteAttribute_Private(file, "extra", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, (hsize_t)nextra, extra));
      PetscCall(PetscFree(extra));
    }
  }
  PetscCall(PetscFree(options));
  PetscCall(PetscFree(versions));
  PetscCall(PetscFree(scn));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* /grid: the parameters and the full level raster, which rank 0 writes (the others select nothing). */
static PetscErrorCode PffIOWriteGridGroup(PffGrid grid, MPI_Comm comm, hid_t file, hid_t dxpl)
{
  const PetscInt *level;
  PetscInt        nb[3], n0, nlevels;
  PetscReal       origin[3], h0;
  PetscBool       periodic[3];
  PetscMPIInt     rank;
  hid_t           group, dset, fspace, mspace;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCall(PffGridGetRaster(grid, nb, &level, NULL));
  PetscCall(PffGridGetSizes(grid, &n0, &nlevels, origin, &h0, periodic));
  const int        bs = (int)n0, nl = (int)nlevels, per[3] = {periodic[0], periodic[1], periodic[2]};
  const double     org[3] = {(double)origin[0], (double)origin[1], (double)origin[2]}, h = (double)h0;
  const PetscInt64 raster[3] = {nb[0], nb[1], nb[2]};
  const hsize_t    nblocks   = (hsize_t)nb[0] * (hsize_t)nb[1] * (hsize_t)nb[2];

  PffCallHDF5(group = H5Gcreate2(file, "grid", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  PetscCall(PffH5WriteAttribute_Private(group, "block_size", H5T_STD_I32LE, H5T_NATIVE_INT, 0, &bs));
  PetscCall(PffH5WriteAttribute_Private(group, "levels", H5T_STD_I32LE, H5T_NATIVE_INT, 0, &nl));
  PetscCall(PffH5WriteAttribute_Private(group, "origin", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 3, org));
  PetscCall(PffH5WriteAttribute_Private(group, "h0", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 0, &h));
  PetscCall(PffH5WriteAttribute_Private(group, "periodic", H5T_STD_I32LE, H5T_NATIVE_INT, 3, per));
  PetscCall(PffH5WriteAttribute_Private(group, "raster", H5T_STD_I64LE, H5T_NATIVE_INT64, 3, raster));

  PetscCall(PffH5CreateDataset_Private(group, "level", H5T_STD_I32LE, 1, &nblocks, &dset));
  PffCallHDF5(fspace = H5Dget_space(dset));
  PetscCall(PffIOCreateMemSpace_Private(rank == 0 ? nblocks : 0, 0, &mspace));
  if (rank != 0) PffCallHDF5(H5Sselect_none(fspace));
  PffCallHDF5(H5Dwrite(dset, PFF_H5T_NATIVE_PETSCINT, mspace, fspace, dxpl, level));
  PffCallHDF5(H5Sclose(mspace));
  PffCallHDF5(H5Sclose(fspace));
  PffCallHDF5(H5Dclose(dset));
  PffCallHDF5(H5Gclose(group));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Writes this rank's rows buf (nlocal rows of ncol values, Morton order) of the block dataset name. */
static PetscErrorCode PffIOWriteBlockDataset(const PffFrameLayout *L, hid_t group, const char name[], hid_t filetype,
                                             hid_t memtype, hsize_t ncol, hid_t dxpl, const void *buf)
{
  const hsize_t dims[2] = {(hsize_t)L->nactive, ncol};
  hid_t         dset, fspace, mspace;

  PetscFunctionBeginUser;
  PetscCall(PffH5CreateDataset_Private(group, name, filetype, ncol > 0 ? 2 : 1, dims, &dset));
  PffCallHDF5(fspace = H5Dget_space(dset));
  PetscCall(PffIOSelectBlocks_Private(L, fspace));
  PetscCall(PffIOCreateMemSpace_Private((hsize_t)L->nlocal, ncol, &mspace));
  PffCallHDF5(H5Dwrite(dset, memtype, mspace, fspace, dxpl, buf));
  PffCallHDF5(H5Sclose(mspace));
  PffCallHDF5(H5Sclose(fspace));
  PffCallHDF5(H5Dclose(dset));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffIOWriteBlocks(PffGrid grid, MPI_Comm comm, const PffFrameLayout *L, hid_t file, hid_t dxpl)
{
  PetscInt64 *gid, *offset;
  PetscInt   *level;
  int        *owner;
  double     *origin;
  PetscMPIInt rank;
  hid_t       group;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCall(
      PetscMalloc5(L->nlocal, &gid, L->nlocal, &offset, L->nlocal, &level, L->nlocal, &owner, 3 * L->nlocal, &origin));
  for (PetscInt k = 0; k < L->nlocal; k++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(grid, L->lb[k], &info));
    gid[k]    = info.gid;
    offset[k] = L->offset[L->lpos[k]];
    level[k]  = info.level;
    owner[k]  = rank;
    for (int d = 0; d < 3; d++) origin[3 * k + d] = (double)info.lo[d];
  }
  PffCallHDF5(group = H5Gcreate2(file, "blocks", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  PetscCall(PffIOWriteBlockDataset(L, group, "gid", H5T_STD_I64LE, H5T_NATIVE_INT64, 0, dxpl, gid));
  PetscCall(PffIOWriteBlockDataset(L, group, "level", H5T_STD_I32LE, PFF_H5T_NATIVE_PETSCINT, 0, dxpl, level));
  PetscCall(PffIOWriteBlockDataset(L, group, "owner", H5T_STD_I32LE, H5T_NATIVE_INT, 0, dxpl, owner));
  PetscCall(PffIOWriteBlockDataset(L, group, "origin", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 3, dxpl, origin));
  PetscCall(PffIOWriteBlockDataset(L, group, "offset", H5T_STD_I64LE, H5T_NATIVE_INT64, 0, dxpl, offset));
  PffCallHDF5(H5Gclose(group));
  PetscCall(PetscFree5(gid, offset, level, owner, origin));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* /fields: one float32 dataset per channel component; the owned blocks are packed in Morton order,
   the order in which HDF5 walks the union of hyperslabs. all: every channel (checkpoints), otherwise
   only those with the output flag (PffGridSetChannelOutput). */
static PetscErrorCode PffIOWriteFields(PffGrid grid, const PffFrameLayout *L, hid_t file, hid_t dxpl, PetscBool all)
{
  PetscBool     first = PETSC_TRUE;
  const hsize_t total = (hsize_t)L->offset[L->nactive];
  PetscInt      nch;
  float        *buf;
  hid_t         group, fspace, mspace;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetNumChannels(grid, &nch));
  PetscCall(PetscMalloc1(L->ncells > 0 ? L->ncells : 1, &buf));
  PffCallHDF5(group = H5Gcreate2(file, "fields", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  PffCallHDF5(fspace = H5Screate_simple(1, &total, NULL));
  PetscCall(PffIOSelectCells_Private(L, fspace));
  PetscCall(PffIOCreateMemSpace_Private((hsize_t)L->ncells, 0, &mspace));
  for (PetscInt c = 0; c < nch; c++) {
    const char    *name;
    PffChannelKind kind;
    PetscInt       ncomp;
    PetscBool      write;

    PetscCall(PffGridGetChannelOutput(grid, c, &write));
    if (!write && !all) continue;
    PetscCall(PffGridGetChannelInfo(grid, c, &name, &kind, &ncomp, NULL));
    for (PetscInt comp = 0; comp < ncomp; comp++) {
      char       dname[256];
      int        component = (int)comp;
      PetscInt64 pos       = 0;
      hid_t      dset;

      for (PetscInt k = 0; k < L->nlocal; k++) {
        const PetscInt64 nc = (PetscInt64)L->ln[k] * L->ln[k] * L->ln[k];
        float           *data;
        PetscCall(PffGridGetBlockData(grid, c, L->lb[k], comp, &data));
        PetscCall(PetscArraycpy(buf + pos, data, nc));
        pos += nc;
      }
      PetscCall(PffIOFieldName_Private(name, kind, comp, dname, sizeof(dname)));
      PetscCall(PffH5CreateDataset_Private(group, dname, H5T_IEEE_F32LE, 1, &total, &dset));
      PetscCall(PffH5WriteAttributeString_Private(dset, "kind", PffChannelKinds[kind]));
      PetscCall(PffH5WriteAttribute_Private(dset, "component", H5T_STD_I32LE, H5T_NATIVE_INT, 0, &component));
      PetscCall(PffH5WriteAttributeString_Private(dset, "channel", name));
      PffCallHDF5(H5Dwrite(dset, H5T_NATIVE_FLOAT, mspace, fspace, dxpl, buf));
      PffCallHDF5(H5Dclose(dset));
      if (first) {
        first = PETSC_FALSE;
        /* HDF5 silently falls back to independent I/O (much slower at scale); say so under -info. */
        H5D_mpio_actual_io_mode_t mode;
        uint32_t                  lcause, gcause;
        PffCallHDF5(H5Pget_mpio_actual_io_mode(dxpl, &mode));
        PffCallHDF5(H5Pget_mpio_no_collective_cause(dxpl, &lcause, &gcause));
        PetscCall(PetscInfo(NULL, "field writes are %s (HDF5 no-collective cause 0x%x)\n",
                            mode == H5D_MPIO_NO_COLLECTIVE ? "independent" : "collective", (unsigned)gcause));
      }
    }
  }
  PffCallHDF5(H5Sclose(mspace));
  PffCallHDF5(H5Sclose(fspace));
  PffCallHDF5(H5Gclose(group));
  PetscCall(PetscFree(buf));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* <path>.tmp, the sidecar name (path with .h5 replaced by .xmf, or .xmf appended) and its .tmp, and
   the basename of path, by which the sidecar refers to the frame. */
static PetscErrorCode PffIOFrameNames(const char path[], char tmp[], char xmf[], char xmftmp[], const char **base)
{
  size_t      len;
  const char *slash;

  PetscFunctionBeginUser;
  PetscCall(PetscStrlen(path, &len));
  PetscCheck(len > 0 && len + 8 < PETSC_MAX_PATH_LEN, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG,
             "frame path \"%s\" is empty or too long", path);
  PetscCall(PetscSNPrintf(tmp, PETSC_MAX_PATH_LEN, "%s.tmp", path));
  if (len > 3 && !strcmp(path + len - 3, ".h5"))
    PetscCall(PetscSNPrintf(xmf, PETSC_MAX_PATH_LEN, "%.*s.xmf", (int)(len - 3), path));
  else
    PetscCall(PetscSNPrintf(xmf, PETSC_MAX_PATH_LEN, "%s.xmf", path));
  PetscCall(PetscSNPrintf(xmftmp, PETSC_MAX_PATH_LEN, "%s.tmp", xmf));
  slash = strrchr(path, '/');
  *base = slash ? slash + 1 : path;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Writes the file <path>.tmp collectively, and renames it (and, for frames, the XDMF sidecar) once
   every rank has closed it: the shared path of frames and checkpoints. */
static PetscErrorCode PffIOWriteFile(PffGrid grid, const char path[], PetscReal time, PetscInt step, const char scene[],
                                     const PffIOWriteOptions *o)
{
  char           tmp[PETSC_MAX_PATH_LEN], xmf[PETSC_MAX_PATH_LEN], xmftmp[PETSC_MAX_PATH_LEN];
  const char    *base = NULL, *what = o->checkpoint ? "checkpoint" : "frame";
  MPI_Comm       comm;
  PetscMPIInt    rank;
  PffFrameLayout L;
  hid_t          fapl, dxpl, file;
  PetscInt64     npart  = -1;        /* particles written, -1 for none */
  int            err[3] = {0, 0, 0}; /* errno of: XDMF write, file rename, XDMF rename */

  PetscFunctionBeginUser;
  PetscCheck(o->nextra >= 0 && (o->nextra == 0 || o->extra != NULL), PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG,
             "checkpoint %s: %" PetscInt_FMT " extra values requested but the array is NULL or the count negative",
             path, o->nextra);
  PetscCall(PffIOInitialize_Private());
  PetscCall(PffIOGetComm_Private(grid, &comm));
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCall(PffIOFrameNames(path, tmp, xmf, xmftmp, &base));
  PetscCall(PetscLogEventBegin(PFF_IOWrite, 0, 0, 0, 0));
  PetscCall(PffIOLayoutCreate_Private(grid, &L));

  PetscCall(PffIOCreateAccessList_Private(comm, &fapl));
  PetscCall(PffIOCreateTransferList_Private(&dxpl));
  /* H5F_ACC_TRUNC also overwrites a stale <path>.tmp that a killed writer left behind. */
  file = H5Fcreate(tmp, H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
  if (file < 0) {
    char msg[256];
    PffHDF5ErrorMessage_Private(msg, sizeof(msg));
    SETERRQ(comm, PETSC_ERR_FILE_OPEN, "cannot create %s %s: %s", what, tmp, msg);
  }
  PetscCall(PffIOWriteRootAttributes(comm, file, time, step, scene, o));
  PetscCall(PffIOWriteGridGroup(grid, comm, file, dxpl));
  PetscCall(PffIOWriteBlocks(grid, comm, &L, file, dxpl));
  PetscCall(PffIOWriteFields(grid, &L, file, dxpl, o->checkpoint));
  if (o->particles) PetscCall(PffIOWriteParticles_Private(o->particles, comm, file, dxpl, o->checkpoint, &npart));
  PffCallHDF5(H5Fclose(file));
  PffCallHDF5(H5Pclose(dxpl));
  PffCallHDF5(H5Pclose(fapl));

  /* Every rank has closed the file before rank 0 gives it its final name. */
  PetscCallMPI(MPI_Barrier(comm));
  if (rank == 0) {
    if (!o->checkpoint) PetscCall(PffIOWriteXdmf_Private(grid, &L, xmftmp, base, time, npart, &err[0]));
    if (rename(tmp, path) != 0) err[1] = errno;
    if (!o->checkpoint && !err[0] && rename(xmftmp, xmf) != 0) err[2] = errno;
  }
  PetscCallMPI(MPI_Bcast(err, 3, MPI_INT, 0, comm));
  PetscCheck(!err[1], comm, PETSC_ERR_FILE_WRITE, "cannot rename %s to %s: %s", tmp, path, strerror(err[1]));
  PetscCheck(!err[0], comm, PETSC_ERR_FILE_WRITE, "cannot write %s: %s", xmftmp, strerror(err[0]));
  PetscCheck(!err[2], comm, PETSC_ERR_FILE_WRITE, "cannot rename %s to %s: %s", xmftmp, xmf, strerror(err[2]));
  PetscCall(PetscInfo(NULL, "wrote %s %s (%" PetscInt_FMT " blocks, %" PetscInt64_FMT " particles)\n", what, path,
                      L.nactive, npart < 0 ? 0 : npart));
  PetscCall(PffIOLayoutDestroy_Private(&L));
#if defined(__GLIBC__)
  /* glibc keeps the pages of freed heap buffers resident: with whole-store particle buffers rt3d at W = 128 grew by
     640-770 MB per rank at each checkpoint. The particles now move in chunks (particles.c), so what remains to
     hand back is the chunk buffer and the field datasets' block buffers. */
  malloc_trim(0);
#endif
  PetscCall(PetscLogEventEnd(PFF_IOWrite, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffIOWriteFrame(PffGrid grid, const char path[], PetscReal time, PetscInt step, const char scene[])
{
  const PffIOWriteOptions o = {NULL, PETSC_FALSE, 0, NULL};

  PetscFunctionBeginUser;
  PetscCall(PffIOWriteFile(grid, path, time, step, scene, &o));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffIOWriteFrameParticles(PffGrid grid, PffParticles particles, const char path[], PetscReal time,
                                        PetscInt step, const char scene[])
{
  const PffIOWriteOptions o = {particles, PETSC_FALSE, 0, NULL};

  PetscFunctionBeginUser;
  PetscCall(PffIOWriteFile(grid, path, time, step, scene, &o));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffIOWriteCheckpoint(PffGrid grid, PffParticles particles, const char path[], PetscReal time,
                                    PetscInt step, PetscInt nextra, const PetscReal extra[], const char scene[])
{
  const PffIOWriteOptions o = {particles, PETSC_TRUE, nextra, extra};

  PetscFunctionBeginUser;
  PetscCall(PffIOWriteFile(grid, path, time, step, scene, &o));
  PetscFunctionReturn(PETSC_SUCCESS);
}
