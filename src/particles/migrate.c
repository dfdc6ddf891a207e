/* Migration (DESIGN.md Sec. 4 step 9, Sec. 6): every particle goes to the rank that owns the block
   containing it. Periodic axes are wrapped and walled axes clamped first (so nothing leaves the
   domain), then counts by destination are exchanged (MPI_Alltoall) and the particles themselves in
   one MPI_Alltoallv of packed records (the store's fields back to back, PFF_PARTICLE_BYTES). Kept particles stay in
   order, received ones are appended in rank order, then everything is binned by the local blocks found here (no second
   locate). The leavers stay in the store until the binning, which drops them (PFF_SORT_DROP): compacting the
   stayers here moved every particle behind the first leaver, serially, before the sort moved them again. Nothing is
   created or lost: a particle in an inactive block is an error, so the global count and mass per type are invariant. */
#include "particlesimpl.h"
#include <omp.h>

/* Wraps or clamps particle i and sets dest[i] (see PffParticlesMigrate), counting into the caller's sums. */
static inline void PffMigrateLocate(PffParticles p, PetscInt i, const PetscInt level[], const PetscMPIInt owner[],
                                    const PetscInt local[], int32_t dest[], PetscInt64 *sent, PetscInt64 *wrapped,
                                    PetscInt64 *clamped, PetscInt *nbad)
{
  PetscBool w, c;
  PffParticlesWrapClamp_Private(p, &p->s.x[3 * i], &w, &c);
  *wrapped += w;
  *clamped += c;
  const PetscInt gid = PffParticlesLocate_Private(p, &p->s.x[3 * i], level);
  if (gid < 0) {
    dest[i] = -1;
    (*nbad)++;
  } else if (owner[gid] == p->rank)
    dest[i] = (int32_t)local[gid];
  else {
    dest[i] = -2 - (int32_t)owner[gid];
    (*sent)++;
  }
}

PetscErrorCode PffParticlesMigrate(PffParticles p, PffParticleStats *stats)
{
  const PetscInt    *level;
  const PetscMPIInt *owner;
  PetscInt           nb[3], nbad = 0;
  PetscInt64         loc[3] = {0, 0, 0}; /* sent, wrapped, clamped */
  const PetscInt     n      = p->n;
  int32_t           *dest;

  PetscFunctionBeginUser;
  PetscCall(PetscLogEventBegin(PFF_PartMigrate, 0, 0, 0, 0));
  PetscCall(PffGridGetRaster(p->grid, nb, &level, &owner));
  const PetscBool  wasBinned = p->binned;
  PetscBool        changed;
  PetscInt         nold = 0, *oldStart = NULL, *oldGid = NULL;
  PetscObjectState state;
  PetscCall(PffGridGetTopologyState(p->grid, &state));
  if (wasBinned && p->topology != state) { /* the bins of the raster before the change (PffParticlesReset keeps them) */
    nold = p->nlocal;
    PetscCall(PetscMalloc2(nold + 1, &oldStart, PetscMax(nold, 1), &oldGid));
    PetscCall(PetscArraycpy(oldStart, p->start, nold + 1));
    PetscCall(PetscArraycpy(oldGid, p->lgid, nold));
  }
  PetscCall(PffParticlesUpdateBlocks_Private(p, &changed));
  PetscCall(PffParticlesGetIntWork_Private(p, (size_t)n + 1, &dest));
  const PetscInt *local = p->local;
  /* dest[i]: the local block of a particle that stays (the binning's input, so it locates nothing
     again), -2 - r for one that goes to rank r, -1 outside every active block */
  PetscInt64 sent = 0, wrapped = 0, clamped = 0;
  if (wasBinned && !changed && p->start[p->nlocal] == n) {
    /* a particle still inside the raster cell of its bin's block (most of them after an advection step) is left
       alone by the wrap and the clamp and stays in that block: a box test instead of both and the locate. The
       particles that stay in their bin's block are flagged for the one-thread sort, which moves them in place. */
    const int32_t stays = omp_get_max_threads() == 1 ? PFF_SORT_STAYS : 0;
#pragma omp parallel for reduction(+ : sent, wrapped, clamped, nbad) schedule(dynamic, 4)
    for (PetscInt lb = 0; lb < p->nlocal; lb++) {
      PetscInt ijk[3];
      PffRasterCoordinates(nb, p->lgid[lb], ijk);
      float lo[3], hi[3];
      for (int a = 0; a < 3; a++) {
        lo[a] = ijk[a] == 0 ? PFF_PARTICLE_WALL_LO : (float)(ijk[a] * p->n0);
        hi[a] = (float)((ijk[a] + 1) * p->n0);
      }
      /* the box test in a branch-free loop that vectorises (as a branch per particle it was 3 % of the uniform
         rt3d step), then the locate for the few outside */
      const int32_t      in = (int32_t)lb | stays;
      const PetscInt     i0 = p->start[lb], i1 = p->start[lb + 1];
      const float *const xs = p->s.x;
      for (PetscInt i = i0; i < i1; i++) {
        const float *x = &xs[3 * i];
        const int    inside =
            (x[0] >= lo[0]) & (x[0] < hi[0]) & (x[1] >= lo[1]) & (x[1] < hi[1]) & (x[2] >= lo[2]) & (x[2] < hi[2]);
        dest[i] = inside ? in : PFF_SORT_DROP;
      }
      for (PetscInt i = i0; i < i1; i++) {
        if (dest[i] != PFF_SORT_DROP) continue;
        PffMigrateLocate(p, i, level, owner, local, dest, &sent, &wrapped, &clamped, &nbad);
        if (dest[i] == (int32_t)lb) dest[i] |= stays;
      }
    }
  } else if (oldStart && oldStart[nold] == n) {
    /* after a topology change: a bin's particles lie in its block's raster cell, which kept its place whatever its
       level or owner now, so they go where that block went, without a locate. With one thread they are flagged for
       the in-place sort when the blocks that stay here kept their order (their destinations then grow with their
       places): most of the store then stays where it is. */
    PetscBool monotone = PETSC_TRUE;
    for (PetscInt lb = 0, last = -1; lb < nold; lb++) {
      const PetscInt gid = oldGid[lb];
      if (level[gid] < 0 || owner[gid] != p->rank) continue;
      if (local[gid] < last) monotone = PETSC_FALSE;
      last = local[gid];
    }
    const int32_t stays = omp_get_max_threads() == 1 && monotone ? PFF_SORT_STAYS : 0;
#pragma omp parallel for reduction(+ : sent, wrapped, clamped, nbad) schedule(dynamic, 4)
    for (PetscInt lb = 0; lb < nold; lb++) {
      const PetscInt gid = oldGid[lb], i0 = oldStart[lb], i1 = oldStart[lb + 1];
      if (level[gid] < 0) /* the block is gone: the locate reports its particles */
        for (PetscInt i = i0; i < i1; i++)
          PffMigrateLocate(p, i, level, owner, local, dest, &sent, &wrapped, &clamped, &nbad);
      else if (owner[gid] == p->rank)
        for (PetscInt i = i0; i < i1; i++) dest[i] = (int32_t)local[gid] | stays;
      else {
        for (PetscInt i = i0; i < i1; i++) dest[i] = -2 - (int32_t)owner[gid];
        sent += i1 - i0;
      }
    }
  } else {
#pragma omp parallel for reduction(+ : sent, wrapped, clamped, nbad) schedule(static)
    for (PetscInt i = 0; i < n; i++)
      PffMigrateLocate(p, i, level, owner, local, dest, &sent, &wrapped, &clamped, &nbad);
  }
  PetscCall(PetscFree2(oldStart, oldGid));
  loc[0] = sent;
  loc[1] = wrapped;
  loc[2] = clamped;
  if (nbad > 0) {
    PetscInt i = 0;
    while (dest[i] != -1) i++;
    SETERRQ(PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
            "%" PetscInt_FMT " particles lie in inactive blocks, e.g. id %" PetscInt64_FMT " at (%g, %g, %g)", nbad,
            (PetscInt64)p->s.id[i], (double)(p->origin[0] + p->h0 * p->s.x[3 * i]),
            (double)(p->origin[1] + p->h0 * p->s.x[3 * i + 1]), (double)(p->origin[2] + p->h0 * p->s.x[3 * i + 2]));
  }
  if (p->size > 1) {
    PetscMPIInt *scount, *rcount, *sdispl, *rdispl;
    PetscInt    *fill;
    {
      const size_t bytes[5] = {sizeof(PetscMPIInt) * (size_t)p->size, sizeof(PetscMPIInt) * (size_t)p->size,
                               sizeof(PetscMPIInt) * (size_t)(p->size + 1), sizeof(PetscMPIInt) * (size_t)(p->size + 1),
                               sizeof(PetscInt) * (size_t)p->size};
      void        *ptrs[5];
      PetscCall(PffParticlesGetScratch_Private(p, PFF_SCRATCH_MIGRATE, 5, bytes, ptrs));
      scount = (PetscMPIInt *)ptrs[0];
      rcount = (PetscMPIInt *)ptrs[1];
      sdispl = (PetscMPIInt *)ptrs[2];
      rdispl = (PetscMPIInt *)ptrs[3];
      fill   = (PetscInt *)ptrs[4];
      PetscCall(PetscArrayzero(scount, p->size));
    }
    for (PetscInt i = 0; i < n; i++)
      if (dest[i] < 0) scount[-2 - dest[i]]++;
    PetscCallMPI(MPI_Alltoall(scount, 1, MPI_INT, rcount, 1, MPI_INT, p->comm));
    PetscInt64 ns = 0, nr = 0;
    for (PetscMPIInt r = 0; r < p->size; r++) {
      ns += scount[r];
      nr += rcount[r];
    }
    /* byte counts and displacements of the packed records (the store's fields back to back) */
    const PetscMPIInt rec = (PetscMPIInt)PFF_PARTICLE_BYTES;
    char             *sbuf, *rbuf;
    {
      const size_t bytes[2] = {(size_t)ns * (size_t)rec, (size_t)nr * (size_t)rec};
      void        *ptrs[2];
      PetscCall(PffParticlesGetScratch_Private(p, PFF_SCRATCH_MIGRATE_RECORDS, 2, bytes, ptrs));
      sbuf = (char *)ptrs[0];
      rbuf = (char *)ptrs[1];
    }
    sdispl[0] = rdispl[0] = 0;
    for (PetscMPIInt r = 0; r < p->size; r++) {
      fill[r] = sdispl[r]; /* next record to pack for rank r */
      PetscCall(PetscMPIIntCast((PetscInt64)sdispl[r] + scount[r], &sdispl[r + 1]));
      PetscCall(PetscMPIIntCast((PetscInt64)rdispl[r] + rcount[r], &rdispl[r + 1]));
    }
    PetscMPIInt bytes; /* the byte totals must fit MPI counts */
    PetscCall(PetscMPIIntCast(ns * rec, &bytes));
    PetscCall(PetscMPIIntCast(nr * rec, &bytes));
    /* pack the leavers; the sort drops them */
    for (PetscInt i = 0; i < n; i++)
      if (dest[i] < 0) {
        PffParticlesPack_Private(&p->s, i, sbuf + (size_t)rec * (size_t)fill[-2 - dest[i]]++);
        dest[i] = PFF_SORT_DROP;
      }
    for (PetscMPIInt r = 0; r < p->size; r++) {
      sdispl[r] *= rec;
      rdispl[r] *= rec;
      scount[r] *= rec;
      rcount[r] *= rec;
    }
    PetscCallMPI(MPI_Alltoallv(sbuf, scount, sdispl, MPI_BYTE, rbuf, rcount, rdispl, MPI_BYTE, p->comm));
    PetscCall(PffParticlesReserve_Private(p, n + (PetscInt)nr));
    PetscCall(PffParticlesGrowIntWork_Private(p, (size_t)(n + nr) + 1, n, &dest));
    for (PetscInt64 r = 0; r < nr; r++) {
      const PetscInt j = p->n++;
      PffParticlesUnpack_Private(&p->s, j, rbuf + (size_t)rec * (size_t)r);
      /* the sender found it in a block of this rank */
      const PetscInt gid = PffParticlesLocate_Private(p, &p->s.x[3 * j], level);
      PetscCheck(gid >= 0 && owner[gid] == p->rank, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                 "particle %" PetscInt64_FMT " received by rank %d is not in one of its blocks", (PetscInt64)p->s.id[j],
                 (int)p->rank);
      dest[j] = (int32_t)local[gid];
    }
    /* the records are kept for the next step, unless a mass migration (a restart) made them large */
    if (p->nscratch[PFF_SCRATCH_MIGRATE_RECORDS] > 4 * (size_t)p->n + 65536) {
      PetscCall(PetscFree(p->scratch[PFF_SCRATCH_MIGRATE_RECORDS]));
      p->nscratch[PFF_SCRATCH_MIGRATE_RECORDS] = 0;
    }
  }
  p->binned = PETSC_FALSE;
  PetscCall(PetscLogEventEnd(PFF_PartMigrate, 0, 0, 0, 0));
  PetscCall(PetscLogEventBegin(PFF_PartBin, 0, 0, 0, 0));
  PetscCall(PffParticlesSort_Private(p));
  PetscCall(PetscLogEventEnd(PFF_PartBin, 0, 0, 0, 0));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, loc, 3, MPIU_INT64, MPI_SUM, p->comm));
  if (stats) {
    stats->sent     = loc[0];
    stats->wrapped  = loc[1];
    stats->clamped  = loc[2];
    stats->pushed   = 0;
    stats->substeps = 0;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
