/* Cell-channel values at the particles (the escaped-particle stage reads the phase field there):
   block by block in threads, through ghost tiles of one layer and chunks of PFF_CHUNK particles in
   float, like G2P, clamped at walls and holes as the grid's general path does. */
#include "particlesimpl.h"

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
    if (!PffSamplerBlockTiles_Private(p, &s, lb, &tb)) continue;
    const PffSampleBlock *b  = &tb;
    const PetscInt        i1 = p->start[lb + 1], n = b->n, mm = n + 2;
    int32_t               st[8];
    float                 lo[3], ih;
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
      if (b->hole) { /* the grid's clamping at walls and holes */
        PffChunkClamp_Private(b, m, -1, c, tt, cc, tc);
        for (int e = 0; e < 3; e++) {
          c[e]  = cc[e];
          tt[e] = tc[e];
        }
      }
      const int32_t *restrict cx = c[0], *restrict cy = c[1], *restrict cz = c[2];
      const float *restrict tx = tt[0], *restrict ty = tt[1], *restrict tz = tt[2], *t = b->tile[0][0];
      float   w[PFF_CHUNK]; /* val's address goes to fn: gathers into it would not vectorise */
      int32_t o[PFF_CHUNK];
      for (PetscInt j = 0; j < m; j++) o[j] = (cx[j] + 1) + (int32_t)mm * ((cy[j] + 1) + (int32_t)mm * (cz[j] + 1));
      for (PetscInt j = PffTrilinearChunk16_Private(t, o, st, tx, ty, tz, m, w); j < m; j++)
        w[j] = PffTrilinear_Private(t, o[j], st, tx[j], ty[j], tz[j]);
      memcpy(val, w, sizeof(float) * (size_t)m);
      fn(j0, m, val, ctx);
    }
  }
  PetscCall(PffSamplerDestroy_Private(&s));
  PetscFunctionReturn(PETSC_SUCCESS);
}
