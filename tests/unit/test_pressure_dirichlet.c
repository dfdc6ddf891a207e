/* Dirichlet walls of the pressure projection (p = 0 at the wall face, 2 h beta on the boundary cell's
   diagonal; PffPressureSetDirichletWalls, -pressure_dirichlet_walls):
   - the operator: symmetric, no null space attached, A 1 = the Dirichlet diagonal (the closed part has
     zero row sums), diag(A) and PffPressureGetDiagonal include it, ptap and direct assembly agree, a
     second SetCoefficients gives the same A;
   - exactness: p = distance to the Dirichlet wall is reproduced exactly by the discrete operator (the
     one-sided wall gradient and the interior and level-boundary gradients are exact for it) on a
     uniform grid and on a grid graded along the wall normal, for a -x and a +z wall; CG + Jacobi on the
     nonzero-mean rhs recovers it to 1e-8;
   - positive definiteness with random beta in [1e-3, 1] and walls ymin,zmax from the option: CG
     converges to 1e-10 on a nonzero-mean rhs and its Lanczos estimate of the smallest eigenvalue is
     positive; the projection through PffPressureProject (gamg) converges, and its p agrees with a
     one-rank solve of the same problem (partition independence);
   - bad input: a Dirichlet wall on a periodic axis, an unknown wall name.
   Sample run: mpiexec -n 4 ./test_pressure_dirichlet     prints one line per check on rank 0. */
#include "pfftest.h"

#define NB 4
#define N0 8

typedef struct {
  PetscInt          betaCh, openCh, uCh, pCh;
  PetscBool         randomBeta;
  const PffTestCtx *t;
} Case;

static PetscReal Random01(const PffTestCtx *t, const PetscReal x[3], PetscInt comp, uint64_t purpose)
{
  return PffTestUniform01(PffTestPositionKey(t, x, comp, purpose));
}

static PetscReal BetaField(const PetscReal x[3], PetscInt comp, void *vctx)
{
  const Case *c = (const Case *)vctx;
  return c->randomBeta ? 1e-3 + (1 - 1e-3) * Random01(c->t, x, comp, 7) : 1.0;
}

static PetscReal RandomVelocity(const PetscReal x[3], PetscInt comp, void *vctx)
{
  const Case *c = (const Case *)vctx;
  if (PetscAbsReal(x[comp] - c->t->origin[comp]) < 1e-3 * c->t->h0) return 0; /* lower wall face */
  return 2 * Random01(c->t, x, comp, 11) - 1;
}

/* A closed unit box of NB^3 blocks of N0 cells; graded: level 0, 1, 2, 2 by block index along axis d,
   so that every level boundary is a d-face. */
static PetscErrorCode CreateGrid(MPI_Comm comm, PetscBool graded, PetscInt d, PffTestCtx *t)
{
  const PetscInt  nb[3] = {NB, NB, NB}, map[NB] = {0, 1, 2, 2};
  const PetscBool per[3]    = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};
  const PetscReal origin[3] = {0, 0, 0};
  PetscInt        request[NB * NB * NB];

  PetscFunctionBeginUser;
  for (PetscInt b = 0; b < NB * NB * NB; b++) {
    const PetscInt ijk[3] = {b % NB, (b / NB) % NB, b / (NB * NB)};
    request[b]            = graded ? map[ijk[d]] : 0;
  }
  PetscCall(PffTestCreateGridFromMap(comm, nb, per, origin, 1.0 / (NB * N0), N0, graded ? 3 : 1, request, t));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode CaseSetUp(PffTestCtx *t, PetscBool randomBeta, Case *c)
{
  PetscFunctionBeginUser;
  c->t          = t;
  c->randomBeta = randomBeta;
  PetscCall(
      PffTestAddPressureChannels(t->grid, BetaField, RandomVelocity, c, &c->betaCh, &c->openCh, &c->uCh, &c->pCh));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* For wall w (axis d = w / 2, upper side w % 2): pexact = distance of the cell centre to the wall plane,
   bexact = A_f = h^2 on the cells at the opposite (closed) wall and 0 elsewhere: the Neumann outflow
   of grad p = -/+ e_d through the closed wall, which is what A pexact must be. */
static PetscErrorCode FillExact(const PffTestCtx *t, PetscInt w, Vec pexact, Vec bexact)
{
  const PetscInt d = w / 2, upper = w % 2;
  PetscScalar   *p, *b;
  PetscInt64     rstart;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetCellNumbering(t->grid, -1, NULL, NULL, &rstart, NULL));
  PetscCall(VecGetArrayWrite(pexact, &p));
  PetscCall(VecGetArrayWrite(bexact, &b));
  for (PetscInt lb = 0; lb < t->nlocal; lb++) {
    PffBlockInfo info;
    PetscInt64   first;
    PetscCall(PffGridGetBlockInfo(t->grid, lb, &info));
    PetscCall(PffGridGetCellNumbering(t->grid, info.gid, &first, NULL, NULL, NULL));
    const PetscInt n = info.n;
    for (PetscInt k = 0; k < n; k++)
      for (PetscInt j = 0; j < n; j++)
        for (PetscInt i = 0; i < n; i++) {
          const PetscInt c[3] = {i, j, k}, q = (PetscInt)(first - rstart) + i + n * (j + n * k);
          PetscReal      x[3];
          PffTestSamplePosition(&info, PFF_CHANNEL_CELL, 0, c, x);
          const PetscBool opposite = upper ? (info.ijk[d] == 0 && c[d] == 0) : (info.ijk[d] == NB - 1 && c[d] == n - 1);
          p[q]                     = upper ? 1.0 - x[d] : x[d];
          b[q]                     = opposite ? info.h * info.h : 0.0;
        }
  }
  PetscCall(VecRestoreArrayWrite(bexact, &b));
  PetscCall(VecRestoreArrayWrite(pexact, &p));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Symmetry, no null space, A 1 = Dirichlet diagonal >= 0 with the expected sum, diag(A) = GetDiagonal. */
static PetscErrorCode CheckOperator(PffPressure ps, const char *what, PetscReal dirsum)
{
  Mat          A;
  MatNullSpace nsp;
  Vec          one, r, dd, diag, md;
  PetscBool    sym;
  PetscReal    err, an, sum, dmin, derr;
  MPI_Comm     comm;

  PetscFunctionBeginUser;
  PetscCall(PffPressureGetOperator(ps, &A));
  PetscCall(PffPressureGetDirichletDiagonal(ps, &dd));
  PetscCall(PffPressureGetDiagonal(ps, &diag));
  comm = PetscObjectComm((PetscObject)A);
  PetscCall(MatIsSymmetric(A, 1e-10, &sym));
  PetscCheck(sym, comm, PETSC_ERR_PLIB, "%s: A is not symmetric", what);
  PetscCall(MatGetNullSpace(A, &nsp));
  PetscCheck(nsp == NULL, comm, PETSC_ERR_PLIB, "%s: a null space is attached to A", what);
  PetscCall(MatCreateVecs(A, &one, &r));
  PetscCall(VecDuplicate(one, &md));
  PetscCall(VecSet(one, 1.0));
  PetscCall(MatMult(A, one, r));
  PetscCall(VecAXPY(r, -1.0, dd));
  PetscCall(VecNorm(r, NORM_INFINITY, &err));
  PetscCall(MatNorm(A, NORM_INFINITY, &an));
  PetscCheck(err <= 1e-12 * an, comm, PETSC_ERR_PLIB, "%s: |A 1 - dirichlet diagonal| = %g against |A| = %g", what,
             (double)err, (double)an);
  PetscCall(VecMin(dd, NULL, &dmin));
  PetscCall(VecSum(dd, &sum));
  PetscCheck(dmin >= 0 && (dirsum < 0 || PetscAbsReal(sum - dirsum) <= 1e-12 * dirsum), comm, PETSC_ERR_PLIB,
             "%s: Dirichlet diagonal min %g sum %g, expected >= 0 and sum %g", what, (double)dmin, (double)sum,
             (double)dirsum);
  PetscCall(MatGetDiagonal(A, md));
  PetscCall(VecAXPY(md, -1.0, diag));
  PetscCall(VecNorm(md, NORM_INFINITY, &derr));
  PetscCheck(derr <= 1e-14 * an, comm, PETSC_ERR_PLIB, "%s: PffPressureGetDiagonal differs from diag(A) by %g", what,
             (double)derr);
  PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                        "operator %-26s symmetric, no null space, |A 1 - D|/|A| = %.1e, sum D = %.6g\n", what,
                        (double)(err / an), (double)sum));
  PetscCall(VecDestroy(&one));
  PetscCall(VecDestroy(&r));
  PetscCall(VecDestroy(&md));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* CG + Jacobi from a zero guess on A x = b to rtol; returns the iterations and the smallest Lanczos
   eigenvalue estimate. */
static PetscErrorCode SolveCG(Mat A, Vec b, Vec x, PetscReal rtol, PetscInt *its, PetscReal *emin)
{
  KSP                ksp;
  PC                 pc;
  KSPConvergedReason reason;
  PetscReal          emax;

  PetscFunctionBeginUser;
  PetscCall(KSPCreate(PetscObjectComm((PetscObject)A), &ksp));
  PetscCall(KSPSetOperators(ksp, A, A));
  PetscCall(KSPSetType(ksp, KSPCG));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PCSetType(pc, PCJACOBI));
  PetscCall(KSPSetNormType(ksp, KSP_NORM_UNPRECONDITIONED));
  PetscCall(KSPSetTolerances(ksp, rtol, 1e-50, PETSC_DEFAULT, 20000));
  PetscCall(KSPSetComputeSingularValues(ksp, PETSC_TRUE));
  PetscCall(VecSet(x, 0.0));
  PetscCall(KSPSolve(ksp, b, x));
  PetscCall(KSPGetConvergedReason(ksp, &reason));
  PetscCall(KSPGetIterationNumber(ksp, its));
  PetscCheck(reason > 0, PetscObjectComm((PetscObject)A), PETSC_ERR_NOT_CONVERGED, "CG did not converge: %s",
             KSPConvergedReasons[reason]);
  PetscCall(KSPComputeExtremeSingularValues(ksp, &emax, emin));
  PetscCall(KSPDestroy(&ksp));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* p = distance to wall w is exact for A on a uniform grid and on a grid graded along the wall normal. */
static PetscErrorCode TestExact(void)
{
  const PetscInt walls[2] = {0, 5}; /* xmin, zmax */

  PetscFunctionBeginUser;
  for (PetscInt g = 0; g < 2; g++)
    for (PetscInt q = 0; q < 2; q++) {
      const PetscInt w = walls[q], d = w / 2;
      PetscBool      dw[6] = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE, PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};
      PffTestCtx     t;
      Case           c;
      PffPressure    ps;
      Mat            A, Acopy;
      Vec            pex, bex, ap, x;
      PetscReal      berr, bscale, perr, emin, mean, dnorm, anorm;
      PetscInt       its, nglob;
      char           what[64];

      PetscCall(CreateGrid(PETSC_COMM_WORLD, (PetscBool)g, d, &t));
      PetscCall(CaseSetUp(&t, PETSC_FALSE, &c));
      PetscCall(PffPressureCreate(t.grid, &ps));
      PetscCall(PffPressureSetFromOptions(ps));
      dw[w] = PETSC_TRUE;
      PetscCall(PffPressureSetDirichletWalls(ps, dw));
      PetscCall(PffPressureSetUp(ps));
      PetscCall(PffPressureSetCoefficients(ps, c.betaCh, c.openCh));
      PetscCall(PetscSNPrintf(what, sizeof(what), "%s wall %s", g ? "graded" : "uniform", w == 0 ? "xmin" : "zmax"));
      {
        /* the wall layer is at level 0 (xmin: map[0]) or 2 (zmax: map[NB - 1]) on the graded grid:
           (1 / h)^2 cells of 2 h each */
        const PetscReal hw = t.h0 * (g ? (w % 2 ? 4.0 : 1.0) : 1.0);
        PetscCall(CheckOperator(ps, what, 2.0 / hw));
      }
      /* a second assembly gives the same A (the diagonal terms are not accumulated) */
      PetscCall(PffPressureGetOperator(ps, &A));
      PetscCall(MatNorm(A, NORM_INFINITY, &anorm));
      PetscCall(MatDuplicate(A, MAT_COPY_VALUES, &Acopy));
      PetscCall(PffPressureSetCoefficients(ps, c.betaCh, c.openCh));
      PetscCall(PffPressureGetOperator(ps, &A));
      PetscCall(MatAXPY(Acopy, -1.0, A, SAME_NONZERO_PATTERN));
      PetscCall(MatNorm(Acopy, NORM_INFINITY, &dnorm));
      /* off-rank contributions of MatPtAP arrive in any order: equal up to rounding */
      PetscCheck(dnorm <= 1e-14 * anorm, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
                 "%s: a second SetCoefficients changed A by %g", what, (double)dnorm);
      PetscCall(MatDestroy(&Acopy));

      PetscCall(MatCreateVecs(A, &pex, &bex));
      PetscCall(VecDuplicate(pex, &ap));
      PetscCall(VecDuplicate(pex, &x));
      PetscCall(FillExact(&t, w, pex, bex));
      PetscCall(MatMult(A, pex, ap));
      PetscCall(VecAXPY(ap, -1.0, bex));
      PetscCall(VecNorm(ap, NORM_INFINITY, &berr));
      PetscCall(VecNorm(bex, NORM_INFINITY, &bscale));
      PetscCheck(berr <= 1e-12 * bscale, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
                 "%s: A p_exact differs from the exact rhs by %g (scale %g)", what, (double)berr, (double)bscale);
      PetscCall(VecSum(bex, &mean));
      PetscCall(VecGetSize(bex, &nglob));
      PetscCall(SolveCG(A, bex, x, 1e-12, &its, &emin));
      PetscCall(VecAXPY(x, -1.0, pex));
      PetscCall(VecNorm(x, NORM_INFINITY, &perr));
      PetscCheck(perr <= 1e-8, PETSC_COMM_WORLD, PETSC_ERR_PLIB, "%s: CG solution differs from p_exact by %g", what,
                 (double)perr);
      PetscCheck(emin > 0, PETSC_COMM_WORLD, PETSC_ERR_PLIB, "%s: smallest eigenvalue estimate %g", what, (double)emin);
      PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                            "exact    %-26s |A p* - b|/|b| = %.1e  mean b %.2e  CG its %4d  |p - p*| = %.1e\n", what,
                            (double)(berr / bscale), (double)(mean / (PetscReal)nglob), (int)its, (double)perr));
      PetscCall(VecDestroy(&pex));
      PetscCall(VecDestroy(&bex));
      PetscCall(VecDestroy(&ap));
      PetscCall(VecDestroy(&x));
      PetscCall(PffPressureDestroy(&ps));
      PetscCall(PffGridDestroy(&t.grid));
    }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Random beta, walls ymin,zmax from the option, graded along z; out = {its, rnorm, sum V p, sum V p^2}. */
static PetscErrorCode RunRandom(MPI_Comm comm, const char *assembly, PetscBool check, PetscReal out[4])
{
  PffTestCtx       t;
  Case             c;
  PffPressure      ps;
  PffPressureStats st;
  KSP              ksp;
  PetscBool        walls[6];
  PetscReal        s[2] = {0, 0};

  PetscFunctionBeginUser;
  PetscCall(CreateGrid(comm, PETSC_TRUE, 2, &t));
  PetscCall(CaseSetUp(&t, PETSC_TRUE, &c));
  PetscCall(PetscOptionsSetValue(NULL, "-pressure_dirichlet_walls", "ymin,zmax"));
  PetscCall(PetscOptionsSetValue(NULL, "-pressure_assembly", assembly));
  PetscCall(PffPressureCreate(t.grid, &ps));
  PetscCall(PffPressureSetFromOptions(ps));
  PetscCall(PetscOptionsClearValue(NULL, "-pressure_dirichlet_walls"));
  PetscCall(PetscOptionsClearValue(NULL, "-pressure_assembly"));
  PetscCall(PffPressureGetDirichletWalls(ps, walls));
  PetscCheck(!walls[0] && !walls[1] && walls[2] && !walls[3] && !walls[4] && walls[5], comm, PETSC_ERR_PLIB,
             "-pressure_dirichlet_walls ymin,zmax was not parsed");
  PetscCall(PffPressureSetUp(ps));
  PetscCall(PffPressureSetCoefficients(ps, c.betaCh, c.openCh));
  if (check) {
    Mat       A;
    Vec       b, x;
    PetscReal emin;
    PetscInt  its;
    PetscCall(CheckOperator(ps, "graded random beta", -1));
    PetscCall(PffPressureGetOperator(ps, &A));
    PetscCall(MatCreateVecs(A, &x, &b));
    PetscCall(VecSet(b, 1.0)); /* nonzero mean: solvable only because A is definite */
    PetscCall(SolveCG(A, b, x, 1e-10, &its, &emin));
    PetscCheck(emin > 0, comm, PETSC_ERR_PLIB, "random beta: smallest eigenvalue estimate %g", (double)emin);
    PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                          "definite graded random beta        CG its %4d to 1e-10, lambda_min ~ %.3e\n", (int)its,
                          (double)emin));
    PetscCall(VecDestroy(&x));
    PetscCall(VecDestroy(&b));
  }
  PetscCall(PffPressureGetKSP(ps, &ksp));
  PetscCall(KSPSetTolerances(ksp, 1e-10, 1e-50, PETSC_DEFAULT, 10000));
  PetscCall(PffPressureProject(ps, c.uCh, 1.0, -1, c.pCh, &st));
  PetscCheck(st.reason > 0 && st.rnorm <= 1.01e-10, comm, PETSC_ERR_NOT_CONVERGED,
             "projection with Dirichlet walls: %s, relative residual %g", KSPConvergedReasons[st.reason],
             (double)st.rnorm);
  for (PetscInt lb = 0; lb < t.nlocal; lb++) {
    PffBlockInfo info;
    float       *p;
    PetscCall(PffGridGetBlockInfo(t.grid, lb, &info));
    PetscCall(PffGridGetBlockData(t.grid, c.pCh, lb, 0, &p));
    for (PetscInt q = 0; q < info.n * info.n * info.n; q++) {
      s[0] += info.h * info.h * info.h * p[q];
      s[1] += info.h * info.h * info.h * p[q] * p[q];
    }
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, s, 2, MPIU_REAL, MPIU_SUM, comm));
  out[0] = (PetscReal)st.its;
  out[1] = st.rnorm;
  out[2] = s[0];
  out[3] = s[1];
  PetscCall(PffPressureDestroy(&ps));
  PetscCall(PffGridDestroy(&t.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode TestRandom(void)
{
  PetscMPIInt rank;
  MPI_Comm    self;
  PetscReal   w[4], d[4], s[4] = {0};

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(PETSC_COMM_WORLD, &rank));
  PetscCallMPI(MPI_Comm_split(PETSC_COMM_WORLD, rank == 0 ? 0 : MPI_UNDEFINED, 0, &self));
  PetscCall(RunRandom(PETSC_COMM_WORLD, "ptap", PETSC_TRUE, w));
  PetscCall(RunRandom(PETSC_COMM_WORLD, "direct", PETSC_FALSE, d));
  if (rank == 0) PetscCall(RunRandom(self, "ptap", PETSC_FALSE, s));
  PetscCallMPI(MPI_Bcast(s, 4, MPIU_REAL, 0, PETSC_COMM_WORLD));
  const PetscReal dp = PetscAbsReal(w[2] - s[2]) / PetscAbsReal(s[2]), dq = PetscAbsReal(w[3] - s[3]) / s[3];
  const PetscReal da = PetscAbsReal(w[3] - d[3]) / d[3];
  PetscCall(
      PetscPrintf(PETSC_COMM_WORLD,
                  "project  graded random beta        its %4d  rel. residual %.1e  sum Vp %.6e  sum Vp^2 %.6e  vs "
                  "1 rank %.0e %.0e  vs direct %.0e\n",
                  (int)w[0], (double)w[1], (double)w[2], (double)w[3], (double)dp, (double)dq, (double)da));
  PetscCheck(dp <= 1e-6 && dq <= 1e-6, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
             "rank count changes the Dirichlet solution: sum V p %.9e vs %.9e, sum V p^2 %.9e vs %.9e", (double)w[2],
             (double)s[2], (double)w[3], (double)s[3]);
  PetscCheck(da <= 1e-6, PETSC_COMM_WORLD, PETSC_ERR_PLIB, "ptap and direct assembly disagree: %.9e vs %.9e",
             (double)w[3], (double)d[3]);
  if (self != MPI_COMM_NULL) PetscCallMPI(MPI_Comm_free(&self));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A Dirichlet wall on a periodic axis and an unknown wall name are errors (caught, not printed). */
static PetscErrorCode TestErrors(void)
{
  const PetscInt  nb[3]     = {2, 2, 2};
  const PetscBool per[3]    = {PETSC_FALSE, PETSC_FALSE, PETSC_TRUE};
  const PetscReal origin[3] = {0, 0, 0};
  const PetscBool walls[6]  = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE, PETSC_FALSE, PETSC_FALSE, PETSC_TRUE};
  PffTestCtx      t;
  PffPressure     ps;
  PetscErrorCode  e1, e2;

  PetscFunctionBeginUser;
  PetscCall(PffTestCreateGrid(PETSC_COMM_WORLD, nb, per, origin, 1.0 / 16, 8, 1, 0, 0, 3, &t));
  PetscCall(PffPressureCreate(t.grid, &ps));
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  e1 = PffPressureSetDirichletWalls(ps, walls);
  PetscCall(PetscOptionsSetValue(NULL, "-pressure_dirichlet_walls", "zmax,top"));
  e2 = PffPressureSetFromOptions(ps);
  PetscCall(PetscPopErrorHandler());
  PetscCall(PetscOptionsClearValue(NULL, "-pressure_dirichlet_walls"));
  PetscCheck(e1 == PETSC_ERR_ARG_INCOMP, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
             "a Dirichlet wall on a periodic axis gave error %d, expected %d", (int)e1, (int)PETSC_ERR_ARG_INCOMP);
  PetscCheck(e2 == PETSC_ERR_ARG_UNKNOWN_TYPE, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
             "an unknown wall name gave error %d, expected %d", (int)e2, (int)PETSC_ERR_ARG_UNKNOWN_TYPE);
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "errors   periodic axis and unknown wall name rejected\n"));
  PetscCall(PffPressureDestroy(&ps));
  PetscCall(PffGridDestroy(&t.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  PetscCall(PffInitializePackage());
  PetscCall(TestExact());
  PetscCall(TestRandom());
  PetscCall(TestErrors());
  PetscCall(PetscFinalize());
  return 0;
}
