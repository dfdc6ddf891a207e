/* Particle split and probabilistic coarsening (PF-FLIP Sec. 5.1, 5.4 step 6; docs/particles.md,
   "Adaptive particles").

   A particle of level l asked for level t < l becomes 8^(l - t) particles of level t with its velocity, type and
   flags. Children are placed per group: the splitting particles of one (l, t) that lie in one cell C of level l
   share C's 64 sub-cells of level l - 1 (8 particles per cell, as seeding puts them): in rounds each parent takes
   the nearest of the least used sub-cells in the least filled octant of C (AssignSubCells); a split by more than one
   level repeats that per level, the children in each octant sharing its sub-cells (AssignSlots); each child goes to
   a uniformly random place inside its sub-cell. The level-l kernel saw C's parents as a smooth density, but they lie
   anywhere in C after advection: placing each parent's children around the parent (in its finer cell, or in its own
   cube) left the finer cells that no parent happened to sit in empty. Such holes read phi = 0.3 in the bulk of the
   liquid, and rt3d_small_adaptive lost 4 % of its liquid volume for three steps after a refinement. Sharing the sub-
   cells leaves no hole while C has at least 8 parents; mass and momentum are exact (each child carries its parent's
   velocity and 8^-(l - t) of its volume). Children stay in C, so particles keep their block and the store is binned
   again without a migration. The groups, their order (by id) and the draws (keyed by child ids) do not depend on the
   partition or the threads.

   Coarsening is stratified: the candidates that go from level l to t (per type) in one cell of level t are ordered by
   their own draw, and the first K = floor(N 8^(l - t) + u) of the N survive, u one draw per group. Each candidate still
   survives with probability 8^(l - t), so mass is kept in expectation as with independent draws, but a group's
   survivors miss its volume by less than one coarse particle: independent draws let the liquid mass of a whole rt3d W =
   64 adaptive run walk by 0.4-0.6 % over its 108-122 grid changes (docs/validation.md). */
#include "particlesimpl.h"
#include <omp.h>

/* A particle of a split or coarsening group, for the sort: the group (split: l, t and the cell of level l in the
   block; coarsening: type, l, t and the cell of level t), its draw (coarsening; 0 for a split), its id and its index.
   Sorted by group, then draw, then id. */
typedef struct {
  PetscInt64 group;
  PetscReal  u;
  uint64_t   id;
  PetscInt   i;
} PffAdaptItem;

static int PffAdaptItemCompare(const void *pa, const void *pb)
{
  const PffAdaptItem *a = (const PffAdaptItem *)pa, *b = (const PffAdaptItem *)pb;
  if (a->group != b->group) return a->group < b->group ? -1 : 1;
  if (a->u != b->u) return a->u < b->u ? -1 : 1;
  return a->id < b->id ? -1 : (a->id > b->id ? 1 : 0);
}

/* The end of the group that starts at g0 in the sorted items [0, n). */
static inline PetscInt PffAdaptGroupEnd(const PffAdaptItem *it, PetscInt g0, PetscInt n)
{
  PetscInt g1 = g0 + 1;
  while (g1 < n && it[g1].group == it[g0].group) g1++;
  return g1;
}

/* The cell of level l that holds grid coordinate x (one axis): its index within its block, and in lo
   (if not NULL) its lower face. */
static inline PetscInt CellOfLevel(PffParticles p, float x, PetscInt l, float *lo)
{
  const PetscInt xi = (PetscInt)x, b = (xi >> p->log2n0) << p->log2n0;
  const PetscInt q = PetscClipInterval((xi - b) >> l, 0, (p->n0 >> l) - 1);
  if (lo) *lo = (float)(b + (q << l));
  return q;
}

/* bits of a coarsening group for the cell of level t in its block: (64 >> t)^3 <= 2^18 cells */
#define PFF_COARSEN_CELL_BITS 18

static inline PetscBool PffCoarsenCandidate(uint32_t w, PetscInt t, PetscInt delay)
{
  return (PetscBool)(t > PffParticleWordLevel(w) && PffParticleWordCoarsen(w) >= delay);
}

/* The stratified coarsening of the candidates [i0, i1) of block gid (see the top of the file): survivors take level t,
   the others the removal flag; counts and volume changes per type into the sums. it is scratch for i1 - i0 items. */
static void PffCoarsenBlock(PffParticles p, const int8_t target[], PetscInt delay, uint64_t key, PetscInt gid,
                            PetscInt i0, PetscInt i1, PffAdaptItem *it, PetscInt64 *removed, PetscReal dv[2])
{
  const PetscInt lmax = p->nlevels - 1;
  const uint32_t rm   = PffParticleWordSetFlags(0, PFF_PARTICLE_FLAG_REMOVE, PETSC_TRUE);
  PetscInt       m    = 0;
  for (PetscInt i = i0; i < i1; i++) {
    const uint32_t w = p->s.word[i];
    const PetscInt t = PetscClipInterval((PetscInt)target[i], 0, lmax);
    if (!PffCoarsenCandidate(w, t, delay)) continue;
    PetscInt64 cell = 0;
    for (int a = 2; a >= 0; a--) cell = cell * (p->n0 >> t) + CellOfLevel(p, p->s.x[3 * i + a], t, NULL);
    const PetscInt64 kind =
        (PffParticleWordType(w) * PFF_GRID_MAX_LEVELS + PffParticleWordLevel(w)) * PFF_GRID_MAX_LEVELS + t;
    it[m++] = (PffAdaptItem){(kind << PFF_COARSEN_CELL_BITS) | cell,
                             PffRandom01_Private(p->seed, p->s.id[i], PFF_RNG_COARSEN, key), p->s.id[i], i};
  }
  qsort(it, (size_t)m, sizeof(PffAdaptItem), PffAdaptItemCompare);
  for (PetscInt g0 = 0, g1; g0 < m; g0 = g1) {
    g1                    = PffAdaptGroupEnd(it, g0, m);
    const PetscInt64 kind = it[g0].group >> PFF_COARSEN_CELL_BITS;
    const PetscInt   t    = (PetscInt)(kind % PFF_GRID_MAX_LEVELS),
                   l      = (PetscInt)((kind / PFF_GRID_MAX_LEVELS) % PFF_GRID_MAX_LEVELS);
    const PetscInt  type  = (PetscInt)(kind / (PFF_GRID_MAX_LEVELS * PFF_GRID_MAX_LEVELS));
    const PetscReal q     = 1.0 / (PetscReal)((PetscInt64)1 << (3 * (t - l)));
    const PetscReal u     = PffRandom01_Private(p->seed, PffHash64_Private((uint64_t)gid) ^ (uint64_t)it[g0].group,
                                                PFF_RNG_COARSEN_GROUP, key);
    const PetscInt  keep  = (PetscInt)PetscFloorReal((PetscReal)(g1 - g0) * q + u);
    const PetscReal vl = (PetscReal)((PetscInt64)1 << (3 * l)), vt = (PetscReal)((PetscInt64)1 << (3 * t));
    for (PetscInt g = g0; g < g1; g++) {
      const PetscInt i = it[g].i;
      if (g - g0 < keep) {
        p->s.word[i] = PffParticleWordSetLevel(p->s.word[i], t, 0);
        dv[type] += vt - vl;
      } else {
        p->s.word[i] |= rm;
        (*removed)++;
        dv[type] -= vl;
      }
    }
  }
}

static inline uint64_t PffChildId(uint64_t parent, PetscInt64 c)
{
  return PffHash64_Private(parent ^ (0x9e3779b97f4a7c15ULL * (uint64_t)(c + 1))) | (1ULL << 63);
}

/* The octant of C (a cell of level l - 1) that first-level sub-cell k (2 bits per axis) lies in */
static inline PetscInt SubCellOctant(PetscInt k)
{
  return ((k >> 1) & 1) | ((k >> 2) & 2) | ((k >> 3) & 4);
}

/* The first-level sub-cells of the np parents at x[3 np] in one cell C (lower corner lo, sub-cells of side q1):
   slot[8 g + c] for child c of parent g. In 8 rounds each parent in turn takes a sub-cell of the octant of C (a cell
   of level l - 1) with the fewest children so far, the least used sub-cell in it, the nearest to the parent among
   those; so every octant gets exactly np children, every finer cell in C its share (no hole while C has 8 parents,
   an even density below that), and each child stays near its parent. */
static void AssignSubCells(const PetscReal x[], PetscInt np, const PetscReal lo[3], PetscReal q1, PetscInt slot[])
{
  PetscInt used[64] = {0}, octUsed[8] = {0};

  for (PetscInt c = 0; c < 8; c++)
    for (PetscInt g = 0; g < np; g++) {
      PetscInt  best = 0;
      PetscReal bd   = PETSC_MAX_REAL, sq[3][4];
      /* the squared distances along each axis to the 4 sub-cell centres: a sub-cell's distance is their sum */
      for (int a = 0; a < 3; a++)
        for (PetscInt j = 0; j < 4; j++) {
          const PetscReal e = lo[a] + q1 * ((PetscReal)j + 0.5) - x[3 * g + a];
          sq[a][j]          = e * e;
        }
      /* the least filled octant first, then the least used sub-cell in it, then the nearest, then the lowest k: the
         smallest (octant count, sub-cell count) key, and among its sub-cells the nearest (a branch-free first pass) */
      PetscInt64 key[64], kmin = INT64_MAX;
      for (PetscInt k = 0; k < 64; k++) {
        key[k] = ((PetscInt64)octUsed[SubCellOctant(k)] << 32) | (PetscInt64)used[k];
        kmin   = PetscMin(kmin, key[k]);
      }
      for (PetscInt k = 0; k < 64; k++) {
        if (key[k] != kmin) continue;
        const PetscReal d2 = sq[0][k & 3] + sq[1][(k >> 2) & 3] + sq[2][(k >> 4) & 3];
        if (d2 < bd) {
          best = k;
          bd   = d2;
        }
      }
      used[best]++;
      octUsed[SubCellOctant(best)]++;
      slot[g * 8 + c] = best;
    }
}

/* The lower corners of the slots of level t = l - r (side 2^t / 2) of the 8^r children of each of the np parents at
   x[3 np] in cell C (corner lo, side): corner[3 (8^r g + c)]. One level at a time: the parents share C's sub-cells
   (AssignSubCells); for r > 1 the children in each octant of C, placed at their sub-cells' centres, share that
   octant's sub-cells in turn, and so on down. So every cell of level t in C gets as many children as C had parents.
   Taking the octants of each child's own sub-cell instead left the cells of level t under the sub-cells that no
   parent took empty: rt3d W = 64 refined 51 blocks from level 2 to 0 at once and read 995 such holes as air, 0.5 %
   of the liquid volume (docs/validation.md). */
static PetscErrorCode AssignSlots(const PetscReal x[], PetscInt np, const PetscReal lo[3], PetscReal side, PetscInt r,
                                  PetscReal corner[])
{
  const PetscReal q1 = 0.25 * side;
  PetscInt       *slot;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(8 * np, &slot));
  AssignSubCells(x, np, lo, q1, slot);
  if (r == 1) {
    for (PetscInt c = 0; c < 8 * np; c++)
      for (int a = 0; a < 3; a++) corner[3 * c + a] = lo[a] + q1 * (PetscReal)((slot[c] >> (2 * a)) & 3);
  } else {
    const PetscInt nd = (PetscInt)1 << (3 * (r - 1));
    PetscReal     *xv, *cv;
    PetscInt      *who;
    /* an octant holds np children (AssignSubCells) */
    PetscCall(PetscMalloc3(3 * np, &xv, 3 * nd * np, &cv, np, &who));
    for (PetscInt o = 0; o < 8; o++) {
      PetscInt  nv = 0;
      PetscReal lo1[3];
      for (int a = 0; a < 3; a++) lo1[a] = lo[a] + 0.5 * side * (PetscReal)((o >> a) & 1);
      for (PetscInt c = 0; c < 8 * np; c++) {
        if (SubCellOctant(slot[c]) != o) continue;
        for (int a = 0; a < 3; a++) xv[3 * nv + a] = lo[a] + q1 * ((PetscReal)((slot[c] >> (2 * a)) & 3) + 0.5);
        who[nv++] = c;
      }
      PetscCheck(nv == np, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                 "octant %" PetscInt_FMT " of a split holds %" PetscInt_FMT " children, not %" PetscInt_FMT, o, nv, np);
      PetscCall(AssignSlots(xv, nv, lo1, 0.5 * side, r - 1, cv));
      for (PetscInt v = 0; v < nv; v++) PetscCall(PetscArraycpy(corner + 3 * nd * who[v], cv + 3 * nd * v, 3 * nd));
    }
    PetscCall(PetscFree3(xv, cv, who));
  }
  PetscCall(PetscFree(slot));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The 8^r children of level t = l - r of parent i (id, velocity and word taken first): child 0 in the parent's
   slot, the others appended at *m with bin lb in dst; child c at a random place in the slot of level t whose lower
   corner is corner[3 c] (AssignSlots). */
static void PlaceChildren(PffParticles p, PetscInt i, PetscInt r, PetscInt t, const float lo[3], float cside,
                          const PetscReal corner[], PetscInt lb, PetscInt *m, int32_t dst[])
{
  const PetscInt64 nc   = (PetscInt64)1 << (3 * r);
  const PetscReal  qt   = 0.5 * (PetscReal)((PetscInt)1 << t);
  const uint64_t   id   = p->s.id[i];
  const uint32_t   wc   = PffParticleWordSetLevel(p->s.word[i], t, 0);
  const float      v[3] = {p->s.v[3 * i], p->s.v[3 * i + 1], p->s.v[3 * i + 2]};

  for (PetscInt64 c = 0; c < nc; c++) {
    const uint64_t cid = PffChildId(id, c);
    const PetscInt j   = c == 0 ? i : (*m)++;
    for (int a = 0; a < 3; a++) {
      const PetscReal u = PffRandom01_Private(p->seed, cid, PFF_RNG_SPLIT, (uint64_t)a);
      const PetscReal x = corner[3 * c + a] + qt * u;
      /* rounding must not carry a child out of C (or its block) */
      p->s.x[3 * j + a] = PetscMin((float)x, nextafterf(lo[a] + cside, 0));
      p->s.v[3 * j + a] = v[a];
    }
    p->s.id[j]   = cid;
    p->s.word[j] = wc;
    if (c > 0) dst[j] = (int32_t)lb; /* the parent's slot stays in its bin */
  }
}

PetscErrorCode PffParticlesAdaptCounters(PffParticles p, int8_t wish[], PetscInt delay)
{
  const PetscInt n = p->n, lmax = p->nlevels - 1;

  PetscFunctionBeginUser;
  PetscCheck(delay >= 1 && delay <= 15, p->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "PffParticlesAdaptCounters: the coarsening delay %" PetscInt_FMT " must be in [1, 15]", delay);
#pragma omp parallel for schedule(static)
  for (PetscInt i = 0; i < n; i++) wish[i] = (int8_t)PffParticleWordCountWish(&p->s.word[i], wish[i], lmax, delay);
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffParticlesAdaptLevels(PffParticles p, const int8_t target[], PetscInt delay, uint64_t key,
                                       PffParticleAdaptStats *stats)
{
  PffParticleAdaptStats st = {0};
  const PetscInt        n = p->n, lmax = p->nlevels - 1;
  PetscInt64            extra = 0, nsplit = 0, marked = 0, removed = 0;
  PetscReal             vl0 = 0, va0 = 0, dl = 0, da = 0; /* volumes before, and their changes, per type */

  PetscFunctionBeginUser;
  PetscCheck(delay >= 1 && delay <= 15, p->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "PffParticlesAdaptLevels: the coarsening delay %" PetscInt_FMT " must be in [1, 15]", delay);
  PetscCall(PetscLogEventBegin(PFF_PartAdapt, 0, 0, 0, 0));
  /* volumes, splits and coarsening candidates counted in threads (each particle on its own) */
#pragma omp parallel for reduction(+ : extra, nsplit, marked, vl0, va0) schedule(static)
  for (PetscInt i = 0; i < n; i++) {
    const uint32_t  w = p->s.word[i];
    const PetscInt  l = PffParticleWordLevel(w), t = PetscClipInterval((PetscInt)target[i], 0, lmax);
    const PetscBool liquid = (PetscBool)(PffParticleWordType(w) == PFF_PARTICLE_LIQUID);
    const PetscReal vol    = (PetscReal)((PetscInt64)1 << (3 * l));
    if (liquid)
      vl0 += vol;
    else
      va0 += vol;
    if (t < l) {
      extra += ((PetscInt64)1 << (3 * (l - t))) - 1;
      nsplit++;
    } else if (PffCoarsenCandidate(w, t, delay))
      marked++;
  }
  if (marked) {
    /* whole bins per thread: the groups are a block's, so the survivors do not depend on the partition */
    PetscCheck(p->binned, PETSC_COMM_SELF, PETSC_ERR_ORDER,
               "PffParticlesAdaptLevels: coarsening needs binned particles");
    PetscInt mmax = 0;
    for (PetscInt lb = 0; lb < p->nlocal; lb++) mmax = PetscMax(mmax, p->start[lb + 1] - p->start[lb]);
    const PetscInt nth = PetscMax(omp_get_max_threads(), 1);
    PffAdaptItem  *items;
    PetscCall(PetscMalloc1((size_t)nth * (size_t)PetscMax(mmax, 1), &items));
#pragma omp parallel for reduction(+ : removed, dl, da) schedule(dynamic, 1)
    for (PetscInt lb = 0; lb < p->nlocal; lb++) {
      PetscReal dv[2] = {0, 0};
      PffCoarsenBlock(p, target, delay, key, p->lgid[lb], p->start[lb], p->start[lb + 1],
                      items + (size_t)omp_get_thread_num() * (size_t)PetscMax(mmax, 1), &removed, dv);
      dl += dv[PFF_PARTICLE_LIQUID];
      da += dv[PFF_PARTICLE_AIR];
    }
    PetscCall(PetscFree(items));
  }
  PetscCheck(n + extra < PETSC_MAX_INT, PETSC_COMM_SELF, PETSC_ERR_SUP,
             "the split would give %" PetscInt64_FMT " particles on one rank", (PetscInt64)n + extra);
  if (nsplit) {
    int32_t         *dst = NULL;
    PetscInt         m = n, nb = 0, ns = 0;
    PetscObjectState state;
    const uint32_t   rm = PffParticleWordSetFlags(0, PFF_PARTICLE_FLAG_REMOVE, PETSC_TRUE);
    PffAdaptItem    *item;
    /* binned on the current raster: the children's bins are their parents', so the sort needs no locate */
    PetscCall(PffGridGetTopologyState(p->grid, &state));
    PetscCheck(p->binned && p->topology == state, PETSC_COMM_SELF, PETSC_ERR_ORDER,
               "PffParticlesAdaptLevels: a split needs the particles binned on the current grid");
    PetscCall(PffGridGetLocalBlocks(p->grid, &nb));
    PetscCall(PffParticlesGetIntWork_Private(p, (size_t)(n + extra) + 1, &dst));
    PetscCall(PffParticlesReserve_Private(p, n + (PetscInt)extra)); /* the store may move */
    PetscReal *x = NULL, *corner = NULL; /* a group's parent positions and its children's slots, cap each */
    PetscInt   cap = 0;
    PetscCall(PetscMalloc1(nsplit, &item));
    for (PetscInt lb = 0; lb < nb; lb++) {
      const PetscInt i0 = p->start[lb], i1 = p->start[lb + 1];
      PetscInt       k0 = ns;
      for (PetscInt i = i0; i < i1; i++) {
        const uint32_t w = p->s.word[i];
        /* the sort leaves out the particles that coarsening removed */
        dst[i]           = (w & rm) ? PFF_SORT_DROP : (int32_t)lb | PFF_SORT_STAYS;
        const PetscInt l = PffParticleWordLevel(w), t = PetscClipInterval((PetscInt)target[i], 0, lmax);
        if (t >= l) continue;
        PetscInt64 cell = 0;
        for (int a = 2; a >= 0; a--) cell = cell * (p->n0 >> l) + CellOfLevel(p, p->s.x[3 * i + a], l, NULL);
        item[ns++] = (PffAdaptItem){(cell * PFF_GRID_MAX_LEVELS + l) * PFF_GRID_MAX_LEVELS + t, 0, p->s.id[i], i};
      }
      qsort(item + k0, (size_t)(ns - k0), sizeof(PffAdaptItem), PffAdaptItemCompare);
      for (PetscInt g0 = k0, g1; g0 < ns; g0 = g1) {
        g1                = PffAdaptGroupEnd(item, g0, ns);
        const PetscInt ip = item[g0].i, l = PffParticleWordLevel(p->s.word[ip]);
        const PetscInt t  = PetscClipInterval((PetscInt)target[ip], 0, lmax);
        const PetscInt np = g1 - g0, nc = (PetscInt)1 << (3 * (l - t));
        float          lo[3];
        PetscReal      lor[3];
        for (int a = 0; a < 3; a++) {
          (void)CellOfLevel(p, p->s.x[3 * ip + a], l, &lo[a]);
          lor[a] = lo[a];
        }
        if (nc * np > cap) { /* grown, not allocated per group */
          PetscCall(PetscFree2(x, corner));
          cap = PetscMax(nc * np, 2 * cap);
          PetscCall(PetscMalloc2(3 * cap, &x, 3 * cap, &corner));
        }
        for (PetscInt g = 0; g < np; g++)
          for (int a = 0; a < 3; a++) x[3 * g + a] = p->s.x[3 * item[g0 + g].i + a];
        PetscCall(AssignSlots(x, np, lor, (PetscReal)((PetscInt)1 << l), l - t, corner));
        for (PetscInt g = g0; g < g1; g++)
          PlaceChildren(p, item[g].i, l - t, t, lo, (float)((PetscInt)1 << l), corner + 3 * nc * (g - g0), lb, &m, dst);
      }
    }
    PetscCall(PetscFree(item));
    PetscCall(PetscFree2(x, corner));
    p->n = m;
    PetscCall(PffParticlesSort_Private(p)); /* bins again (the children are the movers) */
  }

  /* a store that only changed levels keeps its bins; after a split the sort dropped the removed particles */
  if (removed && !nsplit) PetscCall(PffParticlesRemove(p));
  if (!p->binned) PetscCall(PffParticlesBin(p));
  {
    PetscReal v[4] = {vl0, va0, dl, da};
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, v, 4, MPIU_REAL, MPI_SUM, p->comm));
    st.volumeBefore[PFF_PARTICLE_LIQUID] = v[0];
    st.volumeBefore[PFF_PARTICLE_AIR]    = v[1];
    st.volumeAfter[PFF_PARTICLE_LIQUID]  = v[0] + v[2];
    st.volumeAfter[PFF_PARTICLE_AIR]     = v[1] + v[3];
  }
  st.split    = nsplit;
  st.children = nsplit + extra;
  st.marked   = marked;
  st.removed  = removed;
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &st.split, 4, MPIU_INT64, MPI_SUM, p->comm));
  PetscCall(PetscLogEventEnd(PFF_PartAdapt, 0, 0, 0, 0));
  if (stats) *stats = st;
  PetscFunctionReturn(PETSC_SUCCESS);
}
