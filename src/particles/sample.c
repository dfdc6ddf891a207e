/* The block table of PffSampler (particlesimpl.h): G2P and advection sample face channels through it.
   Also the ghost shell of a block tile, which P2G sums into. */
#include "particlesimpl.h"
#include <omp.h>

void PffTileShell_Private(const PffView *views, PetscInt n, PetscInt gw, float *tile, PetscBool add)
{
  const PetscInt m = n + 2 * gw;
  for (PetscInt kk = -gw; kk < n + gw; kk++)
    for (PetscInt jj = -gw; jj < n + gw; jj++) {
      const PetscBool inner = (PetscBool)(jj >= 0 && jj < n && kk >= 0 && kk < n);
      for (PetscInt ii = -gw; ii < n + gw; ii += (inner && ii == -1) ? n + 1 : 1) {
        float *t = &tile[(ii + gw) + m * ((jj + gw) + m * (kk + gw))];
        if (!add)
          *t = *PffViewsAt(views, ii, jj, kk, n);
        else if (*t != 0)
          *PffViewsAt(views, ii, jj, kk, n) += *t;
      }
    }
}

PetscErrorCode PffSamplerCreate_Private(PffParticles p, PetscInt nch, const PetscInt ch[], PetscInt gw, PffSampler *s)
{
  PetscFunctionBeginUser;
  PetscCheck(nch >= 1 && nch <= 2, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "a sampler takes 1 or 2 channels");
  s->grid = p->grid;
  s->nch  = nch;
  s->gw   = gw;
  for (PetscInt k = 0; k < nch; k++) {
    PffChannelKind kind;
    PetscInt       width;
    const char    *name;
    PetscCall(PffGridGetChannelInfo(p->grid, ch[k], &name, &kind, NULL, &width));
    PetscCheck(kind == PFF_CHANNEL_FACE || kind == PFF_CHANNEL_CELL, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG,
               "channel %s must be a face or cell channel", name);
    if (k == 0) s->ncomp = kind == PFF_CHANNEL_FACE ? 3 : 1;
    PetscCheck((kind == PFF_CHANNEL_FACE ? 3 : 1) == s->ncomp, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG,
               "the channels of a sampler must be of one kind (%s is not)", name);
    /* a point in its block reaches one cell beyond it, and the tiles hold gw ghost layers */
    PetscCheck(width >= PetscMax(gw, 1), PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG,
               "channel %s needs a halo of at least %" PetscInt_FMT " cells", name, PetscMax(gw, 1));
    s->ch[k] = ch[k];
  }
  {
    const size_t bytes[2] = {sizeof(PffSampleBlock) * (size_t)p->nlocal,
                             sizeof(const PffView *) * 6 * (size_t)p->nlocal};
    void        *ptrs[2];
    PetscCall(PffParticlesGetScratch_Private(p, PFF_SCRATCH_SAMPLER, 2, bytes, ptrs));
    s->blocks = (PffSampleBlock *)ptrs[0];
    s->views  = (const PffView **)ptrs[1];
  }
  /* tiles for every block, built by the thread that works on the block into its own buffer
     (PffSamplerBlockTiles_Private): scratch per thread, not per block, and cache-hot when used. Where a stencil
     keeps off the block's wall and hole sides, the grid's general path is a plain trilinear stencil over the
     views, which the tile holds value for value; the stencils that reach such a side take the general path, which
     clamps there (hole bits). */
  for (PetscInt lb = 0; lb < p->nlocal; lb++) {
    PffBlockInfo    info;
    PffSampleBlock *b = &s->blocks[lb];
    PetscCall(PffGridGetBlockInfo(p->grid, lb, &info));
    b->n     = info.n;
    b->level = info.level;
    b->hole  = 0;
    b->holes = info.holes;
    for (PetscInt r = 0; r < 27; r++) {
      PetscInt d[3];
      PffRegionDirection(r, d);
      /* the clamps of PffStencilClamped for a stencil that crosses the sides d: every hole region among the
         regions it reaches clamps the axes it steps across */
      b->clamp[r] = 0;
      for (int q = 1; q < 8; q++) {
        PetscInt rq = 13;
        for (int a = 0, w = 1; a < 3; a++, w *= 3)
          if ((q >> a) & 1) rq += d[a] * w;
        if (rq == 13 || !((info.holes >> rq) & 1)) continue;
        for (int a = 0; a < 3; a++)
          if (((q >> a) & 1) && d[a]) b->clamp[r] |= 1 << (2 * a + (d[a] > 0));
      }
      if (!((info.holes >> r) & 1)) continue;
      for (int a = 0; a < 3; a++)
        if (d[a]) b->hole |= 1u << (2 * a + (d[a] > 0));
    }
    for (int d = 0; d < 3; d++) b->ijk[d] = info.ijk[d];
    for (PetscInt k = 0; k < 2; k++)
      for (int d = 0; d < 3; d++) {
        b->data[k][d]                = NULL;
        b->tile[k][d]                = NULL;
        s->views[6 * lb + 3 * k + d] = NULL;
      }
    for (PetscInt k = 0; k < nch; k++)
      for (int d = 0; d < s->ncomp; d++) {
        float *data;
        PetscCall(PffGridGetBlockData(p->grid, ch[k], lb, d, &data));
        b->data[k][d] = data;
        PetscCall(PffGridGetBlockViews(p->grid, ch[k], lb, d, &s->views[6 * lb + 3 * k + d]));
      }
  }
  const PetscInt m = p->n0 + 2 * gw;
  s->tstride       = (size_t)(s->ncomp * nch) * (size_t)(m * m * m);
  PetscCall(PffParticlesGetFloatWork_Private(p, s->tstride * (size_t)PetscMax(omp_get_max_threads(), 1), &s->tiles));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscBool PffSamplerBlockTiles_Private(PffParticles p, const PffSampler *s, PetscInt lb, unsigned need,
                                       PffSampleBlock *tb)
{
  const PetscInt gw = s->gw;

  if (p->start[lb] == p->start[lb + 1]) return PETSC_FALSE;
  *tb              = s->blocks[lb];
  const PetscInt n = tb->n, m = n + 2 * gw;
  float         *base = s->tiles + s->tstride * (size_t)omp_get_thread_num();
  for (PetscInt k = 0; k < s->nch; k++)
    for (PetscInt d = 0; d < s->ncomp; d++) {
      float *tile    = base + (size_t)(k * s->ncomp + d) * (size_t)(m * m * m);
      tb->tile[k][d] = tile;
      if (!((need >> k) & 1)) continue;
      /* the own cells row by row from the block's array, the ghost shell from the views */
      for (PetscInt kk = 0; kk < n; kk++)
        for (PetscInt jj = 0; jj < n; jj++)
          memcpy(&tile[gw + m * ((jj + gw) + m * (kk + gw))], &tb->data[k][d][n * (jj + n * kk)],
                 sizeof(float) * (size_t)n);
      PffTileShell_Private(s->views[6 * lb + 3 * k + d], n, gw, tile, PETSC_FALSE);
    }
  return PETSC_TRUE;
}

PetscErrorCode PffSamplerDestroy_Private(PffSampler *s)
{
  PetscFunctionBeginUser;
  s->blocks = NULL; /* the particles' scratch */
  s->views  = NULL;
  s->tiles  = NULL; /* the particles' float scratch */
  PetscFunctionReturn(PETSC_SUCCESS);
}
