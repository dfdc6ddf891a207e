/* Dynamic dual particle-grid adaptivity (PF-FLIP Sec. 5.4; docs/flow.md, "Adaptivity").

   Once per -adapt_interval steps, before the step's P2G:
   1. an auxiliary distance d to the interface (step 5) on a uniform lattice of the cells of the
      coarsest adaptive level, from the phase field averaged over each of its cells and thresholded at
      1/2; the lattice is small (one cell per (2^(L-1))^3 finest cells) and replicated, so every rank
      computes the same d, from interface cells (a neighbour across the threshold, d = half a cell)
      by a two-pass 26-neighbour chamfer (weights 1, sqrt 2, sqrt 3), first-order as the paper's;
   2. the level each particle asks for (step 6), l = min(L - 1, floor(beta |d(x_p)| / n0)) with d
      interpolated trilinearly;
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

/* Neighbour of lattice cell (i, j, k) at offset o, wrapped on periodic axes; -1 outside. */
static inline PetscInt LatticeNeighbour(const PffFlowAdaptCtx *a, const PetscInt c[3], const PetscInt o[3])
{
  PetscInt q[3];
  for (int d = 0; d < 3; d++) {
    q[d] = c[d] + o[d];
    if (q[d] < 0 || q[d] >= a->C[d]) {
      if (!a->periodic[d]) return -1;
      q[d] = (q[d] + a->C[d]) % a->C[d];
    }
  }
  return q[0] + a->C[0] * (q[1] + a->C[1] * q[2]);
}

/* Step 5: the distance to the thresholded interface in finest cells, a->dist. */
static PetscErrorCode Distance(PffFlow f)
{
  PffFlowAdaptCtx *a    = &f->adapt;
  const PetscInt   ntot = a->C[0] * a->C[1] * a->C[2];
  float           *phi = a->work, *d = a->dist;
  const float      big = 1e30f;

  PetscFunctionBeginUser;
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
          const PetscInt q = LatticeNeighbour(a, cc, o);
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
        const PetscInt q = LatticeNeighbour(a, cc, o);
        if (q < 0) continue;
        const PetscInt n1 = (o[0] != 0) + (o[1] != 0) + (o[2] != 0);
        const float    w  = n1 == 1 ? 1.0f : (n1 == 2 ? 1.41421356f : 1.73205081f);
        best              = PetscMin(best, d[q] + w);
      }
      d[c] = best;
    }
  }
  for (PetscInt c = 0; c < ntot; c++) d[c] *= (float)a->s;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* d at grid position g (finest cells), trilinear between lattice cell centres, clamped at walls. */
static inline float DistanceAt(const PffFlowAdaptCtx *a, const float g[3])
{
  PetscInt i0[3], i1[3];
  float    t[3];
  for (int d = 0; d < 3; d++) {
    const float u = g[d] / (float)a->s - 0.5f;
    PetscInt    b = (PetscInt)PetscFloorReal(u);
    t[d]          = u - (float)b;
    i0[d]         = b;
    i1[d]         = b + 1;
    if (a->periodic[d]) {
      i0[d] = (i0[d] + a->C[d]) % a->C[d];
      i1[d] = i1[d] % a->C[d];
    } else {
      if (i0[d] < 0) {
        i0[d] = 0;
        t[d]  = 0;
      }
      if (i1[d] > a->C[d] - 1) {
        i1[d] = a->C[d] - 1;
        t[d]  = i0[d] == i1[d] ? 0 : t[d];
      }
    }
  }
  float v = 0;
  for (PetscInt q = 0; q < 8; q++) {
    float    w   = 1;
    PetscInt idx = 0, st = 1;
    for (int d = 0; d < 3; d++) {
      const PetscInt bit = (q >> d) & 1;
      w *= bit ? t[d] : 1 - t[d];
      idx += (bit ? i1[d] : i0[d]) * st;
      st *= a->C[d];
    }
    v += w * a->dist[idx];
  }
  return v;
}

/* Step 6's criterion per local particle. */
static PetscErrorCode Targets(PffFlow f, int8_t **target)
{
  PffFlowAdaptCtx  *a = &f->adapt;
  PffParticleArrays pa;

  PetscFunctionBeginUser;
  PetscCall(PffParticlesGetArrays(f->part, &pa));
  if ((size_t)pa.n + 1 > a->ntarget) {
    PetscCall(PetscFree(a->target));
    a->ntarget = (size_t)pa.n + (size_t)pa.n / 4 + 1;
    PetscCall(PetscMalloc1(a->ntarget, &a->target));
  }
  const float scale = (float)(a->band / (PetscReal)a->n0);
  const int   lmax  = (int)(a->levels - 1);
  int8_t     *t     = a->target;
#pragma omp parallel for schedule(static)
  for (PetscInt i = 0; i < pa.n; i++) {
    const float l = PetscFloorReal(scale * DistanceAt(a, &pa.x[3 * i]));
    t[i]          = (int8_t)(l >= (float)lmax ? lmax : (int)l);
  }
  *target = t;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Step 1: per block the finest level of the particles whose box touches it (their own levels, or
   level[] per particle), merged over ranks; blocks inactive at set-up stay so. */
static PetscErrorCode MapFromParticles(PffFlow f, const int8_t level[], PetscInt map[])
{
  PffFlowAdaptCtx  *a = &f->adapt;
  PffParticleArrays pa;
  PetscInt          nlocal, nb[3], nblocks;
  PetscInt         *reach;
  const PetscInt    lmax = a->levels - 1, none = PETSC_MAX_INT;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetRaster(f->grid, nb, NULL, NULL));
  nblocks = nb[0] * nb[1] * nb[2];
  PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
  PetscCall(PffParticlesGetArrays(f->part, &pa));
  PetscCheck(pa.start, PETSC_COMM_SELF, PETSC_ERR_ORDER, "adapt: the particles must be binned");
  PetscCall(PetscMalloc1(27 * (size_t)PetscMax(nlocal, 1), &reach));
  PetscBool ok = PETSC_TRUE;
#pragma omp parallel for schedule(dynamic, 1) reduction(&& : ok)
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    PetscInt    *r = reach + 27 * lb;
    for (int q = 0; q < 27; q++) r[q] = none;
    if (PffGridGetBlockInfo(f->grid, lb, &info)) {
      ok = PETSC_FALSE;
      continue;
    }
    const float lo[3] = {(float)(info.ijk[0] * a->n0), (float)(info.ijk[1] * a->n0), (float)(info.ijk[2] * a->n0)};
    for (PetscInt i = pa.start[lb]; i < pa.start[lb + 1]; i++) {
      const PetscInt l  = level ? (PetscInt)level[i] : PffParticleWordLevel(pa.word[i]);
      const float    rp = (float)((PetscInt)1 << l) + (float)a->margin;
      PetscInt       rlo[3], rhi[3];
      for (int d = 0; d < 3; d++) {
        const float x = pa.x[3 * i + d] - lo[d];
        rlo[d]        = x - rp < 0 ? 0 : 1;
        rhi[d]        = x + rp >= (float)a->n0 ? 2 : 1;
      }
      for (PetscInt z = rlo[2]; z <= rhi[2]; z++)
        for (PetscInt y = rlo[1]; y <= rhi[1]; y++)
          for (PetscInt x = rlo[0]; x <= rhi[0]; x++) {
            const PetscInt q = x + 3 * (y + 3 * z);
            if (l < r[q]) r[q] = l;
          }
    }
  }
  PetscCheck(ok, PETSC_COMM_SELF, PETSC_ERR_PLIB, "adapt: bad local block");
  for (PetscInt b = 0; b < nblocks; b++) map[b] = none;
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(f->grid, lb, &info));
    for (PetscInt q = 0; q < 27; q++) {
      PetscInt o[3];
      if (reach[27 * lb + q] == none) continue;
      PffRegionDirection(q, o);
      const PetscInt nbr = PffRasterNeighbour(nb, a->periodic, info.ijk, o);
      if (nbr >= 0) map[nbr] = PetscMin(map[nbr], reach[27 * lb + q]);
    }
  }
  PetscCall(PetscFree(reach));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, map, (PetscMPIInt)nblocks, MPIU_INT, MPI_MIN, f->comm));
  for (PetscInt b = 0; b < nblocks; b++) map[b] = a->base[b] < 0 ? -1 : PetscMin(map[b], lmax);
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
  PetscInt         nb[3], nlevels, cells[3];

  PetscFunctionBeginUser;
  if (a->levels == 0) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PffGridGetSizes(f->grid, &a->n0, &nlevels, NULL, NULL, a->periodic));
  PetscCheck(a->levels >= 2 && a->levels <= nlevels, f->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-adapt_levels %" PetscInt_FMT " is invalid: must be 0 (off) or in [2, -grid_levels = %" PetscInt_FMT "]",
             a->levels, nlevels);
  PetscCall(PffGridGetRaster(f->grid, nb, &level, NULL));
  PetscCall(PffGridGetCells(f->grid, cells));
  a->s = (PetscInt)1 << (a->levels - 1);
  a->m = a->n0 / a->s;
  for (int d = 0; d < 3; d++) a->C[d] = nb[d] * a->m;
  const PetscInt nblocks = nb[0] * nb[1] * nb[2], ntot = a->C[0] * a->C[1] * a->C[2];
  PetscCall(PetscMalloc4(nblocks, &a->base, nblocks, &a->request, ntot, &a->dist, ntot, &a->work));
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
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The graded map of the particles' targets, and each target capped by the level its block will have: a
   particle never stays coarser than its block (P2G splats with the block's radius, which would leave a
   coarse particle's mass in too few faces), and a coarsening never outruns the grid, which would split
   the particle again at the next adaptation. */
static PetscErrorCode GradedTargets(PffFlow f, int8_t target[], PetscInt map[])
{
  PffFlowAdaptCtx  *a = &f->adapt;
  PffParticleArrays pa;
  PetscInt          nlocal, nb[3];

  PetscFunctionBeginUser;
  PetscCall(MapFromParticles(f, target, map));
  PetscCall(PffGridGetRaster(f->grid, nb, NULL, NULL));
  PetscCall(PffGradeLevels(nb, a->periodic, map));
  PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
  PetscCall(PffParticlesGetArrays(f->part, &pa));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(f->grid, lb, &info));
    const int8_t cap = (int8_t)map[info.gid];
    for (PetscInt i = pa.start[lb]; i < pa.start[lb + 1]; i++) target[i] = PetscMin(target[i], cap);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowAdapt_Private(PffFlow f, PffFlowAdaptStats *st)
{
  PffFlowAdaptCtx *a = &f->adapt;
  int8_t          *target;
  PetscInt        *map, nb[3];

  PetscFunctionBeginUser;
  PetscCall(PffFlowCheckTopology_Private(f));
  PetscCall(PffGridGetRaster(f->grid, nb, NULL, NULL));
  PetscCall(PetscMalloc1(nb[0] * nb[1] * nb[2], &map));
  PetscCall(Distance(f));
  PetscCall(Targets(f, &target));
  PetscCall(GradedTargets(f, target, map));
  PetscCall(PffParticlesAdaptLevels(f->part, target, a->delay, (uint64_t)f->step + 1, &st->particles));
  PetscCall(AdaptGrid(f, map, st));
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
    int8_t *target;
    PetscCall(PffParticlesSeed(f->part, fn, ctx));
    PetscCall(PffFlowUpdateFields(f, PETSC_FALSE));
    PetscCall(Distance(f));
    PetscCall(Targets(f, &target));
    PetscCall(GradedTargets(f, target, map));
    if (it == a->levels || SameMap(a, nb[0] * nb[1] * nb[2], map)) break;
    PetscCall(PffParticlesClear(f->part));
    PetscCall(AdaptGrid(f, map, NULL));
  }
  PetscCall(PetscFree(map));
  PetscCall(PetscInfo(NULL, "adapt: the seed settled after %" PetscInt_FMT " grid adaptations\n", it));
  PetscFunctionReturn(PETSC_SUCCESS);
}
