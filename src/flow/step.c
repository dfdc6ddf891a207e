/* One PF-FLIP time step (DESIGN.md §4): P2G, phase field, forces, pressure, G2P, escaped particles,
   advection. Each stage is a PETSc log stage and is timed for the run summary. */
#include "flowimpl.h"
#if defined(__GLIBC__)
#include <malloc.h>
#endif

static PetscLogStage PffFlowStages[PFF_FLOW_NSTAGES];
static PetscBool     PffFlowStagesRegistered = PETSC_FALSE;

/* the two-phase model's volume on the cell centres: src/particles/volume.c says why */
PetscErrorCode PffFlowSplat_Private(PffFlow f, PffParticles part, const PetscReal density[])
{
  const PetscBool cells = (PetscBool)(f->chVol >= 0 && f->model == PFF_FLOW_TWO_PHASE);

  PetscFunctionBeginUser;
  PetscCall(PffParticlesP2G(part, density, f->chMass, f->chUt, cells ? -1 : f->chVol));
  if (cells) PetscCall(PffParticlesSplatVolume(part, f->chVol));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffFlowRegisterStages(void)
{
  PetscFunctionBeginUser;
  if (PffFlowStagesRegistered) PetscFunctionReturn(PETSC_SUCCESS);
  for (PetscInt s = 0; s < PFF_FLOW_NSTAGES; s++)
    PetscCall(PetscLogStageRegister(PffFlowStageNames[s], &PffFlowStages[s]));
  PffFlowStagesRegistered = PETSC_TRUE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

enum {
  PFF_STAGE_P2G,
  PFF_STAGE_PHASE,
  PFF_STAGE_FORCES,
  PFF_STAGE_PRESSURE,
  PFF_STAGE_G2P,
  PFF_STAGE_ADVECT,
  PFF_STAGE_ESCAPED,
  PFF_STAGE_CORRECTION,
  PFF_STAGE_ADAPT
};

static PetscErrorCode PffStageBegin(PetscInt s, PetscLogDouble *t0)
{
  PetscFunctionBeginUser;
  PetscCall(PetscLogStagePush(PffFlowStages[s]));
  PetscCall(PetscTime(t0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffStageEnd(PffFlowStepStats *st, PetscInt s, PetscLogDouble t0)
{
  PetscLogDouble t1;

  PetscFunctionBeginUser;
  PetscCall(PetscTime(&t1));
  st->stageTime[s] += t1 - t0;
  PetscCall(PetscLogStagePop());
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The phase field and density from the particles: P2G of mass (and momentum) and Eq. 7. */
static PetscErrorCode PffFlowTransfer(PffFlow f, PffFlowStepStats *st)
{
  PetscLogDouble t0 = 0;

  PetscFunctionBeginUser;
  PetscCall(PffStageBegin(PFF_STAGE_P2G, &t0));
  PetscCall(PffFlowSplat_Private(f, f->part, f->rho));
  if (f->band > 0) PetscCall(PffFlowLiquidBandFill_Private(f));
  PetscCall(PffStageEnd(st, PFF_STAGE_P2G, t0));
  PetscCall(PffStageBegin(PFF_STAGE_PHASE, &t0));
  PetscCall(PffFlowPhaseField_Private(f));
  PetscCall(PffStageEnd(st, PFF_STAGE_PHASE, t0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowUpdateFields(PffFlow f, PetscBool vorticity)
{
  PffFlowStepStats st;

  PetscFunctionBeginUser;
  PetscCall(PffFlowRegisterStages());
  PetscCall(PetscMemzero(&st, sizeof(st)));
  PetscCall(PffFlowCheckTopology_Private(f));
  PetscCall(PffFlowTransfer(f, &st));
  if (vorticity) PetscCall(PffFlowVorticity_Private(f, f->chU));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* dt from the CFL number on the finest cells, the growth of velocity under gravity over one step,
   (with a physical viscosity) the explicit limit of Eq. 13 that keeps alpha >= 0 on the finest level,
   -flow_dt_max and the time dtmax to the next output. */
static PetscErrorCode PffFlowChooseDt(PffFlow f, PetscReal umax, PetscReal dtmax, PetscReal *dt)
{
  PetscReal h0, g = 0, numax = PetscMax(f->nu[0], f->nu[1]), d = PETSC_MAX_REAL;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetSizes(f->grid, NULL, NULL, NULL, &h0, NULL));
  for (int a = 0; a < 3; a++) g += f->gravity[a] * f->gravity[a];
  g = PetscSqrtReal(g);
  if (umax > 0) d = f->cfl * h0 / umax;
  if (g > 0 && !f->prescribed) d = PetscMin(d, PetscSqrtReal(f->cfl * h0 / g));
  if (numax > 0 && !f->prescribed) d = PetscMin(d, h0 * h0 / (6 * numax));
  d = PetscMin(d, f->dtMax);
  /* the time to the next output (or the end) in one step if it fits, in two equal ones if it fits in
     two: no sliver step is left before it (a sliver once inflated a velocity-based volume correction,
     which scaled with 1/dt; the displacement of correction.c does not, but a sliver is still wasted work) */
  if (dtmax <= d)
    d = dtmax;
  else if (dtmax < 2 * d)
    d = 0.5 * dtmax;
  PetscCheck(d > 0 && d < PETSC_MAX_REAL, f->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "no finite time step: the flow is at rest with no gravity; set -flow_dt_max");
  *dt = d;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A prescribed field may grow within the step: the time-reversing shear field vanishes at T/4, where
   the speed at t alone allows a step across its next maximum (at 16^3 one step went from t = 0.25 T
   to 1.12 T). The speed is therefore the maximum over t, t + dt/2 and t + dt, and dt shrinks until
   it obeys the CFL number for that maximum (umax only grows as dt does not, so this ends). */
static PetscErrorCode PffFlowPrescribedDt(PffFlow f, PetscReal dtmax, PetscReal *umax, PetscReal *dt)
{
  PetscReal u = 0, ue = 0, d;
  PetscBool settled = PETSC_FALSE;

  PetscFunctionBeginUser;
  /* the speed at t is the previous step's sample at its t + dt (each fill costs sin/cos per face) */
  if (f->prescribedNextT == f->t)
    u = f->prescribedNextU;
  else {
    PetscCall(PffFlowPrescribe_Private(f, f->t));
    PetscCall(PffFlowGetDiagnostics(f, &u, NULL));
  }
  PetscCall(PffFlowChooseDt(f, u, dtmax, &d));
  for (PetscInt it = 0; it < 20 && !settled; it++) {
    PetscReal um, dn;
    /* t + dt first, so that the grid holds the mid-step field the advection uses when d settles */
    PetscCall(PffFlowPrescribe_Private(f, f->t + d));
    PetscCall(PffFlowGetDiagnostics(f, &ue, NULL));
    PetscCall(PffFlowPrescribe_Private(f, f->t + 0.5 * d));
    PetscCall(PffFlowGetDiagnostics(f, &um, NULL));
    u = PetscMax(u, PetscMax(um, ue));
    PetscCall(PffFlowChooseDt(f, u, dtmax, &dn));
    if (dn >= d * (1 - 1e-12))
      settled = PETSC_TRUE;
    else
      d = dn;
  }
  if (!settled) PetscCall(PffFlowPrescribe_Private(f, f->t + 0.5 * d));
  f->prescribedNextT = settled ? f->t + d : PETSC_MAX_REAL;
  f->prescribedNextU = ue;
  *umax              = u;
  *dt                = d;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* RK3 advection (Sec. 3.7) through the projected velocity: liquid particles through the liquid
   velocity extrapolated into the air by -flow_extrapolate_layers faces, air particles through u. A
   prescribed field and zero layers use u for both (chUl is then not allocated). With the volume
   correction both channels carry its displacement as d / dt (correction.c). */
static PetscErrorCode PffFlowAdvect(PffFlow f, PetscReal dt, PffFlowStepStats *st)
{
  PetscInt  ch[PFF_PARTICLE_NTYPES] = {f->chU, f->chU};
  PetscBool extrapolated            = PETSC_FALSE;

  PetscFunctionBeginUser;
  if (f->model == PFF_FLOW_LIQUID && !f->prescribed) {
    /* the liquid model's G2P extrapolated this step's u into chUl already, and nothing changed u since; its
       volume correction added the displacement in chUa (liquidcorr.c) */
    ch[PFF_PARTICLE_LIQUID] = f->chUa >= 0 ? f->chUa : f->chUl;
    PetscCall(PffParticlesAdvectPerType(f->part, ch, dt, f->solid, f->solidCtx, &st->advect));
    if (f->band > 0) PetscCall(PffFlowLiquidBandAdvect_Private(f, dt, ch[PFF_PARTICLE_LIQUID], st));
    PetscFunctionReturn(PETSC_SUCCESS);
  } else if (f->chUlMask >= 0) {
    PetscInt64 faces = 0;
    PetscCall(PffExtrapolateLiquidVelocity(f->grid, f->chU, f->chPhiF, f->chOpen, f->extrapLayers, f->chUlMask, f->chUl,
                                           f->chUlWork, &faces));
    PetscCall(PetscInfo(NULL, "liquid velocity extrapolated to %" PetscInt64_FMT " air faces\n", faces));
    ch[PFF_PARTICLE_LIQUID] = f->chUl;
    extrapolated            = PETSC_TRUE;
  }
  if (f->chUa >= 0) {
    PetscCall(PffFlowCorrectionVelocity_Private(f, dt, extrapolated));
    ch[PFF_PARTICLE_LIQUID] = f->chUl;
    ch[PFF_PARTICLE_AIR]    = f->chUa;
  }
  PetscCall(PffParticlesAdvectPerType(f->part, ch, dt, f->solid, f->solidCtx, &st->advect));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowStep(PffFlow f, PetscReal dtmax, PffFlowStepStats *st)
{
  PetscLogDouble t0   = 0;
  PetscReal      umax = 0, dt = 0, h0, alpha[PFF_PARTICLE_NTYPES * PFF_GRID_MAX_LEVELS];
  PetscInt64     count[PFF_PARTICLE_NTYPES];
  PetscReal      mass[PFF_PARTICLE_NTYPES];

  PetscFunctionBeginUser;
  PetscCheck(f->setupcalled, f->comm, PETSC_ERR_ORDER, "PffFlowSetUp() must come before PffFlowStep()");
  PetscCall(PffFlowRegisterStages());
  PetscCall(PetscMemzero(st, sizeof(*st)));
  /* the flow's own reset after a grid change (open faces, the reference lattice) is part of the adaptation */
  if (f->adapt.levels > 0 && f->step % f->adapt.interval == 0) {
    PetscCall(PffStageBegin(PFF_STAGE_ADAPT, &t0));
    PetscCall(PffFlowAdapt_Private(f, &st->adapt));
    PetscCall(PffFlowCheckTopology_Private(f));
    PetscCall(PffStageEnd(st, PFF_STAGE_ADAPT, t0));
  }
  if (f->model == PFF_FLOW_LIQUID && f->step > 0) {
    PetscInt every, nlevels;
    PetscCall(PffTallGetSizing(f->tall, NULL, &every));
    PetscCall(PffGridGetSizes(f->grid, NULL, &nlevels, NULL, NULL, NULL));
    if (every > 0 && nlevels > 1 && f->step % every == 0) {
      PetscCall(PffStageBegin(PFF_STAGE_ADAPT, &t0));
      PetscCall(PffFlowLiquidQuadtreeStep_Private(f, &st->adapt));
      PetscCall(PffFlowCheckTopology_Private(f));
      PetscCall(PffStageEnd(st, PFF_STAGE_ADAPT, t0));
    }
  }
  PetscCall(PffFlowCheckTopology_Private(f));
  PetscCall(PffGridGetSizes(f->grid, NULL, NULL, NULL, &h0, NULL));
  if (f->prescribed)
    PetscCall(PffFlowPrescribedDt(f, dtmax, &umax, &dt));
  else {
    PetscCall(PffFlowMaxParticleSpeed_Private(f, &umax));
    PetscCall(PffFlowChooseDt(f, umax, dtmax, &dt));
  }
  st->dt   = dt;
  st->umax = umax;
  st->cfl  = umax * dt / h0;

  if (f->prescribed) {
    /* the field at mid-step (filled by PffFlowPrescribedDt): second order in time for the
       time-reversing benchmarks */
    PetscCall(PffStageBegin(PFF_STAGE_FORCES, &t0));
    PetscCall(PffGridHaloBegin(f->grid, f->chU));
    PetscCall(PffGridHaloEnd(f->grid, f->chU));
    PetscCall(PffStageEnd(st, PFF_STAGE_FORCES, t0));
  } else {
    PetscCall(PffFlowTransfer(f, st));
    if (f->band > 0) { /* the grid's level set from the particles and the grid's liquid together */
      PetscCall(PffStageBegin(PFF_STAGE_PHASE, &t0));
      PetscCall(PffFlowLiquidBandDistance_Private(f));
      PetscCall(PffStageEnd(st, PFF_STAGE_PHASE, t0));
    }

    PetscCall(PffStageBegin(PFF_STAGE_FORCES, &t0));
    PetscCall(PffFlowFaceVelocity_Private(f, dt));
    PetscCall(PffStageEnd(st, PFF_STAGE_FORCES, t0));

    PetscCall(PffStageBegin(PFF_STAGE_PRESSURE, &t0));
    if (f->usePressure && f->model == PFF_FLOW_LIQUID)
      PetscCall(PffFlowLiquidProject_Private(f, dt, &st->pressure));
    else if (f->usePressure) {
      PetscCall(PffPressureSetCoefficients(f->press, f->chBeta, f->chOpen));
      PetscCall(PffPressureProject(f->press, f->chU, dt, -1, f->chP, &st->pressure));
      PetscCall(PffPressureCheckSolve(f->press, &st->pressure, "Pressure", f->step + 1, f->t,
                                      "raise -pressure_ksp_max_it or loosen -pressure_ksp_rtol"));
    }
    /* the liquid model reads u and its change on owned faces only: its extrapolation exchanges the results */
    if (f->model != PFF_FLOW_LIQUID) {
      PetscCall(PffGridHaloBegin(f->grid, f->chU));
      PetscCall(PffGridHaloEnd(f->grid, f->chU));
    }
    PetscCall(PffStageEnd(st, PFF_STAGE_PRESSURE, t0));

    PetscCall(PffStageBegin(PFF_STAGE_G2P, &t0));
    PetscCall(PffFlowVelocityChange_Private(f));
    if (f->model != PFF_FLOW_LIQUID) {
      PetscCall(PffGridHaloBegin(f->grid, f->chUt));
      PetscCall(PffGridHaloEnd(f->grid, f->chUt));
    }
    PetscCall(PffFlowFlipRatios_Private(f, dt, alpha));
    if (f->model == PFF_FLOW_LIQUID)
      PetscCall(PffFlowLiquidG2P_Private(f, alpha));
    else
      PetscCall(PffParticlesG2P(f->part, f->chU, f->chUt, alpha));
    PetscCall(PffStageEnd(st, PFF_STAGE_G2P, t0));

    PetscCall(PffStageBegin(PFF_STAGE_ESCAPED, &t0));
    PetscCall(PffFlowEscaped_Private(f, &st->bubblesDeleted, &st->dropletCandidates));
    PetscCall(PffStageEnd(st, PFF_STAGE_ESCAPED, t0));

    if (f->chVol >= 0) {
      PetscCall(PffStageBegin(PFF_STAGE_CORRECTION, &t0));
      if (f->model == PFF_FLOW_LIQUID)
        PetscCall(PffFlowLiquidCorrection_Private(f, dt));
      else
        PetscCall(PffFlowVolumeCorrection_Private(f, st));
      PetscCall(PffStageEnd(st, PFF_STAGE_CORRECTION, t0));
    }
  }

  PetscCall(PffStageBegin(PFF_STAGE_ADVECT, &t0));
  PetscCall(PffFlowAdvect(f, dt, st));
  /* the reference lattice near moving bodies for their new poses, before the next P2G or frame reads it */
  PetscCall(PffFlowReferenceBodies_Private(f));
  PetscCall(PffStageEnd(st, PFF_STAGE_ADVECT, t0));

  f->t += dt;
  f->step++;
  f->dtPrev = dt;
#if defined(__GLIBC__)
  /* after a grid change the pressure, pffmg and the particles' scratch were made again on the new grid
     in this step; glibc keeps the pages of the old ones resident until it is told to trim */
  if (st->adapt.adapted) {
    PetscCall(PffStageBegin(PFF_STAGE_ADAPT, &t0));
    malloc_trim(0);
    PetscCall(PffStageEnd(st, PFF_STAGE_ADAPT, t0));
  }
#endif
  PetscCall(PffParticlesGetTotals(f->part, f->rho, count, mass));
  st->particles = count[0] + count[1];
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The largest |u| over the owned faces of face channel ch, over all ranks. */
PetscErrorCode PffFlowMaxFaceSpeed_Private(PffFlow f, PetscInt ch, PetscReal *umax)
{
  PetscInt  nlocal;
  PetscReal m = 0;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
  for (PetscInt lb = 0; lb < nlocal; lb++)
    for (PetscInt d = 0; d < 3; d++) {
      float   *u;
      PetscInt n3 = 0;
      float    mb = 0; /* in float, so that the loop vectorises; the max of floats is one of them */
      PetscCall(PffFlowBlockData_Private(f, lb, d, 1, &ch, &u, &n3));
#pragma omp simd reduction(max : mb)
      for (PetscInt c = 0; c < n3; c++) mb = PetscMax(mb, fabsf(u[c]));
      m = PetscMax(m, (PetscReal)mb);
    }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &m, 1, MPIU_REAL, MPI_MAX, f->comm));
  *umax = m;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowGetDiagnostics(PffFlow f, PetscReal *umax, PetscReal *liquidVolume)
{
  PetscFunctionBeginUser;
  if (umax) PetscCall(PffFlowMaxFaceSpeed_Private(f, f->chU, umax));
  /* one definition of the liquid volume: the drift checks' */
  if (liquidVolume) PetscCall(PffFlowGetPhaseVolumes(f, liquidVolume, NULL));
  PetscFunctionReturn(PETSC_SUCCESS);
}
