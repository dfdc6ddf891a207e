/* Private state of PffParticles; only src/particles/ includes this. */
#pragma once

#include <pff.h>

#define PFF_PARTICLES_JITTER_DEFAULT 1.0
#define PFF_PARTICLES_JITTER_BAND_DEFAULT 2
#define PFF_PARTICLES_JITTER_BAND_MAX 8
#define PFF_PARTICLES_SEED_DEFAULT 0
#define PFF_PARTICLES_SUBSTEP_CFL_DEFAULT 1.0
#define PFF_PARTICLES_IO_CHUNK_DEFAULT (1 << 20)
#define PFF_PARTICLES_MAX_SUBSTEPS 16

/* Purposes of the counter-based RNG (the third key besides the seed and the particle id). */
enum { PFF_RNG_SEED_JITTER = 1, PFF_RNG_SPLIT = 2, PFF_RNG_COARSEN = 3, PFF_RNG_COARSEN_GROUP = 4 };

/* The particle fields, declared once: X(name, C type, values per particle, files). Growth, compaction, the
   binning's lane sort, the migration record and, for fields whose last entry is FILE, the frames and
   checkpoints (a dataset /particles/<name> of that type, PffParticlesGetFileFields) are generated from this
   list, so a new per-particle field (a spray radius, a lifetime) is one line here; what a field means (Add,
   GetArrays) is written where it is used. OWN fields are written by the files' own code: x (world
   positions), v (widened in checkpoints) and word (unpacked into the type, level and flags datasets). Every
   field is a multiple of 4 bytes per particle (the sort moves 4-byte lanes). x: position in grid units
   (world - origin) / h0; word: PffParticleWord(type, level, flags). */
#define PFF_PARTICLE_FIELDS(X)                                                                                         \
  X(x, float, 3, OWN) X(v, float, 3, OWN) X(id, uint64_t, 1, FILE) X(word, uint32_t, 1, OWN)

#define PFF_PARTICLE_FIELD_DECLARE(name, type, k, f) type *name;
#define PFF_PARTICLE_FIELD_BYTES(name, type, k, f) +(k) * sizeof(type)

/* Bytes per particle of the store (36), which is also the migration record. */
#define PFF_PARTICLE_BYTES (0 PFF_PARTICLE_FIELDS(PFF_PARTICLE_FIELD_BYTES))

/* The structure-of-arrays store: n particles of capacity cap. */
typedef struct {
  PFF_PARTICLE_FIELDS(PFF_PARTICLE_FIELD_DECLARE)
} PffParticleSoA;

/* Scratch slots of the hot paths, kept between calls and grown by half when too small, so that P2G,
   G2P, advection, migration and the sort allocate nothing once warm. One slot per user; the users of
   a slot never run nested. */
typedef enum {
  PFF_SCRATCH_SAMPLER,
  PFF_SCRATCH_ADVECT,
  PFF_SCRATCH_SORT,
  PFF_SCRATCH_P2G,
  PFF_SCRATCH_MIGRATE,
  PFF_SCRATCH_MIGRATE_RECORDS,
  PFF_SCRATCH_SORT_MOVERS,
  PFF_SCRATCH_SOLID,
  PFF_SCRATCH_VOLUME,
  PFF_SCRATCH_N
} PffScratchSlot;

struct _n_PffParticles {
  PffGrid     grid; /* borrowed */
  MPI_Comm    comm; /* the grid's communicator, borrowed */
  PetscMPIInt rank, size;

  /* options */
  PetscReal jitter, substepCfl;
  PetscInt  jitterBand; /* cells within this many of a change of the seeding type sit on the lattice */
  PetscInt  ioChunk;    /* particles per collective transfer of frames and checkpoints */
  uint64_t  seed;

  /* store */
  PetscInt       n, cap;
  PffParticleSoA s;

  /* bins: particles of local block lb are [start[lb], start[lb + 1]) */
  PetscBool        binned;
  PetscObjectState topology; /* the grid's topology state when the bins were built (PffGridGetTopologyState) */
  PetscInt         nlocal, *start, *lgid;
  PetscInt        *local; /* [nblocks] local index of global block or -1; rebuilt by every Bin */
  PetscInt         nblocksCache;

  /* grid geometry, cached at Create (fixed for the grid's life) */
  PetscInt  n0, log2n0, nlevels, nb[3], cells[3];
  PetscReal origin[3], h0;
  PetscBool periodic[3];

  /* scratch, grown on demand and kept: 4 B per particle each at most (the binning's destination
     index and its lane buffer), plus the tiles of PffSampler and P2G */
  int32_t *i32work;
  size_t   ni32work;
  float   *fwork;
  size_t   nfwork;
  void    *scratch[PFF_SCRATCH_N];
  size_t   nscratch[PFF_SCRATCH_N];
};

/* splitmix64 finaliser: a counter-based hash, the same on every rank and thread. */
static inline uint64_t PffHash64_Private(uint64_t z)
{
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

/* Uniform in [0, 1) keyed by (seed, id, purpose, counter). */
static inline PetscReal PffRandom01_Private(uint64_t seed, uint64_t id, uint64_t purpose, uint64_t counter)
{
  const uint64_t h = PffHash64_Private(PffHash64_Private(PffHash64_Private(seed) ^ id) ^ (purpose << 32 | counter));
  return (PetscReal)(h >> 11) / 9007199254740992.0;
}

/* Global block of grid position g (grid units; periodic axes wrapped), as PffGridLocate computes it for
   the world point origin + h0 g; -1 outside the domain; the level map decides activity. */
static inline PetscInt PffParticlesLocateReal_Private(PffParticles p, const PetscReal g[3], const PetscInt level[])
{
  PetscInt b[3];
  for (int d = 0; d < 3; d++) {
    const PetscReal nc = (PetscReal)p->cells[d];
    PetscReal       s  = g[d];
    if (p->periodic[d] && !(s >= 0 && s < nc)) {
      s = PetscFmodReal(s, nc);
      if (s < 0) s += nc;
      if (s >= nc) s = 0;
    }
    if (!(s >= 0 && s < nc)) return -1;
    b[d] = ((PetscInt)s) >> p->log2n0;
  }
  const PetscInt gid = b[0] + p->nb[0] * (b[1] + p->nb[1] * b[2]);
  return level[gid] >= 0 ? gid : -1;
}

/* The same for a stored position. */
static inline PetscInt PffParticlesLocate_Private(PffParticles p, const float g[3], const PetscInt level[])
{
  const PetscReal r[3] = {g[0], g[1], g[2]};
  return PffParticlesLocateReal_Private(p, r, level);
}

/* Moves particle src to slot dst (compaction after removals or sends). */
static inline void PffParticlesMove_Private(PffParticles p, PetscInt dst, PetscInt src)
{
#define PFF_PARTICLE_FIELD_MOVE(name, type, k, f)                                                                      \
  for (int c = 0; c < (k); c++) p->s.name[(k)*dst + c] = p->s.name[(k)*src + c];
  PFF_PARTICLE_FIELDS(PFF_PARTICLE_FIELD_MOVE)
#undef PFF_PARTICLE_FIELD_MOVE
}

/* Moves the particles [src, src + count) to [dst, dst + count), dst <= src (runs of a compaction). */
static inline void PffParticlesMoveRange_Private(PffParticles p, PetscInt dst, PetscInt src, PetscInt count)
{
#define PFF_PARTICLE_FIELD_MOVE_RANGE(name, type, k, f)                                                                \
  memmove(&p->s.name[(k)*dst], &p->s.name[(k)*src], (size_t)(k) * sizeof(type) * (size_t)count);
  PFF_PARTICLE_FIELDS(PFF_PARTICLE_FIELD_MOVE_RANGE)
#undef PFF_PARTICLE_FIELD_MOVE_RANGE
}

/* Packs particle i into (or unpacks it from) a migration record of PFF_PARTICLE_BYTES bytes. */
static inline void PffParticlesPack_Private(const PffParticleSoA *s, PetscInt i, char *rec)
{
#define PFF_PARTICLE_FIELD_PACK(name, type, k, f)                                                                      \
  memcpy(rec, &s->name[(k)*i], (k) * sizeof(type));                                                                    \
  rec += (k) * sizeof(type);
  PFF_PARTICLE_FIELDS(PFF_PARTICLE_FIELD_PACK)
#undef PFF_PARTICLE_FIELD_PACK
}

static inline void PffParticlesUnpack_Private(PffParticleSoA *s, PetscInt i, const char *rec)
{
#define PFF_PARTICLE_FIELD_UNPACK(name, type, k, f)                                                                    \
  memcpy(&s->name[(k)*i], rec, (k) * sizeof(type));                                                                    \
  rec += (k) * sizeof(type);
  PFF_PARTICLE_FIELDS(PFF_PARTICLE_FIELD_UNPACK)
#undef PFF_PARTICLE_FIELD_UNPACK
}

PETSC_INTERN PetscErrorCode PffParticlesReserve_Private(PffParticles, PetscInt);
/* An int32 scratch of at least n values, kept between calls like the float scratch below. */
PETSC_INTERN PetscErrorCode PffParticlesGetIntWork_Private(PffParticles, size_t n, int32_t **);
/* Slot `slot` carved into n arrays of bytes[i] bytes each (64-byte aligned), returned in ptrs[i];
   contents undefined. */
PETSC_INTERN PetscErrorCode PffParticlesGetScratch_Private(PffParticles, PffScratchSlot slot, PetscInt n,
                                                           const size_t bytes[], void *ptrs[]);
/* The same, keeping the first keep values. */
PETSC_INTERN PetscErrorCode PffParticlesGrowIntWork_Private(PffParticles, size_t n, PetscInt keep, int32_t **);
/* A float scratch of at least n values, kept between calls (grown by half): no allocation, and no
   first-touch page faults, per step. */
PETSC_INTERN PetscErrorCode PffParticlesGetFloatWork_Private(PffParticles, size_t n, float **);
/* The lower wall's clamp, in finest cells (Migrate's box test keeps particles below it out of its fast path). */
#define PFF_PARTICLE_WALL_LO 1e-6f

/* Wraps periodic axes and clamps walled axes of grid position g in place; returns what it did. Periodic axes: the
   image in [0, cells), wrapped like PffGridLocate. Walled axes: clamped a millionth
   of a finest cell inside at the lower wall and one float step inside at the upper one, so the point
   lies strictly within the domain. Inline: Migrate calls it for every particle, and took 10 % less time inlined
   (rt3d W = 64, docs/benchmarks.md). */
static inline void PffParticlesWrapClamp_Private(PffParticles p, float g[3], PetscBool *wrapped, PetscBool *clamped)
{
  *wrapped = *clamped = PETSC_FALSE;
  for (int d = 0; d < 3; d++) {
    const float nc = (float)p->cells[d];
    if (p->periodic[d]) {
      if (g[d] >= 0 && g[d] < nc) continue;
      float t = fmodf(g[d], nc); /* exact */
      if (t < 0) t += nc;        /* may round up to nc */
      if (!(t < nc)) t = 0;
      g[d]     = t;
      *wrapped = PETSC_TRUE;
    } else {
      /* nextafterf(nc, 0) for the positive normal nc, without a libm call per particle and axis */
      uint32_t bits;
      float    hi;
      memcpy(&bits, &nc, sizeof(bits));
      bits--;
      memcpy(&hi, &bits, sizeof(hi));
      const float lo = PFF_PARTICLE_WALL_LO;
      if (!(g[d] >= lo)) {
        g[d]     = lo;
        *clamped = PETSC_TRUE;
      } else if (g[d] > hi) {
        g[d]     = hi;
        *clamped = PETSC_TRUE;
      }
    }
  }
}

PETSC_INTERN PetscErrorCode PffParticlesCheckBinned_Private(PffParticles, const char[]);
/* The binning in two parts: the owned-block tables (p->local, p->lgid, p->nlocal), and the stable sort
   by the local block of each particle that the int32 scratch holds (Migrate knows them already). */
PETSC_INTERN PetscErrorCode PffParticlesUpdateBlocks_Private(PffParticles, PetscBool *changed);
/* Flag in the sort's input: the particle is still in the block of the bin it sat in, so the stayers
   keep their order and the sort can move them in place (bin.c). */
#define PFF_SORT_STAYS ((int32_t)1 << 30)
/* a particle the sort removes (Migrate's leavers, packed and sent before the sort) */
#define PFF_SORT_DROP ((int32_t)-1)
PETSC_INTERN PetscErrorCode PffParticlesSort_Private(PffParticles);

/* Block-batched sampling of face channels (G2P and advection; sample.c). A table built once per call
   holds, per local block, its level, size and raster place and the data of each face component of up
   to two channels, so that the per-point work needs no lookup, no check and no log call and runs in
   threads. */
typedef struct {
  PetscInt n, level, ijk[3];
  unsigned hole;           /* bit 2a (2a + 1): a wall or an inactive block lies on the lower (upper) side along axis a,
                              where the grid's general path clamps the stencil and a plain tile stencil must not go */
  PetscInt holes;          /* the grid's mask of neighbour regions across a wall or facing an inactive block */
  int32_t  clamp[27];      /* per crossing pattern of a stencil (region index of its sides), the sides it clamps:
                              bit 2a (2a + 1) the lower (upper) side along axis a (PffStencilClamped) */
  const float *data[2][3]; /* channel k, face component d: the block's own n^3 cells */
  const float *tile[2][3]; /* the same with gw ghost layers, (n + 2 gw)^3 from cell -gw: NULL in the sampler's
                              table, set in the thread's copy by PffSamplerBlockTiles_Private */
} PffSampleBlock;

typedef struct {
  PffGrid         grid;
  PetscInt        ch[2], nch, gw, ncomp; /* ncomp: 3 for face channels, 1 for cell channels */
  PffSampleBlock *blocks;                /* [nlocal] */
  const PffView **views;                 /* [6 nlocal]: channel k, component d of block lb at 6 lb + 3 k + d */
  float          *tiles;                 /* per-thread tile buffers (the particles' float scratch, borrowed) */
  size_t          tstride;               /* floats per thread */
} PffSampler;

/* The face lattices of a chunk of at most PFF_CHUNK particles of one block (P2G and G2P): per axis the
   lattice of the faces normal to it (integer positions, c) and of the faces across it (half-integer, h):
   lower index and fraction. For a particle in the block the indices lie in [0, n - 1] and [-1, n - 1], so
   every 2 x 2 x 2 stencil lies in the block's tile of (n + 2)^3 from cell -1; they are clamped there so
   that a rounding at the block's edge cannot reach beyond it. Computed in float in loops without
   dependences, which the compiler vectorises. */
#define PFF_CHUNK 64
typedef struct {
  int32_t ic[3][PFF_CHUNK], ih[3][PFF_CHUNK];
  float   tc[3][PFF_CHUNK], th[3][PFF_CHUNK];
} PffChunkLattice;

/* x: the chunk's first position (grid units); lo: the block's lower corner (grid units); ih: 1 / its
   cell size. */
/* floorf for |v| < 2^31 by truncation and a correction, which the vectoriser takes (floorf it does not) */
static inline float PffFloorf_Private(float v)
{
  const float t = (float)(int32_t)v;
  return t > v ? t - 1 : t;
}

static inline void PffChunkAxis_Private(float g, float lo, float ih, int32_t n, int32_t *ic, float *tc, int32_t *ih2,
                                        float *th)
{
  /* exact in float: lo is an integer and g - lo lies in [0, g]; ih is a power of two */
  const float sp = (g - lo) * ih, fc = PffFloorf_Private(sp), fh = PffFloorf_Private(sp - 0.5f);
  *ic  = PetscMin(PetscMax((int32_t)fc, 0), n - 1);
  *tc  = sp - fc;
  *ih2 = PetscMin(PetscMax((int32_t)fh, -1), n - 1);
  *th  = sp - 0.5f - fh;
}

static inline void PffChunkLattice_Private(const float *x, PetscInt m, const float lo[3], float ih, PetscInt n,
                                           PffChunkLattice *L)
{
  /* the axes written out: the three loads of x form one interleaved group the vectoriser handles */
  for (PetscInt j = 0; j < m; j++) {
    PffChunkAxis_Private(x[3 * j], lo[0], ih, (int32_t)n, &L->ic[0][j], &L->tc[0][j], &L->ih[0][j], &L->th[0][j]);
    PffChunkAxis_Private(x[3 * j + 1], lo[1], ih, (int32_t)n, &L->ic[1][j], &L->tc[1][j], &L->ih[1][j], &L->th[1][j]);
    PffChunkAxis_Private(x[3 * j + 2], lo[2], ih, (int32_t)n, &L->ic[2][j], &L->tc[2][j], &L->ih[2][j], &L->th[2][j]);
  }
}

/* The grid's clamping at walls and holes (PffStencilClamped) on a chunk's lattice of one component: lower index c and
   fraction t per axis into cc and tc; normal is the axis with the normal lattice (whose wall face, index n, is read,
   not clamped), -1 for cell values. b->clamp gives the sides to clamp for the stencil's crossing pattern. A clamped
   axis reads one plane with weight 1 and the other with weight 0, so the tile's values across walls and holes never
   count. */
static inline void PffChunkClamp_Private(const PffSampleBlock *b, PetscInt m, int normal, const int32_t *const c[3],
                                         const float *const t[3], int32_t cc[3][PFF_CHUNK], float tc[3][PFF_CHUNK])
{
  const int32_t n = (int32_t)b->n;
  for (PetscInt j = 0; j < m; j++) {
    const int32_t ci[3] = {c[0][j], c[1][j], c[2][j]};
    int32_t       p     = 0;
    for (int a = 0, w = 1; a < 3; a++, w *= 3) p += w * (ci[a] < 0 ? 0 : (ci[a] + 1 >= n ? 2 : 1));
    const int32_t mask = b->clamp[p];
    for (int a = 0; a < 3; a++) {
      const int32_t lower = (mask >> (2 * a)) & (ci[a] < 0);
      const int32_t upper = (mask >> (2 * a + 1)) & (ci[a] + 1 >= n) & !(a == normal && ci[a] + 1 == n);
      cc[a][j]            = lower ? 0 : (upper ? PetscMin(ci[a], n - 1) : ci[a]);
      tc[a][j]            = (lower | upper) ? 0.0f : t[a][j];
    }
  }
}

/* PffChunkClamp_Private where the block has walls or holes: c and t then point to the clamped cc and tc. */
static inline __attribute__((always_inline)) void
PffChunkClampHoles_Private(const PffSampleBlock *b, PetscInt m, int normal, const int32_t *c[3], const float *t[3],
                           int32_t cc[3][PFF_CHUNK], float tc[3][PFF_CHUNK])
{
  if (!b->hole) return;
  PffChunkClamp_Private(b, m, normal, c, t, cc, tc);
  for (int a = 0; a < 3; a++) {
    c[a] = cc[a];
    t[a] = tc[a];
  }
}

/* Trilinear interpolation of the 2 x 2 x 2 values at t + o + st[q] (st: the corner offsets in a tile)
   with fractions (x1, y1, z1), axis by axis; inlined into loops the compiler vectorises. */
static inline float PffTrilinear_Private(const float *restrict t, int32_t o, const int32_t st[8], float x1, float y1,
                                         float z1)
{
  const float x0 = 1 - x1, y0 = 1 - y1, z0 = 1 - z1;
  return z0 * (y0 * (x0 * t[o + st[0]] + x1 * t[o + st[1]]) + y1 * (x0 * t[o + st[2]] + x1 * t[o + st[3]])) +
         z1 * (y0 * (x0 * t[o + st[4]] + x1 * t[o + st[5]]) + y1 * (x0 * t[o + st[6]] + x1 * t[o + st[7]]));
}

#if defined(__AVX512F__)
#include <immintrin.h>
/* Sixteen floats (particles j .. j + 15 of a chunk). */
typedef float PffV16 __attribute__((vector_size(64)));

/* t[idx] and t[idx + 1] for 16 offsets idx: one 64-bit gather brings both faces of an x pair of corners, so a
   trilinear stencil needs 4 gathered elements per particle instead of 8; gathers bound the interpolating kernels. */
static inline __attribute__((always_inline)) void PffGatherXPair16_Private(const float *t, __m512i idx, PffV16 *a,
                                                                           PffV16 *b)
{
  const __m512i g0 = _mm512_i32gather_epi64(_mm512_castsi512_si256(idx), (const void *)t, 4);
  const __m512i g1 = _mm512_i32gather_epi64(_mm512_extracti64x4_epi64(idx, 1), (const void *)t, 4);
  const __m512i lo =
      _mm512_inserti64x4(_mm512_castsi256_si512(_mm512_cvtepi64_epi32(g0)), _mm512_cvtepi64_epi32(g1), 1);
  const __m512i hi = _mm512_inserti64x4(_mm512_castsi256_si512(_mm512_cvtepi64_epi32(_mm512_srli_epi64(g0, 32))),
                                        _mm512_cvtepi64_epi32(_mm512_srli_epi64(g1, 32)), 1);
  *a               = (PffV16)_mm512_castsi512_ps(lo);
  *b               = (PffV16)_mm512_castsi512_ps(hi);
}

/* PffTrilinear_Private for 16 particles: o their offsets in the tile, (x1, y1, z1) their fractions; the same
   operations in the same order, so the same result to the bit. */
static inline __attribute__((always_inline)) PffV16 PffTrilinear16_Private(const float *t, const int32_t *o,
                                                                           const int32_t st[8], const float *x1p,
                                                                           const float *y1p, const float *z1p)
{
  const __m512i base = _mm512_loadu_si512((const void *)o);
  PffV16        c[8], x1, y1, z1;
  for (int q = 0; q < 8; q += 2)
    PffGatherXPair16_Private(t, _mm512_add_epi32(base, _mm512_set1_epi32(st[q])), &c[q], &c[q + 1]);
  memcpy(&x1, x1p, sizeof x1);
  memcpy(&y1, y1p, sizeof y1);
  memcpy(&z1, z1p, sizeof z1);
  const PffV16 x0 = 1 - x1, y0 = 1 - y1, z0 = 1 - z1;
  return z0 * (y0 * (x0 * c[0] + x1 * c[1]) + y1 * (x0 * c[2] + x1 * c[3])) +
         z1 * (y0 * (x0 * c[4] + x1 * c[5]) + y1 * (x0 * c[6] + x1 * c[7]));
}
#endif

/* PffTrilinear_Private of the first 16 k <= m points of a chunk into out (o: offsets in the tile, t*: fractions);
   returns 16 k, the points done (0 without AVX-512). */
static inline PetscInt PffTrilinearChunk16_Private(const float *t, const int32_t *o, const int32_t st[8],
                                                   const float *tx, const float *ty, const float *tz, PetscInt m,
                                                   float *out)
{
  PetscInt j = 0;
#if defined(__AVX512F__)
  for (; j + 16 <= m; j += 16) {
    const PffV16 r = PffTrilinear16_Private(t, o + j, st, tx + j, ty + j, tz + j);
    memcpy(out + j, &r, sizeof r);
  }
#else
  (void)t, (void)o, (void)st, (void)tx, (void)ty, (void)tz, (void)m, (void)out;
#endif
  return j;
}

/* All m points of a chunk: the rest after PffTrilinearChunk16_Private (all of them without AVX-512) in a loop the
   compiler vectorises. G2P keeps its own loop for the rest, which interpolates u and du together: a variant of G2P
   with two calls of this, not kept, was 12-17 % slower (pff-bench-particles, 2026-12-05). */
static inline __attribute__((always_inline)) void PffTrilinearChunk_Private(const float *t, const int32_t *o,
                                                                            const int32_t st[8], const float *tx,
                                                                            const float *ty, const float *tz,
                                                                            PetscInt m, float *out)
{
  for (PetscInt j = PffTrilinearChunk16_Private(t, o, st, tx, ty, tz, m, out); j < m; j++)
    out[j] = PffTrilinear_Private(t, o[j], st, tx[j], ty[j], tz[j]);
}

/* Offsets in a tile of mm^3 values with gw ghost layers of the stencils whose lower corners are the cells c. */
static inline __attribute__((always_inline)) void
PffChunkOffsets_Private(int32_t mm, int32_t gw, const int32_t *const c[3], PetscInt m, int32_t *restrict o)
{
  const int32_t *restrict cx = c[0], *restrict cy = c[1], *restrict cz = c[2];
  for (PetscInt j = 0; j < m; j++) o[j] = (cx[j] + gw) + mm * ((cy[j] + gw) + mm * (cz[j] + gw));
}

/* Corner offsets of a 2 x 2 x 2 stencil in a tile of m^3 values. */
static inline void PffTileCorners_Private(int32_t m, int32_t st[8])
{
  for (int q = 0; q < 8; q++) st[q] = (q & 1) + m * (((q >> 1) & 1) + m * ((q >> 2) & 1));
}

/* A block's lower corner in grid units (exact in float) and the inverse of its cell size. */
static inline void PffBlockCorner_Private(PetscInt n0, const PetscInt ijk[3], PetscInt level, float lo[3], float *ih)
{
  for (int a = 0; a < 3; a++) lo[a] = (float)(ijk[a] * n0);
  *ih = 1.0f / (float)((PetscInt)1 << level);
}

/* The lattice of face component d: per axis the normal lattice on axis d, the half one on the others. */
static inline void PffChunkLatticeOf_Private(const PffChunkLattice *L, int d, const int32_t *c[3], const float *t[3])
{
  for (int a = 0; a < 3; a++) {
    c[a] = a == d ? L->ic[a] : L->ih[a];
    t[a] = a == d ? L->tc[a] : L->th[a];
  }
}

/* The scratch of a splat over the local blocks (slot): per block its info, nviews view and data pointers (block lb's at
   [nviews lb, nviews (lb + 1))), and the colour order's two arrays, valid until the slot's next use. */
PETSC_INTERN PetscErrorCode PffParticlesSplatScratch_Private(PffParticles, PffScratchSlot slot, PetscInt nviews,
                                                             PffBlockInfo **info, const PffView ***views, float ***data,
                                                             PetscInt **order, PetscInt **colour);
/* The local blocks in splat order: colour[lb] (0..26) from the parity of the raster coordinates (on a periodic axis
   with an odd block count the last block gets colour 2, since it touches block 0), order[] the blocks sorted by
   colour (stable), cstart[c] .. cstart[c + 1] - 1 the range of colour c in it. Two blocks of one colour never write
   the same cell or face of a tile with one ghost layer. */
PETSC_INTERN void PffParticlesColourOrder_Private(PffParticles, const PffBlockInfo info[], PetscInt colour[],
                                                  PetscInt order[], PetscInt cstart[28]);
/* The ghost shell (the gw layers beyond the block) of a block tile of (n + 2 gw)^3 floats from cell -gw, copied
   from the block's views (add false) or added to them (add true; zeros skipped). */
PETSC_INTERN void PffTileShell_Private(const PffView *views, PetscInt n, PetscInt gw, float *tile, PetscBool add);
/* A sampler of nch channels whose tiles hold gw ghost layers (the channels' halos must be as wide). */
PETSC_INTERN PetscErrorCode PffSamplerCreate_Private(PffParticles, PetscInt nch, const PetscInt ch[], PetscInt gw,
                                                     PffSampler *);
PETSC_INTERN PetscErrorCode PffSamplerDestroy_Private(PffSampler *);
/* The calling thread's copy of block lb's table entry, with its tiles built in the thread's buffer (valid
   until the thread's next call); PETSC_FALSE, and nothing built, when the block holds no particle. */
/* Fills the thread's tiles of block lb for the channels k whose bit is set in need (the others keep their place in the
   thread's buffer, unfilled); false when the block has no particles. */
PETSC_INTERN PetscBool PffSamplerBlockTiles_Private(PffParticles, const PffSampler *, PetscInt lb, unsigned need,
                                                    PffSampleBlock *);

/* Position of grid point g (grid units) in cell units of local block lb's level, from its lower corner,
   as PffGridInterpolateFrom() computes it for the world point origin + h0 g: on a periodic axis the
   image nearest to the block's centre. */
static inline void PffSamplerLocal_Private(const PffParticles p, const PffSampleBlock *b, const PetscReal g[3],
                                           PetscReal lp[3])
{
  const PetscReal inv = 1.0 / (PetscReal)((PetscInt)1 << b->level);
  for (int d = 0; d < 3; d++) {
    PetscReal sp = g[d];
    if (p->periodic[d]) { /* the shift floor((sp - centre) / L + 0.5) L, without its division */
      const PetscReal L = (PetscReal)p->cells[d], centre = (PetscReal)(b->ijk[d] * p->n0) + 0.5 * (PetscReal)p->n0;
      if (sp - centre >= 0.5 * L)
        sp -= L;
      else if (sp - centre < -0.5 * L)
        sp += L;
    }
    lp[d] = (sp - (PetscReal)(b->ijk[d] * p->n0)) * inv;
  }
}

/* Whether a 2 x 2 x 2 stencil from lower index i0 keeps off every side of block b with a wall or hole, so that the
   tile holds, value for value, what the grid's general path reads. */
static inline PetscBool PffSampleStencilClear_Private(const PffSampleBlock *b, const PetscInt i0[3])
{
  for (int a = 0; a < 3; a++)
    if ((((b->hole >> (2 * a)) & 1) && i0[a] < 0) || (((b->hole >> (2 * a + 1)) & 1) && i0[a] + 1 >= b->n))
      return PETSC_FALSE;
  return PETSC_TRUE;
}

/* The grid's general path (PffStencilClamped: clamped at walls and holes, the same weights and summation order as
   PffGridInterpolate) on a tile of block b with gw ghost layers, for lattice offsets o; PETSC_FALSE, and nothing
   computed, when the stencil leaves the tile. */
static inline PetscBool PffSamplerTileClamped_Private(const PffSampleBlock *b, PetscInt gw, const float *tile,
                                                      const PetscReal o[3], const PetscReal lp[3], PetscReal *val)
{
  const PetscInt n = b->n, m = n + 2 * gw;
  PetscInt       i0[3], i1[3];
  PetscReal      t[3], v = 0;

  (void)PffStencilClamped(n, b->holes, o, lp, i0, i1, t);
  for (int a = 0; a < 3; a++)
    if (i0[a] < -gw || i1[a] >= n + gw) return PETSC_FALSE;
  for (int q = 0; q < 8; q++) {
    const PetscInt  ii = (q & 1) ? i1[0] : i0[0], jj = (q & 2) ? i1[1] : i0[1], kk = (q & 4) ? i1[2] : i0[2];
    const PetscReal w = ((q & 1) ? t[0] : 1 - t[0]) * ((q & 2) ? t[1] : 1 - t[1]) * ((q & 4) ? t[2] : 1 - t[2]);
    if (w != 0) v += w * (PetscReal)tile[(ii + gw) + m * ((jj + gw) + m * (kk + gw))];
  }
  *val = v;
  return PETSC_TRUE;
}

/* Face component d of channels k0 and (if nk = 2) k0 + 1 at lp in local block lb, with one set of
   trilinear weights (lower lattice index i0 and fraction t per axis): the block's own cells when the
   stencil lies inside them, the block's tile when it reaches no farther than its gw ghost layers and the
   block has one and it keeps off the block's wall and hole sides, else the grid's general path: on the tile
   (PffSamplerTileClamped_Private) when the clamped stencil lies in it, else PffGridInterpolateInBlock(). The fast paths
   interpolate axis by axis and so agree with the general path to rounding. */
static inline void PffSamplerFaceAt_Private(const PffSampler *s, const PffSampleBlock *b, PetscInt lb, PetscInt k0,
                                            PetscInt nk, PetscInt d, const PetscInt i0[3], const PetscReal t[3],
                                            const PetscReal lp[3], PetscReal val[2])
{
  const PetscInt n = b->n;
  PetscInt       o, m = n;
  const float   *base[2] = {NULL, NULL};

  if (i0[0] >= 0 && i0[0] + 1 < n && i0[1] >= 0 && i0[1] + 1 < n && i0[2] >= 0 && i0[2] + 1 < n) {
    o = i0[0] + n * (i0[1] + n * i0[2]);
    for (PetscInt k = 0; k < nk; k++) base[k] = b->data[k0 + k][d];
  } else if (b->tile[k0][d] && i0[0] >= -s->gw && i0[0] + 1 < n + s->gw && i0[1] >= -s->gw && i0[1] + 1 < n + s->gw &&
             i0[2] >= -s->gw && i0[2] + 1 < n + s->gw && PffSampleStencilClear_Private(b, i0)) {
    const PetscInt gw = s->gw;
    m                 = n + 2 * gw;
    o                 = (i0[0] + gw) + m * ((i0[1] + gw) + m * (i0[2] + gw));
    for (PetscInt k = 0; k < nk; k++) base[k] = b->tile[k0 + k][d];
  } else {
    const PetscReal off[3] = {d == 0 ? 0.0 : 0.5, d == 1 ? 0.0 : 0.5, d == 2 ? 0.0 : 0.5};
    for (PetscInt k = 0; k < nk; k++)
      if (!b->tile[k0 + k][d] || !PffSamplerTileClamped_Private(b, s->gw, b->tile[k0 + k][d], off, lp, &val[k]))
        val[k] = PffGridInterpolateInBlock(s->grid, s->ch[k0 + k], lb, d, lp);
    return;
  }
  const PetscReal wx0 = 1 - t[0], wy0 = 1 - t[1], wz0 = 1 - t[2];
  for (PetscInt k = 0; k < nk; k++) {
    const float    *a   = base[k] + o;
    const PetscReal c00 = wx0 * a[0] + t[0] * a[1], c10 = wx0 * a[m] + t[0] * a[m + 1];
    const PetscReal c01 = wx0 * a[m * m] + t[0] * a[m * m + 1], c11 = wx0 * a[m * m + m] + t[0] * a[m * m + m + 1];
    val[k] = wz0 * (wy0 * c00 + t[1] * c10) + t[2] * (wy0 * c01 + t[1] * c11);
  }
}

/* All three face components of channel k0 (and k0 + 1 if nk = 2) at lp: val[k][d]. The two lattices
   per axis (faces normal to it and across it) are located once. */
static inline void PffSamplerVector_Private(const PffSampler *s, const PffSampleBlock *b, PetscInt lb, PetscInt k0,
                                            PetscInt nk, const PetscReal lp[3], PetscReal val[2][3])
{
  PetscInt  ic[3], ih[3];
  PetscReal tc[3], th[3];
  for (int e = 0; e < 3; e++) {
    const PetscReal xh = lp[e] - 0.5;
    ic[e]              = (PetscInt)PetscFloorReal(lp[e]);
    tc[e]              = lp[e] - (PetscReal)ic[e];
    ih[e]              = (PetscInt)PetscFloorReal(xh);
    th[e]              = xh - (PetscReal)ih[e];
  }
  for (PetscInt d = 0; d < 3; d++) {
    const PetscInt  i0[3] = {d == 0 ? ic[0] : ih[0], d == 1 ? ic[1] : ih[1], d == 2 ? ic[2] : ih[2]};
     const PetscReal t[3] = {d == 0 ? tc[0] : th[0], d == 1 ? tc[1] : th[1], d == 2 ? tc[2] : th[2]};
     PetscReal v[2];
    PffSamplerFaceAt_Private(s, b, lb, k0, nk, d, i0, t, lp, v);
    for (PetscInt k = 0; k < nk; k++) val[k][d] = v[k];
  }
}
