/* Dynamic dual particle-grid adaptivity (PF-FLIP Sec. 5.4; docs/flow.md, "Adaptivity").

   Once per -adapt_interval steps, before the step's P2G:
   1. an auxiliary distance d to the interface (step 5) on a uniform lattice of the cells of the
      coarsest adaptive level, from the phase field averaged over each of its cells and thresholded at
      1/2; the lattice is small (one cell per (2^(L-1))^3 finest cells) and replicated, so every rank
      computes the same d, from interface cells (a neighbour across the threshold, d = half a cell)
      by a two-pass 26-neighbour chamfer (weights 1, sqrt 2, sqrt 3), first-order as the paper's;
   2. the level each particle asks for (step 6), l = min(L - 1, floor(beta |d(x_p)| / n0)) with d
      interpolated trilinearly; the deferred-coarsening counters D_p advance, and a particle whose
      coarsening is pending (D_p < delay) asks for its current level;
   3. the block map (step 1): the minimum level asked by the particles whose box x_p +- (r + margin)
      touches a block, r = 2^l finest cells for the level l asked; blocks no particle touches take level
      L - 1, blocks inactive at set-up stay inactive; graded 2:1. Each particle's level is then capped by
      its block's, so that particles are never coarser than their block (see GradedTargets);
   4. the split and probabilistic coarsening of PffParticlesAdaptLevels to the capped levels, and
      PffGridAdapt when the map differs from the last one (steps 2-3: grading, re-partition, moving
      channels); particles, pressure and flow follow the topology state on their next call.
   Seeding with adaptivity iterates seed -> phase field -> map until the map holds, so that a run starts
   with fine particles near the interface only, instead of seeding everything fine. */
#include "flowimpl.h"

/* Mean phase field per cell of the distance lattice, -1 outside active blocks; the same on every rank. */
static PetscErrorCode CoarsePhase(PffFlow f, float *phi)
{
  PffFlowAdaptCtx *a = &f->adapt;
  const PetscInt   m = a->m, ntot = a->C[0] * a->C[1] * a->C[2];
  PetscInt         nlocal;

  PetscFunctionBeginUser;
  for (PetscInt c = 0; c < ntot; c++) phi[c] = -1;
  PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    float       *v;
    PetscCall(PffGridGetBlockInfo(f->grid, lb, &info));
    PetscCall(PffGridGetBlockData(f->grid, f->chPhi, lb, 0, &v));
    const PetscInt n = info.n;
    for (PetscInt ck = 0; ck < m; ck++)
      for (PetscInt cj = 0; cj < m; cj++)
        for (PetscInt ci = 0; ci < m; ci++) {
          const PetscInt cc[3] = {ci, cj, ck};
          PetscInt       lo[3], hi[3];
          double         sum = 0;
          /* the block's cells under this lattice cell (one cell when the block is coarser) */
          for (int d = 0; d < 3; d++) {
            lo[d] = n >= m ? cc[d] * (n / m) : cc[d] / (m / n);
            hi[d] = n >= m ? lo[d] + n / m : lo[d] + 1;
          }
          for (PetscInt k = lo[2]; k < hi[2]; k++)
            for (PetscInt j = lo[1]; j < hi[1]; j++)
              for (PetscInt i = lo[0]; i < hi[0]; i++) sum += v[i + n * (j + n * k)];
          const PetscInt g[3] = {info.ijk[0] * m + ci, info.ijk[1] * m + cj, info.ijk[2] * m + ck};
          phi[g[0] + a->C[0] * (g[1] + a->C[1] * g[2])] =
              (float)(sum / (double)((hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2])));
        }
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, phi, (PetscMPIInt)ntot, MPI_FLOAT, MPI_MAX, f->comm));
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
  const float l = (float)(a->band / (PetscReal)a->n0) * d; /* >= 0: the cast floors */
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

/* The level particle position g asks for (step 6). */
static inline PetscInt LevelAt(const PffFlowAdaptCtx *a, const float g[3])
{
  PetscInt b[3];
  for (int d = 0; d < 3; d++) b[d] = (PetscInt)(g[d] * a->is + 0.5f) - 1; /* floor(g / s - 1/2) for g >= 0 */
  const uint8_t l = a->lev[DualIndex(a, b)];
  return l != 0xff ? (PetscInt)l : LevelOf(a, DistanceAt(a, g));
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
  PetscCall(CoarsePhase(f, phi));
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
     after it; twice, so that distances also come around periodic axes */
  for (int pass = 0; pass < 4; pass++) {
    const PetscBool fwd = (PetscBool)(pass % 2 == 0);
    for (PetscInt s = 0; s < ntot; s++) {
      const PetscInt c     = fwd ? s : ntot - 1 - s,
                     cc[3] = {c % a->C[0], (c / a->C[0]) % a->C[1], c / (a->C[0] * a->C[1])};
      float best           = d[c];
      for (PetscInt r = 0; r < 27; r++) {
        if ((r < 13) != fwd || r == 13) continue;
        PetscInt o[3];
        PffRegionDirection(r, o);
        const PetscInt q = PffRasterNeighbour(a->C, a->periodic, cc, o);
        if (q < 0) continue;
        const PetscInt n1 = (o[0] != 0) + (o[1] != 0) + (o[2] != 0);
        const float    w  = n1 == 1 ? 1.0f : (n1 == 2 ? 1.41421356f : 1.73205081f);
        best              = PetscMin(best, d[q] + w);
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
   particle whose coarsening is pending asks for its own level instead (PffParticlesAdaptCounters), so a
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
  const float n0f    = (float)a->n0;
  int8_t     *target = a->target;
  {
    const PffFlowAdaptCtx ac = *a;
    const float *const    x  = pa.x;
#pragma omp parallel for schedule(static)
    for (PetscInt i = 0; i < pa.n; i++) target[i] = (int8_t)LevelAt(&ac, &x[3 * i]);
  }
  /* a particle whose coarsening is pending holds the grid at its level (the blocks' hysteresis) */
  if (counters) PetscCall(PffParticlesAdaptCounters(f->part, target, a->delay));
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
    /* each particle's box x_p +- (2^l + margin) marks the neighbour regions it reaches; most particles
       reach none but their own block (one comparison pair per axis) */
    const float *const x  = pa.x;
    const PetscInt     i0 = pa.start[lb], i1 = pa.start[lb + 1];
    float              rp[PFF_GRID_MAX_LEVELS];
    for (PetscInt l = 0; l <= lmax; l++) rp[l] = (float)((PetscInt)1 << l) + (float)a->margin;
    for (PetscInt i = i0; i < i1; i++) {
      const PetscInt l  = target[i];
      PetscInt      *rr = r + (counters && PffParticleWordPending(pa.word[i], a->delay) ? 27 : 0);
      PetscInt       rlo[3], rhi[3];
      for (int d = 0; d < 3; d++) {
        const float u = x[3 * i + d] - lo[d];
        rlo[d]        = u - rp[l] < 0 ? 0 : 1;
        rhi[d]        = u + rp[l] >= n0f ? 2 : 1;
      }
      for (PetscInt z = rlo[2]; z <= rhi[2]; z++)
        for (PetscInt y = rlo[1]; y <= rhi[1]; y++)
          for (PetscInt q = rlo[0]; q <= rhi[0]; q++) rr[q + 3 * (y + 3 * z)] = PetscMin(rr[q + 3 * (y + 3 * z)], l);
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
  a->s  = (PetscInt)1 << (a->levels - 1);
  a->is = 1.0f / (float)a->s;
  a->m  = a->n0 / a->s;
  for (int d = 0; d < 3; d++) a->C[d] = nb[d] * a->m;
  const PetscInt nblocks = nb[0] * nb[1] * nb[2], ntot = a->C[0] * a->C[1] * a->C[2];
  PetscCall(PetscMalloc4(nblocks, &a->base, nblocks, &a->request, ntot, &a->dist, ntot, &a->work));
  PetscCall(PetscMalloc1((a->C[0] + 1) * (a->C[1] + 1) * (a->C[2] + 1), &a->lev));
  PetscCall(PetscMalloc1(nblocks, &a->pwork));
  for (PetscInt b = 0; b < nblocks; b++) {
    a->base[b]    = level[b] < 0 ? -1 : 0;
    a->request[b] = level[b];
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
    PetscCall(GradedTargets(f, PETSC_FALSE, map)); /* a fresh seed has nothing pending */
    if (it == a->levels || SameMap(a, nb[0] * nb[1] * nb[2], map)) break;
    PetscCall(PffParticlesClear(f->part));
    PetscCall(AdaptGrid(f, map, NULL));
  }
  PetscCall(PetscFree(map));
  PetscCall(PetscInfo(NULL, "adapt: the seed settled after %" PetscInt_FMT " grid adaptations\n", it));
  PetscFunctionReturn(PETSC_SUCCESS);
}
