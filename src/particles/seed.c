/* Seeding (PF-FLIP Sec. 3.2; DESIGN.md Sec. 6): 2 x 2 x 2 particles per cell of every owned block at
   the block's level, each at its sub-cell centre (i + 1/4 + s/2) h, s in {0, 1}, moved by a jitter of
   up to +-jitter/2 of the sub-cell spacing h/2 per axis, so a particle never leaves its sub-cell.

   Ids are global and partition-independent: id = ((gid * n0^3 + c) * 8 + s) with gid the raster
   index of the block, c the cell index at the block's level (x fastest, c < n^3 <= n0^3) and s the
   sub-cell. The jitter is a counter-based hash of (seed, id, purpose, axis), so the particles (and
   the callback's answers) are the same on any number of ranks and threads. */
#include "particlesimpl.h"

PetscErrorCode PffParticlesSeed(PffParticles p, PffSeedFn fn, void *ctx)
{
  PetscInt nlocal;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetLocalBlocks(p->grid, &nlocal));
  PetscCall(PffParticlesSeedBlocks(p, fn, ctx, 0, nlocal, NULL));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The 8 lattice particles of cell (i, j, k) of block info that fn accepts, appended to the store (reserved). With
   key != 0 the ids are the lattice ids hashed with key, top bit set (reseeded particles: the lattice id of the cell
   may still be in use). */
static PetscErrorCode SeedCell(PffParticles p, const PffBlockInfo *info, PetscInt i, PetscInt j, PetscInt k,
                               PffSeedFn fn, void *ctx, uint64_t key)
{
  const PetscInt  n     = info->n;
  const PetscReal scale = (PetscReal)((PetscInt)1 << info->level);
  const uint64_t  cell  = (uint64_t)(i + n * (j + n * k));

  PetscFunctionBeginUser;
  for (PetscInt sub = 0; sub < 8; sub++) {
    uint64_t       id   = ((uint64_t)info->gid * (uint64_t)(p->n0 * p->n0 * p->n0) + cell) * 8 + (uint64_t)sub;
    const PetscInt c[3] = {i, j, k};
    PetscReal      x[3], v[3] = {0, 0, 0};
    float          g[3];
    PetscInt       type = -1;
    if (key) id = PffHash64_Private(id ^ PffHash64_Private(key)) | (UINT64_C(1) << 63);
    /* the callback sees the world point of the stored float position */
    for (int a = 0; a < 3; a++) {
      /* no hash for an unjittered lattice (the reference lattice is seeded at every step with bodies):
         0 (u - 1/2) adds a zero either way */
      const PetscReal u  = p->jitter != 0 ? PffRandom01_Private(p->seed, id, PFF_RNG_SEED_JITTER, (uint64_t)a) : 0.5;
      const PetscReal s  = 0.25 + 0.5 * (PetscReal)((sub >> a) & 1) + p->jitter * (u - 0.5) * 0.5;
      const PetscReal lo = (PetscReal)(info->ijk[a] * p->n0) + (PetscReal)c[a] * scale;
      /* rounding to float must not carry the particle into the next cell (or block, or rank) */
      g[a] = PetscMin((float)(lo + s * scale), nextafterf((float)(lo + scale), 0));
      x[a] = p->origin[a] + p->h0 * (PetscReal)g[a];
    }
    PetscCall(fn(x, &type, v, ctx));
    if (type < 0) continue;
    PetscCheck(type < PFF_PARTICLE_NTYPES, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
               "seeding function returned type %" PetscInt_FMT ", not a PffParticleType or -1", type);
    const PetscInt m = p->n++;
    for (int a = 0; a < 3; a++) {
      p->s.x[3 * m + a] = g[a];
      p->s.v[3 * m + a] = (float)v[a];
    }
    p->s.id[m]   = id;
    p->s.word[m] = PffParticleWord(type, info->level, 0);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode CheckIdRange(PffParticles p)
{
  const PetscReal n0c = (PetscReal)p->n0 * (PetscReal)p->n0 * (PetscReal)p->n0;

  PetscFunctionBeginUser;
  PetscCheck(n0c * (PetscReal)(p->nb[0] * p->nb[1]) * (PetscReal)p->nb[2] * 8 < 1.8e19, p->comm,
             PETSC_ERR_ARG_OUTOFRANGE, "the raster is too large for 64-bit particle ids");
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffParticlesSeedBlocks(PffParticles p, PffSeedFn fn, void *ctx, PetscInt lb0, PetscInt lb1,
                                      const PetscBool mask[])
{
  PetscInt   nlocal;
  PetscInt64 ncand = 0;

  PetscFunctionBeginUser;
  PetscCheck(fn != NULL, p->comm, PETSC_ERR_ARG_NULL, "PffParticlesSeed needs a seeding function");
  PetscCall(CheckIdRange(p));
  PetscCall(PetscLogEventBegin(PFF_PartSeed, 0, 0, 0, 0));
  PetscCall(PffGridGetLocalBlocks(p->grid, &nlocal));
  PetscCheck(lb0 >= 0 && lb0 <= lb1 && lb1 <= nlocal, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
             "PffParticlesSeedBlocks: blocks [%" PetscInt_FMT ", %" PetscInt_FMT ") are not in [0, %" PetscInt_FMT ")",
             lb0, lb1, nlocal);
  for (PetscInt lb = lb0; lb < lb1; lb++) {
    PffBlockInfo info;
    if (mask && !mask[lb]) continue;
    PetscCall(PffGridGetBlockInfo(p->grid, lb, &info));
    ncand += 8 * (PetscInt64)info.n * info.n * info.n;
  }
  /* an eighth more than the candidates: particles that migrate in later fill untouched pages, where a
     growth would hold the old and the new store at once (+36 B per particle of peak memory) */
  PetscCall(PffParticlesReserve_Private(p, p->n + (PetscInt)(ncand + ncand / 8)));
  for (PetscInt lb = lb0; lb < lb1; lb++) {
    if (mask && !mask[lb]) continue;
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(p->grid, lb, &info));
    for (PetscInt k = 0; k < info.n; k++)
      for (PetscInt j = 0; j < info.n; j++)
        for (PetscInt i = 0; i < info.n; i++) PetscCall(SeedCell(p, &info, i, j, k, fn, ctx, 0));
  }
  p->binned = PETSC_FALSE;
  PetscCall(PetscLogEventEnd(PFF_PartSeed, 0, 0, 0, 0));
  PetscCall(PffParticlesBin(p));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffParticlesSeedCells(PffParticles p, PffSeedFn fn, void *ctx, PetscInt ncells, const PetscInt cells[],
                                     uint64_t key)
{
  PetscFunctionBeginUser;
  PetscCheck(fn != NULL, p->comm, PETSC_ERR_ARG_NULL, "PffParticlesSeedCells needs a seeding function");
  PetscCheck(key != 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "PffParticlesSeedCells needs a key other than 0");
  PetscCall(CheckIdRange(p));
  PetscCall(PetscLogEventBegin(PFF_PartSeed, 0, 0, 0, 0));
  PetscCall(PffParticlesReserve_Private(p, p->n + 8 * ncells));
  for (PetscInt q = 0; q < ncells; q++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(p->grid, cells[2 * q], &info));
    const PetscInt c = cells[2 * q + 1], n = info.n;
    PetscCheck(c >= 0 && c < n * n * n, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
               "PffParticlesSeedCells: cell %" PetscInt_FMT " is not in a block of %" PetscInt_FMT "^3", c, n);
    PetscCall(SeedCell(p, &info, c % n, (c / n) % n, c / (n * n), fn, ctx, key));
  }
  p->binned = PETSC_FALSE;
  PetscCall(PetscLogEventEnd(PFF_PartSeed, 0, 0, 0, 0));
  PetscCall(PffParticlesBin(p));
  PetscFunctionReturn(PETSC_SUCCESS);
}
