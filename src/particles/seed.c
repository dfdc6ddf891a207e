/* Seeding (PF-FLIP Sec. 3.2; DESIGN.md Sec. 6): 2 x 2 x 2 particles per cell of every owned block at
   the block's level, each at its sub-cell centre (i + 1/4 + s/2) h, s in {0, 1}, moved by a jitter of
   up to +-jitter/2 of the sub-cell spacing h/2 per axis, so a particle never leaves its sub-cell.

   Ids are global and partition-independent: id = ((gid * n0^3 + c) * 8 + s) with gid the raster
   index of the block, c the cell index at the block's level (x fastest, c < n^3 <= n0^3) and s the
   sub-cell. The jitter is a counter-based hash of (seed, id, purpose, axis), so the particles (and
   the callback's answers) are the same on any number of ranks and threads.

   The cells within -particles_jitter_band cells of an interface between two particle types that lies on sub-cell
   faces are seeded on the lattice. A jittered interface is rough: the raw density of Eq. 7 on the faces between a
   liquid and an air cell varies from column to column, and the light phase above it cannot balance that
   variation, so a pool at rest started at 0.17 m/s (docs/validation.md). The kernel of P2G reaches 1.5 cells, so
   a band of 2 leaves such interface faces a sum over lattice particles only. Where the interface crosses
   sub-cells the particles stay jittered: the jitter is what places it inside them. */
#include <limits.h>

#include "particlesimpl.h"

PetscErrorCode PffParticlesSeed(PffParticles p, PffSeedFn fn, void *ctx)
{
  PetscInt nlocal;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetLocalBlocks(p->grid, &nlocal));
  PetscCall(PffParticlesSeedBlocks(p, fn, ctx, 0, nlocal, NULL));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The 8 lattice particles of cell (i, j, k) of block info that fn accepts, appended to the store (reserved). With
   key != 0 the ids are the lattice ids hashed with key, top bit set (reseeded particles: the lattice id of the cell
   may still be in use). */
static PetscErrorCode SeedCell(PffParticles p, const PffBlockInfo *info, PetscInt i, PetscInt j, PetscInt k,
                               PetscReal jitter, PffSeedFn fn, void *ctx, uint64_t key)
{
  const PetscInt  n     = info->n;
  const PetscReal scale = (PetscReal)((PetscInt)1 << info->level);
  const uint64_t  cell  = (uint64_t)(i + n * (j + n * k));
  const uint64_t  hkey  = key ? PffHash64_Private(key) : 0;
  const PetscInt  c[3]  = {i, j, k};
  PetscReal       lo[3];
  float           top[3];

  PetscFunctionBeginUser;
  for (int a = 0; a < 3; a++) {
    lo[a] = (PetscReal)(info->ijk[a] * p->n0) + (PetscReal)c[a] * scale;
    /* rounding to float must not carry the particle into the next cell (or block, or rank) */
    top[a] = nextafterf((float)(lo[a] + scale), 0);
  }
  for (PetscInt sub = 0; sub < 8; sub++) {
    uint64_t  id = ((uint64_t)info->gid * (uint64_t)(p->n0 * p->n0 * p->n0) + cell) * 8 + (uint64_t)sub;
    PetscReal x[3], v[3] = {0, 0, 0};
    float     g[3];
    PetscInt  type = -1;
    if (key) id = PffHash64_Private(id ^ hkey) | (UINT64_C(1) << 63);
    /* the callback sees the world point of the stored float position */
    for (int a = 0; a < 3; a++) {
      /* no hash for an unjittered lattice (the reference lattice is seeded at every step with bodies):
         0 (u - 1/2) adds a zero either way */
      const PetscReal u = jitter != 0 ? PffRandom01_Private(p->seed, id, PFF_RNG_SEED_JITTER, (uint64_t)a) : 0.5;
      const PetscReal s = 0.25 + 0.5 * (PetscReal)((sub >> a) & 1) + jitter * (u - 0.5) * 0.5;
      g[a]              = PetscMin((float)(lo[a] + s * scale), top[a]);
      x[a]              = p->origin[a] + p->h0 * (PetscReal)g[a];
    }
    PetscCall(fn(x, &type, v, ctx));
    if (type < 0) continue;
    PetscCheck(type < PFF_PARTICLE_NTYPES, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
               "seeding function returned type %" PetscInt_FMT ", not a PffParticleType or -1", type);
    const PetscInt m = p->n++;
    for (int a = 0; a < 3; a++) {
      p->s.x[3 * m + a] = g[a];
      p->s.v[3 * m + a] = (float)v[a];
    }
    p->s.id[m]   = id;
    p->s.word[m] = PffParticleWord(type, info->level, 0);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Work arrays of the band: the types at the lattice sub-cells of a block and a ring of r cells, then their
   minimum and maximum per cell, reduced axis by axis over windows of 2r + 1 cells. */
typedef struct {
  PetscInt     r, cap;
  signed char *type, *lo[2], *hi[2];
  PetscBool   *crossed; /* the inner cells with a crossed sub-cell within r cells */
} PffBand;

#define PFF_BAND_NONE SCHAR_MAX /* a sub-cell outside a walled domain: no type */

/* Minimum (lo) and maximum (hi) over windows of 2r + 1 along axis a of a box of m[0] x m[1] x m[2] cells (x
   fastest) into out; m[a] shrinks by 2r. */
static void BandWindow(PetscInt m[3], int a, PetscInt r, const signed char *lo, const signed char *hi, signed char *olo,
                       signed char *ohi)
{
  const PetscInt stride = a == 0 ? 1 : a == 1 ? m[0] : m[0] * m[1];
  PetscInt       o[3]   = {m[0], m[1], m[2]};

  o[a] -= 2 * r;
  for (PetscInt k = 0; k < o[2]; k++)
    for (PetscInt j = 0; j < o[1]; j++)
      for (PetscInt i = 0; i < o[0]; i++) {
        const PetscInt src = i + m[0] * (j + m[1] * k);
        signed char    l = PFF_BAND_NONE, h = SCHAR_MIN;
        for (PetscInt w = 0; w <= 2 * r; w++) {
          l = PetscMin(l, lo[src + w * stride]);
          h = PetscMax(h, hi[src + w * stride]);
        }
        olo[i + o[0] * (j + o[1] * k)] = l;
        ohi[i + o[0] * (j + o[1] * k)] = h;
      }
  m[a] = o[a];
}

/* The callback's particle type at point c (in cells of the block's level from the block's lower corner): PFF_BAND_NONE
   beyond a walled side and where nothing is seeded (a solid, the liquid model's air), since the band is for the
   interface between two phases of particles */
static PetscErrorCode TypeAt(PffParticles p, const PffBlockInfo *info, const PetscReal c[3], PffSeedFn fn, void *ctx,
                             signed char *t)
{
  const PetscReal scale = (PetscReal)((PetscInt)1 << info->level);
  PetscReal       x[3], v[3];
  PetscInt        type = -1;

  PetscFunctionBeginUser;
  *t = PFF_BAND_NONE;
  for (int a = 0; a < 3; a++) {
    const PetscReal nc = (PetscReal)p->cells[a];
    PetscReal       g  = (PetscReal)(info->ijk[a] * p->n0) + c[a] * scale;
    if (p->periodic[a])
      g = PetscFmodReal(PetscFmodReal(g, nc) + nc, nc);
    else if (!(g >= 0 && g < nc))
      PetscFunctionReturn(PETSC_SUCCESS);
    x[a] = p->origin[a] + p->h0 * g;
  }
  PetscCall(fn(x, &type, v, ctx));
  if (type >= 0) *t = (signed char)type;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* lo, hi of the extended cells (the block and a ring of r cells) into the window of the inner cells, flags[c] =
   whether the window of inner cell c holds two values (lo < hi) */
static void BandReduce(PffBand *b, PetscInt n, PetscBool flags[])
{
  const PetscInt m       = n + 2 * b->r;
  PetscInt       dims[3] = {m, m, m}, cur = 0;

  for (int a = 0; a < 3; a++, cur ^= 1)
    BandWindow(dims, a, b->r, b->lo[cur], b->hi[cur], b->lo[cur ^ 1], b->hi[cur ^ 1]);
  for (PetscInt c = 0; c < n * n * n; c++) flags[c] = (PetscBool)(b->hi[cur][c] > b->lo[cur][c]);
}

/* The least and largest type of the 8 sub-cell centres of each of the m^3 extended cells */
static void CellRanges(const PffBand *b, PetscInt m, signed char lo[], signed char hi[])
{
  const PetscInt ms = 2 * m;

  for (PetscInt c = 0; c < m * m * m; c++) {
    const PetscInt q[3] = {c % m, (c / m) % m, c / (m * m)};
    signed char    l = PFF_BAND_NONE, h = SCHAR_MIN;
    for (PetscInt sub = 0; sub < 8; sub++) {
      const signed char t =
          b->type[(2 * q[0] + (sub & 1)) + ms * ((2 * q[1] + (sub >> 1 & 1)) + ms * (2 * q[2] + (sub >> 2)))];
      if (t == PFF_BAND_NONE) continue;
      l = PetscMin(l, t);
      h = PetscMax(h, t);
    }
    lo[c] = l;
    hi[c] = h;
  }
}

/* band[c] for the n^3 cells of block info: whether the particle type changes within r cells of c, read at the lattice
   sub-cell centres, and no sub-cell within r cells holds a change (the interface lies on sub-cell faces, where the
   lattice places it exactly). Where an interface crosses sub-cells the jitter is what represents its position inside
   them: rt3d_small seeded on the regular lattice (-particles_jitter 0) lags by 0.06 W at t/t0 = 3. */
static PetscErrorCode BandCells(PffParticles p, const PffBlockInfo *info, PffSeedFn fn, void *ctx, PffBand *b,
                                PetscBool band[])
{
  const PetscInt  r = b->r, n = info->n, m = n + 2 * r, ms = 2 * m;
  const PetscReal reach = 0.25 * p->jitter * (1 - 1e-6); /* how far a jittered particle moves, in cells */
  PetscBool       any   = PETSC_FALSE;

  PetscFunctionBeginUser;
  if (m * m * m > b->cap) {
    PetscCall(PetscFree6(b->type, b->lo[0], b->lo[1], b->hi[0], b->hi[1], b->crossed));
    b->cap = m * m * m;
    PetscCall(PetscMalloc6(8 * b->cap, &b->type, b->cap, &b->lo[0], b->cap, &b->lo[1], b->cap, &b->hi[0], b->cap,
                           &b->hi[1], b->cap, &b->crossed));
  }
  for (PetscInt c = 0; c < ms * ms * ms; c++) {
    const PetscInt  q[3] = {c % ms, (c / ms) % ms, c / (ms * ms)};
    const PetscReal x[3] = {0.5 * (PetscReal)(q[0] - 2 * r) + 0.25, 0.5 * (PetscReal)(q[1] - 2 * r) + 0.25,
                            0.5 * (PetscReal)(q[2] - 2 * r) + 0.25};
    PetscCall(TypeAt(p, info, x, fn, ctx, &b->type[c]));
  }
  CellRanges(b, m, b->lo[0], b->hi[0]);
  BandReduce(b, n, band);
  for (PetscInt c = 0; c < n * n * n; c++) any = (PetscBool)(any || band[c]);
  if (!any) PetscFunctionReturn(PETSC_SUCCESS);
  /* the sub-cells a change crosses: a corner of the box their particle may jitter in against the centre's type. Only
     cells within one cell of a change of the centres' types are looked at: a change crossing a sub-cell flips a
     centre there, unless it is thinner than a sub-cell, which the lattice does not see either */
  CellRanges(b, m, b->lo[1], b->hi[1]);
  for (PetscInt e = 0; e < m * m * m; e++) {
    const PetscInt q[3]  = {e % m, (e / m) % m, e / (m * m)};
    signed char    cross = 0, nl = PFF_BAND_NONE, nh = SCHAR_MIN; /* the range of the 27 cells around */
    for (PetscInt w = 0; w < 27; w++) {
      const PetscInt o[3] = {q[0] + w % 3 - 1, q[1] + (w / 3) % 3 - 1, q[2] + w / 9 - 1};
      if (o[0] < 0 || o[1] < 0 || o[2] < 0 || o[0] >= m || o[1] >= m || o[2] >= m) continue;
      nl = PetscMin(nl, b->lo[1][o[0] + m * (o[1] + m * o[2])]);
      nh = PetscMax(nh, b->hi[1][o[0] + m * (o[1] + m * o[2])]);
    }
    for (PetscInt sub = 0; sub < 8 && !cross && nh > nl; sub++) {
      const PetscInt s[3] = {2 * q[0] + (sub & 1), 2 * q[1] + (sub >> 1 & 1), 2 * q[2] + (sub >> 2)};
      signed char    l = b->type[s[0] + ms * (s[1] + ms * s[2])], h = l;
      for (PetscInt corner = 0; corner < 8; corner++) {
        PetscReal   x[3];
        signed char t;
        for (int a = 0; a < 3; a++)
          x[a] = 0.5 * (PetscReal)(s[a] - 2 * r) + 0.25 + ((corner >> a) & 1 ? reach : -reach);
        PetscCall(TypeAt(p, info, x, fn, ctx, &t));
        if (t == PFF_BAND_NONE) continue;
        if (l == PFF_BAND_NONE) l = h = t;
        l = PetscMin(l, t);
        h = PetscMax(h, t);
      }
      cross = (signed char)(l != PFF_BAND_NONE && h > l);
    }
    b->lo[0][e] = 0;
    b->hi[0][e] = cross;
  }
  BandReduce(b, n, b->crossed);
  for (PetscInt c = 0; c < n * n * n; c++) band[c] = (PetscBool)(band[c] && !b->crossed[c]);
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode CheckIdRange(PffParticles p)
{
  const PetscReal n0c = (PetscReal)p->n0 * (PetscReal)p->n0 * (PetscReal)p->n0;

  PetscFunctionBeginUser;
  PetscCheck(n0c * (PetscReal)(p->nb[0] * p->nb[1]) * (PetscReal)p->nb[2] * 8 < 1.8e19, p->comm,
             PETSC_ERR_ARG_OUTOFRANGE, "the raster is too large for 64-bit particle ids");
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffParticlesSeedBlocks(PffParticles p, PffSeedFn fn, void *ctx, PetscInt lb0, PetscInt lb1,
                                      const PetscBool mask[])
{
  PetscInt   nlocal, nmax = 0;
  PetscInt64 ncand = 0;
  PffBand    b     = {p->jitter != 0 ? p->jitterBand : 0, 0, NULL, {NULL, NULL}, {NULL, NULL}, NULL};
  PetscBool *band  = NULL;

  PetscFunctionBeginUser;
  PetscCheck(fn != NULL, p->comm, PETSC_ERR_ARG_NULL, "PffParticlesSeed needs a seeding function");
  PetscCall(CheckIdRange(p));
  PetscCall(PetscLogEventBegin(PFF_PartSeed, 0, 0, 0, 0));
  PetscCall(PffGridGetLocalBlocks(p->grid, &nlocal));
  PetscCheck(lb0 >= 0 && lb0 <= lb1 && lb1 <= nlocal, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
             "PffParticlesSeedBlocks: blocks [%" PetscInt_FMT ", %" PetscInt_FMT ") are not in [0, %" PetscInt_FMT ")",
             lb0, lb1, nlocal);
  for (PetscInt lb = lb0; lb < lb1; lb++) {
    PffBlockInfo info;
    if (mask && !mask[lb]) continue;
    PetscCall(PffGridGetBlockInfo(p->grid, lb, &info));
    ncand += 8 * (PetscInt64)info.n * info.n * info.n;
    nmax = PetscMax(nmax, info.n);
  }
  /* an eighth more than the candidates: particles that migrate in later fill untouched pages, where a
     growth would hold the old and the new store at once (+36 B per particle of peak memory) */
  PetscCall(PffParticlesReserve_Private(p, p->n + (PetscInt)(ncand + ncand / 8)));
  if (b.r > 0) PetscCall(PetscMalloc1(nmax * nmax * nmax, &band));
  for (PetscInt lb = lb0; lb < lb1; lb++) {
    if (mask && !mask[lb]) continue;
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(p->grid, lb, &info));
    if (band) PetscCall(BandCells(p, &info, fn, ctx, &b, band));
    for (PetscInt k = 0, c = 0; k < info.n; k++)
      for (PetscInt j = 0; j < info.n; j++)
        for (PetscInt i = 0; i < info.n; i++, c++)
          PetscCall(SeedCell(p, &info, i, j, k, band && band[c] ? 0 : p->jitter, fn, ctx, 0));
  }
  PetscCall(PetscFree(band));
  PetscCall(PetscFree6(b.type, b.lo[0], b.lo[1], b.hi[0], b.hi[1], b.crossed));
  p->binned = PETSC_FALSE;
  PetscCall(PetscLogEventEnd(PFF_PartSeed, 0, 0, 0, 0));
  PetscCall(PffParticlesBin(p));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffParticlesSeedCells(PffParticles p, PffSeedFn fn, void *ctx, PetscInt ncells, const PetscInt cells[],
                                     uint64_t key)
{
  PetscFunctionBeginUser;
  PetscCheck(fn != NULL, p->comm, PETSC_ERR_ARG_NULL, "PffParticlesSeedCells needs a seeding function");
  PetscCheck(key != 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "PffParticlesSeedCells needs a key other than 0");
  PetscCall(CheckIdRange(p));
  PetscCall(PetscLogEventBegin(PFF_PartSeed, 0, 0, 0, 0));
  PetscCall(PffParticlesReserve_Private(p, p->n + 8 * ncells));
  for (PetscInt q = 0; q < ncells; q++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(p->grid, cells[2 * q], &info));
    const PetscInt c = cells[2 * q + 1], n = info.n;
    PetscCheck(c >= 0 && c < n * n * n, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
               "PffParticlesSeedCells: cell %" PetscInt_FMT " is not in a block of %" PetscInt_FMT "^3", c, n);
    PetscCall(SeedCell(p, &info, c % n, (c / n) % n, c / (n * n), p->jitter, fn, ctx, key));
  }
  p->binned = PETSC_FALSE;
  PetscCall(PetscLogEventEnd(PFF_PartSeed, 0, 0, 0, 0));
  PetscCall(PffParticlesBin(p));
  PetscFunctionReturn(PETSC_SUCCESS);
}
