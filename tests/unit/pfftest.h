/* Helpers shared by the grid unit tests: counter-based hashing (the same values on every rank),
   pseudo-random graded multi-level grids, sample positions and linear test fields. */
#pragma once

#include <pff.h>

static inline uint64_t PffTestHash64(uint64_t i)
{
  uint64_t z = i + 0x9e3779b97f4a7c15ULL;
  z          = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z          = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

static inline uint64_t PffTestKey(uint64_t a, uint64_t b, uint64_t c, uint64_t d)
{
  return PffTestHash64(PffTestHash64(PffTestHash64(PffTestHash64(a) ^ b) ^ c) ^ d);
}

/* A set-up grid and what the tests read from it. */
typedef struct {
  PffGrid            grid;
  MPI_Comm           comm;
  PetscMPIInt        rank;
  PetscInt           nb[3], nblocks, nlocal;
  const PetscInt    *level;
  const PetscMPIInt *owner;
  PetscBool          periodic[3];
  PetscReal          origin[3], h0, blen;
} PffTestCtx;

/* A key from a sample position (quarter-cell lattice of the finest cells), a component and a purpose:
   the same value on every rank count and partition. */
static inline uint64_t PffTestPositionKey(const PffTestCtx *t, const PetscReal x[3], PetscInt comp, uint64_t purpose)
{
  uint64_t q[3];
  for (int a = 0; a < 3; a++) q[a] = (uint64_t)llround((x[a] - t->origin[a]) / (0.25 * t->h0));
  return PffTestKey(purpose, q[0] + 1000003ULL * (uint64_t)comp, q[1], q[2]);
}

/* Uniform in [0, 1) from a key (its 53 high bits). */
static inline PetscReal PffTestUniform01(uint64_t key)
{
  return (PetscReal)(key >> 11) / 9007199254740992.0;
}

/* A grid of nb blocks of n0 cells with nlevels levels and the requested level of every block
   (request, -1 inactive); fills ctx. */
static inline PetscErrorCode PffTestCreateGridFromMap(MPI_Comm comm, const PetscInt nb[3], const PetscBool periodic[3],
                                                      const PetscReal origin[3], PetscReal h0, PetscInt n0,
                                                      PetscInt nlevels, const PetscInt request[], PffTestCtx *ctx)
{
  const PetscInt cells[3] = {n0 * nb[0], n0 * nb[1], n0 * nb[2]};

  PetscFunctionBeginUser;
  PetscCall(PetscMemzero(ctx, sizeof(*ctx)));
  PetscCall(PffGridCreate(comm, &ctx->grid));
  PetscCall(PffGridSetCells(ctx->grid, cells));
  PetscCall(PffGridSetBlockSize(ctx->grid, n0));
  PetscCall(PffGridSetLevels(ctx->grid, nlevels));
  PetscCall(PffGridSetDomain(ctx->grid, origin, h0));
  PetscCall(PffGridSetPeriodic(ctx->grid, periodic));
  PetscCall(PffGridSetRefinementMap(ctx->grid, request));
  PetscCall(PffGridSetUp(ctx->grid));
  ctx->comm = comm;
  PetscCallMPI(MPI_Comm_rank(comm, &ctx->rank));
  PetscCall(PffGridGetRaster(ctx->grid, ctx->nb, &ctx->level, &ctx->owner));
  PetscCall(PffGridGetSizes(ctx->grid, NULL, NULL, ctx->origin, &ctx->h0, ctx->periodic));
  PetscCall(PffGridGetLocalBlocks(ctx->grid, &ctx->nlocal));
  ctx->nblocks = nb[0] * nb[1] * nb[2];
  ctx->blen    = (PetscReal)n0 * ctx->h0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A requested level per block of an nb raster. With uniform >= 0 every block has that level; otherwise
   levels grow with the distance from a random block, with random jumps, so every level and every kind of
   level step occurs and grading has work to do. inactive: percentage of blocks requested inactive. */
static inline void PffTestRandomMap(const PetscInt nb[3], PetscInt nlevels, PetscInt uniform, PetscInt inactive,
                                    uint64_t seed, PetscInt request[])
{
  const PetscInt nblocks = nb[0] * nb[1] * nb[2];

  for (PetscInt b = 0; b < nblocks; b++) {
    const uint64_t h  = PffTestKey(seed, 1, (uint64_t)b, 0);
    PetscReal      d2 = 0;
    for (int a = 0; a < 3; a++) {
      const PetscInt ia = a == 0 ? b % nb[0] : (a == 1 ? (b / nb[0]) % nb[1] : b / (nb[0] * nb[1]));
      d2 += PetscSqr((PetscReal)(ia - (PetscInt)(PffTestKey(seed, 2, (uint64_t)a, 0) % (uint64_t)nb[a])));
    }
    const PetscInt l = (PetscInt)(PetscSqrtReal(d2) / 1.5) + (PetscInt)(h % 3) - 1;
    request[b]       = uniform >= 0 ? uniform : PetscMax(0, PetscMin(nlevels - 1, l));
    if ((PetscInt)((h >> 32) % 100) < inactive) request[b] = -1;
  }
}

/* Whether cell or face c of a block lies more than reach cells from every neighbour block of another level. */
static inline PetscBool PffTestAwayFromLevelJumps(const PffTestCtx *ctx, const PffBlockInfo *info, const PetscInt c[3],
                                                  PetscInt reach)
{
  const PetscInt n = info->n;
  for (PetscInt r = 0; r < 27; r++) {
    PetscInt d[3], near = 1;
    PffRegionDirection(r, d);
    for (int a = 0; a < 3; a++)
      if ((d[a] < 0 && c[a] > reach) || (d[a] > 0 && c[a] < n - 1 - reach)) near = 0;
    if (r == PFF_REGION_SELF || !near) continue;
    const PetscInt nbr = PffRasterNeighbour(ctx->nb, ctx->periodic, info->ijk, d);
    if (nbr >= 0 && ctx->level[nbr] != info->level) return PETSC_FALSE;
  }
  return PETSC_TRUE;
}

/* A grid of nb blocks of n0 cells with the levels of PffTestRandomMap. */
static inline PetscErrorCode PffTestCreateGrid(MPI_Comm comm, const PetscInt nb[3], const PetscBool periodic[3],
                                               const PetscReal origin[3], PetscReal h0, PetscInt n0, PetscInt nlevels,
                                               PetscInt uniform, PetscInt inactive, uint64_t seed, PffTestCtx *ctx)
{
  PetscInt *request;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(nb[0] * nb[1] * nb[2], &request));
  PffTestRandomMap(nb, nlevels, uniform, inactive, seed, request);
  PetscCall(
      PffTestCreateGridFromMap(comm, nb, periodic, origin, h0, n0, uniform >= 0 ? uniform + 1 : nlevels, request, ctx));
  PetscCall(PetscFree(request));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* World position of the sample of component comp at block-local cell c: the cell centre, or the lower
   comp-face for a face channel. */
static inline void PffTestSamplePosition(const PffBlockInfo *info, PffChannelKind kind, PetscInt comp,
                                         const PetscInt c[3], PetscReal x[3])
{
  for (int a = 0; a < 3; a++)
    x[a] = info->lo[a] + ((PetscReal)c[a] + (kind == PFF_CHANNEL_FACE && comp == a ? 0.0 : 0.5)) * info->h;
}

/* The linear test field of component comp; no slope along periodic axes, so it is periodic. */
static inline PetscReal PffTestLinear(const PffTestCtx *ctx, PetscInt comp, const PetscReal x[3])
{
  const PetscReal slope[3] = {0.3, -0.7, 0.45};
  PetscReal       f        = 1.0 + 0.5 * (PetscReal)comp;
  for (int a = 0; a < 3; a++)
    if (!ctx->periodic[a]) f += slope[(a + comp) % 3] * x[a];
  return f;
}

/* Largest |PffTestLinear| of components shift..shift+ncomp-1 over the domain (attained at a corner):
   the scale that float tolerances are relative to. */
static inline PetscReal PffTestFieldScale(const PffTestCtx *ctx, PetscInt ncomp, PetscInt shift)
{
  PetscReal scale = 0;
  for (PetscInt comp = 0; comp < ncomp; comp++)
    for (int c = 0; c < 8; c++) {
      PetscReal x[3];
      for (int a = 0; a < 3; a++) x[a] = ctx->origin[a] + ((c >> a) & 1 ? ctx->blen * (PetscReal)ctx->nb[a] : 0.0);
      scale = PetscMax(scale, PetscAbsReal(PffTestLinear(ctx, comp + shift, x)));
    }
  return scale;
}

/* PffTestLinear as a PffFieldFn for PffGridFillChannel: component comp gets field comp + shift. */
typedef struct {
  const PffTestCtx *ctx;
  PetscInt          shift;
} PffTestLinearFill;

static inline PetscReal PffTestLinearValue(const PetscReal x[3], PetscInt comp, void *fill)
{
  const PffTestLinearFill *f = (const PffTestLinearFill *)fill;
  return PffTestLinear(f->ctx, comp + f->shift, x);
}

static inline PetscReal PffTestOne(const PetscReal x[3], PetscInt comp, void *ctx)
{
  (void)x, (void)comp, (void)ctx;
  return 1.0;
}

static inline PetscReal PffTestZero(const PetscReal x[3], PetscInt comp, void *ctx)
{
  (void)x, (void)comp, (void)ctx;
  return 0.0;
}

/* The channels of a pressure test: face channels beta and u filled from the given functions (both get
   ctx), face channel open = 1 (every face open), cell channel p = 0. */
static inline PetscErrorCode PffTestAddPressureChannels(PffGrid grid, PffFieldFn beta, PffFieldFn u, void *ctx,
                                                        PetscInt *betaCh, PetscInt *openCh, PetscInt *uCh,
                                                        PetscInt *pCh)
{
  PetscFunctionBeginUser;
  PetscCall(PffGridAddChannel(grid, "beta", PFF_CHANNEL_FACE, 1, betaCh));
  PetscCall(PffGridAddChannel(grid, "open", PFF_CHANNEL_FACE, 1, openCh));
  PetscCall(PffGridAddChannel(grid, "u", PFF_CHANNEL_FACE, 1, uCh));
  PetscCall(PffGridAddChannel(grid, "p", PFF_CHANNEL_CELL, 1, pCh));
  PetscCall(PffGridFillChannel(grid, *betaCh, beta, ctx));
  PetscCall(PffGridFillChannel(grid, *openCh, PffTestOne, NULL));
  PetscCall(PffGridFillChannel(grid, *uCh, u, ctx));
  PetscCall(PffGridFillChannel(grid, *pCh, PffTestZero, NULL));
  PetscFunctionReturn(PETSC_SUCCESS);
}
