/* The pressure projection (PF-FLIP Eq. 8-10) on uniform and graded multi-level grids:
   - the operator: A p = -h^3 lap p for a periodic sine (second order), A symmetric (uniform, graded,
     random beta), A 1 = 0, and V D (beta G p) = -A p (the divergence is the adjoint of the gradient);
   - the projection of a random u* with a dense sphere (beta 1 and 1e-3), closed and periodic in x,z,
     with PC gamg, hypre, bjacobi and jacobi: max |D u| drops by 1e-7 or more, and p and u agree with a
     solve of the same problem on one rank (partition independence);
   - hydrostatic balance for layered density (exact, u = 0) on a uniform and a y-graded grid.
   Sample run: mpiexec -n 4 ./test_pressure            prints one line per check on rank 0.
   Benchmark:  mpiexec -n 2 ./test_pressure -bench 64  one 64^3 bubbly projection per PC and assembly
               (PCs pffmg, gamg, hypre, bjacobi, jacobi; -bench_npcs k runs the first k). */
#include "pfftest.h"

typedef struct {
  PetscInt          uCh, betaCh, openCh, pCh, cdivCh;
  PetscReal         centre[3], radius, dt;
  PetscInt          kind; /* beta field: 0 = 1, 1 = sphere (1e-3 inside), 2 = random in [1e-3, 1], 3 = layered 1/rho */
  const PffTestCtx *t;
} Case;

static PetscBool OnLowerWall(const PffTestCtx *t, const PetscReal x[3], PetscInt comp)
{
  return (PetscBool)(!t->periodic[comp] && PetscAbsReal(x[comp] - t->origin[comp]) < 1e-3 * t->h0);
}

static PetscReal BetaField(const PetscReal x[3], PetscInt comp, void *vctx)
{
  const Case *c = (const Case *)vctx;
  switch (c->kind) {
  case 1: {
    PetscReal r2 = 0;
    for (int a = 0; a < 3; a++) r2 += PetscSqr(x[a] - c->centre[a]);
    return r2 < PetscSqr(c->radius) ? 1e-3 : 1.0;
  }
  case 2:
    return 1e-3 + (1 - 1e-3) * (PetscReal)(PffTestPositionKey(c->t, x, comp, 7) >> 11) / 9007199254740992.0;
  case 3:
    return x[1] < 0.5 ? 1e-3 : 1.0;
  case 4: /* water (rho 1000) with 16 air bubbles of radius 0.06 L */
    for (uint64_t b = 0; b < 16; b++) {
      PetscReal r2 = 0;
      for (int a = 0; a < 3; a++) {
        const PetscReal L = c->t->blen * (PetscReal)c->t->nb[a];
        r2 += PetscSqr(x[a] - c->t->origin[a] -
                       L * (0.1 + 0.8 * (PetscReal)(PffTestKey(3, b, (uint64_t)a, 0) % 1000) / 1000));
      }
      if (r2 < PetscSqr(0.06 * c->t->blen * (PetscReal)c->t->nb[0])) return 1.0;
    }
    return 1e-3;
  default:
    return 1.0;
  }
}

static PetscReal RandomVelocity(const PetscReal x[3], PetscInt comp, void *vctx)
{
  const Case *c = (const Case *)vctx;
  if (OnLowerWall(c->t, x, comp)) return 0;
  return (PetscReal)(PffTestPositionKey(c->t, x, comp, 11) >> 11) / 9007199254740992.0 - 0.5;
}

static PetscReal Gravity(const PetscReal x[3], PetscInt comp, void *vctx)
{
  const Case *c = (const Case *)vctx;
  return comp == 1 && !OnLowerWall(c->t, x, comp) ? -9.81 * c->dt : 0.0;
}

static PetscReal GravityNoise(const PetscReal x[3], PetscInt comp, void *vctx)
{
  return Gravity(x, comp, vctx) + 0.1 * RandomVelocity(x, comp, vctx);
}

/* Adds the channels and fills beta, open (all 1), p = 0, c_div = 0. */
static PetscErrorCode CaseSetUp(PffTestCtx *t, PetscInt kind, Case *c)
{
  PetscFunctionBeginUser;
  c->t    = t;
  c->kind = kind;
  c->dt   = 0.01;
  for (int a = 0; a < 3; a++) c->centre[a] = t->origin[a] + 0.37 * t->blen * (PetscReal)t->nb[a];
  c->radius = 0.22 * t->blen * (PetscReal)t->nb[0];
  PetscCall(PffGridAddChannel(t->grid, "u", PFF_CHANNEL_FACE, 1, &c->uCh));
  PetscCall(PffGridAddChannel(t->grid, "beta", PFF_CHANNEL_FACE, 1, &c->betaCh));
  PetscCall(PffGridAddChannel(t->grid, "open", PFF_CHANNEL_FACE, 1, &c->openCh));
  PetscCall(PffGridAddChannel(t->grid, "p", PFF_CHANNEL_CELL, 1, &c->pCh));
  PetscCall(PffGridAddChannel(t->grid, "cdiv", PFF_CHANNEL_CELL, 1, &c->cdivCh));
  PetscCall(PffGridFillChannel(t->grid, c->betaCh, BetaField, c));
  PetscCall(PffGridFillChannel(t->grid, c->openCh, PffTestOne, c));
  PetscCall(PffGridFillChannel(t->grid, c->pCh, PffTestZero, c));
  PetscCall(PffGridFillChannel(t->grid, c->cdivCh, PffTestZero, c));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Vec in the global cell numbering from a function of the cell centre. */
static PetscErrorCode FillCellVec(const PffTestCtx *t, PetscReal (*fn)(const PetscReal[3]), Vec v)
{
  PetscScalar *a;
  PetscInt64   rstart;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetCellNumbering(t->grid, -1, NULL, NULL, &rstart, NULL));
  PetscCall(VecGetArrayWrite(v, &a));
  for (PetscInt lb = 0; lb < t->nlocal; lb++) {
    PffBlockInfo info;
    PetscInt64   first;
    PetscCall(PffGridGetBlockInfo(t->grid, lb, &info));
    PetscCall(PffGridGetCellNumbering(t->grid, info.gid, &first, NULL, NULL, NULL));
    const PetscInt n = info.n;
    for (PetscInt k = 0; k < n; k++)
      for (PetscInt j = 0; j < n; j++)
        for (PetscInt i = 0; i < n; i++) {
          const PetscInt c[3] = {i, j, k};
          PetscReal      x[3];
          PffTestSamplePosition(&info, PFF_CHANNEL_CELL, 0, c, x);
          a[first - rstart + i + n * (j + n * k)] = fn ? fn(x) : info.h * info.h * info.h;
        }
  }
  PetscCall(VecRestoreArrayWrite(v, &a));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscReal SineP(const PetscReal x[3])
{
  return PetscSinReal(2 * PETSC_PI * x[0]) * PetscSinReal(2 * PETSC_PI * x[1]) * PetscSinReal(2 * PETSC_PI * x[2]);
}

static PetscErrorCode CheckSymmetric(Mat A, const char *what)
{
  PetscBool sym;
  Vec       one, r;
  PetscReal rn, an;

  PetscFunctionBeginUser;
  PetscCall(MatIsSymmetric(A, 1e-10, &sym));
  PetscCheck(sym, PetscObjectComm((PetscObject)A), PETSC_ERR_PLIB, "%s: A is not symmetric", what);
  PetscCall(MatCreateVecs(A, &one, &r));
  PetscCall(VecSet(one, 1.0));
  PetscCall(MatMult(A, one, r));
  PetscCall(VecNorm(r, NORM_INFINITY, &rn));
  PetscCall(MatNorm(A, NORM_INFINITY, &an));
  PetscCheck(rn <= 1e-12 * an, PetscObjectComm((PetscObject)A), PETSC_ERR_PLIB, "%s: |A 1| = %g against |A| = %g", what,
             (double)rn, (double)an);
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "operator %-28s symmetric, |A 1|/|A| = %.1e\n", what, (double)(rn / an)));
  PetscCall(VecDestroy(&one));
  PetscCall(VecDestroy(&r));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The 7-point limit, symmetry and row sums, and V D (beta G p) = -A p. */
static PetscErrorCode TestOperator(void)
{
  const PetscInt  nb[3]       = {4, 4, 4};
  const PetscBool allper[3]   = {PETSC_TRUE, PETSC_TRUE, PETSC_TRUE};
  const PetscBool closed[3]   = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};
  const PetscReal origin[3]   = {0, 0, 0};
  const PetscReal h0          = 1.0 / 32;
  const char     *names[3][2] = {{"uniform periodic beta=1", "uniform periodic random beta"},
                                 {"graded closed beta=1", "graded closed random beta"},
                                 {"graded periodic beta=1", "graded periodic random beta"}};

  PetscFunctionBeginUser;
  for (PetscInt g = 0; g < 3; g++)
    for (PetscInt kind = 0; kind < 2; kind++) {
      PffTestCtx  t;
      Case        c;
      PffPressure ps;
      Mat         A;
      PetscCall(PffTestCreateGrid(PETSC_COMM_WORLD, nb, g == 1 ? closed : allper, origin, h0, 8, 3, g == 0 ? 0 : -1, 0,
                                  17 + (uint64_t)g, &t));
      PetscCall(CaseSetUp(&t, kind == 0 ? 0 : 2, &c));
      PetscCall(PffPressureCreate(t.grid, &ps));
      PetscCall(PffPressureSetFromOptions(ps));
      PetscCall(PffPressureSetUp(ps));
      PetscCall(PffPressureSetCoefficients(ps, c.betaCh, c.openCh));
      PetscCall(PffPressureGetOperator(ps, &A));
      PetscCall(CheckSymmetric(A, names[g][kind]));
      if (g == 0 && kind == 0) { /* A p = -h^3 lap p = 12 pi^2 h^3 p */
        Vec       p, ap, ref;
        PetscReal err, scale;
        PetscCall(MatCreateVecs(A, &p, &ap));
        PetscCall(VecDuplicate(p, &ref));
        PetscCall(FillCellVec(&t, SineP, p));
        PetscCall(MatMult(A, p, ap));
        PetscCall(VecCopy(p, ref));
        PetscCall(VecScale(ref, 12 * PETSC_PI * PETSC_PI * h0 * h0 * h0));
        PetscCall(VecNorm(ref, NORM_INFINITY, &scale));
        PetscCall(VecAXPY(ref, -1.0, ap));
        PetscCall(VecNorm(ref, NORM_INFINITY, &err));
        /* the 7-point symbol 4 sin^2(pi h)/h^2 per axis against (2 pi)^2: relative (2 pi h)^2 / 12 = 3.2e-3 */
        PetscCheck(err <= 4e-3 * scale, PETSC_COMM_WORLD, PETSC_ERR_PLIB, "A p != -h^3 lap p: max error %g against %g",
                   (double)err, (double)scale);
        PetscCall(PetscPrintf(PETSC_COMM_WORLD, "operator A sin = -h^3 lap sin         relative error %.2e\n",
                              (double)(err / scale)));
        PetscCall(VecDestroy(&p));
        PetscCall(VecDestroy(&ap));
        PetscCall(VecDestroy(&ref));
      }
      if (kind == 1) { /* V D (beta G p) = -A p: project u* with dt = 1, v = u* - u = beta G p */
        PffPressureStats st;
        KSP              ksp;
        Vec              p, ap, vol;
        PetscReal        dmax, ref;
        PetscInt         vCh;
        PetscCall(PffGridFillChannel(t.grid, c.uCh, RandomVelocity, &c));
        PetscCall(PffGridAddChannel(t.grid, "v", PFF_CHANNEL_FACE, 1, &vCh));
        PetscCall(PffGridFillChannel(t.grid, vCh, RandomVelocity, &c));
        PetscCall(PffPressureProject(ps, c.uCh, 1.0, -1, c.pCh, &st));
        for (PetscInt lb = 0; lb < t.nlocal; lb++)
          for (PetscInt d = 0; d < 3; d++) {
            float       *u, *v;
            PffBlockInfo info;
            PetscCall(PffGridGetBlockInfo(t.grid, lb, &info));
            PetscCall(PffGridGetBlockData(t.grid, c.uCh, lb, d, &u));
            PetscCall(PffGridGetBlockData(t.grid, vCh, lb, d, &v));
            for (PetscInt q = 0; q < info.n * info.n * info.n; q++) v[q] -= u[q];
          }
        PetscCall(PffPressureMaxDivergence(ps, vCh, &dmax));
        PetscCall(PffPressureGetKSP(ps, &ksp));
        PetscCall(KSPGetSolution(ksp, &p));
        PetscCall(MatCreateVecs(A, NULL, &ap));
        PetscCall(VecDuplicate(ap, &vol));
        PetscCall(FillCellVec(&t, NULL, vol));
        PetscCall(MatMult(A, p, ap));
        PetscCall(VecPointwiseDivide(ap, ap, vol));
        PetscCall(VecNorm(ap, NORM_INFINITY, &ref));
        /* v = u* - u went through float storage: a few ulps of |u| / h per cell */
        PetscCheck(PetscAbsReal(dmax - ref) <= 1e-5 * ref, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
                   "%s: max |D (beta G p)| = %g but max |A p / V| = %g", names[g][kind], (double)dmax, (double)ref);
        PetscCall(PetscPrintf(PETSC_COMM_WORLD, "adjoint  %-28s max|D beta G p| %.6e = max|A p/V| %.6e\n",
                              names[g][kind], (double)dmax, (double)ref));
        PetscCall(VecDestroy(&ap));
        PetscCall(VecDestroy(&vol));
      }
      PetscCall(PffPressureDestroy(&ps));
      PetscCall(PffGridDestroy(&t.grid));
    }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Sum over owned values of channel ch of f(value) * weight, reduced on the grid's communicator:
   mode 0: sum of V p, 1: sum of V, 2: sum of V (p - mean)^2 (needs mean), 3: sum of u^2 over faces,
   4: max |u| over faces. */
static PetscErrorCode ChannelReduce(const PffTestCtx *t, PetscInt ch, PetscInt mode, PetscReal mean, PetscReal *out)
{
  PetscReal s = 0;

  PetscFunctionBeginUser;
  for (PetscInt lb = 0; lb < t->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(t->grid, lb, &info));
    const PetscInt  nc = info.n * info.n * info.n;
    const PetscReal V  = info.h * info.h * info.h;
    for (PetscInt d = 0; d < (mode >= 3 ? 3 : 1); d++) {
      float *a;
      PetscCall(PffGridGetBlockData(t->grid, ch, lb, d, &a));
      for (PetscInt q = 0; q < nc; q++) switch (mode) {
        case 0:
          s += V * a[q];
          break;
        case 1:
          s += V;
          break;
        case 2:
          s += V * PetscSqr(a[q] - mean);
          break;
        case 3:
          s += PetscSqr((PetscReal)a[q]);
          break;
        default:
          s = PetscMax(s, PetscAbsReal(a[q]));
          break;
        }
    }
  }
  PetscCall(MPIU_Allreduce(&s, out, 1, MPIU_REAL, mode == 4 ? MPIU_MAX : MPIU_SUM, t->comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A pressure on the case's grid and coefficients, solving to rtol, with PC pctype (NULL: the default). */
static PetscErrorCode CasePressure(const PffTestCtx *t, const Case *c, PetscReal rtol, PCType pctype, PffPressure *ps)
{
  KSP ksp;

  PetscFunctionBeginUser;
  PetscCall(PffPressureCreate(t->grid, ps));
  PetscCall(PffPressureSetFromOptions(*ps));
  PetscCall(PffPressureGetKSP(*ps, &ksp));
  PetscCall(KSPSetTolerances(ksp, rtol, 1e-50, PETSC_DEFAULT, 10000));
  if (pctype) {
    PC pc;
    PetscCall(KSPGetPC(ksp, &pc));
    PetscCall(PCSetType(pc, pctype));
  }
  PetscCall(PffPressureSetUp(*ps));
  PetscCall(PffPressureSetCoefficients(*ps, c->betaCh, c->openCh));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* out = {its, divBefore, divAfter (double), divAfter (float channel), |p - mean|_V, sum u^2} */
static PetscErrorCode RunProjection(MPI_Comm comm, PetscBool graded, PetscBool perxz, PCType pctype, PetscReal out[6])
{
  const PetscInt   nbU[3] = {3, 3, 3}, nbG[3] = {4, 4, 4};
  const PetscBool  per[3]    = {perxz, PETSC_FALSE, perxz};
  const PetscReal  origin[3] = {0, 0, 0};
  PffTestCtx       t;
  Case             c;
  PffPressure      ps;
  PffPressureStats st;
  PetscReal        vp, v, var;

  PetscFunctionBeginUser;
  PetscCall(PffTestCreateGrid(comm, graded ? nbG : nbU, per, origin, graded ? 1.0 / 32 : 1.0 / 24, 8, 3,
                              graded ? -1 : 0, 0, 5, &t));
  PetscCall(CaseSetUp(&t, 1, &c));
  PetscCall(PffGridFillChannel(t.grid, c.uCh, RandomVelocity, &c));
  PetscCall(CasePressure(&t, &c, 1e-10, pctype, &ps));
  PetscCall(PffPressureSetMonitorDivergence(ps, PETSC_TRUE)); /* off by default: divBefore/divAfter would be -1 */
  PetscCall(PffPressureProject(ps, c.uCh, c.dt, c.cdivCh, c.pCh, &st));
  PetscCheck(st.reason > 0, comm, PETSC_ERR_NOT_CONVERGED, "projection with %s did not converge: %s", pctype,
             KSPConvergedReasons[st.reason]);
  out[0] = (PetscReal)st.its;
  out[1] = st.divBefore;
  out[2] = st.divAfter;
  PetscCall(PffPressureMaxDivergence(ps, c.uCh, &out[3]));
  PetscCall(ChannelReduce(&t, c.pCh, 0, 0, &vp));
  PetscCall(ChannelReduce(&t, c.pCh, 1, 0, &v));
  PetscCall(ChannelReduce(&t, c.pCh, 2, vp / v, &var));
  out[4] = PetscSqrtReal(var);
  PetscCall(ChannelReduce(&t, c.uCh, 3, 0, &out[5]));
  PetscCall(PffPressureDestroy(&ps));
  PetscCall(PffGridDestroy(&t.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode TestProjection(void)
{
  const PCType pcs[4] = {PCGAMG, PCHYPRE, PCBJACOBI, PCJACOBI};
  PetscMPIInt  rank;
  MPI_Comm     self;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(PETSC_COMM_WORLD, &rank));
  PetscCallMPI(MPI_Comm_split(PETSC_COMM_WORLD, rank == 0 ? 0 : MPI_UNDEFINED, 0, &self));
  for (PetscInt graded = 0; graded < 2; graded++)
    for (PetscInt perxz = 0; perxz < 2; perxz++)
      for (PetscInt k = 0; k < 4; k++) {
        PetscReal w[6], s[6] = {0};
        PetscCall(RunProjection(PETSC_COMM_WORLD, (PetscBool)graded, (PetscBool)perxz, pcs[k], w));
        if (rank == 0) PetscCall(RunProjection(self, (PetscBool)graded, (PetscBool)perxz, pcs[k], s));
        PetscCallMPI(MPI_Bcast(s, 6, MPIU_REAL, 0, PETSC_COMM_WORLD));
        const PetscReal dp = PetscAbsReal(w[4] - s[4]) / s[4], du = PetscAbsReal(w[5] - s[5]) / s[5];
        PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                              "project %-7s %-8s %-9s its %4d  max|Du| %.3e -> %.2e (float u %.2e)  |p| %.6e "
                              "sum u^2 %.6e  vs 1 rank %.0e %.0e\n",
                              graded ? "graded" : "uniform", perxz ? "per x,z" : "closed", pcs[k], (int)w[0],
                              (double)w[1], (double)w[2], (double)w[3], (double)w[4], (double)w[5], (double)dp,
                              (double)du));
        PetscCheck(w[1] > 0 && w[2] >= 0, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
                   "%s: the divergence was not measured (%g, %g)", pcs[k], (double)w[1], (double)w[2]);
        PetscCheck(w[2] <= 1e-7 * w[1], PETSC_COMM_WORLD, PETSC_ERR_PLIB, "%s: max |D u| %g -> %g, not 1e-7 smaller",
                   pcs[k], (double)w[1], (double)w[2]);
        PetscCheck(w[3] <= 1e-5 * w[1], PETSC_COMM_WORLD, PETSC_ERR_PLIB,
                   "%s: max |D u| of the stored (float) u %g against %g before", pcs[k], (double)w[3], (double)w[1]);
        PetscCheck(dp <= 1e-6 && du <= 1e-6, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
                   "%s: rank count changes the result: |p| %.9e vs %.9e, sum u^2 %.9e vs %.9e", pcs[k], (double)w[4],
                   (double)s[4], (double)w[5], (double)s[5]);
      }
  if (self != MPI_COMM_NULL) PetscCallMPI(MPI_Comm_free(&self));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* PffPressureProjectSource (u* = 0, the volume correction's displacement) against PffPressureProject of a zeroed
   velocity, with a random c_div: the same velocity and pressure, although the channel holds a random velocity when
   ProjectSource is called (it must not be read). */
static PetscErrorCode TestProjectSource(void)
{
  const PetscInt  nbG[3]    = {4, 4, 4};
  const PetscBool per[3]    = {PETSC_TRUE, PETSC_FALSE, PETSC_TRUE};
  const PetscReal origin[3] = {0, 0, 0};

  PetscFunctionBeginUser;
  for (PetscInt graded = 0; graded < 2; graded++) {
    PffTestCtx       t;
    Case             c;
    PffPressure      ps;
    PffPressureStats st[2];
    PetscReal        su[2], sp[2];
    PetscCall(PffTestCreateGrid(PETSC_COMM_WORLD, nbG, per, origin, 1.0 / 32, 8, 3, graded ? -1 : 0, 0, 5, &t));
    PetscCall(CaseSetUp(&t, 1, &c));
    PetscCall(PffGridFillChannel(t.grid, c.cdivCh, RandomVelocity, &c));
    PetscCall(CasePressure(&t, &c, 1e-10, NULL, &ps));
    for (PetscInt k = 0; k < 2; k++) {
      PetscCall(PffGridFillChannel(t.grid, c.uCh, k == 0 ? RandomVelocity : PffTestZero, &c));
      PetscCall(PffGridFillChannel(t.grid, c.pCh, PffTestZero, &c));
      if (k == 0)
        PetscCall(PffPressureProjectSource(ps, c.uCh, c.dt, c.cdivCh, c.pCh, &st[k]));
      else
        PetscCall(PffPressureProject(ps, c.uCh, c.dt, c.cdivCh, c.pCh, &st[k]));
      PetscCall(ChannelReduce(&t, c.uCh, 3, 0, &su[k]));
      PetscCall(ChannelReduce(&t, c.pCh, 2, 0, &sp[k]));
    }
    PetscCall(PetscPrintf(PETSC_COMM_WORLD, "source   %-7s its %d / %d  sum u^2 %.9e / %.9e  sum V p^2 %.9e / %.9e\n",
                          graded ? "graded" : "uniform", (int)st[0].its, (int)st[1].its, (double)su[0], (double)su[1],
                          (double)sp[0], (double)sp[1]));
    PetscCheck(su[1] > 0 && st[0].its == st[1].its && PetscAbsReal(su[0] - su[1]) <= 1e-12 * su[1] &&
                   PetscAbsReal(sp[0] - sp[1]) <= 1e-12 * sp[1],
               PETSC_COMM_WORLD, PETSC_ERR_PLIB, "ProjectSource differs from Project of u* = 0");
    PetscCall(PffPressureDestroy(&ps));
    PetscCall(PffGridDestroy(&t.grid));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Hydrostatic balance: beta = 1/rho layered (rho = 1000 below y = 0.5), u* = dt g: u = 0. The graded
   grid refines along y only, so every level boundary is a y-face and the balance stays exact (a level
   boundary across x or z puts fine and coarse cells at different heights on one face: not exact). */
static PetscErrorCode TestHydrostatic(void)
{
  PetscFunctionBeginUser;
  for (PetscInt graded = 0; graded < 2; graded++) {
    const PetscInt   nb[3] = {2, 4, 2}, n0 = 8, map[4] = {2, 1, 0, 0};
    const PetscInt   cells[3]  = {nb[0] * n0, nb[1] * n0, nb[2] * n0};
    const PetscBool  per[3]    = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};
    const PetscReal  origin[3] = {0, 0, 0};
    PetscInt         request[16];
    PffTestCtx       t = {0};
    Case             c;
    PffPressure      ps;
    PffPressureStats st;
    PetscReal        umax;

    for (PetscInt b = 0; b < 16; b++) request[b] = graded ? map[(b / nb[0]) % nb[1]] : 0;
    PetscCall(PffGridCreate(PETSC_COMM_WORLD, &t.grid));
    PetscCall(PffGridSetCells(t.grid, cells));
    PetscCall(PffGridSetBlockSize(t.grid, n0));
    PetscCall(PffGridSetLevels(t.grid, graded ? 3 : 1));
    PetscCall(PffGridSetDomain(t.grid, origin, 1.0 / 32));
    PetscCall(PffGridSetPeriodic(t.grid, per));
    PetscCall(PffGridSetRefinementMap(t.grid, request));
    PetscCall(PffGridSetUp(t.grid));
    t.comm = PETSC_COMM_WORLD;
    PetscCall(PffGridGetRaster(t.grid, t.nb, &t.level, &t.owner));
    PetscCall(PffGridGetSizes(t.grid, NULL, NULL, t.origin, &t.h0, t.periodic));
    PetscCall(PffGridGetLocalBlocks(t.grid, &t.nlocal));
    t.blen = n0 * t.h0;
    PetscCall(CaseSetUp(&t, 3, &c));
    PetscCall(PffGridFillChannel(t.grid, c.uCh, Gravity, &c));
    PetscCall(CasePressure(&t, &c, 1e-12, NULL, &ps));
    PetscCall(PffPressureProject(ps, c.uCh, c.dt, -1, c.pCh, &st));
    PetscCall(ChannelReduce(&t, c.uCh, 4, 0, &umax));
    PetscCall(PetscPrintf(PETSC_COMM_WORLD, "hydrostatic %-8s its %3d  max |u| / |dt g| = %.2e\n",
                          graded ? "y-graded" : "uniform", (int)st.its, (double)(umax / (9.81 * c.dt))));
    PetscCheck(umax <= 1e-6 * 9.81 * c.dt, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
               "hydrostatic (%s): max |u| = %g, not below 1e-6 |dt g|", graded ? "graded" : "uniform", (double)umax);
    PetscCheck(st.reason > 0, PETSC_COMM_WORLD, PETSC_ERR_NOT_CONVERGED,
               "hydrostatic (%s): the default PC did not reach rtol 1e-12: %s", graded ? "graded" : "uniform",
               KSPConvergedReasons[st.reason]);
    PetscCall(PffPressureDestroy(&ps));
    PetscCall(PffGridDestroy(&t.grid));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* One bubbly 64^3 projection per PC: assembly times of both assemblies, set-up and solve times and
   iterations at the default rtol 1e-4 and at 1e-8. */
static PetscErrorCode Bench(PetscInt N)
{
  const PetscInt  n0 = 16, nb[3] = {N / n0, N / n0, N / n0};
  const PetscBool per[3]    = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};
  const PetscReal origin[3] = {0, 0, 0};
  const PCType    pcs[5]    = {"pffmg", PCGAMG, PCHYPRE, PCBJACOBI, PCJACOBI};
  PffTestCtx      t;
  Case            c;
  PetscMPIInt     size;

  PetscFunctionBeginUser;
  PetscCheck(N % n0 == 0, PETSC_COMM_WORLD, PETSC_ERR_ARG_OUTOFRANGE, "-bench N: N must be a multiple of %d", (int)n0);
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  PetscCall(PffTestCreateGrid(PETSC_COMM_WORLD, nb, per, origin, 1.0 / (PetscReal)N, n0, 1, 0, 0, 3, &t));
  PetscCall(CaseSetUp(&t, 4, &c));
  PetscInt npcs = 5;
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-bench_npcs", &npcs, NULL));
  PetscCheck(npcs >= 1 && npcs <= 5, PETSC_COMM_WORLD, PETSC_ERR_ARG_OUTOFRANGE,
             "-bench_npcs %" PetscInt_FMT " is invalid: must be in [1, 5]", npcs);
  for (PetscInt k = 0; k < npcs; k++) {
    PffPressure    ps;
    KSP            ksp;
    PC             pc;
    PetscLogDouble tsu0, tsu1, tasm[2] = {1e30, 1e30};
    for (PetscInt a = 0; a < 2; a++) {
      PetscCall(PetscOptionsSetValue(NULL, "-pressure_assembly", a == 0 ? "ptap" : "direct"));
      PetscCall(PetscTime(&tsu0));
      PetscCall(PffPressureCreate(t.grid, &ps));
      PetscCall(PffPressureSetFromOptions(ps));
      PetscCall(PffPressureSetUp(ps));
      PetscCall(PetscTime(&tsu1));
      for (PetscInt rep = 0; rep < 3; rep++) {
        PetscLogDouble t0, t1;
        PetscCall(PetscTime(&t0));
        PetscCall(PffPressureSetCoefficients(ps, c.betaCh, c.openCh));
        PetscCall(PetscTime(&t1));
        tasm[a] = PetscMin(tasm[a], t1 - t0);
      }
      if (a == 0) PetscCall(PffPressureDestroy(&ps));
    }
    PetscCall(PffPressureSetMonitorDivergence(ps, PETSC_TRUE));
    PetscCall(PffPressureGetKSP(ps, &ksp));
    PetscCall(KSPGetPC(ksp, &pc));
    PetscCall(PCSetType(pc, pcs[k]));
    PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                          "bench %" PetscInt_FMT
                          "^3 ranks %d pc %-8s set-up %.3f s, assembly ptap %.3f s direct %.3f s\n",
                          N, size, pcs[k], tsu1 - tsu0, tasm[0], tasm[1]));
    for (PetscInt tol = 0; tol < 2; tol++) {
      PffPressureStats st;
      PetscCall(KSPSetTolerances(ksp, tol == 0 ? 1e-4 : 1e-8, 1e-50, PETSC_DEFAULT, 10000));
      PetscCall(PffGridFillChannel(t.grid, c.uCh, GravityNoise, &c));
      PetscCall(PffGridFillChannel(t.grid, c.pCh, PffTestZero, &c));
      PetscCall(PffPressureProject(ps, c.uCh, c.dt, -1, c.pCh, &st));
      PetscCall(
          PetscPrintf(PETSC_COMM_WORLD,
                      "bench   rtol %.0e: its %4d  pc set-up %.3f s  solve %.3f s  rel. residual %.1e  max|Du| %.2e "
                      "-> %.2e  %s\n",
                      tol == 0 ? 1e-4 : 1e-8, (int)st.its, st.setupTime, st.solveTime, (double)st.rnorm,
                      (double)st.divBefore, (double)st.divAfter, KSPConvergedReasons[st.reason]));
    }
    PetscCall(PffPressureDestroy(&ps));
  }
  PetscCall(PetscOptionsClearValue(NULL, "-pressure_assembly"));
  PetscCall(PffGridDestroy(&t.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  PetscInt bench = 0;

  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  PetscCall(PffInitializePackage());
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-bench", &bench, NULL));
  if (bench > 0)
    PetscCall(Bench(bench));
  else {
    PetscCall(TestOperator());
    PetscCall(TestProjection());
    PetscCall(TestProjectSource());
    PetscCall(TestHydrostatic());
  }
  PetscCall(PetscFinalize());
  return 0;
}
