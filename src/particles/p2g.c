/* P2G (PF-FLIP Sec. 3.2, Eq. 3-6; DESIGN.md Sec. 4 step 2): mass and momentum of the particles
   splatted onto the MAC faces,
     chMass[f] = sum_p w_fp m_p / 8^l_f,   chMom[f] = sum_p w_fp m_p v_p,d / 8^l_f,
     w_fp = (max(1 - (|x_f - x_p| / r)^2, 0))^3,   m_p = density[type] * 8^l_p,
   with r = h of the block the particle lies in. The particle's level only sets its volume. Per axis a
   face lattice point lies within r of the particle only for the two lattice indices around it, so
   each component has a 2 x 2 x 2 stencil, which reaches at most one cell beyond the block (any
   channel width >= 1 suffices).

   Threads: blocks are coloured by the parity of their raster coordinates (8 colours; on a periodic
   axis with an odd block count the last block gets a third colour, since it touches block 0), so
   two blocks of one colour never write the same face, and the colours run one after another with
   a parallel loop over the blocks of each colour: no locks or atomics.

   Level boundaries: a particle always splats on the lattice of its own block and normalises by
   8^(its block's level). Contributions that land in the ghost region of a coarser or finer
   neighbour are moved by the grid's conservative reverse halo (whole or half values to the coarse
   face under a fine one, equal shares to the fine faces under a coarse one). This conserves the
   sum of the stored values but not the "8^-l_f" normalisation of the receiving face: at faces
   within one cell of a level boundary the density of a uniform lattice deviates from
   density * rho~_0 (by up to about a factor 8 in the ghost layer's share). Momentum and mass get
   the same treatment, so mom / mass is still a weighted mean of particle velocities. Away from
   level boundaries the result is exact. Wall ghost regions are zero boxes that the reverse halo
   does not sum, so contributions to the upper wall faces (index n of the normal component) are
   dropped; the boundary conditions own those faces. */
#include "particlesimpl.h"
#include <omp.h>

PetscErrorCode PffParticlesGetKernelSum(PffParticles p, PetscReal *rho0)
{
  /* offsets of the lattice (i + 1/4 or 3/4) from a face, per axis, in cells; the same for all axes
     and components, since faces sit at integer or half-integer positions */
  const PetscReal off[4] = {-0.75, -0.25, 0.25, 0.75};
  PetscReal       sum    = 0;

  PetscFunctionBeginUser;
  PetscCheck(rho0 != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "PffParticlesGetKernelSum: output pointer is NULL");
  (void)p;
  for (int a = 0; a < 4; a++)
    for (int b = 0; b < 4; b++)
      for (int c = 0; c < 4; c++) {
        const PetscReal q = 1 - (off[a] * off[a] + off[b] * off[b] + off[c] * off[c]);
        if (q > 0) sum += q * q * q;
      }
  *rho0 = sum;
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffCheckFaceChannel(PffGrid grid, PetscInt ch, const char what[])
{
  PffChannelKind kind;
  PetscInt       width;
  const char    *name;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetChannelInfo(grid, ch, &name, &kind, NULL, &width));
  PetscCheck(kind == PFF_CHANNEL_FACE, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG, "%s channel %s must be a face channel",
             what, name);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Eight floats: the tile values of a pair of x-neighbouring faces (below), or a particle's eight corner weights. */
typedef float   PffV8 __attribute__((vector_size(32)));
typedef int32_t PffI8 __attribute__((vector_size(32)));

/* Floats per face in the splat tile: mass, momentum, volume and a pad, so that the two faces of an x pair of
   corners are one 8-float vector. */
#define PFF_SPLAT_QUAD 4

/* Floats of a thread's splat tile for blocks of at most n0^3 cells: the quad tiles of the three components and
   one plain tile into which a channel is taken out of them. */
static inline size_t PffSplatTileFloats(PetscInt n0)
{
  const size_t m = (size_t)(n0 + 2);
  return (3 * PFF_SPLAT_QUAD + 1) * m * m * m;
}

/* Adds one particle to the quad tile T of one component: lattice fractions (ax, ay, az) from corner 0, tile cell o
   of corner 0, st the corner offsets (x pairs at st[0], st[2], st[4], st[6]). The eight corner weights of Eq. 6 (and
   the trilinear ones of the volume) are one vector each; each x pair of corners is one vector read-modify-write of
   mass, momentum and volume, four per component instead of 24 scalar ones. The arithmetic is the scalar
   splat's, operation for operation, so the sums are the same to the bit. */
static inline __attribute__((always_inline)) void PffSplatParticle(float *restrict T, int32_t o, const int32_t st[8],
                                                                   float ax, float ay, float az, float vol, float r,
                                                                   float rv, const int withVolume)
{
  const float x0 = ax * ax, bx = 1 - ax, x1 = bx * bx, y0 = ay * ay, by = 1 - ay, y1 = by * by;
  const float z0 = az * az, bz = 1 - az, z1 = bz * bz;
  const PffV8 X = {x0, x1, x0, x1, x0, x1, x0, x1}, Y = {y0, y0, y1, y1, y0, y0, y1, y1};
  const PffV8 Z = {z0, z0, z0, z0, z1, z1, z1, z1}, one = {1, 1, 1, 1, 1, 1, 1, 1};
  PffV8       e     = one - (X + Y + Z);
  e                 = (PffV8)((PffI8)e & (e > 0)); /* max(e, 0) */
  const PffV8 W     = e * e * e * vol;
  PffV8       V     = W; /* volume: vol lx ly, times lz in the pair's multiplier (lz is one per z half) */
  float       lz[2] = {0, 0};
  if (withVolume) {
    const PffV8 LX = {bx, ax, bx, ax, bx, ax, bx, ax}, LY = {by, by, ay, ay, by, by, ay, ay};
    V     = vol * LX * LY;
    lz[0] = bz;
    lz[1] = az;
  }
  const PffV8 P0 = {r, rv, lz[0], 0, r, rv, lz[0], 0}, P1 = {r, rv, lz[1], 0, r, rv, lz[1], 0};
#define PFF_SPLAT_PAIR(q, P)                                                                                           \
  do {                                                                                                                 \
    float *t = T + PFF_SPLAT_QUAD * (o + st[q]);                                                                       \
    PffV8  v;                                                                                                          \
    memcpy(&v, t, sizeof v);                                                                                           \
    v = v + __builtin_shufflevector(W, V, q, q, 8 + q, 8 + q, q + 1, q + 1, 9 + q, 9 + q) * P;                         \
    memcpy(t, &v, sizeof v);                                                                                           \
  } while (0)
  PFF_SPLAT_PAIR(0, P0);
  PFF_SPLAT_PAIR(2, P0);
  PFF_SPLAT_PAIR(4, P1);
  PFF_SPLAT_PAIR(6, P1);
#undef PFF_SPLAT_PAIR
}

/* Splats the particles [i0, i1) of one block. A binned particle's 2 x 2 x 2 stencils reach at most one
   cell beyond its block, so every corner lands in a tile of (n + 2)^3 faces from cell -1 per component:
   the inner loop has no branch on where a corner falls, and its weights are float. The tile holds mass,
   momentum and volume of a face side by side (PffSplatParticle). Each channel is then taken out into a plain
   tile, whose own cells are added to the block's arrays row by row, and its ghost shell to the views (the
   reverse halo sums those into their owners). */
static void PffSplatBlock(const PffParticleSoA *s, PetscInt i0, PetscInt i1, const PffBlockInfo *info,
                          const PffView *vm[3], const PffView *vp[3], const PffView *vv[3], float *const dm[3],
                          float *const dp[3], float *const dv[3], const PetscReal density[], PetscInt n0, float *tile)
{
  const PetscInt n = info->n, mm = n + 2, m3 = mm * mm * mm, nc = vv ? 3 : 2;
  const float    norm = 1.0f / (float)((PetscInt64)1 << (3 * info->level));
  int32_t        st[8];
  float          lo[3], ih;
  float         *plain = tile + 3 * PFF_SPLAT_QUAD * m3;
  if (i1 == i0) return; /* the channels were zeroed: an empty block adds nothing */
  PffTileCorners_Private((int32_t)mm, st);
  PffBlockCorner_Private(n0, info->ijk, info->level, lo, &ih);
  const float           rho[PFF_PARTICLE_NTYPES] = {(float)density[0], (float)density[1]};
  const PffView *const *vc[3]                    = {vm, vp, vv};
  float *const         *dc[3]                    = {dm, dp, dv};

  memset(tile, 0, sizeof(float) * (size_t)(3 * PFF_SPLAT_QUAD * m3));
  /* chunks of particles: the lattices for the whole chunk in loops without dependences (vectorised), then
     particle by particle into the tile */
  for (PetscInt j0 = i0; j0 < i1; j0 += PFF_CHUNK) {
    const PetscInt  m = PetscMin(PFF_CHUNK, i1 - j0);
    float           vol[PFF_CHUNK], r[PFF_CHUNK];
    PffChunkLattice L;
    for (PetscInt j = 0; j < m; j++) {
      const uint32_t word = s->word[j0 + j];
      vol[j]              = (float)(1u << (3 * PffParticleWordLevel(word))) * norm;
      r[j]                = rho[PffParticleWordType(word)];
    }
    PffChunkLattice_Private(&s->x[3 * j0], m, lo, ih, n, &L);
    for (int d = 0; d < 3; d++) {
      const int32_t *c[3];
      const float   *t[3];
      PffChunkLatticeOf_Private(&L, d, c, t);
      const float   *tx = t[0], *ty = t[1], *tz = t[2];
      const int32_t *cx = c[0], *cy = c[1], *cz = c[2];
      float         *T = tile + d * PFF_SPLAT_QUAD * m3;
      if (vv)
        for (PetscInt j = 0; j < m; j++)
          PffSplatParticle(T, (cx[j] + 1) + (int32_t)mm * ((cy[j] + 1) + (int32_t)mm * (cz[j] + 1)), st, tx[j], ty[j],
                           tz[j], vol[j], r[j], r[j] * s->v[3 * (j0 + j) + d], 1);
      else
        for (PetscInt j = 0; j < m; j++)
          PffSplatParticle(T, (cx[j] + 1) + (int32_t)mm * ((cy[j] + 1) + (int32_t)mm * (cz[j] + 1)), st, tx[j], ty[j],
                           tz[j], vol[j], r[j], r[j] * s->v[3 * (j0 + j) + d], 0);
    }
  }
  for (PetscInt c = 0; c < nc; c++)
    for (int d = 0; d < 3; d++) {
      const float *T    = tile + d * PFF_SPLAT_QUAD * m3 + c;
      float       *data = dc[c][d];
      for (PetscInt i = 0; i < m3; i++) plain[i] = T[PFF_SPLAT_QUAD * i];
      for (PetscInt kk = 0; kk < n; kk++)
        for (PetscInt jj = 0; jj < n; jj++) {
          const float *row = plain + 1 + mm * ((jj + 1) + mm * (kk + 1));
          float       *dst = data + n * (jj + n * kk);
          for (PetscInt ii = 0; ii < n; ii++) dst[ii] += row[ii];
        }
      PffTileShell_Private(vc[c][d], n, 1, plain, PETSC_TRUE);
    }
}

PetscErrorCode PffParticlesSplatScratch_Private(PffParticles p, PffScratchSlot slot, PetscInt nviews,
                                                PffBlockInfo **info, const PffView ***views, float ***data,
                                                PetscInt **order, PetscInt **colour)
{
  const size_t n        = (size_t)p->nlocal;
  const size_t bytes[5] = {sizeof(PffBlockInfo) * n, sizeof(const PffView *) * (size_t)nviews * n,
                           sizeof(float *) * (size_t)nviews * n, sizeof(PetscInt) * n, sizeof(PetscInt) * n};
  void        *ptrs[5];

  PetscFunctionBeginUser;
  PetscCall(PffParticlesGetScratch_Private(p, slot, 5, bytes, ptrs));
  *info   = (PffBlockInfo *)ptrs[0];
  *views  = (const PffView **)ptrs[1];
  *data   = (float **)ptrs[2];
  *order  = (PetscInt *)ptrs[3];
  *colour = (PetscInt *)ptrs[4];
  PetscFunctionReturn(PETSC_SUCCESS);
}

void PffParticlesColourOrder_Private(PffParticles p, const PffBlockInfo info[], PetscInt colour[], PetscInt order[],
                                     PetscInt cstart[28])
{
  PetscInt fill[27];

  for (int c = 0; c < 28; c++) cstart[c] = 0;
  for (PetscInt lb = 0; lb < p->nlocal; lb++) {
    PetscInt c = 0;
    for (int a = 0, m = 1; a < 3; a++, m *= 3) {
      const PetscInt  ia  = info[lb].ijk[a];
      const PetscBool odd = (PetscBool)(p->periodic[a] && (p->nb[a] & 1) && ia == p->nb[a] - 1);
      c += m * (odd ? 2 : (ia & 1));
    }
    colour[lb] = c;
    cstart[c + 1]++;
  }
  for (int c = 0; c < 27; c++) cstart[c + 1] += cstart[c];
  for (int c = 0; c < 27; c++) fill[c] = cstart[c];
  for (PetscInt lb = 0; lb < p->nlocal; lb++) order[fill[colour[lb]]++] = lb;
}

PetscErrorCode PffParticlesP2G(PffParticles p, const PetscReal density[PFF_PARTICLE_NTYPES], PetscInt chMass,
                               PetscInt chMom, PetscInt chVolume)
{
  PffBlockInfo   *info;
  const PffView **views;
  float         **data;
  PetscInt       *order = NULL, *colour = NULL, cstart[28];

  PetscFunctionBeginUser;
  PetscCall(PffParticlesCheckBinned_Private(p, "PffParticlesP2G")); /* may rebin after an adapt */
  const PetscInt nlocal = p->nlocal;
  PetscCheck(chMass != chMom && chVolume != chMass && chVolume != chMom, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG,
             "P2G needs different channels for mass, momentum and volume");
  PetscCall(PffCheckFaceChannel(p->grid, chMass, "P2G mass"));
  PetscCall(PffCheckFaceChannel(p->grid, chMom, "P2G momentum"));
  if (chVolume >= 0) PetscCall(PffCheckFaceChannel(p->grid, chVolume, "P2G volume"));
  const PetscInt nv = chVolume >= 0 ? 3 : 0, stride = 6 + nv;
  PetscCall(PetscLogEventBegin(PFF_P2G, 0, 0, 0, 0));
  PetscCall(PffParticlesSplatScratch_Private(p, PFF_SCRATCH_P2G, stride, &info, &views, &data, &order, &colour));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PetscCall(PffGridGetBlockInfo(p->grid, lb, &info[lb]));
    for (PetscInt comp = 0; comp < 3; comp++) {
      PetscCall(PffGridGetBlockViews(p->grid, chMass, lb, comp, &views[stride * lb + comp]));
      PetscCall(PffGridGetBlockViews(p->grid, chMom, lb, comp, &views[stride * lb + 3 + comp]));
      PetscCall(PffGridGetBlockData(p->grid, chMass, lb, comp, &data[stride * lb + comp]));
      PetscCall(PffGridGetBlockData(p->grid, chMom, lb, comp, &data[stride * lb + 3 + comp]));
      if (nv) {
        PetscCall(PffGridGetBlockViews(p->grid, chVolume, lb, comp, &views[stride * lb + 6 + comp]));
        PetscCall(PffGridGetBlockData(p->grid, chVolume, lb, comp, &data[stride * lb + 6 + comp]));
      }
    }
  }
  /* the ghost boxes may hold a forward halo's values, and splatting adds to them */
  PetscCall(PffGridZeroChannel(p->grid, chMass));
  PetscCall(PffGridZeroChannel(p->grid, chMom));
  if (nv) PetscCall(PffGridZeroChannel(p->grid, chVolume));

  PffParticlesColourOrder_Private(p, info, colour, order, cstart);

  const PffParticleSoA *s     = &p->s;
  const PetscInt       *start = p->start;
  const size_t          tsize = PffSplatTileFloats(p->n0);
  float                *tiles;
  PetscCall(PffParticlesGetFloatWork_Private(p, tsize * (size_t)PetscMax(omp_get_max_threads(), 1), &tiles));
  for (int c = 0; c < 27; c++) {
#pragma omp parallel for schedule(dynamic, 1)
    for (PetscInt e = cstart[c]; e < cstart[c + 1]; e++) {
      const PetscInt lb = order[e];
      PffSplatBlock(s, start[lb], start[lb + 1], &info[lb], &views[stride * lb], &views[stride * lb + 3],
                    nv ? &views[stride * lb + 6] : NULL, &data[stride * lb], &data[stride * lb + 3],
                    nv ? &data[stride * lb + 6] : NULL, density, p->n0, tiles + tsize * (size_t)omp_get_thread_num());
    }
  }

  PetscCall(PffGridHaloReverseBegin(p->grid, chMass));
  PetscCall(PffGridHaloReverseEnd(p->grid, chMass));
  PetscCall(PffGridHaloReverseBegin(p->grid, chMom));
  PetscCall(PffGridHaloReverseEnd(p->grid, chMom));
  if (nv) {
    PetscCall(PffGridHaloReverseBegin(p->grid, chVolume));
    PetscCall(PffGridHaloReverseEnd(p->grid, chVolume));
  }
  PetscCall(PetscLogEventEnd(PFF_P2G, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}
