/* pff-bench-particles: particle throughput of P2G, G2P and RK3 advection at 1 and 2 OpenMP threads.

   mpiexec -n 1 build/bin/pff-bench-particles [-bench_n 64] [-bench_reps 3] [-bench_walls]

   A periodic bench_n^3 grid of 16^3 blocks, seeded with 8 jittered particles per cell; the velocity
   is a smooth periodic field (a Taylor-Green vortex) with a halo of width 2. -bench_walls closes
   every axis with walls instead (a closed tank, where every block at the boundary touches a wall; the
   field's normal components vanish there). Each kernel runs
   -bench_reps times per thread count (after one warm-up) and the best time counts. Advection moves
   particles about half a cell per step and migrates them. A streaming copy of 2 x 256 MiB per rank
   (read + write counted) at 1 and 2 threads gives the memory speed the kernels are held to. Prints
     RESULT copy ranks=<r> gb_s_1t=<x> gb_s_2t=<y>
     RESULT kernel=<k> ranks=<r> walls=<0|1> particles=<n> mparts_s_1t=<x> mparts_s_2t=<y> bytes=<b>
            copy_share_1t=<s> copy_share_2t=<s>
   for k = p2g, g2p, advect and p2g_volume (P2G as the fluid scenes call it, with the particle-volume channel of
   the density correction: three more face values per corner, the same state read).

   bytes is the particle state a kernel must move at least in the compact store (float positions and
   velocities, a 4-byte word): P2G reads x, v, word = 28 B; G2P reads x, v, word and writes v = 40 B;
   advection reads x, word and writes x = 28 B), and copy_share the share of the copy's bandwidth that the
   rate times bytes reaches (issue 12: a kernel at memory speed reaches about 1). */
#include <pff.h>
#include <omp.h>

static const char help[] = "Particle P2G / G2P / advection throughput.\n";

static PetscErrorCode Seed(const PetscReal x[3], PetscInt *type, PetscReal v[3], void *ctx)
{
  PetscFunctionBeginUser;
  (void)ctx;
  *type = x[2] < 0.5 ? PFF_PARTICLE_LIQUID : PFF_PARTICLE_AIR;
  v[0] = v[1] = v[2] = 0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscReal TaylorGreen(const PetscReal x[3], PetscInt comp, void *ctx)
{
  const PetscReal k = 2 * PETSC_PI;
  (void)ctx;
  if (comp == 0) return PetscSinReal(k * x[0]) * PetscCosReal(k * x[1]) * PetscCosReal(k * x[2]);
  if (comp == 1) return -PetscCosReal(k * x[0]) * PetscSinReal(k * x[1]) * PetscCosReal(k * x[2]);
  return 0;
}

int main(int argc, char **argv)
{
  PffGrid      grid;
  PffParticles part;
  PetscInt     n = 64, reps = 3, chMass, chMom, chVolume, chU, chDU;
  PetscMPIInt  size;
  PetscBool    walls     = PETSC_FALSE;
  PetscReal    origin[3] = {0, 0, 0}, density[2] = {1000, 1}, alpha[2 * PFF_GRID_MAX_LEVELS];
  double       rate[4][2];
  PetscInt64   count[2];

  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(PffHugePagesSetFromOptions(PETSC_COMM_WORLD));
  PetscCall(PffInitializePackage());
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-bench_n", &n, NULL));
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-bench_reps", &reps, NULL));
  PetscCall(PetscOptionsGetBool(NULL, NULL, "-bench_walls", &walls, NULL));
  const PetscBool periodic[3] = {!walls, !walls, !walls};
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  const PetscInt cells[3] = {n, n, n};
  PetscCall(PffGridCreate(PETSC_COMM_WORLD, &grid));
  PetscCall(PffGridSetCells(grid, cells));
  PetscCall(PffGridSetBlockSize(grid, 16));
  PetscCall(PffGridSetDomain(grid, origin, 1.0 / (PetscReal)n));
  PetscCall(PffGridSetPeriodic(grid, periodic));
  PetscCall(PffGridSetUp(grid));
  PetscCall(PffGridAddChannel(grid, "mass", PFF_CHANNEL_FACE, 1, &chMass));
  PetscCall(PffGridAddChannel(grid, "mom", PFF_CHANNEL_FACE, 1, &chMom));
  PetscCall(PffGridAddChannel(grid, "volume", PFF_CHANNEL_FACE, 1, &chVolume));
  PetscCall(PffGridAddChannel(grid, "u", PFF_CHANNEL_FACE, 2, &chU));
  PetscCall(PffGridAddChannel(grid, "du", PFF_CHANNEL_FACE, 2, &chDU));
  PetscCall(PffGridFillChannel(grid, chU, TaylorGreen, NULL));
  PetscCall(PffGridFillChannel(grid, chDU, TaylorGreen, NULL));
  PetscCall(PffGridHaloBegin(grid, chU));
  PetscCall(PffGridHaloEnd(grid, chU));
  PetscCall(PffGridHaloBegin(grid, chDU));
  PetscCall(PffGridHaloEnd(grid, chDU));
  PetscCall(PffParticlesCreate(grid, &part));
  PetscCall(PffParticlesSetFromOptions(part));
  PetscCall(PffParticlesSeed(part, Seed, NULL));
  PetscCall(PffParticlesGetTotals(part, NULL, count, NULL));
  for (PetscInt i = 0; i < 2 * PFF_GRID_MAX_LEVELS; i++) alpha[i] = 0.95;
  const PetscReal dt = 0.5 / (PetscReal)n; /* |u| <= 1: at most half a cell per step */
  const double    np = (double)(count[0] + count[1]);
  for (int t = 0; t < 2; t++) {
    omp_set_num_threads(t + 1);
    for (int k = 0; k < 4; k++) {
      double best = 1e30;
      for (PetscInt r = 0; r <= reps; r++) {
        PetscCallMPI(MPI_Barrier(PETSC_COMM_WORLD));
        const double t0 = MPI_Wtime();
        if (k == 0)
          PetscCall(PffParticlesP2G(part, density, chMass, chMom, -1));
        else if (k == 3)
          PetscCall(PffParticlesP2G(part, density, chMass, chMom, chVolume));
        else if (k == 1)
          PetscCall(PffParticlesG2P(part, chU, chDU, alpha));
        else
          PetscCall(PffParticlesAdvect(part, chU, dt, NULL, NULL, NULL));
        PetscCallMPI(MPI_Barrier(PETSC_COMM_WORLD));
        if (r > 0) best = PetscMin(best, MPI_Wtime() - t0);
      }
      rate[k][t] = np / best / 1e6;
    }
  }
  /* the streaming copy, per rank, all ranks at once (as the kernels run) */
  double gbs[2];
  {
    const size_t nd = (size_t)32 << 20; /* doubles: 256 MiB per array */
    double      *a, *b;
    PetscCall(PetscMalloc2(nd, &a, nd, &b));
    for (int t = 0; t < 2; t++) {
      double best = 1e30;
      omp_set_num_threads(t + 1);
#pragma omp parallel for schedule(static)
      for (size_t i = 0; i < nd; i++) a[i] = b[i] = (double)i;
      for (PetscInt r = 0; r <= reps; r++) {
        PetscCallMPI(MPI_Barrier(PETSC_COMM_WORLD));
        const double t0 = MPI_Wtime();
#pragma omp parallel for schedule(static)
        for (size_t i = 0; i < nd; i++) b[i] = a[i];
        PetscCallMPI(MPI_Barrier(PETSC_COMM_WORLD));
        if (r > 0) best = PetscMin(best, MPI_Wtime() - t0);
      }
      gbs[t] = 2.0 * (double)nd * sizeof(double) * (double)size / best / 1e9; /* all ranks */
    }
    PetscCall(PetscFree2(a, b));
  }
  PetscCall(
      PetscPrintf(PETSC_COMM_WORLD, "RESULT copy ranks=%d gb_s_1t=%.2f gb_s_2t=%.2f\n", (int)size, gbs[0], gbs[1]));
  const char  *names[4] = {"p2g", "g2p", "advect", "p2g_volume"};
  const double bytes[4] = {28, 40, 28, 28};
  for (int k = 0; k < 4; k++)
    PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                          "RESULT kernel=%s ranks=%d walls=%d particles=%.0f mparts_s_1t=%.2f mparts_s_2t=%.2f "
                          "bytes=%.0f copy_share_1t=%.3f copy_share_2t=%.3f\n",
                          names[k], (int)size, (int)walls, np, rate[k][0], rate[k][1], bytes[k],
                          rate[k][0] * 1e6 * bytes[k] / (gbs[0] * 1e9), rate[k][1] * 1e6 * bytes[k] / (gbs[1] * 1e9)));
  PetscCall(PffParticlesDestroy(&part));
  PetscCall(PffGridDestroy(&grid));
  PetscCall(PetscFinalize());
  return 0;
}
