/* pff-bench-tall: the projection of one liquid scene with three discretisations of the same effective
   resolution, as in Narita et al. 2025, Tables 1-2 (projection columns): uniform cubic cells, uniform tall
   cells (Irving et al. 2006 in the variational form) and quadtree tall cells.

   The scene (-bench_scene drop): the unit box with N^3 finest cells (-bench_n, default 64) in blocks of 8^3;
   a pool of depth 0.5 and a drop of radius 0.08 just above it at (0.5, 0.62, 0.5), falling at 2 m/s (the
   moment before impact of the paper's Fig. 5). phi is the exact signed distance, u* = -g dt on every
   vertical face (dt = 1e-3 s) plus the drop's -2 m/s on the faces inside it. The quadtree comes from the
   sizing function (PffTallSizingLevels: curvature and velocity variation at the surface, -tall_levels 3 by
   default here) evaluated on the uniform grid, graded 2:1 by the grid. Every method uses the same KSP
   (CG with block Jacobi / ICC(0) by default, relative residual 1e-4 as in the paper; -tall_* options).

   Sample run:  mpiexec -n 2 build/bin/pff-bench-tall -bench_n 128
   Prints one line per method
     RESULT scene=drop method=<uniform|tall|quadtree> n=<N> ranks=<r> cells=<c> tall_cells=<t> samples=<s>
            rows=<r> liquid_cells=<l> sizing_s=<s> quadtree_s=<s> assemble_s=<s> solve_s=<s> projection_s=<s>
            res0=<inf-norm> res=<inf-norm> its=<i> peak_rss_MB=<MB>
   (best of -bench_repeat R runs of Build + Project; sizing_s and quadtree_s for the quadtree only: the sizing
   function and the grid set-up on its map), then
     RATIO projection_uniform_over_quadtree=<x> projection_tall_over_quadtree=<x> cells_uniform_over_quadtree=<x>
           total_uniform_over_quadtree=<x>
   with total = sizing + quadtree + projection. Fails when a solve does not converge. */
#include <pff.h>
#include <sys/resource.h>

#define BENCH_N0 8
#define BENCH_G 9.81
#define BENCH_DT 1e-3
#define BENCH_RHO 1000.0

static const char help[] = "Projection on uniform cubic, uniform tall and quadtree tall cells (Narita et al. 2025).\n";

typedef struct {
  PetscReal H, r, c[3], vdrop;
} Drop;

static PetscReal DropPhi(const PetscReal x[3], PetscInt comp, void *vctx)
{
  const Drop *d = (const Drop *)vctx;
  (void)comp;
  const PetscReal ds = PetscSqrtReal(PetscSqr(x[0] - d->c[0]) + PetscSqr(x[1] - d->c[1]) + PetscSqr(x[2] - d->c[2]));
  return PetscMin(x[1] - d->H, ds - d->r);
}

static PetscReal DropU(const PetscReal x[3], PetscInt comp, void *vctx)
{
  const Drop *d = (const Drop *)vctx;
  if (comp != 1 || x[1] < 1e-12) return 0;
  const PetscReal ds = PetscSqrtReal(PetscSqr(x[0] - d->c[0]) + PetscSqr(x[1] - d->c[1]) + PetscSqr(x[2] - d->c[2]));
  return -BENCH_G * BENCH_DT + (ds < d->r ? d->vdrop : 0);
}

typedef struct {
  PffGrid  grid;
  PetscInt phi, u, p;
} Case;

static PetscErrorCode CaseCreate(PetscInt n, const PetscInt *map, Drop *drop, Case *c)
{
  const PetscInt  cells[3]  = {n, n, n};
  const PetscReal origin[3] = {0, 0, 0};
  const PetscBool per[3]    = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};

  PetscFunctionBeginUser;
  PetscCall(PffGridCreate(PETSC_COMM_WORLD, &c->grid));
  PetscCall(PffGridSetCells(c->grid, cells));
  PetscCall(PffGridSetBlockSize(c->grid, BENCH_N0));
  PetscCall(PffGridSetLevels(c->grid, 3));
  PetscCall(PffGridSetDomain(c->grid, origin, 1.0 / (PetscReal)n));
  PetscCall(PffGridSetPeriodic(c->grid, per));
  PetscCall(PffGridSetPartitionType(c->grid, PFF_PARTITION_COLUMNS));
  if (map) PetscCall(PffGridSetRefinementMap(c->grid, map));
  PetscCall(PffGridSetUp(c->grid));
  PetscCall(PffGridAddChannel(c->grid, "phi", PFF_CHANNEL_CELL, 1, &c->phi));
  PetscCall(PffGridAddChannel(c->grid, "u", PFF_CHANNEL_FACE, 1, &c->u));
  PetscCall(PffGridAddChannel(c->grid, "p", PFF_CHANNEL_CELL, 1, &c->p));
  PetscCall(PffGridFillChannel(c->grid, c->phi, DropPhi, drop));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Best of R runs of Build + Project on a fresh u*. */
static PetscErrorCode RunMethod(Case *c, PetscBool merge, PetscInt repeat, Drop *drop, PffTallStats *best)
{
  PffTall tc;

  PetscFunctionBeginUser;
  PetscCall(PffTallCreate(c->grid, &tc));
  PetscCall(PffTallSetFromOptions(tc));
  PetscCall(PffTallSetMerge(tc, merge));
  for (PetscInt r = 0; r < repeat; r++) {
    PffTallStats st;
    PetscCall(PffGridFillChannel(c->grid, c->u, DropU, drop));
    PetscCall(PffTallBuild(tc, c->phi));
    PetscCall(PffTallProject(tc, c->u, BENCH_DT, BENCH_RHO, c->p, &st));
    PetscCheck(st.reason > 0, PETSC_COMM_WORLD, PETSC_ERR_NOT_CONVERGED,
               "pff-bench-tall: the solve did not converge (%s)", KSPConvergedReasons[st.reason]);
    if (r == 0 || st.assembleTime + st.solveTime < best->assembleTime + best->solveTime) *best = st;
  }
  PetscCall(PffTallDestroy(&tc));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PeakRSS(PetscReal *mb)
{
  struct rusage ru;
  PetscReal     m;

  PetscFunctionBeginUser;
  getrusage(RUSAGE_SELF, &ru);
  m = (PetscReal)ru.ru_maxrss / 1024.0;
  PetscCallMPI(MPIU_Allreduce(&m, mb, 1, MPIU_REAL, MPI_MAX, PETSC_COMM_WORLD));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode Print(const char *method, PetscInt n, const PffTallStats *st, PetscReal sizing, PetscReal qt)
{
  PetscMPIInt size;
  PetscReal   rss;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  PetscCall(PeakRSS(&rss));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                        "RESULT scene=drop method=%s n=%" PetscInt_FMT " ranks=%d cells=%" PetscInt64_FMT
                        " tall_cells=%" PetscInt64_FMT " samples=%" PetscInt64_FMT " rows=%" PetscInt64_FMT
                        " liquid_cells=%" PetscInt64_FMT " sizing_s=%.4f quadtree_s=%.4f assemble_s=%.4f solve_s=%.4f "
                        "projection_s=%.4f res0=%.3e res=%.3e its=%" PetscInt_FMT " peak_rss_MB=%.0f\n",
                        method, n, size, st->cells, st->tallCells, st->samples, st->rows, st->liquidCells,
                        (double)sizing, (double)qt, st->assembleTime, st->solveTime, st->assembleTime + st->solveTime,
                        (double)st->res0, (double)st->res, st->its, (double)rss));
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  PetscInt       n = 64, repeat = 1, *map, nblocks, hist[3] = {0, 0, 0};
  Drop           drop = {0.5, 0.08, {0.5, 0.62, 0.5}, -2.0};
  Case           uni, quad;
  PffTallStats   su, st, sq;
  PetscLogDouble t0, t1, t2;
  char           scene[32] = "drop";

  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(PffHugePagesSetFromOptions(PETSC_COMM_WORLD));
  PetscCall(PffInitializePackage());
  PetscOptionsBegin(PETSC_COMM_WORLD, NULL, "pff-bench-tall", NULL);
  PetscCall(PffOptionsBoundedInt("-bench_n", "Finest cells per axis (a multiple of 32)", NULL, n, &n, NULL, 32));
  PetscCall(PffOptionsBoundedInt("-bench_repeat", "Runs per method (best is printed)", NULL, repeat, &repeat, NULL, 1));
  PetscCall(PetscOptionsString("-bench_scene", "Scene: drop", NULL, scene, scene, sizeof(scene), NULL));
  PetscOptionsEnd();
  PetscCheck(n % (4 * BENCH_N0) == 0, PETSC_COMM_WORLD, PETSC_ERR_ARG_OUTOFRANGE,
             "-bench_n: %" PetscInt_FMT " is not a multiple of %d", n, 4 * BENCH_N0);
  {
    PetscBool isdrop;
    PetscCall(PetscStrcmp(scene, "drop", &isdrop));
    PetscCheck(isdrop, PETSC_COMM_WORLD, PETSC_ERR_ARG_UNKNOWN_TYPE, "-bench_scene: unknown scene '%s' (drop)", scene);
  }
  {
    PetscBool set;
    PetscCall(PetscOptionsHasName(NULL, NULL, "-tall_levels", &set));
    if (!set) PetscCall(PetscOptionsSetValue(NULL, "-tall_levels", "3"));
  }

  /* uniform cubic and uniform tall on the level-0 grid */
  PetscCall(CaseCreate(n, NULL, &drop, &uni));
  PetscCall(RunMethod(&uni, PETSC_FALSE, repeat, &drop, &su));
  PetscCall(Print("uniform", n, &su, 0, 0));
  PetscCall(RunMethod(&uni, PETSC_TRUE, repeat, &drop, &st));
  PetscCall(Print("tall", n, &st, 0, 0));

  /* the quadtree: sizing on the uniform grid's cells, then the grid on that map */
  nblocks = (n / BENCH_N0) * (n / BENCH_N0) * (n / BENCH_N0);
  PetscCall(PetscMalloc1(nblocks, &map));
  {
    PffTall tc;
    PetscCall(PffTallCreate(uni.grid, &tc));
    PetscCall(PffTallSetFromOptions(tc));
    PetscCall(PffGridFillChannel(uni.grid, uni.u, DropU, &drop));
    PetscCallMPI(MPI_Barrier(PETSC_COMM_WORLD));
    PetscCall(PetscTime(&t0));
    PetscCall(PffTallSizingLevels(tc, uni.phi, uni.u, map));
    PetscCall(PetscTime(&t1));
    PetscCall(PffTallDestroy(&tc));
  }
  PetscCall(PffGridDestroy(&uni.grid));
  PetscCall(CaseCreate(n, map, &drop, &quad));
  PetscCall(PetscTime(&t2));
  {
    const PetscInt *level, nb = n / BENCH_N0;
    PetscCall(PffGridGetRaster(quad.grid, NULL, &level, NULL));
    for (PetscInt c = 0; c < nb * nb; c++) hist[level[c % nb + nb * nb * (c / nb)]]++;
    PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                          "# quadtree: block columns at level 0 / 1 / 2: %" PetscInt_FMT " / %" PetscInt_FMT
                          " / %" PetscInt_FMT " of %" PetscInt_FMT "\n",
                          hist[0], hist[1], hist[2], nb * nb));
  }
  PetscCall(RunMethod(&quad, PETSC_TRUE, repeat, &drop, &sq));
  PetscCall(Print("quadtree", n, &sq, t1 - t0, t2 - t1));
  {
    const PetscReal pu = su.assembleTime + su.solveTime, pt = st.assembleTime + st.solveTime,
                    pq = sq.assembleTime + sq.solveTime, tq = pq + (t2 - t0);
    PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                          "RATIO projection_uniform_over_quadtree=%.2f projection_tall_over_quadtree=%.2f "
                          "cells_uniform_over_quadtree=%.1f total_uniform_over_quadtree=%.2f\n",
                          (double)(pu / pq), (double)(pt / pq), (double)su.cells / (double)sq.cells,
                          (double)(pu / tq)));
  }
  PetscCall(PetscFree(map));
  PetscCall(PffGridDestroy(&quad.grid));
  PetscCall(PetscFinalize());
  return 0;
}
