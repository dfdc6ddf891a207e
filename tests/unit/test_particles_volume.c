/* Unit test of PffParticlesSplatVolume (the cell-centre volume of the two-phase correction) at any rank count.

   Conservation: jittered particles on a 3-level periodic grid (layers of levels 0, 1, 2, 1), moved 4 steps by a uniform
   field so that particles of every level sit in blocks of every other level and beside every level boundary: the
   channel summed over all owned cells equals the particles' volume (sum of 8^l_p) to 1e-6 relative. With the values
   in densities (each divided by its block's 8^level, as P2G's faces are) the cells hold about a quarter of it and the
   test fails. Lattice: an unjittered lattice gives 8^(l + 1) in every cell of a level-l block that lies more than one
   cell from a block of another level (1e-6 relative); the largest deviation beside level boundaries is printed.
   Locality: a single particle at a random place adds its volume to at most the 8 cells around it on a uniform grid,
   with the trilinear weights (1e-6).

   Sample run:  mpiexec -n 4 ./test_particles_volume
   Prints the same lines on any number of ranks. */
#include "pfftest.h"

static const char help[] = "Cell-centre particle volume: conservation across levels, lattice values, weights.\n";

#define N0 8

static PetscErrorCode SeedLiquid(const PetscReal x[3], PetscInt *type, PetscReal v[3], void *ctx)
{
  PetscFunctionBeginUser;
  (void)ctx;
  *type = x[0] < 0.6 ? PFF_PARTICLE_LIQUID : PFF_PARTICLE_AIR;
  v[0] = v[1] = v[2] = 0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscReal Uniform(const PetscReal x[3], PetscInt comp, void *ctx)
{
  (void)x;
  return ((const PetscReal *)ctx)[comp];
}

static PetscErrorCode CreateParticles(PffTestCtx *ctx, const char jitter[], PffParticles *part)
{
  PetscFunctionBeginUser;
  PetscCall(PetscOptionsSetValue(NULL, "-particles_jitter", jitter));
  PetscCall(PffParticlesCreate(ctx->grid, part));
  PetscCall(PffParticlesSetFromOptions(*part));
  PetscCall(PetscOptionsClearValue(NULL, "-particles_jitter"));
  PetscCall(PffParticlesSeed(*part, SeedLiquid, NULL));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The particles' volume in level-0 particles (vp) and the channel summed over all owned cells (vg), in double over
   all ranks */
static PetscErrorCode Totals(PffTestCtx *ctx, PffParticles part, PetscInt ch, PetscReal *vp, PetscReal *vg)
{
  PffParticleArrays a;
  PetscReal         v[2] = {0, 0};

  PetscFunctionBeginUser;
  PetscCall(PffParticlesGetArrays(part, &a));
  for (PetscInt i = 0; i < a.n; i++) v[0] += (PetscReal)(1u << (3 * PffParticleWordLevel(a.word[i])));
  for (PetscInt lb = 0; lb < ctx->nlocal; lb++) {
    PffBlockInfo info;
    float       *w;
    PetscCall(PffGridGetBlockInfo(ctx->grid, lb, &info));
    PetscCall(PffGridGetBlockData(ctx->grid, ch, lb, 0, &w));
    for (PetscInt c = 0; c < info.n * info.n * info.n; c++) v[1] += (PetscReal)w[c];
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, v, 2, MPIU_REAL, MPI_SUM, ctx->comm));
  *vp = v[0];
  *vg = v[1];
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode TestConservation(void)
{
  const PetscInt   nb[3]       = {4, 2, 2};
  const PetscBool  periodic[3] = {PETSC_TRUE, PETSC_TRUE, PETSC_TRUE};
  const PetscReal  origin[3] = {0, 0, 0}, u[3] = {1.0, -0.75, 0.5};
  PffTestCtx       ctx;
  PffParticles     part;
  PffParticleStats st;
  PetscInt         chU, chV, nlev = 0;
  PetscReal        vp, vg;

  PetscFunctionBeginUser;
  PetscInt request[16];
  /* layers of blocks along x at levels 0, 1, 2, 1 (periodic), with one level-1 block in the level-0 layer */
  for (PetscInt b = 0; b < 16; b++) request[b] = (PetscInt[]){0, 1, 2, 1}[b % 4];
  request[4] = 1;
  PetscCall(PffTestCreateGridFromMap(PETSC_COMM_WORLD, nb, periodic, origin, 1.0 / 16, N0, 3, request, &ctx));
  for (PetscInt b = 0; b < ctx.nblocks; b++) nlev = PetscMax(nlev, ctx.level[b] + 1);
  PetscCall(PffGridAddChannel(ctx.grid, "u", PFF_CHANNEL_FACE, 2, &chU));
  PetscCall(PffGridAddChannel(ctx.grid, "volume", PFF_CHANNEL_CELL, 1, &chV));
  PetscCall(PffGridFillChannel(ctx.grid, chU, Uniform, (void *)u));
  PetscCall(PffGridHaloBegin(ctx.grid, chU));
  PetscCall(PffGridHaloEnd(ctx.grid, chU));
  PetscCall(CreateParticles(&ctx, "1", &part));
  /* 4 steps of 1.7 finest cells: every particle leaves its sub-cell, many their block */
  for (PetscInt s = 0; s < 4; s++) PetscCall(PffParticlesAdvect(part, chU, 1.7 * ctx.h0 / u[0], NULL, NULL, &st));
  PetscCall(PffParticlesSplatVolume(part, chV));
  PetscCall(Totals(&ctx, part, chV, &vp, &vg));
  PetscCall(PetscPrintf(ctx.comm,
                        "conservation (%" PetscInt_FMT " levels): particle volume %.1f, on the cells %.1f, "
                        "relative difference %.1e\n",
                        nlev, (double)vp, (double)vg, (double)PetscAbsReal(vg / vp - 1)));
  PetscCheck(nlev == 3, ctx.comm, PETSC_ERR_PLIB, "the test grid has %" PetscInt_FMT " levels, not 3", nlev);
  PetscCheck(PetscAbsReal(vg / vp - 1) <= 1e-6, ctx.comm, PETSC_ERR_PLIB,
             "the cells hold %.9g of the particles' volume %.9g", (double)vg, (double)vp);
  PetscCall(PffParticlesDestroy(&part));
  PetscCall(PffGridDestroy(&ctx.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode TestLattice(void)
{
  const PetscInt  nb[3]       = {3, 2, 2};
  const PetscBool periodic[3] = {PETSC_TRUE, PETSC_TRUE, PETSC_TRUE};
  const PetscReal origin[3]   = {0, 0, 0};
  PffTestCtx      ctx;
  PffParticles    part;
  PetscInt        chV;
  PetscReal       err[2] = {0, 0}, vp, vg; /* away from, beside level boundaries */

  PetscFunctionBeginUser;
  PetscCall(PffTestCreateGrid(PETSC_COMM_WORLD, nb, periodic, origin, 1.0 / 16, N0, 2, -1, 0, 5, &ctx));
  PetscCall(PffGridAddChannel(ctx.grid, "volume", PFF_CHANNEL_CELL, 1, &chV));
  PetscCall(CreateParticles(&ctx, "0", &part));
  PetscCall(PffParticlesSplatVolume(part, chV));
  for (PetscInt lb = 0; lb < ctx.nlocal; lb++) {
    PffBlockInfo info;
    float       *w;
    PetscCall(PffGridGetBlockInfo(ctx.grid, lb, &info));
    PetscCall(PffGridGetBlockData(ctx.grid, chV, lb, 0, &w));
    const PetscInt  n      = info.n;
    const PetscReal expect = (PetscReal)(8u << (3 * info.level));
    for (PetscInt c = 0; c < n * n * n; c++) {
      const PetscInt cc[3] = {c % n, (c / n) % n, c / (n * n)};
      const int      at    = PffTestAwayFromLevelJumps(&ctx, &info, cc, 1) ? 0 : 1;
      err[at]              = PetscMax(err[at], PetscAbsReal((PetscReal)w[c] / expect - 1));
    }
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, err, 2, MPIU_REAL, MPI_MAX, ctx.comm));
  PetscCall(Totals(&ctx, part, chV, &vp, &vg));
  PetscCall(PetscPrintf(ctx.comm,
                        "lattice (2 levels): max relative deviation from 8^(l+1) %.1e away from level boundaries, %.3f "
                        "beside them; total %.1e off\n",
                        (double)err[0], (double)err[1], (double)PetscAbsReal(vg / vp - 1)));
  PetscCheck(err[0] <= 1e-6, ctx.comm, PETSC_ERR_PLIB, "a lattice cell holds %g relative off 8^(l+1)", (double)err[0]);
  PetscCheck(PetscAbsReal(vg / vp - 1) <= 1e-6, ctx.comm, PETSC_ERR_PLIB, "the lattice's volume is not kept");
  PetscCall(PffParticlesDestroy(&part));
  PetscCall(PffGridDestroy(&ctx.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* One particle per rank-independent random place of a uniform periodic grid: its 8 cells get its trilinear weights */
static PetscErrorCode TestWeights(void)
{
  const PetscInt  nb[3]       = {2, 2, 2};
  const PetscBool periodic[3] = {PETSC_TRUE, PETSC_TRUE, PETSC_TRUE};
  const PetscReal origin[3]   = {0, 0, 0};
  PffTestCtx      ctx;
  PffParticles    part;
  PetscInt        chV;
  PetscReal       err = 0;

  PetscFunctionBeginUser;
  PetscCall(PffTestCreateGrid(PETSC_COMM_WORLD, nb, periodic, origin, 1.0 / 16, N0, 1, 0, 0, 7, &ctx));
  PetscCall(PffGridAddChannel(ctx.grid, "volume", PFF_CHANNEL_CELL, 1, &chV));
  PetscCall(PffParticlesCreate(ctx.grid, &part));
  for (uint64_t trial = 0; trial < 20; trial++) {
    PffParticleStats st;
    PetscReal        x[3], v[3] = {0, 0, 0}, g[3];
    const uint8_t    type  = PFF_PARTICLE_LIQUID;
    const int8_t     level = 0;
    for (int a = 0; a < 3; a++) {
      /* grid units in [0, 16), on the store's float grid */
      g[a] = (PetscReal)(float)(16 * PffTestUniform01(PffTestKey(trial, (uint64_t)a, 7, 1)));
      x[a] = origin[a] + g[a] * ctx.h0;
    }
    PetscCall(PffParticlesClear(part));
    if (ctx.rank == 0) PetscCall(PffParticlesAdd(part, 1, x, v, NULL, &type, &level, NULL));
    PetscCall(PffParticlesMigrate(part, &st));
    PetscCall(PffParticlesSplatVolume(part, chV));
    for (PetscInt lb = 0; lb < ctx.nlocal; lb++) {
      PffBlockInfo info;
      float       *w;
      PetscCall(PffGridGetBlockInfo(ctx.grid, lb, &info));
      PetscCall(PffGridGetBlockData(ctx.grid, chV, lb, 0, &w));
      for (PetscInt c = 0; c < N0 * N0 * N0; c++) {
        const PetscInt cc[3]  = {info.ijk[0] * N0 + c % N0, info.ijk[1] * N0 + (c / N0) % N0,
                                 info.ijk[2] * N0 + c / (N0 * N0)};
        PetscReal      expect = 1;
        for (int a = 0; a < 3; a++) { /* periodic distance of the cell centre, in cells */
          PetscReal dd = PetscAbsReal((PetscReal)cc[a] + 0.5 - g[a]);
          dd           = PetscMin(dd, 16 - dd);
          expect *= PetscMax(0, 1 - dd);
        }
        err = PetscMax(err, PetscAbsReal((PetscReal)w[c] - expect));
      }
    }
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &err, 1, MPIU_REAL, MPI_MAX, ctx.comm));
  PetscCall(PetscPrintf(ctx.comm, "weights (20 single particles): max error %.1e\n", (double)err));
  PetscCheck(err <= 1e-6, ctx.comm, PETSC_ERR_PLIB, "a cell's weight is %g off the trilinear one", (double)err);
  PetscCall(PffParticlesDestroy(&part));
  PetscCall(PffGridDestroy(&ctx.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(PffInitializePackage());
  PetscCall(TestConservation());
  PetscCall(TestLattice());
  PetscCall(TestWeights());
  PetscCall(PetscFinalize());
  return 0;
}
