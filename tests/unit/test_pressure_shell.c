/* The matrix-free pressure operator (src/pressure/shell.c) against the assembled A = G^T diag(M beta open) G:
   - S x = A x (relative 1e-12) for random x and MatGetDiagonal(S) = MatGetDiagonal(A), on uniform and
     graded 3-level grids, closed, periodic and with inactive blocks, random beta in [1e-3, 1], 10% of the
     faces closed at random and a solid box (its cells have every face closed: unit diagonal), also with
     Dirichlet walls (their 2 h beta diagonal terms);
   - Jacobi-preconditioned CG with (S, S) against (A, A): the shell's diagonal drives the same iterations;
   - a projection with -pressure_operator shell gives the p and u of -pressure_operator aij (rtol 1e-10,
     default PC pffmg and PC jacobi, both on the assembled Pmat; also with Dirichlet walls), and without Dirichlet
     walls leaves max |div u| <= 1e-3 although u was random on the closed faces (also with 2 % of the faces closed
     inside the blocks: the divergence's open-face mask).
   Sample run: mpiexec -n 4 ./test_pressure_shell            prints one line per check on rank 0.
   Benchmark:  mpiexec -n 2 ./test_pressure_shell -bench 64  MatMult of aij and shell on a 64^3 box, best of 10. */
#include "pfftest.h"

typedef struct {
  const PffTestCtx *t;
  PetscReal         boxlo[3], boxhi[3]; /* the solid: every face on or inside it is closed */
  PetscReal         closedFraction;     /* of the other faces, closed at random */
} Fill;

static PetscReal RandomBeta(const PetscReal x[3], PetscInt comp, void *vctx)
{
  const Fill *f = (const Fill *)vctx;
  return 1e-3 + (1 - 1e-3) * PffTestUniform01(PffTestPositionKey(f->t, x, comp, 7));
}

static PetscReal OpenField(const PetscReal x[3], PetscInt comp, void *vctx)
{
  const Fill *f     = (const Fill *)vctx;
  PetscBool   solid = PETSC_TRUE;
  for (int a = 0; a < 3; a++)
    if (x[a] < f->boxlo[a] - 1e-9 || x[a] > f->boxhi[a] + 1e-9) solid = PETSC_FALSE;
  if (solid) return 0.0;
  return PffTestUniform01(PffTestPositionKey(f->t, x, comp, 13)) < f->closedFraction ? 0.0 : 1.0;
}

static PetscReal RandomVelocity(const PetscReal x[3], PetscInt comp, void *vctx)
{
  const Fill *f = (const Fill *)vctx;
  if (!f->t->periodic[comp] && PetscAbsReal(x[comp] - f->t->origin[comp]) < 1e-3 * f->t->h0) return 0;
  return PffTestUniform01(PffTestPositionKey(f->t, x, comp, 11)) - 0.5;
}

/* x_i from the global cell number i, so the same vector on every partition. */
static PetscErrorCode RandomCellVec(Vec x, uint64_t seed)
{
  PetscScalar *a;
  PetscInt     lo, hi;

  PetscFunctionBeginUser;
  PetscCall(VecGetOwnershipRange(x, &lo, &hi));
  PetscCall(VecGetArrayWrite(x, &a));
  for (PetscInt i = lo; i < hi; i++) a[i - lo] = PffTestUniform01(PffTestKey(seed, (uint64_t)i, 0, 0)) - 0.5;
  PetscCall(VecRestoreArrayWrite(x, &a));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Channels beta (random), open (solid box of coarse blocks + random closures), u, p, on a new grid. */
typedef struct {
  PffTestCtx t;
  Fill       f;
  PetscInt   betaCh, openCh, uCh, pCh;
} Problem;

static PetscErrorCode ProblemCreate(MPI_Comm comm, PetscInt g, PetscReal closedFraction, Problem *pb)
{
  const PetscInt  nb[3]     = {4, 4, 4};
  const PetscBool closed[3] = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};
  const PetscBool allper[3] = {PETSC_TRUE, PETSC_TRUE, PETSC_TRUE};
  const PetscBool perxz[3]  = {PETSC_TRUE, PETSC_FALSE, PETSC_TRUE};
  const PetscReal origin[3] = {0, 0, 0};
  /* g: 0 uniform closed, 1 uniform periodic, 2 graded closed, 3 graded periodic, 4 graded periodic in x,z
     with 10% inactive blocks */
  const PetscBool *per = g == 0 || g == 2 ? closed : (g == 4 ? perxz : allper);

  PetscFunctionBeginUser;
  PetscCall(PffTestCreateGrid(comm, nb, per, origin, 1.0 / 32, 8, 3, g < 2 ? 0 : -1, g == 4 ? 10 : 0, 23 + (uint64_t)g,
                              &pb->t));
  pb->f.t = &pb->t;
  for (int a = 0; a < 3; a++) { /* one block-aligned box, 1/4 of the domain on a side */
    pb->f.boxlo[a] = pb->t.origin[a] + pb->t.blen;
    pb->f.boxhi[a] = pb->t.origin[a] + 2 * pb->t.blen;
  }
  pb->f.closedFraction = closedFraction;
  PetscCall(PffGridAddChannel(pb->t.grid, "beta", PFF_CHANNEL_FACE, 1, &pb->betaCh));
  PetscCall(PffGridAddChannel(pb->t.grid, "open", PFF_CHANNEL_FACE, 1, &pb->openCh));
  PetscCall(PffGridAddChannel(pb->t.grid, "u", PFF_CHANNEL_FACE, 1, &pb->uCh));
  PetscCall(PffGridAddChannel(pb->t.grid, "p", PFF_CHANNEL_CELL, 1, &pb->pCh));
  PetscCall(PffGridFillChannel(pb->t.grid, pb->betaCh, RandomBeta, &pb->f));
  PetscCall(PffGridFillChannel(pb->t.grid, pb->openCh, OpenField, &pb->f));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static const char *const GridNames[] = {"uniform closed", "uniform periodic", "graded closed", "graded periodic",
                                        "graded inactive"};

/* Dirichlet walls (p = 0) on the non-periodic walls -x and +y when asked: they add 2 h beta to the
   diagonal of the cells beside them, a diagonal-only term the shell must reproduce. */
static PetscErrorCode SetWalls(PffPressure ps, const PffTestCtx *t, PetscBool dirichlet)
{
  PetscBool walls[6] = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE, PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};

  PetscFunctionBeginUser;
  if (!dirichlet) PetscFunctionReturn(PETSC_SUCCESS);
  walls[0] = !t->periodic[0];
  walls[3] = !t->periodic[1];
  PetscCall(PffPressureSetDirichletWalls(ps, walls));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* S x = A x, diag(S) = diag(A), and Jacobi-CG with (S, S) = with (A, A). */
static PetscErrorCode TestEquality(PetscInt g, PetscBool dirichlet)
{
  Problem     pb;
  PffPressure ps;
  Mat         A, S;
  Vec         x, ya, ys, da, ds;
  PetscReal   errMax    = 0, derr, ndA;
  PetscInt    nisolated = 0, its[2];

  PetscFunctionBeginUser;
  PetscCall(ProblemCreate(PETSC_COMM_WORLD, g, 0.1, &pb));
  PetscCall(PffPressureCreate(pb.t.grid, &ps));
  PetscCall(PffPressureSetFromOptions(ps));
  PetscCall(SetWalls(ps, &pb.t, dirichlet));
  PetscCall(PffPressureSetUp(ps));
  PetscCall(PffPressureSetCoefficients(ps, pb.betaCh, pb.openCh));
  PetscCall(PffPressureGetOperator(ps, &A));
  PetscCall(PffPressureGetShellOperator(ps, &S));
  if (dirichlet) { /* the walls are on: A is definite, and has the 2 h beta terms */
    MatNullSpace nsp;
    Vec          dd;
    PetscReal    ddsum;
    PetscCall(MatGetNullSpace(A, &nsp));
    PetscCall(PffPressureGetDirichletDiagonal(ps, &dd));
    PetscCall(VecSum(dd, &ddsum));
    PetscCheck(nsp == NULL && ddsum > 0, PETSC_COMM_WORLD, PETSC_ERR_PLIB, "%s: Dirichlet walls not applied",
               GridNames[g]);
  } else { /* no walls: the Dirichlet diagonal is made on request, and is zero */
    Vec       dd;
    PetscReal ddmax;
    PetscCall(PffPressureGetDirichletDiagonal(ps, &dd));
    PetscCall(VecNorm(dd, NORM_INFINITY, &ddmax));
    PetscCheck(ddmax == 0, PETSC_COMM_WORLD, PETSC_ERR_PLIB, "%s: Dirichlet terms %g without Dirichlet walls",
               GridNames[g], (double)ddmax);
  }
  PetscCall(MatCreateVecs(A, &x, &ya));
  PetscCall(VecDuplicate(ya, &ys));
  PetscCall(VecDuplicate(ya, &da));
  PetscCall(VecDuplicate(ya, &ds));
  for (uint64_t seed = 1; seed <= 3; seed++) {
    PetscReal an, en;
    PetscCall(RandomCellVec(x, seed));
    PetscCall(MatMult(A, x, ya));
    PetscCall(MatMult(S, x, ys));
    PetscCall(VecNorm(ya, NORM_2, &an));
    PetscCall(VecAXPY(ys, -1.0, ya));
    PetscCall(VecNorm(ys, NORM_2, &en));
    PetscCheck(en <= 1e-12 * an, PETSC_COMM_WORLD, PETSC_ERR_PLIB, "%s: |A x - S x| = %g against |A x| = %g",
               GridNames[g], (double)en, (double)an);
    errMax = PetscMax(errMax, en / an);
    PetscCall(MatMultTranspose(S, x, ys));
    PetscCall(VecAXPY(ys, -1.0, ya));
    PetscCall(VecNorm(ys, NORM_2, &en));
    PetscCheck(en <= 1e-12 * an, PETSC_COMM_WORLD, PETSC_ERR_PLIB, "%s: |A x - S^T x| = %g against |A x| = %g",
               GridNames[g], (double)en, (double)an);
  }
  PetscCall(MatGetDiagonal(A, da));
  PetscCall(MatGetDiagonal(S, ds));
  PetscCall(VecNorm(da, NORM_INFINITY, &ndA));
  PetscCall(VecAXPY(ds, -1.0, da));
  PetscCall(VecNorm(ds, NORM_INFINITY, &derr));
  PetscCheck(derr <= 1e-12 * ndA, PETSC_COMM_WORLD, PETSC_ERR_PLIB, "%s: |diag A - diag S| = %g against %g",
             GridNames[g], (double)derr, (double)ndA);
  { /* a cell with an open face has a sum of random c_f < 1 on the diagonal: exactly 1 means every face closed */
    const PetscScalar *d;
    PetscInt           n;
    PetscCall(VecGetLocalSize(da, &n));
    PetscCall(VecGetArrayRead(da, &d));
    for (PetscInt i = 0; i < n; i++)
      if (d[i] == 1.0) nisolated++;
    PetscCall(VecRestoreArrayRead(da, &d));
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &nisolated, 1, MPIU_INT, MPI_SUM, PETSC_COMM_WORLD));
    PetscCheck(nisolated > 0, PETSC_COMM_WORLD, PETSC_ERR_PLIB, "%s: the solid box left no closed cell", GridNames[g]);
  }

  /* Jacobi needs only MatGetDiagonal: the shell as Pmat must reproduce the AIJ run */
  for (PetscInt k = 0; k < 2; k++) {
    KSP ksp;
    PC  pc;
    Vec b, sol;
    Mat op = k == 0 ? A : S;
    PetscCall(VecDuplicate(x, &b));
    PetscCall(VecDuplicate(x, &sol));
    PetscCall(RandomCellVec(x, 9));
    PetscCall(MatMult(A, x, b));
    PetscCall(KSPCreate(PETSC_COMM_WORLD, &ksp));
    PetscCall(KSPSetOperators(ksp, op, op));
    PetscCall(KSPSetType(ksp, KSPCG));
    PetscCall(KSPGetPC(ksp, &pc));
    PetscCall(PCSetType(pc, PCJACOBI));
    PetscCall(KSPSetTolerances(ksp, 1e-8, 1e-50, PETSC_DEFAULT, 5000));
    PetscCall(KSPSolve(ksp, b, sol));
    KSPConvergedReason reason;
    PetscCall(KSPGetConvergedReason(ksp, &reason));
    PetscCheck(reason > 0, PETSC_COMM_WORLD, PETSC_ERR_NOT_CONVERGED, "%s: Jacobi-CG with %s did not converge (%s)",
               GridNames[g], k == 0 ? "(A, A)" : "(S, S)", KSPConvergedReasons[reason]);
    PetscCall(KSPGetIterationNumber(ksp, &its[k]));
    PetscCall(KSPDestroy(&ksp));
    PetscCall(VecDestroy(&b));
    PetscCall(VecDestroy(&sol));
  }
  PetscCheck(PetscAbsInt(its[0] - its[1]) <= 1, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
             "%s: Jacobi-CG took %" PetscInt_FMT " iterations with (A, A) but %" PetscInt_FMT " with (S, S)",
             GridNames[g], its[0], its[1]);
  PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                        "shell %-16s %-9s |Ax-Sx|/|Ax| <= %.1e  |diag A - diag S| %.1e  closed cells %" PetscInt_FMT
                        "  jacobi-cg its aij/shell %s\n",
                        GridNames[g], dirichlet ? "dirichlet" : "", (double)errMax, (double)(derr / ndA), nisolated,
                        its[0] == its[1] ? "equal" : "within 1"));
  PetscCall(VecDestroy(&x));
  PetscCall(VecDestroy(&ya));
  PetscCall(VecDestroy(&ys));
  PetscCall(VecDestroy(&da));
  PetscCall(VecDestroy(&ds));
  PetscCall(PffPressureDestroy(&ps));
  PetscCall(PffGridDestroy(&pb.t.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The projection with -pressure_operator aij and shell: p (up to the null space) and u agree. */
static PetscErrorCode TestProjection(PetscInt g, PCType pctype, PetscBool dirichlet, PetscReal closedFraction)
{
  Problem   pb;
  Vec       pref = NULL, uref = NULL;
  PetscInt  its[2];
  PetscReal dp = 0, du = 0, pn = 0;

  PetscFunctionBeginUser;
  PetscCall(ProblemCreate(PETSC_COMM_WORLD, g, closedFraction, &pb)); /* 0: only the box, the fluid stays connected */
  for (PetscInt k = 0; k < 2; k++) {
    PffPressure      ps;
    PffPressureStats st;
    KSP              ksp;
    PC               pc;
    Mat              Amat, Pmat, A;
    Vec              p, u;
    PetscBool        isshell;
    MatNullSpace     nsp;
    PetscCall(PffGridFillChannel(pb.t.grid, pb.uCh, RandomVelocity, &pb.f));
    PetscCall(PffGridFillChannel(pb.t.grid, pb.pCh, PffTestZero, &pb.f));
    PetscCall(PetscOptionsSetValue(NULL, "-pressure_operator", k == 0 ? "aij" : "shell"));
    PetscCall(PffPressureCreate(pb.t.grid, &ps));
    PetscCall(PffPressureSetFromOptions(ps));
    PetscCall(PetscOptionsClearValue(NULL, "-pressure_operator"));
    PetscCall(SetWalls(ps, &pb.t, dirichlet));
    PetscCall(PffPressureGetKSP(ps, &ksp));
    PetscCall(KSPSetTolerances(ksp, 1e-10, 1e-50, PETSC_DEFAULT, 10000));
    if (pctype) {
      PetscCall(KSPGetPC(ksp, &pc));
      PetscCall(PCSetType(pc, pctype));
    }
    PetscCall(PffPressureSetUp(ps));
    PetscCall(PffPressureSetCoefficients(ps, pb.betaCh, pb.openCh));
    PetscCall(KSPGetOperators(ksp, &Amat, &Pmat));
    PetscCall(PetscObjectTypeCompare((PetscObject)Amat, MATSHELL, &isshell));
    /* the matrix-free pffmg (pctype NULL) preconditions from the Amat itself; other PCs from the assembled A,
       which PffPressureGetOperator assembles on demand */
    PetscCheck(isshell == (k == 1 ? PETSC_TRUE : PETSC_FALSE) && (pctype != NULL || Pmat == Amat), PETSC_COMM_WORLD,
               PETSC_ERR_PLIB, "-pressure_operator %s: wrong KSP operators", k == 0 ? "aij" : "shell");
    PetscCall(PffPressureGetOperator(ps, &A));
    PetscCheck(pctype == NULL || Pmat == A, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
               "-pressure_operator %s: the PC does not get the assembled A", k == 0 ? "aij" : "shell");
    PetscCall(PffPressureProject(ps, pb.uCh, 0.01, -1, pb.pCh, &st));
    PetscCheck(st.reason > 0, PETSC_COMM_WORLD, PETSC_ERR_NOT_CONVERGED, "projection (%s) did not converge: %s",
               k == 0 ? "aij" : "shell", KSPConvergedReasons[st.reason]);
    its[k] = st.its;
    if (!dirichlet) {
      /* the velocity is random on the solid box's closed faces too: the rhs must take the open faces only
         (the divergence's open-face mask), or the update, which zeroes the closed faces, leaves their flux (with a
         Dirichlet wall the flux through it is not a face velocity, so the cells beside it keep a divergence) */
      PetscReal maxdiv;
      PetscCall(PffPressureMaxDivergence(ps, pb.uCh, &maxdiv));
      PetscCheck(maxdiv <= 1e-3, PETSC_COMM_WORLD, PETSC_ERR_PLIB, "%s (%s): max |div u| %g after the projection",
                 GridNames[g], k == 0 ? "aij" : "shell", (double)maxdiv);
    }
    PetscCall(KSPGetSolution(ksp, &p));
    PetscCall(MatGetNullSpace(A, &nsp));
    {
      PetscScalar *a;
      PetscInt     n;
      PetscCall(VecGetLocalSize(p, &n));
      PetscCall(VecCreateMPI(PETSC_COMM_WORLD, 3 * n, PETSC_DETERMINE, &u));
      PetscCall(VecGetArrayWrite(u, &a));
      for (PetscInt lb = 0, c0 = 0; lb < pb.t.nlocal; lb++) {
        PffBlockInfo info;
        PetscCall(PffGridGetBlockInfo(pb.t.grid, lb, &info));
        const PetscInt nc = info.n * info.n * info.n;
        for (PetscInt d = 0; d < 3; d++) {
          float *data;
          PetscCall(PffGridGetBlockData(pb.t.grid, pb.uCh, lb, d, &data));
          for (PetscInt q = 0; q < nc; q++) a[3 * (c0 + q) + d] = data[q];
        }
        c0 += nc;
      }
      PetscCall(VecRestoreArrayWrite(u, &a));
    }
    if (k == 0) {
      PetscCall(VecDuplicate(p, &pref));
      PetscCall(VecCopy(p, pref));
      if (nsp) PetscCall(MatNullSpaceRemove(nsp, pref)); /* none with a Dirichlet wall */
      PetscCall(VecNorm(pref, NORM_2, &pn));
      uref = u;
    } else {
      PetscReal un;
      PetscCall(VecAXPY(pref, -1.0, p));
      if (nsp) PetscCall(MatNullSpaceRemove(nsp, pref));
      PetscCall(VecNorm(pref, NORM_2, &dp));
      dp /= pn;
      PetscCall(VecNorm(uref, NORM_2, &un));
      PetscCall(VecAXPY(uref, -1.0, u));
      PetscCall(VecNorm(uref, NORM_2, &du));
      du /= un;
      PetscCall(VecDestroy(&u));
    }
    PetscCall(PffPressureDestroy(&ps));
  }
  PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                        "project %-16s %-9s pc %-6s its aij %3" PetscInt_FMT " shell %3" PetscInt_FMT
                        "  |p_shell - p_aij|/|p| %.1e  |u_shell - u_aij|/|u| %.1e\n",
                        GridNames[g], dirichlet ? "dirichlet" : "", pctype ? pctype : "pffmg", its[0], its[1],
                        (double)dp, (double)du));
  /* rtol 1e-10 on the residual; rounding alone separates the two runs */
  PetscCheck(dp <= 1e-6 && du <= 1e-6, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
             "%s: shell and aij projections differ: p %g, u %g (relative)", GridNames[g], (double)dp, (double)du);
  PetscCheck(PetscAbsInt(its[0] - its[1]) <= 2, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
             "%s: %" PetscInt_FMT " iterations with aij, %" PetscInt_FMT " with shell", GridNames[g], its[0], its[1]);
  PetscCall(VecDestroy(&pref));
  PetscCall(VecDestroy(&uref));
  PetscCall(PffGridDestroy(&pb.t.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* MatMult of the assembled A and of the shell on an N^3 closed uniform box (blocks of 16, random beta,
   every face open): best of nrep products, slowest rank. */
static PetscErrorCode Bench(PetscInt N, PetscInt nrep)
{
  const PetscInt  n0 = 16, nb[3] = {N / n0, N / n0, N / n0};
  const PetscBool per[3]    = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};
  const PetscReal origin[3] = {0, 0, 0};
  PffTestCtx      t;
  Fill            f = {0};
  PffPressure     ps;
  PetscInt        betaCh;
  Mat             op[2];
  Vec             x, y;
  PetscLogDouble  best[2] = {1e30, 1e30}, tsu0, tsu1;
  PetscMPIInt     size;

  PetscFunctionBeginUser;
  PetscCheck(N % n0 == 0, PETSC_COMM_WORLD, PETSC_ERR_ARG_OUTOFRANGE, "-bench N: N must be a multiple of %d", (int)n0);
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  PetscCall(PffTestCreateGrid(PETSC_COMM_WORLD, nb, per, origin, 1.0 / (PetscReal)N, n0, 1, 0, 0, 3, &t));
  f.t = &t;
  PetscCall(PffGridAddChannel(t.grid, "beta", PFF_CHANNEL_FACE, 1, &betaCh));
  PetscCall(PffGridFillChannel(t.grid, betaCh, RandomBeta, &f));
  PetscCall(PffPressureCreate(t.grid, &ps));
  PetscCall(PffPressureSetFromOptions(ps));
  PetscCall(PffPressureSetUp(ps));
  PetscCall(PffPressureSetCoefficients(ps, betaCh, -1));
  PetscCall(PffPressureGetOperator(ps, &op[0]));
  PetscCall(PetscTime(&tsu0));
  PetscCall(PffPressureGetShellOperator(ps, &op[1]));
  PetscCall(PetscTime(&tsu1));
  PetscCall(MatCreateVecs(op[0], &x, &y));
  PetscCall(RandomCellVec(x, 1));
  for (PetscInt rep = 0; rep < nrep; rep++)
    for (PetscInt k = 0; k < 2; k++) {
      PetscLogDouble t0, t1, dt;
      PetscCallMPI(MPI_Barrier(PETSC_COMM_WORLD));
      PetscCall(PetscTime(&t0));
      PetscCall(MatMult(op[k], x, y));
      PetscCall(PetscTime(&t1));
      dt = t1 - t0;
      PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &dt, 1, MPI_DOUBLE, MPI_MAX, PETSC_COMM_WORLD));
      best[k] = PetscMin(best[k], dt);
    }
  PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                        "bench %" PetscInt_FMT
                        "^3 ranks %d: MatMult aij %.2f ms  shell %.2f ms  (shell/aij %.2f, best of %" PetscInt_FMT
                        "; shell set-up %.1f ms)\n",
                        N, size, 1e3 * best[0], 1e3 * best[1], best[1] / best[0], nrep, 1e3 * (tsu1 - tsu0)));
  PetscCall(VecDestroy(&x));
  PetscCall(VecDestroy(&y));
  PetscCall(PffPressureDestroy(&ps));
  PetscCall(PffGridDestroy(&t.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Without -pressure_operator: the matrix-free pffmg gets the shell as Amat and Pmat (no assembled A), any other
   PC the assembled A as both. */
static PetscErrorCode TestDefaultOperators(void)
{
  Problem pb;

  PetscFunctionBeginUser;
  PetscCall(ProblemCreate(PETSC_COMM_WORLD, 2, 0.0, &pb));
  for (PetscInt k = 0; k < 2; k++) {
    PffPressure             ps;
    KSP                     ksp;
    PC                      pc;
    Mat                     Amat, Pmat;
    PetscBool               isshell;
    PffPressureOperatorType type;
    PetscCall(PffPressureCreate(pb.t.grid, &ps));
    PetscCall(PffPressureSetFromOptions(ps));
    PetscCall(PffPressureGetKSP(ps, &ksp));
    if (k == 1) {
      PetscCall(KSPGetPC(ksp, &pc));
      PetscCall(PCSetType(pc, PCJACOBI));
    }
    PetscCall(PffPressureSetUp(ps));
    PetscCall(PffPressureSetCoefficients(ps, pb.betaCh, pb.openCh));
    PetscCall(KSPGetOperators(ksp, &Amat, &Pmat));
    PetscCall(PetscObjectTypeCompare((PetscObject)Amat, MATSHELL, &isshell));
    PetscCall(PffPressureGetOperatorType(ps, &type));
    PetscCheck(Pmat == Amat && isshell == (k == 0) && (type == PFF_PRESSURE_OPERATOR_SHELL) == (k == 0),
               PETSC_COMM_WORLD, PETSC_ERR_PLIB, "default operators with %s: Amat %s, Pmat %s Amat",
               k == 0 ? "pffmg" : "jacobi", isshell ? "shell" : "aij", Pmat == Amat ? "=" : "!=");
    PetscCall(PetscPrintf(PETSC_COMM_WORLD, "default operators with %-6s: Amat = Pmat = %s\n",
                          k == 0 ? "pffmg" : "jacobi", isshell ? "the shell (no assembled A)" : "the assembled A"));
    PetscCall(PffPressureDestroy(&ps));
  }
  PetscCall(PffGridDestroy(&pb.t.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  PetscInt bench = 0, nrep = 10;

  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  PetscCall(PffInitializePackage());
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-bench", &bench, NULL));
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-bench_reps", &nrep, NULL));
  if (bench > 0)
    PetscCall(Bench(bench, nrep));
  else {
    for (PetscInt g = 0; g < 5; g++) PetscCall(TestEquality(g, PETSC_FALSE));
    PetscCall(TestEquality(2, PETSC_TRUE));
    PetscCall(TestEquality(4, PETSC_TRUE));
    PetscCall(TestProjection(0, NULL, PETSC_FALSE, 0.0));
    PetscCall(TestProjection(2, NULL, PETSC_FALSE, 0.0));
    PetscCall(TestProjection(3, PCJACOBI, PETSC_FALSE, 0.0));
    PetscCall(TestProjection(2, NULL, PETSC_TRUE, 0.0));
    PetscCall(TestProjection(2, NULL, PETSC_FALSE, 0.02)); /* closed faces inside the blocks too */
    PetscCall(TestDefaultOperators());
  }
  PetscCall(PetscFinalize());
  return 0;
}
