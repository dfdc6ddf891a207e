/* Unit test of particle split and probabilistic coarsening (PffParticlesAdaptLevels, PF-FLIP Sec. 5.1).

   A closed 16^3 box of 8^3 blocks with three levels, liquid below y = 1/2 and air above, each particle
   with a velocity of its own. Checks:
   - split: particles of level 2 in x < 1/2 (all of them, then three quarters drawn by id), each at a random
     place in its level-2 cell (as after advection), asked for level 0 split into 64 children each; the volume
     (mass) per type is exact, the momentum per type to 1e-12, every sub-cell of level 0 (half a finest cell)
     holds at most one particle and every finest cell as many as its level-2 cell had splitting parents (no
     hole where no parent sat, also with fewer than 8 parents), the rest is untouched, and every particle lies
     in the block of its bin (the store bins again without a locate);
   - coarsening: level-0 particles asked for level 1 (and level 2) are kept through delay - 1 calls, during
     which PffParticlesAdaptCounters has them hold the grid at their own level, then removed with
     probability 7/8 (63/64): the survivors' count within 5 sigma of the expectation, their
     level the target, exactly 8 in every cell of the target level (the coarsening is stratified per such
     cell), and the volume per type within 5 sigma of its expectation (reported as the drift) and within one
     coarse particle per block of it;
   - hysteresis: a call with target <= l_p resets the counter, so the next delay - 1 calls remove nothing;
   - independence of the partition: the ids that survive, hashed together, and the count equal those of
     the same run on one rank (PETSC_COMM_SELF on rank 0), also with threads.

   Sample run:  mpiexec -n 4 ./test_particles_adapt
   Prints one line per case, the same on any number of ranks. */
#include "pfftest.h"

static const char help[] = "Particle split and probabilistic coarsening.\n";

#define DELAY 3

static PetscErrorCode SeedHalf(const PetscReal x[3], PetscInt *type, PetscReal v[3], void *ctx)
{
  PetscFunctionBeginUser;
  (void)ctx;
  *type = x[1] < 0.5 ? PFF_PARTICLE_LIQUID : PFF_PARTICLE_AIR;
  v[0]  = x[0] + 2 * x[1];
  v[1]  = -x[2];
  v[2]  = 0.5 - x[0] * x[1];
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode Create(MPI_Comm comm, PetscInt level, PffGrid *grid, PffParticles *p)
{
  const PetscInt  cells[3]    = {16, 16, 16};
  const PetscBool periodic[3] = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};
  const PetscReal origin[3]   = {0, 0, 0};
  PetscInt        map[8];

  PetscFunctionBeginUser;
  for (int b = 0; b < 8; b++) map[b] = level;
  PetscCall(PffGridCreate(comm, grid));
  PetscCall(PffGridSetCells(*grid, cells));
  PetscCall(PffGridSetBlockSize(*grid, 8));
  PetscCall(PffGridSetLevels(*grid, 3));
  PetscCall(PffGridSetDomain(*grid, origin, 1.0 / 16));
  PetscCall(PffGridSetPeriodic(*grid, periodic));
  PetscCall(PffGridSetRefinementMap(*grid, map));
  PetscCall(PffGridSetUp(*grid));
  PetscCall(PffParticlesCreate(*grid, p));
  PetscCall(PffParticlesSetFromOptions(*p));
  PetscCall(PffParticlesSeed(*p, SeedHalf, NULL));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode Destroy(PffGrid *grid, PffParticles *p)
{
  PetscFunctionBeginUser;
  PetscCall(PffParticlesDestroy(p));
  PetscCall(PffGridDestroy(grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Momentum (sum 8^l v) per type and component, summed over ranks. */
static PetscErrorCode Momentum(MPI_Comm comm, PffParticles p, PetscReal mom[2][3])
{
  PffParticleArrays a;

  PetscFunctionBeginUser;
  PetscCall(PffParticlesGetArrays(p, &a));
  PetscCall(PetscArrayzero(&mom[0][0], 6));
  for (PetscInt i = 0; i < a.n; i++)
    for (int d = 0; d < 3; d++)
      mom[PffParticleWordType(a.word[i])][d] +=
          (PetscReal)((PetscInt64)1 << (3 * PffParticleWordLevel(a.word[i]))) * a.v[3 * i + d];
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &mom[0][0], 6, MPIU_REAL, MPI_SUM, comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* share: the fraction of the level-2 parents in x < 1/2 that split (by a draw from the id), the others stay */
static PetscErrorCode CaseSplit(MPI_Comm comm, PetscReal share)
{
  PffGrid               grid;
  PffParticles          p;
  PffParticleArrays     a;
  PffParticleAdaptStats st;
  PetscReal             mom0[2][3], mom1[2][3];
  int8_t               *target;
  PetscInt             *count, *sub, nsplit = 0, nbad = 0, parents[64] = {0};
  PetscInt64            n0, n1;

  PetscFunctionBeginUser;
  PetscCall(Create(comm, 2, &grid, &p));
  PetscCall(PffParticlesGetArrays(p, &a));
  /* advected parents: each anywhere in its level-2 cell (4 finest cells, 8 parents per cell), drawn from
     its id, so that a parent's own neighbourhood says nothing about where the finer cells are empty */
  for (PetscInt i = 0; i < a.n; i++)
    for (int d = 0; d < 3; d++) {
      const PetscReal u = PffTestUniform01(PffTestKey(a.id[i], (uint64_t)d, 0, 0));
      a.x[3 * i + d]    = (float)(4 * PetscFloorReal(a.x[3 * i + d] / 4) + 4 * u);
    }
  PetscCall(Momentum(comm, p, mom0));
  PetscCall(PetscMalloc1(a.n + 1, &target));
  for (PetscInt i = 0; i < a.n; i++) {
    const PetscBool split = (PetscBool)(a.x[3 * i] < 8 && PffTestUniform01(PffTestKey(a.id[i], 3, 0, 0)) < share);
    target[i]             = (int8_t)(split ? 0 : 2);
    nsplit += split;
    if (split)
      parents[(PetscInt)(a.x[3 * i] / 4) + 4 * ((PetscInt)(a.x[3 * i + 1] / 4) + 4 * (PetscInt)(a.x[3 * i + 2] / 4))]++;
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, parents, 64, MPIU_INT, MPI_SUM, comm));
  n0 = a.n;
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &n0, 1, MPIU_INT64, MPI_SUM, comm));
  PetscCall(PffParticlesAdaptLevels(p, target, DELAY, 1, &st));
  PetscCall(PetscFree(target));
  PetscCall(Momentum(comm, p, mom1));
  PetscCall(PffParticlesGetArrays(p, &a));
  n1 = a.n;
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &n1, 1, MPIU_INT64, MPI_SUM, comm));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &nsplit, 1, MPIU_INT, MPI_SUM, comm));
  PetscCheck(st.split == nsplit && st.children == 64 * nsplit && n1 == n0 + 63 * nsplit, comm, PETSC_ERR_PLIB,
             "split %" PetscInt64_FMT " into %" PetscInt64_FMT ", count %" PetscInt64_FMT " -> %" PetscInt64_FMT,
             st.split, st.children, n0, n1);
  for (int t = 0; t < 2; t++) {
    PetscCheck(st.volumeAfter[t] == st.volumeBefore[t], comm, PETSC_ERR_PLIB, "type %d: volume %.17g -> %.17g", t,
               (double)st.volumeBefore[t], (double)st.volumeAfter[t]);
    for (int d = 0; d < 3; d++)
      PetscCheck(PetscAbsReal(mom1[t][d] - mom0[t][d]) <= 1e-12 * st.volumeBefore[t], comm, PETSC_ERR_PLIB,
                 "type %d: momentum %d %.17g -> %.17g", t, d, (double)mom0[t][d], (double)mom1[t][d]);
  }
  /* every finest cell of a level-2 cell C gets as many children as C had splitting parents, at most one per level-0
     sub-cell (32^3 over the box): no hole where no parent sat, also when C had fewer than 8; levels (a level-2
     particle in x < 1/2 did not split, nor lies in a sub-cell of its own) */
  PetscCall(PetscCalloc2(16 * 16 * 16, &count, 32 * 32 * 32, &sub));
  for (PetscInt i = 0; i < a.n; i++) {
    const PetscInt l = PffParticleWordLevel(a.word[i]);
    if (l != 0 && l != 2) nbad++;
    if (l == 0 && a.x[3 * i] >= 8) nbad++;
    if (l != 0) continue;
    PetscInt s[3];
    for (int d = 0; d < 3; d++) s[d] = (PetscInt)PetscFloorReal(2 * (PetscReal)a.x[3 * i + d]);
    sub[s[0] + 32 * (s[1] + 32 * s[2])]++;
    count[s[0] / 2 + 16 * (s[1] / 2 + 16 * (s[2] / 2))]++;
  }
  /* the bins after the split: every particle in the block of its bin */
  {
    PetscInt nlocal;
    PetscCall(PffGridGetLocalBlocks(grid, &nlocal));
    PetscCheck(a.start && a.start[nlocal] == a.n, PETSC_COMM_SELF, PETSC_ERR_PLIB, "not binned after the split");
    for (PetscInt lb = 0; lb < nlocal; lb++) {
      PffBlockInfo info;
      PetscCall(PffGridGetBlockInfo(grid, lb, &info));
      for (PetscInt i = a.start[lb]; i < a.start[lb + 1]; i++)
        for (int d = 0; d < 3; d++)
          PetscCheck((PetscInt)(a.x[3 * i + d] / 8) == info.ijk[d], PETSC_COMM_SELF, PETSC_ERR_PLIB,
                     "particle %" PetscInt_FMT " lies outside the block of its bin %" PetscInt_FMT, i, lb);
    }
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, count, 16 * 16 * 16, MPIU_INT, MPI_SUM, comm));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, sub, 32 * 32 * 32, MPIU_INT, MPI_SUM, comm));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &nbad, 1, MPIU_INT, MPI_SUM, comm));
  PetscCheck(nbad == 0, comm, PETSC_ERR_PLIB, "%" PetscInt_FMT " particles with the wrong level", nbad);
  for (PetscInt c = 0; c < 32 * 32 * 32; c++)
    PetscCheck(sub[c] <= 1, comm, PETSC_ERR_PLIB, "sub-cell %" PetscInt_FMT " holds %" PetscInt_FMT " particles", c,
               sub[c]);
  for (PetscInt c = 0; c < 16 * 16 * 16; c++) {
    const PetscInt i = c % 16, j = (c / 16) % 16, k = c / 256, nc = parents[i / 4 + 4 * (j / 4 + 4 * (k / 4))];
    PetscCheck(count[c] == nc, comm, PETSC_ERR_PLIB,
               "finest cell (%" PetscInt_FMT ", %" PetscInt_FMT ", %" PetscInt_FMT ") holds %" PetscInt_FMT
               " children, its level-2 cell had %" PetscInt_FMT " parents",
               i, j, k, count[c], nc);
  }
  PetscCall(PetscFree2(count, sub));
  PetscCall(PetscPrintf(comm,
                        "split (share %g): %" PetscInt64_FMT " particles into %" PetscInt64_FMT ", %" PetscInt64_FMT
                        " particles; volume and momentum per type kept, every finest cell as many as its parents\n",
                        (double)share, st.split, st.children, n1));
  PetscCall(Destroy(&grid, &p));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Coarsening to level `to` from 0 on comm: counts, ids hash, volumes. */
static PetscErrorCode Coarsen(MPI_Comm comm, PetscInt to, PetscBool hysteresis, PetscInt64 *kept, uint64_t *hash,
                              PffParticleAdaptStats *last)
{
  PffGrid               grid;
  PffParticles          p;
  PffParticleArrays     a;
  PffParticleAdaptStats st;
  int8_t               *target;
  PetscInt              calls = 0, d = 0, nbad = 0;

  PetscFunctionBeginUser;
  PetscCall(Create(comm, 0, &grid, &p));
  /* with hysteresis: delay - 1 calls, one at the particles' own level, then delay - 1 calls again */
  const PetscInt ncalls = hysteresis ? 2 * DELAY - 1 : DELAY;
  for (PetscInt c = 0; c < ncalls; c++) {
    const PetscInt want = hysteresis && c == DELAY - 1 ? 0 : to;
    PetscCall(PffParticlesGetArrays(p, &a));
    PetscCall(PetscMalloc1(a.n + 1, &target));
    /* the counters: while a coarsening is pending the particle holds the grid at its own level */
    d = want > 0 ? d + 1 : 0;
    for (PetscInt i = 0; i < a.n; i++) target[i] = (int8_t)want;
    PetscCall(PffParticlesAdaptCounters(p, target, DELAY));
    for (PetscInt i = 0; i < a.n; i++) nbad += target[i] != (want > 0 && d < DELAY ? 0 : want);
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &nbad, 1, MPIU_INT, MPI_SUM, comm));
    PetscCheck(nbad == 0, comm, PETSC_ERR_PLIB,
               "call %" PetscInt_FMT ": %" PetscInt_FMT " particles hold a wrong level", calls + 1, nbad);
    for (PetscInt i = 0; i < a.n; i++) target[i] = (int8_t)want;
    PetscCall(PffParticlesAdaptLevels(p, target, DELAY, (uint64_t)(c + 1), &st));
    PetscCall(PetscFree(target));
    calls++;
    if (c + 1 < ncalls)
      PetscCheck(st.marked == 0 && st.removed == 0, comm, PETSC_ERR_PLIB,
                 "call %" PetscInt_FMT ": %" PetscInt64_FMT " particles coarsened before the delay", calls, st.marked);
  }
  PetscCall(PffParticlesGetArrays(p, &a));
  if (!hysteresis) {
    /* stratified per cell of the target level: each of them had 8^(to + 1) candidates and keeps exactly 8, where
       draws per block left some cells with half as many and others with twice (holes after a later split) */
    const PetscInt nc = 16 >> to;
    PetscInt      *count;
    PetscCall(PetscCalloc1(nc * nc * nc, &count));
    for (PetscInt i = 0; i < a.n; i++) {
      PetscInt c[3];
      for (int e = 0; e < 3; e++) c[e] = (PetscInt)a.x[3 * i + e] >> to;
      count[c[0] + nc * (c[1] + nc * c[2])]++;
    }
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, count, nc * nc * nc, MPIU_INT, MPI_SUM, comm));
    for (PetscInt c = 0; c < nc * nc * nc; c++)
      PetscCheck(count[c] == 8, comm, PETSC_ERR_PLIB,
                 "cell %" PetscInt_FMT " of level %" PetscInt_FMT " keeps %" PetscInt_FMT " particles, not 8", c, to,
                 count[c]);
    PetscCall(PetscFree(count));
  }
  *hash = 0;
  for (PetscInt i = 0; i < a.n; i++) {
    PetscCheck(PffParticleWordLevel(a.word[i]) == (hysteresis ? 0 : to), PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "a survivor has level %" PetscInt_FMT, PffParticleWordLevel(a.word[i]));
    *hash ^= a.id[i] * 0x9e3779b97f4a7c15ULL;
  }
  *kept = a.n;
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, kept, 1, MPIU_INT64, MPI_SUM, comm));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, hash, 1, MPI_UINT64_T, MPI_BXOR, comm));
  *last = st;
  PetscCall(Destroy(&grid, &p));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode CaseCoarsen(MPI_Comm comm, PetscInt to)
{
  const PetscInt64 n = 16 * 16 * 16 * 8;
  const PetscReal  q = 1.0 / (PetscReal)((PetscInt64)1 << (3 * to)), sigma = PetscSqrtReal((PetscReal)n * q * (1 - q));
  PffParticleAdaptStats st, stSelf;
  PetscInt64            kept, keptSelf = 0;
  uint64_t              hash, hashSelf = 0;
  PetscMPIInt           rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCall(Coarsen(comm, to, PETSC_FALSE, &kept, &hash, &st));
  PetscCheck(st.marked == n && st.removed == n - kept, comm, PETSC_ERR_PLIB,
             "marked %" PetscInt64_FMT " removed %" PetscInt64_FMT, st.marked, st.removed);
  PetscCheck(PetscAbsReal((PetscReal)kept - q * (PetscReal)n) <= 5 * sigma, comm, PETSC_ERR_PLIB,
             "to level %" PetscInt_FMT ": %" PetscInt64_FMT " of %" PetscInt64_FMT " kept, expected %.1f +- %.1f", to,
             kept, n, (double)(q * (PetscReal)n), (double)sigma);
  for (int t = 0; t < 2; t++) {
    const PetscReal drift = st.volumeAfter[t] / st.volumeBefore[t] - 1,
                    sd    = PetscSqrtReal((1 - q) / (q * 0.5 * (PetscReal)n));
    PetscCheck(PetscAbsReal(drift) <= 5 * sd, comm, PETSC_ERR_PLIB, "type %d: volume drift %.4f beyond 5 sigma (%.4f)",
               t, (double)drift, (double)sd);
    /* stratified: each of the (at most 8) blocks of a type misses its volume by less than one coarse particle,
       where independent draws would miss by about sigma (30-40 coarse particles here) */
    const PetscReal vt = (PetscReal)((PetscInt64)1 << (3 * to));
    PetscCheck(PetscAbsReal(st.volumeAfter[t] - st.volumeBefore[t]) < 8 * vt, comm, PETSC_ERR_PLIB,
               "type %d: the survivors miss the volume by %g, beyond one coarse particle per block (%g)", t,
               (double)(st.volumeAfter[t] - st.volumeBefore[t]), (double)vt);
    PetscCall(PetscPrintf(comm, "coarsen to level %" PetscInt_FMT ": %s volume drift %+.4f (sigma %.4f)\n", to,
                          PffParticleTypes[t], (double)drift, (double)sd));
  }
  if (rank == 0) PetscCall(Coarsen(PETSC_COMM_SELF, to, PETSC_FALSE, &keptSelf, &hashSelf, &stSelf));
  PetscCallMPI(MPI_Bcast(&keptSelf, 1, MPIU_INT64, 0, comm));
  PetscCallMPI(MPI_Bcast(&hashSelf, 1, MPI_UINT64_T, 0, comm));
  PetscCheck(kept == keptSelf && hash == hashSelf, comm, PETSC_ERR_PLIB,
             "the survivors depend on the partition: %" PetscInt64_FMT " here, %" PetscInt64_FMT " on one rank", kept,
             keptSelf);
  PetscCall(PetscPrintf(comm,
                        "coarsen to level %" PetscInt_FMT ": %" PetscInt64_FMT " of %" PetscInt64_FMT
                        " kept (expected %.1f +- %.1f), the same survivors as on one rank\n",
                        to, kept, n, (double)(q * (PetscReal)n), (double)sigma));
  /* hysteresis */
  PetscCall(Coarsen(comm, to, PETSC_TRUE, &kept, &hash, &st));
  PetscCheck(kept == n, comm, PETSC_ERR_PLIB, "hysteresis: %" PetscInt64_FMT " of %" PetscInt64_FMT " kept", kept, n);
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  PetscFunctionBeginUser;
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(CaseSplit(PETSC_COMM_WORLD, 1.0));
  PetscCall(CaseSplit(PETSC_COMM_WORLD, 0.75));
  PetscCall(CaseCoarsen(PETSC_COMM_WORLD, 1));
  PetscCall(CaseCoarsen(PETSC_COMM_WORLD, 2));
  PetscCall(PetscFinalize());
  return 0;
}
