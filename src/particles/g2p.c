/* G2P (PF-FLIP Sec. 3.6, Eq. 11-12; DESIGN.md Sec. 4 step 6): the FLIP/PIC blend
     v_p <- alpha (v_p + I(du, x_p)) + (1 - alpha) I(u, x_p),
   alpha = alpha[type * nlevels + level of the block containing p], which lets the caller equalise
   the artificial viscosity of Eq. 13 across particle types and cell sizes (Sec. 5.3). I is the
   grid's trilinear MAC interpolation on the lattice of the particle's bin block. */
#include "particlesimpl.h"

PetscErrorCode PffParticlesG2P(PffParticles p, PetscInt chU, PetscInt chDU, const PetscReal alpha[])
{
  PetscReal     *u, *du;
  PetscInt      *blevel;
  const PetscInt n = p->n, nlevels = p->nlevels;

  PetscFunctionBeginUser;
  PetscCall(PffParticlesCheckBinned_Private(p, "PffParticlesG2P"));
  PetscCheck(alpha != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "PffParticlesG2P needs the FLIP weights alpha");
  for (PetscInt ch = 0; ch < 2; ch++) {
    PffChannelKind kind;
    const char    *name;
    PetscCall(PffGridGetChannelInfo(p->grid, ch ? chDU : chU, &name, &kind, NULL, NULL));
    PetscCheck(kind == PFF_CHANNEL_FACE, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG, "G2P channel %s must be a face channel",
               name);
  }
  PetscCall(PetscLogEventBegin(PFF_G2P, 0, 0, 0, 0));
  PetscCall(PffParticlesGetWork_Private(p, (size_t)(6 * n), &u, (size_t)p->nlocal, &blevel));
  du = u + 3 * n;
  for (PetscInt lb = 0; lb < p->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(p->grid, lb, &info));
    blevel[lb] = info.level;
  }
  /* the grid's interpolation is called from one thread: it logs events, which is not thread-safe */
  PetscCall(PffGridInterpolateFrom(p->grid, chU, n, p->s.x, p->blk, u));
  PetscCall(PffGridInterpolateFrom(p->grid, chDU, n, p->s.x, p->blk, du));
  PetscReal      *v    = p->s.v;
  const uint8_t  *type = p->s.type;
  const PetscInt *blk  = p->blk;
#pragma omp parallel for schedule(static)
  for (PetscInt i = 0; i < n; i++) {
    const PetscReal a = alpha[type[i] * nlevels + blevel[blk[i]]];
    for (int d = 0; d < 3; d++) v[3 * i + d] = a * (v[3 * i + d] + du[3 * i + d]) + (1 - a) * u[3 * i + d];
  }
  PetscCall(PetscLogEventEnd(PFF_G2P, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}
