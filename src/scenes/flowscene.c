/* The fluid-scene driver: -sim_* options, the time loop, diagnostics CSV, frames and the run
   summary with each stage's share of the step time. */
#include "flowscene.h"
#include <sys/resource.h>
#include <errno.h>

PetscErrorCode PffFlowSceneDefault(const char key[], const char value[])
{
  PetscBool set;

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsHasName(NULL, NULL, key, &set));
  if (!set) PetscCall(PetscOptionsSetValue(NULL, key, value));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowSceneDefaultReal(const char key[], PetscReal value)
{
  char buf[64];

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(buf, sizeof(buf), "%.17g", (double)value));
  PetscCall(PffFlowSceneDefault(key, buf));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowSceneDomain(PffFlowScene *fs, PetscReal lo[3], PetscReal hi[3])
{
  PetscFunctionBeginUser;
  /* from the set parameters, so that it also serves before PffGridSetUp (ops.gridsetup) */
  PetscCall(PffGridGetDomain(fs->grid, lo, hi));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* With -adapt_levels L the grid starts on its coarsest adaptive level everywhere, so that nothing (grid
   channels, pressure, the first seed) is ever allocated at the finest level over the whole domain; the
   adaptive seed then refines towards the interface (docs/flow.md, "Adaptivity"). This replaces any
   static refinement of the scene. A value that is not a valid level count is left to the flow, which
   names the key. */
static PetscErrorCode PffFlowSceneAdaptiveStart(PffFlowScene *fs)
{
  char      val[64];
  PetscBool set;
  PetscInt  cells[3], n0, nlevels, nblocks = 1, *map;
  char     *end;

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsGetString(NULL, NULL, "-adapt_levels", val, sizeof(val), &set));
  if (!set) PetscFunctionReturn(PETSC_SUCCESS);
  const long al = strtol(val, &end, 10);
  PetscCall(PffGridGetCells(fs->grid, cells));
  PetscCall(PffGridGetSizes(fs->grid, &n0, &nlevels, NULL, NULL, NULL));
  if (*end || end == val || al < 2 || al > nlevels) PetscFunctionReturn(PETSC_SUCCESS);
  for (int d = 0; d < 3; d++) nblocks *= cells[d] / n0;
  PetscCall(PetscMalloc1(nblocks, &map));
  for (PetscInt b = 0; b < nblocks; b++) map[b] = (PetscInt)al - 1;
  PetscCall(PffGridSetRefinementMap(fs->grid, map));
  PetscCall(PetscFree(map));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Per phase (PFF_PARTICLE_LIQUID, PFF_PARTICLE_AIR): the option of its volume-drift bound and its name. */
static const char *const PffFlowSceneDriftKeys[PFF_PARTICLE_NTYPES]  = {"-sim_max_volume_drift",
                                                                        "-sim_max_gas_volume_drift"};
static const char *const PffFlowScenePhaseNames[PFF_PARTICLE_NTYPES] = {"liquid", "gas"};

static PetscErrorCode PffFlowSceneSetFromOptions(PffScene s)
{
  PffFlowScene *fs = (PffFlowScene *)s->data;

  PetscFunctionBeginUser;
  if (fs->ops.setfromoptions) PetscCall(fs->ops.setfromoptions(fs));
  PetscOptionsBegin(s->comm, NULL, "Simulation run", "PffScene");
  PetscCall(PffOptionsReal("-sim_t_end",
                           "End time (in the scene time unit: t0 = sqrt(W/g) for rt3d and rt_paper, seconds otherwise)",
                           NULL, fs->tEnd, &fs->tEnd, NULL));
  PetscCall(PffOptionsReal("-sim_output_interval",
                           "Time between frames, in the scene time unit (0: first and last only)", NULL,
                           fs->outputInterval, &fs->outputInterval, NULL));
  PetscCall(PffOptionsInt("-sim_max_steps", "Stop after this many steps (0: no limit)", NULL, fs->maxSteps,
                          &fs->maxSteps, NULL));
  PetscCall(PffOptionsBool("-sim_frames", "Write HDF5 frames", NULL, fs->frames, &fs->frames, NULL));
  PetscCall(PffOptionsBool("-sim_frame_particles", "Include the particles in frames", NULL, fs->frameParticles,
                           &fs->frameParticles, NULL));
  PetscCall(PffOptionsInt("-sim_checkpoint_every", "Write <output_dir>/checkpoint.h5 every this many steps (0: never)",
                          NULL, fs->checkpointEvery, &fs->checkpointEvery, NULL));
  PetscCall(PetscOptionsString("-sim_restart", "Continue from this checkpoint (any rank count)", NULL, fs->restart,
                               fs->restart, sizeof(fs->restart), NULL));
  PetscCall(PffOptionsBool("-sim_check_particles",
                           "Fail at the end unless the liquid particle count is unchanged and the gas count changed "
                           "only by deleted bubbles (for tests)",
                           NULL, fs->checkParticles, &fs->checkParticles, NULL));
  PetscCall(PffOptionsReal("-sim_max_volume_drift",
                           "Fail as soon as the liquid volume drift |V - V0| / V0 after a step exceeds this (0: no "
                           "check; for tests)",
                           NULL, fs->driftBound[PFF_PARTICLE_LIQUID], &fs->driftBound[PFF_PARTICLE_LIQUID], NULL));
  PetscCall(PffOptionsReal("-sim_max_gas_volume_drift",
                           "Fail as soon as the gas volume drift |V - V0| / V0 after a step exceeds this (0: no "
                           "check; for tests)",
                           NULL, fs->driftBound[PFF_PARTICLE_AIR], &fs->driftBound[PFF_PARTICLE_AIR], NULL));
  PetscOptionsEnd();
  if (fs->restart[0]) {
    PetscMPIInt rank;
    int         bad     = 0;
    const char *problem = NULL;
    PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
    if (rank == 0) problem = PffFileProblem(fs->restart);
    bad = problem != NULL;
    PetscCallMPI(MPI_Bcast(&bad, 1, MPI_INT, 0, s->comm));
    PetscCheck(!bad, s->comm, PETSC_ERR_FILE_OPEN, "-sim_restart %s cannot be read: %s", fs->restart,
               rank == 0 ? problem : "see rank 0");
  }
  PetscCheck(fs->checkpointEvery >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-sim_checkpoint_every %" PetscInt_FMT " is invalid: must be >= 0", fs->checkpointEvery);
  PetscCheck(fs->tEnd > 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-sim_t_end %g is invalid: must be positive",
             (double)fs->tEnd);
  PetscCheck(fs->outputInterval >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-sim_output_interval %g is invalid: must be >= 0", (double)fs->outputInterval);
  PetscCheck(fs->maxSteps >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-sim_max_steps %" PetscInt_FMT " is invalid: must be >= 0", fs->maxSteps);
  for (PetscInt k = 0; k < PFF_PARTICLE_NTYPES; k++)
    PetscCheck(!PetscIsInfOrNanReal(fs->driftBound[k]) && fs->driftBound[k] >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE,
               "%s %g is invalid: must be finite and >= 0 (0: no check)", PffFlowSceneDriftKeys[k],
               (double)fs->driftBound[k]);
  /* grid, flow and scene set-up are validated here, before the driver checks unused options */
  PetscCall(PffGridCreate(s->comm, &fs->grid));
  PetscCall(PffGridSetFromOptions(fs->grid));
  if (fs->ops.gridsetup) PetscCall(fs->ops.gridsetup(fs));
  PetscCall(PffFlowSceneAdaptiveStart(fs));
  PetscCall(PffGridSetUp(fs->grid));
  PetscCall(PffFlowCreate(fs->grid, &fs->flow));
  PetscCall(PffFlowSetFromOptions(fs->flow));
  if (fs->ops.setup) PetscCall(fs->ops.setup(fs));
  PetscCall(PffFlowSetUp(fs->flow));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffFlowSceneWriteFrame(PffFlowScene *fs, PetscInt frame)
{
  char      path[PETSC_MAX_PATH_LEN];
  PetscReal t;
  PetscInt  step;

  PetscFunctionBeginUser;
  if (!fs->frames) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PffFlowGetTime(fs->flow, &t, &step));
  PetscCall(PffFlowUpdateFields(fs->flow, PETSC_TRUE));
  PetscCall(PetscSNPrintf(path, sizeof(path), "%s/frame_%04" PetscInt_FMT ".h5", fs->scene->outdir, frame));
  if (fs->frameParticles) {
    PffParticles p;
    PetscCall(PffFlowGetParticles(fs->flow, &p));
    PetscCall(PffIOWriteFrameParticles(fs->grid, p, path, t, step, fs->scene->name));
  } else
    PetscCall(PffIOWriteFrame(fs->grid, path, t, step, fs->scene->name));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Global particle counts and masses per type. Collective. */
static PetscErrorCode PffFlowSceneCount(PffFlowScene *fs, PetscInt64 count[PFF_PARTICLE_NTYPES],
                                        PetscReal mass[PFF_PARTICLE_NTYPES])
{
  PffParticles p;
  PetscReal    rho[PFF_PARTICLE_NTYPES];

  PetscFunctionBeginUser;
  PetscCall(PffFlowGetParticles(fs->flow, &p));
  PetscCall(PffFlowGetDensities(fs->flow, rho));
  PetscCall(PffParticlesGetTotals(p, rho, count, mass));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Volumes of the phases in the fluid cells (PffFlowGetPhaseVolumes) from the phase field now on the grid,
   their drifts (V - V0) / V0 since the reference and the max |drift| so far. A phase without volume at
   the start has drift 0. Collective. */
static PetscErrorCode PffFlowSceneVolumes(PffFlowScene *fs)
{
  PetscReal v[PFF_PARTICLE_NTYPES];

  PetscFunctionBeginUser;
  PetscCall(PffFlowGetPhaseVolumes(fs->flow, &v[PFF_PARTICLE_LIQUID], &v[PFF_PARTICLE_AIR]));
  fs->liquidVolume = v[PFF_PARTICLE_LIQUID];
  fs->gasVolume    = v[PFF_PARTICLE_AIR];
  for (PetscInt k = 0; k < PFF_PARTICLE_NTYPES; k++) {
    const PetscReal v0 = fs->volumeStart[k];
    fs->drift[k]       = v0 > 0 ? (v[k] - v0) / v0 : 0;
    fs->driftMax[k]    = PetscMax(fs->driftMax[k], PetscAbsReal(fs->drift[k]));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* With -sim_max_volume_drift or -sim_max_gas_volume_drift, a drift of the latest row past its bound
   fails the run (after the row is written, so the CSV shows it). Collective (the drifts are global). */
static PetscErrorCode PffFlowSceneCheckDrift(PffFlowScene *fs, PetscInt step)
{
  const PetscReal v[PFF_PARTICLE_NTYPES] = {fs->liquidVolume, fs->gasVolume};

  PetscFunctionBeginUser;
  for (PetscInt k = 0; k < PFF_PARTICLE_NTYPES; k++) {
    const PetscReal v0 = fs->volumeStart[k], bound = fs->driftBound[k];
    PetscCheck(bound == 0 || PetscAbsReal(fs->drift[k]) <= bound, fs->scene->comm, PETSC_ERR_NOT_CONVERGED,
               "%s: the %s volume drifted by %.3e (V %.9e, V0 %.9e) at step %" PetscInt_FMT ", beyond the bound %g",
               PffFlowSceneDriftKeys[k], PffFlowScenePhaseNames[k], (double)fs->drift[k], (double)v[k], (double)v0,
               step, (double)bound);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -sim_check_particles under adaptivity: the liquid particle mass drift from probabilistic coarsening
   (issue 14's bound) */
#define PFF_FLOW_SCENE_ADAPT_MASS_TOL 5e-3

/* The conservation line of every fluid run: particles are created only by the seed and removed only
   by bubble deletion (Sec. 3.4), so the liquid count is constant and the gas count drops by the
   deleted bubbles. Counts are exact; the volume drifts (V - V0) / V0 of the fluid cells are printed to
   3 digits, at the end and as the max |drift| over the rows since the seed (their drift comes from the
   phase field, not from lost particles). With -sim_check_particles a broken count fails the run; with
   -sim_max_volume_drift or -sim_max_gas_volume_drift a drift past the bound has already failed it
   (PffFlowSceneCheckDrift), except a max carried from the run a checkpoint continues, which fails here.
   Collective. */
static PetscErrorCode PffFlowSceneConservation(PffFlowScene *fs)
{
  const PetscInt64 *c0 = fs->countStart, *c1 = fs->countEnd;
  const PetscReal  *dmax = fs->driftMax, *bound = fs->driftBound;
  PetscBool         counts  = (PetscBool)(c1[PFF_PARTICLE_LIQUID] == c0[PFF_PARTICLE_LIQUID] &&
                                 c1[PFF_PARTICLE_AIR] == c0[PFF_PARTICLE_AIR] - fs->bubblesDeletedRun);
  PetscBool         volumes = PETSC_TRUE, band = (PetscBool)(fs->bandDeletedRun || fs->bandSeededRun);
  PetscInt          adapt;

  PetscFunctionBeginUser;
  PetscCall(PffFlowGetAdaptLevels(fs->flow, &adapt));
  /* the narrow band deletes and reseeds particles: the count (corrected by them) is the check, not the mass */
  if (band) adapt = 0;
  if (adapt) {
    /* splits and coarsening change the counts; coarsening keeps the mass in expectation only */
    PetscReal drift[PFF_PARTICLE_NTYPES];
    for (PetscInt k = 0; k < PFF_PARTICLE_NTYPES; k++)
      drift[k] = fs->massStart[k] > 0 ? fs->massEnd[k] / fs->massStart[k] - 1 : 0;
    counts = (PetscBool)(PetscAbsReal(drift[PFF_PARTICLE_LIQUID]) <= PFF_FLOW_SCENE_ADAPT_MASS_TOL);
    PetscCall(PetscPrintf(fs->scene->comm,
                          "adaptivity: particle mass drift liquid %.2e  gas %.2e (split, coarsening%s)\n",
                          (double)drift[PFF_PARTICLE_LIQUID], (double)drift[PFF_PARTICLE_AIR],
                          fs->bubblesDeletedRun ? ", deleted bubbles" : ""));
  }
  for (PetscInt k = 0; k < PFF_PARTICLE_NTYPES; k++)
    if (bound[k] > 0 && dmax[k] > bound[k]) volumes = PETSC_FALSE;
  if (band)
    PetscCall(PetscPrintf(fs->scene->comm,
                          "narrow band: %" PetscInt64_FMT " liquid particles deleted below the band, %" PetscInt64_FMT
                          " reseeded in it (the start count below includes both)\n",
                          fs->bandDeletedRun, fs->bandSeededRun));
  PetscCall(PetscPrintf(fs->scene->comm,
                        "conservation: liquid particles %" PetscInt64_FMT " (start %" PetscInt64_FMT
                        ")  gas particles %" PetscInt64_FMT " (start %" PetscInt64_FMT ", %" PetscInt64_FMT
                        " deleted as bubbles)  liquid volume drift %.2e (max |drift| %.2e)  gas volume drift %.2e "
                        "(max |drift| %.2e)  %s\n",
                        c1[PFF_PARTICLE_LIQUID], c0[PFF_PARTICLE_LIQUID], c1[PFF_PARTICLE_AIR], c0[PFF_PARTICLE_AIR],
                        fs->bubblesDeletedRun, (double)fs->drift[PFF_PARTICLE_LIQUID],
                        (double)dmax[PFF_PARTICLE_LIQUID], (double)fs->drift[PFF_PARTICLE_AIR],
                        (double)dmax[PFF_PARTICLE_AIR], counts && volumes ? "ok" : "BROKEN"));
  for (PetscInt k = 0; k < PFF_PARTICLE_NTYPES; k++)
    PetscCheck(bound[k] == 0 || dmax[k] <= bound[k], fs->scene->comm, PETSC_ERR_NOT_CONVERGED,
               "%s: the %s volume drift reached %.3e since the seed (before the restart), beyond the bound %g",
               PffFlowSceneDriftKeys[k], PffFlowScenePhaseNames[k], (double)dmax[k], (double)bound[k]);
  PetscCheck(!fs->checkParticles || counts || !adapt, fs->scene->comm, PETSC_ERR_PLIB,
             "-sim_check_particles: the liquid particle mass drifted by more than %g under adaptivity: %.9e -> %.9e",
             (double)PFF_FLOW_SCENE_ADAPT_MASS_TOL, (double)fs->massStart[PFF_PARTICLE_LIQUID],
             (double)fs->massEnd[PFF_PARTICLE_LIQUID]);
  PetscCheck(!fs->checkParticles || counts, fs->scene->comm, PETSC_ERR_PLIB,
             "-sim_check_particles: particles were lost or created: liquid %" PetscInt64_FMT " -> %" PetscInt64_FMT
             ", gas %" PetscInt64_FMT " -> %" PetscInt64_FMT " with %" PetscInt64_FMT " deleted as bubbles",
             c0[PFF_PARTICLE_LIQUID], c1[PFF_PARTICLE_LIQUID], c0[PFF_PARTICLE_AIR], c1[PFF_PARTICLE_AIR],
             fs->bubblesDeletedRun);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The extra values of a scene checkpoint, each pair liquid then gas: the reference volumes V0 and the
   max |drift| so far, so that a restarted run measures its drift since the seed, as the uninterrupted
   run would; the particle counts after the seed and the bubbles deleted since, so that its
   conservation line counts from the run's start; the densities, which a restart must not change; and the state of
   the liquid volume's control (PffFlowGetVolumeControl), so that it goes on as in the uninterrupted run.
   Checkpoints written before the counts and densities were stored hold only the first 4, those written before the
   control's state the first 9 (a restart from them starts the control again). */
#define PFF_FLOW_SCENE_NEXTRA 11
#define PFF_FLOW_SCENE_NEXTRA_COUNTS 9
#define PFF_FLOW_SCENE_NEXTRA_LEGACY 4

/* <output_dir>/checkpoint.h5, written to a temporary name and renamed by the io module. The rigid bodies' state
   (PffBodiesGetCheckpointState) follows the scene's extra values. */
static PetscErrorCode PffFlowSceneCheckpoint(PffFlowScene *fs)
{
  PetscReal   *extra, rho[PFF_PARTICLE_NTYPES];
  char         path[PETSC_MAX_PATH_LEN];
  PetscReal    t;
  PetscInt     step, nbody;
  PffParticles p;
  PffBodies    bodies;

  PetscFunctionBeginUser;
  PetscCall(PffFlowGetBodies(fs->flow, &bodies));
  PetscCall(PffBodiesGetCheckpointState(bodies, &nbody, NULL));
  PetscCall(PetscMalloc1(PFF_FLOW_SCENE_NEXTRA + nbody, &extra));
  if (nbody) PetscCall(PffBodiesGetCheckpointState(bodies, &nbody, extra + PFF_FLOW_SCENE_NEXTRA));
  PetscCall(PffFlowGetDensities(fs->flow, rho));
  for (PetscInt k = 0; k < PFF_PARTICLE_NTYPES; k++) {
    extra[k]     = fs->volumeStart[k];
    extra[2 + k] = fs->driftMax[k];
    extra[4 + k] = (PetscReal)fs->countStart[k]; /* exact in double below 2^53 particles */
    extra[7 + k] = rho[k];
  }
  extra[6] = (PetscReal)fs->bubblesDeletedRun;
  PetscCall(PffFlowGetVolumeControl(fs->flow, &extra[9], &extra[10]));
  PetscCall(PffFlowGetTime(fs->flow, &t, &step));
  PetscCall(PffFlowGetParticles(fs->flow, &p));
  PetscCall(PetscSNPrintf(path, sizeof(path), "%s/checkpoint.h5", fs->scene->outdir));
  PetscCall(PffIOWriteCheckpoint(fs->grid, p, path, t, step, PFF_FLOW_SCENE_NEXTRA + nbody, extra, fs->scene->name));
  PetscCall(PetscFree(extra));
  PetscCall(PetscPrintf(fs->scene->comm, "checkpoint %s at step %" PetscInt_FMT "\n", path, step));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Seeds, or continues from -sim_restart: particles and fields from the checkpoint, then the fields
   that derive from the particles. The reference volumes V0 are those after the seed; a restart takes
   them and the max |drift| so far from the checkpoint. A checkpoint without them (written before they
   were stored) gives the volumes at the restart as V0, and the run says so. */
static PetscErrorCode PffFlowSceneStart(PffFlowScene *fs)
{
  PetscFunctionBeginUser;
  if (!fs->restart[0]) {
    PetscCall(PffFlowSeed(fs->flow, fs->ops.seed, fs->ctx));
    PetscCall(
        PffFlowGetPhaseVolumes(fs->flow, &fs->volumeStart[PFF_PARTICLE_LIQUID], &fs->volumeStart[PFF_PARTICLE_AIR]));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PffParticles p;
  PffBodies    bodies;
  PetscReal    t, *extra;
  PetscInt     step, nextra, nbody;
  PetscCall(PffFlowGetParticles(fs->flow, &p));
  PetscCall(PffFlowGetBodies(fs->flow, &bodies));
  PetscCall(PffBodiesGetCheckpointState(bodies, &nbody, NULL));
  PetscCall(PffIOGetCheckpointExtraCount(fs->grid, fs->restart, &nextra));
  /* the scene's values (nscene of them: a checkpoint from before the control's state has 9), then the bodies'
     (checkpoints before bodies were stored have none) */
  const PetscInt nscene =
      nextra == PFF_FLOW_SCENE_NEXTRA_COUNTS + nbody ? PFF_FLOW_SCENE_NEXTRA_COUNTS : PFF_FLOW_SCENE_NEXTRA;
  PetscCheck(nextra <= nscene || nextra == nscene + nbody, fs->scene->comm, PETSC_ERR_ARG_INCOMP,
             "-sim_restart %s holds the state of %" PetscInt_FMT " rigid bodies, the scene has %" PetscInt_FMT
             " (-body_<i>_*)",
             fs->restart, (nextra - nscene) / PFF_BODY_CHECKPOINT_VALUES, nbody / PFF_BODY_CHECKPOINT_VALUES);
  PetscCheck(!nbody || nextra == nscene + nbody, fs->scene->comm, PETSC_ERR_ARG_INCOMP,
             "-sim_restart %s holds no rigid bodies, the scene has %" PetscInt_FMT " (-body_<i>_*)", fs->restart,
             nbody / PFF_BODY_CHECKPOINT_VALUES);
  /* any other count is the reader's error: the checkpoint is not one of a fluid scene */
  if (nextra != 0 && nextra != PFF_FLOW_SCENE_NEXTRA_LEGACY) nextra = nscene + nbody;
  PetscCall(PetscMalloc1(PFF_FLOW_SCENE_NEXTRA + nbody, &extra));
  {
    /* an adaptive run continues on the grid the checkpoint was written on (its level map); a static one
       must match it, which the reader checks */
    PetscInt adapt;
    PetscCall(PffFlowGetAdaptLevels(fs->flow, &adapt));
    if (adapt) {
      PetscInt nb[3], fnb[3], *level;
      PetscCall(PffGridGetRaster(fs->grid, nb, NULL, NULL));
      PetscCall(PffIOReadLevels(fs->scene->comm, fs->restart, fnb, &level));
      if (fnb[0] == nb[0] && fnb[1] == nb[1] && fnb[2] == nb[2]) PetscCall(PffFlowAdaptSetMap(fs->flow, level));
      PetscCall(PetscFree(level));
    }
  }
  PetscCall(PffIOReadCheckpoint(fs->grid, p, fs->restart, &t, &step, nextra, extra));
  if (nextra == nscene + nbody) { /* the counts and densities are there */
    PetscReal rho[PFF_PARTICLE_NTYPES];
    char      diff[256] = "";
    PetscCall(PffFlowGetDensities(fs->flow, rho));
    for (PetscInt k = 0; k < PFF_PARTICLE_NTYPES; k++)
      if (PetscAbsReal(extra[7 + k] - rho[k]) > 1e-12 * rho[k])
        PetscCall(PetscSNPrintf(diff + strlen(diff), sizeof(diff) - strlen(diff), "; -rho_%s %g in the file, %g now",
                                k == PFF_PARTICLE_LIQUID ? "liquid" : "gas", (double)extra[7 + k], (double)rho[k]));
    PetscCheck(!diff[0], fs->scene->comm, PETSC_ERR_ARG_INCOMP, "-sim_restart %s was written with other physics: %s",
               fs->restart, diff + 2);
    for (PetscInt k = 0; k < PFF_PARTICLE_NTYPES; k++) fs->countStart[k] = (PetscInt64)extra[4 + k];
    fs->bubblesDeletedRun = (PetscInt64)extra[6];
    fs->countsCarried     = PETSC_TRUE;
    if (nscene == PFF_FLOW_SCENE_NEXTRA) PetscCall(PffFlowSetVolumeControl(fs->flow, extra[9], extra[10]));
  }
  if (nbody) PetscCall(PffBodiesSetCheckpointState(bodies, extra + nscene));
  PetscCall(PffFlowSetTime(fs->flow, t, step));
  PetscCall(PffFlowUpdateFields(fs->flow, PETSC_FALSE));
  fs->restarted = PETSC_TRUE;
  PetscCall(PetscPrintf(fs->scene->comm, "restarted from %s at step %" PetscInt_FMT ", t %.6e\n", fs->restart, step,
                        (double)t));
  if (nextra) {
    for (PetscInt k = 0; k < PFF_PARTICLE_NTYPES; k++) {
      fs->volumeStart[k] = extra[k];
      fs->driftMax[k]    = extra[PFF_PARTICLE_NTYPES + k];
    }
  } else {
    PetscCall(
        PffFlowGetPhaseVolumes(fs->flow, &fs->volumeStart[PFF_PARTICLE_LIQUID], &fs->volumeStart[PFF_PARTICLE_AIR]));
    PetscCall(PetscPrintf(fs->scene->comm,
                          "restart: %s holds no reference volumes; volume drifts are measured from the restart\n",
                          fs->restart));
  }
  PetscCall(PetscFree(extra));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffFlowSceneDiagRow(PffFlowScene *fs, PetscInt step, PetscReal t, const PffFlowStepStats *st,
                                          PetscLogDouble wall)
{
  PetscReal  umaxGrid, fraction;
  PetscInt64 cells;
  char       extra[512] = "";

  PetscFunctionBeginUser;
  PetscCall(PffFlowGetDiagnostics(fs->flow, &umaxGrid, NULL));
  PetscCall(PffFlowGetVolumeControl(fs->flow, NULL, &fraction));
  fs->umaxGrid = umaxGrid;
  PetscCall(PffFlowSceneVolumes(fs));
  if (fs->ops.diagnose) PetscCall(fs->ops.diagnose(fs, t, extra, sizeof(extra)));
  if (fs->diag) {
    PetscCall(PffGridGetCellCounts(fs->grid, NULL, &cells)); /* an adaptive grid's cost follows them */
    fprintf(fs->diag,
            "%" PetscInt_FMT ",%.9e,%.9e,%.6e,%.6e,%" PetscInt64_FMT ",%" PetscInt_FMT
            ",%.3e,%.6e,%.9e,%" PetscInt64_FMT ",%" PetscInt64_FMT ",%.4e,%.9e,%.6f%s,%" PetscInt64_FMT "\n",
            step, (double)t, (double)(t / fs->timeUnit), (double)st->dt, (double)st->cfl, st->particles,
            st->pressure.its, (double)st->pressure.rnorm, (double)umaxGrid, (double)fs->liquidVolume,
            st->bubblesDeleted, st->dropletCandidates, (double)wall, (double)fs->gasVolume, (double)fraction, extra,
            cells);
    fflush(fs->diag);
  }
  PetscCall(PffFlowSceneCheckDrift(fs, step));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* With -info: one line per rank and step with the step's wall time, each stage's, and the minor page faults since
   the previous line (*minflt; first touch of fresh memory), for per-rank and first-step breakdowns
   (docs/benchmarks.md). Not collective. */
static PetscErrorCode PffFlowSceneInfoStep(PetscInt step, PetscLogDouble wall, const PffFlowStepStats *st, long *minflt)
{
  PetscBool     on;
  struct rusage ru;
  char          line[512];
  size_t        len = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscInfoEnabled(PETSC_SMALLEST_CLASSID, &on)); /* the class of PetscInfo(NULL, ...) */
  if (!on) PetscFunctionReturn(PETSC_SUCCESS);
  const long now = getrusage(RUSAGE_SELF, &ru) == 0 ? ru.ru_minflt : *minflt;
  line[0]        = 0;
  for (PetscInt k = 0; k < PFF_FLOW_NSTAGES; k++) {
    PetscCall(
        PetscSNPrintf(line + len, sizeof(line) - len, " %s %.4f", PffFlowStageNames[k], (double)st->stageTime[k]));
    PetscCall(PetscStrlen(line, &len));
  }
  PetscCall(PetscInfo(NULL, "step %" PetscInt_FMT " wall %.4f s, minor page faults %ld, stages (s):%s\n", step,
                      (double)wall, now - *minflt, line));
  *minflt = now;
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffFlowSceneRun(PffScene s)
{
  PffFlowScene    *fs = (PffFlowScene *)s->data;
  PffProgress      prog;
  PffFlowStepStats st;
  PetscMPIInt      rank;
  PetscReal        t, tEnd = fs->tEnd * fs->timeUnit, every = fs->outputInterval * fs->timeUnit, nextOut;
  PetscInt         step, frame = 0;
  PetscLogDouble   total[PFF_FLOW_NSTAGES] = {0}, stepTime = 0, tstart, tnow;
  PetscBool        deleteBubbles;
  long             minflt = 0;
  PffBodies        bodies;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  PetscCall(PffGridView(fs->grid, NULL));
  PetscCall(PffFlowSceneStart(fs));
  PetscCall(PffSceneMakeOutputDir_Private(s));
  {
    /* a restart carries the counts; particle masses are measured from the restart */
    PetscInt64 now[PFF_PARTICLE_NTYPES];
    PetscCall(PffFlowSceneCount(fs, fs->countsCarried ? now : fs->countStart, fs->massStart));
  }
  PetscCall(PffFlowGetDeleteBubbles(fs->flow, &deleteBubbles));
  {
    char path[PETSC_MAX_PATH_LEN];
    int  err = 0;
    PetscCall(PetscSNPrintf(path, sizeof(path), "%s/%s_diag.csv", s->outdir, s->name));
    /* a restarted run appends to the diagnostics of the run it continues, or starts a new file */
    if (rank == 0) {
      fs->diag = fopen(path, fs->restarted ? "a" : "w");
      if (!fs->diag) err = errno;
    }
    PetscCallMPI(MPI_Bcast(&err, 1, MPI_INT, 0, s->comm));
    PetscCheck(!err, s->comm, PETSC_ERR_FILE_OPEN, "-output_dir %s: cannot write %s: %s", s->outdir, path,
               strerror(err));
    if (rank == 0 && !fseek(fs->diag, 0, SEEK_END) && ftell(fs->diag) == 0)
      fprintf(fs->diag,
              "step,t,t_over_t0,dt,cfl,particles,ksp_its,ksp_rnorm,umax_grid,liquid_volume,bubbles_deleted,"
              "droplet_candidates,wall_s,gas_volume,liquid_target_fraction%s,active_cells\n",
              fs->ops.diagHeader ? fs->ops.diagHeader : "");
  }
  PetscCall(PffFlowGetTime(fs->flow, &t, &step));
  PetscCall(PetscMemzero(&st, sizeof(st)));
  PetscCall(PffFlowGetBodies(fs->flow, &bodies));
  if (!fs->restarted) {
    PetscCall(PffFlowSceneDiagRow(fs, step, t, &st, 0));
    if (bodies) PetscCall(PffBodiesWriteCSV(bodies, s->outdir, step, t));
    PetscCall(PffFlowSceneWriteFrame(fs, frame++));
    nextOut = every > 0 ? t + every : tEnd;
  } else {
    /* frames continue the numbering of the interrupted run */
    const PetscReal done = every > 0 ? PetscFloorReal(t / every * (1 + 1e-12)) : 0;
    frame                = (PetscInt)done + 1;
    nextOut              = every > 0 ? (done + 1) * every : tEnd;
  }
  PetscCall(PffProgressStart(&prog, t, tEnd, step, fs->maxSteps));
  PetscCall(PetscTime(&tstart));
  {
    struct rusage ru; /* the first step's page faults count from here */
    if (getrusage(RUSAGE_SELF, &ru) == 0) minflt = ru.ru_minflt;
  }
  while (t < tEnd * (1 - 1e-12) && (!fs->maxSteps || step < fs->maxSteps)) {
    PetscLogDouble t0, t1;
    char           extra[512];
    PetscCall(PetscTime(&t0));
    PetscCall(PffFlowStep(fs->flow, PetscMin(nextOut, tEnd) - t, &st));
    PetscCall(PetscTime(&t1));
    PetscCall(PffFlowGetTime(fs->flow, &t, &step));
    for (PetscInt k = 0; k < PFF_FLOW_NSTAGES; k++) total[k] += st.stageTime[k];
    stepTime += t1 - t0;
    PetscCall(PffFlowSceneInfoStep(step, t1 - t0, &st, &minflt));
    if (deleteBubbles) fs->bubblesDeletedRun += st.bubblesDeleted;
    fs->bandDeletedRun += st.bandDeleted;
    fs->bandSeededRun += st.bandSeeded;
    fs->countStart[PFF_PARTICLE_LIQUID] += st.bandSeeded - st.bandDeleted;
    PetscCall(PffFlowSceneDiagRow(fs, step, t - st.dt, &st, t1 - t0));
    if (bodies) PetscCall(PffBodiesWriteCSV(bodies, s->outdir, step, t));
    PetscCall(PetscSNPrintf(extra, sizeof(extra),
                            "dt %.3e  CFL %.2f  particles %" PetscInt64_FMT "  ksp %" PetscInt_FMT
                            " %.1e  bubbles %" PetscInt64_FMT "  droplets %" PetscInt64_FMT,
                            (double)st.dt, (double)st.cfl, st.particles, st.pressure.its, (double)st.pressure.rnorm,
                            st.bubblesDeleted, st.dropletCandidates));
    if (st.bandDeleted || st.bandSeeded) {
      const size_t len = strlen(extra);
      PetscCall(PetscSNPrintf(extra + len, sizeof(extra) - len, "  band -%" PetscInt64_FMT " +%" PetscInt64_FMT,
                              st.bandDeleted, st.bandSeeded));
    }
    if (st.adapt.repartitioned) {
      const size_t len = strlen(extra);
      PetscCall(PetscSNPrintf(extra + len, sizeof(extra) - len,
                              "  repartition: imbalance %.3f -> %.3f, %" PetscInt_FMT
                              " blocks and %.2f MB moved in %.3f s",
                              (double)st.adapt.imbalanceBefore, (double)st.adapt.imbalance, st.adapt.grid.moved,
                              (double)st.adapt.grid.bytesMoved / 1048576.0, (double)st.adapt.grid.seconds));
    }
    if (st.adapt.particles.split || st.adapt.particles.marked || st.adapt.adapted) {
      const PffParticleAdaptStats *pa  = &st.adapt.particles;
      const size_t                 len = strlen(extra);
      PetscCall(PetscSNPrintf(extra + len, sizeof(extra) - len,
                              "  adapt: split %" PetscInt64_FMT " removed %" PetscInt64_FMT "/%" PetscInt64_FMT
                              " blocks +%" PetscInt_FMT " -%" PetscInt_FMT " moved %" PetscInt_FMT " imbalance %.3f",
                              pa->split, pa->removed, pa->marked, st.adapt.grid.refined, st.adapt.grid.coarsened,
                              st.adapt.grid.moved, (double)st.adapt.imbalance));
    }
    {
      /* the largest resident set of any rank now and its peak so far: adaptivity, splits and re-partitions
         move memory around */
      PetscLogDouble rss[2];
      struct rusage  ru;
      const size_t   len = strlen(extra);
      PetscCall(PetscMemoryGetCurrentUsage(&rss[0]));
      rss[1] = getrusage(RUSAGE_SELF, &ru) == 0 ? 1024.0 * (PetscLogDouble)ru.ru_maxrss : rss[0];
      PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, rss, 2, MPI_DOUBLE, MPI_MAX, s->comm));
      PetscCall(PetscSNPrintf(extra + len, sizeof(extra) - len, "  rss %.0f MB (peak %.0f)", rss[0] / 1048576.0,
                              rss[1] / 1048576.0));
    }
    PetscCall(PffProgressPrint(s->comm, &prog, step, t, extra));
    if (t >= nextOut * (1 - 1e-12) || t >= tEnd * (1 - 1e-12)) {
      PetscCall(PffFlowSceneWriteFrame(fs, frame++));
      nextOut = every > 0 ? nextOut + every : tEnd;
    }
    if (fs->checkpointEvery > 0 && step % fs->checkpointEvery == 0) PetscCall(PffFlowSceneCheckpoint(fs));
  }
  PetscCall(PetscTime(&tnow));
  PetscCall(PffFlowUpdateFields(fs->flow, PETSC_FALSE));
  /* the state at the end time (the step rows carry the time at which each step's fields were made) */
  PetscCall(PetscMemzero(&st, sizeof(st)));
  PetscCall(PffFlowSceneDiagRow(fs, step, t, &st, 0));
  PetscCall(PffFlowSceneCount(fs, fs->countEnd, fs->massEnd));
  if (fs->ops.finish) PetscCall(fs->ops.finish(fs));
  PetscCall(PffFlowSceneConservation(fs));
  /* the step count is the run's (restarts included), the wall time and the rate this process's */
  PetscCall(PetscPrintf(s->comm, "summary: %" PetscInt_FMT " steps  t %.6e  wall %.2f s  (%.3f s/step)", step,
                        (double)t, tnow - tstart, step > prog.step0 ? stepTime / (double)(step - prog.step0) : 0.0));
  if (fs->restarted)
    PetscCall(PetscPrintf(s->comm, "  over the %" PetscInt_FMT " steps since the restart at step %" PetscInt_FMT,
                          step - prog.step0, prog.step0));
  PetscCall(PetscPrintf(s->comm, "\n"));
  /* the slowest rank sets the pace: shares of the largest per-rank stage times */
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, total, PFF_FLOW_NSTAGES, MPI_DOUBLE, MPI_MAX, s->comm));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &stepTime, 1, MPI_DOUBLE, MPI_MAX, s->comm));
  PetscCall(PetscPrintf(s->comm, "summary: stage shares of the step time (max over ranks):"));
  for (PetscInt k = 0; k < PFF_FLOW_NSTAGES; k++)
    PetscCall(
        PetscPrintf(s->comm, "  %s %.1f%%", PffFlowStageNames[k], stepTime > 0 ? 100 * total[k] / stepTime : 0.0));
  PetscCall(PetscPrintf(s->comm, "\n"));
  if (fs->diag) {
    fclose(fs->diag);
    fs->diag = NULL;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffFlowSceneDestroy(PffScene s)
{
  PffFlowScene *fs = (PffFlowScene *)s->data;

  PetscFunctionBeginUser;
  if (fs->ops.destroy) PetscCall(fs->ops.destroy(fs));
  PetscCall(PetscFree(fs->ctx));
  PetscCall(PffFlowDestroy(&fs->flow));
  PetscCall(PffGridDestroy(&fs->grid));
  if (fs->diag) fclose(fs->diag);
  PetscCall(PetscFree(s->data));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowSceneCreate_Private(PffScene s, const PffFlowSceneOps *ops, void *ctx)
{
  PffFlowScene *fs;

  PetscFunctionBeginUser;
  PetscCall(PetscNew(&fs));
  fs->scene             = s;
  fs->ops               = *ops;
  fs->ctx               = ctx;
  fs->tEnd              = 1;
  fs->timeUnit          = 1;
  fs->frames            = PETSC_TRUE;
  fs->frameParticles    = PETSC_TRUE;
  s->data               = fs;
  s->ops.setfromoptions = PffFlowSceneSetFromOptions;
  s->ops.run            = PffFlowSceneRun;
  s->ops.destroy        = PffFlowSceneDestroy;
  PetscFunctionReturn(PETSC_SUCCESS);
}
