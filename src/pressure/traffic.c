/* The memory traffic of a solve: the bytes its Krylov vectors and operator products must move, so that a benchmark
   can set an iteration's time against the time that traffic takes at the copy bandwidth (docs/pressure.md,
   "Memory traffic of an iteration"). It is a count, not a measurement: each operation reads and writes its arrays
   once, nothing stays in cache between operations. */
#include "pressureimpl.h"

/* Bytes moved by the vector operations of PETSc 3.18's KSPSolve_FCG (src/ksp/ksp/impls/fcg/fcg.c) over its
   iterations on vectors of nlocal entries, without the operator products and the PC, which their owners count. Per
   operation, in vector passes of 8 nlocal B: VecSet 1 (a zero initial guess, KSPSolve), VecCopy 2, VecAYPX 3, VecNorm
   1 (also |b| after a nonzero guess), VecMTDot against nd earlier directions nd + 1, VecMAXPY nd + 2, VecTDot 2,
   VecAXPY 3, VecScale 2. *known is false (and *bytes 0) for any other KSP type. */
PetscErrorCode PffPressureFCGBytes_Private(KSP ksp, PetscInt its, PetscInt nlocal, PetscLogDouble *bytes,
                                           PetscBool *known)
{
  PetscBool            isfcg, nonzero;
  KSPNormType          norm;
  KSPFCDTruncationType trunc;
  PetscInt             mmax, passes;

  PetscFunctionBeginUser;
  *bytes = 0;
  PetscCall(PetscObjectTypeCompare((PetscObject)ksp, KSPFCG, &isfcg));
  *known = isfcg;
  if (!isfcg || its <= 0) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(KSPGetInitialGuessNonzero(ksp, &nonzero));
  PetscCall(KSPGetNormType(ksp, &norm));
  PetscCall(KSPFCGGetMmax(ksp, &mmax));
  PetscCall(KSPFCGGetTruncationType(ksp, &trunc));
  /* the preconditioned and natural norms take a PC application to b in KSPConvergedDefault after a nonzero guess */
  if (nonzero && norm != KSP_NORM_UNPRECONDITIONED && norm != KSP_NORM_NONE) {
    *known = PETSC_FALSE;
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  const PetscInt nrm = norm == KSP_NORM_NONE ? 0 : (norm == KSP_NORM_UNPRECONDITIONED ? 1 : 2);
  /* r = b - A x (AYPX) and |b| for the relative tolerance (KSPConvergedDefault), or x = 0 and r = b; the first norm */
  passes = (nonzero ? 3 + nrm : 1 + 2) + nrm;
  for (PetscInt i = 0; i < its; i++) {
    /* the earlier directions it is orthogonalised against (KSPFCDGetNumOldDirections) */
    const PetscInt mi = trunc == KSP_FCD_TRUNC_TYPE_NOTAY ? (i > 0 ? (i - 1) % mmax + 1 : 0) : mmax;
    const PetscInt nd = PetscMin(i, mi);
    passes += 2 + (nd > 0 ? 2 * nd + 3 : 0) + 2 + 2 + 3 + 3 + nrm; /* p = z - ..., p.r, p.Ap, x and r updates */
    if (i < its - 1) passes += 2;                                  /* C scaled: every step but the last */
  }
  *bytes = 8.0 * (PetscLogDouble)passes * (PetscLogDouble)nlocal;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Bytes of one product with A on this rank: a MATSHELL moves shellRow bytes per row (its owner knows what it reads);
   an assembled matrix reads its values and column indices, its row pointers and x, and writes y. */
PetscErrorCode PffPressureProductBytes_Private(Mat A, PetscReal shellRow, PetscLogDouble *bytes)
{
  PetscBool isshell;
  PetscInt  m;

  PetscFunctionBeginUser;
  PetscCall(MatGetLocalSize(A, &m, NULL));
  PetscCall(PetscObjectTypeCompare((PetscObject)A, MATSHELL, &isshell));
  if (isshell)
    *bytes = shellRow * m;
  else {
    MatInfo info;
    PetscCall(MatGetInfo(A, MAT_LOCAL, &info));
    *bytes = (PetscLogDouble)info.nz_used * (sizeof(PetscScalar) + sizeof(PetscInt)) +
             (PetscLogDouble)m * (sizeof(PetscInt) + 8.0 + 8.0);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureGetSolveTraffic(PffPressure ps, const PffPressureStats *st, PetscLogDouble *bytes,
                                          PetscBool *known)
{
  Mat            A;
  PetscInt       m;
  PetscBool      nonzero;
  PetscLogDouble krylov = 0, product = 0;

  PetscFunctionBeginUser;
  PetscCheck(ps != NULL && st != NULL && bytes != NULL && known != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL,
             "pressure: NULL argument");
  PetscCheck(ps->setup, ps->comm, PETSC_ERR_ORDER, "pressure: no solve yet");
  PetscCall(KSPGetOperators(ps->ksp, &A, NULL));
  PetscCall(MatGetLocalSize(A, &m, NULL));
  PetscCall(PffPressureFCGBytes_Private(ps->ksp, st->its, m, &krylov, known));
  PetscCall(KSPGetInitialGuessNonzero(ps->ksp, &nonzero));
  /* the pressure shell reads x and its three double face coefficients and writes y */
  PetscCall(PffPressureProductBytes_Private(A, 8.0 + 3 * 8.0 + 8.0, &product));
  *bytes = krylov + (st->its + (nonzero ? 1 : 0)) * product;
  PetscCallMPI(MPIU_Allreduce(MPI_IN_PLACE, bytes, 1, MPIU_PETSCLOGDOUBLE, MPI_SUM, ps->comm));
  PetscCallMPI(MPIU_Allreduce(MPI_IN_PLACE, known, 1, MPIU_BOOL, MPI_LAND, ps->comm));
  if (!*known) *bytes = 0;
  PetscFunctionReturn(PETSC_SUCCESS);
}
