/* PffFlow life cycle and options. */
#include "flowimpl.h"

const char *const PffFlowModels[]               = {"two_phase", "liquid", "PffFlowModel", "PFF_FLOW_", NULL};
const char *const PffFlowCorrectionInterfaces[] = {"liquid",         "closed", "layer", "PffFlowCorrectionInterface",
                                                   "PFF_FLOW_CORR_", NULL};

const char *const PffFlowStageNames[] = {"P2G",    "PhaseField", "Forces",     "Pressure", "G2P",
                                         "Advect", "Escaped",    "Correction", "Adapt",    NULL};

PetscErrorCode PffFlowCreate(PffGrid grid, PffFlow *flow)
{
  PffFlow f;

  PetscFunctionBeginUser;
  PetscCall(PffInitializePackage());
  PetscCall(PetscNew(&f));
  PetscCall(PffGridGetComm(grid, &f->comm));
  f->grid                     = grid;
  f->rho[PFF_PARTICLE_LIQUID] = 1000;
  f->rho[PFF_PARTICLE_AIR]    = 1;
  f->gravity[1]               = -9.81;
  f->cfl                      = PFF_FLOW_CFL_DEFAULT;
  f->dtMax                    = PETSC_MAX_REAL;
  f->alphaPhi                 = PFF_FLOW_ALPHA_PHI_DEFAULT;
  f->deltaPhi                 = PFF_FLOW_DELTA_PHI_DEFAULT;
  f->flip                     = PFF_FLOW_FLIP_DEFAULT;
  f->volCorr                  = PFF_FLOW_VOLCORR_DEFAULT;
  f->volCorrMaxDisp           = PFF_FLOW_VOLCORR_MAXDISP_DEFAULT;
  f->volCorrRtol              = PFF_FLOW_VOLCORR_RTOL_DEFAULT;
  f->volControl               = PFF_FLOW_VOLCONTROL_DEFAULT;
  f->volFraction              = 1;
  f->usePressure              = PETSC_TRUE;
  f->deleteBubbles            = PETSC_TRUE;
  f->extrapLayers             = PFF_FLOW_EXTRAPOLATE_LAYERS_DEFAULT;
  f->adapt.band               = PFF_FLOW_ADAPT_BAND_DEFAULT;
  f->adapt.interval           = 1;
  f->adapt.delay              = PFF_FLOW_ADAPT_DELAY_DEFAULT;
  f->adapt.margin             = -1; /* ceil(CFL) */
  f->adapt.pweight            = PFF_FLOW_ADAPT_PARTICLE_WEIGHT_DEFAULT;
  f->adapt.imbalance          = PFF_FLOW_ADAPT_IMBALANCE_DEFAULT;
  f->chMass = f->chMassRef = f->chUt = f->chU = f->chPhiF = f->chBeta = f->chOpen = f->chPhi = f->chP = f->chCdiv =
      f->chVort                                                                                       = -1;
  f->chUl = f->chUlMask = f->chUlWork = f->chVol = f->chVolRef = f->chQ = f->chUa = -1;
  f->chLS = f->chDuL = f->chSolidD = f->chLSs = f->chTallH = -1;
  f->chLSg = f->chLSgWork = f->chUg = -1;
  f->model                          = PFF_FLOW_TWO_PHASE;
  PetscCall(PffParticlesCreate(grid, &f->part));
  PetscCall(PffPressureCreate(grid, &f->press));
  *flow = f;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowSetFromOptions(PffFlow f)
{
  PetscInt  ng = 3;
  PetscBool set;

  PetscFunctionBeginUser;
  PetscOptionsBegin(f->comm, NULL, "PF-FLIP flow", "PffFlow");
  PetscCall(
      PffOptionsReal("-rho_liquid", "Liquid density rho_l", "PffFlowSetFromOptions", f->rho[0], &f->rho[0], NULL));
  PetscCall(PffOptionsReal("-rho_gas", "Gas density rho_g", "PffFlowSetFromOptions", f->rho[1], &f->rho[1], NULL));
  PetscCall(PffOptionsReal("-nu_liquid", "Liquid kinematic viscosity (0: none, FLIP ratio -flow_flip)",
                           "PffFlowSetFromOptions", f->nu[0], &f->nu[0], NULL));
  PetscCall(PffOptionsReal("-nu_gas", "Gas kinematic viscosity (0: none)", "PffFlowSetFromOptions", f->nu[1], &f->nu[1],
                           NULL));
  PetscCall(PffOptionsRealArray("-gravity", "Gravity vector gx,gy,gz", "PffFlowSetFromOptions", f->gravity, &ng, &set));
  PetscCheck(!set || ng == 3, f->comm, PETSC_ERR_ARG_SIZ, "-gravity takes 3 values gx,gy,gz; got %" PetscInt_FMT, ng);
  PetscCall(PffOptionsReal("-flow_cfl", "CFL number of the time step (0, 4]", "PffFlowSetFromOptions", f->cfl, &f->cfl,
                           NULL));
  PetscCall(PffOptionsReal("-flow_dt_max", "Largest time step", "PffFlowSetFromOptions", f->dtMax, &f->dtMax, NULL));
  PetscCall(PffOptionsReal("-flow_alpha_phi", "Phase-field stiffness alpha_phi (Eq. 7)", "PffFlowSetFromOptions",
                           f->alphaPhi, &f->alphaPhi, NULL));
  PetscCall(PffOptionsReal("-flow_delta_phi", "Escaped-particle margin delta_phi (Sec. 3.4)", "PffFlowSetFromOptions",
                           f->deltaPhi, &f->deltaPhi, NULL));
  PetscCall(PffOptionsReal("-flow_flip", "FLIP ratio alpha where no viscosity is given", "PffFlowSetFromOptions",
                           f->flip, &f->flip, NULL));
  PetscCall(PffOptionsBool("-flow_pressure", "Solve the pressure projection", "PffFlowSetFromOptions", f->usePressure,
                           &f->usePressure, NULL));
  PetscCall(
      PffOptionsReal("-flow_volume_correction",
                     "Volume correction: share kappa of each cell's particle-volume error removed per step (0: off)",
                     "PffFlowSetFromOptions", f->volCorr, &f->volCorr, NULL));
  PetscCall(PffOptionsReal("-flow_volume_correction_max_displacement",
                           "Largest volume-correction displacement of a face per step, in cells",
                           "PffFlowSetFromOptions", f->volCorrMaxDisp, &f->volCorrMaxDisp, NULL));
  PetscCall(PffOptionsReal("-flow_volume_correction_rtol", "Relative tolerance of the volume-correction solve",
                           "PffFlowSetFromOptions", f->volCorrRtol, &f->volCorrRtol, NULL));
  PetscCall(PffOptionsReal("-flow_volume_control",
                           "Gain of the control that holds the liquid volume sum(phi V) at its value after the seed "
                           "through the liquid's target particle fraction (0: target 1, no control)",
                           "PffFlowSetFromOptions", f->volControl, &f->volControl, NULL));
  PetscCall(
      PffOptionsEnum("-flow_volume_correction_interface",
                     "What the correction's displacement may do at a liquid-gas face: liquid (the liquid crosses, "
                     "the gas moves into the gas only), closed (neither phase crosses) or layer (no face of an "
                     "interface cell moves)",
                     "PffFlowSetFromOptions", PffFlowCorrectionInterfaces, (PetscEnum)f->volCorrInterface,
                     (PetscEnum *)&f->volCorrInterface, NULL));
  PetscCall(PffOptionsBool("-flow_delete_bubbles", "Delete escaped air particles deep in liquid (Sec. 3.4)",
                           "PffFlowSetFromOptions", f->deleteBubbles, &f->deleteBubbles, NULL));
  PetscCall(PffOptionsEnum("-flow_model", "Flow model: two_phase (PF-FLIP) or liquid (free surface, tall cells)",
                           "PffFlowSetFromOptions", PffFlowModels, (PetscEnum)f->model, (PetscEnum *)&f->model, NULL));
  PetscCall(PffOptionsReal("-flow_liquid_band",
                           "Liquid model: FLIP particles only within this many cells under the surface, the grid's "
                           "level set and velocity below (narrow-band FLIP; 0: particles fill the liquid)",
                           "PffFlowSetFromOptions", f->band, &f->band, NULL));
  PetscCall(PffOptionsBool("-flow_liquid_surface_volume",
                           "Liquid model: the free surface where the particles' trilinear volume fraction is 1/2, not "
                           "Eq. 7's phi",
                           "PffFlowSetFromOptions", f->liquidSurfaceVolume, &f->liquidSurfaceVolume, NULL));
  PetscCall(PffOptionsInt("-flow_extrapolate_layers",
                          "Face layers the liquid velocity is extrapolated into the air for liquid particles (Sec. "
                          "3.7; 0: off)",
                          "PffFlowSetFromOptions", f->extrapLayers, &f->extrapLayers, NULL));
  PetscCall(PffOptionsInt("-adapt_levels",
                          "Dynamic adaptivity (Sec. 5.4) over this many grid levels (0: off; at most -grid_levels)",
                          "PffFlowSetFromOptions", f->adapt.levels, &f->adapt.levels, NULL));
  PetscCall(PffOptionsReal("-adapt_band", "Refinement band factor beta_bw: level floor(beta_bw d / block size)",
                           "PffFlowSetFromOptions", f->adapt.band, &f->adapt.band, NULL));
  PetscCall(PffOptionsInt("-adapt_interval", "Steps between adaptations", "PffFlowSetFromOptions", f->adapt.interval,
                          &f->adapt.interval, NULL));
  PetscCall(PffOptionsInt("-adapt_coarsen_delay", "Steps a particle must ask for a coarser level before it coarsens",
                          "PffFlowSetFromOptions", f->adapt.delay, &f->adapt.delay, NULL));
  PetscCall(PffOptionsReal("-adapt_margin",
                           "Finest cells added to each particle's radius for the block map (default: ceil(-flow_cfl))",
                           "PffFlowSetFromOptions", f->adapt.margin, &f->adapt.margin, NULL));
  PetscCall(PffOptionsReal("-adapt_particle_weight", "Partition work of a particle, in cells (0: cells only)",
                           "PffFlowSetFromOptions", f->adapt.pweight, &f->adapt.pweight, NULL));
  PetscCall(PffOptionsReal("-adapt_imbalance", "Re-partition when the max/mean work per rank exceeds this",
                           "PffFlowSetFromOptions", f->adapt.imbalance, &f->adapt.imbalance, NULL));
  PetscCall(PffOptionsReal("-adapt_vorticity",
                           "Vorticity criterion delta: refine where |curl u| h > delta max|u| (0: off; Sec. 5.2)",
                           "PffFlowSetFromOptions", f->adapt.vort, &f->adapt.vort, NULL));
  PetscCall(PffFlowAdaptRegionOptions_Private(f, PetscOptionsObject));
  PetscOptionsEnd();
  for (int t = 0; t < PFF_PARTICLE_NTYPES; t++) {
    const char *key = t == PFF_PARTICLE_LIQUID ? "liquid" : "gas";
    PetscCheck(f->rho[t] > 0 && PetscIsNormalReal(f->rho[t]), f->comm, PETSC_ERR_ARG_OUTOFRANGE,
               "-rho_%s %g is invalid: must be positive", key, (double)f->rho[t]);
    PetscCheck(f->nu[t] >= 0, f->comm, PETSC_ERR_ARG_OUTOFRANGE, "-nu_%s %g is invalid: must be >= 0", key,
               (double)f->nu[t]);
  }
  PetscCheck(
      f->rho[0] > f->rho[1], f->comm, PETSC_ERR_ARG_OUTOFRANGE,
      "-rho_liquid %g is invalid: must exceed -rho_gas %g (the phase field separates a heavy phase from a light one)",
      (double)f->rho[0], (double)f->rho[1]);
  PetscCheck(f->cfl > 0 && f->cfl <= 4, f->comm, PETSC_ERR_ARG_OUTOFRANGE, "-flow_cfl %g is invalid: must be in (0, 4]",
             (double)f->cfl);
  PetscCheck(f->dtMax > 0, f->comm, PETSC_ERR_ARG_OUTOFRANGE, "-flow_dt_max %g is invalid: must be positive",
             (double)f->dtMax);
  /* Eq. 7 divides the density by alpha_phi rho~_0: the paper uses 0.5 and 1; beyond 10 a full cell reads
     phi < 0.32 and the interface is lost */
  PetscCheck(f->alphaPhi > 0 && f->alphaPhi <= 10, f->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-flow_alpha_phi %g is invalid: must be in (0, 10]", (double)f->alphaPhi);
  PetscCheck(f->deltaPhi >= 0 && f->deltaPhi < 0.5, f->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-flow_delta_phi %g is invalid: must be in [0, 0.5)", (double)f->deltaPhi);
  PetscCheck(f->flip >= 0 && f->flip <= 1, f->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-flow_flip %g is invalid: must be in [0, 1]", (double)f->flip);
  PetscCheck(f->volCorr >= 0 && f->volCorr <= 1, f->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-flow_volume_correction %g is invalid: must be in [0, 1]", (double)f->volCorr);
  PetscCheck(
      !f->liquidSurfaceVolume || (f->model == PFF_FLOW_LIQUID && f->volCorr > 0), f->comm, PETSC_ERR_ARG_INCOMP,
      "-flow_liquid_surface_volume needs -flow_model liquid and -flow_volume_correction > 0 (its volume channels)");
  PetscCheck(f->band == 0 || (f->band >= 2 && f->band <= 64), f->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-flow_liquid_band %g is invalid: must be 0 (off) or in [2, 64] cells", (double)f->band);
  PetscCheck(f->band == 0 || f->model == PFF_FLOW_LIQUID, f->comm, PETSC_ERR_ARG_INCOMP,
             "-flow_liquid_band needs -flow_model liquid (the two-phase model keeps its particles everywhere)");
  PetscCheck(f->volCorrMaxDisp > 0 && f->volCorrMaxDisp <= 1, f->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-flow_volume_correction_max_displacement %g is invalid: must be in (0, 1] cells",
             (double)f->volCorrMaxDisp);
  PetscCheck(f->volCorrRtol > 0 && f->volCorrRtol < 1, f->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-flow_volume_correction_rtol %g is invalid: must be in (0, 1)", (double)f->volCorrRtol);
  PetscCheck(f->volControl >= 0 && f->volControl <= 2, f->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-flow_volume_control %g is invalid: must be in [0, 2]", (double)f->volControl);
  PetscCheck(f->extrapLayers >= 0, f->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-flow_extrapolate_layers %" PetscInt_FMT " is invalid: must be >= 0", f->extrapLayers);
  PetscCheck(f->adapt.levels >= 0, f->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-adapt_levels %" PetscInt_FMT " is invalid: must be >= 0", f->adapt.levels);
  PetscCheck(f->adapt.band > 0 && PetscIsNormalReal(f->adapt.band), f->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-adapt_band %g is invalid: must be positive", (double)f->adapt.band);
  PetscCheck(f->adapt.interval >= 1, f->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-adapt_interval %" PetscInt_FMT " is invalid: must be >= 1", f->adapt.interval);
  PetscCheck(f->adapt.delay >= 1 && f->adapt.delay <= 15, f->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-adapt_coarsen_delay %" PetscInt_FMT " is invalid: must be in [1, 15]", f->adapt.delay);
  if (f->adapt.margin < 0 && f->adapt.margin != -1)
    SETERRQ(f->comm, PETSC_ERR_ARG_OUTOFRANGE, "-adapt_margin %g is invalid: must be >= 0", (double)f->adapt.margin);
  if (f->adapt.margin == -1) f->adapt.margin = PetscCeilReal(f->cfl);
  PetscCheck(f->adapt.pweight >= 0 && f->adapt.pweight <= 1e3, f->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-adapt_particle_weight %g is invalid: must be in [0, 1000]", (double)f->adapt.pweight);
  PetscCheck(f->adapt.imbalance >= 1 && PetscIsNormalReal(f->adapt.imbalance), f->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-adapt_imbalance %g is invalid: must be >= 1", (double)f->adapt.imbalance);
  PetscCheck(f->adapt.vort >= 0 && PetscIsNormalReal(f->adapt.vort + 1), f->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-adapt_vorticity %g is invalid: must be >= 0 (0: off)", (double)f->adapt.vort);
  PetscCheck(f->adapt.levels > 0 || (f->adapt.vort == 0 && f->adapt.nbox == 0 && f->adapt.nsphere == 0), f->comm,
             PETSC_ERR_ARG_INCOMP,
             "-adapt_vorticity, -adapt_region_box and -adapt_region_sphere need -adapt_levels (dynamic adaptivity)");
  if (f->model == PFF_FLOW_LIQUID) {
    /* what the liquid model does not have yet fails here, before any work */
    PetscCheck(f->adapt.levels == 0, f->comm, PETSC_ERR_ARG_INCOMP,
               "-adapt_levels %" PetscInt_FMT ": dynamic adaptivity is not available with -flow_model liquid",
               f->adapt.levels);
    PetscCheck(f->extrapLayers > 0, f->comm, PETSC_ERR_ARG_OUTOFRANGE,
               "-flow_extrapolate_layers 0 is invalid with -flow_model liquid: G2P and advection near the surface read "
               "the liquid velocity extrapolated into the air");
    if (!f->tall) PetscCall(PffTallCreate(f->grid, &f->tall));
    PetscCall(PffTallSetFromOptions(f->tall));
    if (!f->bodies) {
      PetscReal lo[3], hi[3];
      PetscCall(PffGridGetDomain(f->grid, lo, hi));
      PetscCall(PffBodiesCreateFromOptions(f->comm, lo, hi, f->gravity, &f->bodies));
    }
  } else {
    PetscBool has;
    PetscCall(PetscOptionsHasName(NULL, NULL, "-body_0_type", &has));
    PetscCheck(!has, f->comm, PETSC_ERR_ARG_INCOMP,
               "-body_0_type: rigid bodies need the liquid model (-flow_model liquid, quadtree tall cells)");
  }
  PetscCall(PffParticlesSetFromOptions(f->part));
  PetscCall(PffPressureSetFromOptions(f->press));
  /* the advection stages read velocity up to about CFL cells beyond a particle's block, plus one cell
     for the interpolation stencil and one of margin; points beyond the halo on another rank would be
     clamped (a partition-dependent error) */
  f->uWidth = PetscMin(PFF_GRID_MAX_WIDTH, (PetscInt)PetscCeilReal(f->cfl) + 2);
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowSetSolid(PffFlow f, PffSolidFn fn, void *ctx)
{
  PetscFunctionBeginUser;
  f->solid    = fn;
  f->solidCtx = ctx;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowSetPrescribedVelocity(PffFlow f, PffVelocityFn fn, void *ctx)
{
  PetscFunctionBeginUser;
  f->prescribed      = fn;
  f->prescribedCtx   = ctx;
  f->prescribedNextT = PETSC_MAX_REAL;
  f->prescribedAmp   = NULL;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowSetPrescribedSeparable(PffFlow f, PffVelocityFn shape, PffAmplitudeFn amplitude, void *ctx)
{
  PetscFunctionBeginUser;
  PetscCheck(!f->setupcalled, f->comm, PETSC_ERR_ORDER, "PffFlowSetPrescribedSeparable: call it before PffFlowSetUp");
  PetscCheck(shape && amplitude, f->comm, PETSC_ERR_ARG_NULL,
             "PffFlowSetPrescribedSeparable: shape and amplitude are needed");
  PetscCall(PffFlowSetPrescribedVelocity(f, shape, ctx));
  f->prescribedAmp = amplitude;
  f->shapeState    = 0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowSetUp(PffFlow f)
{
  PetscInt n0, nlevels, width = f->uWidth;

  PetscFunctionBeginUser;
  if (f->setupcalled) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PffGridGetSizes(f->grid, &n0, &nlevels, NULL, NULL, NULL));
  /* the halo may not exceed the coarsest block */
  width = PetscMin(width, n0 >> (nlevels - 1));
  PetscCheck(width >= 2, f->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-grid_levels %" PetscInt_FMT " is invalid with -grid_block_size %" PetscInt_FMT
             " for the flow: the coarsest blocks need at least 2 cells per axis",
             nlevels, n0);
  f->uWidth = width;
  PetscCall(PffGridAddChannel(f->grid, "mass", PFF_CHANNEL_FACE, 1, &f->chMass));
  PetscCall(PffGridAddChannel(f->grid, "ut", PFF_CHANNEL_FACE, 1, &f->chUt));
  PetscCall(PffGridAddChannel(f->grid, "velocity", PFF_CHANNEL_FACE, width, &f->chU));
  PetscCall(PffGridAddChannel(f->grid, "phi_face", PFF_CHANNEL_FACE, 1, &f->chPhiF));
  PetscCall(PffGridAddChannel(f->grid, "mass_ref", PFF_CHANNEL_FACE, 1, &f->chMassRef));
  /* a prescribed field has no projection: no coefficients and no pressure (16 B per cell) */
  if (!f->prescribed) PetscCall(PffGridAddChannel(f->grid, "beta", PFF_CHANNEL_FACE, 1, &f->chBeta));
  PetscCall(PffGridAddChannel(f->grid, "open", PFF_CHANNEL_FACE, 1, &f->chOpen));
  PetscCall(PffGridAddChannel(f->grid, "phi", PFF_CHANNEL_CELL, 1, &f->chPhi));
  if (!f->prescribed) PetscCall(PffGridAddChannel(f->grid, "p", PFF_CHANNEL_CELL, 1, &f->chP));
  PetscCall(PffGridAddChannel(f->grid, "vorticity", PFF_CHANNEL_CELL, 1, &f->chVort));
  if (f->prescribedAmp) {
    PetscCall(PffGridAddChannel(f->grid, "velocity_shape", PFF_CHANNEL_FACE, 1, &f->chShape));
    PetscCall(PffGridSetChannelOutput(f->grid, f->chShape, PETSC_FALSE));
    PetscCall(PffGridSetChannelTransfer(f->grid, f->chShape, PFF_TRANSFER_NONE)); /* sampled again instead */
  }
  /* a prescribed field moves both phases alike; without layers nothing is allocated */
  if (!f->prescribed && f->extrapLayers > 0) {
    PetscCall(PffGridAddChannel(f->grid, "velocity_liquid", PFF_CHANNEL_FACE, width, &f->chUl));
    PetscCall(PffGridAddChannel(f->grid, "extrap_mask", PFF_CHANNEL_FACE, 1, &f->chUlMask));
    PetscCall(PffGridSetChannelOutput(f->grid, f->chUl, PETSC_FALSE));
    PetscCall(PffGridSetChannelOutput(f->grid, f->chUlMask, PETSC_FALSE));
    /* the layers then exchange one ghost face, not the advection's width (extrapolate.c): across level boundaries
       every ghost is interpolated, and the wider halo cost the dam break on its quadtree a quarter of its
       extrapolation time; on one level the halo is mostly read in place, and the copy costs what it saves */
    if (width > 1 && nlevels > 1) {
      PetscCall(PffGridAddChannel(f->grid, "extrap_work", PFF_CHANNEL_FACE, 1, &f->chUlWork));
      PetscCall(PffGridSetChannelOutput(f->grid, f->chUlWork, PETSC_FALSE));
    }
  }
  if (f->model == PFF_FLOW_LIQUID) {
    PetscCall(PffGridAddChannel(f->grid, "levelset", PFF_CHANNEL_CELL, 1, &f->chLS));
    /* frames show the tall cells: the pressure cell's height in cells (1 cubic, m tall, 0 air) */
    PetscCall(PffGridAddChannel(f->grid, "tall_height", PFF_CHANNEL_CELL, 1, &f->chTallH));
    PetscCall(PffGridSetChannelTransfer(f->grid, f->chTallH, PFF_TRANSFER_NONE));
    PetscCall(PffGridAddChannel(f->grid, "du_liquid", PFF_CHANNEL_FACE, 1, &f->chDuL));
    PetscCall(PffGridSetChannelOutput(f->grid, f->chDuL, PETSC_FALSE));
    {
      PetscInt every;
      PetscCall(PffTallGetSizing(f->tall, NULL, &every));
      if (every > 0) { /* the smoothed level set the sizing function reads during the run */
        PetscCall(PffGridAddChannel(f->grid, "levelset_sizing", PFF_CHANNEL_CELL, 1, &f->chLSs));
        PetscCall(PffGridSetChannelOutput(f->grid, f->chLSs, PETSC_FALSE));
        PetscCall(PffGridSetChannelTransfer(f->grid, f->chLSs, PFF_TRANSFER_NONE));
      }
    }
    if (f->bodies) { /* the solid the fractions and the particles see is the union of the static ones and the bodies */
      f->staticSolid    = f->solid;
      f->staticSolidCtx = f->solidCtx;
      f->solid          = PffFlowLiquidSolid_Private;
      f->solidCtx       = f;
    }
    if (f->solid) { /* [A]: chOpen holds the open fractions, chSolidD the distance at the cell centres */
      PetscCall(PffGridAddChannel(f->grid, "solid_distance", PFF_CHANNEL_CELL, 1, &f->chSolidD));
      PetscCall(PffGridSetChannelOutput(f->grid, f->chSolidD, PETSC_FALSE));
      PetscCall(PffGridSetChannelTransfer(f->grid, f->chSolidD, PFF_TRANSFER_NONE));
      PetscCall(PffTallSetSolid(f->tall, f->chOpen, f->chSolidD));
    }
  }
  if (f->model == PFF_FLOW_LIQUID) PetscCall(PffFlowLiquidBandSetUp_Private(f));
  /* the volume correction needs the projection and moves particles, so a prescribed field has none */
  if (!f->prescribed && f->usePressure && f->volCorr > 0) {
    /* the two-phase measure is on the cell centres (PffParticlesSplatVolume), the liquid model's on the faces */
    const PffChannelKind vkind = f->model == PFF_FLOW_TWO_PHASE ? PFF_CHANNEL_CELL : PFF_CHANNEL_FACE;
    PetscCall(PffGridAddChannel(f->grid, "volume", vkind, 1, &f->chVol));
    PetscCall(PffGridAddChannel(f->grid, "volume_ref", vkind, 1, &f->chVolRef));
    PetscCall(PffGridAddChannel(f->grid, "cdiv", PFF_CHANNEL_CELL, 1, &f->chCdiv));
    /* the liquid model's correction is local (liquidcorr.c): no potential; chUa is the liquid's advection */
    if (f->model == PFF_FLOW_TWO_PHASE)
      PetscCall(PffGridAddChannel(f->grid, "correction_potential", PFF_CHANNEL_CELL, 1, &f->chQ));
    PetscCall(PffGridAddChannel(f->grid, "velocity_gas", PFF_CHANNEL_FACE, width, &f->chUa));
    /* the liquid's advection channel carries the liquid displacement even without extrapolation */
    if (f->chUl < 0) PetscCall(PffGridAddChannel(f->grid, "velocity_liquid", PFF_CHANNEL_FACE, width, &f->chUl));
    const PetscInt work[] = {f->chVol, f->chVolRef, f->chCdiv, f->chQ, f->chUa, f->chUl};
    for (size_t k = 0; k < PETSC_STATIC_ARRAY_LENGTH(work); k++)
      if (work[k] >= 0) PetscCall(PffGridSetChannelOutput(f->grid, work[k], PETSC_FALSE));
  }
  /* working channels stay out of frames (checkpoints keep everything) */
  const PetscInt hidden[] = {f->chMass, f->chMassRef, f->chUt, f->chPhiF, f->chBeta, f->chOpen};
  for (size_t k = 0; k < PETSC_STATIC_ARRAY_LENGTH(hidden); k++)
    if (hidden[k] >= 0) PetscCall(PffGridSetChannelOutput(f->grid, hidden[k], PETSC_FALSE));
  /* what an adapt need not move: every step recomputes it from the particles, or PffFlowReset does */
  /* (mass_ref and volume_ref move: a reset makes them again only where the levels changed) */
  const PetscInt scratch[] = {f->chMass, f->chUt,   f->chPhiF, f->chBeta,   f->chOpen,
                              f->chVol,  f->chCdiv, f->chQ,    f->chUlMask, f->chUlWork};
  for (size_t k = 0; k < PETSC_STATIC_ARRAY_LENGTH(scratch); k++)
    if (scratch[k] >= 0) PetscCall(PffGridSetChannelTransfer(f->grid, scratch[k], PFF_TRANSFER_NONE));
  PetscCall(PffParticlesGetKernelSum(f->part, &f->rho0));
  PetscCall(PffFlowReset(f));
  PetscCall(PffFlowAdaptSetUp_Private(f));
  if (!f->prescribed && f->usePressure && f->model == PFF_FLOW_TWO_PHASE) PetscCall(PffPressureSetUp(f->press));
  f->setupcalled = PETSC_TRUE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowReset(PffFlow f)
{
  PetscFunctionBeginUser;
  PetscCall(PffFlowOpenFaces_Private(f, PETSC_FALSE));
  PetscCall(PffFlowReferenceVolume_Private(f));
  PetscCall(PffGridGetTopologyState(f->grid, &f->topology));
  f->lsgGhosts = PETSC_FALSE; /* a new grid: the narrow band's level set was moved without its halo */
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Collective: every rank sees the same topology state. */
PetscErrorCode PffFlowCheckTopology_Private(PffFlow f)
{
  PetscObjectState state;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetTopologyState(f->grid, &state));
  if (state == f->topology) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscInfo(NULL, "flow: open faces and reference lattice rebuilt after a grid topology change\n"));
  PetscCall(PffFlowReset(f));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowGetBodies(PffFlow f, PffBodies *bodies)
{
  PetscFunctionBeginUser;
  *bodies = f->bodies;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowDestroy(PffFlow *flow)
{
  PetscFunctionBeginUser;
  if (!flow || !*flow) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PffParticlesDestroy(&(*flow)->part));
  PetscCall(PffPressureDestroy(&(*flow)->press));
  PetscCall(PffTallDestroy(&(*flow)->tall));
  PetscCall(PffBodiesDestroy(&(*flow)->bodies));
  PetscCall(PffFlowAdaptDestroy_Private(*flow));
  PetscCall(PetscFree((*flow)->refLevel));
  PetscCall(PetscFree((*flow)->refBody));
  PetscCall(PetscFree((*flow)->openBody));
  PetscCall(PetscFree(*flow));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The liquid model seeds no air and nothing inside its bodies: those particles are dropped. */
typedef struct {
  PffSeedFn fn;
  void     *ctx;
  PffBodies bodies;
} PffLiquidSeedCtx;

static PetscErrorCode PffLiquidSeed(const PetscReal x[3], PetscInt *type, PetscReal v[3], void *vctx)
{
  const PffLiquidSeedCtx *c = (const PffLiquidSeedCtx *)vctx;

  PetscFunctionBeginUser;
  PetscCall(c->fn(x, type, v, c->ctx));
  if (*type == PFF_PARTICLE_AIR || (c->bodies && PffBodiesDistance(x, NULL, c->bodies) < 0)) *type = -1;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowSeed(PffFlow f, PffSeedFn fn, void *ctx)
{
  PffLiquidSeedCtx lc = {fn, ctx, f->bodies};

  PetscFunctionBeginUser;
  PetscCheck(f->setupcalled, f->comm, PETSC_ERR_ORDER, "PffFlowSetUp() must come before PffFlowSeed()");
  if (f->model == PFF_FLOW_LIQUID) {
    fn  = PffLiquidSeed;
    ctx = &lc;
    PetscCall(PffFlowLiquidQuadtree_Private(f, fn, ctx));
  }
  if (f->adapt.levels > 0)
    PetscCall(PffFlowAdaptSeed_Private(f, fn, ctx));
  else {
    PetscCall(PffParticlesSeed(f->part, fn, ctx));
    PetscCall(PffFlowUpdateFields(f, PETSC_FALSE));
    if (f->band > 0) { /* narrow-band FLIP: the grid takes the liquid below the band */
      PetscCall(PffFlowLiquidBandInit_Private(f));
      PetscCall(PffFlowUpdateFields(f, PETSC_FALSE));
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowGetAdaptLevels(PffFlow f, PetscInt *levels)
{
  PetscFunctionBeginUser;
  *levels = f->adapt.levels;
  if (f->model == PFF_FLOW_LIQUID) { /* the quadtree of the sizing function: a level map of its own */
    PetscBool sizing;
    PetscInt  nlevels;
    PetscCall(PffTallGetSizing(f->tall, &sizing, NULL));
    PetscCall(PffGridGetSizes(f->grid, NULL, &nlevels, NULL, NULL, NULL));
    *levels = sizing && nlevels > 1 ? nlevels : 0;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowGetTime(PffFlow f, PetscReal *t, PetscInt *step)
{
  PetscFunctionBeginUser;
  if (t) *t = f->t;
  if (step) *step = f->step;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowSetTime(PffFlow f, PetscReal t, PetscInt step)
{
  PetscFunctionBeginUser;
  f->t    = t;
  f->step = step;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowGetVolumeControl(PffFlow f, PetscReal *target, PetscReal *fraction)
{
  PetscFunctionBeginUser;
  if (target) *target = f->volTarget;
  if (fraction) *fraction = f->volFraction;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowSetVolumeControl(PffFlow f, PetscReal target, PetscReal fraction)
{
  PetscFunctionBeginUser;
  PetscCheck(target >= 0 && fraction > 0 && !PetscIsInfOrNanReal(target) && !PetscIsInfOrNanReal(fraction), f->comm,
             PETSC_ERR_ARG_OUTOFRANGE, "volume control state (target %g, fraction %g) is invalid", (double)target,
             (double)fraction);
  f->volTarget   = target;
  f->volFraction = fraction;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowGetParticles(PffFlow f, PffParticles *p)
{
  PetscFunctionBeginUser;
  *p = f->part;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowGetGrid(PffFlow f, PffGrid *grid)
{
  PetscFunctionBeginUser;
  *grid = f->grid;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowGetDensities(PffFlow f, PetscReal rho[PFF_PARTICLE_NTYPES])
{
  PetscFunctionBeginUser;
  for (int t = 0; t < PFF_PARTICLE_NTYPES; t++) rho[t] = f->rho[t];
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowGetDeleteBubbles(PffFlow f, PetscBool *del)
{
  PetscFunctionBeginUser;
  *del = f->deleteBubbles;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowGetChannels(PffFlow f, PetscInt *phi, PetscInt *p, PetscInt *u, PetscInt *vort)
{
  PetscFunctionBeginUser;
  if (phi) *phi = f->chPhi;
  if (p) *p = f->chP;
  if (u) *u = f->chU;
  if (vort) *vort = f->chVort;
  PetscFunctionReturn(PETSC_SUCCESS);
}
