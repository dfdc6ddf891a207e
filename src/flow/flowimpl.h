/* Private state of PffFlow; only src/flow/ includes this. */
#pragma once

#include <pff.h>
#include <pff/bodies.h>
#include <pff/flow.h>

/* Dynamic adaptivity (adapt.c). */
#define PFF_FLOW_ADAPT_MAX_REGIONS 8
typedef struct {
  PetscInt    levels, interval, delay; /* -adapt_levels (0: off), -adapt_interval, -adapt_coarsen_delay */
  PetscReal   band, margin;            /* -adapt_band (beta_bw), -adapt_margin (finest cells) */
  float       lscale;                  /* beta_bw / n0: the level per finest cell of distance */
  PetscReal   pweight, imbalance;      /* -adapt_particle_weight, -adapt_imbalance */
  PetscInt64 *pwork;                   /* [nblocks] particle work per block */
  PetscInt    n0, s, m, C[3];          /* block size; lattice cell size s = 2^(levels-1), m per block, C per axis */
  float       is;                      /* 1 / s */
  PetscBool   periodic[3];
  PetscInt   *base;        /* [nblocks] -1: inactive at set-up */
  PetscInt   *request;     /* [nblocks] the map the grid last followed */
  float      *dist, *work; /* [C] distance lattice (finest cells) and the coarse phase field */
  uint8_t    *lev;         /* [C + 1] level of each dual lattice cell, 0xff where it varies */
  int8_t     *target;      /* per particle */
  size_t      ntarget;
  /* -adapt_vorticity delta (0: off): a particle asks for no coarser a level than the one at which |curl u| h stays
     below delta max|u| (Sec. 5.2, after Popinet 2003), from the largest |curl u| of its lattice cell */
  PetscReal vort;
  uint8_t  *vlev; /* [C] the level the vorticity asks for per lattice cell (levels - 1 with the criterion off) */
  /* user regions that force a level: boxes lo, hi and spheres centre, radius (grid units after set-up) */
  PetscInt  nbox, nsphere;
  PetscReal box[6 * PFF_FLOW_ADAPT_MAX_REGIONS], sphere[4 * PFF_FLOW_ADAPT_MAX_REGIONS];
  PetscInt  boxLevel[PFF_FLOW_ADAPT_MAX_REGIONS], sphereLevel[PFF_FLOW_ADAPT_MAX_REGIONS];
} PffFlowAdaptCtx;

struct _n_PffFlow {
  MPI_Comm     comm;
  PffGrid      grid;
  PffParticles part;
  PffPressure  press;
  PetscBool    setupcalled;
  PffFlowModel model;       /* -flow_model */
  PffTall      tall;        /* the liquid model's projection (NULL for two_phase) */
  PetscInt     chLS, chDuL; /* liquid model: level set from phi (cell), extrapolated velocity change (face) */
  PetscInt     chSolidD;    /* liquid model with solids: solid distance at cell centres in cells (chOpen: fractions) */
  PetscInt     chLSs;       /* liquid model, quadtree during the run: the level set smoothed for the sizing function */
  PetscInt     chTallH;     /* liquid model: the tall cells' heights, for frames */
  /* liquid model, narrow-band FLIP (liquidband.c): -flow_liquid_band (cells; 0: particles fill the liquid), the grid's
     level set (cell, a distance to the surface down to the band's depth) and its advection's scratch, the grid's
     velocity below the band (face) */
  PetscReal  band;
  PetscInt   chLSg, chLSgWork, chUg;
  PetscBool  lsgGhosts;   /* the ghosts of chLSg are current (liquidband.c) */
  PffBodies  bodies;      /* liquid model: rigid bodies (NULL: none) */
  PffSolidFn staticSolid; /* with bodies, the scene's static solids; solid is then the union with the bodies */
  void      *staticSolidCtx;

  /* physics and numerics */
  PetscReal                  rho[PFF_PARTICLE_NTYPES], nu[PFF_PARTICLE_NTYPES], gravity[3];
  PetscReal                  cfl, dtMax, alphaPhi, deltaPhi, flip;
  PetscReal                  volCorr, volCorrMaxDisp, volCorrRtol; /* -flow_volume_correction* (correction.c) */
  PffFlowCorrectionInterface volCorrInterface;
  PetscReal                  volControl; /* -flow_volume_control: gain of the liquid volume's control (correction.c) */
  PetscReal volTarget, volFraction;      /* the liquid volume it holds (0: not yet set) and the liquid's target s* */
  PetscBool usePressure, deleteBubbles;
  PetscBool liquidSurfaceVolume; /* the liquid model's surface from the particles' volume fraction (liquid.c) */
  PetscReal rho0;                /* kernel sum rho~_0 (Eq. 7) */

  PffSolidFn       solid;
  void            *solidCtx;
  PffVelocityFn    prescribed;
  void            *prescribedCtx;
  PetscReal        prescribedNextT, prescribedNextU; /* the field's speed at prescribedNextT, sampled last step */
  PffAmplitudeFn   prescribedAmp;                    /* separable field: u = amp(t) shape, the shape in chShape */
  PetscInt         chShape;
  PetscObjectState shapeState; /* 1 + the grid's topology state when chShape was sampled (0: never) */

  /* channels */
  PetscInt chMass, chMassRef, chUt, chU, chPhiF, chBeta, chOpen, chPhi, chP, chCdiv, chVort;
  PetscInt chUl, chUlMask; /* liquid velocity extrapolated into the air and its validity (only with layers > 0) */
  PetscInt chUlWork;       /* width-1 scratch of the extrapolation's layers when chUl is wider, else -1 */
  PetscInt chVol, chVolRef, chQ, chUa; /* volume weights, their lattice target, correction potential, gas advection */
  PetscInt extrapLayers;               /* -flow_extrapolate_layers (Sec. 3.7) */
  PetscInt uWidth;

  PffFlowAdaptCtx  adapt;
  PetscInt        *refLevel; /* [nblocks] raster levels the reference lattice was made for (correction.c) */
  PetscBool       *refBody;  /* [nblocks] blocks the bodies' reference was last made on (correction.c) */
  PetscBool       *openBody; /* [nblocks] blocks the bodies' open fractions were last filled on (fields.c) */
  PetscObjectState topology; /* the grid's topology state of the open faces and the reference lattice */
  PetscReal        t, dtPrev;
  PetscInt         step;
};

/* Component d of nch channels on local block lb of grid (n^3 floats each, x fastest); n3 may be NULL. */
static inline PetscErrorCode PffFlowGridBlockData_Private(PffGrid grid, PetscInt lb, PetscInt d, PetscInt nch,
                                                          const PetscInt ch[], float *data[], PetscInt *n3)
{
  PffBlockInfo info;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetBlockInfo(grid, lb, &info));
  for (PetscInt k = 0; k < nch; k++) PetscCall(PffGridGetBlockData(grid, ch[k], lb, d, &data[k]));
  if (n3) *n3 = info.n * info.n * info.n;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The same on the flow's grid. */
static inline PetscErrorCode PffFlowBlockData_Private(PffFlow f, PetscInt lb, PetscInt d, PetscInt nch,
                                                      const PetscInt ch[], float *data[], PetscInt *n3)
{
  PetscFunctionBeginUser;
  PetscCall(PffFlowGridBlockData_Private(f->grid, lb, d, nch, ch, data, n3));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Tags (cell phi >= 1/2, liquid) of the two cells of the lower d-face of cell (i, j, k) of an n^3 block (a cell of the
   block itself): hi the cell itself, lo its -d neighbour, from the block's own storage (PFF_REGION_SELF) when it lies
   in the block (the region look-up per read was most of the phase field's and the correction's face passes), else
   through the halo of the cell view vphi. */
static inline void PffFlowFaceTags_Private(const PffView *vphi, PetscInt i, PetscInt j, PetscInt k, PetscInt d,
                                           PetscInt n, PetscBool *lo, PetscBool *hi)
{
  if ((d == 0 ? i : (d == 1 ? j : k)) > 0) {
    const float   *own = vphi[PFF_REGION_SELF].ptr + vphi[PFF_REGION_SELF].off;
    const PetscInt c = i + n * (j + n * k), st = d == 0 ? 1 : (d == 1 ? n : n * n);
    *hi = (PetscBool)(own[c] >= 0.5);
    *lo = (PetscBool)(own[c - st] >= 0.5);
    return;
  }
  *hi = (PetscBool)(*PffViewsAt(vphi, i, j, k, n) >= 0.5);
  *lo = (PetscBool)(*PffViewsAt(vphi, i - (d == 0), j - (d == 1), k - (d == 2), n) >= 0.5);
}

/* The sums W and W_ref of a cell's open faces (views of the volume, its lattice target and the open fractions,
   component by component) and their number nopen (may be NULL): its particle volume fraction is s = W / W_ref
   where W_ref > 0. */
static inline void PffFlowCellVolumes_Private(const PffView *vw[3], const PffView *vr[3], const PffView *vo[3],
                                              PetscInt i, PetscInt j, PetscInt k, PetscInt n, PetscReal *wp,
                                              PetscReal *wrefp, PetscInt *nopen)
{
  PetscReal w = 0, wref = 0;
  PetscInt  no = 0;
  /* inside: every face lies in the block's own storage, read without a region look-up */
  const PetscBool inside = (PetscBool)(i < n - 1 && j < n - 1 && k < n - 1);
  const PetscInt  c      = i + n * (j + n * k);
  for (PetscInt d = 0; d < 3; d++)
    for (PetscInt up = 0; up < 2; up++) {
      const PetscInt ii = i + (up && d == 0), jj = j + (up && d == 1), kk = k + (up && d == 2);
      const PetscInt q = c + up * (d == 0 ? 1 : (d == 1 ? n : n * n));
      const PffView *o = &vo[d][PFF_REGION_SELF], *vv = &vw[d][PFF_REGION_SELF], *r = &vr[d][PFF_REGION_SELF];
      const float   *po = inside ? o->ptr + o->off + q : PffViewsAt(vo[d], ii, jj, kk, n);
      if (*po <= 0) continue;
      w += inside ? vv->ptr[vv->off + q] : *PffViewsAt(vw[d], ii, jj, kk, n);
      wref += inside ? r->ptr[r->off + q] : *PffViewsAt(vr[d], ii, jj, kk, n);
      no++;
    }
  *wp    = w;
  *wrefp = wref;
  if (nopen) *nopen = no;
}

/* Whether cell (i, j, k) of an n^3 block has an open face (vo: the open fractions' face views, its upper faces through
   their halo): a fluid cell, not one inside a solid */
static inline PetscBool PffFlowCellOpen_Private(const PffView *vo[3], PetscInt i, PetscInt j, PetscInt k, PetscInt n)
{
  const PetscBool inside = (PetscBool)(i < n - 1 && j < n - 1 && k < n - 1);
  const PetscInt  c      = i + n * (j + n * k);
  for (PetscInt d = 0; d < 3; d++) {
    const PffView *o = &vo[d][PFF_REGION_SELF];
    if (o->ptr[o->off + c] > 0) return PETSC_TRUE;
    const PetscInt ii = i + (d == 0), jj = j + (d == 1), kk = k + (d == 2);
    const PetscInt q = c + (d == 0 ? 1 : (d == 1 ? n : n * n));
    if ((inside ? o->ptr[o->off + q] : *PffViewsAt(vo[d], ii, jj, kk, n)) > 0) return PETSC_TRUE;
  }
  return PETSC_FALSE;
}

/* The face neighbours of cell (i, j, k) of an n^3 block that are walls (across the block's holes) or whose value in the
   cell view v is >= thr (above) or < thr (!above): the liquid model's tests of an enclosed void and of an interior
   cell. */
static inline PetscInt PffFlowFaceNeighbours_Private(const PffBlockInfo *info, const PffView *v, PetscInt i, PetscInt j,
                                                     PetscInt k, PetscInt n, float thr, PetscBool above)
{
  const PetscInt d[6][3] = {{-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};
  PetscInt       cnt     = 0;
  for (PetscInt q = 0; q < 6; q++) {
    const PetscInt ii = i + d[q][0], jj = j + d[q][1], kk = k + d[q][2];
    const PetscInt r = PffRegionIndex(ii, jj, kk, n);
    if (r != 13 && ((info->holes >> r) & 1))
      cnt++;
    else {
      const float val = *PffViewsAt(v, ii, jj, kk, n);
      cnt += above ? val >= thr : val < thr;
    }
  }
  return cnt;
}

/* adapt.c */
PETSC_INTERN PetscErrorCode PffFlowAdaptSetUp_Private(PffFlow);
PETSC_INTERN PetscErrorCode PffFlowAdaptDestroy_Private(PffFlow);
PETSC_INTERN PetscErrorCode PffFlowAdapt_Private(PffFlow, PffFlowAdaptStats *);
PETSC_INTERN PetscErrorCode PffFlowAdaptSeed_Private(PffFlow, PffSeedFn, void *);
PETSC_INTERN PetscErrorCode PffFlowAdaptRegionOptions_Private(PffFlow, PetscOptionItems *);
/* flow.c */
PETSC_INTERN PetscErrorCode PffFlowLiquidProject_Private(PffFlow, PetscReal dt, PffPressureStats *);
PETSC_INTERN PetscErrorCode PffFlowLiquidG2P_Private(PffFlow, const PetscReal alpha[]);
PETSC_INTERN PetscErrorCode PffFlowLiquidQuadtree_Private(PffFlow, PffSeedFn, void *);
PETSC_INTERN PetscErrorCode PffFlowCheckTopology_Private(PffFlow);
/* step.c */
/* P2G of particles part (the flow's, or a reference lattice) into chMass and chUt, and their volume into chVol when
   there is a volume correction: on the cell centres in the two-phase model, on the faces (with P2G) in the liquid
   model. Collective. */
PETSC_INTERN PetscErrorCode PffFlowSplat_Private(PffFlow, PffParticles part, const PetscReal density[]);
/* phase.c */
PETSC_INTERN PetscErrorCode PffFlowPhaseField_Private(PffFlow);
/* correction.c */
PETSC_INTERN PetscErrorCode PffFlowReferenceVolume_Private(PffFlow);
PETSC_INTERN PetscErrorCode PffFlowReferenceBodies_Private(PffFlow);
/* now[] becomes now or last (the blocks a body is at or has left since the last call), last[] becomes now. */
static inline void PffFlowBlocksSince_Private(PetscInt nblocks, PetscBool now[], PetscBool last[])
{
  for (PetscInt b = 0; b < nblocks; b++) {
    const PetscBool n = now[b];
    now[b]            = (PetscBool)(n || last[b]);
    last[b]           = n;
  }
}
/* Sets r[b] for the raster blocks within margin of a body's bounding box (others untouched). */
PETSC_INTERN PetscErrorCode PffFlowBodyBlocks_Private(PffFlow, PetscReal, PetscBool[]);
PETSC_INTERN PetscErrorCode PffFlowVolumeCorrection_Private(PffFlow, PffFlowStepStats *);
PETSC_INTERN PetscErrorCode PffFlowCorrectionVelocity_Private(PffFlow, PetscReal dt, PetscBool extrapolated);
/* liquidband.c */
PETSC_INTERN PetscErrorCode PffFlowLiquidBandSetUp_Private(PffFlow);
PETSC_INTERN PetscErrorCode PffFlowLiquidBandInit_Private(PffFlow);
PETSC_INTERN PetscErrorCode PffFlowLiquidBandFill_Private(PffFlow);
PETSC_INTERN PetscErrorCode PffFlowLiquidBandDistance_Private(PffFlow);
PETSC_INTERN PetscErrorCode PffFlowLiquidBandAdvect_Private(PffFlow, PetscReal dt, PetscInt chVel, PffFlowStepStats *);
/* liquidcorr.c */
PETSC_INTERN PetscErrorCode PffFlowLiquidCorrection_Private(PffFlow, PetscReal dt);
/* fields.c */
PETSC_INTERN PetscErrorCode PffFlowFaceVelocity_Private(PffFlow, PetscReal dt);
PETSC_INTERN PetscErrorCode PffFlowOpenFaces_Private(PffFlow, PetscBool);

/* Position of the lower comp-face (or the centre, comp < 0) of cell (i, j, k) of a block. */
static inline void PffFacePosition(const PffBlockInfo *info, PetscInt i, PetscInt j, PetscInt k, PetscInt comp,
                                   PetscReal x[3])
{
  const PetscInt ijk[3] = {i, j, k};
  for (int a = 0; a < 3; a++) x[a] = info->lo[a] + info->h * ((PetscReal)ijk[a] + (a == comp ? 0.0 : 0.5));
}
PETSC_INTERN PetscReal      PffFlowLiquidSolid_Private(const PetscReal x[3], PetscReal grad[3], void *ctx);
PETSC_INTERN PetscErrorCode PffFlowLiquidQuadtreeStep_Private(PffFlow, PffFlowAdaptStats *);
PETSC_INTERN PetscErrorCode PffFlowPrescribe_Private(PffFlow, PetscReal t);
PETSC_INTERN PetscErrorCode PffFlowVelocityChange_Private(PffFlow);
PETSC_INTERN PetscErrorCode PffFlowVorticity_Private(PffFlow, PetscInt ch);
PETSC_INTERN PetscErrorCode PffFlowMaxFaceSpeed_Private(PffFlow, PetscInt ch, PetscReal *umax);
PETSC_INTERN PetscErrorCode PffFlowFlipRatios_Private(PffFlow, PetscReal dt, PetscReal alpha[]);
PETSC_INTERN PetscErrorCode PffFlowEscaped_Private(PffFlow, PetscInt64 *bubbles, PetscInt64 *droplets);
PETSC_INTERN PetscErrorCode PffFlowMaxParticleSpeed_Private(PffFlow, PetscReal *umax);
