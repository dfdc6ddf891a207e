/* Unit test of the ETA of the progress line (core.h): PffProgressETA.

   Checks the rate extrapolated to the end time and to the step count, that the sooner of the two
   wins when both are known, that nothing is estimated before the first step, and that a clock
   started at a restart (t0 > 0, step0 > 0) uses the rate since the restart: a run restarted at
   t = 0.6 of 1.0 that took 10 s for 0.1 has 30 s left, not 10 * 0.3 / 0.7.

   Sample run:  ./test_progress
   Prints:      progress ok: <n> checks */
#include "pfftest.h"

static const char help[] = "ETA of the progress line.\n";

static PetscErrorCode CheckETA(PetscReal t0, PetscReal tend, PetscInt step0, PetscInt nsteps, PetscInt step,
                               PetscReal t, double elapsed, double expect, PetscInt *n)
{
  PffProgress p;

  PetscFunctionBeginUser;
  PetscCall(PffProgressStart(&p, t0, tend, step0, nsteps));
  const double eta = PffProgressETA(&p, step, t, elapsed);
  PetscCheck(PetscAbs(eta - expect) <= 1e-9 * PetscMax(1.0, PetscAbs(expect)), PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "ETA from t0 %g tend %g step0 %" PetscInt_FMT " nsteps %" PetscInt_FMT " at step %" PetscInt_FMT
             " t %g after %g s: %g, expected %g",
             (double)t0, (double)tend, step0, nsteps, step, (double)t, elapsed, eta, expect);
  (*n)++;
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  PetscInt n = 0;

  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(PffInitializePackage());
  /* from the start: by time, by steps, the sooner of the two */
  PetscCall(CheckETA(0, 2.0, 0, 0, 7, 0.5, 10, 30, &n));
  PetscCall(CheckETA(0, 0, 0, 100, 25, 0, 10, 30, &n));
  PetscCall(CheckETA(0, 2.0, 0, 100, 25, 0.5, 10, 30, &n));
  PetscCall(CheckETA(0, 2.0, 0, 50, 25, 0.5, 10, 10, &n));
  /* nothing to extrapolate from yet, or nothing known */
  PetscCall(CheckETA(0, 2.0, 0, 100, 0, 0, 0, -1, &n));
  PetscCall(CheckETA(0, 0, 0, 0, 10, 1.0, 10, -1, &n));
  /* past the end: no negative time left */
  PetscCall(CheckETA(0, 1.0, 0, 0, 10, 1.1, 10, 0, &n));
  /* restarted at t = 0.6, step 600: the rate since the restart */
  PetscCall(CheckETA(0.6, 1.0, 600, 0, 700, 0.7, 10, 30, &n));
  PetscCall(CheckETA(0.6, 0, 600, 1000, 700, 0.7, 10, 30, &n));
  PetscCall(CheckETA(0.6, 1.0, 600, 0, 600, 0.6, 0, -1, &n));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "progress ok: %" PetscInt_FMT " checks\n", n));
  PetscCall(PetscFinalize());
  return 0;
}
