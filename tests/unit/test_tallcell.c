/* Quadtree tall cells (src/tallcell/, Narita et al. 2025 Sec. 4.2-4.3):
   - still water: a pool at a height between cell centres, u* = -g dt on the vertical faces; the projection
     leaves every row at rest (|u| <= 1e-6 sqrt(g H)) and p = rho g (H - y) at every liquid cell centre
     (to the float channel's rounding, 1e-6 rho g H),
     tall cells included, for uniform cubic cells, uniform tall cells and a random quadtree of tall cells;
   - the variational matrix of random quadtrees with a wavy surface, a drop and an air pocket is symmetric
     and positive definite (smallest eigenvalue of the explicit operator > 0), and a projection of random u*
     leaves no variational divergence;
   - the same random problem on this communicator and on one rank gives the same counts and the same
     cell pressures (partition independence);
   - the sizing function: a flat pool at rest asks for the coarsest level everywhere (walls are not
     surfaces), a falling drop above it asks for the finest level over the drop and the coarsest far away;
   - -grid_refine_columns turns a sphere refinement into a quadtree (levels constant along y) that the tall
     cells accept;
   - bad input: levels that change along y, an out-of-range option.
   Sample run: mpiexec -n 4 ./test_tallcell     prints one line per check on rank 0. */
#include "pfftest.h"

#define N0 8
#define G 9.81
#define RHO 1000.0
#define DT 0.01

typedef struct {
  PetscReal H;     /* pool height */
  PetscInt  shape; /* 0 flat pool; 1 wavy surface, a drop and an air pocket; 2 flat pool and a drop */
} Scene;

static PetscReal Phi(const PetscReal x[3], PetscInt comp, void *vctx)
{
  const Scene *sc = (const Scene *)vctx;
  (void)comp;
  if (sc->shape == 0) return x[1] - sc->H;
  if (sc->shape == 2)
    return PetscMin(x[1] - sc->H,
                    PetscSqrtReal(PetscSqr(x[0] - 0.45) + PetscSqr(x[1] - 0.8) + PetscSqr(x[2] - 0.45)) - 0.1);
  const PetscReal surf   = sc->H + 0.06 * PetscSinReal(9 * x[0]) * PetscCosReal(7 * x[2]);
  const PetscReal drop   = PetscSqrtReal(PetscSqr(x[0] - 0.4) + PetscSqr(x[1] - 0.85) + PetscSqr(x[2] - 0.55)) - 0.09;
  const PetscReal pocket = 0.1 - PetscSqrtReal(PetscSqr(x[0] - 0.7) + PetscSqr(x[1] - 0.25) + PetscSqr(x[2] - 0.3));
  return PetscMin(PetscMax(x[1] - surf, pocket), drop);
}

static PetscReal Gravity(const PetscReal x[3], PetscInt comp, void *vctx)
{
  (void)vctx;
  return comp == 1 && x[1] > 1e-9 ? -G * DT : 0;
}

/* gravity, and -2 m/s inside the drop of shape 2 */
static PetscReal DropU(const PetscReal x[3], PetscInt comp, void *vctx)
{
  const PetscReal d = PetscSqrtReal(PetscSqr(x[0] - 0.45) + PetscSqr(x[1] - 0.8) + PetscSqr(x[2] - 0.45));
  return Gravity(x, comp, vctx) + (comp == 1 && d < 0.1 ? -2.0 : 0.0);
}

static PetscReal RandomU(const PetscReal x[3], PetscInt comp, void *vctx)
{
  const PffTestCtx *t = (const PffTestCtx *)vctx;
  if (PetscAbsReal(x[comp]) < 1e-9) return 0; /* a lower wall */
  return 2 * PffTestUniform01(PffTestPositionKey(t, x, comp, 5)) - 1;
}

/* A unit box of nb blocks, levels constant along y: uniform >= 0, or random per block column in 0..2
   (graded by the grid), partitioned by columns. */
static PetscErrorCode CreateGrid(MPI_Comm comm, const PetscInt nb[3], PetscInt uniform, uint64_t seed, PffTestCtx *t)
{
  PetscInt       *request;
  const PetscInt  cells[3]  = {N0 * nb[0], N0 * nb[1], N0 * nb[2]};
  const PetscReal origin[3] = {0, 0, 0};
  const PetscBool per[3]    = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(nb[0] * nb[1] * nb[2], &request));
  for (PetscInt b = 0; b < nb[0] * nb[1] * nb[2]; b++) {
    const PetscInt bi = b % nb[0], bk = b / (nb[0] * nb[1]);
    request[b] = uniform >= 0 ? uniform : (PetscInt)(PffTestKey(seed, (uint64_t)bi, (uint64_t)bk, 3) % 3);
  }
  PetscCall(PetscMemzero(t, sizeof(*t)));
  PetscCall(PffGridCreate(comm, &t->grid));
  PetscCall(PffGridSetCells(t->grid, cells));
  PetscCall(PffGridSetBlockSize(t->grid, N0));
  PetscCall(PffGridSetLevels(t->grid, 3));
  PetscCall(PffGridSetDomain(t->grid, origin, 1.0 / (PetscReal)cells[0]));
  PetscCall(PffGridSetPeriodic(t->grid, per));
  PetscCall(PffGridSetPartitionType(t->grid, PFF_PARTITION_COLUMNS));
  PetscCall(PffGridSetRefinementMap(t->grid, request));
  PetscCall(PffGridSetUp(t->grid));
  PetscCall(PetscFree(request));
  t->comm = comm;
  PetscCallMPI(MPI_Comm_rank(comm, &t->rank));
  PetscCall(PffGridGetRaster(t->grid, t->nb, &t->level, &t->owner));
  PetscCall(PffGridGetSizes(t->grid, NULL, NULL, t->origin, &t->h0, t->periodic));
  PetscCall(PffGridGetLocalBlocks(t->grid, &t->nlocal));
  t->blen = N0 * t->h0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

typedef struct {
  PffTestCtx   t;
  PffTall      tc;
  PetscInt     phi, u, p;
  PffTallStats st;
} Problem;

static PetscErrorCode ProblemCreate(MPI_Comm comm, const PetscInt nb[3], PetscInt uniform, uint64_t seed,
                                    PetscBool merge, Scene *sc, Problem *pb)
{
  KSP ksp;

  PetscFunctionBeginUser;
  PetscCall(CreateGrid(comm, nb, uniform, seed, &pb->t));
  PetscCall(PffGridAddChannel(pb->t.grid, "phi", PFF_CHANNEL_CELL, 1, &pb->phi));
  PetscCall(PffGridAddChannel(pb->t.grid, "u", PFF_CHANNEL_FACE, 1, &pb->u));
  PetscCall(PffGridAddChannel(pb->t.grid, "p", PFF_CHANNEL_CELL, 1, &pb->p));
  PetscCall(PffGridFillChannel(pb->t.grid, pb->phi, Phi, sc));
  PetscCall(PffTallCreate(pb->t.grid, &pb->tc));
  PetscCall(PffTallSetFromOptions(pb->tc));
  PetscCall(PffTallSetMerge(pb->tc, merge));
  PetscCall(PffTallGetKSP(pb->tc, &ksp));
  PetscCall(KSPSetTolerances(ksp, 1e-12, 1e-30, PETSC_DEFAULT, 2000));
  PetscCall(PffTallBuild(pb->tc, pb->phi));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode ProblemDestroy(Problem *pb)
{
  PetscFunctionBeginUser;
  PetscCall(PffTallDestroy(&pb->tc));
  PetscCall(PffGridDestroy(&pb->t.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Largest |p - rho g (H - y)| over the liquid cell centres, and a position-weighted sum of p (the same on
   any partition). */
static PetscErrorCode PressureCheck(Problem *pb, const Scene *sc, PetscReal *err, PetscReal *wsum)
{
  PetscReal e = 0, w = 0;

  PetscFunctionBeginUser;
  for (PetscInt lb = 0; lb < pb->t.nlocal; lb++) {
    PffBlockInfo info;
    float       *p, *phi;
    PetscCall(PffGridGetBlockInfo(pb->t.grid, lb, &info));
    PetscCall(PffGridGetBlockData(pb->t.grid, pb->p, lb, 0, &p));
    PetscCall(PffGridGetBlockData(pb->t.grid, pb->phi, lb, 0, &phi));
    for (PetscInt k = 0; k < info.n; k++)
      for (PetscInt j = 0; j < info.n; j++)
        for (PetscInt i = 0; i < info.n; i++) {
          const PetscInt c[3] = {i, j, k}, q = i + info.n * (j + info.n * k);
          PetscReal      x[3];
          PffTestSamplePosition(&info, PFF_CHANNEL_CELL, 0, c, x);
          if (phi[q] < 0) e = PetscMax(e, PetscAbsReal(p[q] - RHO * G * (sc->H - x[1])));
          w += p[q] * info.h * info.h * info.h * (1 + PffTestUniform01(PffTestPositionKey(&pb->t, x, 0, 9)));
        }
  }
  PetscCallMPI(MPIU_Allreduce(&e, err, 1, MPIU_REAL, MPI_MAX, pb->t.comm));
  PetscCallMPI(MPIU_Allreduce(&w, wsum, 1, MPIU_REAL, MPI_SUM, pb->t.comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode StillWater(MPI_Comm comm, const char *name, PetscInt uniform, PetscBool merge)
{
  const PetscInt nb[3] = {4, 4, 4};
  Scene          sc    = {0.61, 0};
  Problem        pb;
  PetscReal      umax, err, wsum;

  PetscFunctionBeginUser;
  PetscCall(ProblemCreate(comm, nb, uniform, 11, merge, &sc, &pb));
  PetscCall(PffGridFillChannel(pb.t.grid, pb.u, Gravity, NULL));
  PetscCall(PffTallProject(pb.tc, pb.u, DT, RHO, pb.p, &pb.st));
  PetscCall(PffTallMaxRowVelocity(pb.tc, pb.u, &umax));
  PetscCall(PressureCheck(&pb, &sc, &err, &wsum));
  { /* the cell-height channel for frames: > 0 exactly in the liquid, tall cells at least 3 high */
    PetscInt  chH, bad = 0;
    PetscReal hmax = 0;
    PetscCall(PffGridAddChannel(pb.t.grid, "height", PFF_CHANNEL_CELL, 1, &chH));
    PetscCall(PffTallWriteCellHeight(pb.tc, chH));
    for (PetscInt lb = 0; lb < pb.t.nlocal; lb++) {
      PffBlockInfo info;
      float       *h, *phi;
      PetscCall(PffGridGetBlockInfo(pb.t.grid, lb, &info));
      PetscCall(PffGridGetBlockData(pb.t.grid, chH, lb, 0, &h));
      PetscCall(PffGridGetBlockData(pb.t.grid, pb.phi, lb, 0, &phi));
      for (PetscInt c = 0; c < info.n * info.n * info.n; c++) {
        bad += (phi[c] < 0) != (h[c] > 0);
        hmax = PetscMax(hmax, h[c]);
      }
    }
    PetscCallMPI(MPIU_Allreduce(MPI_IN_PLACE, &bad, 1, MPIU_INT, MPI_SUM, comm));
    PetscCallMPI(MPIU_Allreduce(MPI_IN_PLACE, &hmax, 1, MPIU_REAL, MPI_MAX, comm));
    PetscCheck(!bad && (merge ? hmax >= 3 : hmax == 1), comm, PETSC_ERR_PLIB,
               "still water, %s: cell heights: %" PetscInt_FMT " cells disagree with phi, max %g", name, bad,
               (double)hmax);
  }
  PetscCall(PetscPrintf(comm,
                        "still water, %s: %" PetscInt64_FMT " cells (%" PetscInt64_FMT " tall) for %" PetscInt64_FMT
                        " liquid cells, %" PetscInt64_FMT " samples, %" PetscInt_FMT " its, max |u| %.2e (bound %.2e), "
                        "max |p - rho g (H - y)| %.2e Pa\n",
                        name, pb.st.cells, pb.st.tallCells, pb.st.liquidCells, pb.st.samples, pb.st.its, (double)umax,
                        (double)(1e-6 * PetscSqrtReal(G * sc.H)), (double)err));
  PetscCheck(pb.st.reason > 0, comm, PETSC_ERR_PLIB, "still water, %s: the solve did not converge (%s)", name,
             KSPConvergedReasons[pb.st.reason]);
  PetscCheck(umax <= 1e-6 * PetscSqrtReal(G * sc.H), comm, PETSC_ERR_PLIB, "still water, %s: max |u| %g m/s", name,
             (double)umax);
  PetscCheck(err <= 1e-6 * RHO * G * sc.H, comm, PETSC_ERR_PLIB, "still water, %s: pressure off hydrostatic by %g Pa",
             name, (double)err);
  PetscCheck(merge == (pb.st.tallCells > 0), comm, PETSC_ERR_PLIB, "still water, %s: %" PetscInt64_FMT " tall cells",
             name, pb.st.tallCells);
  PetscCheck(merge || pb.st.cells == pb.st.liquidCells || uniform < 0, comm, PETSC_ERR_PLIB,
             "still water, %s: %" PetscInt64_FMT " cells for %" PetscInt64_FMT " liquid cells", name, pb.st.cells,
             pb.st.liquidCells);
  PetscCall(ProblemDestroy(&pb));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Symmetric positive definite on random quadtrees; the projection of a random u* is divergence-free. */
static PetscErrorCode RandomQuadtrees(MPI_Comm comm)
{
  const PetscInt nb[3] = {4, 2, 4};

  PetscFunctionBeginUser;
  for (uint64_t seed = 1; seed <= 3; seed++) {
    Scene      sc = {0.5, 1};
    Problem    pb;
    Mat        A;
    KSP        eig;
    PetscBool  sym;
    PetscReal *re, *im, lmin = PETSC_MAX_REAL, lmax = 0, div0, div1;
    PetscInt   n;

    PetscCall(ProblemCreate(comm, nb, -1, seed, PETSC_TRUE, &sc, &pb));
    PetscCall(PffTallGetOperator(pb.tc, &A));
    PetscCall(MatIsSymmetric(A, 1e-10, &sym));
    PetscCheck(sym, comm, PETSC_ERR_PLIB, "random quadtree %d: the operator is not symmetric", (int)seed);
    PetscCall(MatGetSize(A, &n, NULL));
    PetscCall(KSPCreate(comm, &eig));
    PetscCall(KSPSetOperators(eig, A, A));
    PetscCall(KSPSetType(eig, KSPGMRES));
    {
      PC pc;
      PetscCall(KSPGetPC(eig, &pc));
      PetscCall(PCSetType(pc, PCNONE));
    }
    PetscCall(KSPSetUp(eig));
    PetscCall(PetscMalloc2(n, &re, n, &im));
    PetscCall(KSPComputeEigenvaluesExplicitly(eig, n, re, im));
    for (PetscInt q = 0; q < n; q++) {
      lmin = PetscMin(lmin, re[q]);
      lmax = PetscMax(lmax, re[q]);
    }
    PetscCall(PetscFree2(re, im));
    PetscCall(KSPDestroy(&eig));
    { /* the explicit eigenvalues exist on rank 0 only */
      PetscReal ext[2] = {lmin, lmax};
      PetscCallMPI(MPI_Bcast(ext, 2, MPIU_REAL, 0, comm));
      lmin = ext[0];
      lmax = ext[1];
    }
    PetscCall(PffGridFillChannel(pb.t.grid, pb.u, RandomU, &pb.t));
    PetscCall(PffTallMaxDivergence(pb.tc, pb.u, &div0));
    PetscCall(PffTallProject(pb.tc, pb.u, DT, RHO, pb.p, &pb.st));
    PetscCall(PffTallMaxDivergence(pb.tc, pb.u, &div1));
    PetscCall(PetscPrintf(
        comm,
        "random quadtree %d: %" PetscInt64_FMT " cells (%" PetscInt64_FMT " tall), %" PetscInt_FMT
        " samples, symmetric, eigenvalues in [%.3e, %.3e], %" PetscInt_FMT " its, max divergence %.2e -> %.2e 1/s\n",
        (int)seed, pb.st.cells, pb.st.tallCells, n, (double)lmin, (double)lmax, pb.st.its, (double)div0, (double)div1));
    PetscCheck(pb.st.tallCells > 0 && pb.st.cells < pb.st.liquidCells, comm, PETSC_ERR_PLIB,
               "random quadtree %d: no tall cells", (int)seed);
    PetscCheck(lmin > 1e-12 * lmax, comm, PETSC_ERR_PLIB, "random quadtree %d: smallest eigenvalue %g", (int)seed,
               (double)lmin);
    PetscCheck(pb.st.reason > 0 && div1 <= 1e-6 * div0, comm, PETSC_ERR_PLIB,
               "random quadtree %d: divergence %g after the projection (%g before)", (int)seed, (double)div1,
               (double)div0);
    PetscCall(ProblemDestroy(&pb));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The same problem on comm and on one rank. */
static PetscErrorCode PartitionIndependence(MPI_Comm comm)
{
  const PetscInt nb[3] = {4, 4, 4};
  Scene          sc    = {0.55, 1};
  Problem        pa, ps;
  PetscReal      ea, es, wa, ws;

  PetscFunctionBeginUser;
  PetscCall(ProblemCreate(comm, nb, -1, 7, PETSC_TRUE, &sc, &pa));
  PetscCall(ProblemCreate(PETSC_COMM_SELF, nb, -1, 7, PETSC_TRUE, &sc, &ps));
  PetscCall(PffGridFillChannel(pa.t.grid, pa.u, Gravity, NULL));
  PetscCall(PffGridFillChannel(ps.t.grid, ps.u, Gravity, NULL));
  PetscCall(PffTallProject(pa.tc, pa.u, DT, RHO, pa.p, &pa.st));
  PetscCall(PffTallProject(ps.tc, ps.u, DT, RHO, ps.p, &ps.st));
  PetscCall(PressureCheck(&pa, &sc, &ea, &wa));
  PetscCall(PressureCheck(&ps, &sc, &es, &ws));
  PetscCall(PetscPrintf(comm,
                        "partition independence: %" PetscInt64_FMT " / %" PetscInt64_FMT " samples, %" PetscInt64_FMT
                        " / %" PetscInt64_FMT " rows, weighted pressure sums %.12e / %.12e\n",
                        pa.st.samples, ps.st.samples, pa.st.rows, ps.st.rows, (double)wa, (double)ws));
  PetscCheck(pa.st.samples == ps.st.samples && pa.st.rows == ps.st.rows && pa.st.cells == ps.st.cells, comm,
             PETSC_ERR_PLIB, "partition independence: the counts differ");
  PetscCheck(PetscAbsReal(wa - ws) <= 1e-8 * PetscAbsReal(ws), comm, PETSC_ERR_PLIB,
             "partition independence: pressures differ (%.12e vs %.12e)", (double)wa, (double)ws);
  PetscCall(ProblemDestroy(&pa));
  PetscCall(ProblemDestroy(&ps));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The sizing function's level map on a uniform grid of 4 x 4 x 4 blocks (block columns of 0.25 x 0.25). */
static PetscErrorCode Sizing(MPI_Comm comm)
{
  const PetscInt nb[3] = {4, 4, 4};
  PetscInt       level[64];

  PetscFunctionBeginUser;
  for (PetscInt shape = 0; shape <= 2; shape += 2) {
    Scene   sc = {0.61, shape};
    Problem pb;
    PetscCall(ProblemCreate(comm, nb, 0, 1, PETSC_TRUE, &sc, &pb));
    PetscCall(PffGridFillChannel(pb.t.grid, pb.u, shape ? DropU : Gravity, NULL));
    PetscCall(PffTallSizingLevels(pb.tc, pb.phi, pb.u, level));
    for (PetscInt b = 0; b < 64; b++)
      PetscCheck(level[b] == level[b % 4 + 16 * (b / 16)], comm, PETSC_ERR_PLIB, "sizing: levels change along y");
    if (shape == 0)
      for (PetscInt b = 0; b < 64; b++)
        PetscCheck(level[b] == 2, comm, PETSC_ERR_PLIB,
                   "sizing, still pool: block %" PetscInt_FMT " asks for level %" PetscInt_FMT, b, level[b]);
    else {
      /* the drop (centre 0.45, radius 0.1) lies over block columns 1..2 in x and z; column (0, 3) is far away */
      PetscCheck(level[1 + 16 * 1] == 0 && level[2 + 16 * 2] == 0 && level[0 + 16 * 3] == 2 && level[3 + 16 * 0] == 2,
                 comm, PETSC_ERR_PLIB,
                 "sizing, drop: levels %" PetscInt_FMT " %" PetscInt_FMT " %" PetscInt_FMT " %" PetscInt_FMT,
                 level[1 + 16], level[2 + 32], level[48], level[3]);
    }
    PetscCall(PetscPrintf(comm,
                          "sizing, %s: block-column levels %" PetscInt_FMT "%" PetscInt_FMT "%" PetscInt_FMT
                          "%" PetscInt_FMT " / %" PetscInt_FMT "%" PetscInt_FMT "%" PetscInt_FMT "%" PetscInt_FMT
                          " / %" PetscInt_FMT "%" PetscInt_FMT "%" PetscInt_FMT "%" PetscInt_FMT " / %" PetscInt_FMT
                          "%" PetscInt_FMT "%" PetscInt_FMT "%" PetscInt_FMT " (z rows)\n",
                          shape ? "falling drop" : "still pool", level[0], level[1], level[2], level[3], level[16],
                          level[17], level[18], level[19], level[32], level[33], level[34], level[35], level[48],
                          level[49], level[50], level[51]));
    PetscCall(ProblemDestroy(&pb));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -grid_refine sphere with -grid_refine_columns: every block column takes its finest level. */
static PetscErrorCode RefineColumns(MPI_Comm comm)
{
  PffGrid         grid;
  PffTall         tc;
  const PetscInt *level;
  PetscInt        nb[3], hist[3] = {0, 0, 0};

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsSetValue(NULL, "-grid_cells", "64,32,64"));
  PetscCall(PetscOptionsSetValue(NULL, "-grid_block_size", "8"));
  PetscCall(PetscOptionsSetValue(NULL, "-grid_levels", "3"));
  PetscCall(PetscOptionsSetValue(NULL, "-grid_refine", "sphere"));
  PetscCall(PetscOptionsSetValue(NULL, "-grid_refine_point", "0.5,0.2,0.5"));
  PetscCall(PetscOptionsSetValue(NULL, "-grid_refine_radius", "0.1"));
  PetscCall(PetscOptionsSetValue(NULL, "-grid_refine_band", "0.5"));
  PetscCall(PetscOptionsSetValue(NULL, "-grid_refine_columns", "true"));
  PetscCall(PetscOptionsSetValue(NULL, "-partition_type", "columns"));
  PetscCall(PffGridCreate(comm, &grid));
  PetscCall(PffGridSetFromOptions(grid));
  PetscCall(PffGridSetUp(grid));
  const char *keys[] = {"-grid_cells",       "-grid_block_size",     "-grid_levels",
                        "-grid_refine",      "-grid_refine_point",   "-grid_refine_radius",
                        "-grid_refine_band", "-grid_refine_columns", "-partition_type"};
  for (size_t k = 0; k < PETSC_STATIC_ARRAY_LENGTH(keys); k++) PetscCall(PetscOptionsClearValue(NULL, keys[k]));
  PetscCall(PffGridGetRaster(grid, nb, &level, NULL));
  for (PetscInt b = 0; b < nb[0] * nb[1] * nb[2]; b++) {
    const PetscInt b0 = b % nb[0] + nb[0] * nb[1] * (b / (nb[0] * nb[1]));
    PetscCheck(level[b] == level[b0], comm, PETSC_ERR_PLIB,
               "refine columns: block %" PetscInt_FMT " at level %" PetscInt_FMT
               ", its column's bottom at %" PetscInt_FMT,
               b, level[b], level[b0]);
    if (b == b0) hist[level[b]]++;
  }
  PetscCheck(hist[0] > 0 && hist[2] > 0, comm, PETSC_ERR_PLIB,
             "refine columns: block columns per level %" PetscInt_FMT " %" PetscInt_FMT " %" PetscInt_FMT, hist[0],
             hist[1], hist[2]);
  PetscCall(PffTallCreate(grid, &tc));
  PetscCall(PffTallDestroy(&tc));
  PetscCall(PffGridDestroy(&grid));
  PetscCall(PetscPrintf(comm,
                        "refine columns: block columns per level %" PetscInt_FMT " / %" PetscInt_FMT " / %" PetscInt_FMT
                        ", constant along y, accepted\n",
                        hist[0], hist[1], hist[2]));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Bad input: one clear error each. */
static PetscErrorCode BadInput(MPI_Comm comm)
{
  PetscErrorCode ierr;
  PffTestCtx     t;
  PffTall        tc = NULL;
  PetscInt       phi;

  PetscFunctionBeginUser;
  {
    /* levels that change along y */
    const PetscInt  nb[3] = {2, 2, 2}, cells[3] = {2 * N0, 2 * N0, 2 * N0};
    PetscInt        request[8] = {0, 0, 1, 1, 0, 0, 1, 1};
    const PetscReal origin[3]  = {0, 0, 0};
    (void)nb;
    PetscCall(PffGridCreate(comm, &t.grid));
    PetscCall(PffGridSetCells(t.grid, cells));
    PetscCall(PffGridSetBlockSize(t.grid, N0));
    PetscCall(PffGridSetLevels(t.grid, 2));
    PetscCall(PffGridSetDomain(t.grid, origin, 1.0 / (2 * N0)));
    PetscCall(PffGridSetPartitionType(t.grid, PFF_PARTITION_COLUMNS));
    PetscCall(PffGridSetRefinementMap(t.grid, request));
    PetscCall(PffGridSetUp(t.grid));
    PetscCall(PffGridAddChannel(t.grid, "phi", PFF_CHANNEL_CELL, 1, &phi));
    PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
    ierr = PffTallCreate(t.grid, &tc);
    PetscCall(PetscPopErrorHandler());
    PetscCheck(ierr == PETSC_ERR_ARG_WRONG, comm, PETSC_ERR_PLIB, "levels along y: error %d", (int)ierr);
    PetscCall(PffTallDestroy(&tc));
    PetscCall(PffGridDestroy(&t.grid));
  }
  {
    const PetscInt nb[3] = {2, 2, 2};
    Scene          sc    = {0.5, 0};
    Problem        pb;
    PetscCall(ProblemCreate(comm, nb, 0, 1, PETSC_TRUE, &sc, &pb));
    PetscCall(PetscOptionsSetValue(NULL, "-tall_layer_fraction", "2"));
    PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
    ierr = PffTallSetFromOptions(pb.tc);
    PetscCall(PetscPopErrorHandler());
    PetscCall(PetscOptionsClearValue(NULL, "-tall_layer_fraction"));
    PetscCheck(ierr == PETSC_ERR_ARG_OUTOFRANGE, comm, PETSC_ERR_PLIB, "-tall_layer_fraction 2: error %d", (int)ierr);
    PetscCall(ProblemDestroy(&pb));
  }
  PetscCall(PetscPrintf(comm, "bad input: levels along y and -tall_layer_fraction 2 are refused\n"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  PetscCall(StillWater(PETSC_COMM_WORLD, "uniform cubic", 0, PETSC_FALSE));
  PetscCall(StillWater(PETSC_COMM_WORLD, "uniform tall", 0, PETSC_TRUE));
  PetscCall(StillWater(PETSC_COMM_WORLD, "quadtree tall", -1, PETSC_TRUE));
  PetscCall(StillWater(PETSC_COMM_WORLD, "quadtree cubic", -1, PETSC_FALSE));
  PetscCall(RandomQuadtrees(PETSC_COMM_WORLD));
  PetscCall(PartitionIndependence(PETSC_COMM_WORLD));
  PetscCall(Sizing(PETSC_COMM_WORLD));
  PetscCall(RefineColumns(PETSC_COMM_WORLD));
  PetscCall(BadInput(PETSC_COMM_WORLD));
  PetscCall(PetscFinalize());
  return 0;
}
