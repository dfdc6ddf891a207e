/* Initial and analytic fields: a function of the sample position evaluated at every owned value,
   each MAC component on its own staggered lattice (PffChannelOffset_Private). */
#include "gridimpl.h"

PetscErrorCode PffGridFillChannel(PffGrid g, PetscInt ch, PffFieldFn fn, void *ctx)
{
  PffChannel *c = NULL;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetChannel_Private(g, ch, &c));
  for (PetscInt lb = 0; lb < g->nlocal; lb++) {
    const PetscInt  gid = g->lgid[lb], l = g->level[gid], n = g->n0 >> l;
    const PetscReal h = g->h0 * (PetscReal)((PetscInt)1 << l);
    PetscInt        ijk[3];
    PffGridBlockIJK_Private(g, gid, ijk);
    for (PetscInt comp = 0; comp < c->ncomp; comp++) {
      float    *v = c->data + c->ncomp * g->loff[lb] + comp * n * n * n;
      PetscReal lo[3], o[3];
      for (int a = 0; a < 3; a++) {
        lo[a] = g->origin[a] + (PetscReal)(ijk[a] * g->n0) * g->h0; /* as PffGridGetBlockInfo */
        o[a]  = PffChannelOffset_Private(c->kind, comp, a);
      }
      for (PetscInt k = 0; k < n; k++)
        for (PetscInt j = 0; j < n; j++)
          for (PetscInt i = 0; i < n; i++) {
            const PetscReal x[3]   = {lo[0] + ((PetscReal)i + o[0]) * h, lo[1] + ((PetscReal)j + o[1]) * h,
                                      lo[2] + ((PetscReal)k + o[2]) * h};
            v[i + n * (j + n * k)] = (float)fn(x, comp, ctx);
          }
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
