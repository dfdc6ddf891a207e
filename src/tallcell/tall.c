/* tallcell: life cycle, options and the projection of the variational tall-cell pressure solve
   (include/pff/tallcell.h, docs/tallcell.md).

   Build = columns and samples (columns.c) + rows and A (rows.c), timed as the paper's "assemble matrix".
   Project: u*_row = mean of the row's faces, b = (rho/dt) [grad]^T V u*_row, KSP solve of A p = b from
   p = 0, then every face of row r gets u <- u - dt/rho F_r ([grad] p)_r. */
#include "tallimpl.h"

#define PFF_TALL_LAYER_FRACTION_DEFAULT 0.25
#define PFF_TALL_LAYER_MIN_DEFAULT 2
#define PFF_TALL_THETA_MIN_DEFAULT 0.01
#define PFF_TALL_RTOL_DEFAULT 1e-4

PetscErrorCode PffTallCreate(PffGrid grid, PffTall *tcp)
{
  PffTall tc;
  PC      pc;

  PetscFunctionBeginUser;
  PetscCheck(tcp != NULL && grid != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "tallcell: NULL argument");
  {
    /* the grid's properties first, so that a refusal leaves nothing allocated */
    PffPartitionType pt;
    PetscBool        periodic[3];
    MPI_Comm         comm;
    PetscCall(PffGridGetComm(grid, &comm));
    PetscCall(PffGridGetPartitionType(grid, &pt));
    PetscCall(PffGridGetSizes(grid, NULL, NULL, NULL, NULL, periodic));
    PetscCheck(
        pt == PFF_PARTITION_COLUMNS, comm, PETSC_ERR_ARG_INCOMP,
        "tallcell: -partition_type %s: the tall-cell grid needs -partition_type columns (whole columns per rank)",
        PffPartitionTypes[pt]);
    PetscCheck(!periodic[1], comm, PETSC_ERR_ARG_INCOMP,
               "tallcell: -grid_periodic: y (the vertical) must not be periodic");
  }
  PetscCall(PetscNew(&tc));
  tc->grid          = grid;
  tc->merge         = PETSC_TRUE;
  tc->layerFraction = PFF_TALL_LAYER_FRACTION_DEFAULT;
  tc->layerMin      = PFF_TALL_LAYER_MIN_DEFAULT;
  tc->thetaMin      = PFF_TALL_THETA_MIN_DEFAULT;
  tc->sizingKappa   = 0.3;
  tc->sizingU       = 0.05;
  tc->sizing        = PETSC_TRUE;
  tc->quadInterval  = 0;
  tc->chA           = -1;
  tc->chSolid       = -1;
  PetscCall(PffGridGetComm(grid, &tc->comm));
  PetscCallMPI(MPI_Comm_rank(tc->comm, &tc->rank));
  PetscCallMPI(MPI_Comm_size(tc->comm, &tc->size));
  PetscCall(PffGridGetRaster(grid, tc->nb, NULL, NULL));
  PetscCall(PffGridGetSizes(grid, &tc->n0, NULL, tc->origin, &tc->h0, tc->periodic));
  tc->nbc = tc->nb[0] * tc->nb[2];
  {
    PetscErrorCode ierr = PffTallCheckGrid_Private(tc);
    if (ierr) PetscCall(PetscFree(tc));
    PetscCall(ierr);
  }
  PetscCall(KSPCreate(tc->comm, &tc->ksp));
  PetscCall(KSPSetOptionsPrefix(tc->ksp, "tall_"));
  PetscCall(KSPSetType(tc->ksp, KSPCG));
  PetscCall(KSPSetTolerances(tc->ksp, PFF_TALL_RTOL_DEFAULT, PETSC_DEFAULT, PETSC_DEFAULT, PETSC_DEFAULT));
  PetscCall(KSPSetNormType(tc->ksp, KSP_NORM_UNPRECONDITIONED));
  PetscCall(KSPGetPC(tc->ksp, &pc));
  PetscCall(PCSetType(pc, PCBJACOBI));
  *tcp = tc;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffTallSetFromOptions(PffTall tc)
{
  PetscFunctionBeginUser;
  PetscOptionsBegin(tc->comm, NULL, "Quadtree tall cells (variational pressure)", "PffTall");
  PetscCall(PffOptionsBool("-tall_merge", "Merge the deep part of each liquid run into a tall cell", "PffTallBuild",
                           tc->merge, &tc->merge, NULL));
  PetscCall(PffOptionsReal("-tall_layer_fraction",
                           "Band of cubic cells under a free surface, as a fraction of the run's height, in [0, 1]",
                           "PffTallBuild", tc->layerFraction, &tc->layerFraction, NULL));
  PetscCall(PffOptionsBoundedInt("-tall_layer_min", "Band of cubic cells under a free surface: at least this many",
                                 "PffTallBuild", tc->layerMin, &tc->layerMin, NULL, 1));
  PetscCall(PffOptionsReal("-tall_theta_min", "Smallest liquid fraction of a free-surface gradient, in (0, 1]",
                           "PffTallBuild", tc->thetaMin, &tc->thetaMin, NULL));
  PetscCall(PffOptionsReal("-tall_sizing_curvature", "Sizing: largest turn of the surface across one cell (rad), > 0",
                           "PffTallSizingLevels", tc->sizingKappa, &tc->sizingKappa, NULL));
  PetscCall(PffOptionsReal("-tall_sizing_velocity", "Sizing: largest velocity jump across one cell (m/s), > 0",
                           "PffTallSizingLevels", tc->sizingU, &tc->sizingU, NULL));
  PetscCall(PffOptionsBool(
      "-tall_sizing", "The liquid model builds the quadtree from the sizing function at t = 0 (false: the grid's map)",
      "PffTallGetSizing", tc->sizing, &tc->sizing, NULL));
  PetscCall(PffOptionsBoundedInt("-tall_levels", "Quadtree levels of the sizing function (0: the grid's)",
                                 "PffTallSizingLevels", tc->levels, &tc->levels, NULL, 0));
  PetscCall(PffOptionsBoundedInt("-tall_quadtree_interval",
                                 "The liquid model rebuilds the quadtree every this many steps (0: only at t = 0)",
                                 "PffTallGetSizing", tc->quadInterval, &tc->quadInterval, NULL, 0));
  PetscOptionsEnd();
  PetscCheck(tc->sizingKappa > 0 && tc->sizingU > 0, tc->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-tall_sizing_curvature and -tall_sizing_velocity must be positive (%g, %g)", (double)tc->sizingKappa,
             (double)tc->sizingU);
  PetscCheck(tc->layerFraction >= 0 && tc->layerFraction <= 1, tc->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-tall_layer_fraction: %g is not in [0, 1]", (double)tc->layerFraction);
  PetscCheck(tc->thetaMin > 0 && tc->thetaMin <= 1, tc->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-tall_theta_min: %g is not in (0, 1]", (double)tc->thetaMin);
  PetscCall(PffOptionsCheckReal(tc->comm, "-tall_ksp_rtol", 0, 1, PETSC_TRUE, "in (0, 1)"));
  PetscCall(PffOptionsCheckInt(tc->comm, "-tall_ksp_max_it", 1, PETSC_MAX_INT));
  PetscCall(KSPSetFromOptions(tc->ksp));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffTallGetSizing(PffTall tc, PetscBool *sizing, PetscInt *interval)
{
  PetscFunctionBeginUser;
  if (sizing) *sizing = tc->sizing;
  if (interval) *interval = tc->sizing ? tc->quadInterval : 0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffTallSetMerge(PffTall tc, PetscBool merge)
{
  PetscFunctionBeginUser;
  tc->merge = merge;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffTallFreeBuild_Private(PffTall tc)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree3(tc->bcLevel, tc->bcOwner, tc->bcOffset));
  PetscCall(PetscFree3(tc->ri, tc->rr, tc->height));
  PetscCall(PetscFree(tc->gkey));
  PetscCall(PetscFree(tc->gstart));
  PetscCall(PetscFree2(tc->gi, tc->gr));
  PetscCall(PetscFree(tc->sampleS));
  PetscCall(PetscFree(tc->rowF));
  PetscCall(PetscFree(tc->rowV));
  PetscCall(PetscFree(tc->rowA));
  PetscCall(PetscFree(tc->faceA));
  PetscCall(PetscFree(tc->rowFace));
  PetscCall(PetscFree(tc->rowEnt));
  PetscCall(PetscFree(tc->faceLb));
  PetscCall(PetscFree(tc->faceComp));
  PetscCall(PetscFree(tc->faceCell));
  tc->nrows = tc->rowsCap = tc->nfaces = tc->facesCap = 0;
  tc->nghost = tc->nrec = tc->nsamp = 0;
  tc->nsurface                      = 0;
  PetscCall(PffTallFreeBodies_Private(tc));
  PetscCall(MatDestroy(&tc->G));
  PetscCall(MatDestroy(&tc->A));
  PetscCall(VecDestroy(&tc->p));
  PetscCall(VecDestroy(&tc->b));
  PetscCall(VecDestroy(&tc->urow));
  PetscCall(VecDestroy(&tc->grow));
  PetscCall(VecDestroy(&tc->w));
  tc->built = PETSC_FALSE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffTallDestroy(PffTall *tc)
{
  PetscFunctionBeginUser;
  if (!tc || !*tc) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PffTallFreeBuild_Private(*tc));
  PetscCall(KSPDestroy(&(*tc)->ksp));
  PetscCall(PetscFree(*tc));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffTallBuild(PffTall tc, PetscInt chPhi)
{
  PetscLogDouble t0, t1;

  PetscFunctionBeginUser;
  PetscCall(PffTallFreeBuild_Private(tc));
  PetscCallMPI(MPI_Barrier(tc->comm));
  PetscCall(PetscLogEventBegin(PFF_TallBuild, 0, 0, 0, 0));
  PetscCall(PetscTime(&t0));
  PetscCall(PffTallBuildColumns_Private(tc, chPhi));
  PetscCall(PffTallBuildRows_Private(tc));
  PetscCall(PffTallBuildBodies_Private(tc));
  /* the system's size changes with the surface: the KSP keeps its type and options, not its set-up */
  PetscCall(KSPReset(tc->ksp));
  PetscCall(KSPSetOperators(tc->ksp, tc->N ? tc->N : tc->A, tc->A));
  tc->subPCDefaultApplied = PETSC_FALSE;
  PetscCall(PetscTime(&t1));
  tc->assembleTime = t1 - t0;
  tc->built        = PETSC_TRUE;
  PetscCall(PetscLogEventEnd(PFF_TallBuild, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* u*_row: the mean of each row's faces in chU, weighted by their open fractions (the flux through the
   row's open area over that area). */
static PetscErrorCode RowVelocity(PffTall tc, PetscInt chU, Vec urow)
{
  PetscScalar *u;

  PetscFunctionBeginUser;
  PetscCall(VecGetArray(urow, &u));
  for (PetscInt r = 0; r < tc->nrows; r++) {
    PetscReal sum = 0, asum = 0;
    for (PetscInt f = tc->rowFace[r]; f < tc->rowFace[r + 1]; f++) {
      float *data;
      PetscCall(PffGridGetBlockData(tc->grid, chU, tc->faceLb[f], tc->faceComp[f], &data));
      sum += tc->faceA[f] * data[tc->faceCell[f]];
      asum += tc->faceA[f];
    }
    u[r] = sum / asum;
  }
  PetscCall(VecRestoreArray(urow, &u));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode ApplySubPCDefault(PffTall tc)
{
  PetscFunctionBeginUser;
  if (tc->subPCDefaultApplied) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(KSPSetUp(tc->ksp));
  PetscCall(PffKSPDefaultSubICC(tc->ksp, "tall_"));
  tc->subPCDefaultApplied = PETSC_TRUE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Every owned cell of cell channel ch: the pressure of its column's function at the centre from the samples p
   (0 in air; the upper half's segment holds the centre), or with p NULL the pressure-cell height. */
static PetscErrorCode WriteCells(PffTall tc, PetscInt ch, const PetscScalar *p)
{
  PetscFunctionBeginUser;
  for (PetscInt bc = 0; bc < tc->nbc; bc++) {
    if (tc->bcOwner[bc] != tc->rank) continue;
    const PetscInt  bi = bc % tc->nb[0], bk = bc / tc->nb[0], l = tc->bcLevel[bc], n = tc->n0 >> l, ny = tc->nb[1] * n;
    const PetscReal s = tc->h0 * (PetscReal)(1 << l);
    for (PetscInt bj = 0; bj < tc->nb[1]; bj++) {
      PetscInt lb;
      float   *data;
      PetscCall(PffGridGetLocalIndex(tc->grid, bi + tc->nb[0] * (bj + tc->nb[1] * bk), &lb));
      PetscCall(PffGridGetBlockData(tc->grid, ch, lb, 0, &data));
      for (PetscInt ck = 0; ck < n; ck++)
        for (PetscInt ci = 0; ci < n; ci++)
          for (PetscInt cj = 0; cj < n; cj++) {
            const PetscInt   j = bj * n + cj, rec = tc->bcOffset[bc] + (ck * n + ci) * ny + j;
            const PetscInt  *ri = tc->ri + PFF_TALL_RI * rec;
            const PetscReal *rr = tc->rr + PFF_TALL_RR * rec, yc = tc->origin[1] + (j + 0.5) * s;
            PetscReal        v = 0;
            if (!p)
              v = tc->height[rec];
            else if (PffTallLiquidKind(ri[4])) {
              PetscInt  id[2];
              PetscReal w[2];
              PffTallCentreWeights(ri, rr, yc, id, w);
              for (PetscInt q = 0; q < 2; q++)
                if (id[q] >= 0 && w[q] != 0) v += w[q] * p[id[q] - tc->sstart];
            }
            data[ci + n * (cj + n * ck)] = (float)v;
          }
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffTallProject(PffTall tc, PetscInt chU, PetscReal dt, PetscReal rho, PetscInt chP, PffTallStats *stats)
{
  const PetscScalar *g, *pa;
  PetscLogDouble     t0, t1;
  PetscInt           its;
  PetscReal          res0, res, rnorm;
  KSPConvergedReason reason;

  PetscFunctionBeginUser;
  PetscCheck(tc->built, tc->comm, PETSC_ERR_ORDER, "tallcell: call PffTallBuild() first");
  PetscCheck(dt > 0 && rho > 0, tc->comm, PETSC_ERR_ARG_OUTOFRANGE, "tallcell: dt and rho must be positive");
  PetscCall(RowVelocity(tc, chU, tc->urow));
  {
    PetscScalar       *w;
    const PetscScalar *u;
    PetscCall(VecGetArrayRead(tc->urow, &u));
    PetscCall(VecGetArray(tc->w, &w));
    for (PetscInt r = 0; r < tc->nrows; r++) w[r] = tc->rowV[r] * tc->rowA[r] * u[r] * rho / dt;
    PetscCall(VecRestoreArray(tc->w, &w));
    PetscCall(VecRestoreArrayRead(tc->urow, &u));
  }
  PetscCall(MatMultTranspose(tc->G, tc->w, tc->b));
  PetscCall(PffTallBodiesRHS_Private(tc, dt, rho));
  if (!tc->nsurface) {
    MatNullSpace nsp;
    PetscCall(MatGetNullSpace(tc->A, &nsp));
    if (nsp) PetscCall(MatNullSpaceRemove(nsp, tc->b));
  }
  PetscCall(VecNorm(tc->b, NORM_INFINITY, &res0));
  PetscCall(VecSet(tc->p, 0));
  PetscCall(ApplySubPCDefault(tc));
  PetscCallMPI(MPI_Barrier(tc->comm));
  PetscCall(PetscTime(&t0));
  PetscCall(KSPSolve(tc->ksp, tc->b, tc->p));
  PetscCall(PetscTime(&t1));
  PetscCall(KSPGetIterationNumber(tc->ksp, &its));
  PetscCall(KSPGetConvergedReason(tc->ksp, &reason));
  {
    Vec       r;
    PetscReal bn;
    PetscCall(VecDuplicate(tc->b, &r));
    PetscCall(MatMult(tc->N ? tc->N : tc->A, tc->p, r));
    PetscCall(VecAYPX(r, -1, tc->b));
    PetscCall(VecNorm(r, NORM_INFINITY, &res));
    PetscCall(VecNorm(r, NORM_2, &rnorm));
    PetscCall(VecNorm(tc->b, NORM_2, &bn));
    rnorm = bn > 0 ? rnorm / bn : rnorm;
    PetscCall(VecDestroy(&r));
  }
  PetscCall(PffTallBodiesUpdate_Private(tc, dt));
  /* velocity update on every face of every row */
  PetscCall(MatMult(tc->G, tc->p, tc->grow));
  PetscCall(VecGetArrayRead(tc->grow, &g));
  for (PetscInt r = 0; r < tc->nrows; r++) {
    const PetscReal du = dt / rho * tc->rowF[r] * g[r];
    for (PetscInt f = tc->rowFace[r]; f < tc->rowFace[r + 1]; f++) {
      float *data;
      if (!(tc->faceA[f] > 0)) continue; /* a closed face keeps the solid's velocity */
      PetscCall(PffGridGetBlockData(tc->grid, chU, tc->faceLb[f], tc->faceComp[f], &data));
      data[tc->faceCell[f]] = (float)(data[tc->faceCell[f]] - du);
    }
  }
  PetscCall(VecRestoreArrayRead(tc->grow, &g));
  /* pressure at the cell centres */
  if (chP >= 0) {
    PetscCall(VecGetArrayRead(tc->p, &pa));
    PetscCall(WriteCells(tc, chP, pa));
    PetscCall(VecRestoreArrayRead(tc->p, &pa));
  }
  if (stats) {
    PetscCall(PffTallGetCounts(tc, stats));
    stats->its       = its;
    stats->res0      = res0;
    stats->res       = res;
    stats->rnorm     = rnorm;
    stats->reason    = reason;
    stats->solveTime = t1 - t0;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffTallMaxDivergence(PffTall tc, PetscInt chU, PetscReal *maxdiv)
{
  const PetscScalar *d;
  PetscScalar       *w;
  const PetscScalar *u;
  Vec                div;
  PetscReal          m = 0;

  PetscFunctionBeginUser;
  PetscCheck(tc->built, tc->comm, PETSC_ERR_ORDER, "tallcell: call PffTallBuild() first");
  PetscCall(RowVelocity(tc, chU, tc->urow));
  PetscCall(VecGetArrayRead(tc->urow, &u));
  PetscCall(VecGetArray(tc->w, &w));
  for (PetscInt r = 0; r < tc->nrows; r++) w[r] = tc->rowV[r] * tc->rowA[r] * u[r];
  PetscCall(VecRestoreArray(tc->w, &w));
  PetscCall(VecRestoreArrayRead(tc->urow, &u));
  PetscCall(VecDuplicate(tc->p, &div));
  PetscCall(MatMultTranspose(tc->G, tc->w, div));
  PetscCall(VecGetArrayRead(div, &d));
  for (PetscInt i = 0; i < tc->nsamp; i++) m = PetscMax(m, PetscAbsReal(d[i]) / PetscPowRealInt(tc->sampleS[i], 3));
  PetscCall(VecRestoreArrayRead(div, &d));
  PetscCall(VecDestroy(&div));
  PetscCallMPI(MPIU_Allreduce(&m, maxdiv, 1, MPIU_REAL, MPI_MAX, tc->comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffTallMaxRowVelocity(PffTall tc, PetscInt chU, PetscReal *umax)
{
  PetscFunctionBeginUser;
  PetscCheck(tc->built, tc->comm, PETSC_ERR_ORDER, "tallcell: call PffTallBuild() first");
  PetscCall(RowVelocity(tc, chU, tc->w));
  PetscCall(VecNorm(tc->w, NORM_INFINITY, umax));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffTallLiquidMomentum(PffTall tc, PetscInt chU, PetscReal rho, PetscReal mom[3])
{
  const PetscScalar *u;
  PetscReal          loc[3] = {0, 0, 0};

  PetscFunctionBeginUser;
  PetscCheck(tc->built, tc->comm, PETSC_ERR_ORDER, "tallcell: call PffTallBuild() first");
  PetscCall(RowVelocity(tc, chU, tc->w));
  PetscCall(VecGetArrayRead(tc->w, &u));
  for (PetscInt r = 0; r < tc->nrows; r++)
    loc[tc->faceComp[tc->rowFace[r]]] += rho * tc->rowV[r] * tc->rowA[r] / tc->rowF[r] * PetscRealPart(u[r]);
  PetscCall(VecRestoreArrayRead(tc->w, &u));
  PetscCallMPI(MPIU_Allreduce(loc, mom, 3, MPIU_REAL, MPI_SUM, tc->comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffTallGetOperator(PffTall tc, Mat *A)
{
  PetscFunctionBeginUser;
  PetscCheck(tc->built, tc->comm, PETSC_ERR_ORDER, "tallcell: call PffTallBuild() first");
  *A = tc->A;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffTallGetSolution(PffTall tc, Vec *p)
{
  PetscFunctionBeginUser;
  PetscCheck(tc->built, tc->comm, PETSC_ERR_ORDER, "tallcell: call PffTallBuild() first");
  *p = tc->p;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffTallGetKSP(PffTall tc, KSP *ksp)
{
  PetscFunctionBeginUser;
  *ksp = tc->ksp;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffTallGetCounts(PffTall tc, PffTallStats *st)
{
  PetscInt64 loc = tc->nrows;

  PetscFunctionBeginUser;
  PetscCheck(tc->built, tc->comm, PETSC_ERR_ORDER, "tallcell: call PffTallBuild() first");
  PetscCall(PetscMemzero(st, sizeof(*st)));
  st->cells       = tc->cells;
  st->tallCells   = tc->tallCells;
  st->liquidCells = tc->liquidCells;
  PetscCallMPI(MPIU_Allreduce(&loc, &st->rows, 1, MPIU_INT64, MPI_SUM, tc->comm));
  loc = tc->nsamp;
  PetscCallMPI(MPIU_Allreduce(&loc, &st->samples, 1, MPIU_INT64, MPI_SUM, tc->comm));
  st->assembleTime = tc->assembleTime;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffTallWriteCellHeight(PffTall tc, PetscInt ch)
{
  PetscFunctionBeginUser;
  PetscCheck(tc->built, tc->comm, PETSC_ERR_ORDER, "tallcell: call PffTallBuild() first");
  PetscCall(WriteCells(tc, ch, NULL));
  PetscFunctionReturn(PETSC_SUCCESS);
}
