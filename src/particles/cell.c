/* Cell-channel values at the particles (the escaped-particle stage reads the phase field there):
   block by block in threads, through ghost tiles of one layer and chunks of PFF_CHUNK particles in
   float, like G2P; blocks beside walls or holes go point by point through the grid's general path. */
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
    if (p->start[lb] == p->start[lb + 1]) continue;
    PffSamplerBlockTiles_Private(&s, lb, &tb);
    const PffSampleBlock *b  = &tb;
    const PetscInt        i1 = p->start[lb + 1], n = b->n, mm = n + 2;
    const PetscInt        st[8] = {0, 1, mm, mm + 1, mm * mm, mm * mm + 1, mm * mm + mm, mm * mm + mm + 1};
    const float           ih    = 1.0f / (float)((PetscInt)1 << b->level);
    const float           lo[3] = {(float)(b->ijk[0] * p->n0), (float)(b->ijk[1] * p->n0), (float)(b->ijk[2] * p->n0)};
    for (PetscInt j0 = p->start[lb]; j0 < i1; j0 += PFF_CHUNK) {
      const PetscInt m = PetscMin(PFF_CHUNK, i1 - j0);
      float          val[PFF_CHUNK];
      if (b->tile[0][0]) {
        /* cell centres: the half lattice on every axis */
        PffChunkLattice L;
        PffChunkLattice_Private(&x[3 * j0], m, lo, ih, n, &L);
        const int32_t *restrict cx = L.ih[0], *restrict cy = L.ih[1], *restrict cz = L.ih[2];
        const float *restrict tx = L.th[0], *restrict ty = L.th[1], *restrict tz = L.th[2], *restrict t = b->tile[0][0];
        for (PetscInt j = 0; j < m; j++) {
          const int32_t o  = (cx[j] + 1) + (int32_t)mm * ((cy[j] + 1) + (int32_t)mm * (cz[j] + 1));
          const float   x1 = tx[j], y1 = ty[j], z1 = tz[j], x0 = 1 - x1, y0 = 1 - y1, z0 = 1 - z1;
          val[j] = z0 * (y0 * (x0 * t[o + st[0]] + x1 * t[o + st[1]]) + y1 * (x0 * t[o + st[2]] + x1 * t[o + st[3]])) +
                   z1 * (y0 * (x0 * t[o + st[4]] + x1 * t[o + st[5]]) + y1 * (x0 * t[o + st[6]] + x1 * t[o + st[7]]));
        }
      } else {
        for (PetscInt j = 0; j < m; j++) {
          const PetscReal g[3] = {x[3 * (j0 + j)], x[3 * (j0 + j) + 1], x[3 * (j0 + j) + 2]};
          PetscReal       lp[3];
          PffSamplerLocal_Private(p, b, g, lp);
          val[j] = (float)PffGridInterpolateInBlock(p->grid, ch, lb, 0, lp);
        }
      }
      fn(j0, m, val, ctx);
    }
  }
  PetscCall(PffSamplerDestroy_Private(&s));
  PetscFunctionReturn(PETSC_SUCCESS);
}
