/* Dynamic dual particle-grid adaptivity (PF-FLIP Sec. 5.4; docs/flow.md, "Adaptivity").

   Once per -adapt_interval steps, before the step's P2G:
   1. an auxiliary distance d to the interface (step 5) on a uniform lattice of the cells of the
      coarsest adaptive level, from the phase field averaged over each of its cells and thresholded at
      1/2; the lattice is small (one cell per (2^(L-1))^3 finest cells) and replicated, so every rank
      computes the same d, from interface cells (a neighbour across the threshold, d = half a cell)
      by a two-pass 26-neighbour chamfer (weights 1, sqrt 2, sqrt 3), first-order as the paper's;
   2. the level each particle asks for (step 6), l = min(L - 1, floor(beta |d(x_p)| / n0)) with d
      interpolated trilinearly, or finer where the optional vorticity criterion asks (Sec. 5.2), or the
      level of a user region that contains it; the deferred-coarsening counters D_p advance, and a
      particle whose coarsening is pending (D_p < delay) asks for its current level;
   3. the block map (step 1): the minimum level asked by the particles whose box x_p +- (r + margin)
      touches a block, r = 2^l finest cells for the level l asked; blocks no particle touches take level
      L - 1, blocks inactive at set-up stay inactive, blocks a user region overlaps take its level; graded 2:1. Each
   particle's level is then capped by its block's, so that particles are never coarser than their block (see
   GradedTargets);
   4. the split and probabilistic coarsening of PffParticlesAdaptLevels to the capped levels, and
      PffGridAdapt when the map differs from the last one (steps 2-3: grading, re-partition, moving
      channels); particles, pressure and flow follow the topology state on their next call.
   Seeding with adaptivity iterates seed -> phase field -> map until the map holds, so that a run starts
   with fine particles near the interface only, instead of seeding everything fine. */
#include "flowimpl.h"

/* Per cell of the distance lattice, the mean (or the largest) value of cell channel ch over the block cells under it,
   fill outside active blocks; the same on every rank. */
static PetscErrorCode LatticeValues(PffFlow f, PetscInt ch, PetscBool max, float fill, float *out)
{
  PffFlowAdaptCtx *a = &f->adapt;
  const PetscInt   m = a->m, ntot = a->C[0] * a->C[1] * a->C[2];
  PetscInt         nlocal;

  PetscFunctionBeginUser;
  for (PetscInt c = 0; c < ntot; c++) out[c] = fill;
  PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    float       *v;
    PetscCall(PffGridGetBlockInfo(f->grid, lb, &info));
    PetscCall(PffGridGetBlockData(f->grid, ch, lb, 0, &v));
    const PetscInt n = info.n;
    for (PetscInt ck = 0; ck < m; ck++)
      for (PetscInt cj = 0; cj < m; cj++)
        for (PetscInt ci = 0; ci < m; ci++) {
          const PetscInt cc[3] = {ci, cj, ck};
          PetscInt       lo[3], hi[3];
          double         sum = 0, big = 0;
          /* the block's cells under this lattice cell (one cell when the block is coarser) */
          for (int d = 0; d < 3; d++) {
            lo[d] = n >= m ? cc[d] * (n / m) : cc[d] / (m / n);
            hi[d] = n >= m ? lo[d] + n / m : lo[d] + 1;
          }
          for (PetscInt k = lo[2]; k < hi[2]; k++)
            for (PetscInt j = lo[1]; j < hi[1]; j++)
              for (PetscInt i = lo[0]; i < hi[0]; i++) {
                sum += v[i + n * (j + n * k)];
                big = PetscMax(big, v[i + n * (j + n * k)]);
              }
          const PetscInt g[3] = {info.ijk[0] * m + ci, info.ijk[1] * m + cj, info.ijk[2] * m + ck};
          out[g[0] + a->C[0] * (g[1] + a->C[1] * g[2])] =
              (float)(max ? big : sum / (double)((hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2])));
        }
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, out, (PetscMPIInt)ntot, MPI_FLOAT, MPI_MAX, f->comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* d at grid position g (finest cells, inside the domain), trilinear between lattice cell centres,
   wrapped on periodic axes and constant beyond the outer centres on walled ones. */
static inline float DistanceAt(const PffFlowAdaptCtx *a, const float g[3])
{
  PetscInt i0[3], i1[3];
  float    t[3];
  for (int d = 0; d < 3; d++) {
    const PetscInt c = a->C[d];
    const float    u = g[d] * a->is - 0.5f;
    const PetscInt b = (PetscInt)(u + 1.0f) - 1; /* floor for u >= -1 */
    t[d]             = u - (float)b;
    i0[d]            = b;
    i1[d]            = b + 1;
    if (b < 0) i0[d] = a->periodic[d] ? c - 1 : 0;
    if (b + 1 >= c) i1[d] = a->periodic[d] ? 0 : c - 1;
  }
  const PetscInt sy = a->C[0], sz = a->C[0] * a->C[1];
  const float   *D  = a->dist;
  const float    x0 = D[i0[0] + sy * i0[1] + sz * i0[2]] * (1 - t[0]) + D[i1[0] + sy * i0[1] + sz * i0[2]] * t[0];
  const float    x1 = D[i0[0] + sy * i1[1] + sz * i0[2]] * (1 - t[0]) + D[i1[0] + sy * i1[1] + sz * i0[2]] * t[0];
  const float    x2 = D[i0[0] + sy * i0[1] + sz * i1[2]] * (1 - t[0]) + D[i1[0] + sy * i0[1] + sz * i1[2]] * t[0];
  const float    x3 = D[i0[0] + sy * i1[1] + sz * i1[2]] * (1 - t[0]) + D[i1[0] + sy * i1[1] + sz * i1[2]] * t[0];
  return (x0 * (1 - t[1]) + x1 * t[1]) * (1 - t[2]) + (x2 * (1 - t[1]) + x3 * t[1]) * t[2];
}

/* Cells of the dual lattice: the boxes between 2 x 2 x 2 lattice cell centres, indexed by their lower
   centre b in [-1, C - 1] per axis (b = -1 and C - 1 are the half cells beside a wall, or the wrap). */
static inline PetscInt DualIndex(const PffFlowAdaptCtx *a, const PetscInt b[3])
{
  return (b[0] + 1) + (a->C[0] + 1) * ((b[1] + 1) + (a->C[1] + 1) * (b[2] + 1));
}

static inline PetscInt LevelOf(const PffFlowAdaptCtx *a, float d)
{
  const float l = a->lscale * d; /* >= 0: the cast floors */
  return l >= (float)(a->levels - 1) ? a->levels - 1 : (PetscInt)l;
}

/* The level of every dual cell whose 8 corners ask for one level (then so does every point inside:
   the interpolant lies between the corners' values, and the level is monotone in d), or 0xff. Most
   particles then need one byte instead of 8 lattice values. */
static void LevelLattice(PffFlowAdaptCtx *a)
{
  for (PetscInt bz = -1; bz < a->C[2]; bz++)
    for (PetscInt by = -1; by < a->C[1]; by++)
      for (PetscInt bx = -1; bx < a->C[0]; bx++) {
        const PetscInt b[3] = {bx, by, bz};
        PetscInt       lo = PETSC_MAX_INT, hi = -1;
        for (PetscInt q = 0; q < 8; q++) {
          PetscInt c[3];
          for (int d = 0; d < 3; d++) {
            c[d] = b[d] + ((q >> d) & 1);
            if (c[d] < 0) c[d] = a->periodic[d] ? a->C[d] - 1 : 0;
            if (c[d] >= a->C[d]) c[d] = a->periodic[d] ? 0 : a->C[d] - 1;
          }
          const PetscInt l = LevelOf(a, a->dist[c[0] + a->C[0] * (c[1] + a->C[1] * c[2])]);
          lo               = PetscMin(lo, l);
          hi               = PetscMax(hi, l);
        }
        a->lev[DualIndex(a, b)] = (uint8_t)(lo == hi ? lo : 0xff);
      }
}

#define PFF_ADAPT_CHUNK 256

/* DualIndex of the dual cell holding grid position g (g >= 0): its lower centre b = floor(g / s - 1/2) per axis. */
static inline int32_t DualCellOf(const PffFlowAdaptCtx *a, const float g[3])
{
  const int32_t sy = (int32_t)(a->C[0] + 1), sz = sy * (int32_t)(a->C[1] + 1);
  return (int32_t)(g[0] * a->is + 0.5f) + sy * (int32_t)(g[1] * a->is + 0.5f) + sz * (int32_t)(g[2] * a->is + 0.5f);
}

/* The level the distance asks for at grid position g in dual cell dual (step 6). */
static inline PetscInt LevelAt(const PffFlowAdaptCtx *a, int32_t dual, const float g[3])
{
  const uint8_t l = a->lev[dual];
  return l != 0xff ? (PetscInt)l : LevelOf(a, DistanceAt(a, g));
}

/* The level forced by the last user region (boxes, then spheres) that contains grid position g, or -1. */
static inline PetscInt RegionLevel(const PffFlowAdaptCtx *a, const float g[3])
{
  PetscInt l = -1;
  for (PetscInt r = 0; r < a->nbox; r++) {
    const PetscReal *b = a->box + 6 * r;
    if (g[0] >= b[0] && g[0] <= b[3] && g[1] >= b[1] && g[1] <= b[4] && g[2] >= b[2] && g[2] <= b[5])
      l = a->boxLevel[r];
  }
  for (PetscInt r = 0; r < a->nsphere; r++) {
    const PetscReal *c  = a->sphere + 4 * r;
    const PetscReal  d2 = (g[0] - c[0]) * (g[0] - c[0]) + (g[1] - c[1]) * (g[1] - c[1]) + (g[2] - c[2]) * (g[2] - c[2]);
    if (d2 <= c[3] * c[3]) l = a->sphereLevel[r];
  }
  return l;
}

/* The same for the block at raster position ijk: the last region its box [ijk n0, (ijk + 1) n0] overlaps. */
static PetscInt BlockRegionLevel(const PffFlowAdaptCtx *a, const PetscInt ijk[3])
{
  PetscReal lo[3], hi[3];
  PetscInt  l = -1;
  for (int d = 0; d < 3; d++) {
    lo[d] = (PetscReal)(ijk[d] * a->n0);
    hi[d] = lo[d] + (PetscReal)a->n0;
  }
  for (PetscInt r = 0; r < a->nbox; r++) {
    const PetscReal *b    = a->box + 6 * r;
    PetscBool        over = PETSC_TRUE;
    for (int d = 0; d < 3; d++) over = (PetscBool)(over && b[d] < hi[d] && b[3 + d] > lo[d]);
    if (over) l = a->boxLevel[r];
  }
  for (PetscInt r = 0; r < a->nsphere; r++) {
    const PetscReal *c  = a->sphere + 4 * r;
    PetscReal        d2 = 0;
    for (int d = 0; d < 3; d++) {
      const PetscReal q = PetscMin(PetscMax(c[d], lo[d]), hi[d]) - c[d]; /* to the closest point of the box */
      d2 += q * q;
    }
    if (d2 < c[3] * c[3]) l = a->sphereLevel[r];
  }
  return l;
}

/* The level particle position g asks for, from the distance's level l: a user region's, else the finer of l and
   the vorticity's (the lattice cell's largest |curl u|, so that no vortex within it is missed). */
static inline PetscInt Ask(const PffFlowAdaptCtx *a, const float g[3], PetscInt l)
{
  const PetscInt r = RegionLevel(a, g);
  if (r >= 0) return r;
  if (a->vlev) {
    PetscInt c[3];
    for (int d = 0; d < 3; d++) c[d] = PetscMin((PetscInt)(g[d] * a->is), a->C[d] - 1);
    l = PetscMin(l, (PetscInt)a->vlev[c[0] + a->C[0] * (c[1] + a->C[1] * c[2])]);
  }
  return l;
}

/* The vorticity criterion (Sec. 5.2, the magnitude of the curl after Popinet 2003): per lattice cell the
   coarsest level l at which |curl u| h0 2^l <= delta max|u|, from the largest |curl u| of the cells under it
   (central differences of the cell-centred velocity, the output's vorticity channel) and the largest face
   speed of the grid, of face channel ch: the last projected velocity in a step, the particles' P2G (u*) at the
   seed. */
static PetscErrorCode VorticityLevels(PffFlow f, PetscInt ch)
{
  PffFlowAdaptCtx *a    = &f->adapt;
  const PetscInt   ntot = a->C[0] * a->C[1] * a->C[2];
  float           *w    = a->work;
  PetscReal        h0, umax;

  PetscFunctionBeginUser;
  if (!a->vlev) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscLogEventBegin(PFF_FlowAdaptDist, 0, 0, 0, 0));
  PetscCall(PffFlowVorticity_Private(f, ch));
  PetscCall(LatticeValues(f, f->chVort, PETSC_TRUE, 0, w));
  PetscCall(PffFlowMaxFaceSpeed_Private(f, ch, &umax));
  PetscCall(PffGridGetSizes(f->grid, NULL, NULL, NULL, &h0, NULL));
  for (PetscInt c = 0; c < ntot; c++) {
    const PetscReal ratio = (PetscReal)w[c] > 0 && umax > 0 ? a->vort * umax / ((PetscReal)w[c] * h0) : PETSC_MAX_REAL;
    PetscInt        l     = 0;
    while (l < a->levels - 1 && ratio >= (PetscReal)((PetscInt)2 << l)) l++; /* h0 2^(l+1) |w| <= delta umax */
    a->vlev[c] = (uint8_t)l;
  }
  if (PetscDefined(USE_INFO)) {
    float    wmax = 0;
    PetscInt fine = 0;
    for (PetscInt c = 0; c < ntot; c++) {
      wmax = PetscMax(wmax, w[c]);
      fine += a->vlev[c] < a->levels - 1;
    }
    PetscCall(PetscInfo(NULL,
                        "adapt: vorticity up to %g 1/s, max |u| %g; %" PetscInt_FMT " of %" PetscInt_FMT
                        " lattice cells ask for a finer level than %" PetscInt_FMT "\n",
                        (double)wmax, (double)umax, fine, ntot, a->levels - 1));
  }
  PetscCall(PetscLogEventEnd(PFF_FlowAdaptDist, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Step 5: the distance to the thresholded interface in finest cells, a->dist. */
static PetscErrorCode Distance(PffFlow f)
{
  PffFlowAdaptCtx *a    = &f->adapt;
  const PetscInt   ntot = a->C[0] * a->C[1] * a->C[2];
  float           *phi = a->work, *d = a->dist;
  const float      big = 1e30f;

  PetscFunctionBeginUser;
  PetscCall(PetscLogEventBegin(PFF_FlowAdaptDist, 0, 0, 0, 0));
  PetscCall(LatticeValues(f, f->chPhi, PETSC_FALSE, -1, phi)); /* -1: no fluid */
  for (PetscInt k = 0, c = 0; k < a->C[2]; k++)
    for (PetscInt j = 0; j < a->C[1]; j++)
      for (PetscInt i = 0; i < a->C[0]; i++, c++) {
        const PetscInt cc[3] = {i, j, k};
        d[c]                 = big;
        if (phi[c] < 0) continue;
        for (PetscInt f6 = 0; f6 < 6; f6++) {
          PetscInt o[3]    = {0, 0, 0};
          o[f6 / 2]        = f6 % 2 ? 1 : -1;
          const PetscInt q = PffRasterNeighbour(a->C, a->periodic, cc, o);
          if (q >= 0 && phi[q] >= 0 && (phi[q] >= 0.5f) != (phi[c] >= 0.5f)) d[c] = 0.5f;
        }
      }
  /* chamfer sweeps: forward over the 13 neighbours before a cell in raster order, backward over the 13
     after it; twice, so that distances also come around periodic axes. Cells off the lattice's faces read
     their neighbours at fixed offsets; the others go through PffRasterNeighbour (walls, periodic wrap). */
  PetscInt off[27], dir[27][3];
  float    wt[27];
  for (PetscInt r = 0; r < 27; r++) {
    PetscInt *o = dir[r];
    PffRegionDirection(r, o);
    const PetscInt n1 = (o[0] != 0) + (o[1] != 0) + (o[2] != 0);
    off[r]            = o[0] + a->C[0] * (o[1] + a->C[1] * o[2]);
    wt[r]             = n1 == 1 ? 1.0f : (n1 == 2 ? 1.41421356f : 1.73205081f);
  }
  for (int pass = 0; pass < 4; pass++) {
    const PetscBool fwd = (PetscBool)(pass % 2 == 0);
    const PetscInt  r0 = fwd ? 0 : 14, r1 = fwd ? 13 : 27;
    for (PetscInt s = 0; s < ntot; s++) {
      const PetscInt c      = fwd ? s : ntot - 1 - s,
                     cc[3]  = {c % a->C[0], (c / a->C[0]) % a->C[1], c / (a->C[0] * a->C[1])};
      const PetscBool inner = (PetscBool)(cc[0] > 0 && cc[0] < a->C[0] - 1 && cc[1] > 0 && cc[1] < a->C[1] - 1 &&
                                          cc[2] > 0 && cc[2] < a->C[2] - 1);
      float           best  = d[c];
      if (inner)
        for (PetscInt r = r0; r < r1; r++) best = PetscMin(best, d[c + off[r]] + wt[r]);
      else
        for (PetscInt r = r0; r < r1; r++) {
          const PetscInt q = PffRasterNeighbour(a->C, a->periodic, cc, dir[r]);
          if (q >= 0) best = PetscMin(best, d[q] + wt[r]);
        }
      d[c] = best;
    }
  }
  for (PetscInt c = 0; c < ntot; c++) d[c] *= (float)a->s;
  LevelLattice(a);
  PetscCall(PetscLogEventEnd(PFF_FlowAdaptDist, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Steps 6 and 1 over the binned particles: the level each particle asks for, l = min(L - 1,
   floor(beta d / n0)), into a->target; with counters, the deferred-coarsening counters advance and a
   particle whose coarsening is pending asks for its own level instead (PffParticleWordCountWish), so a
   block coarsens only after its particles asked for it -adapt_coarsen_delay times in a row. Then per
   block the finest level asked by the particles whose box x_p +- (2^l + margin) touches it, merged over
   ranks into map; blocks no particle touches take L - 1, blocks inactive at set-up stay inactive. Without
   that hold a block flickered whenever a small drop or bubble came and went in the thresholded coarse
   phase field: in rt3d at W = 64, 48-52 blocks refined and coarsened again every few steps from
   t/t0 = 2.6, and each time 1.5 M of 7.4 M particles were split and removed again. The boxes are the particles' own: a
   block's bounding box of its particles per level (the first version) also marked the edge and corner neighbours that
   two particles reached on two faces, which refined blocks no particle was near and made them flicker from one step to
   the next as the particles moved (every flicker splits all of a block's particles, and their children coarsen again a
   few steps later). */
static PetscErrorCode TargetsAndMap(PffFlow f, PetscBool counters, PetscInt map[])
{
  PffFlowAdaptCtx  *a = &f->adapt;
  PffParticleArrays pa;
  PetscInt          nlocal, nb[3], nblocks, *reach, *both;
  const PetscInt    lmax = a->levels - 1, none = PETSC_MAX_INT, *cur;
  PetscBool         ok = PETSC_TRUE;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetRaster(f->grid, nb, &cur, NULL));
  nblocks = nb[0] * nb[1] * nb[2];
  PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
  PetscCall(PffParticlesGetArrays(f->part, &pa));
  PetscCheck(pa.start, PETSC_COMM_SELF, PETSC_ERR_ORDER, "adapt: the particles must be binned");
  if ((size_t)pa.n + 1 > a->ntarget) {
    PetscCall(PetscFree(a->target));
    a->ntarget = (size_t)pa.n + (size_t)pa.n / 4 + 1;
    PetscCall(PetscMalloc1(a->ntarget, &a->target));
  }
  PetscCall(PetscMalloc1(54 * (size_t)PetscMax(nlocal, 1), &reach));
  const float           n0f    = (float)a->n0;
  int8_t *const         target = a->target;
  const PffFlowAdaptCtx ac     = *a;
  const PetscBool       more   = (PetscBool)(ac.vlev || ac.nbox + ac.nsphere > 0); /* regions or vorticity */
  /* one pass per block over its bin: the levels asked, the counters and the regions the particles' boxes reach,
     each particle read once (three passes over the store before, a quarter of the adaptation's time) */
#pragma omp parallel for schedule(dynamic, 1) reduction(&& : ok)
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    PetscInt    *r = reach + 54 * lb; /* [27] the levels asked, [27] the levels held */
    for (int q = 0; q < 54; q++) r[q] = none;
    if (PffGridGetBlockInfo(f->grid, lb, &info)) {
      ok = PETSC_FALSE;
      continue;
    }
    const float lo[3] = {(float)info.ijk[0] * n0f, (float)info.ijk[1] * n0f, (float)info.ijk[2] * n0f};
    /* each particle's box x_p +- (2^l + margin) reaches the neighbour regions of a 6-bit code (below and above
       the block along each axis); the loop only marks which (held, level, code) occur, a store without a
       dependence from one particle to the next, and the few marked codes are spread into the regions after it
       (most particles reach none but their own block) */
    const float *const x = pa.x;
    uint32_t *const    w = pa.word;
    float              rp[PFF_GRID_MAX_LEVELS];
    uint8_t            seen[2 * PFF_GRID_MAX_LEVELS * 64]; /* [held][level][code] */
    memset(seen, 0, sizeof(seen));
    for (PetscInt l = 0; l <= lmax; l++) rp[l] = (float)((PetscInt)1 << l) + (float)a->margin;
    /* in chunks: the dual cells of a chunk in a loop that vectorises, then their levels (the distance
       interpolated only where a dual cell spans levels) */
    for (PetscInt c0 = pa.start[lb]; c0 < pa.start[lb + 1]; c0 += PFF_ADAPT_CHUNK) {
      const PetscInt m = PetscMin(PFF_ADAPT_CHUNK, pa.start[lb + 1] - c0);
      int32_t        dual[PFF_ADAPT_CHUNK];
      for (PetscInt j = 0; j < m; j++) dual[j] = DualCellOf(&ac, &x[3 * (c0 + j)]);
      for (PetscInt j = 0; j < m; j++) {
        const float *g = &x[3 * (c0 + j)];
        PetscInt     l = LevelAt(&ac, dual[j], g);
        if (more) l = Ask(&ac, g, l);
        /* a particle whose coarsening is pending holds the grid at its level (the blocks' hysteresis) */
        if (counters) l = PffParticleWordCountWish(&w[c0 + j], l, lmax, ac.delay);
        target[c0 + j] = (int8_t)l;
      }
      int32_t key[PFF_ADAPT_CHUNK]; /* the codes in a loop that vectorises, then marked */
      for (PetscInt j = 0; j < m; j++) {
        const PetscInt i = c0 + j, l = target[i];
        const int      held = counters && PffParticleWordPending(w[i], ac.delay);
        const float    ux = x[3 * i] - lo[0], uy = x[3 * i + 1] - lo[1], uz = x[3 * i + 2] - lo[2], rl = rp[l];
        const int      code = (ux - rl < 0) | (ux + rl >= n0f) << 1 | (uy - rl < 0) << 2 | (uy + rl >= n0f) << 3 |
                         (uz - rl < 0) << 4 | (uz + rl >= n0f) << 5;
        key[j] = (int32_t)((held * PFF_GRID_MAX_LEVELS + l) * 64 + code);
      }
      for (PetscInt j = 0; j < m; j++) seen[key[j]] = 1;
    }
    for (int held = 0; held < 2; held++)
      for (PetscInt l = 0; l <= lmax; l++)
        for (int code = 0; code < 64; code++) {
          if (!seen[(held * PFF_GRID_MAX_LEVELS + l) * 64 + code]) continue;
          PetscInt *rr = r + 27 * held, rlo[3], rhi[3];
          for (int d = 0; d < 3; d++) {
            rlo[d] = (code >> (2 * d)) & 1 ? 0 : 1;
            rhi[d] = (code >> (2 * d + 1)) & 1 ? 2 : 1;
          }
          for (PetscInt z = rlo[2]; z <= rhi[2]; z++)
            for (PetscInt y = rlo[1]; y <= rhi[1]; y++)
              for (PetscInt q = rlo[0]; q <= rhi[0]; q++)
                rr[q + 3 * (y + 3 * z)] = PetscMin(rr[q + 3 * (y + 3 * z)], l);
        }
  }
  PetscCheck(ok, PETSC_COMM_SELF, PETSC_ERR_PLIB, "adapt: bad local block");
  PetscCall(PetscMalloc1(2 * nblocks, &both)); /* the map asked, then the map held */
  for (PetscInt b = 0; b < 2 * nblocks; b++) both[b] = none;
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(f->grid, lb, &info));
    for (PetscInt q = 0; q < 54; q++) {
      PetscInt o[3];
      if (reach[54 * lb + q] == none) continue;
      PffRegionDirection(q % 27, o);
      const PetscInt nbr = PffRasterNeighbour(nb, a->periodic, info.ijk, o);
      if (nbr >= 0) both[nbr + (q / 27) * nblocks] = PetscMin(both[nbr + (q / 27) * nblocks], reach[54 * lb + q]);
    }
  }
  PetscCall(PetscFree(reach));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, both, (PetscMPIInt)(2 * nblocks), MPIU_INT, MPI_MIN, f->comm));
  /* a hold keeps a block from coarsening but never refines it: a pending particle reaching into a coarser
     neighbour (or a whole grid of them, one block further each step) must not spread the fine region */
  for (PetscInt b = 0; b < nblocks; b++)
    map[b] = a->base[b] < 0 ? -1 : PetscMin(PetscMin(both[b], PetscMax(both[nblocks + b], cur[b])), lmax);
  PetscCall(PetscFree(both));
  /* a user region forces its level on every block it overlaps, whatever the particles asked (grading may still
     refine a block forced coarse beside a finer one) */
  if (a->nbox + a->nsphere > 0)
    for (PetscInt b = 0; b < nblocks; b++) {
      PetscInt ijk[3];
      PffRasterCoordinates(nb, b, ijk);
      const PetscInt l = a->base[b] < 0 ? -1 : BlockRegionLevel(a, ijk);
      if (l >= 0) map[b] = l;
    }
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscBool SameMap(const PffFlowAdaptCtx *a, PetscInt nblocks, const PetscInt map[])
{
  for (PetscInt b = 0; b < nblocks; b++)
    if (map[b] != a->request[b]) return PETSC_FALSE;
  return PETSC_TRUE;
}

/* The grid follows map unless it is the last map it followed. */
static PetscErrorCode AdaptGrid(PffFlow f, const PetscInt map[], PffFlowAdaptStats *st)
{
  PffFlowAdaptCtx *a = &f->adapt;
  PetscInt         nb[3];

  PetscFunctionBeginUser;
  PetscCall(PffGridGetRaster(f->grid, nb, NULL, NULL));
  if (SameMap(a, nb[0] * nb[1] * nb[2], map)) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PffGridAdapt(f->grid, map));
  PetscCall(PetscArraycpy(a->request, map, nb[0] * nb[1] * nb[2]));
  if (st) {
    st->adapted = PETSC_TRUE;
    PetscCall(PffGridGetAdaptInfo(f->grid, &st->grid));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowAdaptSetUp_Private(PffFlow f)
{
  PffFlowAdaptCtx *a = &f->adapt;
  const PetscInt  *level;
  PetscInt         nb[3], nlevels;

  PetscFunctionBeginUser;
  if (a->levels == 0) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PffGridGetSizes(f->grid, &a->n0, &nlevels, NULL, NULL, a->periodic));
  PetscCheck(a->levels >= 2 && a->levels <= nlevels, f->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-adapt_levels %" PetscInt_FMT " is invalid: must be 0 (off) or in [2, -grid_levels = %" PetscInt_FMT "]",
             a->levels, nlevels);
  PetscCall(PffGridGetRaster(f->grid, nb, &level, NULL));
  a->lscale = (float)(a->band / (PetscReal)a->n0);
  a->s      = (PetscInt)1 << (a->levels - 1);
  a->is     = 1.0f / (float)a->s;
  a->m      = a->n0 / a->s;
  for (int d = 0; d < 3; d++) a->C[d] = nb[d] * a->m;
  const PetscInt nblocks = nb[0] * nb[1] * nb[2], ntot = a->C[0] * a->C[1] * a->C[2];
  PetscCall(PetscMalloc4(nblocks, &a->base, nblocks, &a->request, ntot, &a->dist, ntot, &a->work));
  PetscCall(PetscMalloc1((a->C[0] + 1) * (a->C[1] + 1) * (a->C[2] + 1), &a->lev));
  PetscCall(PetscMalloc1(nblocks, &a->pwork));
  for (PetscInt b = 0; b < nblocks; b++) {
    a->base[b]    = level[b] < 0 ? -1 : 0;
    a->request[b] = level[b];
  }
  if (a->vort > 0) PetscCall(PetscMalloc1(ntot, &a->vlev));
  {
    PetscReal origin[3], h0;
    PetscCall(PffGridGetSizes(f->grid, NULL, NULL, origin, &h0, NULL));
    for (PetscInt r = 0; r < a->nbox; r++)
      for (int q = 0; q < 6; q++) a->box[6 * r + q] = (a->box[6 * r + q] - origin[q % 3]) / h0;
    for (PetscInt r = 0; r < a->nsphere; r++) {
      for (int q = 0; q < 3; q++) a->sphere[4 * r + q] = (a->sphere[4 * r + q] - origin[q]) / h0;
      a->sphere[4 * r + 3] /= h0;
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -adapt_region_box x0,y0,z0,x1,y1,z1[,...] with -adapt_region_box_level l[,...], and -adapt_region_sphere
   cx,cy,cz,r[,...] with -adapt_region_sphere_level (domain coordinates); read inside PffFlowSetFromOptions. */
PetscErrorCode PffFlowAdaptRegionOptions_Private(PffFlow f, PetscOptionItems *PetscOptionsObject)
{
  PffFlowAdaptCtx *a  = &f->adapt;
  const PetscInt   mx = PFF_FLOW_ADAPT_MAX_REGIONS;
  PetscInt         nb = 6 * mx, nbl = mx, ns = 4 * mx, nsl = mx;
  PetscBool        setb = PETSC_FALSE, setbl = PETSC_FALSE, sets = PETSC_FALSE, setsl = PETSC_FALSE;

  PetscFunctionBeginUser;
  PetscCall(PffOptionsRealArray("-adapt_region_box", "Boxes that force a grid level: x0,y0,z0,x1,y1,z1 per box",
                                "PffFlowSetFromOptions", a->box, &nb, &setb));
  PetscCall(PffOptionsIntArray("-adapt_region_box_level", "The level each -adapt_region_box forces (0: finest)",
                               "PffFlowSetFromOptions", a->boxLevel, &nbl, &setbl));
  PetscCall(PffOptionsRealArray("-adapt_region_sphere", "Spheres that force a grid level: cx,cy,cz,r per sphere",
                                "PffFlowSetFromOptions", a->sphere, &ns, &sets));
  PetscCall(PffOptionsIntArray("-adapt_region_sphere_level", "The level each -adapt_region_sphere forces (0: finest)",
                               "PffFlowSetFromOptions", a->sphereLevel, &nsl, &setsl));
  if (!setb) nb = 0;
  if (!setbl) nbl = 0;
  if (!sets) ns = 0;
  if (!setsl) nsl = 0;
  PetscCheck(nb % 6 == 0, f->comm, PETSC_ERR_ARG_SIZ,
             "-adapt_region_box is invalid: takes 6 values per box (x0,y0,z0,x1,y1,z1), got %" PetscInt_FMT, nb);
  PetscCheck(ns % 4 == 0, f->comm, PETSC_ERR_ARG_SIZ,
             "-adapt_region_sphere is invalid: takes 4 values per sphere (cx,cy,cz,r), got %" PetscInt_FMT, ns);
  a->nbox    = nb / 6;
  a->nsphere = ns / 4;
  PetscCheck(nbl == a->nbox, f->comm, PETSC_ERR_ARG_SIZ,
             "-adapt_region_box_level is invalid: takes one level per box (%" PetscInt_FMT " boxes, %" PetscInt_FMT
             " levels)",
             a->nbox, nbl);
  PetscCheck(nsl == a->nsphere, f->comm, PETSC_ERR_ARG_SIZ,
             "-adapt_region_sphere_level is invalid: takes one level per sphere (%" PetscInt_FMT
             " spheres, %" PetscInt_FMT " levels)",
             a->nsphere, nsl);
  for (PetscInt r = 0; r < a->nbox; r++) {
    const PetscReal *b = a->box + 6 * r;
    for (int d = 0; d < 6; d++)
      PetscCheck(PetscIsNormalReal(b[d]) || b[d] == 0, f->comm, PETSC_ERR_ARG_OUTOFRANGE,
                 "-adapt_region_box is invalid: box %" PetscInt_FMT " has a value that is not a finite number", r);
    PetscCheck(b[0] < b[3] && b[1] < b[4] && b[2] < b[5], f->comm, PETSC_ERR_ARG_OUTOFRANGE,
               "-adapt_region_box is invalid: box %" PetscInt_FMT " must have x0 < x1, y0 < y1 and z0 < z1", r);
  }
  for (PetscInt r = 0; r < a->nsphere; r++) {
    const PetscReal *c = a->sphere + 4 * r;
    for (int d = 0; d < 3; d++)
      PetscCheck(PetscIsNormalReal(c[d]) || c[d] == 0, f->comm, PETSC_ERR_ARG_OUTOFRANGE,
                 "-adapt_region_sphere is invalid: sphere %" PetscInt_FMT " has a centre that is not finite", r);
    PetscCheck(c[3] > 0 && PetscIsNormalReal(c[3]), f->comm, PETSC_ERR_ARG_OUTOFRANGE,
               "-adapt_region_sphere is invalid: sphere %" PetscInt_FMT " must have a positive radius", r);
  }
  if (a->levels > 0) {
    for (PetscInt r = 0; r < a->nbox; r++)
      PetscCheck(a->boxLevel[r] >= 0 && a->boxLevel[r] < a->levels, f->comm, PETSC_ERR_ARG_OUTOFRANGE,
                 "-adapt_region_box_level %" PetscInt_FMT
                 " is invalid: must be in [0, -adapt_levels - 1 = %" PetscInt_FMT "]",
                 a->boxLevel[r], a->levels - 1);
    for (PetscInt r = 0; r < a->nsphere; r++)
      PetscCheck(a->sphereLevel[r] >= 0 && a->sphereLevel[r] < a->levels, f->comm, PETSC_ERR_ARG_OUTOFRANGE,
                 "-adapt_region_sphere_level %" PetscInt_FMT
                 " is invalid: must be in [0, -adapt_levels - 1 = %" PetscInt_FMT "]",
                 a->sphereLevel[r], a->levels - 1);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowAdaptDestroy_Private(PffFlow f)
{
  PffFlowAdaptCtx *a = &f->adapt;

  PetscFunctionBeginUser;
  PetscCall(PetscFree4(a->base, a->request, a->dist, a->work));
  PetscCall(PetscFree(a->target));
  PetscCall(PetscFree(a->lev));
  PetscCall(PetscFree(a->pwork));
  PetscCall(PetscFree(a->vlev));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The graded map of the particles' targets, and each target capped by the level its block will have: a
   particle never stays coarser than its block (P2G splats with the block's radius, which would leave a
   coarse particle's mass in too few faces), and a coarsening never outruns the grid, which would split
   the particle again at the next adaptation. */
static PetscErrorCode GradedTargets(PffFlow f, PetscBool counters, PetscInt map[])
{
  PffFlowAdaptCtx  *a = &f->adapt;
  PffParticleArrays pa;
  PetscInt          nlocal, nb[3];

  PetscFunctionBeginUser;
  PetscCall(PetscLogEventBegin(PFF_FlowAdaptMap, 0, 0, 0, 0));
  PetscCall(TargetsAndMap(f, counters, map));
  PetscCall(PffGridGetRaster(f->grid, nb, NULL, NULL));
  PetscCall(PffGradeLevels(nb, a->periodic, map));
  PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
  PetscCall(PffParticlesGetArrays(f->part, &pa));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(f->grid, lb, &info));
    const int8_t cap = (int8_t)map[info.gid];
    for (PetscInt i = pa.start[lb]; i < pa.start[lb + 1]; i++) a->target[i] = PetscMin(a->target[i], cap);
  }
  PetscCall(PetscLogEventEnd(PFF_FlowAdaptMap, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Partition weights: each block's particles in cell-equivalents (-adapt_particle_weight), summed over
   ranks into the replicated raster (PffGridSetBlockWork). */
static PetscErrorCode BlockWork(PffFlow f)
{
  PffFlowAdaptCtx  *a = &f->adapt;
  PffParticleArrays pa;
  PetscInt          nlocal, nb[3];

  PetscFunctionBeginUser;
  PetscCall(PffGridGetRaster(f->grid, nb, NULL, NULL));
  const PetscInt nblocks = nb[0] * nb[1] * nb[2];
  PetscCall(PetscArrayzero(a->pwork, nblocks));
  PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
  PetscCall(PffParticlesGetArrays(f->part, &pa));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(f->grid, lb, &info));
    a->pwork[info.gid] = pa.start[lb + 1] - pa.start[lb];
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, a->pwork, (PetscMPIInt)nblocks, MPIU_INT64, MPI_SUM, f->comm));
  for (PetscInt b = 0; b < nblocks; b++) a->pwork[b] = (PetscInt64)(a->pweight * (PetscReal)a->pwork[b] + 0.5);
  PetscCall(PffGridSetBlockWork(f->grid, a->pwork));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowAdaptSetMap(PffFlow f, const PetscInt level[])
{
  PetscFunctionBeginUser;
  if (f->model == PFF_FLOW_LIQUID) { /* the quadtree's map: the grid follows it (particles come later) */
    PetscCall(PffGridAdapt(f->grid, level));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PetscCheck(f->adapt.levels > 0, f->comm, PETSC_ERR_ARG_WRONGSTATE, "PffFlowAdaptSetMap needs -adapt_levels");
  PetscCall(AdaptGrid(f, level, NULL));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowAdapt_Private(PffFlow f, PffFlowAdaptStats *st)
{
  PffFlowAdaptCtx *a = &f->adapt;
  PetscInt        *map, nb[3];

  PetscFunctionBeginUser;
  PetscCall(PffFlowCheckTopology_Private(f));
  PetscCall(PffGridGetRaster(f->grid, nb, NULL, NULL));
  PetscCall(PetscMalloc1(nb[0] * nb[1] * nb[2], &map));
  PetscCall(Distance(f));
  PetscCall(VorticityLevels(f, f->chU));
  PetscCall(GradedTargets(f, PETSC_TRUE, map));
  PetscCall(PffParticlesAdaptLevels(f->part, a->target, a->delay, (uint64_t)f->step + 1, &st->particles));
  /* the new map is partitioned with this step's particle counts; an unchanged one is re-partitioned only
     when the work has become unbalanced */
  {
    PffPartitionQuality q;
    PetscCall(BlockWork(f));
    PetscCall(PffGridGetPartitionQuality(f->grid, &q));
    st->imbalanceBefore = q.imbalance;
    PetscCall(AdaptGrid(f, map, st));
    if (!st->adapted && q.imbalance > a->imbalance) {
      PetscCall(PffGridAdapt(f->grid, NULL));
      PetscCall(PffGridGetAdaptInfo(f->grid, &st->grid));
      st->repartitioned = PETSC_TRUE;
    }
    PetscCall(PffGridGetPartitionQuality(f->grid, &q));
    st->imbalance = q.imbalance;
  }
  PetscCall(PetscFree(map));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowAdaptSeed_Private(PffFlow f, PffSeedFn fn, void *ctx)
{
  PffFlowAdaptCtx *a = &f->adapt;
  PetscInt        *map, nb[3], it;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetRaster(f->grid, nb, NULL, NULL));
  PetscCall(PetscMalloc1(nb[0] * nb[1] * nb[2], &map));
  /* the last round keeps its particles even if their map differs: the first step adapts to it */
  for (it = 0;; it++) {
    PetscCall(PffParticlesSeed(f->part, fn, ctx));
    PetscCall(PffFlowUpdateFields(f, PETSC_FALSE));
    PetscCall(Distance(f));
    PetscCall(VorticityLevels(f, f->chUt));
    PetscCall(GradedTargets(f, PETSC_FALSE, map)); /* a fresh seed has nothing pending */
    if (it == a->levels || SameMap(a, nb[0] * nb[1] * nb[2], map)) break;
    PetscCall(PffParticlesClear(f->part));
    PetscCall(AdaptGrid(f, map, NULL));
  }
  PetscCall(PetscFree(map));
  PetscCall(PetscInfo(NULL, "adapt: the seed settled after %" PetscInt_FMT " grid adaptations\n", it));
  PetscFunctionReturn(PETSC_SUCCESS);
}
