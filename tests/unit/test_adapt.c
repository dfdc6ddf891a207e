/* Unit test of PffGridAdapt (docs/grid.md, "Adaptation").

   Each case sets up a 3-level grid (n0 = 8) from one pseudo-random map A and adapts it to another, B
   (different levels, blocks that appear and go, owners that change), with five channels: a linear cell
   channel and a linear face channel of width 2 (linear transfer), a random cell channel (linear), a
   random face channel (constant) and a scratch channel (none). Checks:
   - the adapted raster (levels, owners, local blocks, Morton order) equals a grid set up with B;
   - every active block is owned by exactly one rank;
   - linear fields arrive exact (1e-5 of the field's scale) in every block active before, refined,
     coarsened (by up to two levels) or kept; new blocks and the scratch channel are zero;
   - the integral of the random cell channel over the blocks active in A and B is unchanged (1e-6);
   - after a halo exchange every face ghost of the linear cell channel facing an active block equals
     the linear field there (views and plans rebuilt);
   - the adapt's counts match the two rasters, and the topology state rises by one per adapt;
   - a round trip B -> B one level finer -> B returns random fields to rounding (linear) or exactly
     (constant), and an adapt to NULL (re-partition only) changes no value;
   - extra block work (PffGridSetBlockWork) enters the imbalance at once, and a re-partition with it
     balances at least as well, owns every block once and moves values unchanged (linear field exact,
     integral to 1e-9);
   - a map with an impossible level, or without an active block, is refused and the grid is unchanged.

   Sample run:  mpiexec -n 4 ./test_adapt
   Prints one line per case with global counts, the same on any number of ranks and threads. */
#include "pfftest.h"

static const char help[] = "Grid adaptation: raster, transfer, halos, topology state.\n";

#define N0 8
#define NLEVELS 3

typedef struct {
  const char *name;
  PetscInt    nb[3];
  PetscBool   periodic[3];
  PetscInt    inactive;
  uint64_t    seedA, seedB;
} Case;

typedef struct {
  PetscInt lin, ulin, rnd, frnd, scratch;
} Channels;

/* A value in [1, 2) from the sample position: the same on every rank and partition. */
static PetscReal RandomValue(const PetscReal x[3], PetscInt comp, void *vctx)
{
  return 1.0 + PffTestUniform01(PffTestPositionKey((const PffTestCtx *)vctx, x, comp, 77));
}

static PetscErrorCode Refresh(PffTestCtx *ctx)
{
  PetscFunctionBeginUser;
  PetscCall(PffGridGetRaster(ctx->grid, NULL, &ctx->level, &ctx->owner));
  PetscCall(PffGridGetLocalBlocks(ctx->grid, &ctx->nlocal));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The adapted raster against a grid set up with the same request. */
static PetscErrorCode CheckRasterMatchesSetUp(const PffTestCtx *ctx, const PetscInt request[])
{
  PffTestCtx      fresh;
  const PetscInt *g1, *g2;
  PetscInt        na1, na2;

  PetscFunctionBeginUser;
  PetscCall(
      PffTestCreateGridFromMap(ctx->comm, ctx->nb, ctx->periodic, ctx->origin, ctx->h0, N0, NLEVELS, request, &fresh));
  for (PetscInt b = 0; b < ctx->nblocks; b++)
    PetscCheck(fresh.level[b] == ctx->level[b] && fresh.owner[b] == ctx->owner[b], PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "block %" PetscInt_FMT ": adapted level %" PetscInt_FMT " owner %d, set up %" PetscInt_FMT " owner %d",
               b, ctx->level[b], ctx->owner[b], fresh.level[b], fresh.owner[b]);
  PetscCheck(fresh.nlocal == ctx->nlocal, PETSC_COMM_SELF, PETSC_ERR_PLIB, "local blocks differ");
  PetscCall(PffGridGetMortonOrder(ctx->grid, &na1, &g1));
  PetscCall(PffGridGetMortonOrder(fresh.grid, &na2, &g2));
  PetscCheck(na1 == na2, PETSC_COMM_SELF, PETSC_ERR_PLIB, "active block counts differ");
  for (PetscInt a = 0; a < na1; a++)
    PetscCheck(g1[a] == g2[a], PETSC_COMM_SELF, PETSC_ERR_PLIB, "Morton order differs");
  PetscCall(PffGridDestroy(&fresh.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode CheckOwnedOnce(const PffTestCtx *ctx)
{
  PetscInt *cnt;

  PetscFunctionBeginUser;
  PetscCall(PetscCalloc1(ctx->nblocks, &cnt));
  for (PetscInt lb = 0; lb < ctx->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(ctx->grid, lb, &info));
    cnt[info.gid]++;
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, cnt, (PetscMPIInt)ctx->nblocks, MPIU_INT, MPI_SUM, ctx->comm));
  for (PetscInt b = 0; b < ctx->nblocks; b++)
    PetscCheck(cnt[b] == (ctx->level[b] >= 0 ? 1 : 0), PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "block %" PetscInt_FMT " (level %" PetscInt_FMT ") is owned %" PetscInt_FMT " times", b, ctx->level[b],
               cnt[b]);
  PetscCall(PetscFree(cnt));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Every value of channel ch: the linear field (blocks active before, per oldLevel) or zero (new blocks). */
static PetscErrorCode CheckLinear(const PffTestCtx *ctx, PetscInt ch, PetscInt shift, const PetscInt oldLevel[])
{
  PffChannelKind  kind;
  PetscInt        ncomp;
  const PetscReal tol = 1e-5 * PffTestFieldScale(ctx, 3, shift);

  PetscFunctionBeginUser;
  PetscCall(PffGridGetChannelInfo(ctx->grid, ch, NULL, &kind, &ncomp, NULL));
  for (PetscInt lb = 0; lb < ctx->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(ctx->grid, lb, &info));
    for (PetscInt comp = 0; comp < ncomp; comp++) {
      float *d;
      PetscCall(PffGridGetBlockData(ctx->grid, ch, lb, comp, &d));
      for (PetscInt k = 0; k < info.n; k++)
        for (PetscInt j = 0; j < info.n; j++)
          for (PetscInt i = 0; i < info.n; i++) {
            const PetscInt c[3] = {i, j, k};
            PetscReal      x[3];
            PffTestSamplePosition(&info, kind, comp, c, x);
            const PetscReal expect = oldLevel[info.gid] >= 0 ? PffTestLinear(ctx, comp + shift, x) : 0.0;
            const PetscReal got    = d[i + info.n * (j + info.n * k)];
            PetscCheck(PetscAbsReal(got - expect) <= tol, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                       "channel %" PetscInt_FMT " block %" PetscInt_FMT " (level %" PetscInt_FMT " -> %" PetscInt_FMT
                       ") comp %" PetscInt_FMT " cell (%" PetscInt_FMT ",%" PetscInt_FMT ",%" PetscInt_FMT
                       "): %g, expected %g",
                       ch, info.gid, oldLevel[info.gid], info.level, comp, i, j, k, (double)got, (double)expect);
          }
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Integral of cell channel ch over the local blocks whose gid is active in both maps. */
static PetscErrorCode Integral(const PffTestCtx *ctx, PetscInt ch, const PetscInt mapA[], const PetscInt mapB[],
                               PetscReal *sum)
{
  PetscFunctionBeginUser;
  *sum = 0;
  for (PetscInt lb = 0; lb < ctx->nlocal; lb++) {
    PffBlockInfo info;
    float       *d;
    PetscCall(PffGridGetBlockInfo(ctx->grid, lb, &info));
    if (mapA[info.gid] < 0 || mapB[info.gid] < 0) continue;
    PetscCall(PffGridGetBlockData(ctx->grid, ch, lb, 0, &d));
    for (PetscInt i = 0; i < info.n * info.n * info.n; i++) *sum += (PetscReal)d[i] * info.h * info.h * info.h;
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, sum, 1, MPIU_REAL, MPI_SUM, ctx->comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* After a halo exchange, every ghost of the six face layers that faces a block active before and after is the
   linear field (a block that became active holds zeros). */
static PetscErrorCode CheckFaceGhosts(const PffTestCtx *ctx, PetscInt ch, const PetscInt oldLevel[], PetscInt *nchecked)
{
  const PetscReal tol = 1e-5 * PffTestFieldScale(ctx, 1, 0);

  PetscFunctionBeginUser;
  PetscCall(PffGridHaloBegin(ctx->grid, ch));
  PetscCall(PffGridHaloEnd(ctx->grid, ch));
  for (PetscInt lb = 0; lb < ctx->nlocal; lb++) {
    PffBlockInfo   info;
    const PffView *views;
    PetscCall(PffGridGetBlockInfo(ctx->grid, lb, &info));
    PetscCall(PffGridGetBlockViews(ctx->grid, ch, lb, 0, &views));
    for (PetscInt f = 0; f < 6; f++) {
      PetscInt d[3]      = {0, 0, 0};
      d[f / 2]           = f % 2 ? 1 : -1;
      const PetscInt nbr = PffRasterNeighbour(ctx->nb, ctx->periodic, info.ijk, d);
      if (nbr < 0 || ctx->level[nbr] < 0 || oldLevel[nbr] < 0) continue;
      for (PetscInt v = 0; v < info.n; v++)
        for (PetscInt u = 0; u < info.n; u++) {
          PetscInt  p[3];
          PetscReal x[3];
          PffBlockSideCell(f, f % 2 ? info.n : -1, u, v, p);
          PffTestSamplePosition(&info, PFF_CHANNEL_CELL, 0, p, x);
          const PetscReal got = *PffViewsAt(views, p[0], p[1], p[2], info.n), expect = PffTestLinear(ctx, 0, x);
          PetscCheck(PetscAbsReal(got - expect) <= tol, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                     "block %" PetscInt_FMT " side %" PetscInt_FMT " ghost (%" PetscInt_FMT ",%" PetscInt_FMT
                     ",%" PetscInt_FMT "): %g, expected %g",
                     info.gid, f, p[0], p[1], p[2], (double)got, (double)expect);
          (*nchecked)++;
        }
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Every owned value of ch, in Morton order of the local blocks, into (or compared with) buf. */
static PetscErrorCode Snapshot(const PffTestCtx *ctx, PetscInt ch, float **buf, PetscBool compare, PetscReal rtol)
{
  PetscInt ncomp;
  size_t   pos = 0, total = 0;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetChannelInfo(ctx->grid, ch, NULL, NULL, &ncomp, NULL));
  for (PetscInt lb = 0; lb < ctx->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(ctx->grid, lb, &info));
    total += (size_t)(ncomp * info.n * info.n * info.n);
  }
  if (!compare) PetscCall(PetscMalloc1(total + 1, buf));
  for (PetscInt lb = 0; lb < ctx->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(ctx->grid, lb, &info));
    for (PetscInt comp = 0; comp < ncomp; comp++) {
      float *d;
      PetscCall(PffGridGetBlockData(ctx->grid, ch, lb, comp, &d));
      for (PetscInt i = 0; i < info.n * info.n * info.n; i++, pos++) {
        if (!compare) {
          (*buf)[pos] = d[i];
          continue;
        }
        PetscCheck(PetscAbsReal((PetscReal)d[i] - (PetscReal)(*buf)[pos]) <= rtol * PetscAbsReal((*buf)[pos]),
                   PETSC_COMM_SELF, PETSC_ERR_PLIB,
                   "channel %" PetscInt_FMT " block %" PetscInt_FMT " comp %" PetscInt_FMT " value %" PetscInt_FMT
                   ": %.9g after the round trip, %.9g before",
                   ch, info.gid, comp, i, (double)d[i], (double)(*buf)[pos]);
      }
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode AdaptChecked(PffTestCtx *ctx, const PetscInt request[])
{
  PetscObjectState s0, s1;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetTopologyState(ctx->grid, &s0));
  PetscCall(PffGridAdapt(ctx->grid, request));
  PetscCall(PffGridGetTopologyState(ctx->grid, &s1));
  PetscCheck(s1 == s0 + 1, PETSC_COMM_SELF, PETSC_ERR_PLIB, "topology state %" PetscInt64_FMT " -> %" PetscInt64_FMT,
             (PetscInt64)s0, (PetscInt64)s1);
  PetscCall(Refresh(ctx));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A refused map leaves the grid as it was. */
static PetscErrorCode CheckRefused(PffTestCtx *ctx, const PetscInt request[], const char what[])
{
  PetscObjectState s0, s1;
  PetscErrorCode   ierr;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetTopologyState(ctx->grid, &s0));
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  ierr = PffGridAdapt(ctx->grid, request);
  PetscCall(PetscPopErrorHandler());
  PetscCall(PffGridGetTopologyState(ctx->grid, &s1));
  PetscCheck(ierr != PETSC_SUCCESS && s1 == s0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "a map %s was accepted", what);
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode RunCase(MPI_Comm comm, const Case *cs)
{
  const PetscReal   origin[3] = {-0.5, 0.25, 0.125};
  const PetscInt    nblocks   = cs->nb[0] * cs->nb[1] * cs->nb[2];
  PffTestCtx        ctx;
  Channels          ch;
  PetscInt         *mapA, *mapB, *fine, *levelA, *bad, nghost = 0;
  PetscMPIInt      *ownerA;
  PffAdaptInfo      info, expect = {0};
  PetscReal         before, after;
  float            *snapR, *snapF;
  PffTestLinearFill fill0 = {NULL, 0}, fill1 = {NULL, 1};

  PetscFunctionBeginUser;
  PetscCall(
      PetscMalloc6(nblocks, &mapA, nblocks, &mapB, nblocks, &fine, nblocks, &levelA, nblocks, &ownerA, nblocks, &bad));
  PffTestRandomMap(cs->nb, NLEVELS, -1, cs->inactive, cs->seedA, mapA);
  PffTestRandomMap(cs->nb, NLEVELS, -1, cs->inactive, cs->seedB, mapB);
  PetscCall(PffTestCreateGridFromMap(comm, cs->nb, cs->periodic, origin, 1.0 / 32, N0, NLEVELS, mapA, &ctx));
  fill0.ctx = fill1.ctx = &ctx;
  PetscCall(PffGridAddChannel(ctx.grid, "lin", PFF_CHANNEL_CELL, 1, &ch.lin));
  PetscCall(PffGridAddChannel(ctx.grid, "ulin", PFF_CHANNEL_FACE, 2, &ch.ulin));
  PetscCall(PffGridAddChannel(ctx.grid, "rnd", PFF_CHANNEL_CELL, 1, &ch.rnd));
  PetscCall(PffGridAddChannel(ctx.grid, "frnd", PFF_CHANNEL_FACE, 1, &ch.frnd));
  PetscCall(PffGridAddChannel(ctx.grid, "scratch", PFF_CHANNEL_CELL, 1, &ch.scratch));
  PetscCall(PffGridSetChannelTransfer(ctx.grid, ch.frnd, PFF_TRANSFER_CONSTANT));
  PetscCall(PffGridSetChannelTransfer(ctx.grid, ch.scratch, PFF_TRANSFER_NONE));
  PetscCall(PffGridFillChannel(ctx.grid, ch.lin, PffTestLinearValue, &fill0));
  PetscCall(PffGridFillChannel(ctx.grid, ch.ulin, PffTestLinearValue, &fill1));
  PetscCall(PffGridFillChannel(ctx.grid, ch.rnd, RandomValue, &ctx));
  PetscCall(PffGridFillChannel(ctx.grid, ch.frnd, RandomValue, &ctx));
  PetscCall(PffGridFillChannel(ctx.grid, ch.scratch, PffTestOne, NULL));
  PetscCall(PetscArraycpy(levelA, ctx.level, nblocks));
  PetscCall(PetscArraycpy(ownerA, ctx.owner, nblocks));

  /* A -> B */
  PetscCall(Integral(&ctx, ch.rnd, levelA, mapB, &before));
  PetscCall(AdaptChecked(&ctx, mapB));
  PetscCall(CheckRasterMatchesSetUp(&ctx, mapB));
  PetscCall(CheckOwnedOnce(&ctx));
  PetscCall(CheckLinear(&ctx, ch.lin, 0, levelA));
  PetscCall(CheckLinear(&ctx, ch.ulin, 1, levelA));
  for (PetscInt lb = 0; lb < ctx.nlocal; lb++) {
    PffBlockInfo info;
    float       *d;
    PetscCall(PffGridGetBlockInfo(ctx.grid, lb, &info));
    PetscCall(PffGridGetBlockData(ctx.grid, ch.scratch, lb, 0, &d));
    for (PetscInt i = 0; i < info.n * info.n * info.n; i++)
      PetscCheck(d[i] == 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "scratch channel not zero after the adapt");
  }
  PetscCall(Integral(&ctx, ch.rnd, levelA, mapB, &after));
  PetscCheck(PetscAbsReal(after - before) <= 1e-6 * PetscAbsReal(before), PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "integral %.12g before the adapt, %.12g after", (double)before, (double)after);
  PetscCall(CheckFaceGhosts(&ctx, ch.lin, levelA, &nghost));
  PetscCall(PffGridGetAdaptInfo(ctx.grid, &info));
  for (PetscInt b = 0; b < nblocks; b++) {
    const PetscInt lo = levelA[b], ln = ctx.level[b];
    expect.activated += lo < 0 && ln >= 0;
    expect.deactivated += lo >= 0 && ln < 0;
    expect.refined += lo >= 0 && ln >= 0 && ln < lo;
    expect.coarsened += lo >= 0 && ln >= 0 && ln > lo;
    expect.moved += lo >= 0 && ln >= 0 && ownerA[b] != ctx.owner[b];
  }
  PetscCheck(info.activated == expect.activated && info.deactivated == expect.deactivated &&
                 info.refined == expect.refined && info.coarsened == expect.coarsened && info.moved == expect.moved,
             PETSC_COMM_SELF, PETSC_ERR_PLIB, "adapt counts differ from the rasters'");
  /* values come over the network exactly when blocks changed owner */
  PetscCheck((info.bytesMoved > 0) == (expect.moved > 0), PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "adapt info: %" PetscInt64_FMT " bytes moved for %" PetscInt_FMT " blocks that changed owner",
             info.bytesMoved, expect.moved);
  PetscCheck(expect.refined > 0 && expect.coarsened > 0, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "case %s: the maps must both refine and coarsen blocks", cs->name);
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &nghost, 1, MPIU_INT, MPI_SUM, comm));
  PetscCall(PetscPrintf(comm,
                        "%s: refined %" PetscInt_FMT " coarsened %" PetscInt_FMT " activated %" PetscInt_FMT
                        " deactivated %" PetscInt_FMT ", integral %.6f, %" PetscInt_FMT " ghosts checked\n",
                        cs->name, info.refined, info.coarsened, info.activated, info.deactivated, (double)after,
                        nghost));

  /* B -> B one level finer -> B, and a re-partition without a new map */
  PetscCall(PffGridFillChannel(ctx.grid, ch.rnd, RandomValue, &ctx));
  PetscCall(PffGridFillChannel(ctx.grid, ch.frnd, RandomValue, &ctx));
  PetscCall(Snapshot(&ctx, ch.rnd, &snapR, PETSC_FALSE, 0));
  PetscCall(Snapshot(&ctx, ch.frnd, &snapF, PETSC_FALSE, 0));
  for (PetscInt b = 0; b < nblocks; b++) {
    fine[b] = ctx.level[b] >= 0 ? PetscMax(0, ctx.level[b] - 1) : -1;
    mapB[b] = ctx.level[b];
  }
  PetscCall(AdaptChecked(&ctx, fine));
  PetscCall(AdaptChecked(&ctx, mapB));
  PetscCall(Snapshot(&ctx, ch.rnd, &snapR, PETSC_TRUE, 1e-6));
  PetscCall(Snapshot(&ctx, ch.frnd, &snapF, PETSC_TRUE, 0));
  PetscCall(AdaptChecked(&ctx, NULL));
  PetscCall(Snapshot(&ctx, ch.rnd, &snapR, PETSC_TRUE, 1e-6));
  PetscCall(CheckRasterMatchesSetUp(&ctx, mapB));

  /* extra work on a third of the blocks: the imbalance accounts for it at once, and a re-partition with
     it balances at least as well and moves values unchanged */
  {
    PffPartitionQuality q0, q1, q2;
    PetscInt64         *extra;
    PetscReal           r0, r1;
    PetscCall(PffGridGetPartitionQuality(ctx.grid, &q0));
    PetscCall(Integral(&ctx, ch.rnd, ctx.level, ctx.level, &r0));
    PetscCall(PetscMalloc1(nblocks, &extra));
    for (PetscInt b = 0; b < nblocks; b++) extra[b] = b % 3 == 0 && ctx.level[b] >= 0 ? 4 * N0 * N0 * N0 : 0;
    PetscCall(PffGridSetBlockWork(ctx.grid, extra));
    PetscCall(PetscFree(extra));
    PetscCall(PffGridGetPartitionQuality(ctx.grid, &q1));
    PetscCall(AdaptChecked(&ctx, NULL));
    PetscCall(PffGridGetPartitionQuality(ctx.grid, &q2));
    PetscCheck(q2.imbalance <= q1.imbalance + 1e-12, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "re-partition with block work: imbalance %g -> %g", (double)q1.imbalance, (double)q2.imbalance);
    PetscCall(CheckOwnedOnce(&ctx));
    PetscCall(CheckLinear(&ctx, ch.lin, 0, levelA)); /* moved, not resampled: exact (zero where A had no block) */
    PetscCall(Integral(&ctx, ch.rnd, ctx.level, ctx.level, &r1));
    PetscCheck(PetscAbsReal(r1 - r0) <= 1e-9 * PetscAbsReal(r0), PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "integral %.12g before the re-partition, %.12g after", (double)r0, (double)r1);
    PetscCall(PetscPrintf(comm, "%s: imbalance %.3f, with block work %.3f, re-partitioned %.3f\n", cs->name,
                          (double)q0.imbalance, (double)q1.imbalance, (double)q2.imbalance));
    PetscCall(PffGridSetBlockWork(ctx.grid, NULL));
    PetscCall(AdaptChecked(&ctx, NULL)); /* back to the partition by cells, which a fresh set-up gives */
  }

  /* refused maps */
  for (PetscInt b = 0; b < nblocks; b++) bad[b] = b == nblocks / 2 ? NLEVELS : mapB[b];
  PetscCall(CheckRefused(&ctx, bad, "with a level past -grid_levels"));
  for (PetscInt b = 0; b < nblocks; b++) bad[b] = -1;
  PetscCall(CheckRefused(&ctx, bad, "without an active block"));
  PetscCall(CheckRasterMatchesSetUp(&ctx, mapB));

  PetscCall(PetscFree(snapR));
  PetscCall(PetscFree(snapF));
  PetscCall(PffGridDestroy(&ctx.grid));
  PetscCall(PetscFree6(mapA, mapB, fine, levelA, ownerA, bad));
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  const Case cases[] = {
      {"walled 4x4x4", {4, 4, 4}, {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE}, 0, 11, 12},
      {"periodic z, inactive blocks", {5, 3, 4}, {PETSC_FALSE, PETSC_FALSE, PETSC_TRUE}, 15, 21, 22},
  };

  PetscFunctionBeginUser;
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  for (size_t c = 0; c < PETSC_STATIC_ARRAY_LENGTH(cases); c++) PetscCall(RunCase(PETSC_COMM_WORLD, &cases[c]));
  PetscCall(PetscFinalize());
  return 0;
}
