/* One progress line per step: step, simulated time, wall time per step and an ETA from the mean
   rate so far (simulated time when an end time is known, step count otherwise). */
#include <pff.h>

PetscErrorCode PffProgressStart(PffProgress *p, PetscReal tend, PetscInt nsteps)
{
  PetscFunctionBeginUser;
  PetscCall(PetscTime(&p->start));
  p->last   = p->start;
  p->tend   = tend;
  p->nsteps = nsteps;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffProgressPrint(MPI_Comm comm, PffProgress *p, PetscInt step, PetscReal t, const char extra[])
{
  PetscLogDouble now;
  double         eta = -1.0;

  PetscFunctionBeginUser;
  PetscCall(PetscTime(&now));
  const double elapsed = now - p->start, wstep = now - p->last;
  p->last = now;
  if (p->tend > 0 && t > 0)
    eta = elapsed * (double)((p->tend - t) / t);
  else if (p->nsteps > 0 && step > 0)
    eta = elapsed * (double)(p->nsteps - step) / (double)step;
  if (eta < 0) eta = 0;
  PetscCall(PetscPrintf(comm, "step %6" PetscInt_FMT "  t %.6e  wall/step %.3e s  elapsed %.1f s  ETA %.1f s%s%s\n",
                        step, (double)t, wstep, elapsed, eta, extra ? "  " : "", extra ? extra : ""));
  PetscFunctionReturn(PETSC_SUCCESS);
}
