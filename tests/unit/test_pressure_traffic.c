/* The memory-traffic count of a solve (src/pressure/traffic.c, PffPressureGetSolveTraffic) against what PETSc itself
   logged: a Jacobi-preconditioned FCG solve on the matrix-free operator (a 32^3 box, random beta in [0.5, 1], a
   Dirichlet wall, so no null space) runs alone in a log stage, and the vector passes of every Vec event of that stage
   (the calls, and for VecMTDot and VecMAXPY the directions, from their logged flops) plus one product per logged
   MatMult must give the counted bytes exactly. This fails if PETSc's FCG does other operations than traffic.c assumes,
   for the default truncation (Notay's, 30 directions), for 2 directions (the truncation wraps) and the standard
   truncation from a nonzero guess (as the pressure module solves), and for a zero guess (as the K-cycle's solves);
   another KSP type must report the count as unknown. At 1, 2 and 4 ranks. Sample run: mpiexec -n 2
   ./test_pressure_traffic            prints one line per case on rank 0. */
#include "pfftest.h"

static PetscReal RandomBeta(const PetscReal x[3], PetscInt comp, void *vctx)
{
  const PffTestCtx *t = (const PffTestCtx *)vctx;
  return 0.5 + 0.5 * PffTestUniform01(PffTestPositionKey(t, x, comp, 7));
}

/* Passes of 8 B per local entry that the logged events of stage moved, and the logged MatMults. */
static PetscErrorCode LoggedPasses(PetscLogStage stage, PetscInt n, PetscLogDouble *passes, PetscInt *mults)
{
  const char *const  names[] = {"VecSet", "VecCopy", "VecAYPX", "VecNorm", "VecTDot", "VecAXPY", "VecScale"};
  const int          per[]   = {1, 2, 3, 1, 2, 3, 2};
  PetscLogEvent      id;
  PetscEventPerfInfo info;

  PetscFunctionBeginUser;
  *passes = 0;
  for (size_t k = 0; k < sizeof(per) / sizeof(per[0]); k++) {
    PetscCall(PetscLogEventGetId(names[k], &id));
    PetscCall(PetscLogEventGetPerfInfo(stage, id, &info));
    *passes += per[k] * (PetscLogDouble)info.count;
  }
  /* VecMTDot against nd vectors logs nd (2n - 1) flops and reads nd + 1 vectors; VecMAXPY logs 2 nd n flops and
     reads nd + 1 and writes one */
  PetscCall(PetscLogEventGetId("VecMTDot", &id));
  PetscCall(PetscLogEventGetPerfInfo(stage, id, &info));
  *passes += round(info.flops / (2.0 * n - 1)) + info.count;
  PetscCall(PetscLogEventGetId("VecMAXPY", &id));
  PetscCall(PetscLogEventGetPerfInfo(stage, id, &info));
  *passes += round(info.flops / (2.0 * n)) + 2.0 * info.count;
  PetscCall(PetscLogEventGetId("MatMult", &id));
  PetscCall(PetscLogEventGetPerfInfo(stage, id, &info));
  *mults = info.count;
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode TestCase(const PffTestCtx *t, PetscInt betaCh, const char *ksptype, PetscInt mmax,
                               KSPFCDTruncationType trunc, PetscBool zeroGuess, PetscInt icase)
{
  const PetscBool  walls[6] = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE, PETSC_FALSE, PETSC_FALSE, PETSC_TRUE};
  PffPressure      ps;
  PffPressureStats st = {0};
  KSP              ksp;
  PC               pc;
  Mat              A;
  Vec              b, x;
  PetscLogStage    stage;
  PetscLogDouble   counted, passes, logged;
  PetscInt         n, mults = 0;
  PetscBool        known;
  char             name[64];

  PetscFunctionBeginUser;
  PetscCall(PffPressureCreate(t->grid, &ps));
  PetscCall(PffPressureSetOperatorType(ps, PFF_PRESSURE_OPERATOR_SHELL));
  PetscCall(PffPressureSetDirichletWalls(ps, walls));
  PetscCall(PffPressureSetFromOptions(ps));
  PetscCall(PffPressureGetKSP(ps, &ksp));
  PetscCall(KSPSetType(ksp, ksptype));
  if (mmax > 0) {
    PetscCall(KSPFCGSetMmax(ksp, mmax));
    PetscCall(KSPFCGSetTruncationType(ksp, trunc));
  }
  PetscCall(KSPSetTolerances(ksp, 1e-6, 0.0, PETSC_DEFAULT, 500));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PCSetType(pc, PCJACOBI));
  PetscCall(PffPressureSetUp(ps));
  PetscCall(PffPressureSetCoefficients(ps, betaCh, -1));
  PetscCall(KSPGetOperators(ksp, &A, NULL));
  PetscCall(MatCreateVecs(A, &x, &b));
  PetscCall(VecSetRandom(b, NULL));
  /* a random guess, as the module's x copied from a channel is one to KSPSolve (a VecSet to 0 would make it zero) */
  PetscCall(VecSetRandom(x, NULL));
  if (zeroGuess) PetscCall(KSPSetInitialGuessNonzero(ksp, PETSC_FALSE));
  PetscCall(KSPSetUp(ksp));
  PetscCall(KSPSetUpOnBlocks(ksp));
  (void)snprintf(name, sizeof(name), "Traffic%d", (int)icase);
  PetscCall(PetscLogStageRegister(name, &stage));
  PetscCall(PetscLogStagePush(stage));
  PetscCall(KSPSolve(ksp, b, x));
  PetscCall(PetscLogStagePop());
  PetscCall(KSPGetIterationNumber(ksp, &st.its));
  PetscCall(KSPGetConvergedReason(ksp, &st.reason));
  PetscCheck(st.reason > 0, PETSC_COMM_WORLD, PETSC_ERR_NOT_CONVERGED, "%s: the solve did not converge (%s)", name,
             KSPConvergedReasons[st.reason]);
  PetscCall(PffPressureGetSolveTraffic(ps, &st, &counted, &known));
  PetscCall(VecGetLocalSize(x, &n));
  PetscCall(LoggedPasses(stage, n, &passes, &mults));
  /* the shell's product: x and three double face coefficients read, y written */
  logged = 8.0 * passes * n + (PetscLogDouble)mults * 40.0 * n;
  PetscCallMPI(MPIU_Allreduce(MPI_IN_PLACE, &logged, 1, MPIU_PETSCLOGDOUBLE, MPI_SUM, PETSC_COMM_WORLD));
  PetscCall(PetscPrintf(
      PETSC_COMM_WORLD,
      "%-5s mmax %2" PetscInt_FMT " %-8s %-13s its %3" PetscInt_FMT ": counted %.6e B, logged %.6e B%s\n", ksptype,
      mmax, mmax > 0 ? KSPFCDTruncationTypes[trunc] : "", zeroGuess ? "zero guess" : "nonzero guess", st.its,
      (double)counted, (double)logged, known ? "" : " (unknown: not FCG)"));
  if (strcmp(ksptype, KSPFCG) == 0)
    PetscCheck(known && PetscAbsReal(counted - logged) <= 1e-9 * logged, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
               "%s: the traffic count %.9e B differs from the logged operations' %.9e B", name, (double)counted,
               (double)logged);
  else
    PetscCheck(!known && counted == 0, PETSC_COMM_WORLD, PETSC_ERR_PLIB, "%s: a count for KSP %s", name, ksptype);
  PetscCall(VecDestroy(&x));
  PetscCall(VecDestroy(&b));
  PetscCall(PffPressureDestroy(&ps));
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  const PetscInt  nb[3]     = {2, 2, 2};
  const PetscBool per[3]    = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};
  const PetscReal origin[3] = {0, 0, 0};
  PffTestCtx      t;
  PetscInt        betaCh;

  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  PetscCall(PffInitializePackage());
  PetscCall(PetscLogDefaultBegin());
  PetscCall(PffTestCreateGrid(PETSC_COMM_WORLD, nb, per, origin, 1.0 / 32, 16, 1, 0, 0, 5, &t));
  PetscCall(PffGridAddChannel(t.grid, "beta", PFF_CHANNEL_FACE, 1, &betaCh));
  PetscCall(PffGridFillChannel(t.grid, betaCh, RandomBeta, &t));
  PetscCall(TestCase(&t, betaCh, KSPFCG, 0, KSP_FCD_TRUNC_TYPE_NOTAY, PETSC_FALSE, 0));
  PetscCall(TestCase(&t, betaCh, KSPFCG, 2, KSP_FCD_TRUNC_TYPE_NOTAY, PETSC_FALSE, 1));
  PetscCall(TestCase(&t, betaCh, KSPFCG, 4, KSP_FCD_TRUNC_TYPE_STANDARD, PETSC_FALSE, 2));
  PetscCall(TestCase(&t, betaCh, KSPFCG, 3, KSP_FCD_TRUNC_TYPE_NOTAY, PETSC_TRUE, 3)); /* as the K-cycle's solves */
  PetscCall(TestCase(&t, betaCh, KSPCG, 0, KSP_FCD_TRUNC_TYPE_NOTAY, PETSC_FALSE, 4));
  PetscCall(PffGridDestroy(&t.grid));
  PetscCall(PetscFinalize());
  return 0;
}
