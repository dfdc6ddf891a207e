/* Unit test of PffGridLocate and PffGridInterpolate on multi-level grids at any rank count.

   Two pseudo-random graded 3-level rasters (n0 = 8): one walled on all sides, one periodic in x with
   inactive blocks. A cell channel and a face channel (width 1) hold linear functions of each value's
   sample position (one function per face component; the periodic case's functions do not depend
   on x). After a halo exchange, at 2000 pseudo-random points per rank inside locally owned blocks and
   at least 4 h0 (a level-2 cell) from walls and inactive blocks in the max norm, PffGridInterpolate
   must return the linear function to 1e-5 of the field's scale, for every face component on its own
   staggered lattice; in the periodic case points are also shifted by a period. Interpolating at a
   sample position (anywhere, walls included) must return the stored sample exactly.
   PffGridLocate must return the block whose box holds the (wrapped) point, the raster's level and the
   cell floor((x - lo) / h); -1 outside walled axes and in inactive blocks; block corners belong to the
   block above them.

   Sample run:  mpiexec -n 4 ./test_interp
   Prints (the same on any number of ranks) one "ok" line per raster and channel. */
#include "pfftest.h"

static const char help[] = "Point location and trilinear interpolation on multi-level grids.\n";

#define N0 8
#define NLEVELS 3
#define NPOINTS 2000

/* Uniform in [0, 1) with 53 random bits. */
static PetscReal Uniform01(uint64_t h)
{
  return (PetscReal)(h >> 11) / 9007199254740992.0;
}

typedef struct {
  const char *name;
  PetscInt    nb[3];
  PetscBool   periodic[3];
  PetscInt    inactive; /* percentage of requested-inactive blocks */
  uint64_t    seed;
} Case;

typedef PffTestCtx Ctx;

static PetscErrorCode CreateGrid(MPI_Comm comm, const Case *c, Ctx *ctx)
{
  const PetscReal origin[3] = {0.375, -1.25, 0.5};

  PetscFunctionBeginUser;
  PetscCall(PffTestCreateGrid(comm, c->nb, c->periodic, origin, 1.0 / 16, N0, NLEVELS, -1, c->inactive, c->seed, ctx));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode FillLinear(const Ctx *ctx, PetscInt ch)
{
  PffTestLinearFill fill = {ctx, 0};

  PetscFunctionBeginUser;
  PetscCall(PffGridFillChannel(ctx->grid, ch, PffTestLinearValue, &fill));
  PetscCall(PffGridHaloBegin(ctx->grid, ch));
  PetscCall(PffGridHaloEnd(ctx->grid, ch));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Whether x (in block gid) is at least dist from every wall and inactive block, in the max norm. */
static PetscBool FarFromHoles(const Ctx *ctx, PetscInt gid, const PetscReal x[3], PetscReal dist)
{
  const PetscInt ijk[3] = {gid % ctx->nb[0], (gid / ctx->nb[0]) % ctx->nb[1], gid / (ctx->nb[0] * ctx->nb[1])};
  for (PetscInt r = 0; r < 27; r++) {
    const PetscInt d[3] = {r % 3 - 1, (r / 3) % 3 - 1, r / 9 - 1};
    const PetscInt nbr  = PffRasterNeighbour(ctx->nb, ctx->periodic, ijk, d);
    if (r == 13 || (nbr >= 0 && ctx->level[nbr] >= 0)) continue;
    /* max-norm distance from x to the neighbour's box, which lies beside gid's box */
    PetscReal m = 0;
    for (int a = 0; a < 3; a++) {
      const PetscReal lo = ctx->origin[a] + (PetscReal)((ijk[a] + d[a]) * N0) * ctx->h0, hi = lo + ctx->blen;
      m = PetscMax(m, x[a] < lo ? lo - x[a] : (x[a] > hi ? x[a] - hi : 0.0));
    }
    if (m < dist) return PETSC_FALSE;
  }
  return PETSC_TRUE;
}

/* Locate x and check the answer against the raster: expect is the block that holds x, or -1. */
static PetscErrorCode CheckLocate(const Ctx *ctx, const PetscReal x[3], PetscInt expect, const char what[])
{
  PetscInt gid, level = -2, cell[3] = {-1, -1, -1};

  PetscFunctionBeginUser;
  PetscCall(PffGridLocate(ctx->grid, x, &gid, &level, cell));
  if (expect >= 0 && ctx->level[expect] < 0) expect = -1;
  PetscCheck(gid == expect, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "%s: PffGridLocate(%.17g, %.17g, %.17g) gives block %" PetscInt_FMT ", expected %" PetscInt_FMT, what,
             (double)x[0], (double)x[1], (double)x[2], gid, expect);
  if (gid < 0) PetscFunctionReturn(PETSC_SUCCESS);
  const PetscInt  ijk[3] = {gid % ctx->nb[0], (gid / ctx->nb[0]) % ctx->nb[1], gid / (ctx->nb[0] * ctx->nb[1])};
  const PetscReal h      = ctx->h0 * (PetscReal)(1 << ctx->level[gid]);
  PetscCheck(level == ctx->level[gid], PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "%s: PffGridLocate gives level %" PetscInt_FMT " for block %" PetscInt_FMT " of level %" PetscInt_FMT,
             what, level, gid, ctx->level[gid]);
  for (int a = 0; a < 3; a++) {
    const PetscReal len = ctx->blen * ctx->nb[a], lo = ctx->origin[a] + (PetscReal)(ijk[a] * N0) * ctx->h0;
    PetscReal       xa = x[a];
    if (ctx->periodic[a]) {
      while (xa < ctx->origin[a]) xa += len;
      while (xa >= ctx->origin[a] + len) xa -= len;
    }
    PetscCheck(xa >= lo && xa < lo + ctx->blen, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "%s: point %.17g on axis %d is not in block %" PetscInt_FMT " [%g, %g)", what, (double)xa, a, gid,
               (double)lo, (double)(lo + ctx->blen));
    /* on a cell face (to rounding) either side is right */
    const PetscReal s = (xa - lo) / h, r = PetscFloorReal(s + 0.5);
    const PetscInt  c = (PetscInt)PetscFloorReal(s);
    PetscCheck(cell[a] == c || (PetscAbsReal(s - r) < 1e-9 && (cell[a] == (PetscInt)r || cell[a] == (PetscInt)r - 1)),
               PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "%s: PffGridLocate gives cell %" PetscInt_FMT " on axis %d, expected %" PetscInt_FMT, what, cell[a], a,
               c);
    PetscCheck(cell[a] >= 0 && cell[a] < N0 >> level, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "%s: PffGridLocate gives cell %" PetscInt_FMT " outside the block", what, cell[a]);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Locate over the whole raster (any rank can locate any point): random interior points, block
   corners, and points outside the domain. */
static PetscErrorCode TestLocate(const Ctx *ctx, const char cname[])
{
  char what[128];

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s locate", cname));
  for (PetscInt g = 0; g < ctx->nblocks; g++) {
    const PetscInt ijk[3] = {g % ctx->nb[0], (g / ctx->nb[0]) % ctx->nb[1], g / (ctx->nb[0] * ctx->nb[1])};
    PetscReal      lo[3], x[3];
    for (int a = 0; a < 3; a++) lo[a] = ctx->origin[a] + (PetscReal)(ijk[a] * N0) * ctx->h0;
    for (int q = 0; q < 8; q++) {
      for (int a = 0; a < 3; a++)
        x[a] = lo[a] + Uniform01(PffTestKey(7, (uint64_t)g, (uint64_t)q, (uint64_t)a)) * ctx->blen;
      PetscCall(CheckLocate(ctx, x, g, what));
    }
    PetscCall(CheckLocate(ctx, lo, g, what));
    /* the same points one period away on each periodic axis */
    for (int a = 0; a < 3; a++) {
      if (!ctx->periodic[a]) continue;
      for (int s = -1; s <= 1; s += 2) {
        PetscReal y[3] = {lo[0], lo[1], lo[2]};
        y[a] += s * ctx->blen * ctx->nb[a];
        PetscCall(CheckLocate(ctx, y, g, what));
      }
    }
  }
  /* outside the domain on walled axes; the upper domain face belongs to no block */
  for (int a = 0; a < 3; a++) {
    if (ctx->periodic[a]) continue;
    PetscReal x[3];
    for (int b = 0; b < 3; b++) x[b] = ctx->origin[b] + 0.5 * ctx->h0;
    x[a] = ctx->origin[a] - 0.25 * ctx->h0;
    PetscCall(CheckLocate(ctx, x, -1, what));
    x[a] = ctx->origin[a] + ctx->blen * ctx->nb[a];
    PetscCall(CheckLocate(ctx, x, -1, what));
  }
  PetscCall(PetscPrintf(ctx->comm, "interp %s: locate ok\n", cname));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode TestInterpolate(const Ctx *ctx, const char cname[], PetscInt ch)
{
  PetscInt       ncomp, np = 0, attempts = 0;
  PffChannelKind kind;
  PetscReal     *x, *val;
  char           what[128];

  PetscFunctionBeginUser;
  PetscCall(PffGridGetChannelInfo(ctx->grid, ch, NULL, &kind, &ncomp, NULL));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s %s", cname, PffChannelKinds[kind]));
  const PetscReal tol = 1e-5 * PffTestFieldScale(ctx, ncomp, 0);
  PetscCall(PetscMalloc2(3 * NPOINTS, &x, ncomp * NPOINTS, &val));

  /* random points in local blocks, away from walls and inactive blocks */
  while (ctx->nlocal > 0 && np < NPOINTS) {
    const uint64_t key = PffTestKey((uint64_t)ctx->rank, (uint64_t)ch, (uint64_t)attempts++, 11);
    const PetscInt lb  = (PetscInt)(key % (uint64_t)ctx->nlocal);
    PffBlockInfo   info;
    PetscReal     *p = &x[3 * np];
    PetscCheck(attempts < 100 * NPOINTS, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: too few points away from walls", what);
    PetscCall(PffGridGetBlockInfo(ctx->grid, lb, &info));
    for (int a = 0; a < 3; a++) p[a] = info.lo[a] + Uniform01(PffTestKey(key, (uint64_t)a, 0, 0)) * ctx->blen;
    if (!FarFromHoles(ctx, info.gid, p, 4 * ctx->h0)) continue;
    PetscCall(CheckLocate(ctx, p, info.gid, what));
    for (int a = 0; a < 3; a++)
      if (ctx->periodic[a])
        p[a] += (PetscReal)((PetscInt)(PffTestKey(key, 5, (uint64_t)a, 0) % 3) - 1) * ctx->blen * ctx->nb[a];
    np++;
  }
  PetscCall(PffGridInterpolate(ctx->grid, ch, np, x, val));
  for (PetscInt p = 0; p < np; p++)
    for (PetscInt comp = 0; comp < ncomp; comp++) {
      const PetscReal f = PffTestLinear(ctx, comp, &x[3 * p]);
      PetscCheck(PetscAbsReal(val[p * ncomp + comp] - f) <= tol, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                 "%s: interpolated comp %" PetscInt_FMT " at (%.17g, %.17g, %.17g) is %.9g, the linear field is %.9g",
                 what, comp, (double)x[3 * p], (double)x[3 * p + 1], (double)x[3 * p + 2],
                 (double)val[p * ncomp + comp], (double)f);
    }

  /* at a sample position the interpolant is the sample, walls and inactive neighbours included */
  for (PetscInt lb = 0; lb < ctx->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(ctx->grid, lb, &info));
    for (PetscInt comp = 0; comp < ncomp; comp++) {
      float *data;
      PetscCall(PffGridGetBlockData(ctx->grid, ch, lb, comp, &data));
      for (PetscInt s = 0; s < 8; s++) {
        PetscInt  c[3];
        PetscReal p[3], v[3];
        for (int a = 0; a < 3; a++) {
          /* the first, the last, then random cells */
          c[a] = s == 0 ? 0
                        : (s == 1 ? info.n - 1
                                  : (PetscInt)(PffTestKey((uint64_t)info.gid, (uint64_t)s, (uint64_t)a, 3) %
                                               (uint64_t)info.n));
          p[a] = info.lo[a] + ((PetscReal)c[a] + (kind == PFF_CHANNEL_FACE && comp == a ? 0.0 : 0.5)) * info.h;
        }
        PetscCall(PffGridInterpolate(ctx->grid, ch, 1, p, v));
        const float sample = data[c[0] + info.n * (c[1] + info.n * c[2])];
        PetscCheck(v[comp] == (PetscReal)sample, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                   "%s: at the sample position of cell (%" PetscInt_FMT ",%" PetscInt_FMT ",%" PetscInt_FMT
                   ") of block %" PetscInt_FMT " comp %" PetscInt_FMT " the interpolant is %.9g, the sample %.9g",
                   what, c[0], c[1], c[2], info.gid, comp, (double)v[comp], (double)sample);
      }
    }
  }
  PetscCall(PetscFree2(x, val));
  PetscCall(PetscPrintf(ctx->comm, "interp %s: %d points per rank, linear exact, samples exact, ok\n", what, NPOINTS));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscReal OnePlusXPlusY(const PetscReal x[3], PetscInt comp, void *ctx)
{
  return 1 + x[0] + x[1];
}

/* Two regressions: (1) a point near an inactive diagonal (edge) neighbour whose face neighbours are
   active must clamp instead of reading that region's zero ghosts: on f = 1 + x + y the value at
   (7.75, 7.75, 4) beside the inactive block (1,1,0) is a clamped value (16) and never the 15.375
   that mixing in a zero gives; (2) a point a hair below a periodic lower boundary wraps into block 0. */
static PetscErrorCode TestRegressions(void)
{
  PffGrid   grid;
  PetscInt  cells[3] = {16, 16, 8}, map[4] = {0, 0, 0, -1}, ch, nlocal, gid = -1;
  PetscReal origin[3] = {0, 0, 0}, x[3] = {7.75, 7.75, 4}, v = 0, y[3] = {-1e-17, 0.5, 0.5};
  PetscBool per[3] = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};

  PetscFunctionBeginUser;
  PetscCall(PffGridCreate(PETSC_COMM_WORLD, &grid));
  PetscCall(PffGridSetCells(grid, cells));
  PetscCall(PffGridSetBlockSize(grid, 8));
  PetscCall(PffGridSetDomain(grid, origin, 1.0));
  PetscCall(PffGridSetPeriodic(grid, per));
  PetscCall(PffGridSetRefinementMap(grid, map));
  PetscCall(PffGridAddChannel(grid, "f", PFF_CHANNEL_CELL, 1, &ch));
  PetscCall(PffGridSetUp(grid));
  PetscCall(PffGridGetLocalBlocks(grid, &nlocal));
  PetscCall(PffGridFillChannel(grid, ch, OnePlusXPlusY, NULL));
  PetscCall(PffGridHaloBegin(grid, ch));
  PetscCall(PffGridHaloEnd(grid, ch));
  PetscCall(PffGridLocate(grid, x, &gid, NULL, NULL));
  PetscInt lb;
  PetscCall(PffGridGetLocalIndex(grid, gid, &lb));
  if (lb >= 0) {
    PetscCall(PffGridInterpolate(grid, ch, 1, x, &v));
    PetscCheck(PetscAbsReal(v - 16.0) < 1e-6, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "interpolation beside an inactive edge neighbour gave %g, expected the clamped 16", (double)v);
  }
  PetscCall(PffGridDestroy(&grid));

  PetscInt c2[3] = {16, 16, 16};
  per[0] = per[1] = per[2] = PETSC_TRUE;
  PetscCall(PffGridCreate(PETSC_COMM_WORLD, &grid));
  PetscCall(PffGridSetCells(grid, c2));
  PetscCall(PffGridSetBlockSize(grid, 8));
  PetscCall(PffGridSetDomain(grid, origin, 1.0 / 16));
  PetscCall(PffGridSetPeriodic(grid, per));
  PetscCall(PffGridSetUp(grid));
  PetscCall(PffGridLocate(grid, y, &gid, NULL, NULL));
  PetscCheck(gid == 0 + 2 * (1 + 2 * 1), PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "a point a hair below the periodic lower boundary was located in block %" PetscInt_FMT ", expected 6",
             gid);
  PetscCall(PffGridDestroy(&grid));
  PetscCall(
      PetscPrintf(PETSC_COMM_WORLD, "regressions: inactive edge neighbour clamps, periodic wrap below origin ok\n"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  const Case cases[] = {
      {"5x4x3 walls", {5, 4, 3}, {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE}, 0, 31},
      {"4x3x5 periodic x inactive", {4, 3, 5}, {PETSC_TRUE, PETSC_FALSE, PETSC_FALSE}, 12, 32},
  };

  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(PffInitializePackage());
  for (size_t c = 0; c < PETSC_STATIC_ARRAY_LENGTH(cases); c++) {
    Ctx        ctx;
    PetscInt   cch, fch;
    PetscInt64 pl[PFF_GRID_MAX_LEVELS];
    PetscCall(CreateGrid(PETSC_COMM_WORLD, &cases[c], &ctx));
    PetscCall(PffGridGetCellCounts(ctx.grid, pl, NULL));
    PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                          "raster %s: cells per level %" PetscInt64_FMT " %" PetscInt64_FMT " %" PetscInt64_FMT "\n",
                          cases[c].name, pl[0], pl[1], pl[2]));
    PetscCall(PffGridAddChannel(ctx.grid, "phi", PFF_CHANNEL_CELL, 1, &cch));
    PetscCall(PffGridAddChannel(ctx.grid, "vel", PFF_CHANNEL_FACE, 1, &fch));
    PetscCall(FillLinear(&ctx, cch));
    PetscCall(FillLinear(&ctx, fch));
    PetscCall(TestLocate(&ctx, cases[c].name));
    PetscCall(TestInterpolate(&ctx, cases[c].name, cch));
    PetscCall(TestInterpolate(&ctx, cases[c].name, fch));
    PetscCall(PffGridDestroy(&ctx.grid));
  }
  PetscCall(TestRegressions());
  PetscCall(PetscFinalize());
  return 0;
}
