/* One progress line per step: step, simulated time, wall time per step and an ETA from the mean
   rate since the clock started (simulated time when an end time is known, step count otherwise).
   A restarted run counts from its restart point, not from t = 0. */
#include <pff.h>

PetscErrorCode PffProgressStart(PffProgress *p, PetscReal t0, PetscReal tend, PetscInt step0, PetscInt nsteps)
{
  PetscFunctionBeginUser;
  PetscCall(PetscTime(&p->start));
  p->last   = p->start;
  p->t0     = t0;
  p->tend   = tend;
  p->step0  = step0;
  p->nsteps = nsteps;
  PetscFunctionReturn(PETSC_SUCCESS);
}

double PffProgressETA(const PffProgress *p, PetscInt step, PetscReal t, double elapsed)
{
  double eta = PETSC_INFINITY;

  if (p->tend > 0 && t > p->t0) eta = elapsed * (double)((p->tend - t) / (t - p->t0));
  if (p->nsteps > 0 && step > p->step0)
    eta = PetscMin(eta, elapsed * (double)(p->nsteps - step) / (double)(step - p->step0));
  return eta == PETSC_INFINITY ? -1.0 : PetscMax(eta, 0.0);
}

PetscErrorCode PffProgressPrint(MPI_Comm comm, PffProgress *p, PetscInt step, PetscReal t, const char extra[])
{
  PetscLogDouble now;

  PetscFunctionBeginUser;
  PetscCall(PetscTime(&now));
  const double elapsed = now - p->start, wstep = now - p->last;
  const double eta = PetscMax(PffProgressETA(p, step, t, elapsed), 0.0);
  p->last          = now;
  PetscCall(PetscPrintf(comm, "step %6" PetscInt_FMT "  t %.6e  wall/step %.3e s  elapsed %.1f s  ETA %.1f s%s%s\n",
                        step, (double)t, wstep, elapsed, eta, extra ? "  " : "", extra ? extra : ""));
  PetscFunctionReturn(PETSC_SUCCESS);
}
