/* Advection (PF-FLIP Sec. 3.7; DESIGN.md Sec. 4 step 7): every particle integrates dx/dt = u(x)
   through the face velocity channel with Ralston's third-order Runge-Kutta (Bridson 2015),
     k1 = u(x), k2 = u(x + dt/2 k1), k3 = u(x + 3dt/4 k2), x += dt (2 k1 + 3 k2 + 4 k3) / 9,
   in its own sub-steps: n_sub = ceil(|u(x)| dt / (cfl h)), 1 <= n_sub <= PFF_PARTICLES_MAX_SUBSTEPS,
   h the cell size of its block (locally adaptive time stepping).

   Each particle type has its own velocity channel (liquid particles sample the liquid velocity
   extrapolated into the air, Sec. 3.7); the batches are grouped by type so that each channel is
   interpolated in one call.

   Velocity samples use PffGridInterpolateFrom on the lattice of a "current" owned block, which may
   reach (width - 1) cells of that block's level beyond it. A stage point within that reach keeps the
   block; a point beyond it that lies in another owned block switches to that block; a point beyond
   it on another rank (or across a wall) has its displacement clamped, per axis, to the reach of the
   current block (logged with PetscInfo). So within one call a particle may travel about (width - 1)
   cells past its rank's blocks exactly; further motion is truncated until the next call.

   Threads take whole blocks; each particle runs all its sub-steps in registers, in double precision
   and grid units, and is rounded to the float store once (no per-particle scratch). The samples are
   those of PffGridInterpolateFrom at the world point of the grid position, through the block table of
   PffSampler (without its per-point checks). Afterwards particles inside a
   solid are pushed out along the distance gradient and all particles are migrated (which wraps periodic axes and clamps
   walls). */
#include "particlesimpl.h"

typedef struct {
  PetscReal c[3];  /* block centre, grid units */
  PetscReal bound; /* largest allowed |g - c| per axis for a velocity sample, grid units */
  PetscReal h;     /* cell size, grid units */
} PffAdvectBlock;

/* Chooses the block to sample grid position gs from (cur first) and clamps gs into cur's reach if no
   owned block can serve it. Returns PETSC_TRUE when it clamped. */
static PetscBool PffAdvectFix(PffParticles p, const PffAdvectBlock *blocks, const PetscInt level[], PetscInt cur,
                              PetscReal gs[3], PetscInt *out)
{
  const PffAdvectBlock *b      = &blocks[cur];
  PetscBool             within = PETSC_TRUE;
  PetscReal             rel[3];

  for (int a = 0; a < 3; a++) {
    rel[a] = gs[a] - b->c[a];
    if (p->periodic[a]) { /* the nearest image; rel is nearly always within half a period already */
      const PetscReal L = (PetscReal)p->cells[a];
      if (!(rel[a] >= -0.5 * L && rel[a] < 0.5 * L)) rel[a] -= L * PetscFloorReal(rel[a] / L + 0.5);
    }
    if (PetscAbsReal(rel[a]) > b->bound) within = PETSC_FALSE;
  }
  *out = cur;
  if (within) return PETSC_FALSE;
  const PetscInt gid = PffParticlesLocateReal_Private(p, gs, level);
  if (gid >= 0 && p->local[gid] >= 0) {
    *out = p->local[gid];
    return PETSC_FALSE;
  }
  for (int a = 0; a < 3; a++) {
    if (rel[a] > b->bound)
      gs[a] = b->c[a] + b->bound;
    else if (rel[a] < -b->bound)
      gs[a] = b->c[a] - b->bound;
    else
      gs[a] = b->c[a] + rel[a];
  }
  return PETSC_TRUE;
}

/* Velocity at grid position g through local block lb, channel k of the sampler, in grid units per
   unit time. */
static inline void PffAdvectSample(PffParticles p, const PffSampler *s, const PffSampleBlock *b, PetscInt lb,
                                   PetscInt k, const PetscReal g[3], PetscReal u[3])
{
  const PetscReal ih0 = 1.0 / p->h0;
  PetscReal       lp[3], v[2][3];
  PffSamplerLocal_Private(p, b, g, lp);
  PffSamplerVector_Private(s, b, lb, k, 1, lp, v);
  for (PetscInt d = 0; d < 3; d++) u[d] = v[0][d] * ih0;
}

/* The thread's copy of its own block lb (with tiles), the sampler's table for another block c. */
static inline const PffSampleBlock *PffAdvectBlk(const PffSampler *s, const PffSampleBlock *tb, PetscInt lb, PetscInt c)
{
  return c == lb ? tb : &s->blocks[c];
}

/* One particle's RK3 sub-steps in double and grid units through the general sampler: the path of the
   particles the chunk path does not take. Returns the sub-step count and adds the clamps to *nclamp. */
static PetscInt PffAdvectParticle(PffParticles p, const PffSampler *s, const PffSampleBlock *tb,
                                  const PffAdvectBlock *blocks, const PetscInt level[], PetscInt lb, PetscInt k,
                                  PetscReal dt, float xi[3], PetscInt *nclamp)
{
  PetscReal g[3] = {xi[0], xi[1], xi[2]}, k1[3], k2[3], k3[3], gs[3];
  PetscInt  cur  = lb, bl;

  PffAdvectSample(p, s, PffAdvectBlk(s, tb, lb, cur), cur, k, g, k1);
  const PetscReal cells =
      PetscSqrtReal(k1[0] * k1[0] + k1[1] * k1[1] + k1[2] * k1[2]) * dt / (p->substepCfl * blocks[lb].h);
  const PetscInt  m  = PetscMax(1, cells < (PetscReal)PFF_PARTICLES_MAX_SUBSTEPS ? (PetscInt)PetscCeilReal(cells)
                                                                                 : PFF_PARTICLES_MAX_SUBSTEPS);
  const PetscReal hs = dt / (PetscReal)m;
  for (PetscInt sub = 0; sub < m; sub++) {
    if (sub > 0) PffAdvectSample(p, s, PffAdvectBlk(s, tb, lb, cur), cur, k, g, k1);
    /* k2 at g + dt/2 k1, k3 at g + 3 dt/4 k2 */
    for (int a = 0; a < 3; a++) gs[a] = g[a] + 0.5 * hs * k1[a];
    *nclamp += PffAdvectFix(p, blocks, level, cur, gs, &bl);
    PffAdvectSample(p, s, PffAdvectBlk(s, tb, lb, bl), bl, k, gs, k2);
    for (int a = 0; a < 3; a++) gs[a] = g[a] + 0.75 * hs * k2[a];
    *nclamp += PffAdvectFix(p, blocks, level, cur, gs, &bl);
    PffAdvectSample(p, s, PffAdvectBlk(s, tb, lb, bl), bl, k, gs, k3);
    for (int a = 0; a < 3; a++) g[a] += hs * (2 * k1[a] + 3 * k2[a] + 4 * k3[a]) / 9;
    *nclamp += PffAdvectFix(p, blocks, level, cur, g, &cur);
  }
  for (int a = 0; a < 3; a++) xi[a] = (float)g[a];
  return m;
}

/* Lower tile index (clamped into the tile of gw ghost layers) and fraction of coordinate v (finite, within
   2^31); a v outside the tile gives garbage that the caller discards. */
static inline void PffAdvectAxis(float v, int32_t gw, int32_t n, int32_t *i0, float *t)
{
  const float f = PffFloorf_Private(v);
  *i0           = PetscMin(PetscMax((int32_t)f, -gw), n + gw - 2);
  *t            = v - f;
}

/* Face component d (lattice offsets off) of the chunk's points (px, py, pz) from a tile of gw ghost layers of block
   b, times scale, into od; beside a wall or hole the lattice is clamped there as the grid's general path does.
   restrict parameters let the gathers vectorise. */
static void PffAdvectChunkComponent(const PffSampleBlock *b, int d, PetscInt m, const float *restrict px,
                                    const float *restrict py, const float *restrict pz, const float   off[3],
                                    const float *restrict tile, const int32_t *restrict koff, int32_t gw, float scale,
                                    float *restrict od)
{
  const int32_t n = (int32_t)b->n, mm = n + 2 * gw;
  int32_t       st[8], ci[3][PFF_CHUNK];
  float         val[PFF_CHUNK], ti[3][PFF_CHUNK]; /* local targets: the gathers cannot alias them */
  PffTileCorners_Private(mm, st);
  for (PetscInt j = 0; j < m; j++) {
    PffAdvectAxis(px[j] - off[0], gw, n, &ci[0][j], &ti[0][j]);
    PffAdvectAxis(py[j] - off[1], gw, n, &ci[1][j], &ti[1][j]);
    PffAdvectAxis(pz[j] - off[2], gw, n, &ci[2][j], &ti[2][j]);
  }
  const int32_t *c[3] = {ci[0], ci[1], ci[2]};
  const float   *t[3] = {ti[0], ti[1], ti[2]};
  int32_t        cc[3][PFF_CHUNK];
  float          tc[3][PFF_CHUNK];
  PffChunkClampHoles_Private(b, m, d, c, t, cc, tc);
  int32_t o[PFF_CHUNK];
  PffChunkOffsets_Private(mm, gw, c, m, o);
  for (PetscInt j = 0; j < m; j++) o[j] += koff[j];
  PffTrilinearChunk_Private(tile, o, st, t[0], t[1], t[2], m, val);
  for (PetscInt j = 0; j < m; j++) od[j] = scale * val[j];
}

/* Velocity samples of a chunk at block-local points lp (cell units of the block, from its lower corner)
   from the block's tiles (gw ghost layers), times scale: out[d][j]. koff[j] selects the particle's
   channel. Points outside the tiles give garbage that the caller discards (indices are clamped so that
   no read leaves the tile). */
static void PffAdvectChunkSample(const PffSampleBlock *b, PetscInt gw, PetscInt m, float lp[3][PFF_CHUNK],
                                 const int32_t koff[], float scale, float out[3][PFF_CHUNK])
{
  for (int d = 0; d < 3; d++) {
    const float off[3] = {d == 0 ? 0.0f : 0.5f, d == 1 ? 0.0f : 0.5f, d == 2 ? 0.0f : 0.5f};
    PffAdvectChunkComponent(b, d, m, lp[0], lp[1], lp[2], off, b->tile[0][d], koff, (int32_t)gw, scale, out[d]);
  }
}

/* ok[j] &= every coordinate of point j lies in [lo, hi) (false for NaN); a point outside is replaced by
   the origin, so that the samples' float-to-int conversions stay defined. */
static void PffAdvectChunkInside(PetscInt m, float pt[3][PFF_CHUNK], const float lo[3], const float hi[3], uint8_t ok[])
{
  float *restrict x = pt[0], *restrict y = pt[1], *restrict z = pt[2];
  for (PetscInt j = 0; j < m; j++) {
    const int in =
        (x[j] >= lo[0]) & (x[j] < hi[0]) & (y[j] >= lo[1]) & (y[j] < hi[1]) & (z[j] >= lo[2]) & (z[j] < hi[2]);
    ok[j] &= (uint8_t)in;
    x[j] = in ? x[j] : 0.0f;
    y[j] = in ? y[j] : 0.0f;
    z[j] = in ? z[j] : 0.0f;
  }
}

/* The particles [i0, i1) of local block lb. Chunks run one RK3 step in float in the block's local cell units,
   vectorised: every stage point within one cell of the block (inside the reach of any velocity halo and inside
   the tiles; beside a wall or hole the samples are clamped there as in the general path) and one sub-step
   enough. The others take the general path. */
static void PffAdvectBlockChunks(PffParticles p, const PffSampler *s, const PffSampleBlock *tb,
                                 const PffAdvectBlock *blocks, const PetscInt level[], PetscInt lb, PetscReal dt,
                                 PetscInt *maxsub, PetscInt *nclamp)
{
  const PffSampleBlock *b  = tb;
  const PetscInt        i1 = p->start[lb + 1], kair = s->nch - 1;
  const float           hl = (float)((PetscInt)1 << b->level);
  float                 lo[3], ihl;
  PffBlockCorner_Private(p->n0, b->ijk, b->level, lo, &ihl);
  const float   scale = (float)(dt / (p->h0 * (PetscReal)hl)), cfl = (float)p->substepCfl;
  const float   rn = (float)b->n + 1 - 1e-6f, rlo[3] = {-1 + 1e-6f, -1 + 1e-6f, -1 + 1e-6f}, rhi[3] = {rn, rn, rn};
  const int32_t air = (int32_t)(b->tile[kair][0] - b->tile[0][0]); /* tiles are channel-major */
  float        *x   = p->s.x;

  for (PetscInt j0 = p->start[lb]; j0 < i1; j0 += PFF_CHUNK) {
    const PetscInt m = PetscMin(PFF_CHUNK, i1 - j0);
    float          l0[3][PFF_CHUNK], st[3][PFF_CHUNK], k1[3][PFF_CHUNK], k2[3][PFF_CHUNK], k3[3][PFF_CHUNK];
    int32_t        koff[PFF_CHUNK];
    uint8_t        ok[PFF_CHUNK];
    for (PetscInt j = 0; j < m; j++) {
      koff[j] = PffParticleWordType(p->s.word[j0 + j]) == PFF_PARTICLE_LIQUID ? 0 : air;
      ok[j]   = 1;
      for (int a = 0; a < 3; a++) l0[a][j] = (x[3 * (j0 + j) + a] - lo[a]) * ihl; /* exact */
    }
    PffAdvectChunkSample(b, s->gw, m, l0, koff, scale, k1);
    for (PetscInt j = 0; j < m; j++) /* one sub-step: the displacement within -particles_substep_cfl cells */
      ok[j] &= (uint8_t)(k1[0][j] * k1[0][j] + k1[1][j] * k1[1][j] + k1[2][j] * k1[2][j] <= cfl * cfl);
    for (int a = 0; a < 3; a++)
      for (PetscInt j = 0; j < m; j++) st[a][j] = l0[a][j] + 0.5f * k1[a][j];
    PffAdvectChunkInside(m, st, rlo, rhi, ok);
    PffAdvectChunkSample(b, s->gw, m, st, koff, scale, k2);
    for (int a = 0; a < 3; a++)
      for (PetscInt j = 0; j < m; j++) st[a][j] = l0[a][j] + 0.75f * k2[a][j];
    PffAdvectChunkInside(m, st, rlo, rhi, ok);
    PffAdvectChunkSample(b, s->gw, m, st, koff, scale, k3);
    for (int a = 0; a < 3; a++)
      for (PetscInt j = 0; j < m; j++) st[a][j] = l0[a][j] + (2 * k1[a][j] + 3 * k2[a][j] + 4 * k3[a][j]) / 9;
    PffAdvectChunkInside(m, st, rlo, rhi, ok);
    for (PetscInt j = 0; j < m; j++) {
      float *xi = &x[3 * (j0 + j)];
      if (ok[j]) {
        for (int a = 0; a < 3; a++) xi[a] = lo[a] + st[a][j] * hl;
        *maxsub = PetscMax(*maxsub, 1);
      } else {
        /* (PetscMax evaluates its arguments twice) */
        const PetscInt k = koff[j] ? kair : 0, nsub = PffAdvectParticle(p, s, tb, blocks, level, lb, k, dt, xi, nclamp);
        *maxsub = PetscMax(*maxsub, nsub);
      }
    }
  }
}

PetscErrorCode PffParticlesAdvect(PffParticles p, PetscInt chU, PetscReal dt, PffSolidFn solid, void *solidctx,
                                  PffParticleStats *stats)
{
  const PetscInt ch[PFF_PARTICLE_NTYPES] = {chU, chU};

  PetscFunctionBeginUser;
  PetscCall(PffParticlesAdvectPerType(p, ch, dt, solid, solidctx, stats));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Bit t set when particles [i0, i1) hold one of type t. */
static inline unsigned PffBlockTypes(const uint32_t *restrict w, PetscInt i0, PetscInt i1)
{
  unsigned types = 0;
  /* clang-format 14 takes the reduction's operator for an expression */
  // clang-format off
#pragma omp simd reduction(|:types)
  // clang-format on
  for (PetscInt i = i0; i < i1; i++) types |= 1u << PffParticleWordType(w[i]);
  return types;
}

PetscErrorCode PffParticlesAdvectPerType(PffParticles p, const PetscInt chU[PFF_PARTICLE_NTYPES], PetscReal dt,
                                         PffSolidFn solid, void *solidctx, PffParticleStats *stats)
{
  PetscInt        width = PFF_GRID_MAX_WIDTH, nb[3], maxsub = 0, nclamp = 0;
  const PetscInt *level;
  PffAdvectBlock *blocks;
  PffSampler      sampler;
  PetscInt64      pushed = 0;

  PetscFunctionBeginUser;
  PetscCall(PffParticlesCheckBinned_Private(p, "PffParticlesAdvect"));
  for (PetscInt t = 0; t < PFF_PARTICLE_NTYPES; t++) {
    PffChannelKind kind;
    PetscInt       w;
    const char    *name;
    PetscCall(PffGridGetChannelInfo(p->grid, chU[t], &name, &kind, NULL, &w));
    PetscCheck(kind == PFF_CHANNEL_FACE, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG,
               "advection channel %s must be a face channel", name);
    PetscCheck(w >= 2, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG,
               "advection channel %s has halo width %" PetscInt_FMT ": needs >= 2", name, w);
    /* the reach of a sample is that of the narrower halo */
    width = PetscMin(width, w);
  }
  PetscCheck(dt >= 0 && PetscIsNormalReal(dt + 1), PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
             "advection time step %g is invalid", (double)dt);
  PetscCall(PetscLogEventBegin(PFF_Advect, 0, 0, 0, 0));
  PetscCall(PffGridGetRaster(p->grid, nb, &level, NULL));
  PetscCall(PffSamplerCreate_Private(p, chU[0] == chU[1] ? 1 : 2, chU, 2, &sampler));
  {
    const size_t bytes = sizeof(PffAdvectBlock) * (size_t)p->nlocal;
    void        *ptr;
    PetscCall(PffParticlesGetScratch_Private(p, PFF_SCRATCH_ADVECT, 1, &bytes, &ptr));
    blocks = (PffAdvectBlock *)ptr;
  }
  for (PetscInt lb = 0; lb < p->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(p->grid, lb, &info));
    const PetscReal h = (PetscReal)((PetscInt)1 << info.level), half = 0.5 * (PetscReal)p->n0;
    for (int a = 0; a < 3; a++) blocks[lb].c[a] = (PetscReal)(info.ijk[a] * p->n0) + half;
    /* a millionth of a cell inside the reach PffGridInterpolateFrom accepts */
    blocks[lb].bound = half + ((PetscReal)(width - 1) - 1e-6) * h;
    blocks[lb].h     = h;
  }

  /* threads take blocks, which go by chunks */
#pragma omp parallel for reduction(max : maxsub) reduction(+ : nclamp) schedule(dynamic, 1)
  for (PetscInt lb = 0; lb < p->nlocal; lb++) {
    PffSampleBlock tb;
    /* one channel, or the channel of each type the block holds: a block inside one phase fills one tile */
    const unsigned need = sampler.nch > 1 ? PffBlockTypes(p->s.word, p->start[lb], p->start[lb + 1]) : 1u;
    if (!PffSamplerBlockTiles_Private(p, &sampler, lb, need, &tb)) continue;
    PffAdvectBlockChunks(p, &sampler, &tb, blocks, level, lb, dt, &maxsub, &nclamp);
  }

  PetscCall(PffSamplerDestroy_Private(&sampler));
  if (nclamp) PetscCall(PetscInfo(NULL, "%" PetscInt_FMT " advection stages clamped to the halo reach\n", nclamp));

  /* push out of solids along the distance gradient (a few Newton-like steps), in world units. The distance is
     1-Lipschitz (PffSolidFn), so a raster block whose centre lies farther from the solids than its half diagonal
     holds no point inside them: only particles in the other blocks (or outside the raster) are tested. */
  if (solid != NULL) {
    float          *x = p->s.x;
    const PetscReal ulp4 =
        4 * p->h0 * (PetscReal)PetscMax(p->cells[0], PetscMax(p->cells[1], p->cells[2])) / 16777216.0;
    const PetscInt  nraster = p->nb[0] * p->nb[1] * p->nb[2];
    const PetscReal half = 0.5 * (PetscReal)p->n0 * p->h0, reach = PetscSqrtReal(3.0) * half * (1 + 1e-6) + ulp4;
    uint8_t        *near;
    {
      const size_t bytes = (size_t)nraster;
      void        *ptr;
      PetscCall(PffParticlesGetScratch_Private(p, PFF_SCRATCH_SOLID, 1, &bytes, &ptr));
      near = (uint8_t *)ptr;
    }
#pragma omp parallel for schedule(static)
    for (PetscInt r = 0; r < nraster; r++) {
      const PetscInt ijk[3] = {r % p->nb[0], (r / p->nb[0]) % p->nb[1], r / (p->nb[0] * p->nb[1])};
      PetscReal      c[3], gr[3];
      for (int a = 0; a < 3; a++) c[a] = p->origin[a] + p->h0 * (PetscReal)p->n0 * ((PetscReal)ijk[a] + 0.5);
      near[r] = (uint8_t) !(solid(c, gr, solidctx) > reach);
    }
#pragma omp parallel for reduction(+ : pushed) schedule(static)
    for (PetscInt i = 0; i < p->n; i++) {
      PetscBool moved = PETSC_FALSE, inside = PETSC_TRUE;
      PetscReal xw[3];
      PetscInt  r = 0;
      for (int a = 2; a >= 0; a--) {
        const PetscReal b = PetscFloorReal((PetscReal)x[3 * i + a] / (PetscReal)p->n0);
        if (!(b >= 0 && b < (PetscReal)p->nb[a])) inside = PETSC_FALSE;
        r = r * p->nb[a] + (inside ? (PetscInt)b : 0);
      }
      if (inside && !near[r]) continue;
      for (int a = 0; a < 3; a++) xw[a] = p->origin[a] + p->h0 * (PetscReal)x[3 * i + a];
      for (int it = 0; it < 4; it++) {
        PetscReal       gr[3];
        const PetscReal phi = solid(xw, gr, solidctx);
        if (!(phi < 0)) break;
        const PetscReal gn = PetscSqrtReal(gr[0] * gr[0] + gr[1] * gr[1] + gr[2] * gr[2]);
        if (!(gn > 0)) break;
        /* phi < 0 is the distance to the surface: step just beyond it, by more than the float store's
           rounding (4 steps of the largest grid coordinate) */
        const PetscReal step = -phi * (1 + 1e-3) + ulp4;
        for (int a = 0; a < 3; a++) xw[a] += step * gr[a] / gn;
        moved = PETSC_TRUE;
      }
      if (moved)
        for (int a = 0; a < 3; a++) x[3 * i + a] = (float)((xw[a] - p->origin[a]) / p->h0);
      pushed += moved;
    }
  }
  PetscCall(PetscLogEventEnd(PFF_Advect, 0, 0, 0, 0));

  PffParticleStats ms;
  PetscCall(PffParticlesMigrate(p, &ms));
  PetscInt64 loc[2] = {pushed, maxsub};
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &loc[0], 1, MPIU_INT64, MPI_SUM, p->comm));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &loc[1], 1, MPIU_INT64, MPI_MAX, p->comm));
  if (stats) {
    *stats          = ms;
    stats->pushed   = loc[0];
    stats->substeps = (PetscInt)loc[1];
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
