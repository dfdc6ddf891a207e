/* The /particles group of frames and checkpoints (Output stage and restart).

   Writing: rank r owns rows [o_r, o_r + n_r) of every particle dataset, o_r = sum_{q<r} n_q (MPI_Exscan
   of the local counts), so the rows follow the ranks and, within a rank, the store's order; the file
   therefore depends on the partition, but the set of particles does not. Every rank takes part in
   every collective call, selecting nothing when it holds no particle. x and v are float32 in frames
   (converted here, so that the transfer stays collective) and float64 in checkpoints (exact restart).
   Both directions move at most -particles_io_chunk rows per rank and collective call, so that the
   conversion buffers stay a few tens of MB at any count (whole-store buffers added 24 B per particle
   to a checkpointing run's peak, 0.8 GB per rank in rt3d at W = 128); every rank makes as many calls
   as the rank with the most rows, selecting nothing once its own are done.

   Reading (restart on any number of ranks): rank r of P reads rows [N r / P, N (r + 1) / P), appends
   them to the empty store and migrates them to the owners of their blocks. */
#include <stdint.h>
#include "h5util.h"

/* Selects rows [start, start + n) of a dataspace of rows x ncol (ncol = 0: 1-D), none when n = 0. */
static PetscErrorCode PffIOSelectRows(hid_t space, hsize_t start, hsize_t n, hsize_t ncol)
{
  const hsize_t off[2] = {start, 0}, cnt[2] = {n, ncol};

  PetscFunctionBeginUser;
  if (n == 0)
    PffCallHDF5(H5Sselect_none(space));
  else
    PffCallHDF5(H5Sselect_hyperslab(space, H5S_SELECT_SET, off, NULL, cnt, NULL));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The rows of one rank in a dataset of total rows, moved in nchunks collective calls of at most chunk rows. */
typedef struct {
  hid_t      group, dxpl;
  hsize_t    total, start; /* rows in all, this rank's first */
  PetscInt64 n, chunk, nchunks;
} PffIORows;

static PetscErrorCode PffIORowsSetUp(PffParticles particles, MPI_Comm comm, hid_t group, hid_t dxpl, PetscInt64 total,
                                     PetscInt64 start, PetscInt64 n, PffIORows *r)
{
  PetscInt   chunk;
  PetscInt64 nmax = n;

  PetscFunctionBeginUser;
  PetscCall(PffParticlesGetIOChunk(particles, &chunk));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &nmax, 1, MPIU_INT64, MPI_MAX, comm));
  r->group   = group;
  r->dxpl    = dxpl;
  r->total   = (hsize_t)total;
  r->start   = (hsize_t)start;
  r->n       = n;
  r->chunk   = chunk;
  r->nchunks = (nmax + chunk - 1) / chunk;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* This rank's rows [*i0, *i0 + *m) of chunk c (m = 0 once they are done). */
static inline void PffIORowsChunk(const PffIORows *r, PetscInt64 c, PetscInt64 *i0, PetscInt64 *m)
{
  *i0 = PetscMin(c * r->chunk, r->n);
  *m  = PetscMin(r->chunk, r->n - *i0);
}

/* Fills buf with this rank's rows [i0, i0 + m) of a dataset, converted to its memory type. */
typedef void (*PffIORowFill)(const void *ctx, PetscInt64 i0, PetscInt64 m, void *buf);

/* Creates dataset name (rows x ncol, ncol = 0: 1-D) and writes this rank's rows chunk by chunk: through fill
   into buf, or straight from data (rowbytes per row) when fill is NULL. */
static PetscErrorCode PffIOWriteRows(const PffIORows *r, const char name[], hid_t filetype, hid_t memtype, hsize_t ncol,
                                     PffIORowFill fill, const void *ctx, void *buf, const void *data, size_t rowbytes)
{
  const hsize_t dims[2] = {r->total, ncol};
  hid_t         dset, fspace;

  PetscFunctionBeginUser;
  PetscCall(PffH5CreateDataset_Private(r->group, name, filetype, ncol > 0 ? 2 : 1, dims, &dset));
  PffCallHDF5(fspace = H5Dget_space(dset));
  for (PetscInt64 c = 0; c < r->nchunks; c++) {
    PetscInt64  i0, m;
    const void *src;
    hid_t       mspace;
    PffIORowsChunk(r, c, &i0, &m);
    if (fill) fill(ctx, i0, m, buf);
    src = fill ? buf : data ? (const void *)((const char *)data + rowbytes * (size_t)i0) : NULL;
    PetscCall(PffIOSelectRows(fspace, r->start + (hsize_t)i0, (hsize_t)m, ncol));
    PetscCall(PffIOCreateMemSpace_Private((hsize_t)m, ncol, &mspace));
    PffCallHDF5(H5Dwrite(dset, memtype, mspace, fspace, r->dxpl, src));
    PffCallHDF5(H5Sclose(mspace));
  }
  PffCallHDF5(H5Sclose(fspace));
  PffCallHDF5(H5Dclose(dset));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The conversions of the store's rows to the files' (ctx: the store's PffParticleArrays). */
static void PffIOFillWorld(const void *ctx, PetscInt64 i0, PetscInt64 m, void *buf)
{
  for (PetscInt64 i = 0; i < m; i++)
    PffParticleArraysWorld((const PffParticleArrays *)ctx, (PetscInt)(i0 + i), (PetscReal *)buf + 3 * i);
}

static void PffIOFillWorldFloat(const void *ctx, PetscInt64 i0, PetscInt64 m, void *buf)
{
  const PffParticleArrays *a = (const PffParticleArrays *)ctx;
  for (PetscInt64 j = 0; j < 3 * m; j++)
    ((float *)buf)[j] = (float)(a->origin[j % 3] + a->h0 * (PetscReal)a->x[3 * i0 + j]);
}

static void PffIOFillVelocity(const void *ctx, PetscInt64 i0, PetscInt64 m, void *buf)
{
  const PffParticleArrays *a = (const PffParticleArrays *)ctx;
  for (PetscInt64 j = 0; j < 3 * m; j++) ((PetscReal *)buf)[j] = (PetscReal)a->v[3 * i0 + j];
}

/* The packed word unpacked into the files' three byte datasets: type, level, flags (byte k). */
typedef struct {
  const PffParticleArrays *a;
  int                      k;
} PffIOByteField;

static void PffIOFillByte(const void *ctx, PetscInt64 i0, PetscInt64 m, void *buf)
{
  const PffIOByteField *f = (const PffIOByteField *)ctx;
  for (PetscInt64 i = 0; i < m; i++) {
    const uint32_t w    = f->a->word[i0 + i];
    ((uint8_t *)buf)[i] = (uint8_t)(f->k == 0   ? (uint32_t)PffParticleWordType(w)
                                    : f->k == 1 ? (uint32_t)PffParticleWordLevel(w)
                                                : PffParticleFlagsByte(w));
  }
}

/* File and memory HDF5 types of a particle field (PffParticlesGetFileFields). */
static void PffIOFieldTypes(PffFieldType t, hid_t *file, hid_t *mem)
{
  switch (t) {
  case PFF_FIELD_FLOAT:
    *file = H5T_IEEE_F32LE, *mem = H5T_NATIVE_FLOAT;
    break;
  case PFF_FIELD_DOUBLE:
    *file = H5T_IEEE_F64LE, *mem = H5T_NATIVE_DOUBLE;
    break;
  case PFF_FIELD_INT32:
    *file = H5T_STD_I32LE, *mem = H5T_NATIVE_INT32;
    break;
  case PFF_FIELD_UINT32:
    *file = H5T_STD_U32LE, *mem = H5T_NATIVE_UINT32;
    break;
  case PFF_FIELD_INT64:
    *file = H5T_STD_I64LE, *mem = H5T_NATIVE_INT64;
    break;
  default:
    *file = H5T_STD_U64LE, *mem = H5T_NATIVE_UINT64;
  }
}

#define PFF_IO_MAX_FILE_FIELDS 16

PetscErrorCode PffIOWriteParticles_Private(PffParticles particles, MPI_Comm comm, hid_t file, hid_t dxpl, PetscBool dbl,
                                           PetscInt64 *count)
{
  PffParticleArrays a;
  PetscInt64        n, start = 0, total = 0;
  PetscMPIInt       rank;
  hid_t             group;
  const hid_t       ftype = dbl ? H5T_IEEE_F64LE : H5T_IEEE_F32LE;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCall(PffParticlesGetArrays(particles, &a));
  n = a.n;
  PetscCallMPI(MPI_Exscan(&n, &start, 1, MPIU_INT64, MPI_SUM, comm));
  if (rank == 0) start = 0; /* MPI_Exscan leaves rank 0's result undefined */
  PetscCallMPI(MPI_Allreduce(&n, &total, 1, MPIU_INT64, MPI_SUM, comm));

  PffCallHDF5(group = H5Gcreate2(file, "particles", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  PetscCall(PffH5WriteAttribute_Private(group, "count", H5T_STD_I64LE, H5T_NATIVE_INT64, 0, &total));
  {
    /* each rank's row count: a restart on as many ranks reads back each rank's own rows in its own
       order, so that its sums run in the same order as the uninterrupted run's (bit-exact) */
    PetscMPIInt size;
    PetscInt64 *counts;
    PetscCallMPI(MPI_Comm_size(comm, &size));
    PetscCall(PetscMalloc1(size, &counts));
    PetscCallMPI(MPI_Allgather(&n, 1, MPIU_INT64, counts, 1, MPIU_INT64, comm));
    PetscCall(
        PffH5WriteAttribute_Private(group, "rank_counts", H5T_STD_I64LE, H5T_NATIVE_INT64, (hsize_t)size, counts));
    PetscCall(PetscFree(counts));
  }
  /* world positions (double in checkpoints: the store's floats come back exactly), velocities as
     stored or widened, and the packed word unpacked into the file's three byte datasets */
  {
    PffIORows            io;
    PffParticleFieldInfo info[PFF_IO_MAX_FILE_FIELDS];
    PetscInt             nf = PFF_IO_MAX_FILE_FIELDS;
    void                *buf;
    PetscCall(PffIORowsSetUp(particles, comm, group, dxpl, total, start, n, &io));
    PetscCall(PetscMalloc(3 * sizeof(PetscReal) * (size_t)PetscMax(1, PetscMin(io.chunk, n)), &buf));
    if (dbl) {
      PetscCall(PffIOWriteRows(&io, "x", ftype, PFF_H5T_NATIVE_PETSCREAL, 3, PffIOFillWorld, &a, buf, NULL, 0));
      PetscCall(PffIOWriteRows(&io, "v", ftype, PFF_H5T_NATIVE_PETSCREAL, 3, PffIOFillVelocity, &a, buf, NULL, 0));
    } else {
      PetscCall(PffIOWriteRows(&io, "x", ftype, H5T_NATIVE_FLOAT, 3, PffIOFillWorldFloat, &a, buf, NULL, 0));
      PetscCall(PffIOWriteRows(&io, "v", ftype, H5T_NATIVE_FLOAT, 3, NULL, NULL, NULL, a.v, 3 * sizeof(float)));
    }
    PetscCall(PffParticlesGetFileFields(&nf, info));
    for (PetscInt f = 0; f < nf; f++) { /* the fields that need no code of their own, as stored */
      hid_t ft, mt;
      void *data;
      PffIOFieldTypes(info[f].type, &ft, &mt);
      PetscCall(PffParticlesGetFieldArray(particles, info[f].name, &data));
      PetscCall(PffIOWriteRows(&io, info[f].name, ft, mt, info[f].ncomp > 1 ? (hsize_t)info[f].ncomp : 0, NULL, NULL,
                               NULL, data, info[f].size * (size_t)info[f].ncomp));
    }
    const char *const names[3]  = {"type", "level", "flags"};
    const hid_t       ftypes[3] = {H5T_STD_U8LE, H5T_STD_I8LE, H5T_STD_U8LE};
    for (int k = 0; k < 3; k++) {
      const PffIOByteField bf = {&a, k};
      PetscCall(PffIOWriteRows(&io, names[k], ftypes[k], H5T_NATIVE_UINT8, 0, PffIOFillByte, &bf, buf, NULL, 0));
    }
    PetscCall(PetscFree(buf));
  }
  PffCallHDF5(H5Gclose(group));
  *count = total;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The datasets of /particles with their values per row: the ones with code of their own, then the store's file
   fields (PffParticlesGetFileFields). */
static PetscErrorCode PffParticleDatasets(PetscInt *n, const char *names[], PetscInt ncol[])
{
  static const char *const own[] = {"x", "v", "type", "level", "flags"};
  const PetscInt           nown  = 5;
  PffParticleFieldInfo     info[PFF_IO_MAX_FILE_FIELDS];
  PetscInt                 nf = PFF_IO_MAX_FILE_FIELDS;

  PetscFunctionBeginUser;
  PetscCall(PffParticlesGetFileFields(&nf, info));
  for (PetscInt k = 0; k < nown; k++) {
    names[k] = own[k];
    ncol[k]  = k < 2 ? 3 : 1;
  }
  for (PetscInt f = 0; f < nf; f++) {
    names[nown + f] = info[f].name;
    ncol[nown + f]  = info[f].ncomp;
  }
  *n = nown + nf;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffIOCheckParticles_Private(hid_t file, const char path[], PetscInt64 *count, char msg[], size_t len)
{
  PetscBool found;
  htri_t    exists;
  hid_t     group;

  PetscFunctionBeginUser;
  *count = 0;
  PffCallHDF5(exists = H5Lexists(file, "particles", H5P_DEFAULT));
  if (!exists) {
    PetscCall(PetscSNPrintf(msg, len, "checkpoint %s: no /particles group", path));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PffCallHDF5(group = H5Gopen2(file, "particles", H5P_DEFAULT));
  PetscCall(PffH5ReadAttribute_Private(group, "count", H5T_NATIVE_INT64, 0, count, &found));
  if (!found || *count < 0)
    PetscCall(PetscSNPrintf(msg, len, "checkpoint %s: /particles has no count attribute (or a negative one)", path));
  const char *names[5 + PFF_IO_MAX_FILE_FIELDS];
  PetscInt    ncols[5 + PFF_IO_MAX_FILE_FIELDS], nd = 0;
  PetscCall(PffParticleDatasets(&nd, names, ncols));
  for (PetscInt k = 0; k < nd && !msg[0]; k++) {
    const PetscInt ncol    = ncols[k] > 1 ? ncols[k] : 0;
    hsize_t        dims[2] = {0, 0};
    int            ndims;
    hid_t          dset, space;

    PffCallHDF5(exists = H5Lexists(group, names[k], H5P_DEFAULT));
    if (!exists) {
      PetscCall(PetscSNPrintf(msg, len, "checkpoint %s: no dataset /particles/%s", path, names[k]));
      break;
    }
    PffCallHDF5(dset = H5Dopen2(group, names[k], H5P_DEFAULT));
    PffCallHDF5(space = H5Dget_space(dset));
    PffCallHDF5(ndims = H5Sget_simple_extent_ndims(space));
    if (ndims == (ncol ? 2 : 1)) PffCallHDF5(H5Sget_simple_extent_dims(space, dims, NULL));
    if (ndims != (ncol ? 2 : 1) || dims[0] != (hsize_t)*count || (ncol && dims[1] != (hsize_t)ncol))
      PetscCall(PetscSNPrintf(msg, len,
                              "checkpoint %s: /particles/%s is not an array of %" PetscInt64_FMT " rows%s (count "
                              "attribute)",
                              path, names[k], *count, ncol ? " of 3 values" : ""));
    PffCallHDF5(H5Sclose(space));
    PffCallHDF5(H5Dclose(dset));
  }
  PffCallHDF5(H5Gclose(group));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A dataset of /particles open for the whole read, so that every chunk selects in the same file space. */
typedef struct {
  hid_t dset, space;
} PffIOSource;

static PetscErrorCode PffIOSourceOpen(hid_t group, const char name[], PffIOSource *s)
{
  PetscFunctionBeginUser;
  PffCallHDF5(s->dset = H5Dopen2(group, name, H5P_DEFAULT));
  PffCallHDF5(s->space = H5Dget_space(s->dset));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffIOSourceClose(PffIOSource *s)
{
  PetscFunctionBeginUser;
  if (s->space >= 0) PffCallHDF5(H5Sclose(s->space));
  if (s->dset >= 0) PffCallHDF5(H5Dclose(s->dset));
  s->dset = s->space = H5I_INVALID_HID;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Reads rows [start, start + n) of an open dataset (rows x ncol, ncol = 0: 1-D) into buf, converted to memtype. */
static PetscErrorCode PffIOSourceRead(const PffIOSource *s, hid_t memtype, hsize_t ncol, hsize_t start, hsize_t n,
                                      hid_t dxpl, void *buf)
{
  hid_t mspace;

  PetscFunctionBeginUser;
  PetscCall(PffIOSelectRows(s->space, start, n, ncol));
  PetscCall(PffIOCreateMemSpace_Private(n, ncol, &mspace));
  PffCallHDF5(H5Dread(s->dset, memtype, mspace, s->space, dxpl, buf));
  PffCallHDF5(H5Sclose(mspace));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffIOReadParticles_Private(PffParticles particles, PffGrid grid, MPI_Comm comm, hid_t file,
                                          const char path[], hid_t dxpl, PetscInt64 count)
{
  PetscMPIInt          rank, size;
  PetscInt64           lo, bad = -1;
  PetscInt             n, nlevels, nf = PFF_IO_MAX_FILE_FIELDS;
  PetscReal           *x, *v;
  uint8_t             *type, *flags;
  int8_t              *level;
  hid_t                group;
  PffIORows            io;
  PffIOSource          src[5 + PFF_IO_MAX_FILE_FIELDS]; /* x, v, type, level, flags, then the file fields */
  const char          *names[5 + PFF_IO_MAX_FILE_FIELDS];
  PetscInt             ncol[5 + PFF_IO_MAX_FILE_FIELDS], nd;
  PffParticleArrays    a;
  PffParticleFieldInfo info[PFF_IO_MAX_FILE_FIELDS];

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(PffGridGetSizes(grid, NULL, &nlevels, NULL, NULL, NULL));
  PffCallHDF5(group = H5Gopen2(file, "particles", H5P_DEFAULT));
  {
    const PetscInt64 base = count / size, rem = count % size;
    PetscInt64      *counts, sum              = 0;
    PetscBool        found = PETSC_FALSE;

    lo = base * rank + PetscMin((PetscInt64)rank, rem);
    PetscCall(PetscIntCast(base + (rank < rem ? 1 : 0), &n));
    /* written on as many ranks: each rank takes back its own rows (see PffIOWriteParticles_Private) */
    PetscCall(PetscMalloc1(size, &counts));
    PetscCall(PffH5ReadAttribute_Private(group, "rank_counts", H5T_NATIVE_INT64, (hsize_t)size, counts, &found));
    for (PetscMPIInt r = 0; found && r < size; r++) sum += counts[r];
    if (found && sum == count) {
      lo = 0;
      for (PetscMPIInt r = 0; r < rank; r++) lo += counts[r];
      PetscCall(PetscIntCast(counts[rank], &n));
    }
    PetscCall(PetscFree(counts));
  }
  PetscCall(PffIORowsSetUp(particles, comm, group, dxpl, count, lo, n, &io));
  {
    const PetscInt rows = (PetscInt)PetscMax(1, PetscMin(io.chunk, (PetscInt64)n));
    PetscCall(PetscMalloc5(3 * rows, &x, 3 * rows, &v, rows, &type, rows, &level, rows, &flags));
  }
  PetscCall(PffParticlesGetFileFields(&nf, info));
  PetscCall(PffParticleDatasets(&nd, names, ncol)); /* the same order: the five of the store, then info[] */
  for (PetscInt k = 0; k < nd; k++) src[k].dset = src[k].space = H5I_INVALID_HID;
  for (PetscInt k = 0; k < nd; k++) PetscCall(PffIOSourceOpen(group, names[k], &src[k]));
  for (PetscInt64 c = 0; c < io.nchunks; c++) {
    PetscInt64 i0, m;
    PetscInt   n0;
    PffIORowsChunk(&io, c, &i0, &m);
    const hsize_t at = (hsize_t)(lo + i0), rows = (hsize_t)m;
    PetscCall(PffIOSourceRead(&src[0], PFF_H5T_NATIVE_PETSCREAL, 3, at, rows, dxpl, x));
    PetscCall(PffIOSourceRead(&src[1], PFF_H5T_NATIVE_PETSCREAL, 3, at, rows, dxpl, v));
    PetscCall(PffIOSourceRead(&src[2], H5T_NATIVE_UINT8, 0, at, rows, dxpl, type));
    PetscCall(PffIOSourceRead(&src[3], H5T_NATIVE_INT8, 0, at, rows, dxpl, level));
    PetscCall(PffIOSourceRead(&src[4], H5T_NATIVE_UINT8, 0, at, rows, dxpl, flags));
    /* PffParticlesAdd would stop on this rank alone; every rank stops at the first chunk that holds a bad row
       on any rank, naming the lowest such row */
    for (PetscInt64 i = 0; i < m && bad < 0; i++)
      if (type[i] >= PFF_PARTICLE_NTYPES || level[i] < 0 || level[i] >= nlevels) bad = lo + i0 + i;
    if (bad < 0) bad = INT64_MAX;
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &bad, 1, MPIU_INT64, MPI_MIN, comm));
    if (bad != INT64_MAX) {
      for (PetscInt k = 0; k < nd; k++) PetscCall(PffIOSourceClose(&src[k]));
      PffCallHDF5(H5Gclose(group));
      PetscCall(PetscFree5(x, v, type, level, flags));
      SETERRQ(comm, PETSC_ERR_FILE_UNEXPECTED,
              "checkpoint %s: particle row %" PetscInt64_FMT
              " has a type that is not a PffParticleType or a level outside the grid's 0..%" PetscInt_FMT,
              path, bad, nlevels - 1);
    }
    bad = -1;
    /* the fields the files take by themselves go straight into the rows Add appended */
    PetscCall(PffParticlesGetArrays(particles, &a));
    n0 = a.n;
    PetscCall(PffParticlesAdd(particles, (PetscInt)m, x, v, NULL, type, level, flags));
    for (PetscInt f = 0; f < nf; f++) {
      hid_t ft, mt;
      char *data;
      PffIOFieldTypes(info[f].type, &ft, &mt);
      PetscCall(PffParticlesGetFieldArray(particles, info[f].name, (void **)&data));
      PetscCall(PffIOSourceRead(&src[5 + f], mt, info[f].ncomp > 1 ? (hsize_t)info[f].ncomp : 0, at, rows, dxpl,
                                data ? data + info[f].size * (size_t)info[f].ncomp * (size_t)n0 : NULL));
    }
  }
  for (PetscInt k = 0; k < nd; k++) PetscCall(PffIOSourceClose(&src[k]));
  PffCallHDF5(H5Gclose(group));
  PetscCall(PetscFree5(x, v, type, level, flags));
  PetscCall(PffParticlesMigrate(particles, NULL));
  PetscFunctionReturn(PETSC_SUCCESS);
}
