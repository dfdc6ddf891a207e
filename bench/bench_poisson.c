/* pff-bench-poisson: the preconditioners of the pressure solve on the bubbly Poisson problem, the
   hardest system of a two-phase step (PF-FLIP Eq. 8 with a density ratio of 1e3 to 1e5).

   What it shows: iterations, set-up time and solve time of FCG with each PC (-bench_pcs: pffmg, gamg,
   hypre, bjacobi with ICC(0) blocks, jacobi) on the same problem, on a uniform grid and on a 3-level
   adaptive grid, through the public PffPressure API (SetCoefficients from face channels, a Dirichlet
   wall, the module's KSP with -pressure_pc_type <name> set per run). Set-up counts, because the
   coefficients change every time step.

   The problem. The unit cube, N^3 finest cells (-bench_n, default 64,128) in blocks of 16^3
   (-bench_block_size). Water rho = 1 with nine air bubbles of rho = 1/ratio (-bench_ratio, default 1e3),
   radius 0.1, centred at the eight points (0.25 or 0.75)^3 and at (0.5, 0.5, 0.5); a cell is air when
   its centre lies inside a bubble. Face coefficient beta_f = 1/rho_f, rho_f the arithmetic mean of the
   two cell densities (a coarse face over four fine cells: the mean of the coarse density and the mean of
   the four fine ones). p = 0 on the top face z = 1 (Dirichlet at half a cell, -pressure_dirichlet_walls
   zmax), no flow on the other five faces. The rhs is -V D u of a face velocity uniform in [-1, 1] (zero
   on the no-flow walls), from a counter-based hash of (level, axis, global face index at that level),
   so the problem is the same on any rank count. The adaptive grid has levels 0, 1, 2 (level 0 = h = 1/N):
   a block is finest when it intersects a bubble surface, otherwise coarsest, and the grid module grades
   it 2:1. Note that with 16^3 blocks at N = 64 (blocks of 0.25) every block touches a bubble surface, so
   the "adaptive" grid is uniform there; the "#" line before each grid gives the cells per level.
   Tolerance: relative true residual -bench_rtol (default 1e-8; the module's KSP uses the unpreconditioned
   norm), at most -bench_maxit iterations (default 10000), from p = 0.

   Sample run:
     mpiexec -n 2 build/bin/pff-bench-poisson                              (N = 64, 128, ratio 1e3)
     mpiexec -n 2 build/bin/pff-bench-poisson -bench_n 256 -bench_ratio 1e5 -bench_pcs gamg,hypre
   jobs/bench/poisson.sh runs the standard set and saves the output.

   What it prints, per grid one "#" line (cells per level), then per PC exactly one line
     RESULT pc=<name> grid=<uniform|adaptive> n=<N> ratio=<r> ranks=<r> threads=<t> its=<i> setup_s=<s>
            solve_s=<s> relres=<x>
   (on one line), then
     MEMORY pc=<name> ... peak_rss_MB_max_rank=<MB> peak_rss_B_per_cell=<B> solver_B_per_cell=<B> iteration_s=<s>
   (the process's peak resident size so far, all in, and per owned cell; the part above the resident size
   before the first pressure object, i.e. the pressure module, the PC and the Krylov method, per owned cell
   (exact for the first PC of a process, later ones reuse freed memory); max over ranks; the solve time per
   iteration), and for pffmg
     SWEEP pc=pffmg n=<N> level=0 ns_per_cell=<t> bytes_per_cell=44 copy_GBs=<bw> bound_ns_per_cell=<t> ratio=<r>
   (one fixed red-black sweep of the finest level against its memory traffic at the streaming copy
   bandwidth measured in the same run) and
     ITERATION pc=pffmg n=<N> cell_updates=<u> per_finest_cell=<u/cells> visits_per_finest_cell=<v/cells>
   iteration_s=<s> bound_s=<s> ratio=<r> imbalance=<max rank/mean> (the smoother's cell updates, all levels, per FCG
   iteration of the last solve, the cells its block visits brought in, and the time of an iteration against u x 44 B
   at the copy bandwidth of all ranks: the smoothing alone, every in-cache sweep of a visit counted as if it
   streamed), and
     TRAFFIC pc=pffmg n=<N> B_per_finest_cell=<B> smoothing=<B> transfers=<B> kcycle=<B> outer=<B> copy_GBs=<bw>
   iteration_s=<s> bound_s=<s> ratio=<r> (the bytes an iteration must move, per cell of the finest grid: 44 B per
   visited cell, the cycles' transfers, the K-cycles' and the outer FCG's vectors and products, each operation
   streaming its arrays once (PffPressureGetSolveTraffic, PffPressureMGGetStats; test_pressure_traffic checks the
   Krylov count against PETSc's log), and the iteration's time against that traffic at the copy bandwidth), with setup_s
   = KSPSetUp + KSPSetUpOnBlocks, solve_s = KSPSolve (PffPressureStats, timed with PetscTime inside the PressSolve log
   event; -log_view shows one stage per grid), relres
   =
   ||b - A p|| / ||b|| recomputed here from the module's operator, b and p. With -bench_repeat R (default 1)
   each PC sets up (new coefficients, as in a time step) and solves R times and the times are the
   best of R; a "#" line then gives the first set-up, which includes one-time symbolic work. A PC type that PETSc does
   not know prints "SKIP pc=<name> (not available)". The run fails (non-zero exit, after all PCs have run) when a KSP
   did not converge or relres > 1.05 rtol, and when an option was not used (misspelt). */
#include <pff.h>
#include <omp.h>
#include <string.h>
#include <sys/resource.h>

#define BENCH_MAX_N 8
#define BENCH_MAX_PCS 16
#define BENCH_NBUBBLES 9
#define BENCH_RADIUS 0.1
#define BENCH_RTOL_SLACK 1.05 /* FCG stops on its recurrence residual; the true one may be a little larger */

typedef struct {
  PetscInt  n[BENCH_MAX_N], nn, blockSize, maxit, repeat;
  PetscReal ratio, rtol;
  PetscBool grids[2]; /* uniform, adaptive */
  char     *pcs[BENCH_MAX_PCS];
  PetscInt  npcs;
  uint64_t  seed;
} BenchOptions;

static const char *const GridNames[2] = {"uniform", "adaptive"};

static void BubbleCentre(PetscInt b, PetscReal x[3])
{
  for (PetscInt a = 0; a < 3; a++) x[a] = b < 8 ? ((b >> a) & 1 ? 0.75 : 0.25) : 0.5;
}

/* rho at a cell centre: 1 in water, 1/ratio inside a bubble */
static PetscReal Density(const PetscReal x[3], PetscReal ratio)
{
  for (PetscInt b = 0; b < BENCH_NBUBBLES; b++) {
    PetscReal c[3], r2 = 0;
    BubbleCentre(b, c);
    for (PetscInt a = 0; a < 3; a++) r2 += PetscSqr(x[a] - c[a]);
    if (r2 < PetscSqr(BENCH_RADIUS)) return 1.0 / ratio;
  }
  return 1.0;
}

/* Finest where the block box intersects a bubble surface (the nearest point of the box is inside the
   sphere and the farthest corner outside), coarsest elsewhere; the grid grades the rest. */
static PetscErrorCode RefineBubbles(PffGrid grid, const PetscReal lo[3], const PetscReal hi[3], PetscInt *level,
                                    void *ctx)
{
  const PetscInt nlevels = *(const PetscInt *)ctx;

  PetscFunctionBeginUser;
  *level = nlevels - 1;
  for (PetscInt b = 0; b < BENCH_NBUBBLES; b++) {
    PetscReal c[3], dmin2 = 0, dmax2 = 0;
    BubbleCentre(b, c);
    for (PetscInt a = 0; a < 3; a++) {
      const PetscReal near = PetscMax(lo[a], PetscMin(c[a], hi[a]));
      dmin2 += PetscSqr(near - c[a]);
      dmax2 += PetscSqr(PetscMax(PetscAbsReal(lo[a] - c[a]), PetscAbsReal(hi[a] - c[a])));
    }
    if (dmin2 <= PetscSqr(BENCH_RADIUS) && dmax2 >= PetscSqr(BENCH_RADIUS)) *level = 0;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* splitmix64 finaliser chain, the construction of the particles' counter-based RNG
   (PffRandom01_Private), which is private to src/particles: uniform in [0, 1). */
static inline uint64_t Hash64(uint64_t z)
{
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}
static inline PetscReal Random01(uint64_t seed, uint64_t id, uint64_t purpose, uint64_t counter)
{
  return (PetscReal)(Hash64(Hash64(Hash64(seed) ^ id) ^ (purpose << 32 | counter)) >> 11) / 9007199254740992.0;
}

/* Centre of the cell of size h that contains the point x (origin 0). */
static void CellCentreAt(const PetscReal x[3], PetscReal h, PetscReal c[3])
{
  for (PetscInt a = 0; a < 3; a++) c[a] = (PetscFloorReal(x[a] / h) + 0.5) * h;
}

static PetscReal Zero(const PetscReal x[3], PetscInt comp, void *ctx)
{
  (void)x, (void)comp, (void)ctx;
  return 0;
}

/* beta = 1/rho_f on the lower faces of the owned cells and the random u* (0 on the lower walls). */
static PetscErrorCode FillProblem(PffGrid grid, const BenchOptions *o, PetscInt betaCh, PetscInt uCh)
{
  PetscInt        nb[3], nlocal;
  const PetscInt *level;
  PetscBool       periodic[3];
  PetscReal       h0;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetRaster(grid, nb, &level, NULL));
  PetscCall(PffGridGetSizes(grid, NULL, NULL, NULL, &h0, periodic));
  PetscCall(PffGridGetLocalBlocks(grid, &nlocal));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(grid, lb, &info));
    const PetscInt  n = info.n;
    const PetscReal h = info.h;
    /* cells per axis of the whole domain at this block's level, for the global face index */
    const uint64_t nl = (uint64_t)(nb[0] * n);
    for (PetscInt d = 0; d < 3; d++) {
      float   *beta, *u;
      PetscInt dir[3]     = {0, 0, 0};
      dir[d]              = -1;
      const PetscInt ngid = PffRasterNeighbour(nb, periodic, info.ijk, dir);
      PetscCall(PffGridGetBlockData(grid, betaCh, lb, d, &beta));
      PetscCall(PffGridGetBlockData(grid, uCh, lb, d, &u));
      for (PetscInt k = 0; k < n; k++)
        for (PetscInt j = 0; j < n; j++)
          for (PetscInt i = 0; i < n; i++) {
            const PetscInt c[3] = {i, j, k}, q = i + n * (j + n * k);
            PetscReal      xc[3], xl[3], rlow;
            for (PetscInt a = 0; a < 3; a++) xc[a] = info.lo[a] + ((PetscReal)c[a] + 0.5) * h;
            const PetscReal rc   = Density(xc, o->ratio);
            const PetscBool wall = (PetscBool)(c[d] == 0 && ngid < 0);
            if (wall)
              rlow = rc; /* closed face: any positive beta */
            else if (c[d] > 0 || level[ngid] >= info.level) {
              /* one cell below: same block, same-level or coarser neighbour */
              const PetscReal hn   = c[d] > 0 ? h : h0 * (PetscReal)(1 << level[ngid]);
              PetscReal       y[3] = {xc[0], xc[1], xc[2]};
              y[d]                 = xc[d] - 0.5 * h - 0.5 * hn;
              CellCentreAt(y, hn, xl);
              rlow = Density(xl, o->ratio);
            } else { /* finer neighbour: the mean density of the 4 fine cells under the coarse face */
              const PetscReal hf = 0.5 * h;
              rlow               = 0;
              for (PetscInt s = 0; s < 4; s++) {
                PetscInt e = 0;
                for (PetscInt a = 0; a < 3; a++) {
                  if (a == d)
                    xl[a] = xc[a] - 0.5 * h - 0.5 * hf;
                  else
                    xl[a] = xc[a] + ((s >> e++) & 1 ? 0.5 : -0.5) * hf;
                }
                rlow += 0.25 * Density(xl, o->ratio);
              }
            }
            beta[q] = (float)(2.0 / (rc + rlow));
            if (wall)
              u[q] = 0;
            else {
              uint64_t gi[3]; /* global cell index at the block's level */
              for (PetscInt a = 0; a < 3; a++) gi[a] = (uint64_t)(info.ijk[a] * n + c[a]);
              const uint64_t face = (uint64_t)d + 3 * (gi[0] + nl * (gi[1] + nl * gi[2]));
              u[q]                = (float)(2 * Random01(o->seed, face, 1, (uint64_t)info.level) - 1);
            }
          }
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Whether PETSc (or a package registered before, e.g. by PffPressureCreate) knows PC type name:
   PCSetType on a scratch PC with the error handler that only returns the code. */
static PetscErrorCode PCTypeAvailable(MPI_Comm comm, const char *name, PetscBool *avail)
{
  PC             pc;
  PetscErrorCode ierr;

  PetscFunctionBeginUser;
  PetscCall(PCCreate(comm, &pc));
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  ierr = PCSetType(pc, name);
  PetscCall(PetscPopErrorHandler());
  PetscCall(PCDestroy(&pc));
  PetscCheck(ierr == PETSC_SUCCESS || ierr == PETSC_ERR_ARG_UNKNOWN_TYPE, comm, ierr,
             "bench: PCSetType(%s) failed with error %d", name, (int)ierr);
  *avail = ierr == PETSC_SUCCESS ? PETSC_TRUE : PETSC_FALSE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* One grid, every PC; *nfail counts runs that did not converge to rtol. */
/* Streaming copy bandwidth of this rank (read + write bytes per second), the bound of a memory-bound
   kernel; all ranks copy at once, as they sweep at once. */
static PetscErrorCode CopyBandwidth(MPI_Comm comm, PetscReal *gbs)
{
  const size_t   n = (size_t)1 << 24; /* 128 MiB per array, far beyond the caches */
  double        *a, *b;
  PetscLogDouble best = PETSC_MAX_REAL;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc2(n, &a, n, &b));
  for (size_t i = 0; i < n; i++) a[i] = (double)i;
  for (PetscInt rep = 0; rep < 5; rep++) {
    PetscLogDouble t0, t1;
    PetscCallMPI(MPI_Barrier(comm));
    PetscCall(PetscTime(&t0));
    memcpy(b, a, n * sizeof(double));
    PetscCall(PetscTime(&t1));
    best = PetscMin(best, t1 - t0);
  }
  *gbs = 2.0 * n * sizeof(double) / best / 1e9;
  PetscCall(PetscFree2(a, b));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* pffmg only: the time of one fixed red-black sweep of the finest level per cell, against the time
   its memory traffic takes at the copy bandwidth: PFF_MG_VISIT_BYTES per cell (a sweep is one visit). */
static PetscErrorCode SweepRate(MPI_Comm comm, PffPressure ps, KSP ksp, PetscInt N, const PffPressureStats *pst)
{
  PffMGStats     mst;
  Mat            A;
  Vec            x, b;
  PetscRandom    rnd;
  PetscLogDouble best = PETSC_MAX_REAL;
  PetscReal      gbs;
  PetscInt       nloc;
  const PetscInt sweeps = 10;

  PetscFunctionBeginUser;
  PetscCall(PffPressureMGGetStats(ps, &mst)); /* of the last solve, before the sweeps below add theirs */
  PetscCall(KSPGetOperators(ksp, &A, NULL));
  PetscCall(MatCreateVecs(A, &x, &b));
  PetscCall(VecGetLocalSize(x, &nloc));
  PetscCall(PetscRandomCreate(comm, &rnd));
  PetscCall(VecSetRandom(x, rnd));
  PetscCall(VecSet(b, 0.0));
  PetscCall(PffPressureMGSmooth(ps, 0, b, x, 1)); /* warm-up */
  for (PetscInt rep = 0; rep < 3; rep++) {
    PetscLogDouble t0, t1;
    PetscCallMPI(MPI_Barrier(comm));
    PetscCall(PetscTime(&t0));
    PetscCall(PffPressureMGSmooth(ps, 0, b, x, sweeps));
    PetscCall(PetscTime(&t1));
    best = PetscMin(best, t1 - t0);
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &best, 1, MPI_DOUBLE, MPI_MAX, comm));
  PetscCall(CopyBandwidth(comm, &gbs));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &gbs, 1, MPIU_REAL, MPI_MIN, comm));
  {
    const PetscReal ns = best / sweeps / (PetscReal)nloc * 1e9, bound = PFF_MG_VISIT_BYTES / gbs;
    PetscCall(PetscPrintf(comm,
                          "SWEEP pc=pffmg n=%" PetscInt_FMT
                          " level=0 ns_per_cell=%.2f bytes_per_cell=%.0f copy_GBs=%.1f "
                          "bound_ns_per_cell=%.2f ratio=%.2f\n",
                          N, (double)ns, PFF_MG_VISIT_BYTES, (double)gbs, (double)bound, (double)(ns / bound)));
  }
  if (pst->its > 0) {
    /* an iteration against the time its memory traffic takes at the copy bandwidth of all ranks, two ways: the
       cell updates of all levels x 44 B (the smoothing alone, every in-cache sweep counted as if it streamed), and
       the bytes it must move: 44 B per cell a block visit brings in, the transfers, the K-cycles' and the outer
       FCG's vectors and products (each operation streaming its arrays once; PffPressureGetSolveTraffic) */
    PetscMPIInt    size;
    PetscLogDouble outer;
    PetscBool      known;
    PetscCallMPI(MPI_Comm_size(comm, &size));
    PetscCall(PffPressureGetSolveTraffic(ps, pst, &outer, &known));
    PetscInt nglob;
    PetscCall(VecGetSize(x, &nglob));
    const PetscReal cells = (PetscReal)nglob, bw = gbs * 1e9 * size;
    const PetscReal upd = (PetscReal)mst.cellUpdates / pst->its, it = pst->solveTime / pst->its;
    const PetscReal bnd      = upd * PFF_MG_VISIT_BYTES / bw;
    const PetscReal smooth   = PFF_MG_VISIT_BYTES * (PetscReal)mst.cellVisits / pst->its,
                    transfer = mst.bytesTransfer / pst->its, kcycle = mst.bytesKCycle / pst->its,
                    out = outer / pst->its, total = smooth + transfer + kcycle + out;
    PetscCall(PetscPrintf(
        comm,
        "ITERATION pc=pffmg n=%" PetscInt_FMT " cell_updates=%.3g per_finest_cell=%.2f "
        "visits_per_finest_cell=%.2f iteration_s=%.4f bound_s=%.4f ratio=%.2f imbalance=%.2f\n",
        N, (double)upd, (double)(upd / cells), (double)(mst.cellVisits / pst->its / cells), (double)it, (double)bnd,
        (double)(it / bnd),
        (double)(mst.cellUpdates > 0 ? (PetscReal)mst.cellUpdatesMax * size / (PetscReal)mst.cellUpdates : 1)));
    if (known)
      PetscCall(PetscPrintf(comm,
                            "TRAFFIC pc=pffmg n=%" PetscInt_FMT " B_per_finest_cell=%.0f smoothing=%.0f transfers=%.0f "
                            "kcycle=%.0f outer=%.0f copy_GBs=%.1f iteration_s=%.4f bound_s=%.4f ratio=%.2f\n",
                            N, (double)(total / cells), (double)(smooth / cells), (double)(transfer / cells),
                            (double)(kcycle / cells), (double)(out / cells), (double)gbs, (double)it,
                            (double)(total / bw), (double)(it * bw / total)));
  }
  PetscCall(PetscRandomDestroy(&rnd));
  PetscCall(VecDestroy(&x));
  PetscCall(VecDestroy(&b));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode BenchGrid(MPI_Comm comm, const BenchOptions *o, PetscInt N, PetscInt g, PetscLogStage stage,
                                PetscInt *nfail)
{
  const PetscInt  nb = N / o->blockSize, cells[3] = {N, N, N};
  const PetscBool periodic[3] = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};
  const PetscBool walls[6]    = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE, PETSC_FALSE, PETSC_FALSE, PETSC_TRUE};
  const PetscReal origin[3]   = {0, 0, 0};
  PetscInt        nlevels     = g == 0 ? 1 : 3, betaCh, uCh, pCh;
  PetscInt64      perLevel[PFF_GRID_MAX_LEVELS], total;
  PetscMPIInt     size;
  PffGrid         grid;
  PetscLogDouble  baseline;

  PetscFunctionBeginUser;
  PetscCheck(N % o->blockSize == 0 && nb >= 1, comm, PETSC_ERR_ARG_OUTOFRANGE,
             "bench: -bench_n %" PetscInt_FMT " is not a multiple of -bench_block_size %" PetscInt_FMT, N,
             o->blockSize);
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(PffGridCreate(comm, &grid));
  PetscCall(PffGridSetCells(grid, cells));
  PetscCall(PffGridSetBlockSize(grid, o->blockSize));
  PetscCall(PffGridSetLevels(grid, nlevels));
  PetscCall(PffGridSetDomain(grid, origin, 1.0 / (PetscReal)N));
  PetscCall(PffGridSetPeriodic(grid, periodic));
  if (g == 1) PetscCall(PffGridSetRefinementFunction(grid, RefineBubbles, &nlevels));
  PetscCall(PffGridAddChannel(grid, "beta", PFF_CHANNEL_FACE, 1, &betaCh));
  PetscCall(PffGridAddChannel(grid, "u", PFF_CHANNEL_FACE, 1, &uCh));
  PetscCall(PffGridAddChannel(grid, "p", PFF_CHANNEL_CELL, 1, &pCh));
  PetscCall(PffGridSetUp(grid));
  PetscCall(PffGridGetCellCounts(grid, perLevel, &total));
  PetscCall(
      PetscPrintf(comm, "# grid=%s n=%" PetscInt_FMT " cells=%" PetscInt64_FMT " per level", GridNames[g], N, total));
  for (PetscInt l = 0; l < nlevels; l++) PetscCall(PetscPrintf(comm, " %" PetscInt64_FMT, perLevel[l]));
  PetscCall(PetscPrintf(comm, "\n"));

  /* the grid and the problem's channels touched once, so that the resident size before the pressure module
     is the baseline of its memory line */
  PetscCall(FillProblem(grid, o, betaCh, uCh));
  PetscCall(PffGridFillChannel(grid, pCh, Zero, NULL));
  PetscCall(PetscMemoryGetCurrentUsage(&baseline)); /* resident bytes now */
  PetscCall(PetscLogStagePush(stage));
  for (PetscInt k = 0; k < o->npcs; k++) {
    PffPressure      ps;
    PffPressureStats st;
    KSP              ksp;
    Vec              p;
    PetscReal        relres;
    PetscBool        avail = PETSC_FALSE, ispffmg;
    char             ratio[32];
    PetscInt         nloc;

    /* PffPressureCreate first: the pressure module may register its own PC types there */
    PetscCall(PffPressureCreate(grid, &ps));
    PetscCall(PCTypeAvailable(comm, o->pcs[k], &avail));
    if (!avail) {
      PetscCall(PetscPrintf(comm, "SKIP pc=%s (not available)\n", o->pcs[k]));
      PetscCall(PffPressureDestroy(&ps));
      continue;
    }
    PetscCall(PetscOptionsSetValue(NULL, "-pressure_pc_type", o->pcs[k]));
    PetscCall(PffPressureSetDirichletWalls(ps, walls));
    PetscCall(PffPressureGetKSP(ps, &ksp));
    PetscCall(KSPSetTolerances(ksp, o->rtol, 0.0, PETSC_DEFAULT, o->maxit));
    PetscCall(PffPressureSetFromOptions(ps));
    PetscCall(PffPressureSetUp(ps));
    /* repeat as a time step would: new coefficients (numeric set-up) and a solve from p = 0; the
       first set-up also holds the one-time symbolic work, so the minimum over repeats is reported */
    PetscLogDouble setupFirst = 0, setupMin = PETSC_MAX_REAL, solveMin = PETSC_MAX_REAL;
    PetscCall(PetscStrcmp(o->pcs[k], "pffmg", &ispffmg));
    for (PetscInt rep = 0; rep < o->repeat; rep++) {
      if (ispffmg && rep > 0 && rep == o->repeat - 1) PetscCall(PffPressureMGResetStats(ps)); /* count one solve */
      PetscCall(FillProblem(grid, o, betaCh, uCh)); /* the projection overwrote u */
      PetscCall(PffGridFillChannel(grid, pCh, Zero, NULL));
      PetscCall(PffPressureSetCoefficients(ps, betaCh, -1));
      PetscCall(PffPressureProject(ps, uCh, 1.0, -1, pCh, &st));
      if (rep == 0) setupFirst = st.setupTime;
      setupMin = PetscMin(setupMin, st.setupTime);
      solveMin = PetscMin(solveMin, st.solveTime);
    }
    st.setupTime = setupMin;
    st.solveTime = solveMin;
    /* relres: the module's own true residual |b - A p| / |b| with the operator the KSP applied (the
       assembled A or the matrix-free one), independent of what the KSP monitored; no extra Vec, so that
       the memory line counts the solver alone */
    PetscCall(KSPGetSolution(ksp, &p));
    relres = st.rnorm;
    /* plain C formatting: PetscPrintf would print 1000 as "1000." */
    (void)snprintf(ratio, sizeof(ratio), "%g", (double)o->ratio);
    PetscCall(PetscPrintf(comm,
                          "RESULT pc=%s grid=%s n=%" PetscInt_FMT " ratio=%s ranks=%d threads=%d its=%" PetscInt_FMT
                          " setup_s=%.3f solve_s=%.3f relres=%.2e\n",
                          o->pcs[k], GridNames[g], N, ratio, (int)size, omp_get_max_threads(), st.its,
                          (double)st.setupTime, (double)st.solveTime, (double)relres));
    if (o->repeat > 1)
      PetscCall(PetscPrintf(
          comm, "# pc=%s first set-up (with the symbolic part) %.3f s; times above: best of %" PetscInt_FMT "\n",
          o->pcs[k], (double)setupFirst, o->repeat));
    {
      /* memory: the peak resident size of the process so far (grid and problem included; it covers the
         earlier PCs and grids of the same run too, so run one PC and grid per process to attribute it),
         and the same per owned cell; max over ranks */
      PetscLogDouble m[3];
      struct rusage  ru;
      PetscCall(VecGetLocalSize(p, &nloc));
      getrusage(RUSAGE_SELF, &ru);
      m[0] = (PetscLogDouble)ru.ru_maxrss * 1024.0;
      m[1] = m[0] / (PetscLogDouble)PetscMax(nloc, 1);
      m[2] = (m[0] - baseline) / (PetscLogDouble)PetscMax(nloc, 1); /* the solver's share: above the grid's */
      PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, m, 3, MPI_DOUBLE, MPI_MAX, comm));
      PetscCall(PetscPrintf(
          comm,
          "MEMORY pc=%s grid=%s n=%" PetscInt_FMT " peak_rss_MB_max_rank=%.0f peak_rss_B_per_cell=%.0f "
          "solver_B_per_cell=%.0f iteration_s=%.4f\n",
          o->pcs[k], GridNames[g], N, m[0] / 1048576.0, m[1], m[2], (double)(st.its > 0 ? st.solveTime / st.its : 0)));
    }
    if (ispffmg) PetscCall(SweepRate(comm, ps, ksp, N, &st));
    if (st.reason <= 0 || !(relres <= BENCH_RTOL_SLACK * o->rtol)) {
      PetscCall(PetscPrintf(comm, "# FAILED pc=%s grid=%s n=%" PetscInt_FMT ": %s, relres %.2e > %.2e\n", o->pcs[k],
                            GridNames[g], N, KSPConvergedReasons[st.reason], (double)relres,
                            (double)(BENCH_RTOL_SLACK * o->rtol)));
      (*nfail)++;
    }
    PetscCall(PffPressureDestroy(&ps));
  }
  PetscCall(PetscLogStagePop());
  PetscCall(PetscOptionsClearValue(NULL, "-pressure_pc_type"));
  PetscCall(PffGridDestroy(&grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode ProcessOptions(MPI_Comm comm, BenchOptions *o)
{
  const char *const gridChoices[3] = {"uniform", "adaptive", "both"};
  PetscInt          grid = 2, seed = 0;
  PetscBool         nset;
  char              pcs[PETSC_MAX_PATH_LEN] = "pffmg,gamg,hypre,bjacobi,jacobi";

  PetscFunctionBeginUser;
  o->n[0]      = 64;
  o->n[1]      = 128;
  o->nn        = BENCH_MAX_N;
  o->blockSize = 16;
  o->maxit     = 10000;
  o->repeat    = 1;
  o->ratio     = 1e3;
  o->rtol      = 1e-8;
  PetscOptionsBegin(comm, NULL, "Bubbly Poisson benchmark", NULL);
  PetscCall(PetscOptionsIntArray("-bench_n", "Finest cells per axis (list)", NULL, o->n, &o->nn, &nset));
  PetscCall(
      PetscOptionsInt("-bench_block_size", "Cells per block axis at level 0", NULL, o->blockSize, &o->blockSize, NULL));
  PetscCall(PetscOptionsReal("-bench_ratio", "Density ratio water / air", NULL, o->ratio, &o->ratio, NULL));
  PetscCall(PetscOptionsEList("-bench_grid", "Grids to run", NULL, gridChoices, 3, gridChoices[grid], &grid, NULL));
  PetscCall(PetscOptionsString("-bench_pcs", "Comma-separated PC types (-pressure_pc_type per run)", NULL, pcs, pcs,
                               sizeof(pcs), NULL));
  PetscCall(PetscOptionsReal("-bench_rtol", "Relative tolerance on the true residual", NULL, o->rtol, &o->rtol, NULL));
  PetscCall(PetscOptionsInt("-bench_maxit", "Maximum Krylov iterations", NULL, o->maxit, &o->maxit, NULL));
  PetscCall(PetscOptionsBoundedInt("-bench_repeat", "Set-ups and solves per PC (times: the best)", NULL, o->repeat,
                                   &o->repeat, NULL, 1));
  PetscCall(PetscOptionsInt("-bench_seed", "Key of the random velocity", NULL, seed, &seed, NULL));
  PetscOptionsEnd();
  if (!nset) o->nn = 2; /* the two defaults */
  PetscCheck(o->ratio >= 1 && PetscIsNormalReal(o->ratio), comm, PETSC_ERR_ARG_OUTOFRANGE,
             "bench: -bench_ratio %g must be >= 1", (double)o->ratio);
  PetscCheck(o->rtol > 0 && o->rtol < 1, comm, PETSC_ERR_ARG_OUTOFRANGE, "bench: -bench_rtol %g must be in (0, 1)",
             (double)o->rtol);
  o->grids[0] = (PetscBool)(grid != 1);
  o->grids[1] = (PetscBool)(grid != 0);
  o->seed     = (uint64_t)seed;
  {
    PetscToken tok;
    char      *t;
    o->npcs = 0;
    PetscCall(PetscTokenCreate(pcs, ',', &tok));
    PetscCall(PetscTokenFind(tok, &t));
    while (t != NULL) {
      PetscCheck(o->npcs < BENCH_MAX_PCS, comm, PETSC_ERR_ARG_OUTOFRANGE, "bench: more than %d PCs in -bench_pcs",
                 BENCH_MAX_PCS);
      PetscCall(PetscStrallocpy(t, &o->pcs[o->npcs++]));
      PetscCall(PetscTokenFind(tok, &t));
    }
    PetscCall(PetscTokenDestroy(&tok));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  BenchOptions  o;
  PetscLogStage stages[2];
  PetscInt      nfail = 0;

  PetscCall(PetscInitialize(&argc, &argv, NULL, "pff-bench-poisson: preconditioners on the bubbly Poisson problem\n"));
  PetscCall(PffHugePagesSetFromOptions(PETSC_COMM_WORLD));
  PetscCall(PffInitializePackage());
  PetscCall(ProcessOptions(PETSC_COMM_WORLD, &o));
  PetscCall(PetscLogStageRegister("Bench uniform", &stages[0]));
  PetscCall(PetscLogStageRegister("Bench adaptive", &stages[1]));
  for (PetscInt i = 0; i < o.nn; i++)
    for (PetscInt g = 0; g < 2; g++)
      if (o.grids[g]) PetscCall(BenchGrid(PETSC_COMM_WORLD, &o, o.n[i], g, stages[g], &nfail));
  for (PetscInt k = 0; k < o.npcs; k++) PetscCall(PetscFree(o.pcs[k]));
  /* at the end, because PC-specific options (-pressure_pc_gamg_...) are read only when that PC runs */
  PetscCall(PffOptionsCheckUnused(PETSC_COMM_WORLD));
  PetscCheck(nfail == 0, PETSC_COMM_WORLD, PETSC_ERR_NOT_CONVERGED,
             "bench: %" PetscInt_FMT " run(s) did not reach the relative residual %g (lines '# FAILED' above)", nfail,
             (double)o.rtol);
  PetscCall(PetscFinalize());
  return 0;
}
