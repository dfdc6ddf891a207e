/* pressure: interface of the two-phase pressure projection (PF-FLIP Sec. 3.5, Eq. 8-10).

   Stage "Pressure" of the time step: SetUp once per grid topology (face list, gradient G, the
   operator pattern, Vecs and the Krylov solver), SetCoefficients once per step (beta = 1/rho and the
   open mask from face channels, A = G^T diag(M beta open) G plus the Dirichlet wall terms), Project
   (rhs from V D u*, KSP solve, u <- u* - dt beta G p). The KSP applies A or its matrix-free twin (shell.c,
   -pressure_operator) and preconditions with A. Closed boxes and periodic axes leave A singular
   with the constants as null space: it is attached to A and removed from the rhs. A Dirichlet wall
   (p = 0, PffPressureSetDirichletWalls) makes A definite, and then no null space is attached. */
#include "pressureimpl.h"

const char *const PffPressureAssemblyTypes[] = {"ptap", "direct", "PffPressureAssemblyType", "PFF_PRESSURE_ASSEMBLY_",
                                                NULL};
const char *const PffPressureFailureTypes[] = {"stop", "warn", "PffPressureFailureType", "PFF_PRESSURE_FAILURE_", NULL};
const char *const PffPressureOperatorTypes[] = {"aij", "shell", "PffPressureOperatorType", "PFF_PRESSURE_OPERATOR_",
                                                NULL};

#define PFF_PRESSURE_KSP_TYPE_DEFAULT KSPFCG
#define PFF_PRESSURE_FCG_NPREALLOC_DEFAULT 3
#define PFF_PRESSURE_PC_TYPE_DEFAULT "pffmg"
#define PFF_PRESSURE_RTOL_DEFAULT 1e-4
#define PFF_PRESSURE_ASSEMBLY_DEFAULT PFF_PRESSURE_ASSEMBLY_PTAP
#define PFF_PRESSURE_OPERATOR_DEFAULT PFF_PRESSURE_OPERATOR_AIJ

/* Names of the six domain walls in the order of PffPressureSetDirichletWalls. */
static const char *const PffWallNames[6] = {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"};

PetscErrorCode PffPressureCreate(PffGrid grid, PffPressure *ps)
{
  PffPressure p;
  PC          pc;

  PetscFunctionBeginUser;
  PetscCheck(ps != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "pressure: NULL output argument");
  PetscCheck(grid != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "pressure: NULL grid");
  PetscCall(PffGridGetRaster(grid, NULL, NULL, NULL)); /* errors unless the grid is set up */
  PetscCall(PffPressureMGRegister_Private());
  PetscCall(PetscNew(&p));
  p->grid         = grid;
  p->assembly     = PFF_PRESSURE_ASSEMBLY_DEFAULT;
  p->operatorType = PFF_PRESSURE_OPERATOR_DEFAULT;
  PetscCall(PffGridGetComm(grid, &p->comm));
  PetscCall(KSPCreate(p->comm, &p->ksp));
  PetscCall(KSPSetOptionsPrefix(p->ksp, "pressure_"));
  PetscCall(KSPSetType(p->ksp, PFF_PRESSURE_KSP_TYPE_DEFAULT));
  /* FCG's directions (16 B per cell each) as the iterations need them, in PETSc's chunks of 5, instead of 10 up
     front: 8 for up to 8 iterations */
  PetscCall(KSPFCGSetNprealloc(p->ksp, PFF_PRESSURE_FCG_NPREALLOC_DEFAULT));
  PetscCall(KSPSetTolerances(p->ksp, PFF_PRESSURE_RTOL_DEFAULT, PETSC_DEFAULT, PETSC_DEFAULT, PETSC_DEFAULT));
  PetscCall(KSPSetInitialGuessNonzero(p->ksp, PETSC_TRUE));
  /* rtol then bounds the true residual V (D u + c_div) / dt, whatever the PC */
  PetscCall(KSPSetNormType(p->ksp, KSP_NORM_UNPRECONDITIONED));
  PetscCall(KSPGetPC(p->ksp, &pc));
  PetscCall(PffPressureMGComposePressure_Private(pc, p));
  PetscCall(PCSetType(pc, PFF_PRESSURE_PC_TYPE_DEFAULT));
  *ps = p;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* PETSc takes nan, negative and out-of-range tolerances here without a word (a negative rtol means
   "default", a nan one never converges), and its parser does not name the key of a non-number. */
static PetscErrorCode PffPressureCheckKSPOptions(MPI_Comm comm)
{
  PetscFunctionBeginUser;
  PetscCall(PffOptionsCheckReal(comm, "-pressure_ksp_rtol", 0, 1, PETSC_TRUE, "in (0, 1)"));
  PetscCall(PffOptionsCheckReal(comm, "-pressure_ksp_atol", 0, PETSC_MAX_REAL, PETSC_FALSE, ">= 0"));
  PetscCall(PffOptionsCheckReal(comm, "-pressure_ksp_divtol", 1, PETSC_MAX_REAL, PETSC_TRUE, "> 1"));
  PetscCall(PffOptionsCheckInt(comm, "-pressure_ksp_max_it", 1, PETSC_MAX_INT));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureSetFromOptions(PffPressure ps)
{
  char     *names[7] = {NULL};
  PetscInt  nnames   = 7;
  PetscBool set, opset = PETSC_FALSE,
                 walls[6] = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE, PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};

  PetscFunctionBeginUser;
  PetscOptionsBegin(ps->comm, NULL, "Pressure projection", "PffPressure");
  PetscCall(PffOptionsEnum("-pressure_assembly", "Assembly of A = G^T W G", "PffPressureSetCoefficients",
                           PffPressureAssemblyTypes, (PetscEnum)ps->assembly, (PetscEnum *)&ps->assembly, NULL));
  PetscCall(PetscOptionsStringArray("-pressure_dirichlet_walls",
                                    "Walls with p = 0: none or a list of xmin,xmax,ymin,ymax,zmin,zmax",
                                    "PffPressureSetDirichletWalls", names, &nnames, &set));
  PetscCall(PffOptionsEnum(
      "-pressure_on_failure", "When a solve does not converge: stop the run with its reason, or warn and go on",
      "PffPressureCheckSolve", PffPressureFailureTypes, (PetscEnum)ps->onFailure, (PetscEnum *)&ps->onFailure, NULL));
  PetscCall(PffOptionsEnum("-pressure_operator",
                           "Operator the Krylov method applies: assembled AIJ or matrix-free shell (default: shell "
                           "under the matrix-free pffmg, aij with any other PC)",
                           "PffPressureSetOperatorType", PffPressureOperatorTypes, (PetscEnum)ps->operatorType,
                           (PetscEnum *)&ps->operatorType, &opset));
  PetscCall(PetscOptionsBool("-pressure_monitor_divergence", "Measure max |div u| before and after each projection",
                             "PffPressureSetMonitorDivergence", ps->monitorDivergence, &ps->monitorDivergence, NULL));
  PetscOptionsEnd();
  if (opset) ps->operatorTypeSet = PETSC_TRUE;
  /* parsed after the options block, so that a bad name leaves the options object closed */
  if (set) {
    PetscInt bad = -1;
    for (PetscInt q = 0; q < nnames; q++) {
      PetscBool none, found = PETSC_FALSE;
      PetscCall(PetscStrcasecmp(names[q], "none", &none));
      for (PetscInt w = 0; w < 6 && !none && !found; w++) {
        PetscCall(PetscStrcasecmp(names[q], PffWallNames[w], &found));
        if (found) walls[w] = PETSC_TRUE;
      }
      if (!none && !found && bad < 0) bad = q;
    }
    if (bad >= 0) {
      char name[64];
      PetscCall(PetscStrncpy(name, names[bad], sizeof(name)));
      for (PetscInt q = 0; q < nnames; q++) PetscCall(PetscFree(names[q]));
      SETERRQ(ps->comm, PETSC_ERR_ARG_UNKNOWN_TYPE,
              "pressure: -pressure_dirichlet_walls: unknown wall '%s' (use none or xmin,xmax,ymin,ymax,zmin,zmax)",
              name);
    }
    for (PetscInt q = 0; q < nnames; q++) PetscCall(PetscFree(names[q]));
    PetscCall(PffPressureSetDirichletWalls(ps, walls));
  }
  PetscCall(PffPressureCheckKSPOptions(ps->comm));
  PetscCall(KSPSetFromOptions(ps->ksp));
  {
    PC        pc;
    PetscBool mg;
    PetscCall(KSPGetPC(ps->ksp, &pc));
    PetscCall(PffPressureMGIsActive_Private(pc, &mg));
    if (mg) PetscCall(PffPressureMGSetFromOptions_Private(pc));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureSetDirichletWalls(PffPressure ps, const PetscBool walls[6])
{
  PetscBool periodic[3];

  PetscFunctionBeginUser;
  PetscCheck(ps != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "pressure: NULL object");
  PetscCheck(walls != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "pressure: NULL walls argument");
  PetscCall(PffGridGetSizes(ps->grid, NULL, NULL, NULL, NULL, periodic));
  for (PetscInt w = 0; w < 6; w++)
    PetscCheck(!walls[w] || !periodic[w / 2], ps->comm, PETSC_ERR_ARG_INCOMP,
               "pressure: Dirichlet wall %s on the periodic axis %c", PffWallNames[w], (char)('x' + w / 2));
  for (PetscInt w = 0; w < 6; w++) ps->dirichlet[w] = walls[w] ? PETSC_TRUE : PETSC_FALSE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureGetDirichletWalls(PffPressure ps, PetscBool walls[6])
{
  PetscFunctionBeginUser;
  PetscCheck(ps != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "pressure: NULL object");
  for (PetscInt w = 0; w < 6; w++) walls[w] = ps->dirichlet[w];
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureSetUp(PffPressure ps)
{
  PetscFunctionBeginUser;
  if (ps->setup) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscLogEventBegin(PFF_PressSetUp, 0, 0, 0, 0));
  PetscCall(PffPressureBuildFaces_Private(ps));
  PetscCall(VecCreateMPI(ps->comm, ps->ncells, ps->ntotal, &ps->p));
  PetscCall(VecCreateSeq(PETSC_COMM_SELF, 3 * ps->ncells, &ps->uf)); /* faces are numbered per rank only */
  PetscCall(VecDuplicate(ps->p, &ps->b));
  PetscCall(VecDuplicate(ps->p, &ps->vcell));
  PetscCall(VecDuplicate(ps->p, &ps->diag));
  /* the shell holds the face coefficients and the face lists of the divergence and gradient */
  PetscCall(PffPressureShellCreate_Private(ps, &ps->S));
  PetscCall(PffPressureShellGetCoefficients_Private(ps->S, &ps->cf));
  PetscCall(PffGridGetTopologyState(ps->grid, &ps->topology));
  ps->setup = PETSC_TRUE;
  PetscCall(PetscLogEventEnd(PFF_PressSetUp, 0, 0, 0, 0));
  PetscCall(PetscInfo(NULL,
                      "pressure: %" PetscInt_FMT " cells; faces interior %" PetscInt64_FMT " same %" PetscInt64_FMT
                      " coarser %" PetscInt64_FMT " finer %" PetscInt64_FMT " wall %" PetscInt64_FMT
                      " inactive %" PetscInt64_FMT "\n",
                      ps->ntotal, ps->nkind[0], ps->nkind[1], ps->nkind[2], ps->nkind[3], ps->nkind[4], ps->nkind[5]));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Everything derived from the grid's topology; the KSP keeps its type and options. */
static PetscErrorCode PffPressureFreeTopology(PffPressure p)
{
  PetscFunctionBeginUser;
  PetscCall(MatNullSpaceDestroy(&p->nullsp));
  PetscCall(MatDestroy(&p->A));
  PetscCall(MatDestroy(&p->S));
  PetscCall(MatDestroy(&p->W));
  PetscCall(MatDestroy(&p->G));
  PetscCall(VecDestroy(&p->w));
  PetscCall(VecDestroy(&p->p));
  PetscCall(VecDestroy(&p->b));
  PetscCall(VecDestroy(&p->vcell));
  PetscCall(VecDestroy(&p->diag));
  PetscCall(VecDestroy(&p->dirdiag));
  PetscCall(VecDestroy(&p->uf));
  PetscCall(PetscFree(p->blockStart));
  PetscCall(PetscFree(p->kind));
  PetscCall(PetscFree(p->lower));
  PetscCall(PetscFree(p->lower4));
  PetscCall(PetscFree(p->hblock));
  p->cf = NULL; /* the shell's */
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureReset(PffPressure ps)
{
  PetscFunctionBeginUser;
  PetscCheck(ps != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "pressure: NULL object");
  if (!ps->setup) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(KSPReset(ps->ksp)); /* operators of another size follow; pffmg rebuilds its levels (mg.c) */
  {
    /* PETSc 3.18's FCG has no reset: its direction vectors keep the old size. A fresh implementation,
       with the settings of the old one, drops them. */
    PetscBool isfcg;
    PetscCall(PetscObjectTypeCompare((PetscObject)ps->ksp, KSPFCG, &isfcg));
    if (isfcg) {
      PetscInt             mmax, nprealloc;
      KSPFCDTruncationType trunc;
      PetscCall(KSPFCGGetMmax(ps->ksp, &mmax));
      PetscCall(KSPFCGGetNprealloc(ps->ksp, &nprealloc));
      PetscCall(KSPFCGGetTruncationType(ps->ksp, &trunc));
      PetscCall(KSPSetType(ps->ksp, KSPCG));
      PetscCall(KSPSetType(ps->ksp, KSPFCG));
      PetscCall(KSPFCGSetMmax(ps->ksp, mmax));
      PetscCall(KSPFCGSetNprealloc(ps->ksp, nprealloc));
      PetscCall(KSPFCGSetTruncationType(ps->ksp, trunc));
    }
  }
  PetscCall(PffPressureFreeTopology(ps));
  ps->setup = ps->coefficientsSet = ps->subPCDefaultApplied = PETSC_FALSE;
  PetscCall(PetscInfo(NULL, "pressure: reset after a grid topology change\n"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureDestroy(PffPressure *ps)
{
  PetscFunctionBeginUser;
  if (ps == NULL || *ps == NULL) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(KSPDestroy(&(*ps)->ksp));
  PetscCall(PffPressureFreeTopology(*ps));
  PetscCall(PetscFree(*ps));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* After a topology change the pressure sets itself up again (the coefficients are then to be set again).
   Every caller is collective. */
static PetscErrorCode PffPressureCheckSetUp(PffPressure ps, PetscBool coefficients)
{
  PetscObjectState state;

  PetscFunctionBeginUser;
  PetscCheck(ps != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "pressure: NULL object");
  PetscCall(PffGridGetTopologyState(ps->grid, &state));
  if (ps->setup && state != ps->topology) {
    PetscCall(PffPressureReset(ps));
    PetscCall(PffPressureSetUp(ps));
  }
  PetscCheck(ps->setup, ps->comm, PETSC_ERR_ORDER, "pressure: call PffPressureSetUp() first");
  PetscCheck(!coefficients || ps->coefficientsSet, ps->comm, PETSC_ERR_ORDER,
             "pressure: call PffPressureSetCoefficients() first");
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureSetCoefficients(PffPressure ps, PetscInt chBeta, PetscInt chOpen)
{
  PC        pc;
  PetscBool stencilPC, needA;

  PetscFunctionBeginUser;
  PetscCall(PffPressureCheckSetUp(ps, PETSC_FALSE));
  PetscCall(PetscLogEventBegin(PFF_PressAssemble, 0, 0, 0, 0));
  /* The matrix-free pffmg needs no entries: then the Krylov method applies the shell too (unless the
     user chose aij), and A is assembled only if something asks for it (PffPressureGetOperator) */
  PetscCall(KSPGetPC(ps->ksp, &pc));
  PetscCall(PffPressureMGUsesStencil_Private(pc, &stencilPC));
  if (!ps->operatorTypeSet) ps->operatorType = stencilPC ? PFF_PRESSURE_OPERATOR_SHELL : PFF_PRESSURE_OPERATOR_AIJ;
  needA = (PetscBool)(ps->operatorType == PFF_PRESSURE_OPERATOR_AIJ || !stencilPC);
  if (needA) PetscCall(PffPressureCreateOperator_Private(ps));
  PetscCall(PffPressureAssemble_Private(ps, chBeta, chOpen));
  PetscCall(PffPressureShellUpdate_Private(ps, ps->S));
  if (!ps->A) { /* diagonal and null space from the faces */
    PetscCall(PffPressureShellFaceDiagonal_Private(ps->S, ps->diag));
    if (ps->dirdiag) PetscCall(VecAXPY(ps->diag, 1.0, ps->dirdiag));
    PetscCall(PffPressureNullSpace_Private(ps));
    PetscCall(MatSetNullSpace(ps->S, ps->nullsp));
  }
  {
    Mat Amat = ps->operatorType == PFF_PRESSURE_OPERATOR_SHELL ? ps->S : ps->A;
    PetscCall(KSPSetOperators(ps->ksp, Amat, stencilPC ? Amat : ps->A));
  }
  ps->coefficientsSet = PETSC_TRUE;
  PetscCall(PetscLogEventEnd(PFF_PressAssemble, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Block Jacobi: ICC(0) on the blocks unless the user chose -pressure_sub_pc_type (needs the sub-KSPs,
   which exist after PCSetUp and are set up at the first solve). */
PetscErrorCode PffKSPDefaultSubICC(KSP ksp, const char prefix[])
{
  PC        pc;
  PetscBool isbjacobi, userSet;

  PetscFunctionBeginUser;
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PetscObjectTypeCompare((PetscObject)pc, PCBJACOBI, &isbjacobi));
  PetscCall(PetscOptionsHasName(NULL, prefix, "-sub_pc_type", &userSet));
  if (isbjacobi && !userSet) {
    KSP     *sub;
    PetscInt nsub;
    PetscCall(PCBJacobiGetSubKSP(pc, &nsub, NULL, &sub));
    for (PetscInt s = 0; s < nsub; s++) {
      PC subpc;
      PetscCall(KSPGetPC(sub[s], &subpc));
      PetscCall(PCSetType(subpc, PCICC));
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffPressureApplySubPCDefault(PffPressure ps)
{
  PetscFunctionBeginUser;
  if (ps->subPCDefaultApplied) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PffKSPDefaultSubICC(ps->ksp, "pressure_"));
  ps->subPCDefaultApplied = PETSC_TRUE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The projection of PffPressureProject, from u* in chU or, with fromRest, from u* = 0 (chU only written). */
static PetscErrorCode PffPressureProjectFrom(PffPressure ps, PetscInt chU, PetscBool fromRest, PetscReal dt,
                                             PetscInt chCdiv, PetscInt chP, PffPressureStats *stats)
{
  PffPressureStats st = {0};
  PetscLogDouble   t0, t1, t2;
  PetscReal        bnorm, rnorm;

  PetscFunctionBeginUser;
  PetscCall(PffPressureCheckSetUp(ps, PETSC_TRUE));
  PetscCheck(dt > 0 && PetscIsNormalReal(dt), ps->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "pressure: time step dt = %g must be positive", (double)dt);
  PetscCheck(!fromRest || chCdiv >= 0, ps->comm, PETSC_ERR_ARG_WRONG, "pressure: a projection from rest needs c_div");
  PetscCall(PetscLogEventBegin(PFF_PressSolve, 0, 0, 0, 0));
  st.divBefore = st.divAfter = -1;
  if (fromRest) {
    PetscCall(VecZeroEntries(ps->uf)); /* the divergence of u* = 0 is 0: b below reads no vcell */
    if (ps->monitorDivergence) st.divBefore = 0;
  } else {
    PetscCall(PffPressureChannelToVec_Private(ps, chU, PFF_CHANNEL_FACE, ps->uf));
    if (ps->monitorDivergence) PetscCall(PffPressureMaxDivergenceVec_Private(ps, ps->uf, &st.divBefore));
    /* b = -(V D u*_open + V c_div) / dt = (G^T M (open u*) - V c_div) / dt; closed faces end at u = 0,
       so their u* must not enter the balance */
    PetscCall(PffPressureShellDivergence_Private(ps, ps->S, ps->uf, PETSC_TRUE, ps->vcell));
  }
  if (chCdiv >= 0) {
    PetscScalar       *b;
    const PetscScalar *y = NULL;
    PetscCall(PffPressureChannelToVec_Private(ps, chCdiv, PFF_CHANNEL_CELL, ps->b));
    PetscCall(VecGetArray(ps->b, &b));
    if (!fromRest) PetscCall(VecGetArrayRead(ps->vcell, &y));
    for (PetscInt lb = 0; lb < ps->nlocal; lb++) {
      const PetscReal h = ps->hblock[lb], v = h * h * h;
      for (PetscInt c = ps->blockStart[lb]; c < ps->blockStart[lb + 1]; c++) b[c] = (fromRest ? 0 : y[c]) - v * b[c];
    }
    if (!fromRest) PetscCall(VecRestoreArrayRead(ps->vcell, &y));
    PetscCall(VecRestoreArray(ps->b, &b));
  } else
    PetscCall(VecCopy(ps->vcell, ps->b));
  PetscCall(VecScale(ps->b, 1.0 / dt));
  if (ps->nullsp) PetscCall(MatNullSpaceRemove(ps->nullsp, ps->b));

  PetscCall(PffPressureChannelToVec_Private(ps, chP, PFF_CHANNEL_CELL, ps->p));
  PetscCall(PetscTime(&t0));
  PetscCall(KSPSetUp(ps->ksp));
  PetscCall(PffPressureApplySubPCDefault(ps));
  PetscCall(KSPSetUpOnBlocks(ps->ksp));
  PetscCall(PetscTime(&t1));
  PetscCall(KSPSolve(ps->ksp, ps->b, ps->p));
  PetscCall(PetscTime(&t2));
  PetscCall(KSPGetIterationNumber(ps->ksp, &st.its));
  PetscCall(KSPGetConvergedReason(ps->ksp, &st.reason));
  /* true relative residual, whatever norm the KSP monitors, with the operator the KSP applied */
  PetscCall(MatMult(ps->operatorType == PFF_PRESSURE_OPERATOR_SHELL ? ps->S : ps->A, ps->p, ps->vcell));
  PetscCall(VecAYPX(ps->vcell, -1.0, ps->b));
  PetscCall(VecNorm(ps->vcell, NORM_2, &rnorm));
  PetscCall(VecNorm(ps->b, NORM_2, &bnorm));
  st.rnorm = bnorm > 0 ? rnorm / bnorm : rnorm;

  /* u = u* - dt beta G p on open faces, 0 on closed ones */
  PetscCall(PffPressureShellProjectVelocity_Private(ps, ps->S, ps->p, dt, ps->uf));
  if (ps->monitorDivergence) {
    PetscCall(PffPressureMaxDivergenceVec_Private(ps, ps->uf, &st.divAfter));
    PetscCall(PetscInfo(NULL, "pressure: max |div u| %g 1/s before the projection, %g after\n", (double)st.divBefore,
                        (double)st.divAfter));
  }
  PetscCall(PffPressureVecToChannel_Private(ps, ps->uf, PFF_CHANNEL_FACE, chU));
  PetscCall(PffPressureVecToChannel_Private(ps, ps->p, PFF_CHANNEL_CELL, chP));
  st.setupTime = t1 - t0;
  st.solveTime = t2 - t1;
  PetscCall(PetscLogEventEnd(PFF_PressSolve, 0, 0, 0, 0));
  if (stats) *stats = st;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureProject(PffPressure ps, PetscInt chU, PetscReal dt, PetscInt chCdiv, PetscInt chP,
                                  PffPressureStats *stats)
{
  PetscFunctionBeginUser;
  PetscCall(PffPressureProjectFrom(ps, chU, PETSC_FALSE, dt, chCdiv, chP, stats));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureProjectSource(PffPressure ps, PetscInt chU, PetscReal dt, PetscInt chCdiv, PetscInt chP,
                                        PffPressureStats *stats)
{
  PetscFunctionBeginUser;
  PetscCall(PffPressureProjectFrom(ps, chU, PETSC_TRUE, dt, chCdiv, chP, stats));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureMaxDivergence(PffPressure ps, PetscInt chU, PetscReal *maxdiv)
{
  PetscFunctionBeginUser;
  PetscCall(PffPressureCheckSetUp(ps, PETSC_FALSE));
  PetscCheck(maxdiv != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "pressure: NULL output argument");
  PetscCall(PffPressureChannelToVec_Private(ps, chU, PFF_CHANNEL_FACE, ps->uf));
  PetscCall(PffPressureMaxDivergenceVec_Private(ps, ps->uf, maxdiv));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureGetOperator(PffPressure ps, Mat *A)
{
  PetscFunctionBeginUser;
  PetscCall(PffPressureCheckSetUp(ps, PETSC_TRUE));
  if (ps->A == NULL) { /* assembled on demand, then kept current by every SetCoefficients */
    PetscCall(PffPressureCreateOperator_Private(ps));
    PetscCall(PffPressureAssembleOperator_Private(ps));
  }
  *A = ps->A;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureGetDiagonal(PffPressure ps, Vec *diag)
{
  PetscFunctionBeginUser;
  PetscCall(PffPressureCheckSetUp(ps, PETSC_TRUE));
  *diag = ps->diag;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureGetDirichletDiagonal(PffPressure ps, Vec *dirdiag)
{
  PetscFunctionBeginUser;
  PetscCall(PffPressureCheckSetUp(ps, PETSC_TRUE));
  if (!ps->dirdiag) { /* no Dirichlet wall: zero, made only when asked for */
    PetscCall(VecDuplicate(ps->p, &ps->dirdiag));
    PetscCall(VecSet(ps->dirdiag, 0.0));
  }
  *dirdiag = ps->dirdiag;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureGetFaceCoefficients(PffPressure ps, const PetscReal *cf[3])
{
  PetscFunctionBeginUser;
  PetscCall(PffPressureCheckSetUp(ps, PETSC_TRUE));
  PetscCheck(cf != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "pressure: NULL output argument");
  for (PetscInt d = 0; d < 3; d++) cf[d] = ps->cf + d * ps->ncells;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureGetShellOperator(PffPressure ps, Mat *S)
{
  PetscFunctionBeginUser;
  PetscCall(PffPressureCheckSetUp(ps, PETSC_TRUE));
  PetscCheck(S != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "pressure: NULL output argument");
  *S = ps->S;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureSetMonitorDivergence(PffPressure ps, PetscBool flg)
{
  PetscFunctionBeginUser;
  PetscCheck(ps != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "pressure: NULL object");
  ps->monitorDivergence = flg;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureSetOperatorType(PffPressure ps, PffPressureOperatorType type)
{
  PetscFunctionBeginUser;
  PetscCheck(ps != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "pressure: NULL object");
  PetscCheck(type == PFF_PRESSURE_OPERATOR_AIJ || type == PFF_PRESSURE_OPERATOR_SHELL, ps->comm,
             PETSC_ERR_ARG_OUTOFRANGE, "pressure: unknown operator type %d", (int)type);
  ps->operatorType    = type;
  ps->operatorTypeSet = PETSC_TRUE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureGetOperatorType(PffPressure ps, PffPressureOperatorType *type)
{
  PetscFunctionBeginUser;
  PetscCheck(ps != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "pressure: NULL object");
  PetscCheck(type != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "pressure: NULL output argument");
  *type = ps->operatorType;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureGetKSP(PffPressure ps, KSP *ksp)
{
  PetscFunctionBeginUser;
  PetscCheck(ps != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "pressure: NULL object");
  *ksp = ps->ksp;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureCheckSolve(PffPressure ps, const PffPressureStats *st, const char stage[], PetscInt step,
                                     PetscReal t, const char hint[])
{
  KSPType   ktype;
  PCType    ptype;
  PC        pc;
  PetscReal rtol;
  PetscInt  maxit;
  char      line[640];

  PetscFunctionBeginUser;
  const PetscBool finite = (PetscBool)!PetscIsInfOrNanReal(st->rnorm);
  if (st->reason >= 0 && finite) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(KSPGetType(ps->ksp, &ktype));
  PetscCall(KSPGetPC(ps->ksp, &pc));
  PetscCall(PCGetType(pc, &ptype));
  PetscCall(KSPGetTolerances(ps->ksp, &rtol, NULL, NULL, &maxit));
  PetscCall(PetscSNPrintf(
      line, sizeof(line),
      "step %" PetscInt_FMT " (t = %g): stage %s: the solve (KSP %s, PC %s) did not converge: %s after %" PetscInt_FMT
      " of %" PetscInt_FMT " iterations, relative residual %g (rtol %g); %s",
      step, (double)t, stage, ktype, ptype, st->reason < 0 ? KSPConvergedReasons[st->reason] : "non-finite residual",
      st->its, maxit, (double)st->rnorm, (double)rtol, hint));
  /* a non-finite iterate has spoilt the fields, whatever the policy */
  const PetscBool spoilt =
      (PetscBool)(!finite || st->reason == KSP_DIVERGED_NANORINF || st->reason == KSP_DIVERGED_PC_FAILED);
  PetscCheck(ps->onFailure == PFF_PRESSURE_FAILURE_WARN && !spoilt, ps->comm, PETSC_ERR_NOT_CONVERGED, "%s", line);
  PetscCall(PetscPrintf(ps->comm, "pfflip: warning: %s\n", line));
  PetscFunctionReturn(PETSC_SUCCESS);
}
