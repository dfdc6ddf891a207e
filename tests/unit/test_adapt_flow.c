/* Every module follows a topology change (DESIGN.md Sec. 10; docs/grid.md, "Adaptation").

   A closed 32 x 32 x 16 tank (blocks of 8, three levels) with a solid sphere, water below y = 0.4 and air
   above, swirled so that the pressure has work to do. Run A: set up on map A, one PF-FLIP step (the
   particles are binned, the pressure and pffmg are set up, the open faces and the reference lattice are
   built, all for A), then PffGridAdapt to map B and a second step. Run B: a grid set up on map B from the
   start, a flow given run A's particles as they were after the first step, one step. Nothing tells the
   particles, the pressure, pffmg or the flow that the grid changed: they notice the topology state. A
   cache that survived the adapt (particle bins, face lists, multigrid levels, open faces, the reference
   lattice) makes the two steps differ, or fails. Checks, per case:
   - the same time step, particle count and maximum speed, and pffmg's iteration count within one (the
     pressure guess is zeroed in both runs);
   - the sums of the particle velocities and positions within 1e-6 of their scale (the pressure
     solves to 1e-10; the order in which particles are summed differs);
   - the liquid volume after the step within 1e-9.
   A second case does the same with a prescribed separable field (PffFlowSetPrescribedSeparable): its shape is
   sampled once per topology state and not transferred, so a shape kept from map A moves the particles of the
   changed blocks differently (or not at all) from the fresh grid's.

   Sample run:  mpiexec -n 4 ./test_adapt_flow
   Prints one line per case. */
#include <pff.h>

static const char help[] = "Particles, pressure, pffmg and flow follow a grid adapt.\n";

#define NB_X 4
#define NB_Y 4
#define NB_Z 2
#define NBLOCKS (NB_X * NB_Y * NB_Z)

static const PetscReal Centre[3] = {0.5, 0.35, 0.25}, Radius = 0.12;

static PetscReal Sphere(const PetscReal x[3], PetscReal grad[3], void *ctx)
{
  PetscReal r = 0;

  (void)ctx;
  for (int a = 0; a < 3; a++) r += PetscSqr(x[a] - Centre[a]);
  r = PetscSqrtReal(r);
  for (int a = 0; a < 3 && grad; a++) grad[a] = r > 0 ? (x[a] - Centre[a]) / r : 0;
  return r - Radius;
}

static PetscErrorCode SeedSwirl(const PetscReal x[3], PetscInt *type, PetscReal v[3], void *ctx)
{
  PetscFunctionBeginUser;
  (void)ctx;
  *type = Sphere(x, NULL, NULL) < 0 ? -1 : (x[1] < 0.4 ? PFF_PARTICLE_LIQUID : PFF_PARTICLE_AIR);
  v[0]  = 0.3 * PetscSinReal(PETSC_PI * x[1]);
  v[1]  = -0.3 * PetscSinReal(PETSC_PI * x[0]);
  v[2]  = 0.1;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Map A: level 0 in the lower half of the raster, 1 above, 2 in the top corner. Map B: the other way
   round along x, so that blocks refine, coarsen and change owner. */
static void Maps(PetscInt a[], PetscInt b[])
{
  for (PetscInt k = 0; k < NB_Z; k++)
    for (PetscInt j = 0; j < NB_Y; j++)
      for (PetscInt i = 0; i < NB_X; i++) {
        const PetscInt g = i + NB_X * (j + NB_Y * k);
        a[g]             = j < 2 ? 0 : (i == NB_X - 1 && j == NB_Y - 1 ? 2 : 1);
        b[g]             = i < 1 ? 2 : (i < 3 ? 1 : 0);
      }
}

/* The separable case's field: the swirl's shape, scaled by 1 + t. */
static PetscReal SwirlShape(const PetscReal x[3], PetscInt comp, PetscReal t, void *ctx)
{
  (void)t;
  (void)ctx;
  return comp == 0 ? 0.3 * PetscSinReal(PETSC_PI * x[1]) : comp == 1 ? -0.3 * PetscSinReal(PETSC_PI * x[0]) : 0.1;
}

static PetscReal SwirlAmplitude(PetscReal t, void *ctx)
{
  (void)ctx;
  return 1 + t;
}

static PetscErrorCode CreateFlow(MPI_Comm comm, const PetscInt map[], PetscBool separable, PffGrid *grid, PffFlow *flow)
{
  const PetscInt  cells[3]    = {8 * NB_X, 8 * NB_Y, 8 * NB_Z};
  const PetscBool periodic[3] = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};
  const PetscReal origin[3]   = {0, 0, 0};

  PetscFunctionBeginUser;
  PetscCall(PffGridCreate(comm, grid));
  PetscCall(PffGridSetCells(*grid, cells));
  PetscCall(PffGridSetBlockSize(*grid, 8));
  PetscCall(PffGridSetLevels(*grid, 3));
  PetscCall(PffGridSetDomain(*grid, origin, 1.0 / 32));
  PetscCall(PffGridSetPeriodic(*grid, periodic));
  PetscCall(PffGridSetRefinementMap(*grid, map));
  PetscCall(PffGridSetUp(*grid));
  PetscCall(PffFlowCreate(*grid, flow));
  PetscCall(PffFlowSetFromOptions(*flow));
  if (separable)
    PetscCall(PffFlowSetPrescribedSeparable(*flow, SwirlShape, SwirlAmplitude, NULL));
  else
    PetscCall(PffFlowSetSolid(*flow, Sphere, NULL));
  PetscCall(PffFlowSetUp(*flow));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscReal Zero(const PetscReal x[3], PetscInt comp, void *ctx)
{
  (void)x;
  (void)comp;
  (void)ctx;
  return 0;
}

/* The pressure guess is the only state a step carries over on the grid: zero in both runs, so that the
   solves start alike. */
static PetscErrorCode ZeroPressure(PffGrid grid, PffFlow flow)
{
  PetscInt chP;

  PetscFunctionBeginUser;
  PetscCall(PffFlowGetChannels(flow, NULL, &chP, NULL, NULL));
  if (chP >= 0) PetscCall(PffGridFillChannel(grid, chP, Zero, NULL)); /* a prescribed field has none */
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The particles of src appended to dst (world positions come back exactly), then migrated. */
static PetscErrorCode CopyParticles(PffFlow src, PffFlow dst)
{
  PffParticles      ps, pd;
  PffParticleArrays a;
  PetscReal        *x, *v;
  uint8_t          *type;
  int8_t           *level;

  PetscFunctionBeginUser;
  PetscCall(PffFlowGetParticles(src, &ps));
  PetscCall(PffFlowGetParticles(dst, &pd));
  PetscCall(PffParticlesGetArrays(ps, &a));
  PetscCall(PetscMalloc4(3 * a.n + 1, &x, 3 * a.n + 1, &v, a.n + 1, &type, a.n + 1, &level));
  for (PetscInt i = 0; i < a.n; i++) {
    PffParticleArraysWorld(&a, i, &x[3 * i]);
    for (int d = 0; d < 3; d++) v[3 * i + d] = a.v[3 * i + d];
    type[i]  = (uint8_t)PffParticleWordType(a.word[i]);
    level[i] = (int8_t)PffParticleWordLevel(a.word[i]);
  }
  PetscCall(PffParticlesAdd(pd, a.n, x, v, a.id, type, level, NULL));
  PetscCall(PetscFree4(x, v, type, level));
  PetscCall(PffParticlesMigrate(pd, NULL));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Sums over all particles of v (3), x (3) and |v| (the scale). */
static PetscErrorCode ParticleSums(MPI_Comm comm, PffFlow f, PetscReal s[7])
{
  PffParticles      p;
  PffParticleArrays a;

  PetscFunctionBeginUser;
  PetscCall(PffFlowGetParticles(f, &p));
  PetscCall(PffParticlesGetArrays(p, &a));
  for (int k = 0; k < 7; k++) s[k] = 0;
  for (PetscInt i = 0; i < a.n; i++)
    for (int d = 0; d < 3; d++) {
      s[d] += a.v[3 * i + d];
      s[3 + d] += a.x[3 * i + d];
      s[6] += PetscAbsReal(a.v[3 * i + d]);
    }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, s, 7, MPIU_REAL, MPI_SUM, comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode Run(MPI_Comm comm, PetscBool separable)
{
  PetscInt         mapA[NBLOCKS], mapB[NBLOCKS];
  PffGrid          gridA, gridB;
  PffFlow          flowA, flowB;
  PffFlowStepStats st1, stA, stB;
  PffAdaptInfo     info;
  PetscReal        sA[7], sB[7], volA, volB, t;
  PetscInt         step;

  PetscFunctionBeginUser;
  Maps(mapA, mapB);
  PetscCall(CreateFlow(comm, mapA, separable, &gridA, &flowA));
  PetscCall(PffFlowSeed(flowA, SeedSwirl, NULL));
  PetscCall(PffFlowStep(flowA, 1.0, &st1));
  PetscCall(PffGridAdapt(gridA, mapB));
  PetscCall(PffGridGetAdaptInfo(gridA, &info));
  PetscCheck(info.refined > 0 && info.coarsened > 0, comm, PETSC_ERR_PLIB, "the maps must refine and coarsen blocks");

  PetscCall(CreateFlow(comm, mapB, separable, &gridB, &flowB));
  PetscCall(CopyParticles(flowA, flowB));
  PetscCall(PffFlowGetTime(flowA, &t, &step));
  PetscCall(PffFlowSetTime(flowB, t, step));
  {
    PetscReal target, fraction; /* the liquid volume's control goes on as a restart continues it */
    PetscCall(PffFlowGetVolumeControl(flowA, &target, &fraction));
    PetscCall(PffFlowSetVolumeControl(flowB, target, fraction));
  }

  PetscCall(ZeroPressure(gridA, flowA));
  PetscCall(ZeroPressure(gridB, flowB));
  PetscCall(PffFlowStep(flowA, 1.0, &stA));
  PetscCall(PffFlowStep(flowB, 1.0, &stB));
  PetscCall(ParticleSums(comm, flowA, sA));
  PetscCall(ParticleSums(comm, flowB, sB));
  if (separable) { /* a prescribed field transports only: the phase field comes on demand */
    PetscCall(PffFlowUpdateFields(flowA, PETSC_FALSE));
    PetscCall(PffFlowUpdateFields(flowB, PETSC_FALSE));
  }
  PetscCall(PffFlowGetPhaseVolumes(flowA, &volA, NULL));
  PetscCall(PffFlowGetPhaseVolumes(flowB, &volB, NULL));
  PetscCall(PetscPrintf(
      comm,
      "%sadapted (refined %" PetscInt_FMT " coarsened %" PetscInt_FMT "): dt %.6e umax %.6f its %" PetscInt_FMT
      " liquid %.8f; set up on the map: dt %.6e umax %.6f its %" PetscInt_FMT " liquid %.8f\n",
      separable ? "separable field, " : "", info.refined, info.coarsened, (double)stA.dt, (double)stA.umax,
      stA.pressure.its, (double)volA, (double)stB.dt, (double)stB.umax, stB.pressure.its, (double)volB));
  PetscCheck(stA.particles == stB.particles && stA.particles > 0, comm, PETSC_ERR_PLIB, "particle counts differ");
  PetscCheck(PetscAbsReal(stA.dt - stB.dt) <= 1e-12 * stB.dt, comm, PETSC_ERR_PLIB, "time steps differ");
  PetscCheck(PetscAbsReal(stA.umax - stB.umax) <= 1e-6 * stB.umax, comm, PETSC_ERR_PLIB, "maximum speeds differ");
  PetscCheck(PetscAbs(stA.pressure.its - stB.pressure.its) <= 1, comm, PETSC_ERR_PLIB,
             "pressure iterations %" PetscInt_FMT " after the adapt, %" PetscInt_FMT " on a fresh grid",
             stA.pressure.its, stB.pressure.its);
  for (int k = 0; k < 6; k++) {
    const PetscReal scale = k < 3 ? sB[6] : (PetscReal)stB.particles * 32;
    PetscCheck(PetscAbsReal(sA[k] - sB[k]) <= 1e-6 * scale, comm, PETSC_ERR_PLIB,
               "particle %s sum %d: %.10g after the adapt, %.10g on a fresh grid", k < 3 ? "velocity" : "position",
               k % 3, (double)sA[k], (double)sB[k]);
  }
  PetscCheck(PetscAbsReal(volA - volB) <= 1e-9, comm, PETSC_ERR_PLIB, "liquid volumes %.12g and %.12g differ",
             (double)volA, (double)volB);
  PetscCall(PffFlowDestroy(&flowA));
  PetscCall(PffFlowDestroy(&flowB));
  PetscCall(PffGridDestroy(&gridA));
  PetscCall(PffGridDestroy(&gridB));
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  PetscFunctionBeginUser;
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(PetscOptionsSetValue(NULL, "-rho_liquid", "1000"));
  PetscCall(PetscOptionsSetValue(NULL, "-rho_gas", "1"));
  PetscCall(PetscOptionsSetValue(NULL, "-gravity", "0,-9.81,0"));
  PetscCall(PetscOptionsSetValue(NULL, "-pressure_ksp_rtol", "1e-10"));
  PetscCall(Run(PETSC_COMM_WORLD, PETSC_FALSE));
  PetscCall(Run(PETSC_COMM_WORLD, PETSC_TRUE));
  PetscCall(PetscFinalize());
  return 0;
}
