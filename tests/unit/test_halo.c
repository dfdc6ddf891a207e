/* Unit test of the halo exchange of PffGrid, forward and reverse, across ranks and levels.

   Multi-level part: pseudo-random graded 3-level rasters (n0 = 8; walled, or partly periodic with
   inactive blocks), for cell channels of width 1 and 2 and face channels of width 1 and 2. Every
   owned value is set to a linear function of its sample position (the cell centre, or the lower
   d-face for face component d), depending only on the walled axes so that it is periodic. After
   PffGridHaloBegin/End every ghost cell (faces, edges and corners of the 26 regions) must equal
   the linear function at the ghost position: bitwise for a same-level neighbour, to 1e-5 of the
   field's scale for a coarser (interpolated) or finer (averaged) one. Ghosts across walls or
   facing inactive blocks keep what the user wrote there, and owned values are unchanged. Each
   case runs on two channels of the same kind and width (one plan, two buffers) whose Begin/End
   pairs overlap. The reverse exchange is then checked: after it, every ghost buffer is zero; with
   owned values zeroed and 1 + u (u small, deterministic) added into every ghost whose neighbour is
   active (same-rank same-level regions write straight into the neighbour, whose address is
   checked) and a marker written across walls, each block receives exactly what was written into
   ghosts facing it (per block and component, to 1e-5), and nothing written across a wall arrives.

   Uniform part: single-level periodic rasters (one with an axis of a single block, which is its own
   neighbour, and a channel as wide as the block) with a hash of each value's global integer index:
   every ghost must be bitwise the value of the wrapped owner cell, and the reverse exchange must
   deliver each ghost's value to exactly that cell.

   Sample run:  mpiexec -n 4 ./test_halo
   Prints (the same on any number of ranks) one line per raster and channel with global ghost counts. */
#include "pfftest.h"

static const char help[] = "Forward and reverse halo exchange across ranks and levels.\n";

#define N0 8
#define NLEVELS 3
#define MARKER (-7.0f)

/* A float in [1, 2) with all 23 mantissa bits from the hash, exactly representable. */
static float HashValue(uint64_t h)
{
  return (float)(1.0 + (double)(h >> 41) / 8388608.0);
}

typedef struct {
  const char *name;
  PetscInt    nb[3];
  PetscBool   periodic[3];
  PetscInt    inactive; /* percentage of requested-inactive blocks */
  PetscInt    uniform;  /* -1: random levels; otherwise the level of every block */
  uint64_t    seed;
} Case;

typedef PffTestCtx Ctx;

typedef enum {
  REGION_WALL, /* across a wall or facing an inactive block */
  REGION_SAME,
  REGION_COARSER,
  REGION_FINER,
  REGION_KINDS
} RegionKind;

static PetscErrorCode CreateGrid(MPI_Comm comm, const Case *c, Ctx *ctx)
{
  const PetscReal origin[3] = {-0.5, 0.25, 0.125};

  PetscFunctionBeginUser;
  PetscCall(PffTestCreateGrid(comm, c->nb, c->periodic, origin, 1.0 / 32, N0, NLEVELS, c->uniform, c->inactive, c->seed,
                              ctx));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Ghost box of region r (0..26, 13 = the block) in block-local cells: [lo, hi) per axis. */
static void RegionBox(PetscInt r, PetscInt n, PetscInt w, PetscInt lo[3], PetscInt hi[3])
{
  for (int a = 0; a < 3; a++) {
    const PetscInt d = a == 0 ? r % 3 - 1 : (a == 1 ? (r / 3) % 3 - 1 : r / 9 - 1);
    lo[a]            = d < 0 ? -w : (d > 0 ? n : 0);
    hi[a]            = d < 0 ? 0 : (d > 0 ? n + w : n);
  }
}

static RegionKind Classify(const Ctx *ctx, const PffBlockInfo *info, PetscInt r, PetscInt *nbr)
{
  const PetscInt d[3] = {r % 3 - 1, (r / 3) % 3 - 1, r / 9 - 1};
  *nbr                = PffRasterNeighbour(ctx->nb, ctx->periodic, info->ijk, d);
  if (*nbr < 0 || ctx->level[*nbr] < 0) return REGION_WALL;
  if (ctx->level[*nbr] == info->level) return REGION_SAME;
  return ctx->level[*nbr] > info->level ? REGION_COARSER : REGION_FINER;
}

/* A region read in place from a same-level neighbour on this rank rather than from a ghost buffer. */
static PetscBool IsDirect(const Ctx *ctx, RegionKind kind, PetscInt nbr)
{
  return (PetscBool)(kind == REGION_SAME && ctx->owner[nbr] == ctx->rank);
}

/* Checks, for one block component, that each direct region's address is the neighbour's cell. */
static PetscErrorCode CheckDirectAddress(const Ctx *ctx, PetscInt ch, const PffBlockInfo *info, PetscInt comp,
                                         const PffView *views, PetscInt r, PetscInt nbr, PetscInt w)
{
  const PetscInt n = info->n, d[3] = {r % 3 - 1, (r / 3) % 3 - 1, r / 9 - 1};
  PetscInt       lo[3], hi[3], lb;
  float         *data;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetLocalIndex(ctx->grid, nbr, &lb));
  PetscCheck(lb >= 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "block %" PetscInt_FMT " is owned here but has no local index",
             nbr);
  PetscCall(PffGridGetBlockData(ctx->grid, ch, lb, comp, &data));
  RegionBox(r, n, w, lo, hi);
  for (PetscInt k = lo[2]; k < hi[2]; k++)
    for (PetscInt j = lo[1]; j < hi[1]; j++)
      for (PetscInt i = lo[0]; i < hi[0]; i++) {
        const float *expect = data + (i - d[0] * n) + n * ((j - d[1] * n) + n * (k - d[2] * n));
        PetscCheck(PffViewsAt(views, i, j, k, n) == expect, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                   "block %" PetscInt_FMT " region %" PetscInt_FMT ": the view of ghost (%" PetscInt_FMT
                   ",%" PetscInt_FMT ",%" PetscInt_FMT ") does not point at the neighbour's cell",
                   info->gid, r, i, j, k);
      }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* After a reverse exchange every ghost buffer is zero; direct regions must point into the neighbour. */
static PetscErrorCode CheckGhostsCleared(const Ctx *ctx, PetscInt ch, const char what[])
{
  PetscInt ncomp, w;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetChannelInfo(ctx->grid, ch, NULL, NULL, &ncomp, &w));
  for (PetscInt lb = 0; lb < ctx->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(ctx->grid, lb, &info));
    for (PetscInt comp = 0; comp < ncomp; comp++) {
      const PffView *views;
      PetscCall(PffGridGetBlockViews(ctx->grid, ch, lb, comp, &views));
      for (PetscInt r = 0; r < 27; r++) {
        PetscInt   nbr, lo[3], hi[3];
        RegionKind kind;
        if (r == 13) continue;
        kind = Classify(ctx, &info, r, &nbr);
        if (IsDirect(ctx, kind, nbr)) {
          PetscCall(CheckDirectAddress(ctx, ch, &info, comp, views, r, nbr, w));
          continue;
        }
        RegionBox(r, info.n, w, lo, hi);
        for (PetscInt k = lo[2]; k < hi[2]; k++)
          for (PetscInt j = lo[1]; j < hi[1]; j++)
            for (PetscInt i = lo[0]; i < hi[0]; i++) {
              const float v = *PffViewsAt(views, i, j, k, info.n);
              PetscCheck(v == 0, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                         "%s: after the reverse exchange, ghost (%" PetscInt_FMT ",%" PetscInt_FMT ",%" PetscInt_FMT
                         ") of block %" PetscInt_FMT " comp %" PetscInt_FMT " region %" PetscInt_FMT " is %g, not 0",
                         what, i, j, k, info.gid, comp, r, (double)v);
            }
      }
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Owned values of the linear field (variant shift), and a marker in every ghost that no exchange may touch. */
static PetscErrorCode FillLinear(const Ctx *ctx, PetscInt ch, PetscInt shift, const char what[])
{
  PetscInt       ncomp, w;
  PffChannelKind kind;

  PffTestLinearFill fill = {ctx, shift};

  PetscFunctionBeginUser;
  PetscCall(PffGridFillChannel(ctx->grid, ch, PffTestLinearValue, &fill));
  PetscCall(PffGridGetChannelInfo(ctx->grid, ch, NULL, &kind, &ncomp, &w));
  for (PetscInt lb = 0; lb < ctx->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(ctx->grid, lb, &info));
    for (PetscInt comp = 0; comp < ncomp; comp++) {
      const PffView *views;
      PetscCall(PffGridGetBlockViews(ctx->grid, ch, lb, comp, &views));
      for (PetscInt r = 0; r < 27; r++) {
        PetscInt nbr, lo[3], hi[3];
        if (r == 13 || Classify(ctx, &info, r, &nbr) != REGION_WALL) continue;
        RegionBox(r, info.n, w, lo, hi);
        for (PetscInt k = lo[2]; k < hi[2]; k++)
          for (PetscInt j = lo[1]; j < hi[1]; j++)
            for (PetscInt i = lo[0]; i < hi[0]; i++) {
              float *g = PffViewsAt(views, i, j, k, info.n);
              PetscCheck(*g == 0, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                         "%s: ghost of block %" PetscInt_FMT " region %" PetscInt_FMT
                         " across a wall is %g before any exchange",
                         what, info.gid, r, (double)*g);
              *g = MARKER;
            }
      }
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* After a forward exchange: owned values unchanged, every ghost the linear field at its position
   (bitwise from a same-level neighbour), the marker across walls. count[] gets the ghosts per kind. */
static PetscErrorCode CheckForward(const Ctx *ctx, PetscInt ch, PetscInt shift, const char what[],
                                   PetscInt64 count[REGION_KINDS])
{
  PetscInt       ncomp, w;
  PffChannelKind kind;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetChannelInfo(ctx->grid, ch, NULL, &kind, &ncomp, &w));
  const PetscReal tol = 1e-5 * PffTestFieldScale(ctx, ncomp, shift);
  for (PetscInt lb = 0; lb < ctx->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(ctx->grid, lb, &info));
    for (PetscInt comp = 0; comp < ncomp; comp++) {
      float         *data;
      const PffView *views;
      PetscCall(PffGridGetBlockData(ctx->grid, ch, lb, comp, &data));
      PetscCall(PffGridGetBlockViews(ctx->grid, ch, lb, comp, &views));
      for (PetscInt k = 0; k < info.n; k++)
        for (PetscInt j = 0; j < info.n; j++)
          for (PetscInt i = 0; i < info.n; i++) {
            const PetscInt c[3] = {i, j, k};
            PetscReal      x[3];
            PffTestSamplePosition(&info, kind, comp, c, x);
            PetscCheck(data[i + info.n * (j + info.n * k)] == (float)PffTestLinear(ctx, comp + shift, x) &&
                           PffViewsAt(views, i, j, k, info.n) == &data[i + info.n * (j + info.n * k)],
                       PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: owned value or view of block %" PetscInt_FMT " changed",
                       what, info.gid);
          }
      for (PetscInt r = 0; r < 27; r++) {
        PetscInt   nbr, lo[3], hi[3];
        RegionKind rk;
        if (r == 13) continue;
        rk = Classify(ctx, &info, r, &nbr);
        RegionBox(r, info.n, w, lo, hi);
        for (PetscInt k = lo[2]; k < hi[2]; k++)
          for (PetscInt j = lo[1]; j < hi[1]; j++)
            for (PetscInt i = lo[0]; i < hi[0]; i++, count[rk]++) {
              const PetscInt c[3] = {i, j, k};
              const float    v    = *PffViewsAt(views, i, j, k, info.n);
              PetscReal      x[3];
              PffTestSamplePosition(&info, kind, comp, c, x);
              const PetscReal f = PffTestLinear(ctx, comp + shift, x);
              if (rk == REGION_WALL) {
                PetscCheck(v == MARKER, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                           "%s: the exchange overwrote ghost (%" PetscInt_FMT ",%" PetscInt_FMT ",%" PetscInt_FMT
                           ") of block %" PetscInt_FMT " comp %" PetscInt_FMT
                           " across a wall/inactive block (region %" PetscInt_FMT "): %g",
                           what, i, j, k, info.gid, comp, r, (double)v);
              } else if (rk == REGION_SAME) {
                PetscCheck(v == (float)f, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                           "%s: same-level ghost (%" PetscInt_FMT ",%" PetscInt_FMT ",%" PetscInt_FMT
                           ") of block %" PetscInt_FMT " comp %" PetscInt_FMT " region %" PetscInt_FMT
                           " (neighbour %" PetscInt_FMT " on rank %d) is %.9g, expected %.9g",
                           what, i, j, k, info.gid, comp, r, nbr, ctx->owner[nbr], (double)v, (double)(float)f);
              } else {
                PetscCheck(PetscAbsReal((PetscReal)v - f) <= tol, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                           "%s: %s ghost (%" PetscInt_FMT ",%" PetscInt_FMT ",%" PetscInt_FMT
                           ") of block %" PetscInt_FMT " (level %" PetscInt_FMT ") comp %" PetscInt_FMT
                           " region %" PetscInt_FMT " (neighbour %" PetscInt_FMT " level %" PetscInt_FMT
                           ") at (%g, %g, %g) is %.9g, the linear field is %.9g",
                           what, rk == REGION_COARSER ? "coarser" : "finer", i, j, k, info.gid, info.level, comp, r,
                           nbr, ctx->level[nbr], (double)x[0], (double)x[1], (double)x[2], (double)v, (double)f);
              }
            }
      }
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Zeroes the owned values, adds 1 + u into every ghost facing an active block (expect[] collects it
   per receiving block and component) and writes the marker across walls. */
static PetscErrorCode WriteGhosts(const Ctx *ctx, PetscInt ch, uint64_t salt, double expect[])
{
  PetscInt ncomp, w;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetChannelInfo(ctx->grid, ch, NULL, NULL, &ncomp, &w));
  for (PetscInt lb = 0; lb < ctx->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(ctx->grid, lb, &info));
    for (PetscInt comp = 0; comp < ncomp; comp++) {
      float *data;
      PetscCall(PffGridGetBlockData(ctx->grid, ch, lb, comp, &data));
      PetscCall(PetscArrayzero(data, info.n * info.n * info.n));
    }
  }
  for (PetscInt lb = 0; lb < ctx->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(ctx->grid, lb, &info));
    for (PetscInt comp = 0; comp < ncomp; comp++) {
      const PffView *views;
      PetscCall(PffGridGetBlockViews(ctx->grid, ch, lb, comp, &views));
      for (PetscInt r = 0; r < 27; r++) {
        PetscInt   nbr, lo[3], hi[3];
        RegionKind rk;
        if (r == 13) continue;
        rk = Classify(ctx, &info, r, &nbr);
        RegionBox(r, info.n, w, lo, hi);
        for (PetscInt k = lo[2]; k < hi[2]; k++)
          for (PetscInt j = lo[1]; j < hi[1]; j++)
            for (PetscInt i = lo[0]; i < hi[0]; i++) {
              float *g = PffViewsAt(views, i, j, k, info.n);
              if (rk == REGION_WALL) {
                *g = MARKER;
                continue;
              }
              const uint64_t h = PffTestKey((uint64_t)info.gid, (uint64_t)(comp * 27 + r),
                                            (uint64_t)((i + w) + 64 * ((j + w) + 64 * (k + w))), salt);
              const float    v = (float)(1.0 + 0.01 * (double)(h >> 40) / 16777216.0);
              *g += v;
              expect[nbr * ncomp + comp] += (double)v;
            }
      }
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* After the reverse exchange each block component holds what the ghosts facing it held. */
static PetscErrorCode CheckReceived(const Ctx *ctx, PetscInt ch, double expect[], const char what[])
{
  PetscInt    ncomp;
  PetscMPIInt cnt;
  double     *received, total = 0, got = 0;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetChannelInfo(ctx->grid, ch, NULL, NULL, &ncomp, NULL));
  PetscCall(PetscMPIIntCast(ctx->nblocks * ncomp, &cnt));
  PetscCall(PetscCalloc1(ctx->nblocks * ncomp, &received));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, expect, cnt, MPI_DOUBLE, MPI_SUM, ctx->comm));
  for (PetscInt lb = 0; lb < ctx->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(ctx->grid, lb, &info));
    for (PetscInt comp = 0; comp < ncomp; comp++) {
      float *data;
      double sum = 0;
      PetscCall(PffGridGetBlockData(ctx->grid, ch, lb, comp, &data));
      for (PetscInt c = 0; c < info.n * info.n * info.n; c++) sum += (double)data[c];
      received[info.gid * ncomp + comp] = sum;
      const double e                    = expect[info.gid * ncomp + comp];
      PetscCheck(PetscAbsReal(sum - e) <= 1e-5 * PetscMax(e, 1.0), PETSC_COMM_SELF, PETSC_ERR_PLIB,
                 "%s: block %" PetscInt_FMT " (level %" PetscInt_FMT ") comp %" PetscInt_FMT
                 " received %.9g from the reverse exchange, the ghosts facing it held %.9g",
                 what, info.gid, info.level, comp, sum, e);
    }
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, received, cnt, MPI_DOUBLE, MPI_SUM, ctx->comm));
  for (PetscInt b = 0; b < ctx->nblocks * ncomp; b++) {
    total += expect[b];
    got += received[b];
  }
  PetscCheck(PetscAbsReal(total - got) <= 1e-5 * total, ctx->comm, PETSC_ERR_PLIB,
             "%s: reverse exchange: %.9g written into ghosts, %.9g received", what, total, got);
  PetscCall(PetscFree(received));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Linear fields on two channels of the same kind and width (one plan, two buffers) whose exchanges
   overlap: forward against the analytic values, then the reverse exchange per block. */
static PetscErrorCode TestLinear(Ctx *ctx, const char cname[], PffChannelKind kind, PetscInt w)
{
  PetscInt   ch[2], ncomp;
  PetscInt64 count[REGION_KINDS] = {0}, gcount[REGION_KINDS];
  double    *expect[2];
  char       what[2][160];

  PetscFunctionBeginUser;
  for (int c = 0; c < 2; c++) {
    char chname[64];
    PetscCall(PetscSNPrintf(chname, sizeof(chname), "%s_w%" PetscInt_FMT "_%d", PffChannelKinds[kind], w, c));
    PetscCall(PetscSNPrintf(what[c], sizeof(what[c]), "%s %s w=%" PetscInt_FMT " (channel %d)", cname,
                            PffChannelKinds[kind], w, c));
    PetscCall(PffGridAddChannel(ctx->grid, chname, kind, w, &ch[c]));
    PetscCall(FillLinear(ctx, ch[c], c, what[c]));
  }
  PetscCall(PffGridGetChannelInfo(ctx->grid, ch[0], NULL, NULL, &ncomp, NULL));

  PetscCall(PffGridHaloBegin(ctx->grid, ch[0]));
  PetscCall(PffGridHaloBegin(ctx->grid, ch[1]));
  PetscCall(PffGridHaloEnd(ctx->grid, ch[1]));
  PetscCall(PffGridHaloEnd(ctx->grid, ch[0]));
  PetscCall(CheckForward(ctx, ch[0], 0, what[0], count));
  PetscCall(CheckForward(ctx, ch[1], 1, what[1], count));

  /* reverse: first to clear the buffers (they hold the forward values), then with known values */
  for (int c = 0; c < 2; c++) {
    PetscCall(PffGridHaloReverseBegin(ctx->grid, ch[c]));
    PetscCall(PffGridHaloReverseEnd(ctx->grid, ch[c]));
    PetscCall(CheckGhostsCleared(ctx, ch[c], what[c]));
    PetscCall(PetscCalloc1(ctx->nblocks * ncomp, &expect[c]));
    PetscCall(WriteGhosts(ctx, ch[c], (uint64_t)c, expect[c]));
  }
  PetscCall(PffGridHaloReverseBegin(ctx->grid, ch[0]));
  PetscCall(PffGridHaloReverseBegin(ctx->grid, ch[1]));
  PetscCall(PffGridHaloReverseEnd(ctx->grid, ch[1]));
  PetscCall(PffGridHaloReverseEnd(ctx->grid, ch[0]));
  for (int c = 0; c < 2; c++) {
    PetscCall(CheckGhostsCleared(ctx, ch[c], what[c]));
    PetscCall(CheckReceived(ctx, ch[c], expect[c], what[c]));
    PetscCall(PetscFree(expect[c]));
  }

  /* PffGridZeroChannel clears the owned values and every ghost (filled by a forward exchange, markers across walls) */
  for (int c = 0; c < 2; c++) {
    PetscCall(FillLinear(ctx, ch[c], c, what[c]));
    PetscCall(PffGridHaloBegin(ctx->grid, ch[c]));
    PetscCall(PffGridHaloEnd(ctx->grid, ch[c]));
    PetscCall(PffGridZeroChannel(ctx->grid, ch[c]));
    PetscCall(CheckGhostsCleared(ctx, ch[c], what[c]));
    for (PetscInt lb = 0; lb < ctx->nlocal; lb++) {
      PffBlockInfo info;
      PetscCall(PffGridGetBlockInfo(ctx->grid, lb, &info));
      for (PetscInt comp = 0; comp < ncomp; comp++) {
        float *data;
        PetscCall(PffGridGetBlockData(ctx->grid, ch[c], lb, comp, &data));
        for (PetscInt i = 0; i < info.n * info.n * info.n; i++)
          PetscCheck(data[i] == 0, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                     "%s: owned value %" PetscInt_FMT " of block %" PetscInt_FMT " is %g after PffGridZeroChannel",
                     what[c], i, info.gid, (double)data[i]);
      }
    }
  }

  PetscCallMPI(MPI_Allreduce(count, gcount, REGION_KINDS, MPIU_INT64, MPI_SUM, ctx->comm));
  PetscCall(PetscPrintf(ctx->comm,
                        "halo %s %s w=%" PetscInt_FMT ": ghosts same %" PetscInt64_FMT " coarser %" PetscInt64_FMT
                        " finer %" PetscInt64_FMT " wall %" PetscInt64_FMT ", forward ok, reverse ok, zero ok\n",
                        cname, PffChannelKinds[kind], w, gcount[REGION_SAME] / 2, gcount[REGION_COARSER] / 2,
                        gcount[REGION_FINER] / 2, gcount[REGION_WALL] / 2));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Global integer index of block-local cell c on a uniform raster, wrapped on periodic axes;
   returns PETSC_FALSE outside the domain. */
static PetscBool UniformIndex(const Ctx *ctx, const PffBlockInfo *info, const PetscInt c[3], PetscInt64 *index)
{
  PetscInt64 g[3];
  for (int a = 0; a < 3; a++) {
    const PetscInt64 len = (PetscInt64)ctx->nb[a] * info->n;
    g[a]                 = (PetscInt64)info->ijk[a] * info->n + c[a];
    if (g[a] < 0 || g[a] >= len) {
      if (!ctx->periodic[a]) return PETSC_FALSE;
      g[a] = (g[a] + len) % len;
    }
  }
  *index = g[0] + (PetscInt64)ctx->nb[0] * info->n * (g[1] + (PetscInt64)ctx->nb[1] * info->n * g[2]);
  return PETSC_TRUE;
}

/* Uniform raster: ghosts are bitwise the wrapped owner's values; the reverse delivers each ghost to that cell. */
static PetscErrorCode TestUniform(Ctx *ctx, const char cname[], PffChannelKind kind, PetscInt w)
{
  PetscInt    ch, ncomp, n = 0;
  PetscInt64  count[REGION_KINDS] = {0}, gcount[REGION_KINDS], ncells;
  PetscMPIInt nexpect;
  double     *expect;
  char        what[160], chname[64];

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(chname, sizeof(chname), "u%s_w%" PetscInt_FMT, PffChannelKinds[kind], w));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s %s w=%" PetscInt_FMT, cname, PffChannelKinds[kind], w));
  PetscCall(PffGridAddChannel(ctx->grid, chname, kind, w, &ch));
  PetscCall(PffGridGetChannelInfo(ctx->grid, ch, NULL, NULL, &ncomp, NULL));
  for (PetscInt g = 0; g < ctx->nblocks; g++)
    if (ctx->level[g] >= 0) n = N0 >> ctx->level[g];
  ncells = (PetscInt64)ctx->nblocks * n * n * n;

  for (PetscInt lb = 0; lb < ctx->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(ctx->grid, lb, &info));
    PetscCheck(info.n == n, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: the raster is not uniform", what);
    for (PetscInt comp = 0; comp < ncomp; comp++) {
      float *data;
      PetscCall(PffGridGetBlockData(ctx->grid, ch, lb, comp, &data));
      for (PetscInt k = 0; k < n; k++)
        for (PetscInt j = 0; j < n; j++)
          for (PetscInt i = 0; i < n; i++) {
            const PetscInt c[3] = {i, j, k};
            PetscInt64     idx  = -1;
            (void)UniformIndex(ctx, &info, c, &idx);
            data[i + n * (j + n * k)] = HashValue(PffTestKey((uint64_t)idx, (uint64_t)comp, 3, 0));
          }
    }
  }
  PetscCall(PffGridHaloBegin(ctx->grid, ch));
  PetscCall(PffGridHaloEnd(ctx->grid, ch));
  for (PetscInt lb = 0; lb < ctx->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(ctx->grid, lb, &info));
    for (PetscInt comp = 0; comp < ncomp; comp++) {
      const PffView *views;
      PetscCall(PffGridGetBlockViews(ctx->grid, ch, lb, comp, &views));
      for (PetscInt r = 0; r < 27; r++) {
        PetscInt   nbr, lo[3], hi[3];
        RegionKind rk;
        if (r == 13) continue;
        rk = Classify(ctx, &info, r, &nbr);
        PetscCheck(rk == REGION_SAME || rk == REGION_WALL, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: raster not uniform",
                   what);
        RegionBox(r, n, w, lo, hi);
        for (PetscInt k = lo[2]; k < hi[2]; k++)
          for (PetscInt j = lo[1]; j < hi[1]; j++)
            for (PetscInt i = lo[0]; i < hi[0]; i++, count[rk]++) {
              const PetscInt  c[3] = {i, j, k};
              const float     v    = *PffViewsAt(views, i, j, k, n);
              PetscInt64      idx;
              const PetscBool inside = UniformIndex(ctx, &info, c, &idx);
              PetscCheck(inside == (rk == REGION_SAME), PETSC_COMM_SELF, PETSC_ERR_PLIB,
                         "%s: region %" PetscInt_FMT " of block %" PetscInt_FMT " misclassified", what, r, info.gid);
              const float expect = inside ? HashValue(PffTestKey((uint64_t)idx, (uint64_t)comp, 3, 0)) : 0.0f;
              PetscCheck(v == expect, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                         "%s: ghost (%" PetscInt_FMT ",%" PetscInt_FMT ",%" PetscInt_FMT ") of block %" PetscInt_FMT
                         " comp %" PetscInt_FMT " region %" PetscInt_FMT
                         " is %.9g, the wrapped owner cell %" PetscInt64_FMT " holds %.9g",
                         what, i, j, k, info.gid, comp, r, (double)v, inside ? idx : -1, (double)expect);
            }
      }
    }
  }

  /* reverse: each ghost's value must arrive in the one cell it mirrors */
  PetscCall(PffGridHaloReverseBegin(ctx->grid, ch));
  PetscCall(PffGridHaloReverseEnd(ctx->grid, ch));
  PetscCall(CheckGhostsCleared(ctx, ch, what));
  PetscCall(PetscCalloc1(ncells * ncomp, &expect));
  for (PetscInt lb = 0; lb < ctx->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(ctx->grid, lb, &info));
    for (PetscInt comp = 0; comp < ncomp; comp++) {
      float *data;
      PetscCall(PffGridGetBlockData(ctx->grid, ch, lb, comp, &data));
      PetscCall(PetscArrayzero(data, n * n * n));
    }
  }
  for (PetscInt lb = 0; lb < ctx->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(ctx->grid, lb, &info));
    for (PetscInt comp = 0; comp < ncomp; comp++) {
      const PffView *views;
      PetscCall(PffGridGetBlockViews(ctx->grid, ch, lb, comp, &views));
      for (PetscInt r = 0; r < 27; r++) {
        PetscInt lo[3], hi[3];
        if (r == 13) continue;
        RegionBox(r, n, w, lo, hi);
        for (PetscInt k = lo[2]; k < hi[2]; k++)
          for (PetscInt j = lo[1]; j < hi[1]; j++)
            for (PetscInt i = lo[0]; i < hi[0]; i++) {
              const PetscInt c[3] = {i, j, k};
              PetscInt64     idx;
              if (!UniformIndex(ctx, &info, c, &idx)) continue;
              const float v = HashValue(PffTestKey((uint64_t)info.gid, (uint64_t)(comp * 27 + r), (uint64_t)(i + w),
                                                   (uint64_t)((j + w) + 64 * (k + w))));
              *PffViewsAt(views, i, j, k, n) += v;
              expect[comp * ncells + idx] += (double)v;
            }
      }
    }
  }
  PetscCall(PffGridHaloReverseBegin(ctx->grid, ch));
  PetscCall(PffGridHaloReverseEnd(ctx->grid, ch));
  PetscCall(CheckGhostsCleared(ctx, ch, what));
  PetscCall(PetscMPIIntCast(ncells * ncomp, &nexpect));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, expect, nexpect, MPI_DOUBLE, MPI_SUM, ctx->comm));
  for (PetscInt lb = 0; lb < ctx->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(ctx->grid, lb, &info));
    for (PetscInt comp = 0; comp < ncomp; comp++) {
      float *data;
      PetscCall(PffGridGetBlockData(ctx->grid, ch, lb, comp, &data));
      for (PetscInt k = 0; k < n; k++)
        for (PetscInt j = 0; j < n; j++)
          for (PetscInt i = 0; i < n; i++) {
            const PetscInt c[3] = {i, j, k};
            PetscInt64     idx;
            (void)UniformIndex(ctx, &info, c, &idx);
            const double e = expect[comp * ncells + idx], v = (double)data[i + n * (j + n * k)];
            PetscCheck(PetscAbsReal(v - e) <= 1e-6 * PetscMax(e, 1.0), PETSC_COMM_SELF, PETSC_ERR_PLIB,
                       "%s: cell (%" PetscInt_FMT ",%" PetscInt_FMT ",%" PetscInt_FMT ") of block %" PetscInt_FMT
                       " comp %" PetscInt_FMT " received %.9g, the ghosts mirroring it held %.9g",
                       what, i, j, k, info.gid, comp, v, e);
          }
    }
  }
  PetscCall(PetscFree(expect));
  PetscCallMPI(MPI_Allreduce(count, gcount, REGION_KINDS, MPIU_INT64, MPI_SUM, ctx->comm));
  PetscCall(PetscPrintf(
      ctx->comm, "halo %s: ghosts same %" PetscInt64_FMT " wall %" PetscInt64_FMT ", bitwise copies ok, reverse ok\n",
      what, gcount[REGION_SAME], gcount[REGION_WALL]));
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  const Case multi[] = {
      {"4x3x5 walls", {4, 3, 5}, {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE}, 0, -1, 21},
      {"4x3x5 periodic x inactive", {4, 3, 5}, {PETSC_TRUE, PETSC_FALSE, PETSC_FALSE}, 12, -1, 22},
      {"5x4x3 periodic y,z inactive", {5, 4, 3}, {PETSC_FALSE, PETSC_TRUE, PETSC_TRUE}, 10, -1, 23},
      {"2x4x3 periodic x", {2, 4, 3}, {PETSC_TRUE, PETSC_FALSE, PETSC_FALSE}, 0, -1, 24}, /* both x-neighbours are one
                                                                                             block */
  };
  const Case uniform[] = {
      {"uniform 3x2x4 periodic x,y,z", {3, 2, 4}, {PETSC_TRUE, PETSC_TRUE, PETSC_TRUE}, 0, 0, 0},
      {"uniform 2x1x3 level 1 periodic x,y", {2, 1, 3}, {PETSC_TRUE, PETSC_TRUE, PETSC_FALSE}, 0, 1, 0},
  };

  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(PffInitializePackage());
  for (size_t c = 0; c < PETSC_STATIC_ARRAY_LENGTH(multi); c++) {
    Ctx        ctx;
    PetscInt64 pl[PFF_GRID_MAX_LEVELS], total;
    PetscCall(CreateGrid(PETSC_COMM_WORLD, &multi[c], &ctx));
    PetscCall(PffGridGetCellCounts(ctx.grid, pl, &total));
    PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                          "raster %s: cells per level %" PetscInt64_FMT " %" PetscInt64_FMT " %" PetscInt64_FMT "\n",
                          multi[c].name, pl[0], pl[1], pl[2]));
    PetscCall(TestLinear(&ctx, multi[c].name, PFF_CHANNEL_CELL, 1));
    PetscCall(TestLinear(&ctx, multi[c].name, PFF_CHANNEL_CELL, 2));
    PetscCall(TestLinear(&ctx, multi[c].name, PFF_CHANNEL_FACE, 1));
    PetscCall(TestLinear(&ctx, multi[c].name, PFF_CHANNEL_FACE, 2));
    PetscCall(PffGridDestroy(&ctx.grid));
  }
  for (size_t c = 0; c < PETSC_STATIC_ARRAY_LENGTH(uniform); c++) {
    Ctx ctx;
    PetscCall(CreateGrid(PETSC_COMM_WORLD, &uniform[c], &ctx));
    PetscCall(TestUniform(&ctx, uniform[c].name, PFF_CHANNEL_CELL, 1));
    PetscCall(TestUniform(&ctx, uniform[c].name, PFF_CHANNEL_CELL, 2));
    PetscCall(TestUniform(&ctx, uniform[c].name, PFF_CHANNEL_FACE, 1));
    if (uniform[c].uniform > 0)
      PetscCall(TestUniform(&ctx, uniform[c].name, PFF_CHANNEL_CELL, N0 >> uniform[c].uniform));
    PetscCall(PffGridDestroy(&ctx.grid));
  }
  PetscCall(PetscFinalize());
  return 0;
}
