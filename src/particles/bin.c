/* Binning (DESIGN.md Sec. 6): a stable counting sort of the local particles by owned block, so the
   particles of local block lb are contiguous, [start[lb], start[lb + 1]). This gives cache-coherent
   traversal and the per-block work lists of the 8-colour lock-free P2G. */
#include "particlesimpl.h"

/* Refreshes the owned-block tables (the grid may have been re-partitioned since the last call). */
static PetscErrorCode PffParticlesUpdateBlocks(PffParticles p)
{
  PetscInt nlocal, nblocks = p->nb[0] * p->nb[1] * p->nb[2];

  PetscFunctionBeginUser;
  PetscCall(PffGridGetLocalBlocks(p->grid, &nlocal));
  if (p->start == NULL || nlocal != p->nlocal) {
    PetscCall(PetscFree(p->start));
    PetscCall(PetscFree(p->lgid));
    PetscCall(PetscMalloc1(nlocal + 1, &p->start));
    PetscCall(PetscMalloc1(PetscMax(nlocal, 1), &p->lgid));
    p->nlocal = nlocal;
  }
  if (p->local == NULL) PetscCall(PetscMalloc1(nblocks, &p->local));
  for (PetscInt b = 0; b < nblocks; b++) p->local[b] = -1;
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(p->grid, lb, &info));
    p->lgid[lb]        = info.gid;
    p->local[info.gid] = lb;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffParticlesBin(PffParticles p)
{
  const PetscInt *level;
  PetscInt        nb[3], nbad = 0;
  const PetscInt  n = p->n;

  PetscFunctionBeginUser;
  PetscCall(PetscLogEventBegin(PFF_PartBin, 0, 0, 0, 0));
  PetscCall(PffParticlesUpdateBlocks(p));
  PetscCall(PffGridGetRaster(p->grid, nb, &level, NULL));
  PetscCall(PffParticlesReserve_Private(p, n));
  PetscInt *blk = p->blk, *local = p->local;
#pragma omp parallel for reduction(+ : nbad) schedule(static)
  for (PetscInt i = 0; i < n; i++) {
    const PetscInt gid = PffParticlesLocate_Private(p, &p->s.x[3 * i], level);
    blk[i]             = gid >= 0 ? local[gid] : -1;
    if (blk[i] < 0) nbad++;
  }
  if (nbad > 0) {
    PetscInt i = 0;
    while (blk[i] >= 0) i++;
    SETERRQ(PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
            "%" PetscInt_FMT " particles are not in a block owned by rank %d, e.g. id %" PetscInt64_FMT
            " at (%g, %g, %g): call PffParticlesMigrate",
            nbad, (int)p->rank, (PetscInt64)p->s.id[i], (double)p->s.x[3 * i], (double)p->s.x[3 * i + 1],
            (double)p->s.x[3 * i + 2]);
  }
  PetscInt *start = p->start;
  PetscCall(PetscArrayzero(start, p->nlocal + 1));
  for (PetscInt i = 0; i < n; i++) start[blk[i] + 1]++;
  for (PetscInt lb = 0; lb < p->nlocal; lb++) start[lb + 1] += start[lb];
  /* stable scatter; start[lb] runs ahead and is restored below */
  PffParticleSoA *s = &p->s, *t = &p->tmp;
  for (PetscInt i = 0; i < n; i++) {
    const PetscInt j = start[blk[i]]++;
    for (int d = 0; d < 3; d++) {
      t->x[3 * j + d] = s->x[3 * i + d];
      t->v[3 * j + d] = s->v[3 * i + d];
    }
    t->id[j]    = s->id[i];
    t->type[j]  = s->type[i];
    t->level[j] = s->level[i];
    t->flags[j] = s->flags[i];
  }
  for (PetscInt lb = p->nlocal; lb > 0; lb--) start[lb] = start[lb - 1];
  start[0]                  = 0;
  const PffParticleSoA swap = p->s;
  p->s                      = p->tmp;
  p->tmp                    = swap;
  for (PetscInt lb = 0; lb < p->nlocal; lb++)
    for (PetscInt i = start[lb]; i < start[lb + 1]; i++) blk[i] = lb;
  p->binned = PETSC_TRUE;
  PetscCall(PetscLogEventEnd(PFF_PartBin, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}
