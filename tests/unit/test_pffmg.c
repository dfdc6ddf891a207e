/* The adaptive multigrid preconditioner pffmg (PF-FLIP Sec. 6) on uniform and graded 3-level grids:
   - Galerkin: without rescaling every level operator equals P^T A P formed by explicit matrix products,
     and on a uniform grid with beta = 1 a coarse face carries the sum of its four fine face coefficients
     (Algorithm 1); rescaled (the default) it carries the coarse discretisation's coefficient; every level
     is symmetric with zero row sums;
   - the smoother (fixed hybrid red-black sweeps and adaptive relaxation) lowers the energy norm of a
     random error on every level;
   - FCG + pffmg converges at rtol 1e-8 on a bubbly problem (nine bubbles, density ratio 1000), closed
     box, with an iteration count at most 3 above that of a one-rank solve of the same problem;
   - the conditional K-cycle at ratio 1e5 needs at most the iterations of two fixed steps per coarse correction
     and stops its coarse corrections early (fewer cell updates per iteration than four fixed steps);
   - adaptive relaxation relaxes fewer blocks than fixed sweeps when the residual is localised;
   - the matrix-free levels (the default) equal the AIJ Galerkin levels of -pressure_pffmg_operator aij, and so
     does one V-cycle with their block-by-block residual restriction and prolongation.
   Sample run: mpiexec -n 4 ./test_pffmg     prints one line per check on rank 0. */
#include "pfftest.h"

typedef struct {
  PetscInt          uCh, betaCh, openCh, pCh;
  PetscReal         ratio, side;
  const PffTestCtx *t;
} Bubbly;

static PetscBool InBubble(const Bubbly *c, const PetscReal x[3])
{
  for (PetscInt b = 0; b < 9; b++) {
    PetscReal r2 = 0;
    for (int a = 0; a < 3; a++) {
      const PetscReal centre = b == 8 ? 0.5 : ((b >> a) & 1 ? 0.75 : 0.25);
      r2 += PetscSqr(x[a] / c->side - centre);
    }
    if (r2 < 0.01) return PETSC_TRUE;
  }
  return PETSC_FALSE;
}

static PetscReal BetaFn(const PetscReal x[3], PetscInt comp, void *vctx)
{
  const Bubbly *c = (const Bubbly *)vctx;
  (void)comp;
  return c->ratio > 0 && InBubble(c, x) ? c->ratio : 1.0;
}

static PetscReal RandomFn(const PetscReal x[3], PetscInt comp, void *vctx)
{
  const Bubbly *c = (const Bubbly *)vctx;
  uint64_t      q[3];
  if (PetscAbsReal(x[comp] - c->t->origin[comp]) < 1e-3 * c->t->h0) return 0; /* closed lower wall */
  for (int a = 0; a < 3; a++) q[a] = (uint64_t)llround((x[a] - c->t->origin[a]) / (0.25 * c->t->h0));
  return (PetscReal)(PffTestKey(17, q[0] + 1000003ULL * (uint64_t)comp, q[1], q[2]) >> 11) / 9007199254740992.0 - 0.5;
}

/* A closed unit box of N^3 finest cells, blocks of n0, uniform or graded over 3 levels. */
static PetscErrorCode CreateCase(MPI_Comm comm, PetscInt N, PetscInt n0, PetscBool graded, PetscReal ratio,
                                 PffTestCtx *t, Bubbly *c)
{
  const PetscInt  nb[3]     = {N / n0, N / n0, N / n0};
  const PetscBool per[3]    = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};
  const PetscReal origin[3] = {0, 0, 0};

  PetscFunctionBeginUser;
  PetscCall(PffTestCreateGrid(comm, nb, per, origin, 1.0 / (PetscReal)N, n0, graded ? 3 : 1, graded ? -1 : 0, 0, 5, t));
  c->t     = t;
  c->ratio = ratio;
  c->side  = 1.0;
  PetscCall(PffTestAddPressureChannels(t->grid, BetaFn, RandomFn, c, &c->betaCh, &c->openCh, &c->uCh, &c->pCh));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode CreatePressure(PffTestCtx *t, Bubbly *c, PetscReal rtol, PffPressure *ps)
{
  KSP ksp;

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsSetValue(NULL, "-pressure_pc_type", "pffmg"));
  PetscCall(PffPressureCreate(t->grid, ps));
  PetscCall(PffPressureSetFromOptions(*ps));
  PetscCall(PffPressureSetUp(*ps));
  PetscCall(PffPressureSetCoefficients(*ps, c->betaCh, c->openCh));
  PetscCall(PffPressureGetKSP(*ps, &ksp));
  PetscCall(KSPSetTolerances(ksp, rtol, 1e-50, PETSC_DEFAULT, 500));
  PetscCall(KSPSetUp(ksp));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Level-1 row of the coarse cell at global coarse position (5, 6, 7) of a uniform 32^3 grid in 8^3 blocks
   (block (1, 1, 1), local cell (1, 2, 3)) with beta = 1: 7 entries, off-diagonals -cf, diagonal 6 cf. */
static PetscErrorCode CheckUniformRow(PffTestCtx *t, Mat A1, PetscReal cf)
{
  const PetscInt gid = 1 + 4 * (1 + 4 * 1);
  PetscInt       lb;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetLocalIndex(t->grid, gid, &lb));
  if (lb >= 0) {
    PetscInt           rstart1, ncols, nnz = 0;
    const PetscInt    *cols;
    const PetscScalar *vals;
    PetscCall(MatGetOwnershipRange(A1, &rstart1, NULL));
    const PetscInt row = rstart1 + 64 * lb + 1 + 4 * (2 + 4 * 3); /* 4^3 level-1 cells per owned block */
    PetscCall(MatGetRow(A1, row, &ncols, &cols, &vals));
    for (PetscInt k = 0; k < ncols; k++) {
      if (vals[k] == 0) continue;
      nnz++;
      const PetscReal expect = cols[k] == row ? 6 * cf : -cf;
      PetscCheck(PetscAbsScalar(vals[k] - expect) <= 1e-12 * cf, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                 "galerkin: level-1 entry (%" PetscInt_FMT ", %" PetscInt_FMT ") = %g, expected %g", row, cols[k],
                 (double)PetscRealPart(vals[k]), (double)expect);
    }
    PetscCheck(nnz == 7, PETSC_COMM_SELF, PETSC_ERR_PLIB, "galerkin: level-1 row has %" PetscInt_FMT " entries, not 7",
               nnz);
    PetscCall(MatRestoreRow(A1, row, &ncols, &cols, &vals));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -pressure_pffmg_rescale 0: every level equals P^T A P by explicit products, and on a uniform grid with beta = 1
   a coarse face carries the sum 4 h of its four fine faces (Algorithm 1). Rescaled (the default): the coarse face
   carries 2 h = (2h) beta, the coefficient of the coarse discretisation, and every level stays symmetric with
   zero row sums (closed box). */
static PetscErrorCode TestGalerkin(PetscBool graded, PetscBool belowRaster)
{
  PffTestCtx      t;
  Bubbly          c;
  const PetscReal h = 1.0 / 32;

  PetscFunctionBeginUser;
  PetscCall(CreateCase(PETSC_COMM_WORLD, 32, 8, graded, graded ? 1e3 : 0, &t, &c));
  for (PetscInt rescale = 0; rescale < 2; rescale++) {
    PffPressure    ps;
    PffMGStats     st;
    const PetscInt nexpect = belowRaster ? 6 : 4; /* 32^3 in 8^3 blocks: 4 block levels, then 64 -> 8 -> 1 */
    PetscCall(PetscOptionsSetValue(NULL, "-pressure_pffmg_rescale", rescale ? "1" : "0"));
    PetscCall(PetscOptionsSetValue(NULL, "-pressure_pffmg_coarse_max", belowRaster ? "1" : "4096"));
    PetscCall(CreatePressure(&t, &c, 1e-8, &ps));
    PetscCall(PffPressureMGGetStats(ps, &st));
    PetscCheck(st.levels == nexpect, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
               "galerkin: %" PetscInt_FMT " levels, expected %" PetscInt_FMT, st.levels, nexpect);
    for (PetscInt L = 1; L < st.levels; L++) {
      Mat       Af, P, Ac, AP, PtAP;
      Vec       one, r;
      PetscReal nrm, err, rsum;
      PetscBool sym;
      PetscCall(PffPressureMGGetLevel(ps, L - 1, &Af, &P));
      PetscCall(PffPressureMGGetLevel(ps, L, &Ac, NULL));
      PetscCall(MatIsSymmetric(Ac, 1e-12, &sym));
      PetscCheck(sym, PETSC_COMM_WORLD, PETSC_ERR_PLIB, "galerkin: level %" PetscInt_FMT " is not symmetric", L);
      PetscCall(MatCreateVecs(Ac, &one, &r));
      PetscCall(VecSet(one, 1.0));
      PetscCall(MatMult(Ac, one, r));
      PetscCall(VecNorm(r, NORM_INFINITY, &rsum));
      PetscCall(MatNorm(Af, NORM_INFINITY, &nrm)); /* the finer level's scale: the last level may be 1 x 1 and ~0 */
      PetscCheck(rsum <= 1e-12 * nrm, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
                 "galerkin: level %" PetscInt_FMT " row sums up to %g (norm %g)", L, (double)rsum, (double)nrm);
      PetscCall(VecDestroy(&one));
      PetscCall(VecDestroy(&r));
      if (!rescale) {
        PetscCall(MatMatMult(Af, P, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &AP));
        PetscCall(MatTransposeMatMult(P, AP, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &PtAP));
        PetscCall(MatNorm(PtAP, NORM_FROBENIUS, &nrm));
        PetscCall(MatAXPY(PtAP, -1.0, Ac, DIFFERENT_NONZERO_PATTERN));
        PetscCall(MatNorm(PtAP, NORM_FROBENIUS, &err));
        /* the matrix-free levels keep their face coefficients in float: a coarse face is a float sum */
        PetscCheck(err <= 1e-6 * nrm, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
                   "galerkin: level %" PetscInt_FMT " differs from P^T A P by %g (norm %g)", L, (double)err,
                   (double)nrm);
        PetscCall(MatDestroy(&AP));
        PetscCall(MatDestroy(&PtAP));
      }
    }
    if (!graded) {
      Mat A1;
      PetscCall(PffPressureMGGetLevel(ps, 1, &A1, NULL));
      PetscCall(CheckUniformRow(&t, A1, rescale ? 2 * h : 4 * h));
    }
    PetscCall(PetscPrintf(PETSC_COMM_WORLD, "galerkin %s %s: %" PetscInt_FMT " levels%s symmetric, zero row sums%s\n",
                          graded ? "graded " : "uniform", rescale ? "rescaled" : "plain   ", st.levels,
                          belowRaster ? " (2 below the raster)" : "",
                          rescale ? (graded ? "" : ", coarse face 2h")
                                  : (graded ? ", equal P^T A P" : ", equal P^T A P, coarse face = sum of 4 fine")));
    PetscCall(PffPressureDestroy(&ps));
  }
  PetscCall(PetscOptionsClearValue(NULL, "-pressure_pffmg_rescale"));
  PetscCall(PetscOptionsClearValue(NULL, "-pressure_pffmg_coarse_max"));
  PetscCall(PffGridDestroy(&t.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* KSP its of FCG + the module's PC on b = A r (r random, fixed seed) from x = 0. */
static PetscErrorCode SolveRandom(PffPressure ps, PetscInt *its)
{
  KSP         ksp;
  Mat         A;
  Vec         r, b, x;
  PetscRandom rnd;

  PetscFunctionBeginUser;
  PetscCall(PffPressureGetKSP(ps, &ksp));
  PetscCall(KSPGetOperators(ksp, &A, NULL));
  PetscCall(MatCreateVecs(A, &r, &b));
  PetscCall(VecDuplicate(r, &x));
  PetscCall(PetscRandomCreate(PETSC_COMM_WORLD, &rnd));
  PetscCall(PetscRandomSetSeed(rnd, 5));
  PetscCall(PetscRandomSeed(rnd));
  PetscCall(VecSetRandom(r, rnd));
  PetscCall(MatMult(A, r, b));
  PetscCall(VecSet(x, 0.0));
  PetscCall(KSPSolve(ksp, b, x));
  PetscCall(KSPGetIterationNumber(ksp, its));
  PetscCall(PetscRandomDestroy(&rnd));
  PetscCall(VecDestroy(&r));
  PetscCall(VecDestroy(&b));
  PetscCall(VecDestroy(&x));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The matrix-free levels (face coefficients, Algorithm 1 without products) equal the AIJ Galerkin
   products of -pressure_pffmg_operator aij, rescaled and plain, on every level, up to their float storage;
   FCG + pffmg takes the same iterations within 1 with either. */
static PetscErrorCode TestStencilMatchesAIJ(PetscBool graded)
{
  PffTestCtx t;
  Bubbly     c;

  PetscFunctionBeginUser;
  PetscCall(CreateCase(PETSC_COMM_WORLD, 32, 8, graded, 1e3, &t, &c));
  PetscCall(PetscOptionsSetValue(NULL, "-pressure_pffmg_coarse_max", "1"));
  for (PetscInt rescale = 0; rescale < 2; rescale++) {
    PffPressure ps[2];
    PffMGStats  st[2];
    PetscReal   worst = 0;
    PetscInt    its[2];
    PetscCall(PetscOptionsSetValue(NULL, "-pressure_pffmg_rescale", rescale ? "1" : "0"));
    for (PetscInt m = 0; m < 2; m++) { /* the same consistent system b = A r, r random, from x = 0 */
      PetscCall(PetscOptionsSetValue(NULL, "-pressure_pffmg_operator", m == 0 ? "stencil" : "aij"));
      PetscCall(CreatePressure(&t, &c, 1e-8, &ps[m]));
      PetscCall(PffPressureMGGetStats(ps[m], &st[m]));
      PetscCall(SolveRandom(ps[m], &its[m]));
    }
    PetscCheck(st[0].levels == st[1].levels, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
               "stencil: %" PetscInt_FMT " levels, aij %" PetscInt_FMT, st[0].levels, st[1].levels);
    PetscReal scale = 0; /* the finer level's norm: the last level may be 1 x 1 and ~0 */
    for (PetscInt L = 0; L < st[0].levels; L++) {
      Mat       As, Aa, D;
      PetscReal nrm, err;
      PetscCall(PffPressureMGGetLevel(ps[0], L, &As, NULL));
      PetscCall(PffPressureMGGetLevel(ps[1], L, &Aa, NULL));
      PetscCall(MatDuplicate(Aa, MAT_COPY_VALUES, &D));
      PetscCall(MatAXPY(D, -1.0, As, DIFFERENT_NONZERO_PATTERN));
      PetscCall(MatNorm(Aa, NORM_FROBENIUS, &nrm));
      PetscCall(MatNorm(D, NORM_FROBENIUS, &err));
      nrm   = PetscMax(nrm, scale);
      scale = nrm;
      PetscCheck(err <= 1e-6 * nrm, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
                 "stencil: level %" PetscInt_FMT " (%s) differs from the AIJ Galerkin level by %g (norm %g)", L,
                 rescale ? "rescaled" : "plain", (double)err, (double)nrm);
      worst = PetscMax(worst, err / nrm);
      PetscCall(MatDestroy(&D));
    }
    PetscCheck(PetscAbs(its[0] - its[1]) <= 1, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
               "stencil: %" PetscInt_FMT " iterations, aij %" PetscInt_FMT, its[0], its[1]);
    PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                          "stencil %s %s: %" PetscInt_FMT " levels equal the AIJ Galerkin levels to %.1e relative; "
                          "%" PetscInt_FMT " iterations (aij %" PetscInt_FMT ")\n",
                          graded ? "graded " : "uniform", rescale ? "rescaled" : "plain   ", st[0].levels,
                          (double)worst, its[0], its[1]));
    for (PetscInt m = 0; m < 2; m++) PetscCall(PffPressureDestroy(&ps[m]));
  }
  PetscCall(PetscOptionsClearValue(NULL, "-pressure_pffmg_operator"));
  PetscCall(PetscOptionsClearValue(NULL, "-pressure_pffmg_rescale"));
  PetscCall(PetscOptionsClearValue(NULL, "-pressure_pffmg_coarse_max"));
  PetscCall(PffGridDestroy(&t.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* New coefficients (a time step): pffmg sets up again. A module that solved with density ratio 1e3 and
   then gets ratio 1e5 takes the iterations of a fresh module at 1e5, not those of a PC left at 1e3. */
static PetscErrorCode TestNewCoefficients(void)
{
  PffTestCtx  t;
  Bubbly      c;
  PffPressure ps, fresh;
  PetscInt    its0, its1, its2;

  PetscFunctionBeginUser;
  PetscCall(CreateCase(PETSC_COMM_WORLD, 32, 8, PETSC_TRUE, 1e3, &t, &c));
  PetscCall(CreatePressure(&t, &c, 1e-8, &ps));
  PetscCall(SolveRandom(ps, &its0));
  c.ratio = 1e5;
  PetscCall(PffGridFillChannel(t.grid, c.betaCh, BetaFn, &c));
  PetscCall(PffPressureSetCoefficients(ps, c.betaCh, c.openCh));
  PetscCall(SolveRandom(ps, &its1));
  PetscCall(CreatePressure(&t, &c, 1e-8, &fresh));
  PetscCall(SolveRandom(fresh, &its2));
  PetscCheck(PetscAbs(its1 - its2) <= 1, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
             "new coefficients: %" PetscInt_FMT " iterations, a fresh module %" PetscInt_FMT, its1, its2);
  PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                        "new coefficients: ratio 1e3 (%" PetscInt_FMT " its) then 1e5: %" PetscInt_FMT
                        " iterations, a fresh module %" PetscInt_FMT "\n",
                        its0, its1, its2));
  PetscCall(PffPressureDestroy(&ps));
  PetscCall(PffPressureDestroy(&fresh));
  PetscCall(PffGridDestroy(&t.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* e^T A e of a random e falls under fixed sweeps and under adaptive relaxation on every level but the coarsest. */
static PetscErrorCode TestSmoother(PetscBool graded)
{
  PffTestCtx  t;
  Bubbly      c;
  PffPressure ps;
  PffMGStats  st;

  PetscFunctionBeginUser;
  PetscCall(CreateCase(PETSC_COMM_WORLD, 32, 8, graded, 1e3, &t, &c));
  PetscCall(CreatePressure(&t, &c, 1e-8, &ps));
  PetscCall(PffPressureMGGetStats(ps, &st));
  for (PetscInt L = 0; L + 1 < st.levels; L++) {
    Mat         A;
    Vec         x, b, Ax;
    PetscRandom rnd;
    for (PetscInt mode = 0; mode < 2; mode++) {
      PetscScalar e0, e1;
      PetscCall(PffPressureMGGetLevel(ps, L, &A, NULL));
      PetscCall(MatCreateVecs(A, &x, &b));
      PetscCall(VecDuplicate(x, &Ax));
      PetscCall(PetscRandomCreate(PETSC_COMM_WORLD, &rnd));
      PetscCall(PetscRandomSetSeed(rnd, 7 + (unsigned long)L));
      PetscCall(PetscRandomSeed(rnd));
      PetscCall(VecSetRandom(x, rnd));
      PetscCall(VecSet(b, 0.0));
      PetscCall(MatMult(A, x, Ax));
      PetscCall(VecDot(x, Ax, &e0));
      PetscCall(PffPressureMGSmooth(ps, L, b, x, mode == 0 ? 1 : 0));
      PetscCall(MatMult(A, x, Ax));
      PetscCall(VecDot(x, Ax, &e1));
      PetscCheck(PetscRealPart(e1) < 0.9 * PetscRealPart(e0), PETSC_COMM_WORLD, PETSC_ERR_PLIB,
                 "smoother (%s) on level %" PetscInt_FMT ": energy %g -> %g", mode == 0 ? "fixed" : "adaptive", L,
                 (double)PetscRealPart(e0), (double)PetscRealPart(e1));
      PetscCall(PetscPrintf(PETSC_COMM_WORLD, "smoother %s level %" PetscInt_FMT " %-8s: energy ratio %.3f\n",
                            graded ? "graded " : "uniform", L, mode == 0 ? "fixed" : "adaptive",
                            (double)(PetscRealPart(e1) / PetscRealPart(e0))));
      PetscCall(PetscRandomDestroy(&rnd));
      PetscCall(VecDestroy(&x));
      PetscCall(VecDestroy(&b));
      PetscCall(VecDestroy(&Ax));
    }
  }
  PetscCall(PffPressureDestroy(&ps));
  PetscCall(PffGridDestroy(&t.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* One fixed hybrid sweep of the finest level, matrix-free against AIJ, from the same x and b, in blocks of
   16^3 (the rows the AVX-512 kernel takes where it is compiled) and, graded, of 16, 8 and 4: both do the
   same red-black Gauss-Seidel in the same order, so the updates agree up to the float coefficients of the
   matrix-free level. */
static PetscErrorCode TestSweepMatchesAIJ(PetscBool graded)
{
  PffTestCtx t;
  Bubbly     c;
  Vec        x0 = NULL, b = NULL, x[2], dx[2];
  PetscReal  nd, ne;

  PetscFunctionBeginUser;
  PetscCall(CreateCase(PETSC_COMM_WORLD, graded ? 64 : 32, 16, graded, 1e3, &t, &c));
  for (PetscInt m = 0; m < 2; m++) {
    PffPressure ps;
    Mat         A;
    PetscCall(PetscOptionsSetValue(NULL, "-pressure_pffmg_operator", m == 0 ? "stencil" : "aij"));
    PetscCall(CreatePressure(&t, &c, 1e-8, &ps));
    PetscCall(PffPressureMGGetLevel(ps, 0, &A, NULL));
    if (m == 0) {
      PetscRandom rnd;
      PetscCall(MatCreateVecs(A, &x0, &b));
      PetscCall(PetscRandomCreate(PETSC_COMM_WORLD, &rnd));
      PetscCall(PetscRandomSetSeed(rnd, 11));
      PetscCall(PetscRandomSeed(rnd));
      PetscCall(VecSetRandom(x0, rnd));
      PetscCall(VecSetRandom(b, rnd));
      PetscCall(PetscRandomDestroy(&rnd));
    }
    PetscCall(VecDuplicate(x0, &x[m]));
    PetscCall(VecCopy(x0, x[m]));
    PetscCall(PffPressureMGSmooth(ps, 0, b, x[m], 1));
    PetscCall(VecDuplicate(x0, &dx[m]));
    PetscCall(VecWAXPY(dx[m], -1.0, x0, x[m]));
    PetscCall(PffPressureDestroy(&ps));
  }
  PetscCall(VecNorm(dx[1], NORM_2, &nd));
  PetscCall(VecAXPY(dx[0], -1.0, dx[1]));
  PetscCall(VecNorm(dx[0], NORM_2, &ne));
  PetscCheck(nd > 0 && ne <= 1e-5 * nd, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
             "sweep %s: the matrix-free update differs from the AIJ one by %g (norm %g)", graded ? "graded" : "uniform",
             (double)ne, (double)nd);
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "sweep %s, 16^3 blocks: matrix-free update equals AIJ to %.1e relative\n",
                        graded ? "graded " : "uniform", (double)(ne / nd)));
  for (PetscInt m = 0; m < 2; m++) {
    PetscCall(VecDestroy(&x[m]));
    PetscCall(VecDestroy(&dx[m]));
  }
  PetscCall(VecDestroy(&x0));
  PetscCall(VecDestroy(&b));
  PetscCall(PetscOptionsClearValue(NULL, "-pressure_pffmg_operator"));
  PetscCall(PffGridDestroy(&t.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* One application of the preconditioner (fixed sweeps, V-cycle) with matrix-free levels against the AIJ
   levels: the matrix-free levels restrict the residual and prolong the correction block by block without P,
   the AIJ levels through P, so a wrong parent cell (graded: blocks whose coarse block has as many cells)
   shows as an O(1) difference; the float coefficients leave about 1e-7. */
static PetscErrorCode TestCycleMatchesAIJ(PetscBool graded)
{
  PffTestCtx t;
  Bubbly     c;
  Vec        b = NULL, y[2];
  PetscReal  ny, ne;

  PetscFunctionBeginUser;
  PetscCall(CreateCase(PETSC_COMM_WORLD, 32, 8, graded, 1e3, &t, &c));
  PetscCall(PetscOptionsSetValue(NULL, "-pressure_pffmg_adaptive", "0"));
  PetscCall(PetscOptionsSetValue(NULL, "-pressure_pffmg_kcycle", "0"));
  for (PetscInt m = 0; m < 2; m++) {
    PffPressure ps;
    KSP         ksp;
    PC          pc;
    PetscCall(PetscOptionsSetValue(NULL, "-pressure_pffmg_operator", m == 0 ? "stencil" : "aij"));
    PetscCall(CreatePressure(&t, &c, 1e-8, &ps));
    PetscCall(PffPressureGetKSP(ps, &ksp));
    PetscCall(KSPGetPC(ksp, &pc));
    if (m == 0) {
      PetscRandom rnd;
      Mat         A;
      PetscCall(KSPGetOperators(ksp, &A, NULL));
      PetscCall(MatCreateVecs(A, NULL, &b));
      PetscCall(PetscRandomCreate(PETSC_COMM_WORLD, &rnd));
      PetscCall(PetscRandomSetSeed(rnd, 5));
      PetscCall(PetscRandomSeed(rnd));
      PetscCall(VecSetRandom(b, rnd));
      PetscCall(PetscRandomDestroy(&rnd));
    }
    PetscCall(VecDuplicate(b, &y[m]));
    PetscCall(PCApply(pc, b, y[m]));
    PetscCall(PffPressureDestroy(&ps));
  }
  PetscCall(VecNorm(y[1], NORM_2, &ny));
  PetscCall(VecAXPY(y[0], -1.0, y[1]));
  PetscCall(VecNorm(y[0], NORM_2, &ne));
  PetscCheck(ny > 0 && ne <= 1e-4 * ny, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
             "cycle %s: the matrix-free V-cycle differs from the AIJ one by %g (norm %g)",
             graded ? "graded" : "uniform", (double)ne, (double)ny);
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "cycle %s: matrix-free V-cycle equals AIJ to %.1e relative\n",
                        graded ? "graded " : "uniform", (double)(ne / ny)));
  PetscCall(VecDestroy(&y[0]));
  PetscCall(VecDestroy(&y[1]));
  PetscCall(VecDestroy(&b));
  PetscCall(PetscOptionsClearValue(NULL, "-pressure_pffmg_operator"));
  PetscCall(PetscOptionsClearValue(NULL, "-pressure_pffmg_adaptive"));
  PetscCall(PetscOptionsClearValue(NULL, "-pressure_pffmg_kcycle"));
  PetscCall(PffGridDestroy(&t.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode Solve(MPI_Comm comm, PetscBool graded, PetscReal ratio, PetscInt *its, PetscReal *rnorm,
                            PffMGStats *mst)
{
  PffTestCtx       t;
  Bubbly           c;
  PffPressure      ps;
  PffPressureStats st;

  PetscFunctionBeginUser;
  PetscCall(CreateCase(comm, 32, 8, graded, ratio, &t, &c));
  PetscCall(CreatePressure(&t, &c, 1e-8, &ps));
  PetscCall(PffPressureProject(ps, c.uCh, 1.0, -1, c.pCh, &st));
  PetscCheck(st.reason > 0, comm, PETSC_ERR_NOT_CONVERGED,
             "solve: FCG + pffmg did not converge: %s after %" PetscInt_FMT, KSPConvergedReasons[st.reason], st.its);
  *its   = st.its;
  *rnorm = st.rnorm;
  if (mst) PetscCall(PffPressureMGGetStats(ps, mst));
  PetscCall(PffPressureDestroy(&ps));
  PetscCall(PffGridDestroy(&t.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode TestSolve(PetscBool graded, PetscBool belowRaster)
{
  PetscInt  its, its1;
  PetscReal rn, rn1;

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsSetValue(NULL, "-pressure_pffmg_coarse_max", belowRaster ? "1" : "4096"));
  PetscCall(Solve(PETSC_COMM_WORLD, graded, 1e3, &its, &rn, NULL));
  PetscCall(Solve(PETSC_COMM_SELF, graded, 1e3, &its1, &rn1, NULL));
  PetscCheck(rn <= 1e-8 && rn1 <= 1e-8, PETSC_COMM_WORLD, PETSC_ERR_PLIB, "solve: residual %g / %g above 1e-8",
             (double)rn, (double)rn1);
  /* the rank count changes reduction orders and the ownership of coarse cells below the raster */
  PetscCheck(its <= its1 + 3, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
             "solve: %" PetscInt_FMT " iterations on all ranks, %" PetscInt_FMT " on one", its, its1);
  PetscCheck(its <= 25, PETSC_COMM_WORLD, PETSC_ERR_PLIB, "solve: %" PetscInt_FMT " iterations (more than 25)", its);
  PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                        "solve %s bubbly 32^3 ratio 1e3%s: converged to rtol 1e-8 in %" PetscInt_FMT
                        " iterations (one rank: %" PetscInt_FMT ")\n",
                        graded ? "graded " : "uniform", belowRaster ? ", uniform levels below the raster" : "", its,
                        its1));
  PetscCall(PetscOptionsClearValue(NULL, "-pressure_pffmg_coarse_max"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The conditional K-cycle (the default -pressure_pffmg_kcycle 4 -pressure_pffmg_kcycle_rtol 0.25) at ratio 1e5: at
   most the iterations of the fixed two-step K-cycle, and fewer cell updates per iteration than four fixed steps,
   i.e. the coarse corrections do stop early. */
static PetscErrorCode TestKCycle(void)
{
  const char *const set[3][2] = {{"4", "0.25"}, {"2", "0"}, {"4", "0"}};
  PetscInt          its[3];
  PetscReal         rn[3], upd[3];

  PetscFunctionBeginUser;
  for (PetscInt k = 0; k < 3; k++) {
    PffMGStats mst;
    PetscCall(PetscOptionsSetValue(NULL, "-pressure_pffmg_kcycle", set[k][0]));
    PetscCall(PetscOptionsSetValue(NULL, "-pressure_pffmg_kcycle_rtol", set[k][1]));
    PetscCall(Solve(PETSC_COMM_WORLD, PETSC_FALSE, 1e5, &its[k], &rn[k], &mst));
    PetscCheck(rn[k] <= 1e-8, PETSC_COMM_WORLD, PETSC_ERR_PLIB, "kcycle %s rtol %s: residual %g above 1e-8", set[k][0],
               set[k][1], (double)rn[k]);
    upd[k] = (PetscReal)mst.cellUpdates / (PetscReal)its[k];
  }
  PetscCall(PetscOptionsClearValue(NULL, "-pressure_pffmg_kcycle"));
  PetscCall(PetscOptionsClearValue(NULL, "-pressure_pffmg_kcycle_rtol"));
  PetscCheck(its[0] <= its[1], PETSC_COMM_WORLD, PETSC_ERR_PLIB,
             "kcycle: conditional %" PetscInt_FMT " iterations, two fixed steps %" PetscInt_FMT, its[0], its[1]);
  PetscCheck(upd[0] < upd[2], PETSC_COMM_WORLD, PETSC_ERR_PLIB,
             "kcycle: conditional %g cell updates per iteration, four fixed steps %g", (double)upd[0], (double)upd[2]);
  PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                        "kcycle uniform bubbly 32^3 ratio 1e5: conditional (4, 0.25) %" PetscInt_FMT
                        " iterations, %.0f cell updates each; two fixed steps %" PetscInt_FMT
                        " iterations; four fixed steps %" PetscInt_FMT " iterations, %.0f cell updates each\n",
                        its[0], (double)upd[0], its[1], its[2], (double)upd[2]));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The K-cycle only below strong coarsening (-pressure_pffmg_kcycle_ratio): on the graded grid the first coarse level
   keeps the coarse block's cells and holds 1/3.1 of the finest level's rows. With the ratio at 4 that level gets one
   cycle instead of up to four flexible-CG steps: fewer cell updates per iteration, the same residual, at most four
   iterations more (three here: a level at 1/3.1 is still worth its K-cycle, which is why the default is 2.5).
   At the default the graded grid keeps the K-cycle on every level (the same iterations and updates as ratio 0). */
static PetscErrorCode TestKCycleRatio(void)
{
  const char *const ratio[3] = {"4", "0", NULL};
  PetscInt          its[3], n[2];
  PetscReal         rn[3], upd[3];

  PetscFunctionBeginUser;
  {
    PffTestCtx  t;
    Bubbly      c;
    PffPressure ps;
    Mat         A;
    PetscCall(CreateCase(PETSC_COMM_WORLD, 32, 8, PETSC_TRUE, 1e3, &t, &c));
    PetscCall(CreatePressure(&t, &c, 1e-8, &ps));
    for (PetscInt L = 0; L < 2; L++) {
      PetscCall(PffPressureMGGetLevel(ps, L, &A, NULL));
      PetscCall(MatGetSize(A, &n[L], NULL));
    }
    PetscCall(PffPressureDestroy(&ps));
    PetscCall(PffGridDestroy(&t.grid));
  }
  PetscCheck(4 * n[1] > n[0] && 5 * n[1] < 2 * n[0], PETSC_COMM_WORLD, PETSC_ERR_PLIB,
             "kcycle ratio: the graded case's level 1 has %" PetscInt_FMT " rows of level 0's %" PetscInt_FMT
             ", not between 1/4 and 1/2.5",
             n[1], n[0]);
  for (PetscInt k = 0; k < 3; k++) {
    PffMGStats mst;
    if (ratio[k])
      PetscCall(PetscOptionsSetValue(NULL, "-pressure_pffmg_kcycle_ratio", ratio[k]));
    else
      PetscCall(PetscOptionsClearValue(NULL, "-pressure_pffmg_kcycle_ratio"));
    PetscCall(Solve(PETSC_COMM_WORLD, PETSC_TRUE, 1e3, &its[k], &rn[k], &mst));
    PetscCheck(rn[k] <= 1e-8, PETSC_COMM_WORLD, PETSC_ERR_PLIB, "kcycle ratio %s: residual %g above 1e-8",
               ratio[k] ? ratio[k] : "default", (double)rn[k]);
    upd[k] = (PetscReal)mst.cellUpdates / (PetscReal)its[k];
  }
  PetscCheck(upd[0] < upd[1] && its[0] <= its[1] + 4, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
             "kcycle ratio 4: %" PetscInt_FMT " iterations, %g cell updates each; ratio 0: %" PetscInt_FMT
             " iterations, %g cell updates each",
             its[0], (double)upd[0], its[1], (double)upd[1]);
  PetscCheck(its[2] == its[1] && upd[2] == upd[1], PETSC_COMM_WORLD, PETSC_ERR_PLIB,
             "kcycle ratio: the default changed the graded case (%" PetscInt_FMT " iterations, %g cell updates each)",
             its[2], (double)upd[2]);
  PetscCall(PetscPrintf(
      PETSC_COMM_WORLD,
      "kcycle ratio graded bubbly 32^3 (levels 0, 1: %" PetscInt_FMT ", %" PetscInt_FMT " rows): ratio 4 %" PetscInt_FMT
      " iterations, %.0f cell updates each; ratio 0 and default %" PetscInt_FMT " iterations, %.0f cell updates each\n",
      n[0], n[1], its[0], (double)upd[0], its[1], (double)upd[1]));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A solid obstacle: the faces of a box on the floor are closed, so its cells have no open face and get identity rows
   on level 0. Those rows must not reach the coarse levels, where they acted as p = 0 at the solid (a wall that is not
   there: the K-cycle then took more iterations than the V-cycle in the dam breaks, tested on the real scene by
   dam_break_solid_its in tests/postproc), so the prolongation leaves the cells inside the solid alone: one
   application of the preconditioner to a random vector that is 0 there must return 0 there, and not elsewhere. */
static PetscBool InBox(const PetscReal y[3])
{
  return (PetscBool)(y[0] > 0.3 && y[0] < 0.7 && y[1] < 0.3 && y[2] > 0.3 && y[2] < 0.7);
}

static PetscReal OpenOutsideBox(const PetscReal x[3], PetscInt comp, void *vctx)
{
  const Bubbly *c = (const Bubbly *)vctx;
  for (PetscInt side = -1; side <= 1; side += 2) {
    PetscReal y[3] = {x[0], x[1], x[2]};
    y[comp] += 0.5 * side * c->t->h0; /* the cell centre on each side of the face */
    if (InBox(y)) return 0.0;
  }
  return 1.0;
}

static PetscErrorCode TestSolid(PetscBool graded)
{
  PffTestCtx   t;
  Bubbly       c;
  PffPressure  ps;
  KSP          ksp;
  PC           pc;
  Mat          A;
  Vec          b, z;
  PetscRandom  rnd;
  PetscInt     nlocal, inside = 0, nonzero = 0, zeroOutside = 0;
  PetscScalar *bb;
  PetscBool   *mask;

  PetscFunctionBeginUser;
  PetscCall(CreateCase(PETSC_COMM_WORLD, 32, 8, graded, 1e3, &t, &c));
  PetscCall(PffGridFillChannel(t.grid, c.openCh, OpenOutsideBox, &c));
  PetscCall(CreatePressure(&t, &c, 1e-8, &ps));
  PetscCall(PffPressureGetKSP(ps, &ksp));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PffPressureMGGetLevel(ps, 0, &A, NULL));
  PetscCall(MatCreateVecs(A, &z, &b));
  PetscCall(PetscRandomCreate(PETSC_COMM_WORLD, &rnd));
  PetscCall(VecSetRandom(b, rnd));
  PetscCall(PetscRandomDestroy(&rnd));
  PetscCall(VecShift(b, -0.5));
  /* the cells whose centre lies in the box (every face closed): b = 0 there */
  PetscCall(VecGetArray(b, &bb));
  PetscCall(PffGridGetLocalBlocks(t.grid, &nlocal));
  PetscInt nrows;
  PetscCall(VecGetLocalSize(b, &nrows));
  PetscCall(PetscCalloc1(nrows, &mask));
  for (PetscInt lb = 0, r = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(t.grid, lb, &info));
    for (PetscInt k = 0; k < info.n; k++)
      for (PetscInt j = 0; j < info.n; j++)
        for (PetscInt i = 0; i < info.n; i++, r++) {
          const PetscReal y[3] = {info.lo[0] + (i + 0.5) * info.h, info.lo[1] + (j + 0.5) * info.h,
                                  info.lo[2] + (k + 0.5) * info.h};
          /* a coarse cell lies in the box only if all of it does: its eight corners' fine centres */
          PetscBool in = PETSC_TRUE;
          for (PetscInt e = 0; e < 8; e++) {
            const PetscReal q[3] = {y[0] + ((e & 1) ? 0.5 : -0.5) * (info.h - t.h0),
                                    y[1] + ((e & 2) ? 0.5 : -0.5) * (info.h - t.h0),
                                    y[2] + ((e & 4) ? 0.5 : -0.5) * (info.h - t.h0)};
            if (!InBox(q)) in = PETSC_FALSE;
          }
          if (in) {
            mask[r] = PETSC_TRUE;
            bb[r]   = 0;
            inside++;
          }
        }
  }
  PetscCall(VecRestoreArray(b, &bb));
  PetscCall(PCApply(pc, b, z));
  const PetscScalar *zz;
  PetscCall(VecGetArrayRead(z, &zz));
  for (PetscInt r = 0; r < nrows; r++) {
    if (mask[r] && zz[r] != 0) nonzero++;
    if (!mask[r] && zz[r] == 0) zeroOutside++;
  }
  PetscCall(VecRestoreArrayRead(z, &zz));
  PetscCall(PetscFree(mask));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &inside, 1, MPIU_INT, MPI_SUM, PETSC_COMM_WORLD));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &nonzero, 1, MPIU_INT, MPI_SUM, PETSC_COMM_WORLD));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &zeroOutside, 1, MPIU_INT, MPI_SUM, PETSC_COMM_WORLD));
  PetscCheck(inside > 0 && nonzero == 0 && zeroOutside == 0, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
             "solid: %" PetscInt_FMT " of %" PetscInt_FMT " cells inside the box got a correction (%" PetscInt_FMT
             " cells outside none)",
             nonzero, inside, zeroOutside);
  PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                        "solid %s 32^3 with a closed box: the preconditioner leaves its %" PetscInt_FMT " cells at 0\n",
                        graded ? "graded " : "uniform", inside));
  PetscCall(VecDestroy(&b));
  PetscCall(VecDestroy(&z));
  PetscCall(PffPressureDestroy(&ps));
  PetscCall(PffGridDestroy(&t.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The per-level log events (-log_view's MGLevel0 ... MGLevel7+): level 0's is entered twice per V-cycle (before and
   after the coarse correction); each level above the coarsest at least as often as the one above it (the K-cycle
   visits a coarser level once or more per visit of the finer one); the coarsest never (MGCoarse times it); and
   the levels' times add up to at most MGApply's, which holds them all. */
static PetscErrorCode TestLevelEvents(void)
{
  PetscEventPerfInfo before[PFF_MG_LOG_LEVELS + 1], after[PFF_MG_LOG_LEVELS + 1];
  PffMGStats         mst;
  PetscInt           its;
  PetscReal          rn, tl = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscLogDefaultBegin());
  for (PetscInt L = 0; L <= PFF_MG_LOG_LEVELS; L++)
    PetscCall(PetscLogEventGetPerfInfo(0, L < PFF_MG_LOG_LEVELS ? PFF_MGLevel[L] : PFF_MGApply, &before[L]));
  PetscCall(Solve(PETSC_COMM_WORLD, PETSC_FALSE, 1e3, &its, &rn, &mst));
  for (PetscInt L = 0; L <= PFF_MG_LOG_LEVELS; L++)
    PetscCall(PetscLogEventGetPerfInfo(0, L < PFF_MG_LOG_LEVELS ? PFF_MGLevel[L] : PFF_MGApply, &after[L]));
  const PetscInt last = PetscMin(mst.levels - 1, PFF_MG_LOG_LEVELS - 1); /* the levels with their own event */
  PetscCheck(mst.levels >= 3, PETSC_COMM_SELF, PETSC_ERR_PLIB, "level events: only %" PetscInt_FMT " levels",
             mst.levels);
  for (PetscInt L = 0; L <= last; L++) {
    const PetscInt count = after[L].count - before[L].count;
    if (L == 0)
      PetscCheck(count == 2 * mst.applications, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                 "level events: MGLevel0 entered %" PetscInt_FMT " times in %" PetscInt64_FMT " V-cycles", count,
                 mst.applications);
    else if (L == mst.levels - 1)
      PetscCheck(count == 0, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                 "level events: the coarsest level %" PetscInt_FMT " entered %" PetscInt_FMT " times", L, count);
    else
      PetscCheck(count >= after[L - 1].count - before[L - 1].count, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                 "level events: level %" PetscInt_FMT " entered %" PetscInt_FMT " times, fewer than the level above", L,
                 count);
    tl += after[L].time - before[L].time;
  }
  PetscCheck(tl <= 1.001 * (after[PFF_MG_LOG_LEVELS].time - before[PFF_MG_LOG_LEVELS].time), PETSC_COMM_SELF,
             PETSC_ERR_PLIB, "level events: %g s in the levels, %g s in MGApply", (double)tl,
             (double)(after[PFF_MG_LOG_LEVELS].time - before[PFF_MG_LOG_LEVELS].time));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                        "level events uniform bubbly 32^3: %" PetscInt_FMT
                        " levels, MGLevel0 entered %d times in %" PetscInt64_FMT " V-cycles, level 1 %d times\n",
                        mst.levels, after[0].count - before[0].count, mst.applications,
                        after[1].count - before[1].count));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* b nonzero in one block: adaptive relaxation relaxes fewer blocks than two fixed sweeps. */
static PetscErrorCode TestAdaptive(void)
{
  PffTestCtx  t;
  Bubbly      c;
  PffPressure ps;
  PffMGStats  sa, sf;
  Mat         A;
  Vec         x, b;
  PetscInt    rstart;

  PetscFunctionBeginUser;
  PetscCall(CreateCase(PETSC_COMM_WORLD, 32, 8, PETSC_FALSE, 1e3, &t, &c));
  PetscCall(CreatePressure(&t, &c, 1e-8, &ps));
  PetscCall(PffPressureMGGetLevel(ps, 0, &A, NULL));
  PetscCall(MatCreateVecs(A, &x, &b));
  PetscCall(VecSet(b, 0.0));
  PetscCall(MatGetOwnershipRange(A, &rstart, NULL));
  if (rstart == 0) {
    PetscCall(VecSetValue(b, 3 + 8 * (4 + 8 * 5), 1.0, INSERT_VALUES));
    PetscCall(VecSetValue(b, 4 + 8 * (4 + 8 * 5), -1.0, INSERT_VALUES));
  }
  PetscCall(VecAssemblyBegin(b));
  PetscCall(VecAssemblyEnd(b));
  for (PetscInt mode = 0; mode < 2; mode++) {
    PetscCall(VecSet(x, 0.0));
    PetscCall(PffPressureMGResetStats(ps));
    PetscCall(PffPressureMGSmooth(ps, 0, b, x, mode == 0 ? 0 : 2));
    PetscCall(PffPressureMGGetStats(ps, mode == 0 ? &sa : &sf));
  }
  PetscCheck(sa.blockRelaxations < sf.blockRelaxations, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
             "adaptive: %" PetscInt64_FMT " block relaxations, fixed sweeps %" PetscInt64_FMT, sa.blockRelaxations,
             sf.blockRelaxations);
  PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                        "adaptive: localised residual, %" PetscInt64_FMT " block relaxations against %" PetscInt64_FMT
                        " for 2 fixed sweeps\n",
                        sa.blockRelaxations, sf.blockRelaxations));
  PetscCall(VecDestroy(&x));
  PetscCall(VecDestroy(&b));
  PetscCall(PffPressureDestroy(&ps));
  PetscCall(PffGridDestroy(&t.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Adds v to b at cell c of the level-0 block at raster position blk (rows: owned blocks in local order, cells x
   fastest), on the rank that owns it. */
static PetscErrorCode AddAtCell(PffGrid grid, Vec b, const PetscInt blk[3], const PetscInt c[3], PetscScalar v)
{
  PetscInt nlocal, off, rstart;

  PetscFunctionBeginUser;
  PetscCall(VecGetOwnershipRange(b, &rstart, NULL));
  PetscCall(PffGridGetLocalBlocks(grid, &nlocal));
  off = rstart;
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(grid, lb, &info));
    if (info.ijk[0] == blk[0] && info.ijk[1] == blk[1] && info.ijk[2] == blk[2])
      PetscCall(VecSetValue(b, off + c[0] + info.n * (c[1] + info.n * c[2]), v, ADD_VALUES));
    off += info.n * info.n * info.n;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Adaptive relaxation's activation through each side of a block: a dipole on the inner side of one face of block
   (1, 1, 1) of a uniform closed box, with a small uniform background so that the threshold lies far below the
   dipole's residual. The three runs with the dipole at the -x, -y and -z faces (its cells permuted cyclically with
   the axes) are the same problem turned: the box, the coefficients and the red-black colours of cells and blocks
   are invariant under a cyclic permutation of the axes, and the block red-black order gives the same updates in
   any order. So they relax the same number of blocks, and so do the three runs at the + faces; a side whose border
   maximum is lost (not computed, or filed under another side) leaves its neighbour inactive in one run only. (A
   mirror image would not do: it swaps the colours.) Activation must also happen at all. */
static PetscErrorCode TestActivationTurned(void)
{
  PffTestCtx  t;
  Bubbly      c;
  PffPressure ps;
  Mat         A;
  Vec         x, b;
  PetscInt64  relax[2][3];

  PetscFunctionBeginUser;
  PetscCall(CreateCase(PETSC_COMM_WORLD, 32, 8, PETSC_FALSE, 0, &t, &c));
  PetscCall(CreatePressure(&t, &c, 1e-8, &ps));
  PetscCall(PffPressureMGGetLevel(ps, 0, &A, NULL));
  PetscCall(MatCreateVecs(A, &x, &b));
  for (PetscInt side = 0; side < 2; side++)
    for (PetscInt a = 0; a < 3; a++) {
      const PetscInt blk[3] = {1, 1, 1}, base[2][3] = {{side ? 7 : 0, 3, 5}, {side ? 6 : 1, 3, 5}};
      PetscInt       in[3], out[3];
      PffMGStats     st;
      for (PetscInt d = 0; d < 3; d++) { /* axis d of the turned run is axis d - a of the first */
        in[d]  = base[0][(d - a + 3) % 3];
        out[d] = base[1][(d - a + 3) % 3];
      }
      PetscCall(VecSet(b, 1e-6));
      PetscCall(AddAtCell(t.grid, b, blk, in, 1.0));
      PetscCall(AddAtCell(t.grid, b, blk, out, -1.0));
      PetscCall(VecAssemblyBegin(b));
      PetscCall(VecAssemblyEnd(b));
      PetscCall(VecSet(x, 0.0));
      PetscCall(PffPressureMGResetStats(ps));
      PetscCall(PffPressureMGSmooth(ps, 0, b, x, 0));
      PetscCall(PffPressureMGGetStats(ps, &st));
      relax[side][a] = st.blockRelaxations;
    }
  for (PetscInt side = 0; side < 2; side++) {
    PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                          "activation through the %s faces: %" PetscInt64_FMT ", %" PetscInt64_FMT ", %" PetscInt64_FMT
                          " block relaxations (x, y, z; %" PetscInt_FMT " blocks)\n",
                          side ? "+" : "-", relax[side][0], relax[side][1], relax[side][2], t.nblocks));
    PetscCheck(relax[side][0] == relax[side][1] && relax[side][1] == relax[side][2], PETSC_COMM_WORLD, PETSC_ERR_PLIB,
               "activation through the %s faces differs by axis: %" PetscInt64_FMT ", %" PetscInt64_FMT
               ", %" PetscInt64_FMT " block relaxations",
               side ? "+" : "-", relax[side][0], relax[side][1], relax[side][2]);
    PetscCheck(relax[side][0] > t.nblocks + 1, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
               "activation through the %s faces: no block was activated (%" PetscInt64_FMT " relaxations)",
               side ? "+" : "-", relax[side][0]);
  }
  PetscCall(VecDestroy(&x));
  PetscCall(VecDestroy(&b));
  PetscCall(PffPressureDestroy(&ps));
  PetscCall(PffGridDestroy(&t.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  PetscCall(PffInitializePackage());
  PetscCall(TestGalerkin(PETSC_FALSE, PETSC_FALSE));
  PetscCall(TestGalerkin(PETSC_TRUE, PETSC_FALSE));
  PetscCall(TestGalerkin(PETSC_TRUE, PETSC_TRUE));
  PetscCall(TestStencilMatchesAIJ(PETSC_FALSE));
  PetscCall(TestStencilMatchesAIJ(PETSC_TRUE));
  PetscCall(TestSmoother(PETSC_FALSE));
  PetscCall(TestSmoother(PETSC_TRUE));
  PetscCall(TestSweepMatchesAIJ(PETSC_FALSE));
  PetscCall(TestSweepMatchesAIJ(PETSC_TRUE));
  PetscCall(TestCycleMatchesAIJ(PETSC_FALSE));
  PetscCall(TestCycleMatchesAIJ(PETSC_TRUE));
  PetscCall(TestSolve(PETSC_FALSE, PETSC_FALSE));
  PetscCall(TestSolve(PETSC_TRUE, PETSC_FALSE));
  PetscCall(TestSolve(PETSC_TRUE, PETSC_TRUE));
  PetscCall(TestKCycle());
  PetscCall(TestKCycleRatio());
  PetscCall(TestSolid(PETSC_FALSE));
  PetscCall(TestSolid(PETSC_TRUE));
  PetscCall(TestAdaptive());
  PetscCall(TestActivationTurned());
  PetscCall(TestNewCoefficients());
  PetscCall(TestLevelEvents()); /* last: it turns logging on */
  PetscCall(PetscFinalize());
  return 0;
}
