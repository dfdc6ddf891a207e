/* User regions and the vorticity criterion of dynamic adaptivity (docs/flow.md, "Adaptivity"; PF-FLIP
   Sec. 5.2 and 5.4).

   A closed 32^3 box of 8^3 blocks over three levels, a still pool (liquid below y = 1/8, air above, no
   gravity), adaptive from the coarsest level. Three runs from the same seed, each checked after the seed
   and after two steps:
   - no option: the blocks at the interface (y = 1/8) are at level 0, the blocks around (0.5, 0.75, 0.5),
     high above it in the air, at level 1 or 2 (the reference for the next two);
   - a sphere there that forces level 0 and a box across the interface at x < 1/4 that forces level 2:
     every block the sphere overlaps is at level 0 and every particle inside it too; no block the box
     overlaps is at level 0 (grading may lift a forced-coarse block beside a fine one to level 1) and,
     after the seed, no particle inside it either;
   - the air in a ball around the same point spins as a rigid body (vorticity 2 Omega) and
     -adapt_vorticity 0.1 refines the blocks of the ball to level 0 (|curl u| h0 > delta max|u| there), while
     without the option they stay coarser.
   The lines it prints (levels and counts) are the same on any number of ranks.

   Sample run:  mpiexec -n 2 ./test_adapt_regions */
#include "pfftest.h"

static const char help[] = "User regions force grid levels; the vorticity criterion refines a vortex.\n";

#define NB 4

static const PetscReal Centre[3] = {0.5, 0.75, 0.5}, SphereRadius = 0.1, VortexRadius = 0.15, Omega = 4.0;
static const PetscReal BoxLo[3] = {0, 0, 0}, BoxHi[3] = {0.25, 0.25, 1};

typedef struct {
  PetscBool spin;
} SeedCtx;

static PetscErrorCode SeedPool(const PetscReal x[3], PetscInt *type, PetscReal v[3], void *ctx)
{
  const SeedCtx  *sc = (const SeedCtx *)ctx;
  const PetscReal rx = x[0] - Centre[0], ry = x[1] - Centre[1], rz = x[2] - Centre[2];

  PetscFunctionBeginUser;
  *type = x[1] < 0.125 ? PFF_PARTICLE_LIQUID : PFF_PARTICLE_AIR;
  v[0] = v[1] = v[2] = 0;
  if (sc->spin && rx * rx + ry * ry + rz * rz < VortexRadius * VortexRadius) { /* Omega about z */
    v[0] = -Omega * ry;
    v[1] = Omega * rx;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscBool InSphere(const PetscReal x[3])
{
  PetscReal r = 0;
  for (int d = 0; d < 3; d++) r += PetscSqr(x[d] - Centre[d]);
  return (PetscBool)(r <= SphereRadius * SphereRadius);
}

static PetscBool InBox(const PetscReal x[3])
{
  for (int d = 0; d < 3; d++)
    if (x[d] < BoxLo[d] || x[d] > BoxHi[d]) return PETSC_FALSE;
  return PETSC_TRUE;
}

/* Finest and coarsest level of the blocks whose box [lo, hi] overlaps the sphere (which = 0), the box
   (which = 1) or contains the centre (which = 2, the vortex's blocks). */
static PetscErrorCode BlockLevels(PffGrid grid, PetscInt which, PetscInt *lmin, PetscInt *lmax)
{
  PetscInt        nb[3];
  const PetscInt *level;
  const PetscReal w = 1.0 / NB;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetRaster(grid, nb, &level, NULL));
  *lmin = PETSC_MAX_INT;
  *lmax = -1;
  for (PetscInt b = 0; b < nb[0] * nb[1] * nb[2]; b++) {
    const PetscInt ijk[3] = {b % nb[0], (b / nb[0]) % nb[1], b / (nb[0] * nb[1])};
    PetscReal      lo[3], hi[3], d2 = 0;
    PetscBool      over = PETSC_TRUE;
    for (int d = 0; d < 3; d++) {
      lo[d]             = ijk[d] * w;
      hi[d]             = lo[d] + w;
      const PetscReal q = PetscMin(PetscMax(Centre[d], lo[d]), hi[d]) - Centre[d];
      d2 += q * q;
      over = (PetscBool)(over && BoxLo[d] < hi[d] && BoxHi[d] > lo[d]);
    }
    const PetscBool hit = which == 0   ? (PetscBool)(d2 < SphereRadius * SphereRadius)
                          : which == 1 ? over
                                       : (PetscBool)(d2 == 0);
    if (!hit) continue;
    *lmin = PetscMin(*lmin, level[b]);
    *lmax = PetscMax(*lmax, level[b]);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Finest and coarsest particle level inside the sphere (which = 0) or the box (1), over all ranks. */
static PetscErrorCode ParticleLevels(MPI_Comm comm, PffFlow flow, PetscInt which, PetscInt *lmin, PetscInt *lmax)
{
  PffParticles      p;
  PffParticleArrays a;
  PetscInt          m[2] = {PETSC_MAX_INT, PETSC_MAX_INT}; /* min, -max */

  PetscFunctionBeginUser;
  PetscCall(PffFlowGetParticles(flow, &p));
  PetscCall(PffParticlesGetArrays(p, &a));
  for (PetscInt i = 0; i < a.n; i++) {
    PetscReal x[3];
    PffParticleArraysWorld(&a, i, x);
    if (!(which == 0 ? InSphere(x) : InBox(x))) continue;
    const PetscInt l = PffParticleWordLevel(a.word[i]);
    m[0]             = PetscMin(m[0], l);
    m[1]             = PetscMin(m[1], -l);
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, m, 2, MPIU_INT, MPI_MIN, comm));
  *lmin = m[0];
  *lmax = -m[1];
  PetscFunctionReturn(PETSC_SUCCESS);
}

typedef struct {
  PetscInt sphere[2], box[2], vortex[2], psphere[2], pbox[2];
} Levels;

static PetscErrorCode Measure(MPI_Comm comm, PffGrid grid, PffFlow flow, const char *what, Levels *L)
{
  PetscFunctionBeginUser;
  PetscCall(BlockLevels(grid, 0, &L->sphere[0], &L->sphere[1]));
  PetscCall(BlockLevels(grid, 1, &L->box[0], &L->box[1]));
  PetscCall(BlockLevels(grid, 2, &L->vortex[0], &L->vortex[1]));
  PetscCall(ParticleLevels(comm, flow, 0, &L->psphere[0], &L->psphere[1]));
  PetscCall(ParticleLevels(comm, flow, 1, &L->pbox[0], &L->pbox[1]));
  PetscCall(PetscPrintf(comm,
                        "%s: block levels sphere %" PetscInt_FMT "-%" PetscInt_FMT ", box %" PetscInt_FMT
                        "-%" PetscInt_FMT ", vortex %" PetscInt_FMT "-%" PetscInt_FMT
                        "; particle levels sphere %" PetscInt_FMT "-%" PetscInt_FMT ", box %" PetscInt_FMT
                        "-%" PetscInt_FMT "\n",
                        what, L->sphere[0], L->sphere[1], L->box[0], L->box[1], L->vortex[0], L->vortex[1],
                        L->psphere[0], L->psphere[1], L->pbox[0], L->pbox[1]));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Seeds a fresh flow with the given options, measures after the seed and after two steps. */
static PetscErrorCode Run(MPI_Comm comm, const char *name, const char *options, PetscBool spin, Levels L[2])
{
  const PetscInt  nb[3]       = {NB, NB, NB};
  const PetscBool periodic[3] = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};
  const PetscReal origin[3]   = {0, 0, 0};
  PetscInt        map[NB * NB * NB];
  PffTestCtx      tc;
  PffFlow         flow;
  SeedCtx         sc = {spin};
  char            what[64];

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsClearValue(NULL, "-adapt_region_sphere"));
  PetscCall(PetscOptionsClearValue(NULL, "-adapt_region_sphere_level"));
  PetscCall(PetscOptionsClearValue(NULL, "-adapt_region_box"));
  PetscCall(PetscOptionsClearValue(NULL, "-adapt_region_box_level"));
  PetscCall(PetscOptionsClearValue(NULL, "-adapt_vorticity"));
  PetscCall(PetscOptionsInsertString(NULL, options));
  for (PetscInt b = 0; b < NB * NB * NB; b++) map[b] = 2; /* the adaptive start: the coarsest level */
  PetscCall(PffTestCreateGridFromMap(comm, nb, periodic, origin, 1.0 / (8 * NB), 8, 3, map, &tc));
  PetscCall(PffFlowCreate(tc.grid, &flow));
  PetscCall(PffFlowSetFromOptions(flow));
  PetscCall(PffFlowSetUp(flow));
  PetscCall(PffFlowSeed(flow, SeedPool, &sc));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s, seed", name));
  PetscCall(Measure(comm, tc.grid, flow, what, &L[0]));
  for (int s = 0; s < 2; s++) {
    PffFlowStepStats st;
    PetscCall(PffFlowStep(flow, 2e-3, &st));
  }
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s, 2 steps", name));
  PetscCall(Measure(comm, tc.grid, flow, what, &L[1]));
  PetscCall(PffFlowDestroy(&flow));
  PetscCall(PffGridDestroy(&tc.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  MPI_Comm comm;
  Levels   base[2], reg[2], still[2], vort[2];

  PetscFunctionBeginUser;
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  comm = PETSC_COMM_WORLD;
  PetscCall(PetscOptionsSetValue(NULL, "-adapt_levels", "3"));
  PetscCall(PetscOptionsSetValue(NULL, "-gravity", "0,0,0"));
  PetscCall(Run(comm, "no region", "", PETSC_FALSE, base));
  PetscCall(
      Run(comm, "regions",
          "-adapt_region_sphere 0.5,0.75,0.5,0.1 -adapt_region_sphere_level 0 -adapt_region_box 0,0,0,0.25,0.25,1 "
          "-adapt_region_box_level 2",
          PETSC_FALSE, reg));
  PetscCall(Run(comm, "vortex", "", PETSC_TRUE, still));
  PetscCall(Run(comm, "vortex, criterion", "-adapt_vorticity 0.1", PETSC_TRUE, vort));
  for (int s = 0; s < 2; s++) {
    const char *when = s ? "after two steps" : "after the seed";
    /* the references: what the regions and the criterion must change */
    PetscCheck(base[s].sphere[0] >= 1, comm, PETSC_ERR_PLIB,
               "%s: without a region the sphere's blocks reach level %" PetscInt_FMT ", expected >= 1", when,
               base[s].sphere[0]);
    PetscCheck(base[s].box[0] == 0, comm, PETSC_ERR_PLIB,
               "%s: without a region the interface blocks in the box are at level %" PetscInt_FMT ", expected 0", when,
               base[s].box[0]);
    PetscCheck(reg[s].sphere[1] == 0 && reg[s].psphere[1] == 0, comm, PETSC_ERR_PLIB,
               "%s: the sphere forces level 0, but its blocks reach level %" PetscInt_FMT
               " and its particles %" PetscInt_FMT,
               when, reg[s].sphere[1], reg[s].psphere[1]);
    PetscCheck(still[s].vortex[0] >= 1, comm, PETSC_ERR_PLIB,
               "%s: without the criterion the vortex's blocks are at level %" PetscInt_FMT ", expected >= 1", when,
               still[s].vortex[0]);
    PetscCheck(vort[s].vortex[1] == 0, comm, PETSC_ERR_PLIB,
               "%s: -adapt_vorticity left the vortex's blocks at level %" PetscInt_FMT, when, vort[s].vortex[1]);
    PetscCheck(reg[s].box[0] >= 1, comm, PETSC_ERR_PLIB,
               "%s: the box forces level 2 (1 where graded), but its blocks reach level %" PetscInt_FMT, when,
               reg[s].box[0]);
  }
  /* a particle that drifts into the box from a finer block coarsens only after the delay (the hold), so the
     particles are checked after the seed */
  PetscCheck(reg[0].pbox[0] >= 1, comm, PETSC_ERR_PLIB,
             "after the seed: the box forces level 2 (1 where graded), but its particles reach level %" PetscInt_FMT,
             reg[0].pbox[0]);
  PetscCall(PetscPrintf(comm, "regions and vorticity criterion: ok\n"));
  PetscCall(PetscFinalize());
  return 0;
}
