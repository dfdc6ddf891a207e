/* G2P (PF-FLIP Sec. 3.6, Eq. 11-12; DESIGN.md Sec. 4 step 6): the FLIP/PIC blend
     v_p <- alpha (v_p + I(du, x_p)) + (1 - alpha) I(u, x_p),
   alpha = alpha[type * nlevels + level of the block containing p], which lets the caller equalise
   the artificial viscosity of Eq. 13 across particle types and cell sizes (Sec. 5.3). I is the
   grid's trilinear MAC interpolation on the lattice of the particle's bin block.

   Block-batched (issue 12): threads take whole blocks, and per particle and component one set of
   trilinear weights serves both u and du (PffSamplerFace_Private); the result is bit-identical to
   interpolating u and du separately with PffGridInterpolateFrom(). */
#include "particlesimpl.h"

PetscErrorCode PffParticlesG2P(PffParticles p, PetscInt chU, PetscInt chDU, const PetscReal alpha[])
{
  const PetscInt ch[2] = {chU, chDU};
  PffSampler     s;

  PetscFunctionBeginUser;
  PetscCall(PffParticlesCheckBinned_Private(p, "PffParticlesG2P"));
  PetscCheck(alpha != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "PffParticlesG2P needs the FLIP weights alpha");
  PetscCall(PetscLogEventBegin(PFF_G2P, 0, 0, 0, 0));
  PetscCall(PffSamplerCreate_Private(p, 2, ch, &s));
  const float    *x       = p->s.x;
  float          *v       = p->s.v;
  const uint32_t *word    = p->s.word;
  const PetscInt  nlevels = p->nlevels;
#pragma omp parallel for schedule(dynamic, 1)
  for (PetscInt lb = 0; lb < p->nlocal; lb++) {
    const PffSampleBlock *b = &s.blocks[lb];
    for (PetscInt i = p->start[lb]; i < p->start[lb + 1]; i++) {
      const PetscReal a    = alpha[PffParticleWordType(word[i]) * nlevels + b->level];
      const PetscReal g[3] = {x[3 * i], x[3 * i + 1], x[3 * i + 2]};
      PetscReal       lp[3], uv[2];
      PffSamplerLocal_Private(p, b, g, lp);
      for (PetscInt d = 0; d < 3; d++) {
        PffSamplerFace_Private(&s, lb, 0, 2, d, lp, uv);
        v[3 * i + d] = (float)(a * ((PetscReal)v[3 * i + d] + uv[1]) + (1 - a) * uv[0]);
      }
    }
  }
  PetscCall(PffSamplerDestroy_Private(&s));
  PetscCall(PetscLogEventEnd(PFF_G2P, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}
