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

/* Zeroes the owned values of channel ch and every region view within width of each block: the ghost
   buffers may hold a forward halo's values, and splatting adds to them. */
static PetscErrorCode PffZeroWithGhosts(PffGrid grid, PetscInt ch, PetscInt nlocal, const PffBlockInfo *info)
{
  PetscInt width;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetChannelInfo(grid, ch, NULL, NULL, NULL, &width));
  for (PetscInt lb = 0; lb < nlocal; lb++)
    for (PetscInt comp = 0; comp < 3; comp++) {
      float         *data;
      const PffView *views;
      const PetscInt n = info[lb].n;
      PetscCall(PffGridGetBlockData(grid, ch, lb, comp, &data));
      PetscCall(PetscArrayzero(data, n * n * n));
      PetscCall(PffGridGetBlockViews(grid, ch, lb, comp, &views));
      for (PetscInt k = -width; k < n + width; k++)
        for (PetscInt j = -width; j < n + width; j++) {
          const PetscBool inner = (PetscBool)(j >= 0 && j < n && k >= 0 && k < n);
          for (PetscInt i = -width; i < n + width; i++) {
            if (inner && i == 0) i = n; /* skip the block's own row */
            if (i >= n + width) break;
            *PffViewsAt(views, i, j, k, n) = 0;
          }
        }
    }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Splats the particles [i0, i1) of one block into the views of its three face components; a stencil
   inside the block's own cells (most of them) writes its arrays (dm, dp, dv) directly, in the same
   order, so the sums are the same. */
static void PffSplatBlock(const PffParticleSoA *s, PetscInt i0, PetscInt i1, const PffBlockInfo *info,
                          const PffView *vm[3], const PffView *vp[3], const PffView *vv[3], float *const dm[3],
                          float *const dp[3], float *const dv[3], const PetscReal density[], PetscInt n0, float *tile)
{
  const PetscReal lo[3] = {(PetscReal)(info->ijk[0] * n0), (PetscReal)(info->ijk[1] * n0),
                           (PetscReal)(info->ijk[2] * n0)}; /* grid units */
  const PetscReal ih    = 1.0 / (PetscReal)((PetscInt)1 << info->level),
                  norm  = 1.0 / (PetscReal)((PetscInt64)1 << (3 * info->level));
  const PetscInt n = info->n, st[8] = {0, 1, n, n + 1, n * n, n * n + 1, n * n + n, n * n + n + 1}, m = n + 2,
                 m3 = m * m * m, nc = vv ? 3 : 2;
  const PffView *const *vc[3] = {vm, vp, vv};

  /* ghost-layer contributions are summed in a tile (channel, component, (n + 2)^3 from cell -1) and
     added to the views once per block, not per corner (P2G +12-37 % at 1 thread, pff-bench-particles) */
  memset(tile, 0, sizeof(float) * (size_t)(nc * 3 * m3));

  for (PetscInt i = i0; i < i1; i++) {
    const uint32_t  word = s->word[i];
    const PetscReal vol  = (PetscReal)((PetscInt64)1 << (3 * PffParticleWordLevel(word))) * norm,
                    rho  = density[PffParticleWordType(word)];
    PetscReal sp[3];
    for (int a = 0; a < 3; a++) sp[a] = ((PetscReal)s->x[3 * i + a] - lo[a]) * ih;
    for (int d = 0; d < 3; d++) {
      PetscInt  c0[3];
      PetscReal q2[3][2], lin[3][2];
      PetscBool inside = PETSC_TRUE;
      for (int a = 0; a < 3; a++) {
        const PetscReal f = sp[a] - (a == d ? 0.0 : 0.5), fl = PetscFloorReal(f), t = f - fl;
        c0[a] = (PetscInt)fl;
        if (c0[a] < 0 || c0[a] + 1 >= n) inside = PETSC_FALSE;
        q2[a][0]  = t * t;
        q2[a][1]  = (1 - t) * (1 - t);
        lin[a][0] = 1 - t;
        lin[a][1] = t;
      }
      PetscReal w[8];
      for (int q = 0; q < 8; q++) {
        const PetscReal r = 1 - (q2[0][q & 1] + q2[1][(q >> 1) & 1] + q2[2][(q >> 2) & 1]);
        w[q]              = r > 0 ? r * r * r * vol : 0;
      }
      const PetscReal rvd = rho * (PetscReal)s->v[3 * i + d];
      if (inside) {
        const PetscInt o = c0[0] + n * (c0[1] + n * c0[2]);
        for (int q = 0; q < 8; q++) {
          if (w[q] != 0) {
            dm[d][o + st[q]] += (float)(w[q] * rho);
            dp[d][o + st[q]] += (float)(w[q] * rvd);
          }
          if (dv) dv[d][o + st[q]] += (float)(vol * lin[0][q & 1] * lin[1][(q >> 1) & 1] * lin[2][(q >> 2) & 1]);
        }
        continue;
      }
      const PetscBool intile =
          (PetscBool)(c0[0] >= -1 && c0[0] < n && c0[1] >= -1 && c0[1] < n && c0[2] >= -1 && c0[2] < n);
      for (int q = 0; q < 8; q++) {
        if (w[q] == 0 && !vv) continue;
        const PetscInt ii = c0[0] + (q & 1), jj = c0[1] + ((q >> 1) & 1), kk = c0[2] + ((q >> 2) & 1);
        /* the trilinear weight reaches faces beyond Eq. 6's sphere, where mass and momentum get nothing */
        const PetscReal val[3] = {w[q] * rho, w[q] * rvd,
                                  vol * lin[0][q & 1] * lin[1][(q >> 1) & 1] * lin[2][(q >> 2) & 1]};
        const PetscBool own    = (PetscBool)(ii >= 0 && ii < n && jj >= 0 && jj < n && kk >= 0 && kk < n);
        float *const   *dc[3]  = {dm, dp, dv};
        for (PetscInt c = 0; c < nc; c++) {
          if (c < 2 && w[q] == 0) continue;
          if (own)
            dc[c][d][ii + n * (jj + n * kk)] += (float)val[c];
          else if (intile)
            tile[(c * 3 + d) * m3 + (ii + 1) + m * ((jj + 1) + m * (kk + 1))] += (float)val[c];
          else
            *PffViewsAt(vc[c][d], ii, jj, kk, n) += (float)val[c];
        }
      }
    }
  }
  for (PetscInt c = 0; c < nc; c++)
    for (int d = 0; d < 3; d++) PffTileShell_Private(vc[c][d], n, tile + (c * 3 + d) * m3, PETSC_TRUE);
}

PetscErrorCode PffParticlesP2G(PffParticles p, const PetscReal density[PFF_PARTICLE_NTYPES], PetscInt chMass,
                               PetscInt chMom, PetscInt chVolume)
{
  PffBlockInfo   *info;
  const PffView **views;
  float         **data;
  PetscInt       *order, cstart[28] = {0};
  const PetscInt  nlocal = p->nlocal;

  PetscFunctionBeginUser;
  PetscCall(PffParticlesCheckBinned_Private(p, "PffParticlesP2G"));
  PetscCheck(chMass != chMom && chVolume != chMass && chVolume != chMom, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG,
             "P2G needs different channels for mass, momentum and volume");
  PetscCall(PffCheckFaceChannel(p->grid, chMass, "P2G mass"));
  PetscCall(PffCheckFaceChannel(p->grid, chMom, "P2G momentum"));
  if (chVolume >= 0) PetscCall(PffCheckFaceChannel(p->grid, chVolume, "P2G volume"));
  const PetscInt nv = chVolume >= 0 ? 3 : 0, stride = 6 + nv;
  PetscCall(PetscLogEventBegin(PFF_P2G, 0, 0, 0, 0));
  PetscCall(PetscMalloc4(nlocal, &info, stride * nlocal, &views, stride * nlocal, &data, nlocal, &order));
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
  PetscCall(PffZeroWithGhosts(p->grid, chMass, nlocal, info));
  PetscCall(PffZeroWithGhosts(p->grid, chMom, nlocal, info));
  if (nv) PetscCall(PffZeroWithGhosts(p->grid, chVolume, nlocal, info));

  /* blocks sorted by colour (counting sort) */
  PetscInt *colour;
  PetscCall(PetscMalloc1(nlocal, &colour));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
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
  {
    PetscInt fill[27];
    for (int c = 0; c < 27; c++) fill[c] = cstart[c];
    for (PetscInt lb = 0; lb < nlocal; lb++) order[fill[colour[lb]]++] = lb;
  }
  PetscCall(PetscFree(colour));

  const PffParticleSoA *s     = &p->s;
  const PetscInt       *start = p->start;
  const size_t          tsize = (size_t)(stride * (p->n0 + 2) * (p->n0 + 2) * (p->n0 + 2));
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
  PetscCall(PetscFree4(info, views, data, order));

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
