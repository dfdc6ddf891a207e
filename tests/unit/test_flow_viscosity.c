/* Unit test of the viscosity of the PF-FLIP step (Eq. 13, Sec. 5.3): a decaying shear wave.

   A fully periodic 16^3 box of one fluid (no gravity) starts with v_x = U sin(2 pi y). The Stokes
   solution decays as exp(-nu k^2 t), k = 2 pi. The amplitude is measured on the particles,
   A = 2 sum_p v_x sin(2 pi y_p) / N, at the end; the effective viscosity is
   nu_eff = -log(A(T) / A(0)) / (k^2 T), k = 2 pi m. nu = 1/256 and h = 1/16 are the rt3d values at
   W = 16 cells. Two cases:
     - the step of the viscous limit h^2 / (6 nu): alpha = 0, pure PIC (rt3d at W >= 32 runs so);
     - -flow_dt_max slightly below h^2 / (12 nu) (alpha ~ 1/2), whose steps would leave a sliver
       step of 2e-6 before t_end; without the even split of the time to the next output that sliver
       made the run blow up (c_div / dt kept on the particles by alpha ~ 1).
   Each case prints nu_eff / nu and fails outside [-nu_min, -nu_max] (defaults 0.7, 1.1: Eq. 13 with
   our kernel of radius h gives 0.77 for pure PIC, see docs/flow.md). -mode m, -t_end and the flow
   options change the set-up; -verbose prints every step.

   Sample run:  mpiexec -n 2 ./test_flow_viscosity
   Prints two lines (the same on any number of ranks). */
#include <pff.h>

static const char help[] = "Decay of a shear wave: the viscosity of the FLIP/PIC blend.\n";

#define U0 0.01

static PetscReal Mode = 1; /* wavenumber k = 2 pi Mode */

static PetscErrorCode SeedShear(const PetscReal x[3], PetscInt *type, PetscReal v[3], void *ctx)
{
  PetscFunctionBeginUser;
  (void)ctx;
  *type = PFF_PARTICLE_LIQUID;
  v[0]  = U0 * PetscSinReal(2 * PETSC_PI * Mode * x[1]);
  v[1] = v[2] = 0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode Amplitude(PffFlow f, MPI_Comm comm, PetscReal *amp)
{
  PffParticles      p;
  PffParticleArrays a;
  PetscReal         s[2] = {0, 0};

  PetscFunctionBeginUser;
  PetscCall(PffFlowGetParticles(f, &p));
  PetscCall(PffParticlesGetArrays(p, &a));
  for (PetscInt i = 0; i < a.n; i++) {
    s[0] += a.v[3 * i] * PetscSinReal(2 * PETSC_PI * Mode * a.x[3 * i + 1]);
    s[1] += 1;
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, s, 2, MPIU_REAL, MPI_SUM, comm));
  *amp = 2 * s[0] / s[1];
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode SetDefault(const char key[], const char value[])
{
  PetscBool set;

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsHasName(NULL, NULL, key, &set));
  if (!set) PetscCall(PetscOptionsSetValue(NULL, key, value));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* One run of the shear wave to tEnd with -flow_dt_max dtmax (0: none); returns nu_eff / nu. */
static PetscErrorCode RunCase(MPI_Comm comm, PetscReal dtmax, PetscReal tEnd, PetscBool verbose, PetscReal *ratio)
{
  PffGrid         grid;
  PffFlow         flow;
  const PetscInt  cells[3]    = {16, 16, 16};
  const PetscBool periodic[3] = {PETSC_TRUE, PETSC_TRUE, PETSC_TRUE};
  const PetscReal origin[3]   = {0, 0, 0};
  PetscReal       a0, a1, t = 0, nu = 0;
  PetscInt        steps = 0;
  char            buf[64];

  PetscFunctionBeginUser;
  if (dtmax > 0) {
    PetscCall(PetscSNPrintf(buf, sizeof(buf), "%.17g", (double)dtmax));
    PetscCall(PetscOptionsSetValue(NULL, "-flow_dt_max", buf));
  } else
    PetscCall(PetscOptionsClearValue(NULL, "-flow_dt_max"));
  PetscCall(PffGridCreate(comm, &grid));
  PetscCall(PffGridSetCells(grid, cells));
  PetscCall(PffGridSetBlockSize(grid, 8));
  PetscCall(PffGridSetLevels(grid, 1));
  PetscCall(PffGridSetDomain(grid, origin, 1.0 / 16));
  PetscCall(PffGridSetPeriodic(grid, periodic));
  PetscCall(PffGridSetUp(grid));
  PetscCall(PffFlowCreate(grid, &flow));
  PetscCall(PffFlowSetFromOptions(flow));
  PetscCall(PffFlowSetUp(flow));
  PetscCall(PffFlowSeed(flow, SeedShear, NULL));
  PetscCall(Amplitude(flow, comm, &a0));
  while (t < tEnd * (1 - 1e-12)) {
    PffFlowStepStats st;
    PetscCall(PffFlowStep(flow, tEnd - t, &st));
    PetscCall(PffFlowGetTime(flow, &t, &steps));
    if (verbose) {
      PetscReal a;
      PetscCall(Amplitude(flow, comm, &a));
      PetscCall(PetscPrintf(comm, "step %" PetscInt_FMT " t %.4f dt %.4e umax %.4e A/A0 %.5f\n", steps, (double)t,
                            (double)st.dt, (double)st.umax, (double)(a / a0)));
    }
  }
  PetscCall(Amplitude(flow, comm, &a1));
  PetscCall(PetscOptionsGetReal(NULL, NULL, "-nu_liquid", &nu, NULL));
  const PetscReal k2 = 4 * PETSC_PI * PETSC_PI * Mode * Mode, nuEff = -PetscLogReal(a1 / a0) / (k2 * t);
  *ratio = nuEff / nu;
  PetscCall(PetscPrintf(
      comm, "shear wave, dt_max %s: %" PetscInt_FMT " steps to t %g, A/A0 %.4f (Stokes %.4f), nu_eff/nu %.2f\n",
      dtmax > 0 ? "h^2/(12 nu) - 1e-7" : "none", steps, (double)t, (double)(a1 / a0),
      (double)PetscExpReal(-nu * k2 * t), (double)*ratio));
  PetscCall(PffFlowDestroy(&flow));
  PetscCall(PffGridDestroy(&grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  MPI_Comm  comm;
  PetscBool verbose = PETSC_FALSE;
  PetscReal tEnd = 5, numin = 0.7, numax = 1.1, nu = 0, ratio[2];

  PetscFunctionBeginUser;
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  comm = PETSC_COMM_WORLD;
  PetscCall(PetscOptionsGetReal(NULL, NULL, "-t_end", &tEnd, NULL));
  PetscCall(PetscOptionsGetReal(NULL, NULL, "-nu_min", &numin, NULL));
  PetscCall(PetscOptionsGetReal(NULL, NULL, "-nu_max", &numax, NULL));
  PetscCall(PetscOptionsGetReal(NULL, NULL, "-mode", &Mode, NULL));
  PetscCall(PetscOptionsGetBool(NULL, NULL, "-verbose", &verbose, NULL));
  PetscCall(SetDefault("-rho_liquid", "3"));
  PetscCall(SetDefault("-rho_gas", "1"));
  PetscCall(SetDefault("-gravity", "0,0,0"));
  PetscCall(SetDefault("-nu_liquid", "0.00390625"));
  PetscCall(SetDefault("-nu_gas", "0.00390625"));
  PetscCall(SetDefault("-flow_delete_bubbles", "false"));
  PetscCall(PetscOptionsGetReal(NULL, NULL, "-nu_liquid", &nu, NULL));
  PetscCall(RunCase(comm, 0, tEnd, verbose, &ratio[0]));
  PetscCall(RunCase(comm, 1.0 / (16.0 * 16.0 * 12.0 * nu) - 1e-7, tEnd, verbose, &ratio[1]));
  for (int c = 0; c < 2; c++)
    PetscCheck(ratio[c] >= numin && ratio[c] <= numax, comm, PETSC_ERR_PLIB,
               "case %d: effective viscosity %g nu is outside [%g, %g] nu", c, (double)ratio[c], (double)numin,
               (double)numax);
  PetscCall(PetscFinalize());
  return 0;
}
