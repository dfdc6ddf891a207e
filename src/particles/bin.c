/* Binning (DESIGN.md Sec. 6): a stable counting sort of the local particles by owned block, so the
   particles of local block lb are contiguous, [start[lb], start[lb + 1]). This gives cache-coherent
   traversal and the per-block work lists of the 8-colour lock-free P2G. The sort runs in threads over
   contiguous chunks whose offsets keep the chunks in order, so its result does not depend on the
   thread count (bit-exact restarts rely on the order).

   No second copy of the store (issue 12): the sort computes each particle's destination (4 B per
   particle) and then moves the store one 4-byte lane at a time (x, y, z of x and v, the two halves of
   the id, the word) through a lane buffer of 4 B per particle. A store that is already in order is
   left as it is. Particles marked PFF_SORT_DROP (Migrate's leavers) are left out, so the store ends with
   start[nlocal] particles. */
#include "particlesimpl.h"
#include <omp.h>

/* Refreshes the owned-block tables (the grid may have been re-partitioned since the last call). */
PetscErrorCode PffParticlesUpdateBlocks_Private(PffParticles p, PetscBool *changed)
{
  PetscInt nlocal, nblocks = p->nb[0] * p->nb[1] * p->nb[2];

  PetscFunctionBeginUser;
  PetscCall(PffGridGetLocalBlocks(p->grid, &nlocal));
  *changed = (PetscBool)(p->start == NULL || nlocal != p->nlocal);
  if (p->start == NULL || nlocal != p->nlocal) {
    PetscCall(PetscFree(p->start));
    PetscCall(PetscFree(p->lgid));
    PetscCall(PetscMalloc1(nlocal + 1, &p->start));
    PetscCall(PetscMalloc1(PetscMax(nlocal, 1), &p->lgid));
    p->nlocal = nlocal;
  }
  if (p->local == NULL) PetscCall(PetscMalloc1(nblocks, &p->local));
  for (PetscInt b = 0; b < nblocks; b++) p->local[b] = -1;
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(p->grid, lb, &info));
    if (p->lgid[lb] != info.gid) *changed = PETSC_TRUE;
    p->lgid[lb]        = info.gid;
    p->local[info.gid] = lb;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Moves 4-byte lane `lane` of the n records of `size` bytes at base to their destinations dst through
   buf, which leaves nout records (the dropped ones have no destination): lane by lane keeps the scratch at
   4 B per particle. */
static void PffBinScatterLane(void *base, size_t size, size_t lane, PetscInt n, PetscInt nout, const int32_t dst[],
                              float *buf)
{
  char *b = (char *)base + 4 * lane;
#pragma omp parallel for schedule(static)
  for (PetscInt i = 0; i < n; i++)
    if (dst[i] != PFF_SORT_DROP) memcpy(&buf[dst[i] & ~PFF_SORT_STAYS], b + size * (size_t)i, 4);
#pragma omp parallel for schedule(static)
  for (PetscInt j = 0; j < nout; j++) memcpy(b + size * (size_t)j, &buf[j], 4);
}

PetscErrorCode PffParticlesBin(PffParticles p)
{
  const PetscInt *level;
  PetscInt        nb[3], nbad = 0;
  const PetscInt  n = p->n;
  int32_t        *dst;

  PetscFunctionBeginUser;
  PetscCall(PetscLogEventBegin(PFF_PartBin, 0, 0, 0, 0));
  PetscBool changed;
  PetscCall(PffParticlesUpdateBlocks_Private(p, &changed));
  PetscCall(PffGridGetRaster(p->grid, nb, &level, NULL));
  PetscCall(PffParticlesGetIntWork_Private(p, (size_t)n + 1, &dst));
  const PetscInt *local = p->local;
#pragma omp parallel for reduction(+ : nbad) schedule(static)
  for (PetscInt i = 0; i < n; i++) {
    const PetscInt gid = PffParticlesLocate_Private(p, &p->s.x[3 * i], level);
    dst[i]             = gid >= 0 ? (int32_t)local[gid] : -1;
    if (dst[i] < 0) nbad++;
  }
  if (nbad > 0) {
    PetscInt i = 0;
    while (dst[i] >= 0) i++;
    SETERRQ(PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
            "%" PetscInt_FMT " particles are not in a block owned by rank %d, e.g. id %" PetscInt64_FMT
            " at (%g, %g, %g): call PffParticlesMigrate",
            nbad, (int)p->rank, (PetscInt64)p->s.id[i], (double)(p->origin[0] + p->h0 * p->s.x[3 * i]),
            (double)(p->origin[1] + p->h0 * p->s.x[3 * i + 1]), (double)(p->origin[2] + p->h0 * p->s.x[3 * i + 2]));
  }
  PetscCall(PffParticlesSort_Private(p));
  PetscCall(PetscLogEventEnd(PFF_PartBin, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The sort when few particles changed block (after an advection step): the particles flagged
   PFF_SORT_STAYS keep their order, so their destinations increase with their places. The others (the
   movers) are packed into a buffer; the stayers that move left are moved in ascending order and those
   that move right in descending order, so none overwrites a stayer not yet moved (a place a stayer
   moves to is a mover's, a dropped particle's or an already moved stayer's); then the movers are unpacked. One
   pass over the store instead of two per 4-byte lane, and scratch for the movers only. */
static PetscErrorCode PffParticlesSortInPlace(PffParticles p, PetscInt movers)
{
  const PetscInt n   = p->n;
  const int32_t *dst = p->i32work;
  const size_t   rec = PFF_PARTICLE_BYTES + sizeof(int32_t);
  char          *buf;

  PetscFunctionBeginUser;
  {
    const size_t bytes = rec * (size_t)movers;
    void        *ptr;
    PetscCall(PffParticlesGetScratch_Private(p, PFF_SCRATCH_SORT_MOVERS, 1, &bytes, &ptr));
    buf = (char *)ptr;
  }
  for (PetscInt i = 0, m = 0; i < n; i++)
    if (dst[i] != PFF_SORT_DROP && !(dst[i] & PFF_SORT_STAYS)) {
      PffParticlesPack_Private(&p->s, i, buf + rec * (size_t)m);
      memcpy(buf + rec * (size_t)m + PFF_PARTICLE_BYTES, &dst[i], sizeof(int32_t));
      m++;
    }
  for (PetscInt i = 0; i < n; i++) {
    const PetscInt d = dst[i] & ~PFF_SORT_STAYS;
    if (dst[i] != PFF_SORT_DROP && (dst[i] & PFF_SORT_STAYS) && d < i) PffParticlesMove_Private(p, d, i);
  }
  for (PetscInt i = n - 1; i >= 0; i--) {
    const PetscInt d = dst[i] & ~PFF_SORT_STAYS;
    if (dst[i] != PFF_SORT_DROP && (dst[i] & PFF_SORT_STAYS) && d > i) PffParticlesMove_Private(p, d, i);
  }
  for (PetscInt m = 0; m < movers; m++) {
    int32_t d;
    memcpy(&d, buf + rec * (size_t)m + PFF_PARTICLE_BYTES, sizeof(int32_t));
    PffParticlesUnpack_Private(&p->s, d, buf + rec * (size_t)m);
  }
  /* released when a large reorder made it big */
  if (p->nscratch[PFF_SCRATCH_SORT_MOVERS] > 8 * (size_t)n + 65536) {
    PetscCall(PetscFree(p->scratch[PFF_SCRATCH_SORT_MOVERS]));
    p->nscratch[PFF_SCRATCH_SORT_MOVERS] = 0;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The calling thread's contiguous chunk [i0, i1) of the n particles and its row c of counts (rows of nl + 1). */
static inline void PffSortChunk(PetscInt n, PetscInt nl, PetscInt counts[], PetscInt *i0, PetscInt *i1, PetscInt **c)
{
  const PetscInt th = omp_get_thread_num(), nth = omp_get_num_threads();
  *i0 = n * th / nth;
  *i1 = n * (th + 1) / nth;
  *c  = counts + (size_t)th * (size_t)(nl + 1);
}

/* In the calling thread's chunk [i0, i1) of dst: c[b] += the particles of bin b. The particles come mostly in runs of
   one bin (binned before): a run's count stays in a register, where c[b]++ per particle waited on its own store (about
   5 ms per sort of 1.75 M particles). */
static inline void PffSortCount(const int32_t dst[], PetscInt n, PetscInt nl, PetscInt counts[])
{
  PetscInt i0, i1, *c;
  PetscInt cur = -1, run = 0;
  PffSortChunk(n, nl, counts, &i0, &i1, &c);
  for (PetscInt i = i0; i < i1; i++) {
    if (dst[i] == PFF_SORT_DROP) continue;
    const PetscInt b = dst[i] & ~PFF_SORT_STAYS;
    if (b != cur) {
      if (cur >= 0) c[cur] += run;
      cur = b;
      run = 0;
    }
    run++;
  }
  if (cur >= 0) c[cur] += run;
}

/* counts[th][lb] (nth rows of nl + 1) from counts to the first place of thread th's particles of block lb, and
   start[lb] the first place of block lb. */
static inline void PffSortOffsets(PetscInt counts[], PetscInt nl, PetscInt nth, PetscInt start[])
{
  PetscInt off = 0;
  for (PetscInt lb = 0; lb < nl; lb++) {
    start[lb] = off;
    for (PetscInt q = 0; q < nth; q++) {
      PetscInt *cq = counts + (size_t)q * (size_t)(nl + 1), m = cq[lb];
      cq[lb] = off;
      off += m;
    }
  }
  start[nl] = off;
}

/* In the calling thread's chunk [i0, i1) of dst: from bins to places, c[b] the next place of bin b (advanced); the
   STAYS flags are kept. Counts the particles that move or are dropped, and the movers (not flagged). The next place of
   a run's bin in a register, as in PffSortCount. */
static inline void PffSortNumber(int32_t dst[], PetscInt n, PetscInt nl, PetscInt counts[], PetscInt *moved,
                                 PetscInt *movers)
{
  PetscInt i0, i1, *c;
  PetscInt cur = -1, next = 0;
  PffSortChunk(n, nl, counts, &i0, &i1, &c);
  for (PetscInt i = i0; i < i1; i++) {
    if (dst[i] == PFF_SORT_DROP) {
      (*moved)++;
      continue;
    }
    const PetscInt b = dst[i] & ~PFF_SORT_STAYS;
    if (b != cur) {
      if (cur >= 0) c[cur] = next;
      cur  = b;
      next = c[b];
    }
    const int32_t stays = dst[i] & PFF_SORT_STAYS, d = (int32_t)next++;
    dst[i] = d | stays;
    *moved += d != i;
    *movers += !stays;
  }
  if (cur >= 0) c[cur] = next;
}

PetscErrorCode PffParticlesSort_Private(PffParticles p)
{
  PetscInt       moved = 0, movers = 0;
  const PetscInt n   = p->n;
  int32_t       *dst = p->i32work;

  PetscFunctionBeginUser;
  PetscCheck(n < PFF_SORT_STAYS, PETSC_COMM_SELF, PETSC_ERR_SUP,
             "%" PetscInt_FMT " particles on one rank: the binning indexes them with 30 bits; use more ranks", n);
  /* stable counting sort in threads: each thread counts and then numbers its own contiguous chunk,
     from offsets that put the chunks in order, so the result is the serial sort's */
  PetscInt      *start = p->start, *counts;
  const PetscInt nl = p->nlocal, nt = (PetscInt)PetscMax(omp_get_max_threads(), 1);
  {
    const size_t bytes = sizeof(PetscInt) * (size_t)nt * (size_t)(nl + 1);
    void        *ptr;
    PetscCall(PffParticlesGetScratch_Private(p, PFF_SCRATCH_SORT, 1, &bytes, &ptr));
    counts = (PetscInt *)ptr;
    PetscCall(PetscArrayzero(counts, (size_t)nt * (size_t)(nl + 1)));
  }
  /* one parallel region, so that both passes split the particles into the same chunks */
#pragma omp parallel num_threads(nt) reduction(+ : moved, movers)
  {
    PffSortCount(dst, n, nl, counts);
    /* clang-format aligned the second pragma like a declaration */
    // clang-format off
#pragma omp barrier
#pragma omp single
    PffSortOffsets(counts, nl, omp_get_num_threads(), start);
    // clang-format on
    PffSortNumber(dst, n, nl, counts, &moved, &movers);
  }

  /* in place when few moved and one thread sorts (its sweeps are serial: +11 % advection at 1 thread,
     -6 % at 2 against the lane sort, which runs in threads; pff-bench-particles) */
  if (moved && movers <= n / 8 && nt == 1)
    PetscCall(PffParticlesSortInPlace(p, movers));
  else if (moved) {
    float *buf;
    PetscCall(PffParticlesGetFloatWork_Private(p, (size_t)n + 1, &buf));
#define PFF_PARTICLE_FIELD_SORT(name, type, k, f)                                                                      \
  for (size_t l = 0; l < (k) * sizeof(type) / 4; l++)                                                                  \
    PffBinScatterLane(p->s.name, (k) * sizeof(type), l, n, p->start[nl], dst, buf);
    PFF_PARTICLE_FIELDS(PFF_PARTICLE_FIELD_SORT)
#undef PFF_PARTICLE_FIELD_SORT
  }
  p->n      = p->start[nl]; /* without the dropped particles */
  p->binned = PETSC_TRUE;
  PetscCall(PffGridGetTopologyState(p->grid, &p->topology));
  PetscFunctionReturn(PETSC_SUCCESS);
}
