/* Unit test of PffFlowGetPhaseVolumes (the phase volumes of the drift checks, issue 10) at any rank count.

   A closed unit box (16^3 cells, 8^3 blocks, no periodic axis), liquid seeded below y = 1/2 and gas
   above, at rest; the volumes are those of the phase field after PffFlowSeed. Three cases:
     - uniform grid: liquid + gas is the box volume 1 to rounding (every cell has an open face), and the
       liquid volume is 1/2 plus the square root's 0.16 h per unit interface area (Eq. 7, measured on
       a flat interface, docs/flow.md), within 0.5%;
     - with a solid cube [1/4, 1/2]^3 (4^3 cells whose faces are all closed): liquid + gas is
       1 - 1/64 to rounding, the liquid volume 1/2 - 1/64 plus the surface term within 0.5%;
     - two levels (the blocks with x >= 1/2 coarse): liquid + gas is 1 to rounding, liquid 1/2 plus the surface term
   within 0.5%. Each case prints both volumes to 6 digits, the same on any number of ranks, and fails through
   PetscCheck.
   A fourth case checks the liquid volume's control (-flow_volume_control, docs/flow.md) over one step of the uniform
   box: the first step takes the liquid volume of the phase field after the seed as the volume to hold, and a
   volume out of reach (twice the liquid's, set by PffFlowSetVolumeControl as a restart would) moves the target
   fraction s* by -1/2 in one step, which the clamp stops at 0.8.

   Sample run:  mpiexec -n 4 ./test_flow_volumes
   Prints five lines (the same on any number of ranks). */
#include <pff.h>

static const char help[] = "Liquid and gas volumes of the fluid cells (PffFlowGetPhaseVolumes).\n";

static const PetscReal SolidLo = 0.25, SolidHi = 0.5;
static const PetscReal SurfaceExcess = 0.16; /* phi-volume above the particle volume per unit interface area, in h */

/* Signed distance to the solid cube, negative inside (the gradient is not needed here). */
static PetscReal SolidCube(const PetscReal x[3], PetscReal grad[3], void *ctx)
{
  PetscReal out = 0, in = -PETSC_MAX_REAL;

  (void)ctx;
  for (int a = 0; a < 3; a++) {
    const PetscReal d = PetscMax(SolidLo - x[a], x[a] - SolidHi);
    out += PetscMax(d, 0) * PetscMax(d, 0);
    in = PetscMax(in, d);
    if (grad) grad[a] = 0;
  }
  return out > 0 ? PetscSqrtReal(out) : in;
}

static PetscErrorCode SeedHalf(const PetscReal x[3], PetscInt *type, PetscReal v[3], void *ctx)
{
  const PetscBool solid = *(const PetscBool *)ctx;

  PetscFunctionBeginUser;
  v[0] = v[1] = v[2] = 0;
  if (solid && SolidCube(x, NULL, NULL) < 0)
    *type = -1;
  else
    *type = x[1] < 0.5 ? PFF_PARTICLE_LIQUID : PFF_PARTICLE_AIR;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The closed unit box of every case (16^3 cells, 8^3 blocks), with the solid cube or on two levels, seeded half full.
 */
static PetscErrorCode CreateBox(MPI_Comm comm, PetscBool solid, PetscBool twoLevels, PffGrid *grid, PffFlow *flow)
{
  const PetscInt  cells[3]    = {16, 16, 16};
  const PetscBool periodic[3] = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};
  const PetscReal origin[3]   = {0, 0, 0};
  /* raster 2 x 2 x 2, x fastest: the blocks with x >= 1/2 at level 1 */
  const PetscInt levels[8] = {0, 1, 0, 1, 0, 1, 0, 1};

  PetscFunctionBeginUser;
  PetscCall(PffGridCreate(comm, grid));
  PetscCall(PffGridSetCells(*grid, cells));
  PetscCall(PffGridSetBlockSize(*grid, 8));
  PetscCall(PffGridSetLevels(*grid, twoLevels ? 2 : 1));
  PetscCall(PffGridSetDomain(*grid, origin, 1.0 / 16));
  PetscCall(PffGridSetPeriodic(*grid, periodic));
  if (twoLevels) PetscCall(PffGridSetRefinementMap(*grid, levels));
  PetscCall(PffGridSetUp(*grid));
  PetscCall(PffFlowCreate(*grid, flow));
  PetscCall(PffFlowSetFromOptions(*flow));
  if (solid) PetscCall(PffFlowSetSolid(*flow, SolidCube, NULL));
  PetscCall(PffFlowSetUp(*flow));
  PetscCall(PffFlowSeed(*flow, SeedHalf, &solid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode RunCase(MPI_Comm comm, const char name[], PetscBool solid, PetscBool twoLevels)
{
  PffGrid         grid;
  PffFlow         flow;
  const PetscReal fluid = 1 - (solid ? PetscPowReal(SolidHi - SolidLo, 3) : 0);
  /* the particle volume below y = 1/2 plus the square root's 0.16 h per unit area of free surface (the
     solid's top face covers 1/16 of it; on two levels half the surface has h = 1/8) */
  const PetscReal area      = solid ? 1 - PetscSqr(SolidHi - SolidLo) : 1,
                  hmean     = twoLevels ? 0.5 * (1.0 / 16 + 1.0 / 8) : 1.0 / 16;
  const PetscReal liquidRef = fluid - 0.5 + SurfaceExcess * hmean * area;
  PetscReal       liquid, gas;

  PetscFunctionBeginUser;
  PetscCall(CreateBox(comm, solid, twoLevels, &grid, &flow));
  PetscCall(PffFlowGetPhaseVolumes(flow, &liquid, &gas));
  PetscCall(PetscPrintf(comm, "%s: liquid %.6f  gas %.6f  fluid %.6f (expected %.6f)\n", name, (double)liquid,
                        (double)gas, (double)(liquid + gas), (double)fluid));
  PetscCheck(PetscAbsReal(liquid + gas - fluid) <= 1e-12, comm, PETSC_ERR_PLIB,
             "%s: liquid + gas = %.15g, expected the fluid volume %.15g", name, (double)(liquid + gas), (double)fluid);
  PetscCheck(PetscAbsReal(liquid - liquidRef) <= 0.005 * liquidRef, comm, PETSC_ERR_PLIB,
             "%s: liquid volume %g is not within 0.5%% of %g", name, (double)liquid, (double)liquidRef);
  PetscCall(PffFlowDestroy(&flow));
  PetscCall(PffGridDestroy(&grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode RunControl(MPI_Comm comm)
{
  PffGrid          grid;
  PffFlow          flow;
  PffFlowStepStats st;
  PetscReal        liquid, target, fraction;

  PetscFunctionBeginUser;
  PetscCall(CreateBox(comm, PETSC_FALSE, PETSC_FALSE, &grid, &flow));
  PetscCall(PffFlowGetPhaseVolumes(flow, &liquid, NULL));
  PetscCall(PffFlowGetVolumeControl(flow, &target, &fraction));
  PetscCheck(target == 0 && fraction == 1, comm, PETSC_ERR_PLIB, "control before the first step: %g, %g",
             (double)target, (double)fraction);
  PetscCall(PffFlowStep(flow, 1.0, &st));
  PetscCall(PffFlowGetVolumeControl(flow, &target, &fraction));
  PetscCall(PetscPrintf(comm, "control: holds %.6f (liquid after the seed %.6f), fraction %.6f\n", (double)target,
                        (double)liquid, (double)fraction));
  PetscCheck(PetscAbsReal(target - liquid) <= 1e-12 * liquid && fraction == 1, comm, PETSC_ERR_PLIB,
             "the first step must hold the seed's liquid volume %.15g at fraction 1, not %.15g at %.15g",
             (double)liquid, (double)target, (double)fraction);
  PetscCall(PffFlowSetVolumeControl(flow, 2 * liquid, 1.0));
  PetscCall(PffFlowStep(flow, 1.0, &st));
  PetscCall(PffFlowGetVolumeControl(flow, &target, &fraction));
  PetscCall(PetscPrintf(comm, "control: out of reach, fraction %.6f\n", (double)fraction));
  PetscCheck(target == 2 * liquid && fraction == (PetscReal)0.8, comm, PETSC_ERR_PLIB,
             "a volume out of reach must stop the fraction at 0.8, not %.15g (holding %.15g)", (double)fraction,
             (double)target);
  PetscCall(PffFlowDestroy(&flow));
  PetscCall(PffGridDestroy(&grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  MPI_Comm comm;

  PetscFunctionBeginUser;
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  comm = PETSC_COMM_WORLD;
  PetscCall(PetscOptionsSetValue(NULL, "-rho_liquid", "1000"));
  PetscCall(PetscOptionsSetValue(NULL, "-rho_gas", "1"));
  PetscCall(PetscOptionsSetValue(NULL, "-gravity", "0,-9.81,0"));
  PetscCall(RunCase(comm, "uniform", PETSC_FALSE, PETSC_FALSE));
  PetscCall(RunCase(comm, "solid cube", PETSC_TRUE, PETSC_FALSE));
  PetscCall(RunCase(comm, "two levels", PETSC_FALSE, PETSC_TRUE));
  PetscCall(RunControl(comm));
  PetscCall(PetscFinalize());
  return 0;
}
