/* pff-bench-grid: bandwidth of the MSBG 7-point Laplacian against a streaming copy (paper Table 3).

   mpiexec -n 2 build/bin/pff-bench-grid                       (2 ranks x 1 thread)
   OMP_NUM_THREADS=2 mpiexec -n 1 build/bin/pff-bench-grid     (1 rank x 2 threads)

   Case uniform: a 256^3 grid (-bench_n) stored as 16^3 blocks, periodic. Case adaptive: a 512^3
   domain (-bench_adaptive_n) with 3 levels refined around a sphere of radius 0.3, about as many active
   cells as the uniform case, so that neither fits in the last-level cache. Each case times -bench_reps applications of
   the Laplacian (ghosts exchanged once beforehand, and that exchange timed on its own) and, in the same run, a
   streaming copy of the same number of cells between two arrays of the same size. Both move 4 bytes in and 4 bytes out
   per cell, so pct_copy = Laplacian cells/s over copy cells/s. Prints RESULT case=<uniform|adaptive> ranks=<r>
   threads=<t> mcells_s=<x> pct_copy=<y> ... Rates are per run (all ranks), the best of -bench_reps repetitions (after
   one warm-up). */
#include <pff.h>
#include <omp.h>

static PetscErrorCode BenchCopy(MPI_Comm comm, PetscInt64 ncells, PetscInt reps, double *best)
{
  float *a, *b;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc2(ncells, &a, ncells, &b));
#pragma omp parallel for schedule(static)
  for (PetscInt64 i = 0; i < ncells; i++) {
    a[i] = (float)(i % 17);
    b[i] = 0.0f;
  }
  *best = 1e30;
  for (PetscInt r = 0; r <= reps; r++) {
    double t0, t1;
    PetscCallMPI(MPI_Barrier(comm));
    t0 = MPI_Wtime();
#pragma omp parallel for schedule(static)
    for (PetscInt64 i = 0; i < ncells; i++) b[i] = a[i];
    PetscCallMPI(MPI_Barrier(comm));
    t1 = MPI_Wtime();
    if (r > 0) *best = PetscMin(*best, t1 - t0);
  }
  PetscCheck(b[ncells / 2] == a[ncells / 2], PETSC_COMM_SELF, PETSC_ERR_PLIB, "copy check failed");
  PetscCall(PetscFree2(a, b));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode BenchCase(MPI_Comm comm, const char *name, PetscInt n, PetscInt levels, PetscInt reps)
{
  PffGrid     grid;
  PetscInt    u, lap, nlocal, cells[3] = {n, n, n};
  PetscBool   periodic[3] = {PETSC_TRUE, PETSC_TRUE, PETSC_TRUE};
  PetscReal   origin[3]   = {0, 0, 0};
  PetscInt64  local       = 0, total;
  double      tl = 1e30, th, tc = 1e30;
  PetscMPIInt size;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(PffGridCreate(comm, &grid));
  PetscCall(PffGridSetCells(grid, cells));
  PetscCall(PffGridSetBlockSize(grid, 16));
  PetscCall(PffGridSetLevels(grid, levels));
  PetscCall(PffGridSetDomain(grid, origin, 1.0 / (PetscReal)n));
  PetscCall(PffGridSetPeriodic(grid, periodic));
  PetscCall(PffGridSetFromOptions(grid)); /* -grid_refine sphere etc. from the command line */
  PetscCall(PffGridAddChannel(grid, "u", PFF_CHANNEL_CELL, 1, &u));
  PetscCall(PffGridAddChannel(grid, "lap", PFF_CHANNEL_CELL, 1, &lap));
  PetscCall(PffGridSetUp(grid));
  PetscCall(PffGridGetLocalBlocks(grid, &nlocal));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    float       *v;
    PetscCall(PffGridGetBlockInfo(grid, lb, &info));
    PetscCall(PffGridGetBlockData(grid, u, lb, 0, &v));
    for (PetscInt c = 0; c < info.n * info.n * info.n; c++) v[c] = (float)((c * 7 + lb) % 13);
    local += info.n * info.n * info.n;
  }
  PetscCallMPI(MPI_Allreduce(&local, &total, 1, MPIU_INT64, MPI_SUM, comm));
  PetscCallMPI(MPI_Barrier(comm));
  th = MPI_Wtime();
  PetscCall(PffGridHaloBegin(grid, u));
  PetscCall(PffGridHaloEnd(grid, u));
  PetscCallMPI(MPI_Barrier(comm));
  th = MPI_Wtime() - th;
  for (PetscInt r = 0; r <= reps; r++) {
    double t0;
    PetscCallMPI(MPI_Barrier(comm));
    t0 = MPI_Wtime();
    PetscCall(PffGridApplyLaplacian(grid, u, lap));
    PetscCallMPI(MPI_Barrier(comm));
    if (r > 0) tl = PetscMin(tl, MPI_Wtime() - t0);
  }
  PetscCall(BenchCopy(comm, local, reps, &tc));
  const double lrate = (double)total / tl * 1e-6, crate = (double)total / tc * 1e-6;
  PetscCall(PetscPrintf(comm,
                        "RESULT case=%s ranks=%d threads=%d mcells_s=%.1f pct_copy=%.1f cells=%" PetscInt64_FMT
                        " copy_mcells_s=%.1f copy_gb_s=%.2f halo_ms=%.2f\n",
                        name, size, omp_get_max_threads(), lrate, 100.0 * lrate / crate, total, crate, crate * 8e-3,
                        th * 1e3));
  PetscCall(PffGridDestroy(&grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  PetscInt n = 256, na = 512, reps = 10;
  char     which[32] = "all";

  PetscCall(PetscInitialize(&argc, &argv, NULL, "pff-bench-grid: MSBG Laplacian vs streaming copy\n"));
  PetscCall(PffHugePagesSetFromOptions(PETSC_COMM_WORLD));
  PetscCall(PffInitializePackage());
  PetscOptionsBegin(PETSC_COMM_WORLD, NULL, "Grid benchmark", NULL);
  PetscCall(PetscOptionsInt("-bench_n", "Finest cells per axis", NULL, n, &n, NULL));
  PetscCall(PetscOptionsInt("-bench_adaptive_n", "Finest cells per axis of the adaptive case", NULL, na, &na, NULL));
  PetscCall(PetscOptionsInt("-bench_reps", "Timed repetitions (best is kept)", NULL, reps, &reps, NULL));
  PetscCall(PetscOptionsString("-bench_case", "uniform, adaptive or all", NULL, which, which, sizeof(which), NULL));
  PetscOptionsEnd();
  if (!strcmp(which, "all") || !strcmp(which, "uniform")) PetscCall(BenchCase(PETSC_COMM_WORLD, "uniform", n, 1, reps));
  if (!strcmp(which, "all") || !strcmp(which, "adaptive")) {
    /* three levels graded around a sphere of radius 0.3 (unless overridden on the command line) */
    PetscCall(PetscOptionsSetValue(NULL, "-grid_refine", "sphere"));
    PetscCall(PetscOptionsSetValue(NULL, "-grid_refine_radius", "0.3"));
    PetscCall(BenchCase(PETSC_COMM_WORLD, "adaptive", na, 3, reps));
  }
  PetscCall(PetscFinalize());
  return 0;
}
