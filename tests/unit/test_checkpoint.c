/* Unit test of checkpoints and particle frames: a checkpoint restarts exactly on any number of ranks,
   survives a writer killed half-way, and rejects what it cannot restart from.

   Builds a 2-level grid (4x4x2 blocks of 8^3 cells, the upper layer of blocks at level 1) with a cell
   channel "phi" and a face channel "aux" whose output flag is off, fills both from a function of the
   world position, and seeds 8 particles per cell (liquid below z = 0.2, air above). Then:
   - writes a checkpoint (with 2 extra values) and reads it back into a fresh grid and an empty store:
     time, step, extra values, the global count and mass per type, the multiset of ids (sum and xor of
     hash(id)), the sum of hash(id) * bits(x_d) and hash(id) * bits(v_d) (mod 2^64, so exact and
     independent of the order: every bit of every position and velocity must come back on the right
     particle) and the checksum of both channels (hash of block and cell times the value's bits) agree;
   - cross rank count: the checkpoint written on all ranks is read on one rank (MPI_Comm_split), and
     one written on one rank is read on all ranks, with the same invariants;
   - crash safety: garbage in <path>.tmp (what a killed writer leaves) does not hurt the checkpoint at
     <path>; the next write replaces it and removes the .tmp;
   - errors: a missing file, a plain frame and a checkpoint of another raster fail with messages naming
     them;
   - frames: PffIOWriteFrameParticles writes /particles (float32 x, the right count, every row equal
     to the checkpoint's rounded to float) and leaves the hidden channel out of /fields and of the .xmf,
     whose particle grid is a Polyvertex; reading that frame leaves the hidden channel untouched;
   - a particle row with an impossible type in the checkpoint's last rows fails the restart, naming the
     row (every chunk of the read is checked).
   Particles move -particles_io_chunk rows per collective call (default 2^20: one call here); the
   ctest cases with 1000 rows (the option at 2 ranks, PffParticlesSetIOChunk through -api_io_chunk at 4) take many
   calls, a different number on each rank.

   Sample run:  mpiexec -n 4 ./test_checkpoint -prefix /tmp/ckpt [-particles_io_chunk 1000 | -api_io_chunk 1000]
   Prints (the same on any number of ranks): the particle counts, masses and checksums. */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>
#include <hdf5.h>
#include <pff.h>
#include "pfftest.h"

static const char help[] = "Checkpoint and particle-frame round trips.\n"
                           "  -prefix <name>  prefix of the files written (default test_checkpoint)\n"
                           "  -particles_io_chunk <rows>  particles per collective transfer\n"
                           "  -api_io_chunk <rows>  the same through PffParticlesSetIOChunk\n";

static const PetscReal density[PFF_PARTICLE_NTYPES] = {1000.0, 1.0};

typedef struct {
  PetscInt64 count[PFF_PARTICLE_NTYPES];
  PetscReal  mass[PFF_PARTICLE_NTYPES];
  uint64_t   idsum, idxor, xsum, vsum, chsum;
} Invariants;

/* raster 4x4x2 blocks of n0 = 8; the blocks of the upper layer are at level 1 unless coarse = 0.
   Channel 0 "phi" (cell, written to frames), channel 1 "aux" (face, output flag off). */
static PetscErrorCode CreateGrid(MPI_Comm comm, PetscBool coarse, PffGrid *grid)
{
  const PetscInt  cells[3] = {32, 32, 16}, nb[3] = {4, 4, 2};
  const PetscReal origin[3] = {0.0, 0.0, 0.0};
  PetscInt        level[32], ch;

  PetscFunctionBeginUser;
  for (PetscInt b = 0; b < nb[0] * nb[1] * nb[2]; b++) level[b] = (coarse && b >= nb[0] * nb[1]) ? 1 : 0;
  PetscCall(PffGridCreate(comm, grid));
  PetscCall(PffGridSetCells(*grid, cells));
  PetscCall(PffGridSetBlockSize(*grid, 8));
  PetscCall(PffGridSetLevels(*grid, 2));
  PetscCall(PffGridSetDomain(*grid, origin, 1.0 / 32));
  PetscCall(PffGridSetRefinementMap(*grid, level));
  PetscCall(PffGridSetUp(*grid));
  PetscCall(PffGridAddChannel(*grid, "phi", PFF_CHANNEL_CELL, 1, &ch));
  PetscCall(PffGridAddChannel(*grid, "aux", PFF_CHANNEL_FACE, 1, &ch));
  PetscCall(PffGridSetChannelOutput(*grid, ch, PETSC_FALSE));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode Fill(PffGrid grid, PetscInt ch, float shift)
{
  PetscInt nlocal, ncomp;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetLocalBlocks(grid, &nlocal));
  PetscCall(PffGridGetChannelInfo(grid, ch, NULL, NULL, &ncomp, NULL));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(grid, lb, &info));
    for (PetscInt comp = 0; comp < ncomp; comp++) {
      float *d;
      PetscCall(PffGridGetBlockData(grid, ch, lb, comp, &d));
      for (PetscInt c = 0; c < info.n * info.n * info.n; c++) {
        const PetscInt i = c % info.n, j = (c / info.n) % info.n, k = c / (info.n * info.n);
        const double   x = info.lo[0] + (i + 0.5) * info.h, y = info.lo[1] + (j + 0.5) * info.h;
        const double   z = info.lo[2] + (k + 0.5) * info.h;
        d[c]             = shift + (float)(sin(7.0 * x + comp) * cos(3.0 * y) + z * z);
      }
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Order-independent exact checksum of every owned value of every channel: sum of hash(gid, comp, cell)
   times the float's bits, mod 2^64. */
static PetscErrorCode ChannelSum(PffGrid grid, PetscInt ch, uint64_t *sum)
{
  PetscInt nlocal, ncomp;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetLocalBlocks(grid, &nlocal));
  PetscCall(PffGridGetChannelInfo(grid, ch, NULL, NULL, &ncomp, NULL));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(grid, lb, &info));
    for (PetscInt comp = 0; comp < ncomp; comp++) {
      float *d;
      PetscCall(PffGridGetBlockData(grid, ch, lb, comp, &d));
      for (PetscInt c = 0; c < info.n * info.n * info.n; c++) {
        uint32_t bits;
        memcpy(&bits, &d[c], sizeof(bits));
        *sum += PffTestKey((uint64_t)ch, (uint64_t)info.gid, (uint64_t)comp, (uint64_t)c) * (uint64_t)bits;
      }
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode GetInvariants(PffGrid grid, PffParticles p, Invariants *inv)
{
  PffParticleArrays a;
  MPI_Comm          comm;
  uint64_t          loc[4] = {0, 0, 0, 0}, lxor = 0;
  PetscInt          nch;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetComm(grid, &comm));
  PetscCall(PffParticlesGetTotals(p, density, inv->count, inv->mass));
  PetscCall(PffParticlesGetArrays(p, &a));
  for (PetscInt i = 0; i < a.n; i++) {
    const uint64_t h = PffTestHash64(a.id[i]);
    loc[0] += h;
    lxor ^= h;
    for (int d = 0; d < 3; d++) {
      uint32_t xb, vb; /* the stored floats' bits */
      memcpy(&xb, &a.x[3 * i + d], sizeof(xb));
      memcpy(&vb, &a.v[3 * i + d], sizeof(vb));
      loc[1] += PffTestHash64(a.id[i] * 3 + (uint64_t)d) * xb;
      loc[2] += PffTestHash64(a.id[i] * 3 + (uint64_t)d + 1000) * vb;
    }
    loc[1] += PffTestHash64(a.id[i] ^ 0x5555) * (uint64_t)a.word[i];
  }
  PetscCall(PffGridGetNumChannels(grid, &nch));
  for (PetscInt c = 0; c < nch; c++) PetscCall(ChannelSum(grid, c, &loc[3]));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, loc, 4, MPI_UINT64_T, MPI_SUM, comm));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &lxor, 1, MPI_UINT64_T, MPI_BXOR, comm));
  inv->idsum = loc[0];
  inv->xsum  = loc[1];
  inv->vsum  = loc[2];
  inv->chsum = loc[3];
  inv->idxor = lxor;
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode CompareInvariants(const Invariants *a, const Invariants *b, const char what[])
{
  PetscFunctionBeginUser;
  for (int t = 0; t < PFF_PARTICLE_NTYPES; t++) {
    PetscCheck(a->count[t] == b->count[t], PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "%s: %s particle count %" PetscInt64_FMT " != %" PetscInt64_FMT, what, PffParticleTypes[t], b->count[t],
               a->count[t]);
    PetscCheck(a->mass[t] == b->mass[t], PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: %s mass %.17g != %.17g", what,
               PffParticleTypes[t], (double)b->mass[t], (double)a->mass[t]);
  }
  PetscCheck(a->idsum == b->idsum && a->idxor == b->idxor, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "%s: the multiset of particle ids differs", what);
  PetscCheck(a->xsum == b->xsum, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "%s: particle positions (or type, level, flags) are not bit-identical per id", what);
  PetscCheck(a->vsum == b->vsum, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: particle velocities differ", what);
  PetscCheck(a->chsum == b->chsum, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: channel checksum differs", what);
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode SeedFn(const PetscReal x[3], PetscInt *type, PetscReal v[3], void *ctx)
{
  (void)ctx;
  *type = x[2] < 0.2 ? PFF_PARTICLE_LIQUID : PFF_PARTICLE_AIR;
  v[0]  = PetscSinReal(5 * x[1]);
  v[1]  = PetscCosReal(3 * x[0]) / 3;
  v[2]  = x[0] * x[1] - 0.1;
  return PETSC_SUCCESS;
}

/* An empty store that takes -particles_io_chunk, or -api_io_chunk through the setter. */
static PetscErrorCode CreateParticles(PffGrid grid, PffParticles *p)
{
  PetscInt  rows, got;
  PetscBool set;

  PetscFunctionBeginUser;
  PetscCall(PffParticlesCreate(grid, p));
  PetscCall(PffParticlesSetFromOptions(*p));
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-api_io_chunk", &rows, &set));
  if (set) {
    PetscCall(PffParticlesSetIOChunk(*p, rows));
    PetscCall(PffParticlesGetIOChunk(*p, &got));
    PetscCheck(got == rows, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "PffParticlesSetIOChunk(%" PetscInt_FMT ") left %" PetscInt_FMT, rows, got);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Grid + seeded particles + filled channels on comm, and their invariants. */
static PetscErrorCode BuildState(MPI_Comm comm, PffGrid *grid, PffParticles *p, Invariants *inv)
{
  PetscFunctionBeginUser;
  PetscCall(CreateGrid(comm, PETSC_TRUE, grid));
  PetscCall(Fill(*grid, 0, 0.0f));
  PetscCall(Fill(*grid, 1, 2.0f));
  PetscCall(CreateParticles(*grid, p));
  PetscCall(PffParticlesSeed(*p, SeedFn, NULL));
  if (inv) PetscCall(GetInvariants(*grid, *p, inv));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Reads path into a fresh grid and empty store on comm and compares with the expected invariants. */
static PetscErrorCode ReadAndCompare(MPI_Comm comm, const char path[], const Invariants *expect, PetscInt expectStep,
                                     const char what[])
{
  PffGrid      grid;
  PffParticles p;
  Invariants   inv;
  PetscReal    time = 0, extra[2] = {0, 0};
  PetscInt     step = -1;

  PetscFunctionBeginUser;
  PetscCall(CreateGrid(comm, PETSC_TRUE, &grid));
  PetscCall(CreateParticles(grid, &p));
  PetscCall(PffIOReadCheckpoint(grid, p, path, &time, &step, 2, extra));
  PetscCall(GetInvariants(grid, p, &inv));
  PetscCall(CompareInvariants(expect, &inv, what));
  PetscCheck(time == 0.125 && step == expectStep, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "%s: time %g step %" PetscInt_FMT " (expected 0.125, %" PetscInt_FMT ")", what, (double)time, step,
             expectStep);
  PetscCheck(extra[0] == 1e-3 / 3 && extra[1] == -7.5, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: extra values %.17g %.17g",
             what, (double)extra[0], (double)extra[1]);
  PetscCall(PffParticlesDestroy(&p));
  PetscCall(PffGridDestroy(&grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode ExpectReadError(MPI_Comm comm, PetscBool coarse, const char path[], const char expect[])
{
  PffGrid        grid;
  PffParticles   p;
  PetscReal      extra[2];
  PetscErrorCode ierr;
  const char    *text;
  char          *specific;

  PetscFunctionBeginUser;
  PetscCall(CreateGrid(comm, coarse, &grid));
  PetscCall(CreateParticles(grid, &p));
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  ierr = PffIOReadCheckpoint(grid, p, path, NULL, NULL, 2, extra);
  PetscCall(PetscPopErrorHandler());
  PetscCheck(ierr != PETSC_SUCCESS, PETSC_COMM_SELF, PETSC_ERR_PLIB, "reading %s should have failed (%s)", path,
             expect);
  PetscCall(PetscErrorMessage(ierr, &text, &specific));
  PetscCheck(specific && strstr(specific, expect) && strstr(specific, path), PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "reading %s failed with \"%s\", which does not name the file and \"%s\"", path, specific ? specific : "",
             expect);
  PetscCall(PffParticlesDestroy(&p));
  PetscCall(PffGridDestroy(&grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Rank 0 alone, plain HDF5: /particles of the frame and the hidden channel's absence. */
/* Rows [0, total) of /particles/name in path as memtype (size bytes per row). */
static PetscErrorCode ReadParticleRows(const char path[], const char name[], hid_t memtype, size_t size,
                                       PetscInt64 total, void **buf)
{
  hid_t file, dset;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc(size * (size_t)total + 1, buf));
  PetscCheck((file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT)) >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN,
             "cannot open %s", path);
  dset = H5Dopen2(file, name, H5P_DEFAULT);
  PetscCheck(dset >= 0 && H5Dread(dset, memtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, *buf) >= 0, PETSC_COMM_SELF,
             PETSC_ERR_FILE_READ, "%s: cannot read %s", path, name);
  H5Dclose(dset);
  H5Fclose(file);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The frame's particle rows are the checkpoint's, written from the same store, in float: x and v rounded,
   id, type, level and flags as they are. */
static PetscErrorCode CompareFrameRows(const char frame[], const char ckpt[], PetscInt64 total)
{
  const char *const names[6] = {"/particles/x",    "/particles/v",     "/particles/id",
                                "/particles/type", "/particles/level", "/particles/flags"};
  const hid_t       types[6] = {H5T_NATIVE_FLOAT, H5T_NATIVE_FLOAT, H5T_NATIVE_UINT64,
                                H5T_NATIVE_UINT8, H5T_NATIVE_UINT8, H5T_NATIVE_UINT8};
  const size_t      sizes[6] = {3 * sizeof(float), 3 * sizeof(float), sizeof(uint64_t), 1, 1, 1};

  PetscFunctionBeginUser;
  for (int k = 0; k < 6; k++) {
    void *a, *b;
    PetscCall(ReadParticleRows(frame, names[k], types[k], sizes[k], total, &a));
    PetscCall(ReadParticleRows(ckpt, names[k], types[k], sizes[k], total, &b));
    for (PetscInt64 i = 0; i < total; i++)
      PetscCheck(!memcmp((char *)a + sizes[k] * (size_t)i, (char *)b + sizes[k] * (size_t)i, sizes[k]), PETSC_COMM_SELF,
                 PETSC_ERR_PLIB, "%s row %" PetscInt64_FMT ": the frame's %s differs from %s's", frame, i, names[k],
                 ckpt);
    PetscCall(PetscFree(a));
    PetscCall(PetscFree(b));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Writes type 9 into row `row` of path's /particles/type, as a damaged or foreign file could hold. */
static PetscErrorCode DamageType(const char path[], PetscInt64 row)
{
  const hsize_t start = (hsize_t)row, one = 1;
  const uint8_t bad = 9;
  hid_t         file, dset, fspace, mspace;

  PetscFunctionBeginUser;
  PetscCheck((file = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT)) >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN,
             "cannot open %s", path);
  dset   = H5Dopen2(file, "/particles/type", H5P_DEFAULT);
  fspace = H5Dget_space(dset);
  mspace = H5Screate_simple(1, &one, NULL);
  PetscCheck(H5Sselect_hyperslab(fspace, H5S_SELECT_SET, &start, NULL, &one, NULL) >= 0 &&
                 H5Dwrite(dset, H5T_NATIVE_UINT8, mspace, fspace, H5P_DEFAULT, &bad) >= 0,
             PETSC_COMM_SELF, PETSC_ERR_FILE_WRITE, "%s: cannot write row %" PetscInt64_FMT, path, row);
  H5Sclose(mspace);
  H5Sclose(fspace);
  H5Dclose(dset);
  H5Fclose(file);
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode CheckFrameFile(const char path[], const char xmf[], PetscInt64 total)
{
  hid_t      file, grp, attr, dset, space, type;
  PetscInt64 count   = -1;
  hsize_t    dims[2] = {0, 0};
  FILE      *fp;
  char      *text;
  long       len;

  PetscFunctionBeginUser;
  PetscCheck((file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT)) >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN,
             "cannot open %s", path);
  PetscCheck(H5Lexists(file, "particles", H5P_DEFAULT) > 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: no /particles", path);
  grp  = H5Gopen2(file, "particles", H5P_DEFAULT);
  attr = H5Aopen(grp, "count", H5P_DEFAULT);
  PetscCheck(attr >= 0 && H5Aread(attr, H5T_NATIVE_INT64, &count) >= 0, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "%s: no /particles count", path);
  PetscCheck(count == total, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "%s: /particles count %" PetscInt64_FMT " != %" PetscInt64_FMT, path, count, total);
  dset  = H5Dopen2(grp, "x", H5P_DEFAULT);
  space = H5Dget_space(dset);
  type  = H5Dget_type(dset);
  H5Sget_simple_extent_dims(space, dims, NULL);
  PetscCheck(dims[0] == (hsize_t)total && dims[1] == 3 && H5Tget_size(type) == 4, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "%s: /particles/x is not float32 [%" PetscInt64_FMT ", 3]", path, total);
  H5Tclose(type);
  H5Sclose(space);
  H5Dclose(dset);
  for (int k = 0; k < 4; k++) {
    const char *names[4] = {"v", "id", "type", "level"};
    PetscCheck(H5Lexists(grp, names[k], H5P_DEFAULT) > 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: no /particles/%s", path,
               names[k]);
  }
  PetscCheck(H5Lexists(grp, "flags", H5P_DEFAULT) > 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: no /particles/flags",
             path);
  H5Aclose(attr);
  H5Gclose(grp);
  PetscCheck(H5Lexists(file, "/fields/phi", H5P_DEFAULT) > 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: no /fields/phi",
             path);
  PetscCheck(H5Lexists(file, "/fields/aux_x", H5P_DEFAULT) == 0, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "%s: the hidden channel aux was written", path);
  H5Fclose(file);

  fp = fopen(xmf, "r");
  PetscCheck(fp, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "cannot open %s", xmf);
  fseek(fp, 0, SEEK_END);
  len = ftell(fp);
  rewind(fp);
  PetscCall(PetscCalloc1(len + 1, &text));
  PetscCheck(fread(text, 1, (size_t)len, fp) == (size_t)len, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "cannot read %s",
             xmf);
  fclose(fp);
  PetscCheck(!strstr(text, "/fields/aux"), PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s lists the hidden channel aux", xmf);
  PetscCheck(strstr(text, "/fields/phi"), PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s does not list phi", xmf);
  PetscCheck(strstr(text, "TopologyType=\"Polyvertex\"") && strstr(text, ":/particles/x") &&
                 strstr(text, ":/particles/v") && strstr(text, ":/particles/type"),
             PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s has no particle grid", xmf);
  PetscCall(PetscFree(text));
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  const PetscReal time = 0.125, extra[2] = {1e-3 / 3, -7.5};
  char            prefix[PETSC_MAX_PATH_LEN] = "test_checkpoint";
  char            ckpt[PETSC_MAX_PATH_LEN + 32], ckpt1[PETSC_MAX_PATH_LEN + 32], tmp[PETSC_MAX_PATH_LEN + 40];
  char            frame[PETSC_MAX_PATH_LEN + 32], xmf[PETSC_MAX_PATH_LEN + 32], missing[PETSC_MAX_PATH_LEN + 32];
  MPI_Comm        comm, one;
  PetscMPIInt     rank, size;
  PffGrid         grid;
  PffParticles    p;
  Invariants      inv;

  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(PffInitializePackage());
  comm = PETSC_COMM_WORLD;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscOptionsBegin(comm, NULL, "checkpoint test", NULL);
  PetscCall(PetscOptionsString("-prefix", "Prefix of the files written", NULL, prefix, prefix, sizeof(prefix), NULL));
  PetscOptionsEnd();
  PetscCall(PetscSNPrintf(ckpt, sizeof(ckpt), "%s.ckpt.h5", prefix));
  PetscCall(PetscSNPrintf(ckpt1, sizeof(ckpt1), "%s.ckpt1.h5", prefix));
  PetscCall(PetscSNPrintf(tmp, sizeof(tmp), "%s.tmp", ckpt));
  PetscCall(PetscSNPrintf(frame, sizeof(frame), "%s_frame.h5", prefix));
  PetscCall(PetscSNPrintf(xmf, sizeof(xmf), "%s_frame.xmf", prefix));
  PetscCall(PetscSNPrintf(missing, sizeof(missing), "%s.missing.h5", prefix));
  PetscCallMPI(MPI_Comm_split(comm, rank == 0 ? 0 : MPI_UNDEFINED, 0, &one));

  /* Round trip on the current communicator. */
  PetscCall(BuildState(comm, &grid, &p, &inv));
  PetscCall(PetscPrintf(comm, "particles liquid %" PetscInt64_FMT " air %" PetscInt64_FMT " mass %.6e %.6e\n",
                        inv.count[0], inv.count[1], (double)inv.mass[0], (double)inv.mass[1]));
  PetscCall(PetscPrintf(comm,
                        "checksums ids %016" PRIx64 " x %016" PRIx64 " v %016" PRIx64 " channels %016" PRIx64 "\n",
                        inv.idsum, inv.xsum, inv.vsum, inv.chsum));
  PetscCall(PffIOWriteCheckpoint(grid, p, ckpt, time, 7, 2, extra, "test_checkpoint"));
  PetscCall(ReadAndCompare(comm, ckpt, &inv, 7, "round trip"));

  /* Written on all ranks, read on one. */
  if (one != MPI_COMM_NULL) PetscCall(ReadAndCompare(one, ckpt, &inv, 7, "written on all ranks, read on one"));
  PetscCallMPI(MPI_Barrier(comm));

  /* Written on one rank, read on all. */
  if (one != MPI_COMM_NULL) {
    PffGrid      g1;
    PffParticles p1;
    Invariants   inv1;
    PetscCall(BuildState(one, &g1, &p1, &inv1));
    PetscCall(CompareInvariants(&inv, &inv1, "seeding on one rank"));
    PetscCall(PffIOWriteCheckpoint(g1, p1, ckpt1, time, 7, 2, extra, "test_checkpoint"));
    PetscCall(PffParticlesDestroy(&p1));
    PetscCall(PffGridDestroy(&g1));
  }
  PetscCallMPI(MPI_Barrier(comm));
  PetscCall(ReadAndCompare(comm, ckpt1, &inv, 7, "written on one rank, read on all"));

  /* A writer killed half-way leaves garbage in <path>.tmp; the checkpoint itself is intact. */
  if (rank == 0) {
    FILE *fp = fopen(tmp, "w");
    PetscCheck(fp, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "cannot create %s", tmp);
    fputs("\x89HDF\r\n\x1a\n half-written garbage of a killed writer", fp);
    fclose(fp);
  }
  PetscCallMPI(MPI_Barrier(comm));
  PetscCall(ReadAndCompare(comm, ckpt, &inv, 7, "beside a stale .tmp"));
  PetscCall(PffIOWriteCheckpoint(grid, p, ckpt, time, 8, 2, extra, "test_checkpoint"));
  PetscCheck(access(tmp, F_OK) != 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s is still there after a new write", tmp);
  PetscCall(ReadAndCompare(comm, ckpt, &inv, 8, "rewritten"));

  /* Frames: particles in single precision, the hidden channel absent. */
  PetscCall(PffIOWriteFrameParticles(grid, p, frame, time, 9, "test_checkpoint"));
  if (rank == 0) PetscCall(CheckFrameFile(frame, xmf, inv.count[0] + inv.count[1]));
  if (rank == 0) PetscCall(CompareFrameRows(frame, ckpt, inv.count[0] + inv.count[1]));
  {
    PffGrid  g2;
    uint64_t s0 = 0, s1 = 0, r0 = 0, r1 = 0;
    PetscCall(CreateGrid(comm, PETSC_TRUE, &g2));
    PetscCall(Fill(g2, 1, -5.0f));
    PetscCall(ChannelSum(grid, 0, &s0));
    PetscCall(ChannelSum(g2, 1, &s1));
    PetscCall(PffIOReadFrame(g2, frame, NULL, NULL));
    PetscCall(ChannelSum(g2, 0, &r0));
    PetscCall(ChannelSum(g2, 1, &r1));
    PetscCheck(s0 == r0 && s1 == r1, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "frame read: phi must round-trip and the hidden channel aux stay untouched");
    PetscCall(PffGridDestroy(&g2));
  }

  /* Errors, each naming the file and what is wrong. */
  PetscCall(ExpectReadError(comm, PETSC_TRUE, missing, "no such file"));
  PetscCall(ExpectReadError(comm, PETSC_TRUE, frame, "not a checkpoint"));
  PetscCall(ExpectReadError(comm, PETSC_FALSE, ckpt, "has level 1 in the file but 0 in the grid"));
  {
    char             expect[64];
    const PetscInt64 row = inv.count[0] + inv.count[1] - 3;
    PetscCall(PetscSNPrintf(expect, sizeof(expect), "particle row %" PetscInt64_FMT " has a type", row));
    if (rank == 0) PetscCall(DamageType(ckpt1, row));
    PetscCallMPI(MPI_Barrier(comm));
    PetscCall(ExpectReadError(comm, PETSC_TRUE, ckpt1, expect));
  }
  PetscCall(PetscPrintf(comm, "checkpoint round trips, cross-rank restart, crash safety, errors and frames: ok\n"));

  if (one != MPI_COMM_NULL) PetscCallMPI(MPI_Comm_free(&one));
  PetscCall(PffParticlesDestroy(&p));
  PetscCall(PffGridDestroy(&grid));
  PetscCall(PetscFinalize());
  return 0;
}
