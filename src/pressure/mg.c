/* pffmg: the adaptive multigrid preconditioner of PF-FLIP Sec. 6, as a PETSc PCSHELL inside
   KSPFCG (flexible CG, Polak-Ribiere; Sec. 6.4), registered as the PC type "pffmg" so that
   -pressure_pc_type pffmg selects it like any PETSc PC.

   One application is a cycle with zero initial guess over the multigrid levels of mglevels.c:
   smooth (mgsmooth.c), restrict the residual with R = P^T, correct on the next level, add P times the
   correction, smooth again. The correction below the finest level is two flexible-CG steps (K-cycle,
   default) or one recursive V-cycle (-pressure_pffmg_kcycle 0, the paper's choice); the coarsest
   level is solved by the KSP with options prefix pressure_pffmg_coarse_ (default: a redundant direct
   solve). The smoother is the two-stage
   red-black hybrid Gauss-Seidel with adaptive relaxation (Algorithm 2), or fixed sweeps, or
   weighted Jacobi, chosen by options so that the comparison of the paper's Fig. 17 can be redone.
   Set-up is symbolic once per grid and numeric (Galerkin products, coarse factorisation) each time
   the coefficients change, i.e. once per time step. */
#include "mgimpl.h"

#define PFF_MG_NAME "pffmg"
#define PFF_MG_SMOOTHER_DEFAULT PFF_MG_SMOOTHER_RBGS
#define PFF_MG_ADAPTIVE_DEFAULT PETSC_TRUE
#define PFF_MG_BLOCK_SWEEPS_DEFAULT PETSC_TRUE
#define PFF_MG_SWEEPS_DEFAULT 2
#define PFF_MG_ADAPTIVE_STEPS_DEFAULT 10
#define PFF_MG_BLOCK_SWEEPS_MAX_DEFAULT 4
#define PFF_MG_OMEGA_DEFAULT (6.0 / 7.0)
#define PFF_MG_THETA_SIGMAS_DEFAULT 2.0
#define PFF_MG_MAX_LEVELS_DEFAULT 16
#define PFF_MG_CORRECTION_DEFAULT 1.0
#define PFF_MG_RESCALE_DEFAULT PETSC_TRUE
#define PFF_MG_KCYCLE_DEFAULT 4
#define PFF_MG_KCYCLE_RTOL_DEFAULT 0.25
#define PFF_MG_KCYCLE_RATIO_DEFAULT 2.5
#define PFF_MG_COARSE_MAX_DEFAULT 4096
#define PFF_MG_OPERATOR_DEFAULT PFF_MG_OPERATOR_STENCIL
#define PFF_MG_OMP_MIN_ROWS_DEFAULT 32768

static PetscErrorCode PffMGGetContext(PC pc, PffMG **mg)
{
  const char *name = NULL;

  PetscFunctionBeginUser;
  PetscCall(PCShellGetName(pc, &name));
  PetscCheck(name != NULL && strcmp(name, PFF_MG_NAME) == 0, PetscObjectComm((PetscObject)pc), PETSC_ERR_ARG_WRONG,
             "pressure: the preconditioner is not pffmg (-pressure_pc_type pffmg)");
  PetscCall(PCShellGetContext(pc, mg));
  PetscFunctionReturn(PETSC_SUCCESS);
}

#define PFF_MG_PRESSURE_KEY "PffPressure"

/* The pressure module composes itself with the PC once. PCSetType replaces the PC's implementation
   but keeps composed objects, so pffmg finds the grid and the face coefficients however it was chosen
   (options or PCSetType). */
PetscErrorCode PffPressureMGComposePressure_Private(PC pc, PffPressure ps)
{
  PetscContainer c;

  PetscFunctionBeginUser;
  PetscCall(PetscContainerCreate(PetscObjectComm((PetscObject)pc), &c));
  PetscCall(PetscContainerSetPointer(c, ps));
  PetscCall(PetscObjectCompose((PetscObject)pc, PFF_MG_PRESSURE_KEY, (PetscObject)c));
  PetscCall(PetscContainerDestroy(&c));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffMGQueryPressure(PC pc, PffPressure *ps)
{
  PetscObject c;

  PetscFunctionBeginUser;
  *ps = NULL;
  PetscCall(PetscObjectQuery((PetscObject)pc, PFF_MG_PRESSURE_KEY, &c));
  if (c) PetscCall(PetscContainerGetPointer((PetscContainer)c, (void **)ps));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode VCycle(PffMG *mg, PetscInt L, Vec b, Vec x)
{
  PffMGLevel *lv = &mg->lev[L];

  PetscFunctionBeginUser;
  if (L == mg->nlevels - 1) {
    PetscCall(PetscLogEventBegin(PFF_MGCoarse, 0, 0, 0, 0));
    PetscCall(KSPSolve(mg->coarse, b, x));
    PetscCall(PetscLogEventEnd(PFF_MGCoarse, 0, 0, 0, 0));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PffMGLevel         *c  = &mg->lev[L + 1];
  const PetscLogEvent ev = PFF_MGLevel[PetscMin(L, PFF_MG_LOG_LEVELS - 1)];
  /* the level's event leaves out the coarse correction, so that each level's own time shows */
  PetscCall(PetscLogEventBegin(ev, 0, 0, 0, 0));
  PetscCall(VecSet(x, 0.0));
  PetscCall(PffMGSmooth_Private(mg, L, b, x));
  if (lv->mf)
    PetscCall(PffMGStencilResidualRestrict_Private(mg, L, b, x, c->b));
  else {
    PetscCall(MatMult(lv->A, x, lv->r));
    PetscCall(VecAYPX(lv->r, -1.0, b));
    PetscCall(MatMultTranspose(lv->P, lv->r, c->b));
  }
  PetscCall(PetscLogEventEnd(ev, 0, 0, 0, 0));
  if (c->kcycle) {
    PetscInt       its;
    PetscLogDouble krylov, product;
    PetscBool      known;
    PetscCall(KSPSolve(c->kcycle, c->b, c->x));
    PetscCall(KSPGetIterationNumber(c->kcycle, &its));
    PetscCall(PffPressureFCGBytes_Private(c->kcycle, its, c->nrows, &krylov, &known));
    /* a matrix-free level's product reads x, three float face coefficients and the double ds, and writes y */
    PetscCall(PffPressureProductBytes_Private(c->A, 8.0 + 3 * sizeof(PffMGReal) + 8.0 + 8.0, &product));
    mg->stats.bytesKCycle += krylov + its * product;
  } else
    PetscCall(VCycle(mg, L + 1, c->b, c->x));
  PetscCall(PetscLogEventBegin(ev, 0, 0, 0, 0));
  if (mg->opt.correction != 1.0) PetscCall(VecScale(c->x, mg->opt.correction));
  /* x zeroed (8 B per cell), the residual and its restriction (x, b, ds and cf read, the coarse b written; counted
     so on AIJ levels too), the prolongation (coarse x read, x read and written), the correction's scale; the
     visits' smoothing is counted as cellVisits x PFF_MG_VISIT_BYTES */
  mg->stats.bytesTransfer +=
      (8.0 + 36.0 + 16.0) * lv->nrows + (8.0 + 8.0 + (mg->opt.correction != 1.0 ? 16.0 : 0)) * c->nrows;
  if (lv->mf)
    PetscCall(PffMGStencilProlongAdd_Private(mg, L, c->x, x));
  else
    PetscCall(MatMultAdd(lv->P, c->x, x, x));
  PetscCall(PffMGSmooth_Private(mg, L, b, x));
  PetscCall(PetscLogEventEnd(ev, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

typedef struct {
  PffMG   *mg;
  PetscInt L;
} PffMGKCycle;

static PetscErrorCode PffMGKCycleApply(PC pc, Vec b, Vec x)
{
  PffMGKCycle *k;

  PetscFunctionBeginUser;
  PetscCall(PCShellGetContext(pc, &k));
  PetscCall(VCycle(k->mg, k->L, b, x));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffMGKCycleDestroy(PC pc)
{
  PffMGKCycle *k;

  PetscFunctionBeginUser;
  PetscCall(PCShellGetContext(pc, &k));
  PetscCall(PetscFree(k));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* K-cycle (Notay & Vassilevski): the correction on level L is two flexible-CG steps preconditioned by
   the cycle of that level, which keeps aggregation multigrid's convergence independent of the depth. */
static PetscErrorCode PffMGSetUpKCycle(PffMG *mg, PetscInt L)
{
  PffMGLevel  *lv = &mg->lev[L];
  PffMGKCycle *k;
  PC           pc;

  PetscFunctionBeginUser;
  if (lv->kcycle == NULL) {
    PetscCall(KSPCreate(mg->comm, &lv->kcycle));
    PetscCall(KSPSetType(lv->kcycle, KSPFCG));
    /* Notay's conditional K-cycle: the residual norm costs one reduction per step, and the steps it saves
       are those the level's problem does not need */
    PetscCall(KSPSetNormType(lv->kcycle, mg->opt.kcycleRtol > 0 ? KSP_NORM_UNPRECONDITIONED : KSP_NORM_NONE));
    PetscCall(KSPSetTolerances(lv->kcycle, mg->opt.kcycleRtol, 0.0, PETSC_DEFAULT, mg->opt.kcycleIts));
    /* kcycleIts steps need no more directions (FCG would keep 2 x 10 vectors per level) */
    PetscCall(KSPFCGSetMmax(lv->kcycle, mg->opt.kcycleIts));
    PetscCall(KSPFCGSetNprealloc(lv->kcycle, mg->opt.kcycleIts));
    PetscCall(KSPGetPC(lv->kcycle, &pc));
    PetscCall(PCSetType(pc, PCSHELL));
    PetscCall(PetscNew(&k));
    k->mg = mg;
    k->L  = L;
    PetscCall(PCShellSetContext(pc, k));
    PetscCall(PCShellSetApply(pc, PffMGKCycleApply));
    PetscCall(PCShellSetDestroy(pc, PffMGKCycleDestroy));
  }
  PetscCall(KSPSetOperators(lv->kcycle, lv->A, lv->A));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffMGApply(PC pc, Vec b, Vec x)
{
  PffMG *mg;

  PetscFunctionBeginUser;
  PetscCall(PCShellGetContext(pc, &mg));
  PetscCall(PetscLogEventBegin(PFF_MGApply, 0, 0, 0, 0));
  PetscCall(VCycle(mg, 0, b, x));
  mg->stats.applications++;
  PetscCall(PetscLogEventEnd(PFF_MGApply, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffMGSetUp(PC pc)
{
  PffMG           *mg;
  Mat              A;
  PetscObjectState state = 0;

  PetscFunctionBeginUser;
  PetscCall(PCShellGetContext(pc, &mg));
  /* chosen by PCSetType after PffPressureSetFromOptions */
  if (!mg->optionsRead) PetscCall(PffPressureMGSetFromOptions_Private(pc));
  PetscCall(PetscLogEventBegin(PFF_MGSetUp, 0, 0, 0, 0));
  PetscCall(PCGetOperators(pc, NULL, &A));
  /* a new operator, or one of a new topology: a freed Mat's address can come back for the next one */
  if (mg->built) PetscCall(PffGridGetTopologyState(mg->grid, &state));
  if (mg->built && (mg->Apc != A || mg->topology != state)) PetscCall(PffMGDestroyLevels_Private(mg));
  const PetscBool rebuilt = (PetscBool)!mg->built;
  if (rebuilt) PetscCall(PffMGBuildLevels_Private(mg));
  PetscCall(PffMGUpdateOperators_Private(mg, A));
  for (PetscInt L = 1; L + 1 < mg->nlevels; L++) {
    PetscInt nf, nc;
    PetscCall(MatGetSize(mg->lev[L - 1].A, &nf, NULL));
    PetscCall(MatGetSize(mg->lev[L].A, &nc, NULL));
    const PetscBool k = (PetscBool)(mg->opt.kcycleIts > 0 && (PetscReal)nf >= mg->opt.kcycleRatio * (PetscReal)nc);
    if (k)
      PetscCall(PffMGSetUpKCycle(mg, L));
    else
      PetscCall(KSPDestroy(&mg->lev[L].kcycle));
    if (rebuilt) /* the rows follow the grid: once per hierarchy, not every step */
      PetscCall(PetscInfo(pc,
                          "pffmg: level %" PetscInt_FMT " of %" PetscInt_FMT ": %" PetscInt_FMT
                          " rows (1/%.2f of the level above), %s\n",
                          L, mg->nlevels, nc, (double)nf / (double)PetscMax(nc, 1), k ? "K-cycle" : "one cycle"));
  }
  mg->stats.levels = mg->nlevels;
  PetscCall(PetscLogEventEnd(PFF_MGSetUp, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffMGView(PC pc, PetscViewer viewer)
{
  PffMG    *mg;
  PetscBool ascii;

  PetscFunctionBeginUser;
  PetscCall(PCShellGetContext(pc, &mg));
  PetscCall(PetscObjectTypeCompare((PetscObject)viewer, PETSCVIEWERASCII, &ascii));
  if (!ascii) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscViewerASCIIPrintf(
      viewer,
      "pffmg: %" PetscInt_FMT " levels (%s operators), smoother %s, adaptive relaxation %s (%" PetscInt_FMT
      " steps, theta = mean + %g sd), block sweeps %s (max %" PetscInt_FMT "), fixed sweeps %" PetscInt_FMT
      ", omega %g\n",
      mg->nlevels, PffMGOperatorTypes[mg->opt.operatorType], PffMGSmootherTypes[mg->opt.smoother],
      mg->opt.adaptive ? "on" : "off", mg->opt.adaptiveSteps, (double)mg->opt.thetaSigmas,
      mg->opt.blockSweeps ? "adaptive" : "one", mg->opt.blockSweepsMax, mg->opt.sweeps, (double)mg->opt.omega));
  for (PetscInt L = 0; L < mg->nlevels; L++) {
    PetscInt N = 0;
    if (mg->lev[L].A) PetscCall(MatGetSize(mg->lev[L].A, &N, NULL));
    PetscCall(PetscViewerASCIIPrintf(viewer, "  level %" PetscInt_FMT ": %" PetscInt_FMT " cells\n", L, N));
  }
  PetscCall(PetscViewerASCIIPushTab(viewer));
  PetscCall(KSPView(mg->coarse, viewer));
  PetscCall(PetscViewerASCIIPopTab(viewer));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffMGDestroy(PC pc)
{
  PffMG *mg;

  PetscFunctionBeginUser;
  PetscCall(PCShellGetContext(pc, &mg));
  if (mg == NULL) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PffMGDestroyLevels_Private(mg));
  PetscCall(KSPDestroy(&mg->coarse));
  PetscCall(PetscFree(mg));
  PetscCall(PCShellSetContext(pc, NULL));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The constructor behind PCSetType(pc, "pffmg"): a PCSHELL with our callbacks. */
static PetscErrorCode PCCreate_PffMG(PC pc)
{
  PffMG      *mg;
  const char *prefix;
  PC          cpc;

  PetscFunctionBeginUser;
  PetscCall(PCSetType(pc, PCSHELL));
  PetscCall(PetscNew(&mg));
  mg->comm               = PetscObjectComm((PetscObject)pc);
  mg->opt.smoother       = PFF_MG_SMOOTHER_DEFAULT;
  mg->opt.adaptive       = PFF_MG_ADAPTIVE_DEFAULT;
  mg->opt.blockSweeps    = PFF_MG_BLOCK_SWEEPS_DEFAULT;
  mg->opt.sweeps         = PFF_MG_SWEEPS_DEFAULT;
  mg->opt.adaptiveSteps  = PFF_MG_ADAPTIVE_STEPS_DEFAULT;
  mg->opt.blockSweepsMax = PFF_MG_BLOCK_SWEEPS_MAX_DEFAULT;
  mg->opt.omega          = PFF_MG_OMEGA_DEFAULT;
  mg->opt.thetaSigmas    = PFF_MG_THETA_SIGMAS_DEFAULT;
  mg->opt.maxLevels      = PFF_MG_MAX_LEVELS_DEFAULT;
  mg->opt.correction     = PFF_MG_CORRECTION_DEFAULT;
  mg->opt.rescale        = PFF_MG_RESCALE_DEFAULT;
  mg->opt.kcycleIts      = PFF_MG_KCYCLE_DEFAULT;
  mg->opt.kcycleRtol     = PFF_MG_KCYCLE_RTOL_DEFAULT;
  mg->opt.kcycleRatio    = PFF_MG_KCYCLE_RATIO_DEFAULT;
  mg->opt.coarseMax      = PFF_MG_COARSE_MAX_DEFAULT;
  mg->opt.operatorType   = PFF_MG_OPERATOR_DEFAULT;
  mg->opt.ompMinRows     = PFF_MG_OMP_MIN_ROWS_DEFAULT;
  PetscCall(KSPCreate(mg->comm, &mg->coarse));
  PetscCall(PCGetOptionsPrefix(pc, &prefix));
  PetscCall(KSPSetOptionsPrefix(mg->coarse, prefix));
  PetscCall(KSPAppendOptionsPrefix(mg->coarse, "pffmg_coarse_"));
  PetscCall(KSPSetType(mg->coarse, KSPPREONLY));
  PetscCall(KSPGetPC(mg->coarse, &cpc));
  PetscCall(PCSetType(cpc, PCREDUNDANT));
  PetscCall(PCShellSetContext(pc, mg));
  PetscCall(PCShellSetName(pc, PFF_MG_NAME));
  PetscCall(PCShellSetApply(pc, PffMGApply));
  PetscCall(PCShellSetSetUp(pc, PffMGSetUp));
  PetscCall(PCShellSetView(pc, PffMGView));
  PetscCall(PCShellSetDestroy(pc, PffMGDestroy));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureMGRegister_Private(void)
{
  PetscFunctionBeginUser;
  PetscCall(PCRegister(PFF_MG_NAME, PCCreate_PffMG));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Whether the PC is pffmg with matrix-free levels, which needs no assembled operator. */
PetscErrorCode PffPressureMGUsesStencil_Private(PC pc, PetscBool *stencil)
{
  PffMG    *mg;
  PetscBool active;

  PetscFunctionBeginUser;
  *stencil = PETSC_FALSE;
  PetscCall(PffPressureMGIsActive_Private(pc, &active));
  if (!active) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PffMGGetContext(pc, &mg));
  if (!mg->optionsRead) PetscCall(PffPressureMGSetFromOptions_Private(pc));
  *stencil = (PetscBool)(mg->opt.operatorType == PFF_MG_OPERATOR_STENCIL);
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureMGIsActive_Private(PC pc, PetscBool *active)
{
  const char *name = NULL;
  PetscBool   shell;

  PetscFunctionBeginUser;
  *active = PETSC_FALSE;
  PetscCall(PetscObjectTypeCompareAny((PetscObject)pc, &shell, PCSHELL, PFF_MG_NAME, ""));
  if (!shell) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PCShellGetName(pc, &name));
  *active = (PetscBool)(name != NULL && strcmp(name, PFF_MG_NAME) == 0);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Options of pffmg under the pressure KSP's prefix, and the grid PffPressureCreate composed with the PC. */
PetscErrorCode PffPressureMGSetFromOptions_Private(PC pc)
{
  PffMG      *mg;
  const char *prefix;

  PetscFunctionBeginUser;
  PetscCall(PffMGGetContext(pc, &mg));
  PetscCall(PffMGQueryPressure(pc, &mg->ps));
  mg->grid = mg->ps ? mg->ps->grid : NULL;
  PetscCheck(mg->grid != NULL, PetscObjectComm((PetscObject)pc), PETSC_ERR_ORDER,
             "pffmg needs the grid: use it through PffPressure (-pressure_pc_type pffmg)");
  PetscCall(PCGetOptionsPrefix(pc, &prefix));
  PetscOptionsBegin(mg->comm, prefix, "Adaptive multigrid preconditioner (pffmg)", "PC");
  PetscCall(PffOptionsEnum(
      "-pffmg_smoother", "pffmg smoother: two-stage red-black hybrid Gauss-Seidel or weighted Jacobi", "PffPressureMG",
      PffMGSmootherTypes, (PetscEnum)mg->opt.smoother, (PetscEnum *)&mg->opt.smoother, NULL));
  PetscCall(PffOptionsEnum(
      "-pffmg_operator", "Block-level operators: matrix-free face coefficients (stencil) or AIJ Galerkin products",
      "PffPressureMG", PffMGOperatorTypes, (PetscEnum)mg->opt.operatorType, (PetscEnum *)&mg->opt.operatorType, NULL));
  PetscCall(PffOptionsBool("-pffmg_adaptive", "Adaptive relaxation (Algorithm 2) instead of fixed sweeps",
                           "PffPressureMG", mg->opt.adaptive, &mg->opt.adaptive, NULL));
  PetscCall(PffOptionsBool("-pffmg_block_sweeps", "Repeat block-local sweeps until the update falls by 1/3",
                           "PffPressureMG", mg->opt.blockSweeps, &mg->opt.blockSweeps, NULL));
  PetscCall(PffOptionsBoundedInt("-pffmg_block_sweeps_max", "Most block-local sweeps per visit (k_max)",
                                 "PffPressureMG", mg->opt.blockSweepsMax, &mg->opt.blockSweepsMax, NULL, 1));
  PetscCall(PffOptionsBoundedInt("-pffmg_adaptive_steps", "Adaptive relaxation steps per smoothing (N_iter,max)",
                                 "PffPressureMG", mg->opt.adaptiveSteps, &mg->opt.adaptiveSteps, NULL, 1));
  PetscCall(PffOptionsBoundedInt("-pffmg_sweeps", "Pre- and post-sweeps when adaptive relaxation is off",
                                 "PffPressureMG", mg->opt.sweeps, &mg->opt.sweeps, NULL, 1));
  PetscCall(PffOptionsReal("-pffmg_omega", "Relaxation weight omega (6/7 is optimal in 3D)", "PffPressureMG",
                           mg->opt.omega, &mg->opt.omega, NULL));
  PetscCall(PffOptionsReal("-pffmg_theta_sigmas", "theta = 10^(mean + this x sd) of log10 block residual maxima",
                           "PffPressureMG", mg->opt.thetaSigmas, &mg->opt.thetaSigmas, NULL));
  PetscCall(PffOptionsBoundedInt("-pffmg_max_levels", "Most multigrid levels (the last is solved directly)",
                                 "PffPressureMG", mg->opt.maxLevels, &mg->opt.maxLevels, NULL, 1));
  PetscCall(PffOptionsReal("-pffmg_correction",
                           "Scale of the coarse-grid correction (piecewise-constant Galerkin is twice too stiff)",
                           "PffPressureMG", mg->opt.correction, &mg->opt.correction, NULL));
  PetscCall(PffOptionsBool("-pffmg_rescale",
                           "Coarse coefficients consistent with the coarse discretisation (false: plain P^T A P)",
                           "PffPressureMG", mg->opt.rescale, &mg->opt.rescale, NULL));
  PetscCall(PffOptionsBoundedInt("-pffmg_kcycle", "Flexible-CG steps per coarse correction (K-cycle); 0: V-cycle",
                                 "PffPressureMG", mg->opt.kcycleIts, &mg->opt.kcycleIts, NULL, 0));
  PetscCall(
      PffOptionsReal("-pffmg_kcycle_rtol",
                     "A coarse correction stops when its residual falls by this factor (0: always -pffmg_kcycle steps)",
                     "PffPressureMG", mg->opt.kcycleRtol, &mg->opt.kcycleRtol, NULL));
  PetscCall(
      PffOptionsReal("-pffmg_kcycle_ratio",
                     "K-cycle only on levels with at most 1/ratio of the rows of the level above (others: V-cycle)",
                     "PffPressureMG", mg->opt.kcycleRatio, &mg->opt.kcycleRatio, NULL));
  PetscCall(PffOptionsBoundedInt("-pffmg_coarse_max",
                                 "Uniform coarse levels below the block raster until at most this many cells",
                                 "PffPressureMG", mg->opt.coarseMax, &mg->opt.coarseMax, NULL, 1));
  PetscCall(PffOptionsBoundedInt("-pffmg_omp_min_rows",
                                 "Fewest rows per rank on a level for its smoothing and products to use OpenMP threads",
                                 "PffPressureMG", mg->opt.ompMinRows, &mg->opt.ompMinRows, NULL, 0));
  PetscOptionsEnd();
  PetscCheck(mg->opt.omega > 0 && mg->opt.omega < 2, mg->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-pressure_pffmg_omega %g is invalid: must lie in (0, 2)", (double)mg->opt.omega);
  PetscCheck(mg->opt.kcycleRtol >= 0 && mg->opt.kcycleRtol < 1, mg->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-pressure_pffmg_kcycle_rtol %g is invalid: must lie in [0, 1)", (double)mg->opt.kcycleRtol);
  PetscCheck(mg->opt.kcycleRatio >= 0, mg->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-pressure_pffmg_kcycle_ratio %g is invalid: must be >= 0 (0: the K-cycle on every level)",
             (double)mg->opt.kcycleRatio);
  PetscCall(KSPSetFromOptions(mg->coarse));
  mg->optionsRead = PETSC_TRUE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffPressureGetMG(PffPressure ps, PffMG **mg)
{
  PC pc;

  PetscFunctionBeginUser;
  PetscCheck(ps != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "pressure: NULL object");
  PetscCall(KSPGetPC(ps->ksp, &pc));
  PetscCall(PffMGGetContext(pc, mg));
  PetscCheck((*mg)->built, ps->comm, PETSC_ERR_ORDER, "pffmg: the hierarchy exists after the first solve or KSPSetUp");
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureMGGetStats(PffPressure ps, PffMGStats *stats)
{
  PffMG         *mg;
  PetscInt64     sum[3], mx;
  PetscLogDouble bytes[2];

  PetscFunctionBeginUser;
  PetscCall(PffPressureGetMG(ps, &mg));
  *stats = mg->stats;
  sum[0] = mg->stats.blockRelaxations;
  sum[1] = mg->stats.cellUpdates;
  sum[2] = mg->stats.cellVisits;
  PetscCallMPI(MPIU_Allreduce(MPI_IN_PLACE, sum, 3, MPIU_INT64, MPI_SUM, mg->comm));
  PetscCallMPI(MPIU_Allreduce(&mg->stats.cellUpdates, &mx, 1, MPIU_INT64, MPI_MAX, mg->comm));
  stats->blockRelaxations = sum[0];
  stats->cellUpdates      = sum[1];
  stats->cellUpdatesMax   = mx;
  stats->cellVisits       = sum[2];
  bytes[0]                = mg->stats.bytesTransfer;
  bytes[1]                = mg->stats.bytesKCycle;
  PetscCallMPI(MPIU_Allreduce(MPI_IN_PLACE, bytes, 2, MPIU_PETSCLOGDOUBLE, MPI_SUM, mg->comm));
  stats->bytesTransfer = bytes[0];
  stats->bytesKCycle   = bytes[1];
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureMGResetStats(PffPressure ps)
{
  PffMG *mg;

  PetscFunctionBeginUser;
  PetscCall(PffPressureGetMG(ps, &mg));
  mg->stats.applications = mg->stats.blockRelaxations = mg->stats.cellUpdates = mg->stats.cellVisits =
      mg->stats.adaptiveSteps                                                 = 0;
  mg->stats.bytesTransfer = mg->stats.bytesKCycle = 0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureMGGetLevel(PffPressure ps, PetscInt L, Mat *A, Mat *P)
{
  PffMG *mg;

  PetscFunctionBeginUser;
  PetscCall(PffPressureGetMG(ps, &mg));
  PetscCheck(L >= 0 && L < mg->nlevels, ps->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "pffmg: level %" PetscInt_FMT " does not exist (%" PetscInt_FMT " levels)", L, mg->nlevels);
  if (A && mg->lev[L].mf) {
    PetscCall(PffMGStencilAssemble_Private(mg, L, &mg->lev[L].st->Aview));
    *A = mg->lev[L].st->Aview;
  } else if (A)
    *A = mg->lev[L].A;
  if (P && mg->lev[L].P == NULL && L + 1 < mg->nlevels) PetscCall(PffMGBuildProlongation_Private(mg, L));
  if (P) *P = mg->lev[L].P;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureMGSmooth(PffPressure ps, PetscInt L, Vec b, Vec x, PetscInt sweeps)
{
  PffMG *mg;

  PetscFunctionBeginUser;
  PetscCall(PffPressureGetMG(ps, &mg));
  PetscCheck(L >= 0 && L + 1 < mg->nlevels, ps->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "pffmg: level %" PetscInt_FMT " has no smoother (%" PetscInt_FMT " levels)", L, mg->nlevels);
  if (sweeps > 0)
    PetscCall(PffMGSmoothFixed_Private(mg, L, b, x, sweeps));
  else
    PetscCall(PffMGSmooth_Private(mg, L, b, x));
  PetscFunctionReturn(PETSC_SUCCESS);
}
