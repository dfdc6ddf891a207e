/* Unit test of the io module: a frame written on one partition reads back bit for bit on another.

   Builds a 3-level grid (8x6x4 blocks of 8^3 cells at level 0, some inactive, periodic in x) with a
   cell channel and a face channel filled from a smooth function of each value's world position,
   writes it with PffIOWriteFrame, and reads it into a grid partitioned by METIS instead of Morton.
   It checks that every value, the time and the step round-trip exactly, that the checksum of the file
   (re-read on rank 0 with plain HDF5) equals that of the grid, that the METIS grid writes a file whose
   datasets equal the first file's byte for byte (except /blocks/owner), that PffIOReadLevels returns
   the level map, that no temporary file is left, and that a missing file, a different block size and
   a missing channel fail with messages naming them.

   Sample run:  mpiexec -n 4 ./test_io -out /tmp/frame.h5
   Prints (the same on any number of ranks):
     checksum phi <sum> blocks <n>
     checksum vel_x <sum> blocks <n>   (and vel_y, vel_z) */
#include <math.h>
#include <string.h>
#include <unistd.h>
#include <pff.h>
#include "../../src/io/h5util.h"

static const char help[] = "Round trip of an HDF5 frame across partitions.\n"
                           "  -out <file.h5>  frame to write (default test_io.h5)\n";

#define NCOMP_MAX 3

typedef struct {
  PetscInt cch, fch, xch; /* cell channel "phi", face channel "vel", optional cell channel "extra" */
} Channels;

/* A deterministic multi-level map: level grows with the distance from a point, and one corner of the
   domain is inactive; graded so that it is a valid MSBG raster. */
static PetscErrorCode BuildLevelMap(const PetscInt nb[3], const PetscBool periodic[3], PetscInt **level)
{
  const PetscInt nblocks = nb[0] * nb[1] * nb[2];

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(nblocks, level));
  for (PetscInt b = 0; b < nblocks; b++) {
    const PetscInt  ijk[3] = {b % nb[0], (b / nb[0]) % nb[1], b / (nb[0] * nb[1])};
    const PetscReal c[3]   = {0.3 * nb[0], 0.4 * nb[1], 0.5 * nb[2]};
    PetscReal       d2     = 0;
    for (int d = 0; d < 3; d++) d2 += PetscSqr((ijk[d] + 0.5) - c[d]);
    (*level)[b] = PetscMin(2, (PetscInt)(PetscSqrtReal(d2) / 1.5));
    if (ijk[0] >= nb[0] - nb[0] / 4 && ijk[1] >= nb[1] - nb[1] / 3 && ijk[2] >= nb[2] / 2) (*level)[b] = -1;
  }
  PetscCall(PffGradeLevels(nb, periodic, *level));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode CreateGrid(MPI_Comm comm, PetscInt n0, PffPartitionType ptype, PetscBool extra, PffGrid *grid,
                                 Channels *chs)
{
  const PetscInt  cells[3]    = {64, 48, 32};
  const PetscReal origin[3]   = {-0.5, 0.25, 0.0};
  const PetscBool periodic[3] = {PETSC_TRUE, PETSC_FALSE, PETSC_FALSE};
  const PetscInt  nb[3]       = {cells[0] / n0, cells[1] / n0, cells[2] / n0};
  PetscInt       *level;

  PetscFunctionBeginUser;
  PetscCall(PffGridCreate(comm, grid));
  PetscCall(PffGridSetCells(*grid, cells));
  PetscCall(PffGridSetBlockSize(*grid, n0));
  PetscCall(PffGridSetLevels(*grid, 3));
  PetscCall(PffGridSetDomain(*grid, origin, 1.0 / 64));
  PetscCall(PffGridSetPeriodic(*grid, periodic));
  PetscCall(PffGridSetPartitionType(*grid, ptype));
  PetscCall(BuildLevelMap(nb, periodic, &level));
  PetscCall(PffGridSetRefinementMap(*grid, level));
  PetscCall(PetscFree(level));
  PetscCall(PffGridSetUp(*grid));
  PetscCall(PffGridAddChannel(*grid, "phi", PFF_CHANNEL_CELL, 1, &chs->cch));
  PetscCall(PffGridAddChannel(*grid, "vel", PFF_CHANNEL_FACE, 1, &chs->fch));
  if (extra) PetscCall(PffGridAddChannel(*grid, "extra", PFF_CHANNEL_CELL, 1, &chs->xch));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The value of component comp at world position x: smooth, different per component, and computed
   from the position alone, so it does not depend on which rank owns the block. */
static float FieldValue(const PetscReal x[3], PetscInt comp)
{
  return (float)(sin(3.0 * x[0] + comp) * cos(2.0 * x[1] - 0.5 * comp) + 0.25 * x[2] * x[2] + 0.1 * comp);
}

/* Fills channel ch (set = PETSC_TRUE) or counts the values that differ from FieldValue in their bits. */
static PetscErrorCode FillOrCompare(PffGrid grid, PetscInt ch, PetscBool set, PetscInt64 *ndiff)
{
  PffChannelKind kind;
  PetscInt       ncomp, nlocal;

  PetscFunctionBeginUser;
  *ndiff = 0;
  PetscCall(PffGridGetChannelInfo(grid, ch, NULL, &kind, &ncomp, NULL));
  PetscCall(PffGridGetLocalBlocks(grid, &nlocal));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(grid, lb, &info));
    for (PetscInt comp = 0; comp < ncomp; comp++) {
      const PetscInt n = info.n;
      float         *data;
      PetscCall(PffGridGetBlockData(grid, ch, lb, comp, &data));
      for (PetscInt k = 0; k < n; k++)
        for (PetscInt j = 0; j < n; j++)
          for (PetscInt i = 0; i < n; i++) {
            const PetscInt idx[3] = {i, j, k};
            PetscReal      x[3];
            /* Face component d sits on the lower d-face of the cell, the rest at the cell centre. */
            for (int d = 0; d < 3; d++)
              x[d] = info.lo[d] + (idx[d] + ((kind == PFF_CHANNEL_FACE && comp == d) ? 0.0 : 0.5)) * info.h;
            const float v = FieldValue(x, comp);
            float      *p = &data[i + n * (j + n * k)];
            if (set)
              *p = v;
            else if (memcmp(p, &v, sizeof(v)))
              (*ndiff)++;
          }
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Rank-independent checksum of each component of channel ch: per block the double sum of its values,
   then the sum of those over blocks in Morton order. The reduction adds each block's sum to zeros
   only, so it is exact. */
static PetscErrorCode ChannelChecksum(PffGrid grid, MPI_Comm comm, PetscInt ch, double sum[NCOMP_MAX])
{
  const PetscInt *order;
  PetscInt        nactive, ncomp, n0;
  const PetscInt *level;
  double         *bsum;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetMortonOrder(grid, &nactive, &order));
  PetscCall(PffGridGetRaster(grid, NULL, &level, NULL));
  PetscCall(PffGridGetSizes(grid, &n0, NULL, NULL, NULL, NULL));
  PetscCall(PffGridGetChannelInfo(grid, ch, NULL, NULL, &ncomp, NULL));
  PetscCall(PetscCalloc1(nactive * ncomp, &bsum));
  for (PetscInt p = 0; p < nactive; p++) {
    const PetscInt n = n0 >> level[order[p]];
    PetscInt       lb;
    PetscCall(PffGridGetLocalIndex(grid, order[p], &lb));
    if (lb < 0) continue;
    for (PetscInt comp = 0; comp < ncomp; comp++) {
      float *data;
      PetscCall(PffGridGetBlockData(grid, ch, lb, comp, &data));
      for (PetscInt c = 0; c < n * n * n; c++) bsum[comp * nactive + p] += data[c];
    }
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, bsum, (PetscMPIInt)(nactive * ncomp), MPI_DOUBLE, MPI_SUM, comm));
  for (PetscInt comp = 0; comp < ncomp; comp++) {
    sum[comp] = 0;
    for (PetscInt p = 0; p < nactive; p++) sum[comp] += bsum[comp * nactive + p];
  }
  PetscCall(PetscFree(bsum));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Rank 0 alone: the same checksum from the file, with the serial HDF5 driver, using only the layout
   that docs/file-format.md gives (/blocks/offset and the field datasets). Also checks the root
   attributes that identify the frame. */
static PetscErrorCode FileChecksum(const char path[], const char dname[], PetscInt64 expectstep, PetscMPIInt size,
                                   double *sum, PetscInt *nactive)
{
  hid_t       file, dset, space;
  hssize_t    nblocks, ncells;
  PetscInt64 *offset, step;
  float      *val;
  char       *format;
  int         ranks;
  PetscBool   found;

  PetscFunctionBeginUser;
  PffCallHDF5(file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT));
  PetscCall(PffH5ReadAttributeString_Private(file, "format", &format));
  PetscCheck(format && !strcmp(format, "pfflip-frame"), PETSC_COMM_SELF, PETSC_ERR_PLIB, "format attribute is wrong");
  PetscCall(PetscFree(format));
  PetscCall(PffH5ReadAttribute_Private(file, "step", H5T_NATIVE_INT64, 0, &step, &found));
  PetscCheck(found && step == expectstep, PETSC_COMM_SELF, PETSC_ERR_PLIB, "step attribute is wrong");
  PetscCall(PffH5ReadAttribute_Private(file, "mpi_ranks", H5T_NATIVE_INT, 0, &ranks, &found));
  PetscCheck(found && ranks == size, PETSC_COMM_SELF, PETSC_ERR_PLIB, "mpi_ranks attribute is wrong");

  PffCallHDF5(dset = H5Dopen2(file, "/blocks/offset", H5P_DEFAULT));
  PffCallHDF5(space = H5Dget_space(dset));
  PffCallHDF5(nblocks = H5Sget_simple_extent_npoints(space));
  PetscCall(PetscMalloc1(nblocks, &offset));
  PffCallHDF5(H5Dread(dset, H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, offset));
  PffCallHDF5(H5Sclose(space));
  PffCallHDF5(H5Dclose(dset));

  PffCallHDF5(dset = H5Dopen2(file, dname, H5P_DEFAULT));
  PffCallHDF5(space = H5Dget_space(dset));
  PffCallHDF5(ncells = H5Sget_simple_extent_npoints(space));
  PetscCall(PetscMalloc1(ncells, &val));
  PffCallHDF5(H5Dread(dset, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, val));
  PffCallHDF5(H5Sclose(space));
  PffCallHDF5(H5Dclose(dset));
  PffCallHDF5(H5Fclose(file));

  *sum = 0;
  for (hssize_t p = 0; p < nblocks; p++) {
    const PetscInt64 end = p + 1 < nblocks ? offset[p + 1] : (PetscInt64)ncells;
    double           b   = 0;
    for (PetscInt64 c = offset[p]; c < end; c++) b += val[c];
    *sum += b;
  }
  *nactive = (PetscInt)nblocks;
  PetscCall(PetscFree(offset));
  PetscCall(PetscFree(val));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Rank 0 alone: dataset name holds the same bytes in files a and b. */
static PetscErrorCode CompareDataset(const char a[], const char b[], const char name[])
{
  const char *paths[2] = {a, b};
  char       *buf[2]   = {NULL, NULL};
  size_t      bytes[2] = {0, 0};

  PetscFunctionBeginUser;
  for (int f = 0; f < 2; f++) {
    hid_t file, dset, space, type, native;
    PffCallHDF5(file = H5Fopen(paths[f], H5F_ACC_RDONLY, H5P_DEFAULT));
    PffCallHDF5(dset = H5Dopen2(file, name, H5P_DEFAULT));
    PffCallHDF5(space = H5Dget_space(dset));
    PffCallHDF5(type = H5Dget_type(dset));
    PffCallHDF5(native = H5Tget_native_type(type, H5T_DIR_ASCEND));
    bytes[f] = (size_t)H5Sget_simple_extent_npoints(space) * H5Tget_size(native);
    PetscCall(PetscMalloc1(bytes[f] + 1, &buf[f]));
    PffCallHDF5(H5Dread(dset, native, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf[f]));
    PffCallHDF5(H5Tclose(native));
    PffCallHDF5(H5Tclose(type));
    PffCallHDF5(H5Sclose(space));
    PffCallHDF5(H5Dclose(dset));
    PffCallHDF5(H5Fclose(file));
  }
  PetscCheck(bytes[0] == bytes[1] && !memcmp(buf[0], buf[1], bytes[0]), PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "%s differs between %s and %s", name, a, b);
  PetscCall(PetscFree(buf[0]));
  PetscCall(PetscFree(buf[1]));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Runs PffIOReadFrame expecting it to fail with a message containing expect. */
static PetscErrorCode ExpectReadError(PffGrid grid, const char path[], const char expect[])
{
  PetscErrorCode ierr;
  const char    *text;
  char          *specific = NULL;

  PetscFunctionBeginUser;
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  ierr = PffIOReadFrame(grid, path, NULL, NULL);
  PetscCall(PetscPopErrorHandler());
  PetscCheck(ierr != PETSC_SUCCESS, PETSC_COMM_SELF, PETSC_ERR_PLIB, "reading %s should have failed (%s)", path,
             expect);
  PetscCall(PetscErrorMessage(ierr, &text, &specific));
  PetscCheck(specific && strstr(specific, expect), PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "reading %s failed with \"%s\", which does not mention \"%s\"", path, specific ? specific : "", expect);
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  const PetscReal time                = 1.0 / 3.0;
  const PetscInt  step                = 42;
  char        out[PETSC_MAX_PATH_LEN] = "test_io.h5", out2[PETSC_MAX_PATH_LEN + 16], missing[PETSC_MAX_PATH_LEN + 16];
  char        expect[128];
  MPI_Comm    comm;
  PetscMPIInt rank, size;
  PffGrid     grid, grid2, bad;
  Channels    chs, chs2, chsbad;
  double      csum[4], csum2[4];
  PetscInt64  ndiff, ndiff2;
  PetscReal   rtime = 0;
  PetscInt    rstep = 0, nactive;
  const PetscInt *order;
  const char     *dnames[4] = {"phi", "vel_x", "vel_y", "vel_z"};

  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(PffInitializePackage());
  comm = PETSC_COMM_WORLD;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscOptionsBegin(comm, NULL, "io test", NULL);
  PetscCall(PetscOptionsString("-out", "Frame to write", NULL, out, out, sizeof(out), NULL));
  PetscOptionsEnd();

  /* Write from a Morton-partitioned grid. */
  PetscCall(CreateGrid(comm, 8, PFF_PARTITION_MORTON, PETSC_FALSE, &grid, &chs));
  PetscCall(FillOrCompare(grid, chs.cch, PETSC_TRUE, &ndiff));
  PetscCall(FillOrCompare(grid, chs.fch, PETSC_TRUE, &ndiff));
  PetscCall(ChannelChecksum(grid, comm, chs.cch, &csum[0]));
  PetscCall(ChannelChecksum(grid, comm, chs.fch, &csum[1]));
  PetscCall(PffGridGetMortonOrder(grid, &nactive, &order));
  for (int i = 0; i < 4; i++)
    PetscCall(PetscPrintf(comm, "checksum %s %.10e blocks %" PetscInt_FMT "\n", dnames[i], csum[i], nactive));
  PetscCall(PffIOWriteFrame(grid, out, time, step, "test_io"));

  /* The file on its own: final names only, and its checksums equal the grid's. */
  if (rank == 0) {
    char   xmf[PETSC_MAX_PATH_LEN], tmp[PETSC_MAX_PATH_LEN + 8];
    size_t len = strlen(out);
    PetscCall(PetscSNPrintf(xmf, sizeof(xmf), "%.*s.xmf",
                            (int)(len > 3 && !strcmp(out + len - 3, ".h5") ? len - 3 : len), out));
    PetscCheck(access(out, R_OK) == 0 && access(xmf, R_OK) == 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s or %s is missing",
               out, xmf);
    PetscCall(PetscSNPrintf(tmp, sizeof(tmp), "%s.tmp", out));
    PetscCheck(access(tmp, F_OK) != 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s was left behind", tmp);
    PetscCall(PetscSNPrintf(tmp, sizeof(tmp), "%s.tmp", xmf));
    PetscCheck(access(tmp, F_OK) != 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s was left behind", tmp);
    for (int i = 0; i < 4; i++) {
      char     path[64];
      double   fsum    = 0;
      PetscInt fblocks = 0;
      PetscCall(PetscSNPrintf(path, sizeof(path), "/fields/%s", dnames[i]));
      PetscCall(FileChecksum(out, path, step, size, &fsum, &fblocks));
      PetscCheck(fsum == csum[i] && fblocks == nactive, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                 "file checksum of %s is %.17g over %" PetscInt_FMT " blocks, the grid's %.17g over %" PetscInt_FMT,
                 dnames[i], fsum, fblocks, csum[i], nactive);
    }
  }

  /* Read into a METIS-partitioned grid: every value, the time and the step come back exactly. */
  PetscCall(CreateGrid(comm, 8, PFF_PARTITION_METIS, PETSC_FALSE, &grid2, &chs2));
  PetscCall(PffIOReadFrame(grid2, out, &rtime, &rstep));
  PetscCheck(rtime == time && rstep == step, comm, PETSC_ERR_PLIB,
             "time %.17g step %" PetscInt_FMT " read back as %.17g %" PetscInt_FMT, (double)time, step, (double)rtime,
             rstep);
  PetscCall(FillOrCompare(grid2, chs2.cch, PETSC_FALSE, &ndiff));
  PetscCall(FillOrCompare(grid2, chs2.fch, PETSC_FALSE, &ndiff2));
  ndiff += ndiff2;
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &ndiff, 1, MPI_INT64_T, MPI_SUM, comm));
  PetscCheck(ndiff == 0, comm, PETSC_ERR_PLIB, "%" PetscInt64_FMT " values differ after the round trip", ndiff);
  PetscCall(ChannelChecksum(grid2, comm, chs2.cch, &csum2[0]));
  PetscCall(ChannelChecksum(grid2, comm, chs2.fch, &csum2[1]));
  for (int i = 0; i < 4; i++)
    PetscCheck(csum2[i] == csum[i], comm, PETSC_ERR_PLIB, "checksum of %s changed in the round trip", dnames[i]);

  /* A frame does not depend on the partition: the METIS grid writes the same bytes. */
  {
    const char *names[] = {"/grid/level", "/blocks/gid",   "/blocks/level", "/blocks/origin", "/blocks/offset",
                           "/fields/phi", "/fields/vel_x", "/fields/vel_y", "/fields/vel_z"};
    size_t      len     = strlen(out);
    PetscCall(PetscSNPrintf(out2, sizeof(out2), "%.*s_metis.h5",
                            (int)(len > 3 && !strcmp(out + len - 3, ".h5") ? len - 3 : len), out));
    PetscCall(PffIOWriteFrame(grid2, out2, time, step, "test_io"));
    if (rank == 0)
      for (size_t i = 0; i < sizeof(names) / sizeof(names[0]); i++) PetscCall(CompareDataset(out, out2, names[i]));
  }

  /* The level map of the file is the grid's. */
  {
    PetscInt        nb[3], fnb[3], *flevel;
    const PetscInt *level;
    PetscCall(PffGridGetRaster(grid, nb, &level, NULL));
    PetscCall(PffIOReadLevels(comm, out, fnb, &flevel));
    PetscCheck(fnb[0] == nb[0] && fnb[1] == nb[1] && fnb[2] == nb[2], comm, PETSC_ERR_PLIB,
               "PffIOReadLevels: wrong raster");
    for (PetscInt b = 0; b < nb[0] * nb[1] * nb[2]; b++)
      PetscCheck(flevel[b] == level[b], comm, PETSC_ERR_PLIB, "PffIOReadLevels: block %" PetscInt_FMT " differs", b);
    PetscCall(PetscFree(flevel));
  }

  /* Error paths: each fails on every rank with a message naming the problem. */
  PetscCall(PetscSNPrintf(missing, sizeof(missing), "%s.missing", out));
  PetscCall(ExpectReadError(grid2, missing, "no such file"));
  PetscCall(CreateGrid(comm, 16, PFF_PARTITION_MORTON, PETSC_FALSE, &bad, &chsbad));
  PetscCall(ExpectReadError(bad, out, "was written on another grid: -grid_block_size 8 in the file, 16 now"));
  PetscCall(PffGridDestroy(&bad));
  PetscCall(CreateGrid(comm, 8, PFF_PARTITION_MORTON, PETSC_TRUE, &bad, &chsbad));
  PetscCall(PetscSNPrintf(expect, sizeof(expect), "channel extra (cell) is missing"));
  PetscCall(ExpectReadError(bad, out, expect));
  PetscCall(PffGridDestroy(&bad));

  PetscCall(PetscPrintf(comm, "io round trip OK\n"));
  PetscCall(PffGridDestroy(&grid2));
  PetscCall(PffGridDestroy(&grid));
  PetscCall(PetscFinalize());
  return 0;
}
