/* Volume correction (the c_div of PF-FLIP Eq. 8, after Losasso et al. 2008), applied as a particle
   displacement instead of a velocity (docs/flow.md, "Volume correction").

   P2G also splats the type-blind particle volume W_f = sum_p t_fp V_p with trilinear weights t_fp (a
   partition of unity, so a lattice and randomly placed particles have the same expected W). Its target
   W_ref is what the same P2G gives for the regular lattice of 8 particles per cell in every fluid cell,
   splatted once at set-up: the interior value, less beside walls and solids, and whatever the
   cross-level splatting gives at level boundaries, so all three cancel from the ratio. A cell's
   particle volume fraction is s = sum W / sum W_ref over its open faces: the liquid's own fraction plus
   the gas's own, interface cells included. The same set-up splat gives Eq. 6's kernel sum of the
   lattice (mass_ref), against which phase.c reads Eq. 7.

   The correction is the projection of Eq. 8 with u* = 0, dt = 1 and the source of PffCorrectionSource:
   on this step's coefficients beta = 1/rho it gives a face field d = -beta G q with D d = -c_div, a
   displacement in metres that spreads over-dense cells and pulls under-dense ones together. It is
   bounded per face by -flow_volume_correction_max_displacement cells and added to the advection
   velocities as d / dt only: it moves the particles by d in the step, whatever dt is, and never enters
   u, the FLIP update or the particle velocities. */
#include "flowimpl.h"
#if defined(__GLIBC__)
#include <malloc.h>
#endif

/* The part of the raster whose reference is made: depth[27 b + r] is, for raster block b and its neighbour region r
   (PffRegionDirection; PFF_REGION_SELF the block itself), the depth in b's own cells of b's slab toward that
   neighbour (0: none; at most a block's 64 cells, so a byte: the raster may hold millions of blocks). A depth along
   PFF_REGION_SELF means the whole block. */

/* A box of finest-cell units relative to a block's lower corner: [lo, hi) per axis */
typedef struct {
  PetscInt lo[3], hi[3];
} PffRefBox;

/* The boxes of raster block q's regions (depth dep[27]), shifted by shift[] (finest units) into
   another block's frame. Returns their number (at most 27). */
static PetscInt RegionBoxes(const uint8_t dep[27], PetscInt n0, PetscInt level, const PetscInt shift[3],
                            PffRefBox box[])
{
  const PetscInt s = (PetscInt)1 << level;
  PetscInt       m = 0;

  for (PetscInt r = 0; r < 27; r++) {
    PetscInt d[3];
    if (!dep[r]) continue;
    PffRegionDirection(r, d);
    for (PetscInt a = 0; a < 3; a++) {
      const PetscInt w = r == PFF_REGION_SELF ? n0 : PetscMin(n0, dep[r] * s);
      box[m].lo[a]     = shift[a] + (d[a] > 0 ? n0 - w : 0);
      box[m].hi[a]     = shift[a] + (d[a] < 0 ? w : n0);
    }
    m++;
    if (r == PFF_REGION_SELF) return 1; /* the whole block holds the others */
  }
  return m;
}

static inline PetscInt FloorDiv(PetscInt a, PetscInt b)
{
  return a >= 0 ? a / b : -((-a + b - 1) / b);
}

/* mask[c] = true for the cells c of a block at level l (n cells per axis) that lie within reach finest units of one
   of the boxes (reach 0: inside one) */
static void MarkCells(const PffRefBox *box, PetscInt nbox, PetscInt n, PetscInt l, PetscInt reach, PetscBool mask[])
{
  const PetscInt s = (PetscInt)1 << l;

  for (PetscInt q = 0; q < nbox; q++) {
    PetscInt lo[3], hi[3];
    for (PetscInt a = 0; a < 3; a++) { /* cells c with c s - reach < hi and (c + 1) s + reach > lo */
      lo[a] = PetscMax(0, FloorDiv(box[q].lo[a] - reach, s));
      hi[a] = PetscMin(n, FloorDiv(box[q].hi[a] + reach + s - 1, s));
    }
    for (PetscInt k = lo[2]; k < hi[2]; k++)
      for (PetscInt j = lo[1]; j < hi[1]; j++)
        for (PetscInt i = lo[0]; i < hi[0]; i++) mask[i + n * (j + n * k)] = PETSC_TRUE;
  }
}

/* The lattice points of the cells ReferenceLattice lists, except those inside a solid: the scenes seed nothing there
   (distance < 0); with bodies only the sign of their distance counts, and most lattice points lie outside every
   body's bounding box. */
static PetscErrorCode PffReferenceSeed(const PetscReal x[3], PetscInt *type, PetscReal v[3], void *ctx)
{
  const PffFlow f = (PffFlow)ctx;
  PetscReal     grad[3];
  PetscBool     inside;

  PetscFunctionBeginUser;
  v[0] = v[1] = v[2] = 0;
  if (f->bodies)
    inside = (PetscBool)((f->staticSolid && f->staticSolid(x, grad, f->staticSolidCtx) < 0) ||
                         PffBodiesContain(f->bodies, x));
  else
    inside = (PetscBool)(f->solid && f->solid(x, grad, f->solidCtx) < 0);
  *type = inside ? -1 : PFF_PARTICLE_LIQUID;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Lattice particles per batch and rank: the reference lattice (8 particles per cell) exists a batch of
   blocks at a time, so that a reset during a run (PffFlowReset after an adapt) does not hold a lattice
   of the whole grid beside the particles (36 B per lattice particle, 288 B per cell): at most 2^20, 36 MB
   of store per rank (with 2^22 the peak of the adaptive rt3d W = 64 run to t/t0 = 2.7 was 587 MB per rank
   instead of 531; the extra batches cost about 1 % of its time, docs/benchmarks.md). */
#define PFF_REFERENCE_BATCH ((PetscInt64)1 << 20)

/* Owned values of src copied (add = false) or added to dst on the cells of local block lb that mask marks, or on
   all of them for mask NULL (cell or face channels of one width; a cell owns its lower faces) */
static PetscErrorCode PffCopyChannel(PffGrid grid, PetscInt lb, PetscInt src, PetscInt dst, const PetscBool mask[],
                                     PetscBool add)
{
  PffChannelKind kind;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetChannelInfo(grid, src, NULL, &kind, NULL, NULL));
  for (PetscInt d = 0; d < (kind == PFF_CHANNEL_FACE ? 3 : 1); d++) {
    float   *s, *t;
    PetscInt n3 = 0;
    PetscCall(PffFlowGridBlockData_Private(grid, lb, d, 1, &src, &s, &n3));
    PetscCall(PffFlowGridBlockData_Private(grid, lb, d, 1, &dst, &t, NULL));
    if (!mask && !add)
      PetscCall(PetscArraycpy(t, s, n3));
    else
      for (PetscInt c = 0; c < n3; c++)
        if (!mask || mask[c]) t[c] = add ? t[c] + s[c] : s[c];
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* out = in and its 26 neighbours (raster masks) */
static void PffDilate(const PetscInt nb[3], const PetscBool periodic[3], const PetscBool in[], PetscBool out[])
{
  const PetscInt nblocks = nb[0] * nb[1] * nb[2];
  for (PetscInt b = 0; b < nblocks; b++) out[b] = in[b];
  for (PetscInt b = 0; b < nblocks; b++) {
    if (!in[b]) continue;
    PetscInt ijk[3];
    PffRasterCoordinates(nb, b, ijk);
    for (PetscInt r = 0; r < 27; r++) {
      PetscInt d[3];
      PffRegionDirection(r, d);
      const PetscInt q = PffRasterNeighbour(nb, periodic, ijk, d);
      if (q >= 0) out[q] = PETSC_TRUE;
    }
  }
}

/* The regions of depth (the same on every rank) that lie within reach of local block lb's cells, as boxes in lb's
   frame: its own and its 26 neighbours' */
static PetscErrorCode NeighbourBoxes(PffFlow f, const uint8_t depth[], const PffBlockInfo *info, PffRefBox box[],
                                     PetscInt *nbox)
{
  PetscInt        nb[3], n0;
  const PetscInt *level;
  PetscBool       periodic[3];

  PetscFunctionBeginUser;
  PetscCall(PffGridGetRaster(f->grid, nb, &level, NULL));
  PetscCall(PffGridGetSizes(f->grid, &n0, NULL, NULL, NULL, periodic));
  *nbox = 0;
  for (PetscInt r = 0; r < 27; r++) {
    PetscInt d[3], shift[3];
    PffRegionDirection(r, d);
    const PetscInt q = PffRasterNeighbour(nb, periodic, info->ijk, d);
    if (q < 0) continue;
    for (PetscInt a = 0; a < 3; a++) shift[a] = d[a] * n0;
    *nbox += RegionBoxes(&depth[27 * q], n0, level[q], shift, box + *nbox);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The reference of Eq. 6-7 and of the volume correction on the regions of depth (see PFF_REGION_SELF): the P2G of a
   lattice of 8 particles per cell, seeded in every cell within two cells of its own level of a region (a lattice
   particle splats into its block and a ghost layer one cell of its level wide around it, so one farther away adds
   nothing there), copied into mass_ref and volume_ref on the regions' cells only. Collective. */
static PetscErrorCode ReferenceLattice(PffFlow f, const uint8_t depth[], PetscBool trim)
{
  PffParticles    ref;
  const PetscReal one[PFF_PARTICLE_NTYPES] = {1, 1};
  PetscInt        nlocal, nbatch, n0, ncells = 0, cap = 0, *cells = NULL, nregion = 0;
  PetscBool     **copy, *whole; /* per local block: the cells whose faces are copied, or the whole block */
  PffRefBox       box[27 * 27];

  PetscFunctionBeginUser;
  PetscCall(PffGridGetSizes(f->grid, &n0, NULL, NULL, NULL, NULL));
  PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
  PetscCall(PetscCalloc2(PetscMax(nlocal, 1), &copy, PetscMax(nlocal, 1), &whole));
  /* the cells to seed (block, cell) and those to copy, per local block */
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    PetscInt     nbox = 0, n3, zero[3] = {0, 0, 0};
    PetscCall(PffGridGetBlockInfo(f->grid, lb, &info));
    n3 = info.n * info.n * info.n;
    PetscCall(NeighbourBoxes(f, depth, &info, box, &nbox));
    if (!nbox) continue;
    PetscBool *mask;
    PetscCall(PetscCalloc1(n3, &mask));
    MarkCells(box, nbox, info.n, info.level, 2 << info.level, mask);
    PetscCall(PetscIntMultError(2, ncells + n3, NULL)); /* the list's size fits PetscInt */
    if (2 * (ncells + n3) > cap) {
      cap = PetscMax(2 * cap, 2 * (ncells + n3));
      PetscCall(PetscRealloc(sizeof(PetscInt) * cap, &cells));
    }
    for (PetscInt c = 0; c < n3; c++)
      if (mask[c]) {
        cells[2 * ncells]     = lb;
        cells[2 * ncells + 1] = c;
        ncells++;
      }
    const uint8_t *dep = &depth[27 * info.gid];
    nbox               = RegionBoxes(dep, n0, info.level, zero, box);
    if (nbox && !dep[PFF_REGION_SELF]) {
      PetscCall(PetscArrayzero(mask, n3));
      MarkCells(box, nbox, info.n, info.level, 0, mask);
      copy[lb] = mask;
    } else
      PetscCall(PetscFree(mask));
    if (nbox) nregion++;
    whole[lb] = (PetscBool)(nbox && dep[PFF_REGION_SELF]);
  }
  {
    PetscInt64 nbt = (8 * (PetscInt64)ncells + PFF_REFERENCE_BATCH - 1) / PFF_REFERENCE_BATCH;
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &nbt, 1, MPIU_INT64, MPI_MAX, f->comm)); /* P2G is collective */
    nbatch = (PetscInt)PetscMax(nbt, 1);
  }
  PetscCall(PffParticlesCreate(f->grid, &ref));
  PetscCall(PffParticlesSetJitter(ref, 0));
  for (PetscInt k = 0, c0 = 0; k < nbatch; k++) {
    /* a batch ends with the block in which its share of the cells ends, so that a block's cells splat together */
    PetscInt c1 = (PetscInt)((PetscInt64)ncells * (k + 1) / nbatch);
    while (c1 > 0 && c1 < ncells && cells[2 * c1] == cells[2 * (c1 - 1)]) c1++;
    c1 = PetscMax(c1, c0);
    PetscCall(PffParticlesClear(ref));
    PetscCall(PffParticlesSeedCells(ref, PffReferenceSeed, f, c1 - c0, cells ? cells + 2 * c0 : NULL, 1));
    c0 = c1;
    /* the kernel sum of Eq. 6 for the same lattice normalises Eq. 7 (phase.c); mass, momentum and volume land in
       working channels that every step overwrites */
    PetscCall(PffFlowSplat_Private(f, ref, one));
    for (PetscInt lb = 0; lb < nlocal; lb++) {
      if (!whole[lb] && !copy[lb]) continue;
      PetscCall(PffCopyChannel(f->grid, lb, f->chMass, f->chMassRef, copy[lb], (PetscBool)(k > 0)));
      if (f->chVolRef >= 0) PetscCall(PffCopyChannel(f->grid, lb, f->chVol, f->chVolRef, copy[lb], (PetscBool)(k > 0)));
    }
  }
  PetscCall(PffParticlesDestroy(&ref));
  for (PetscInt lb = 0; lb < nlocal; lb++) PetscCall(PetscFree(copy[lb]));
  PetscCall(PetscFree2(copy, whole));
  PetscCall(PetscFree(cells));
#if defined(__GLIBC__)
  /* glibc keeps freed heap pages resident until they are trimmed: the lattice's store and scratch (160 MB per rank
     in rt3d W = 64) stayed resident, and the seed reused only part of them (20 MB per rank of the peak); the bodies'
     reference, made at every step, keeps them (trimmed, their pages were faulted in again at every step) */
  if (trim) malloc_trim(0);
#else
  (void)trim;
#endif
  PetscCall(PetscInfo(
      NULL, "reference lattice made again on %" PetscInt_FMT " local blocks, %" PetscInt_FMT " cells seeded\n", nregion,
      ncells));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The lattice on the regions of depth when there are any, then, for the liquid model, which reads volume_ref's faces
   through their halo, that halo in any case: a re-partition moves blocks without changing their levels (the two-phase
   measure reads its own cells only). Collective. */
static PetscErrorCode ReferenceRegions(PffFlow f, const uint8_t depth[], PetscBool trim)
{
  PetscInt  nb[3];
  PetscBool any = PETSC_FALSE;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetRaster(f->grid, nb, NULL, NULL));
  for (PetscInt b = 0; b < 27 * nb[0] * nb[1] * nb[2] && !any; b++) any = (PetscBool)(depth[b] > 0);
  if (any) PetscCall(ReferenceLattice(f, depth, trim));
  if (f->chVolRef >= 0 && f->model == PFF_FLOW_LIQUID) {
    PetscCall(PffGridHaloBegin(f->grid, f->chVolRef));
    PetscCall(PffGridHaloEnd(f->grid, f->chVolRef));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The reference depends on the levels of its block and its 26 neighbours, walls and solids only. After a topology
   change (refLevel: the raster levels it was last made for) a block whose level changed is made again whole, and a
   block beside one is made again in a slab toward it: as deep as a lattice particle of the changed block at its
   coarser level (before or after) reaches, one cell of that level and its ghost layer, and a cell more. The
   rest kept its values through PffGridAdapt (a copy: the level did not change). Without refLevel everything is
   made. */
PetscErrorCode PffFlowReferenceVolume_Private(PffFlow f)
{
  const PetscInt *level;
  PetscInt        nb[3], nblocks, n0;
  uint8_t        *depth;
  PetscBool       periodic[3], *changed;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetRaster(f->grid, nb, &level, NULL));
  PetscCall(PffGridGetSizes(f->grid, &n0, NULL, NULL, NULL, periodic));
  nblocks = nb[0] * nb[1] * nb[2];
  PetscCall(PetscMalloc1(nblocks, &changed));
  PetscCall(PetscCalloc1(27 * nblocks, &depth));
  for (PetscInt b = 0; b < nblocks; b++) changed[b] = (PetscBool)(!f->refLevel || f->refLevel[b] != level[b]);
  for (PetscInt b = 0; b < nblocks; b++) {
    PetscInt ijk[3];
    if (changed[b]) {
      depth[27 * b + PFF_REGION_SELF] = 1;
      continue;
    }
    PffRasterCoordinates(nb, b, ijk);
    for (PetscInt r = 0; r < 27; r++) {
      PetscInt d[3];
      PffRegionDirection(r, d);
      const PetscInt q = PffRasterNeighbour(nb, periodic, ijk, d);
      if (q < 0 || !changed[q]) continue;
      const PetscInt lq = PetscMax(level[q], f->refLevel[q]), n = n0 >> level[b];
      /* one cell of q's coarser level and its ghost layer, in b's cells, and a cell more (test_adapt_reference
         passes with a cell less and fails with slabs one cell deep) */
      const PetscInt reach = lq >= level[b] ? (PetscInt)2 << (lq - level[b]) : 1;
      depth[27 * b + r]    = (uint8_t)PetscMin(n, reach + 1);
    }
  }
  /* a full build trims the lattice's pages; after an adapt the step trims once at its end (step.c) */
  const PetscBool full = (PetscBool)!f->refLevel;
  if (full) PetscCall(PetscMalloc1(nblocks, &f->refLevel));
  PetscCall(PetscArraycpy(f->refLevel, level, nblocks));
  PetscCall(ReferenceRegions(f, depth, full));
  PetscCall(PetscFree(changed));
  PetscCall(PetscFree(depth));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* With moving bodies the reference follows them: the blocks within two cells of a body's bounding box now, and
   those of the last call (which the body may have left; at the first call, as after a restart, the blocks within
   one block of those of now), are made again at the bodies' current poses. Without
   it the lattice target near a body is the one of its initial pose, and the particles it pushes out of itself
   pile up unseen (the floating box lost 8 % of its pool that way on cubic cells). Collective. */
PetscErrorCode PffFlowReferenceBodies_Private(PffFlow f)
{
  PetscInt   nb[3], nblocks;
  PetscReal  h;
  PetscBool *r1;

  PetscFunctionBeginUser;
  if (!f->bodies) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscLogEventBegin(PFF_FlowRefBodies, 0, 0, 0, 0));
  PetscCall(PffGridGetRaster(f->grid, nb, NULL, NULL));
  PetscCall(PffGridGetSizes(f->grid, NULL, NULL, NULL, &h, NULL));
  nblocks               = nb[0] * nb[1] * nb[2];
  const PetscBool first = (PetscBool)!f->refBody;
  if (first) PetscCall(PetscCalloc1(nblocks, &f->refBody));
  PetscCall(PetscCalloc1(nblocks, &r1));
  PetscCall(PffFlowBodyBlocks_Private(f, 2 * h, r1));
  if (first) { /* the last step's blocks are unknown after a restart: those within a block of the bodies' now */
    PetscBool periodic[3];
    PetscCall(PffGridGetSizes(f->grid, NULL, NULL, NULL, NULL, periodic));
    PffDilate(nb, periodic, r1, f->refBody);
  }
  PffFlowBlocksSince_Private(nblocks, r1, f->refBody);
  {
    uint8_t *depth;
    PetscCall(PetscCalloc1(27 * nblocks, &depth));
    for (PetscInt b = 0; b < nblocks; b++) depth[27 * b + PFF_REGION_SELF] = (uint8_t)r1[b];
    PetscCall(ReferenceRegions(f, depth, PETSC_FALSE));
    PetscCall(PetscFree(depth));
  }
  PetscCall(PetscFree(r1));
  PetscCall(PetscLogEventEnd(PFF_FlowRefBodies, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowBodyBlocks_Private(PffFlow f, PetscReal margin, PetscBool r[])
{
  PetscInt     nb[3], n0, nbody;
  PetscReal    origin[3], h;
  PffTallBody *tb;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetRaster(f->grid, nb, NULL, NULL));
  PetscCall(PffGridGetSizes(f->grid, &n0, NULL, origin, &h, NULL));
  PetscCall(PffBodiesGetTall(f->bodies, &nbody, &tb));
  for (PetscInt i = 0; i < nbody; i++) {
    PetscInt lo[3], hi[3];
    for (PetscInt a = 0; a < 3; a++) {
      const PetscReal blen = (PetscReal)n0 * h;
      lo[a]                = PetscMax(0, (PetscInt)PetscFloorReal((tb[i].lo[a] - margin - origin[a]) / blen));
      hi[a]                = PetscMin(nb[a] - 1, (PetscInt)PetscFloorReal((tb[i].hi[a] + margin - origin[a]) / blen));
    }
    for (PetscInt bk = lo[2]; bk <= hi[2]; bk++)
      for (PetscInt bj = lo[1]; bj <= hi[1]; bj++)
        for (PetscInt bi = lo[0]; bi <= hi[0]; bi++) r[bi + nb[0] * (bj + nb[1] * bk)] = PETSC_TRUE;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The liquid's target particle fraction s* moves by gamma (V - V0) / V0 per step (an integral control, gamma =
   -flow_volume_control), with V the liquid volume sum(phi V) of this step's phase field and V0 its value at the first
   step. Eq. 7 counts particles mixed across the interface as liquid, so a correction to s = 1 in every liquid cell
   let the liquid volume grow with the mixing (the nine bubbles of bubbles_small lost 13 % of their volume in 28
   steps, docs/validation.md); a higher s* packs the liquid's particles a little closer, so that the liquid region
   keeps its volume. s* stays in [PFF_VOLCONTROL_MIN, PFF_VOLCONTROL_MAX]: a volume the control cannot reach (liquid
   leaving the domain) stops it there instead of packing the particles without bound. Collective. */
#define PFF_VOLCONTROL_MIN 0.8
#define PFF_VOLCONTROL_MAX 1.25
static PetscErrorCode PffVolumeControl(PffFlow f)
{
  PetscReal v;

  PetscFunctionBeginUser;
  if (f->volControl <= 0) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PffFlowGetPhaseVolumes(f, &v, NULL));
  if (f->volTarget <= 0)
    f->volTarget = v;
  else
    f->volFraction =
        PetscMax(PFF_VOLCONTROL_MIN,
                 PetscMin(PFF_VOLCONTROL_MAX, f->volFraction + f->volControl * (v - f->volTarget) / f->volTarget));
  PetscCall(PetscInfo(NULL, "volume control: liquid volume %.9e, held at %.9e, target fraction %.6f\n", (double)v,
                      (double)f->volTarget, (double)f->volFraction));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* c_div per fluid cell: -kappa (s - s*) in liquid cells (cell phi >= 1/2; s* = 1 without the control above) and -kappa
   (s - s_gas) - c0 in gas cells, where s_gas is the gas cells' mean s (so that deleted bubbles rarefy the gas, not the
   whole box) and c0 hands the liquid's net volume change to the gas cells, so that sum(c_div V) = 0
   and the liquid reaches its target in a closed box too. 0 in cells closed on every face. */
static PetscErrorCode PffCorrectionSource(PffFlow f)
{
  PetscInt  nlocal;
  PetscReal sum[4] = {0, 0, 0, 0}; /* gas cells: sum W V, sum W_ref V, sum V; liquid cells: sum c_div V */

  PetscFunctionBeginUser;
  PetscCall(PffVolumeControl(f));
  const PetscReal sl = f->volFraction;
  PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
  /* first pass: s into c_div (-1 where no face is open), the totals */
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo   info;
    const PffView *vo[3];
    float         *cdiv, *phi, *vw, *vr;
    PetscCall(PffGridGetBlockInfo(f->grid, lb, &info));
    PetscCall(PffGridGetBlockData(f->grid, f->chCdiv, lb, 0, &cdiv));
    PetscCall(PffGridGetBlockData(f->grid, f->chPhi, lb, 0, &phi));
    PetscCall(PffGridGetBlockData(f->grid, f->chVol, lb, 0, &vw));
    PetscCall(PffGridGetBlockData(f->grid, f->chVolRef, lb, 0, &vr));
    for (PetscInt d = 0; d < 3; d++) PetscCall(PffGridGetBlockViews(f->grid, f->chOpen, lb, d, &vo[d]));
    const PetscInt  n  = info.n;
    const PetscReal vc = info.h * info.h * info.h;
    for (PetscInt k = 0; k < n; k++)
      for (PetscInt j = 0; j < n; j++)
        for (PetscInt i = 0; i < n; i++) {
          const PetscInt  c = i + n * (j + n * k);
          const PetscReal w = vw[c], wref = vr[c];
          /* a cell inside a solid may hold a lattice particle's kernel tail: it has no open face and no source */
          if (wref <= 0 || !PffFlowCellOpen_Private(vo, i, j, k, n)) {
            cdiv[c] = -1;
            continue;
          }
          const PetscReal s = w / wref;
          cdiv[c]           = (float)s;
          if (phi[c] >= 0.5)
            sum[3] += -f->volCorr * (s - sl) * vc;
          else {
            sum[0] += w * vc;
            sum[1] += wref * vc;
            sum[2] += vc;
          }
        }
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, sum, 4, MPIU_REAL, MPI_SUM, f->comm));
  const PetscReal sgas = sum[1] > 0 ? sum[0] / sum[1] : 1, c0 = sum[2] > 0 ? sum[3] / sum[2] : 0;
  /* second pass: s -> c_div */
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    float   *cdiv, *phi;
    PetscInt n3 = 0;
    PetscCall(PffFlowBlockData_Private(f, lb, 0, 1, &f->chCdiv, &cdiv, &n3));
    PetscCall(PffGridGetBlockData(f->grid, f->chPhi, lb, 0, &phi));
    for (PetscInt c = 0; c < n3; c++) {
      const PetscReal s = cdiv[c];
      if (s < 0)
        cdiv[c] = 0;
      else if (phi[c] >= 0.5)
        cdiv[c] = (float)(-f->volCorr * (s - sl));
      else
        cdiv[c] = (float)(-f->volCorr * (s - sgas) - c0);
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The displacement d into chUt (free after G2P): the projection of Eq. 8 with u* = 0, dt = 1 and c_div
   from chCdiv, on the step's own operator (beta = 1/rho: no set-up, and the gas yields where the liquid
   moves), at its own tolerance; q (chQ) is the potential, from a zero initial guess. d is bounded per face.
   Warm started from the previous q, a solve at rtol 0.1 of |b| often stopped after 0 or 1 iterations near the
   previous step's d: the correction lagged a step, and with the volume's control the liquid volume of the
   adaptive rt3d run swung by +-0.3 % at every other step (docs/validation.md, "Holes after a grid change"). */
static PetscErrorCode PffCorrectionDisplacement(PffFlow f, PffPressureStats *st)
{
  KSP       ksp;
  PetscReal rtol, atol, dtol;
  PetscInt  maxit, nlocal;
  PetscBool guess;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
  /* a fraction of a cell needs no 1e-8: the solve runs at its own tolerance, then the pressure's is back */
  PetscCall(PffPressureGetKSP(f->press, &ksp));
  PetscCall(KSPGetTolerances(ksp, &rtol, &atol, &dtol, &maxit));
  PetscCall(KSPGetInitialGuessNonzero(ksp, &guess));
  PetscCall(KSPSetTolerances(ksp, f->volCorrRtol, atol, dtol, maxit));
  PetscCall(KSPSetInitialGuessNonzero(ksp, PETSC_FALSE));
  PetscCall(PffPressureProjectSource(f->press, f->chUt, 1.0, f->chCdiv, f->chQ, st));
  PetscCall(KSPSetInitialGuessNonzero(ksp, guess));
  /* while the correction's tolerance is in force, which the message quotes */
  PetscCall(PffPressureCheckSolve(f->press, st, "Correction", f->step + 1, f->t,
                                  "loosen -flow_volume_correction_rtol or raise -pressure_ksp_max_it"));
  PetscCall(KSPSetTolerances(ksp, rtol, atol, dtol, maxit));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(f->grid, lb, &info));
    const PetscReal bound = f->volCorrMaxDisp * info.h;
    for (PetscInt d = 0; d < 3; d++) {
      float   *u;
      PetscInt n3 = 0;
      PetscCall(PffFlowBlockData_Private(f, lb, d, 1, &f->chUt, &u, &n3));
      for (PetscInt c = 0; c < n3; c++) u[c] = (float)PetscMax(-bound, PetscMin(bound, (PetscReal)u[c]));
    }
  }
  PetscCall(PetscInfo(NULL, "volume correction: %" PetscInt_FMT " iterations, relative residual %.2e\n", st->its,
                      (double)st->rnorm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowVolumeCorrection_Private(PffFlow f, PffFlowStepStats *st)
{
  PetscFunctionBeginUser;
  PetscCall(PffCorrectionSource(f));
  PetscCall(PffCorrectionDisplacement(f, &st->correction));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The advection channels with the displacement as velocity d / dt: chUa = u + d_gas / dt for the gas,
   chUl = (the extrapolated liquid velocity, or u without extrapolation) + d_liquid / dt; halos
   exchanged. On a face between a liquid and a gas cell the gas keeps only the part of d that moves it
   into the gas cell (a type-blind d pulled the gas into every liquid cell short of particles, where it
   was deleted as a bubble, which left the cell short again); the liquid keeps all of d, or, with
   -flow_volume_correction_interface closed, neither phase crosses the face. With layer no face of an interface cell
   (0 < phi < 1) moves: the displacement evens out the bulk's particle noise, and where it reached the interface it
   roughened it, which the square root of Eq. 7 counts as liquid. */
PetscErrorCode PffFlowCorrectionVelocity_Private(PffFlow f, PetscReal dt, PetscBool extrapolated)
{
  PetscInt        nlocal;
  const PetscReal idt = 1.0 / dt;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo   info;
    const PffView *vphi;
    PetscCall(PffGridGetBlockInfo(f->grid, lb, &info));
    PetscCall(PffGridGetBlockViews(f->grid, f->chPhi, lb, 0, &vphi));
    const PetscInt n = info.n;
    for (PetscInt d = 0; d < 3; d++) {
      const PetscInt ch[4] = {f->chUt, f->chU, f->chUa, f->chUl};
      float         *a[4];
      PetscCall(PffFlowBlockData_Private(f, lb, d, 4, ch, a, NULL));
      const float *disp = a[0], *u = a[1];
      float       *ua = a[2], *ul = a[3];
      for (PetscInt k = 0; k < n; k++)
        for (PetscInt j = 0; j < n; j++)
          for (PetscInt i = 0; i < n; i++) {
            const PetscInt c = i + n * (j + n * k);
            PetscBool      lo, hi;
            PffFlowFaceTags_Private(vphi, i, j, k, d, n, &lo, &hi);
            PetscReal dd = disp[c];
            if (f->volCorrInterface == PFF_FLOW_CORR_LAYER) {
              const PetscInt  e[3] = {d == 0, d == 1, d == 2};
              const PetscReal p0   = *PffViewsAt(vphi, i - e[0], j - e[1], k - e[2], n),
                              p1   = *PffViewsAt(vphi, i, j, k, n);
              if ((p0 > 0 && p0 < 1) || (p1 > 0 && p1 < 1)) dd = 0;
            }
            PetscReal dg = dd, dl = dd;
            if (lo != hi && f->volCorrInterface == PFF_FLOW_CORR_CLOSED)
              dg = dl = 0;
            else if (lo && !hi)
              dg = PetscMax(dd, 0); /* liquid below, gas above: + moves into the gas */
            else if (!lo && hi)
              dg = PetscMin(dd, 0);
            ua[c] = (float)(u[c] + idt * dg);
            ul[c] = (float)((extrapolated ? ul[c] : u[c]) + idt * dl);
          }
    }
  }
  PetscCall(PffGridHaloBegin(f->grid, f->chUa));
  PetscCall(PffGridHaloEnd(f->grid, f->chUa));
  PetscCall(PffGridHaloBegin(f->grid, f->chUl));
  PetscCall(PffGridHaloEnd(f->grid, f->chUl));
  PetscFunctionReturn(PETSC_SUCCESS);
}
