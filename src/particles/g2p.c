/* G2P (PF-FLIP Sec. 3.6, Eq. 11-12; DESIGN.md Sec. 4 step 6): the FLIP/PIC blend
     v_p <- alpha (v_p + I(du, x_p)) + (1 - alpha) I(u, x_p),
   alpha = alpha[type * nlevels + level of the block containing p], which lets the caller equalise
   the artificial viscosity of Eq. 13 across particle types and cell sizes (Sec. 5.3). I is the
   grid's trilinear MAC interpolation on the lattice of the particle's bin block.

   Block-batched (issue 12): threads take whole blocks, and every stencil of a block's particles lies in
   its ghost tiles, so chunks of particles are interpolated in float without a branch
   (PffChunkLattice_Private locates the lattices once per chunk and serves u and du). In a block beside
   a wall or hole the lattices are first clamped there as the grid's general path does
   (PffChunkClamp_Private). With AVX-512 the corners come by 64-bit gathers of x pairs
   (PffTrilinear16_Private), half the gathered elements, with the same arithmetic. */
#include "particlesimpl.h"

PetscErrorCode PffParticlesG2P(PffParticles p, PetscInt chU, PetscInt chDU, const PetscReal alpha[])
{
  const PetscInt ch[2] = {chU, chDU};
  PffSampler     s;

  PetscFunctionBeginUser;
  PetscCall(PffParticlesCheckBinned_Private(p, "PffParticlesG2P"));
  PetscCheck(alpha != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "PffParticlesG2P needs the FLIP weights alpha");
  PetscCall(PetscLogEventBegin(PFF_G2P, 0, 0, 0, 0));
  PetscCall(PffSamplerCreate_Private(p, 2, ch, 1, &s));
  const float    *x       = p->s.x;
  float          *v       = p->s.v;
  const uint32_t *word    = p->s.word;
  const PetscInt  nlevels = p->nlevels;
#pragma omp parallel for schedule(dynamic, 1)
  for (PetscInt lb = 0; lb < p->nlocal; lb++) {
    PffSampleBlock tb;
    if (!PffSamplerBlockTiles_Private(p, &s, lb, ~0u, &tb)) continue;
    const PffSampleBlock *b  = &tb;
    const PetscInt        i0 = p->start[lb], i1 = p->start[lb + 1];
    /* every stencil of a binned particle lies in the tiles: chunks of particles, float weights, no branch */
    const PetscInt n = b->n, mm = n + 2;
    int32_t        st[8];
    float          lo[3], ih;
    PffTileCorners_Private((int32_t)mm, st);
    PffBlockCorner_Private(p->n0, b->ijk, b->level, lo, &ih);
    for (PetscInt j0 = i0; j0 < i1; j0 += PFF_CHUNK) {
      const PetscInt  m = PetscMin(PFF_CHUNK, i1 - j0);
      float           a[PFF_CHUNK];
      PffChunkLattice L;
      for (PetscInt j = 0; j < m; j++) a[j] = (float)alpha[PffParticleWordType(word[j0 + j]) * nlevels + b->level];
      PffChunkLattice_Private(&x[3 * j0], m, lo, ih, n, &L);
      for (int d = 0; d < 3; d++) {
        const int32_t *c[3];
        const float   *t[3], *tu = b->tile[0][d], *tdu = b->tile[1][d];
        int32_t        cc[3][PFF_CHUNK];
        float          tc[3][PFF_CHUNK];
        PffChunkLatticeOf_Private(&L, d, c, t);
        PffChunkClampHoles_Private(b, m, d, c, t, cc, tc); /* the grid's clamping at walls and holes */
        float   ur[PFF_CHUNK], dr[PFF_CHUNK];
        int32_t o[PFF_CHUNK];
        PffChunkOffsets_Private((int32_t)mm, 1, c, m, o);
        const float *restrict tx = t[0], *restrict ty = t[1], *restrict tz = t[2];
        const PetscInt j16 = PffTrilinearChunk16_Private(tu, o, st, tx, ty, tz, m, ur);
        PffTrilinearChunk16_Private(tdu, o, st, tx, ty, tz, m, dr);
        for (PetscInt j = j16; j < m; j++) {
          ur[j] = PffTrilinear_Private(tu, o[j], st, tx[j], ty[j], tz[j]);
          dr[j] = PffTrilinear_Private(tdu, o[j], st, tx[j], ty[j], tz[j]);
        }
        float *vd = &v[3 * j0 + d];
        for (PetscInt j = 0; j < m; j++) vd[3 * j] = a[j] * (vd[3 * j] + dr[j]) + (1 - a[j]) * ur[j];
      }
    }
  }
  PetscCall(PffSamplerDestroy_Private(&s));
  PetscCall(PetscLogEventEnd(PFF_G2P, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}
