/* Binning (DESIGN.md Sec. 6): a stable counting sort of the local particles by owned block, so the
   particles of local block lb are contiguous, [start[lb], start[lb + 1]). This gives cache-coherent
   traversal and the per-block work lists of the 8-colour lock-free P2G. The sort runs in threads over
   contiguous chunks whose offsets keep the chunks in order, so its result does not depend on the
   thread count (bit-exact restarts rely on the order). */
#include "particlesimpl.h"
#include <omp.h>

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
#pragma omp          parallel for reduction(+ : nbad) schedule(static)
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
  /* stable counting sort in threads: each thread counts and then scatters its own contiguous chunk,
     from offsets that put the chunks in order, so the result is the serial sort's */
  PetscInt      *start = p->start, *counts;
  const PetscInt nl = p->nlocal, nt = (PetscInt)PetscMax(omp_get_max_threads(), 1);
  PetscCall(PetscCalloc1((size_t)nt * (size_t)(nl + 1), &counts));
  PffParticleSoA *s = &p->s, *t = &p->tmp;
         #pragma omp parallel num_threads(nt)
  {
             const PetscInt th = omp_get_thread_num(), nth = omp_get_num_threads(), i0 = n * th / nth, i1 = n * (th + 1) / nth;
             PetscInt      *c = counts + (size_t)th * (size_t)(nl + 1);
             for (PetscInt i = i0; i < i1; i++) c[blk[i]]++;
#pragma omp barrier
#pragma omp          single
    {
      /* counts[th][lb] becomes the first slot of thread th's particles of block lb */
      PetscInt off = 0;
      for (PetscInt lb = 0; lb < nl; lb++) {
                 start[lb] = off;
                 for (PetscInt q = 0; q < nth; q++) {
                   PetscInt *cq = counts + (size_t)q * (size_t)(nl + 1), m = cq[lb];
                   cq[lb] = off;
                   off += m;
        }
      }
      start[nl] = off;
    }
    for (PetscInt i = i0; i < i1; i++) {
               const PetscInt j = c[blk[i]]++;
               for (int d = 0; d < 3; d++) {
                 t->x[3 * j + d] = s->x[3 * i + d];
                 t->v[3 * j + d] = s->v[3 * i + d];
      }
               t->id[j]    = s->id[i];
               t->type[j]  = s->type[i];
               t->level[j] = s->level[i];
               t->flags[j] = s->flags[i];
    }
  }
  PetscCall(PetscFree(counts));
  const PffParticleSoA swap = p->s;
  p->s                      = p->tmp;
  p->tmp                    = swap;
#pragma omp parallel for schedule(dynamic, 4)
  for (PetscInt lb = 0; lb < p->nlocal; lb++)
    for (PetscInt i = start[lb]; i < start[lb + 1]; i++) blk[i] = lb;
  p->binned = PETSC_TRUE;
  PetscCall(PetscLogEventEnd(PFF_PartBin, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}
