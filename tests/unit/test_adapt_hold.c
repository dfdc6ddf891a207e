/* The blocks' hysteresis of dynamic adaptivity (docs/flow.md, "Adaptivity", Hold; PF-FLIP Sec. 5.4).

   A closed 32^3 box of 8^3 blocks over three levels, a still pool (liquid below y = 1/4, air above, no
   gravity), adaptive from the coarsest level. After a first step has settled the map, the air particles
   in a small sphere high above the pool turn liquid: a drop that appears, as a splash's droplet does in
   the thresholded coarse phase field. The next step refines the blocks around it. Then the drop turns
   back into air, and the particles ask for coarse levels again at once. Checks:
   - the step after the drop appeared refines blocks;
   - the next delay - 1 steps coarsen nothing: the particles whose coarsening is pending hold their blocks
     (PffParticlesAdaptCounters), so a block that the criterion gives up at one step is not coarsened
     at that step;
   - within delay + 1 further steps the blocks around the former drop do coarsen (a hold, not a lock).
   The lines it prints (counts and steps) are the same on any number of ranks.

   Sample run:  mpiexec -n 2 ./test_adapt_hold
   Prints one line per step. */
#include "pfftest.h"

static const char help[] = "Blocks coarsen only after their particles asked for it delay times in a row.\n";

#define NB 4
#define DELAY 3

static const PetscReal Drop[3] = {0.5, 0.72, 0.5}, DropRadius = 0.13;

static PetscErrorCode SeedPool(const PetscReal x[3], PetscInt *type, PetscReal v[3], void *ctx)
{
  PetscFunctionBeginUser;
  (void)ctx;
  *type = x[1] < 0.25 ? PFF_PARTICLE_LIQUID : PFF_PARTICLE_AIR;
  v[0] = v[1] = v[2] = 0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Every particle inside the drop's sphere takes type `type` (its level, flags and counter kept); the
   phase field follows. Collective. */
static PetscErrorCode SetDrop(PffFlow flow, PetscInt type)
{
  PffParticles      p;
  PffParticleArrays a;

  PetscFunctionBeginUser;
  PetscCall(PffFlowGetParticles(flow, &p));
  PetscCall(PffParticlesGetArrays(p, &a));
  for (PetscInt i = 0; i < a.n; i++) {
    PetscReal x[3], r = 0;
    PffParticleArraysWorld(&a, i, x);
    for (int d = 0; d < 3; d++) r += PetscSqr(x[d] - Drop[d]);
    if (r > DropRadius * DropRadius) continue;
    const uint32_t w = a.word[i];
    a.word[i]        = PffParticleWordSetLevel(PffParticleWord(type, PffParticleWordLevel(w), PffParticleWordFlags(w)),
                                               PffParticleWordLevel(w), PffParticleWordCoarsen(w));
  }
  PetscCall(PffFlowUpdateFields(flow, PETSC_FALSE));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode Step(MPI_Comm comm, PffFlow flow, const char *what, PffFlowAdaptStats *ad)
{
  PffFlowStepStats st;
  PetscInt         step;

  PetscFunctionBeginUser;
  PetscCall(PffFlowStep(flow, 1e-3, &st));
  PetscCall(PffFlowGetTime(flow, NULL, &step));
  *ad = st.adapt;
  PetscCall(PetscPrintf(comm,
                        "step %" PetscInt_FMT " (%s): blocks +%" PetscInt_FMT " -%" PetscInt_FMT
                        ", particles %" PetscInt64_FMT "\n",
                        step, what, st.adapt.adapted ? st.adapt.grid.refined : 0,
                        st.adapt.adapted ? st.adapt.grid.coarsened : 0, st.particles));
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  const PetscInt    nb[3]       = {NB, NB, NB};
  const PetscBool   periodic[3] = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};
  const PetscReal   origin[3]   = {0, 0, 0};
  PetscInt          map[NB * NB * NB];
  PffTestCtx        tc;
  PffFlow           flow;
  PffFlowAdaptStats ad;
  MPI_Comm          comm;
  PetscInt          coarsenedAt = -1;

  PetscFunctionBeginUser;
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  comm = PETSC_COMM_WORLD;
  PetscCall(PetscOptionsSetValue(NULL, "-adapt_levels", "3"));
  PetscCall(PetscOptionsSetValue(NULL, "-adapt_coarsen_delay", "3"));
  PetscCall(PetscOptionsSetValue(NULL, "-gravity", "0,0,0"));
  for (PetscInt b = 0; b < NB * NB * NB; b++) map[b] = 2; /* the adaptive start: the coarsest level */
  PetscCall(PffTestCreateGridFromMap(comm, nb, periodic, origin, 1.0 / (8 * NB), 8, 3, map, &tc));
  PetscCall(PffFlowCreate(tc.grid, &flow));
  PetscCall(PffFlowSetFromOptions(flow));
  PetscCall(PffFlowSetUp(flow));
  PetscCall(PffFlowSeed(flow, SeedPool, NULL));
  PetscCall(Step(comm, flow, "settle", &ad));
  PetscCall(Step(comm, flow, "settle", &ad));

  PetscCall(SetDrop(flow, PFF_PARTICLE_LIQUID));
  PetscCall(Step(comm, flow, "drop", &ad));
  PetscCheck(ad.adapted && ad.grid.refined > 0, comm, PETSC_ERR_PLIB, "the drop refined no block");

  PetscCall(SetDrop(flow, PFF_PARTICLE_AIR));
  for (PetscInt k = 1; k <= 2 * DELAY && coarsenedAt < 0; k++) {
    PetscCall(Step(comm, flow, "no drop", &ad));
    if (ad.adapted && ad.grid.coarsened > 0) coarsenedAt = k;
  }
  PetscCheck(coarsenedAt >= 0, comm, PETSC_ERR_PLIB, "the drop's blocks never coarsened in %d steps", 2 * DELAY);
  PetscCheck(coarsenedAt >= DELAY, comm, PETSC_ERR_PLIB,
             "blocks coarsened %" PetscInt_FMT " steps after the drop went, before the delay of %d", coarsenedAt,
             DELAY);
  PetscCall(PetscPrintf(comm, "the drop's blocks coarsened %" PetscInt_FMT " steps after it went (delay %d)\n",
                        coarsenedAt, DELAY));
  PetscCall(PffFlowDestroy(&flow));
  PetscCall(PffGridDestroy(&tc.grid));
  PetscCall(PetscFinalize());
  return 0;
}
