/* Cell-channel values at the particles (the escaped-particle stage reads the phase field there):
   block by block in threads, through ghost tiles of one layer and chunks of PFF_CHUNK particles in
   float, like G2P, clamped at walls and holes as the grid's general path does. A block whose tile holds
   one value passes that value to each of its particles. */
#include "particlesimpl.h"

/* Whether the m values of a tile are one number (not NaN). Most blocks of a scene lie inside one phase, where the
   phase field is 0 or 1 on the whole tile: their particles take that value as it is, without the interpolation,
   which would give it rounded by the weights' sum (a few 1e-8). */
static PetscBool PffTileConstant(const float *restrict t, PetscInt m)
{
  const float c   = t[0];
  int         off = c != c;
#pragma omp simd reduction(| : off)
  for (PetscInt q = 0; q < m; q++) off |= t[q] != c;
  return off ? PETSC_FALSE : PETSC_TRUE;
}

PetscErrorCode PffParticlesInterpolateCell(PffParticles p, PetscInt ch, PffParticleCellFn fn, void *ctx)
{
  PffSampler s;

  PetscFunctionBeginUser;
  PetscCall(PffParticlesCheckBinned_Private(p, "PffParticlesInterpolateCell"));
  PetscCheck(fn != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "PffParticlesInterpolateCell needs a callback");
  PetscCall(PffSamplerCreate_Private(p, 1, &ch, 1, &s));
  PetscCheck(s.ncomp == 1, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG, "PffParticlesInterpolateCell needs a cell channel");
  const float *x = p->s.x;
#pragma omp parallel for schedule(dynamic, 1)
  for (PetscInt lb = 0; lb < p->nlocal; lb++) {
    PffSampleBlock tb;
    if (!PffSamplerBlockTiles_Private(p, &s, lb, ~0u, &tb)) continue;
    const PffSampleBlock *b  = &tb;
    const PetscInt        i1 = p->start[lb + 1], n = b->n, mm = n + 2;
    int32_t               st[8];
    float                 lo[3], ih;
    if (PffTileConstant(b->tile[0][0], mm * mm * mm)) { /* every stencil of the block reads one value */
      float val[PFF_CHUNK];
      for (PetscInt j = 0; j < PFF_CHUNK; j++) val[j] = b->tile[0][0][0];
      for (PetscInt j0 = p->start[lb]; j0 < i1; j0 += PFF_CHUNK) fn(j0, PetscMin(PFF_CHUNK, i1 - j0), val, ctx);
      continue;
    }
    PffTileCorners_Private((int32_t)mm, st);
    PffBlockCorner_Private(p->n0, b->ijk, b->level, lo, &ih);
    for (PetscInt j0 = p->start[lb]; j0 < i1; j0 += PFF_CHUNK) {
      const PetscInt m = PetscMin(PFF_CHUNK, i1 - j0);
      float          val[PFF_CHUNK];
      /* cell centres: the half lattice on every axis */
      PffChunkLattice L;
      PffChunkLattice_Private(&x[3 * j0], m, lo, ih, n, &L);
      const int32_t *c[3]  = {L.ih[0], L.ih[1], L.ih[2]};
      const float   *tt[3] = {L.th[0], L.th[1], L.th[2]};
      int32_t        cc[3][PFF_CHUNK];
      float          tc[3][PFF_CHUNK];
      PffChunkClampHoles_Private(b, m, -1, c, tt, cc, tc); /* the grid's clamping at walls and holes */
      float   w[PFF_CHUNK]; /* val's address goes to fn: gathers into it would not vectorise */
      int32_t o[PFF_CHUNK];
      PffChunkOffsets_Private((int32_t)mm, 1, c, m, o);
      PffTrilinearChunk_Private(b->tile[0][0], o, st, tt[0], tt[1], tt[2], m, w);
      memcpy(val, w, sizeof(float) * (size_t)m);
      fn(j0, m, val, ctx);
    }
  }
  PetscCall(PffSamplerDestroy_Private(&s));
  PetscFunctionReturn(PETSC_SUCCESS);
}
