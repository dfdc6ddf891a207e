/* flow: the PF-FLIP time step (PF-FLIP paper Sec. 3): P2G, phase field, forces, two-phase pressure
   projection, G2P with viscosity through the FLIP ratio, RK3 advection, escaped particles. It owns
   the particles and the pressure solver of one grid and the grid channels it needs. */
#pragma once

#include <pff/particles.h>
#include <pff/pressure.h>
#include <pff/bodies.h>

typedef struct _n_PffFlow *PffFlow;

/* Defaults, named after their options. */
#define PFF_FLOW_CFL_DEFAULT 1.0       /* -flow_cfl, at most 4 */
#define PFF_FLOW_ALPHA_PHI_DEFAULT 1.0 /* -flow_alpha_phi (Eq. 7) */
#define PFF_FLOW_DELTA_PHI_DEFAULT 0.2 /* -flow_delta_phi (Sec. 3.4) */
#define PFF_FLOW_FLIP_DEFAULT 0.99     /* -flow_flip: FLIP ratio where no viscosity is given */
#define PFF_FLOW_VOLCORR_DEFAULT 0.5   /* -flow_volume_correction: kappa, share of the volume error removed per step */
#define PFF_FLOW_VOLCORR_MAXDISP_DEFAULT 0.5       /* -flow_volume_correction_max_displacement, in cells */
#define PFF_FLOW_VOLCORR_RTOL_DEFAULT 1e-1         /* -flow_volume_correction_rtol of its solve */
#define PFF_FLOW_VOLCONTROL_DEFAULT 1.0            /* -flow_volume_control: gain of the liquid volume's control */
#define PFF_FLOW_EXTRAPOLATE_LAYERS_DEFAULT 3      /* -flow_extrapolate_layers: the paper's "a few cells" (Sec. 3.7) */
#define PFF_FLOW_ADAPT_BAND_DEFAULT 1.0            /* -adapt_band: beta_bw of Sec. 5.4 step 6 */
#define PFF_FLOW_ADAPT_DELAY_DEFAULT 3             /* -adapt_coarsen_delay: D_p >= 3 (Sec. 5.4) */
#define PFF_FLOW_ADAPT_PARTICLE_WEIGHT_DEFAULT 0.2 /* -adapt_particle_weight: a particle's work in cells */
#define PFF_FLOW_ADAPT_IMBALANCE_DEFAULT 1.1       /* -adapt_imbalance: re-partition above this max/mean work */

/* Prescribed face velocity (e.g. the shear benchmark): component comp at x and time t. */
typedef PetscReal (*PffVelocityFn)(const PetscReal x[3], PetscInt comp, PetscReal t, void *ctx);

#define PFF_FLOW_NSTAGES 9

/* -flow_model: two_phase, the PF-FLIP step with air particles and the two-phase projection (the default); liquid,
   a free-surface liquid with liquid particles only and the variational tall-cell projection (src/tallcell/,
   docs/tallcell.md), p = 0 in the air. */
typedef enum { PFF_FLOW_TWO_PHASE, PFF_FLOW_LIQUID } PffFlowModel;
PETSC_EXTERN const char *const PffFlowModels[];

/* -flow_volume_correction_interface: what the two-phase correction's displacement may do at a face between a liquid
   and a gas cell. liquid (the default): the liquid takes all of it, the gas only the part that moves it into the gas
   cell; closed: neither phase crosses it (the correction works within each phase, the interface moves with the flow
   only: still pools, drops and rt3d keep their volume better, the dam break worse; docs/validation.md); layer: no
   face of an interface cell (0 < phi < 1) moves, elsewhere the rule of liquid. */
typedef enum { PFF_FLOW_CORR_LIQUID, PFF_FLOW_CORR_CLOSED, PFF_FLOW_CORR_LAYER } PffFlowCorrectionInterface;
PETSC_EXTERN const char *const PffFlowCorrectionInterfaces[];

/* What one adaptation did (PF-FLIP Sec. 5.4, -adapt_levels). */
typedef struct {
  PetscBool             adapted;                    /* the grid changed */
  PetscBool             repartitioned;              /* the grid was re-partitioned only, for load balance */
  PetscReal             imbalanceBefore, imbalance; /* max/mean work (cells + weighted particles) before and after */
  PffAdaptInfo          grid;                       /* PffGridAdapt's counts, bytes and time (when adapted) */
  PffParticleAdaptStats particles;                  /* splits and coarsening */
} PffFlowAdaptStats;

/* What one step did; the scene prints it in the progress line. */
typedef struct {
  PetscReal  dt, cfl; /* time step and the CFL number it realised (max |u| dt / h0) */
  PetscReal  umax;    /* max particle speed at the start of the step */
  PetscInt64 particles;
  PetscInt64 bubblesDeleted, dropletCandidates; /* escaped particles this step (Sec. 3.4) */
  PetscInt64 bandDeleted, bandSeeded; /* narrow-band FLIP (-flow_liquid_band): particles below the band, reseeded */
  PffPressureStats  pressure;         /* its = 0 when the solve is off */
  PffPressureStats  correction;       /* the volume-correction solve (its = 0 when off) */
  PffParticleStats  advect;
  PffFlowAdaptStats adapt;                       /* zero when no adaptation ran this step */
  PetscLogDouble    stageTime[PFF_FLOW_NSTAGES]; /* wall seconds per stage, see PffFlowStageNames */
} PffFlowStepStats;

PETSC_EXTERN const char
    *const PffFlowStageNames[]; /* P2G, PhaseField, Forces, Pressure, G2P, Advect, Escaped, Correction, Adapt */

/* Life cycle. Create borrows the grid, which must be set up (the flow adds its channels in SetUp).
   SetFromOptions reads
   -rho_liquid, -rho_gas (> 0), -nu_liquid, -nu_gas (>= 0; 0 = no physical viscosity: FLIP ratio -flow_flip),
   -gravity gx,gy,gz, -flow_cfl (0, 4], -flow_dt_max, -flow_alpha_phi (0, 10], -flow_delta_phi [0, 0.5),
   -flow_flip [0, 1], -flow_pressure (bool, default true), -flow_volume_correction [0, 1] (0 = off),
   -flow_volume_correction_max_displacement (cells, > 0), -flow_volume_correction_rtol (0, 1),
   -flow_delete_bubbles (bool, default true), -flow_extrapolate_layers (>= 0; 0 = off), -flow_model
   two_phase|liquid (liquid: no air particles are seeded, the projection is PffTall's on quadtree tall cells, which
   needs -partition_type columns and levels constant along y; a local volume correction of its own, no dynamic
   adaptivity), -flow_liquid_surface_volume (bool, liquid only), -flow_liquid_band (liquid only: 0 = off, or [2, 64]
   cells of narrow-band FLIP), and the particle and pressure (or tall_) options. */
PETSC_EXTERN PetscErrorCode PffFlowCreate(PffGrid grid, PffFlow *flow);
PETSC_EXTERN PetscErrorCode PffFlowSetFromOptions(PffFlow flow);
/* Static solids (signed distance, negative inside); faces inside are closed. Before SetUp. */
PETSC_EXTERN PetscErrorCode PffFlowSetSolid(PffFlow flow, PffSolidFn fn, void *ctx);
/* A prescribed velocity field instead of P2G/forces/pressure/G2P: particles are only transported
   (and the phase field is computed on demand). Before SetUp. */
PETSC_EXTERN PetscErrorCode PffFlowSetPrescribedVelocity(PffFlow flow, PffVelocityFn fn, void *ctx);
/* A prescribed field that separates, u(x, t) = amplitude(t) shape(x, comp, 0): the shape is sampled on the grid
   once (again after a topology change) and every later sample is a scaled copy of it, instead of a call of the
   field's function per face (the time step samples the field two to four times). Before SetUp. */
typedef PetscReal (*PffAmplitudeFn)(PetscReal t, void *ctx);
PETSC_EXTERN PetscErrorCode PffFlowSetPrescribedSeparable(PffFlow flow, PffVelocityFn shape, PffAmplitudeFn amplitude,
                                                          void *ctx);
/* Allocates channels, particle store and pressure solver (the grid must be set up). Collective. */
PETSC_EXTERN PetscErrorCode PffFlowSetUp(PffFlow flow);
PETSC_EXTERN PetscErrorCode PffFlowDestroy(PffFlow *flow);
/* Rebuilds what the flow derives from the grid's topology: the open faces (walls and solids) and the
   reference lattice of Eq. 6-7 and of the volume correction. PffFlowStep and PffFlowUpdateFields call it
   when the grid's topology state (PffGridAdapt) changed; the particles and the pressure reset
   themselves. Collective. */
PETSC_EXTERN PetscErrorCode PffFlowReset(PffFlow flow);

/* Seeds the particles (see PffParticlesSeed) and computes the initial phase field. Collective. */
PETSC_EXTERN PetscErrorCode PffFlowSeed(PffFlow flow, PffSeedFn fn, void *ctx);
/* Advances one step of at most dtmax (the scene passes the time to its next output). Collective. */
PETSC_EXTERN PetscErrorCode PffFlowStep(PffFlow flow, PetscReal dtmax, PffFlowStepStats *stats);
/* Recomputes the phase field (cell and face), density and, with vorticity, the vorticity magnitude
   from the current particles, e.g. before output or an error measurement. Collective. */
PETSC_EXTERN PetscErrorCode PffFlowUpdateFields(PffFlow flow, PetscBool vorticity);

PETSC_EXTERN PetscErrorCode PffFlowGetTime(PffFlow flow, PetscReal *t, PetscInt *step);
PETSC_EXTERN PetscErrorCode PffFlowSetTime(PffFlow flow, PetscReal t, PetscInt step);
/* The state of the liquid volume's control (-flow_volume_control, docs/flow.md): the liquid volume it holds (0 until
   the first step sets it) and the liquid's target particle volume fraction s*. A checkpoint stores both, so that a
   restart continues the control as the uninterrupted run would. Not collective. */
PETSC_EXTERN PetscErrorCode PffFlowGetVolumeControl(PffFlow flow, PetscReal *target, PetscReal *fraction);
PETSC_EXTERN PetscErrorCode PffFlowSetVolumeControl(PffFlow flow, PetscReal target, PetscReal fraction);
PETSC_EXTERN PetscErrorCode PffFlowGetParticles(PffFlow flow, PffParticles *p);
/* The levels of dynamic adaptivity (-adapt_levels; 0: off). Not collective. */
PETSC_EXTERN PetscErrorCode PffFlowGetAdaptLevels(PffFlow flow, PetscInt *levels);
/* With -adapt_levels: the grid follows level[] (every raster block; a checkpoint's map, PffIOReadLevels) as
   the flow's own adaptation would make it, so that a restart continues on the grid of the run it
   continues. Collective. */
PETSC_EXTERN PetscErrorCode PffFlowAdaptSetMap(PffFlow flow, const PetscInt level[]);
PETSC_EXTERN PetscErrorCode PffFlowGetGrid(PffFlow flow, PffGrid *grid);
/* The liquid model's rigid bodies (-body_<i>_*, include/pff/bodies.h), or NULL. */
PETSC_EXTERN PetscErrorCode PffFlowGetBodies(PffFlow flow, PffBodies *bodies);
PETSC_EXTERN PetscErrorCode PffFlowGetDensities(PffFlow flow, PetscReal rho[PFF_PARTICLE_NTYPES]);
/* Whether escaped gas particles are deleted (-flow_delete_bubbles); without deletion the
   bubblesDeleted of PffFlowStepStats counts the candidates only. Not collective. */
PETSC_EXTERN PetscErrorCode PffFlowGetDeleteBubbles(PffFlow flow, PetscBool *del);
/* Channel indices: phi (cell), p (cell; -1 under a prescribed field, which has no projection), u (face), vort (cell
   vorticity magnitude). */
PETSC_EXTERN PetscErrorCode PffFlowGetChannels(PffFlow flow, PetscInt *phi, PetscInt *p, PetscInt *u, PetscInt *vort);
/* Max |u| over the faces and the liquid volume (that of PffFlowGetPhaseVolumes), each only when its
   pointer is not NULL (the same on every rank). Collective. */
PETSC_EXTERN PetscErrorCode PffFlowGetDiagnostics(PffFlow flow, PetscReal *umax, PetscReal *liquidVolume);

/* Extrapolation of the liquid velocity into the air (PF-FLIP Sec. 3.7), on face channels of grid: open
   faces with chPhiF >= 1/2 copy chU into chUl; then, layer by layer (layers times), every open face not
   yet valid that has valid neighbours of the same component (6 in that component's lattice, validity of
   the previous layer only) takes their mean; the remaining faces copy chU, closed faces (chOpen 0) get 0.
   Across a level boundary an interpolated neighbour counts as valid when its interpolated mask is >= 1/2
   and contributes the mean of its valid sources. chMask (any width) is scratch; chUl's halo is current
   on return. chWork (-1 for none) is a scratch face channel of width 1 the layers run on, whose result is
   then copied into chUl: a layer reads one ghost face, and a wide chUl (the advection's width) would
   exchange its whole halo at every layer; the result is the same bit for bit. faces (may be NULL)
   receives the global number of faces extrapolated. The flow calls it in the Advect stage; exposed for
   tests. Collective. */
PETSC_EXTERN PetscErrorCode PffExtrapolateLiquidVelocity(PffGrid grid, PetscInt chU, PetscInt chPhiF, PetscInt chOpen,
                                                         PetscInt layers, PetscInt chMask, PetscInt chUl,
                                                         PetscInt chWork, PetscInt64 *faces);
/* The same for nf fields at once (chU[q] into chUl[q], 1 <= nf <= 2, chWork NULL or one entry per field) on the
   shared mask: the result is the one of nf separate calls, bit for bit, with one set of layers, mask exchanges
   and neighbour scans. Collective. */
PETSC_EXTERN PetscErrorCode PffExtrapolateLiquidVelocities(PffGrid grid, PetscInt nf, const PetscInt chU[],
                                                           PetscInt chPhiF, PetscInt chOpen, PetscInt layers,
                                                           PetscInt chMask, const PetscInt chUl[],
                                                           const PetscInt chWork[], PetscInt64 *faces);

/* Volumes of the two phases from the current cell phase field (as left by the last step, PffFlowSeed or
   PffFlowUpdateFields; not recomputed here): liquid = sum phi_c V_c and gas = sum (1 - phi_c) V_c over the
   fluid cells, those with at least one open face; cells with every face closed (inside a solid) count for
   neither, so liquid + gas is the fluid volume of the domain. Either output may be NULL. After
   PffFlowSetUp. Collective. */
PETSC_EXTERN PetscErrorCode PffFlowGetPhaseVolumes(PffFlow flow, PetscReal *liquid, PetscReal *gas);
/* Where the liquid is, over the same fluid cells and phase field: front[0] and front[1] the largest x and y
   reached by a cell with phi >= 1/2 (its upper face: a dam break's front, a splash's crest; 0 without
   one), centroid the liquid centroid sum phi_c V_c x_c / sum phi_c V_c. Collective. */
PETSC_EXTERN PetscErrorCode PffFlowGetLiquidExtent(PffFlow flow, PetscReal front[2], PetscReal centroid[3]);
