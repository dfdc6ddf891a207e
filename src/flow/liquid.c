/* The liquid model (-flow_model liquid): a free-surface liquid on quadtree tall cells (docs/tallcell.md).

   The step is PF-FLIP's without air: P2G of the liquid particles gives the phase field phi (Eq. 7) and u*;
   the level set the tall cells need is psi = (1/2 - phi) 2 s (negative in the liquid, zero where phi = 1/2,
   about a signed distance across the interface layer of two cells); PffTall projects u* with p = 0 in the air;
   G2P and the advection read the liquid velocity and its change extrapolated into the air (Sec. 3.7), since
   the air faces carry no projected velocity. */
#include "flowimpl.h"

/* psi = (1/2 - phi) 2 s, except
   - in holes: a cell below phi = 1/2 with at least 5 of its 6 face neighbours above it is liquid (psi = -s / 4).
     Such one-cell voids open inside the liquid where the particles spread (inside a tall cell the velocity is
     divergence-free only on average); read as air they would be free surfaces with p = 0 deep in the liquid,
     and the pressure would pull the neighbouring faces into them at metres per second;
   - in cells whose centre lies inside a solid: the particles never go there, so psi is extrapolated, the mean
     of the face neighbours' outside the solid (after Batty et al. 2007); read from the particles, a cell cut by
     a solid wall would be air, a free surface with p = 0 at the wall. */
/* -flow_liquid_surface_volume: the cell's liquid fraction from the particles' trilinear volume (P2G's volume over
   the lattice's, per face, the mean over the axes of each axis' open faces) into chF. Trilinear weights are
   separable and a partition of unity, so a flat pool's fraction is the same beside a wall as inside, and a face
   on the particles' surface reads 1/2; Eq. 7's kernel is radial (a wall cuts it differently at the surface) and its
   square root puts phi = 1/2 where a cell is a quarter full. */
static PetscErrorCode PffFlowVolumeFraction(PffFlow f, PetscInt chF)
{
  PetscInt nlocal;

  PetscFunctionBeginUser;
  PetscCall(PffGridHaloBegin(f->grid, f->chVol));
  PetscCall(PffGridHaloEnd(f->grid, f->chVol));
  PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo   info;
    const PffView *vv[3], *vr[3], *vo[3];
    float         *out;
    PetscCall(PffGridGetBlockInfo(f->grid, lb, &info));
    PetscCall(PffGridGetBlockData(f->grid, chF, lb, 0, &out));
    for (PetscInt a = 0; a < 3; a++) {
      PetscCall(PffGridGetBlockViews(f->grid, f->chVol, lb, a, &vv[a]));
      PetscCall(PffGridGetBlockViews(f->grid, f->chVolRef, lb, a, &vr[a]));
      PetscCall(PffGridGetBlockViews(f->grid, f->chOpen, lb, a, &vo[a]));
    }
    const PetscInt n = info.n;
    for (PetscInt k = 0; k < n; k++)
      for (PetscInt j = 0; j < n; j++)
        for (PetscInt i = 0; i < n; i++) {
          PetscReal axes  = 0;
          PetscInt  naxes = 0;
          for (PetscInt a = 0; a < 3; a++) {
            PetscReal sum = 0;
            PetscInt  cnt = 0;
            for (PetscInt side = 0; side < 2; side++) {
              const PetscInt  ii = i + (a == 0) * side, jj = j + (a == 1) * side, kk = k + (a == 2) * side;
              const PetscReal ref = *PffViewsAt(vr[a], ii, jj, kk, n);
              if (!(*PffViewsAt(vo[a], ii, jj, kk, n) > 0) || !(ref > 0)) continue;
              sum += PetscMin(1.0, (PetscReal)*PffViewsAt(vv[a], ii, jj, kk, n) / ref);
              cnt++;
            }
            if (cnt) {
              axes += sum / (PetscReal)cnt;
              naxes++;
            }
          }
          out[i + n * (j + n * k)] = naxes ? (float)(axes / (PetscReal)naxes) : 0.0f;
        }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffFlowLevelSet(PffFlow f)
{
  const PetscInt d[6][3] = {{-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};
  const PetscInt chF = f->liquidSurfaceVolume ? f->chCdiv : f->chPhi; /* the liquid fraction the surface is at 1/2 of */
  PetscInt       nlocal;

  PetscFunctionBeginUser;
  if (f->liquidSurfaceVolume) PetscCall(PffFlowVolumeFraction(f, chF));
  PetscCall(PffGridHaloBegin(f->grid, chF));
  PetscCall(PffGridHaloEnd(f->grid, chF));
  PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo   info;
    const PffView *v, *vs = NULL;
    float         *phi, *ls, *sd = NULL;
    PetscCall(PffGridGetBlockInfo(f->grid, lb, &info));
    PetscCall(PffGridGetBlockData(f->grid, chF, lb, 0, &phi));
    PetscCall(PffGridGetBlockViews(f->grid, chF, lb, 0, &v));
    PetscCall(PffGridGetBlockData(f->grid, f->chLS, lb, 0, &ls));
    if (f->chSolidD >= 0) {
      PetscCall(PffGridGetBlockData(f->grid, f->chSolidD, lb, 0, &sd));
      PetscCall(PffGridGetBlockViews(f->grid, f->chSolidD, lb, 0, &vs));
    }
    const PetscInt n  = info.n;
    const float    s2 = (float)(2 * info.h);
    for (PetscInt k = 0; k < n; k++)
      for (PetscInt j = 0; j < n; j++)
        for (PetscInt i = 0; i < n; i++) {
          const PetscInt c = i + n * (j + n * k);
          ls[c]            = (0.5f - phi[c]) * s2;
          if (sd && sd[c] < 0) {
            float    sum = 0;
            PetscInt cnt = 0;
            for (PetscInt q = 0; q < 6; q++) {
              const PetscInt ii = i + d[q][0], jj = j + d[q][1], kk = k + d[q][2];
              const PetscInt r = PffRegionIndex(ii, jj, kk, n);
              if (r != 13 && ((info.holes >> r) & 1)) continue; /* a domain wall */
              if (*PffViewsAt(vs, ii, jj, kk, n) < 0) continue;
              sum += (0.5f - *PffViewsAt(v, ii, jj, kk, n)) * s2;
              cnt++;
            }
            if (cnt) ls[c] = sum / (float)cnt;
            continue;
          }
          if (phi[c] >= 0.5f) continue;
          /* a wall counts as liquid: a void against a wall is enclosed too */
          if (PffFlowFaceNeighbours_Private(&info, v, i, j, k, n, 0.5f, PETSC_TRUE) >= 5) ls[c] = -0.125f * s2;
        }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The static solids and the bodies: the smaller distance (ctx is the flow). */
PetscReal PffFlowLiquidSolid_Private(const PetscReal x[3], PetscReal grad[3], void *ctx)
{
  const PffFlow f = (const PffFlow)ctx;
  PetscReal     g[3];
  PetscReal     d = PffBodiesDistance(x, grad, f->bodies);

  if (f->staticSolid) {
    const PetscReal ds = f->staticSolid(x, g, f->staticSolidCtx);
    if (ds < d) {
      d = ds;
      if (grad)
        for (PetscInt a = 0; a < 3; a++) grad[a] = g[a];
    }
  }
  return d;
}

/* What G2P and the advection read at a face the solids cut: the mean over the whole face, A u + (1 - A) u_solid
   for the velocity and A du for its change (the solid's part moves with the solid: v + omega x r of a body
   holding the face's centre, rest otherwise), instead of the liquid part's u alone. The projection leaves a
   nearly closed face's u free to take whatever pressure jump its few open square millimetres see (the flux A u
   is what it balances), and a particle beside a body read those as velocities of metres per second. */
static PetscErrorCode SolidFaceVelocities(PffFlow f, PetscInt chU, PetscInt chDu)
{
  PetscInt nlocal;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(f->grid, lb, &info));
    const PetscInt n = info.n;
    for (PetscInt d = 0; d < 3; d++) {
      float *u, *du, *open;
      PetscCall(PffGridGetBlockData(f->grid, chU, lb, d, &u));
      PetscCall(PffGridGetBlockData(f->grid, chDu, lb, d, &du));
      PetscCall(PffGridGetBlockData(f->grid, f->chOpen, lb, d, &open));
      for (PetscInt k = 0; k < n; k++)
        for (PetscInt j = 0; j < n; j++)
          for (PetscInt i = 0; i < n; i++) {
            const PetscInt  c = i + n * (j + n * k);
            const PetscReal a = PetscMax(0, open[c]);
            PetscReal       x[3], vel[3] = {0, 0, 0};
            if (a >= 1) continue;
            if (f->bodies) {
              PffFacePosition(&info, i, j, k, d, x);
              (void)PffBodiesVelocityAt(f->bodies, x, vel);
            }
            u[c]  = (float)(a * u[c] + (1 - a) * vel[d]);
            du[c] = (float)(a * du[c]);
          }
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowLiquidProject_Private(PffFlow f, PetscReal dt, PffPressureStats *ps)
{
  PffTallStats ts;

  PetscFunctionBeginUser;
  if (f->bodies) { /* Algorithm 1, line 7: w* = w + g dt at the current poses (the fractions are theirs) */
    PffTallBody *tb;
    PetscInt     nb;
    PetscCall(PffBodiesPredict(f->bodies, dt, &nb, &tb));
    PetscCall(PffTallSetBodies(f->tall, nb, tb));
  }
  PetscCall(PffFlowLevelSet(f));
  PetscCall(PffTallBuild(f->tall, f->chLS));
  PetscCall(PffTallProject(f->tall, f->chU, dt, f->rho[PFF_PARTICLE_LIQUID], f->chP, &ts));
  PetscCall(PffTallWriteCellHeight(f->tall, f->chTallH));
  if (f->bodies) {
    /* line 11: the bodies move with the projected w, as the particles will with the projected u (moved with w*
       before the solve, a floating body sank by g dt^2 into the liquid every step, and the particles it pushed out
       of itself piled up under it: 8 % of the pool's volume in 1.5 s); the fractions follow for G2P, the
       advection and the next step */
    PetscCall(PffBodiesAdvance(f->bodies, dt));
    PetscCall(PffFlowOpenFaces_Private(f, PETSC_TRUE));
  }
  ps->its       = ts.its;
  ps->rnorm     = ts.rnorm;
  ps->reason    = ts.reason;
  ps->setupTime = ts.assembleTime;
  ps->solveTime = ts.solveTime;
  PetscCheck(ts.reason > 0, f->comm, PETSC_ERR_NOT_CONVERGED,
             "step %" PetscInt_FMT " (t = %g): the tall-cell pressure solve did not converge (%s, %" PetscInt_FMT
             " iterations, relative residual %.3e); raise -tall_ksp_max_it or loosen -tall_ksp_rtol",
             f->step + 1, (double)f->t, KSPConvergedReasons[ts.reason], ts.its, (double)ts.rnorm);
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowLiquidG2P_Private(PffFlow f, const PetscReal alpha[])
{
  /* the velocity and its change on one set of layers (they share the liquid faces) */
  const PetscInt src[2] = {f->chU, f->chUt}, dst[2] = {f->chUl, f->chDuL}, work[2] = {f->chUlWork, -1};

  PetscFunctionBeginUser;
  PetscCall(PffExtrapolateLiquidVelocities(f->grid, 2, src, f->chPhiF, f->chOpen, f->extrapLayers, f->chUlMask, dst,
                                           work, NULL));
  if (f->solid) {
    PetscCall(SolidFaceVelocities(f, f->chUl, f->chDuL));
    PetscCall(PffGridHaloBegin(f->grid, f->chUl));
    PetscCall(PffGridHaloBegin(f->grid, f->chDuL));
    PetscCall(PffGridHaloEnd(f->grid, f->chUl));
    PetscCall(PffGridHaloEnd(f->grid, f->chDuL));
  }
  PetscCall(PffParticlesG2P(f->part, f->chUl, f->chDuL, alpha));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The block columns within a block of a body's bounding box get the finest level (the paper refines near bodies,
   Fig. 1): J reads cell-centre pressures, so the buoyancy is resolved to the cell size there. */
static PetscErrorCode PffFlowLiquidRefineBodies(PffFlow f, const PetscInt nb[3], PetscInt map[])
{
  PetscInt     n, n0;
  PetscReal    origin[3], h;
  PffTallBody *tb;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetSizes(f->grid, &n0, NULL, origin, &h, NULL));
  PetscCall(PffBodiesGetTall(f->bodies, &n, &tb));
  for (PetscInt i = 0; i < n; i++) {
    const PetscReal blen = (PetscReal)n0 * h;
    const PetscInt  i0   = PetscMax(0, (PetscInt)PetscFloorReal((tb[i].lo[0] - origin[0]) / blen) - 1);
    const PetscInt  i1   = PetscMin(nb[0] - 1, (PetscInt)PetscFloorReal((tb[i].hi[0] - origin[0]) / blen) + 1);
    const PetscInt  k0   = PetscMax(0, (PetscInt)PetscFloorReal((tb[i].lo[2] - origin[2]) / blen) - 1);
    const PetscInt  k1   = PetscMin(nb[2] - 1, (PetscInt)PetscFloorReal((tb[i].hi[2] - origin[2]) / blen) + 1);
    for (PetscInt bk = k0; bk <= k1; bk++)
      for (PetscInt bj = 0; bj < nb[1]; bj++)
        for (PetscInt bi = i0; bi <= i1; bi++) map[bi + nb[0] * (bj + nb[1] * bk)] = 0;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The quadtree at t = 0 (tall cells Sec. 4.1): the sizing function on the scene's initial liquid, sampled from the
   seeding function (liquid fraction of 8 sub-cell points per cell, velocity at the face centres), then the grid
   adapts to it before any particle exists, so that every particle is seeded at its block's level. Nothing when
   the grid or -tall_levels has one level. Collective. */
PetscErrorCode PffFlowLiquidQuadtree_Private(PffFlow f, PffSeedFn fn, void *ctx)
{
  PetscInt        nb[3], nlevels, nlocal, *map, nblocks, changed = 0, hist[PFF_GRID_MAX_LEVELS] = {0};
  const PetscInt *level;

  PetscFunctionBeginUser;
  PetscBool sizing;

  PetscCall(PffGridGetSizes(f->grid, NULL, &nlevels, NULL, NULL, NULL));
  PetscCall(PffTallGetSizing(f->tall, &sizing, NULL));
  if (nlevels < 2 || !sizing) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    float       *phi, *ls, *u[3];
    PetscCall(PffGridGetBlockInfo(f->grid, lb, &info));
    PetscCall(PffGridGetBlockData(f->grid, f->chPhi, lb, 0, &phi));
    PetscCall(PffGridGetBlockData(f->grid, f->chLS, lb, 0, &ls));
    for (PetscInt d = 0; d < 3; d++) PetscCall(PffGridGetBlockData(f->grid, f->chU, lb, d, &u[d]));
    const PetscInt n = info.n;
    for (PetscInt k = 0; k < n; k++)
      for (PetscInt j = 0; j < n; j++)
        for (PetscInt i = 0; i < n; i++) {
          const PetscInt c = i + n * (j + n * k), ijk[3] = {i, j, k};
          PetscInt       liquid = 0, type;
          PetscReal      x[3], v[3];
          for (PetscInt q = 0; q < 8; q++) {
            for (PetscInt a = 0; a < 3; a++)
              x[a] = info.lo[a] + ((PetscReal)ijk[a] + 0.25 + 0.5 * ((q >> a) & 1)) * info.h;
            PetscCall(fn(x, &type, v, ctx));
            liquid += type == PFF_PARTICLE_LIQUID;
          }
          phi[c] = (float)liquid / 8.0f;
          ls[c]  = (0.5f - phi[c]) * (float)(2 * info.h);
          for (PetscInt d = 0; d < 3; d++) {
            for (PetscInt a = 0; a < 3; a++) x[a] = info.lo[a] + ((PetscReal)ijk[a] + (a == d ? 0.0 : 0.5)) * info.h;
            PetscCall(fn(x, &type, v, ctx));
            u[d][c] = type == PFF_PARTICLE_LIQUID ? (float)v[d] : 0.0f;
          }
        }
  }
  PetscCall(PffGridGetRaster(f->grid, nb, &level, NULL));
  nblocks = nb[0] * nb[1] * nb[2];
  PetscCall(PetscMalloc1(nblocks, &map));
  PetscCall(PffTallSizingLevels(f->tall, f->chLS, f->chU, map));
  if (f->bodies) PetscCall(PffFlowLiquidRefineBodies(f, nb, map));
  for (PetscInt b = 0; b < nblocks; b++) changed += map[b] != level[b];
  if (changed) PetscCall(PffGridAdapt(f->grid, map));
  PetscCall(PffGridGetRaster(f->grid, NULL, &level, NULL));
  for (PetscInt c = 0; c < nb[0] * nb[2]; c++) hist[level[c % nb[0] + nb[0] * nb[1] * (c / nb[0])]]++;
  PetscCall(PetscPrintf(f->comm, "tall cells: quadtree from the sizing function, block columns per level:"));
  for (PetscInt l = 0; l < nlevels; l++) PetscCall(PetscPrintf(f->comm, " %" PetscInt_FMT, hist[l]));
  PetscCall(PetscPrintf(f->comm, " (of %" PetscInt_FMT ")\n", nb[0] * nb[2]));
  PetscCall(PetscFree(map));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The level set the sizing function reads during the run: the mean of psi over each cell's 27 neighbours. psi
   comes from the particles (PffFlowLevelSet), and its curvature at the scale of a cell is the particles' noise
   (a still pool's surface turns by more than the sizing's 0.3 rad per cell); the mean keeps the surface where
   it is and the curvature of its shape. At t = 0 the sizing reads the scene's exact shape instead. */
static PetscErrorCode SmoothLevelSet(PffFlow f)
{
  PetscInt nlocal;

  PetscFunctionBeginUser;
  PetscCall(PffGridHaloBegin(f->grid, f->chLS));
  PetscCall(PffGridHaloEnd(f->grid, f->chLS));
  PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo   info;
    const PffView *v;
    float         *out;
    PetscCall(PffGridGetBlockInfo(f->grid, lb, &info));
    PetscCall(PffGridGetBlockViews(f->grid, f->chLS, lb, 0, &v));
    PetscCall(PffGridGetBlockData(f->grid, f->chLSs, lb, 0, &out));
    const PetscInt n = info.n;
    for (PetscInt k = 0; k < n; k++)
      for (PetscInt j = 0; j < n; j++)
        for (PetscInt i = 0; i < n; i++) {
          float    sum = 0;
          PetscInt cnt = 0;
          for (PetscInt dk = -1; dk <= 1; dk++)
            for (PetscInt dj = -1; dj <= 1; dj++)
              for (PetscInt di = -1; di <= 1; di++) {
                const PetscInt r = PffRegionIndex(i + di, j + dj, k + dk, n);
                if (r != 13 && ((info.holes >> r) & 1)) continue; /* beyond a wall */
                sum += *PffViewsAt(v, i + di, j + dj, k + dk, n);
                cnt++;
              }
          out[i + n * (j + n * k)] = sum / (float)cnt;
        }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Algorithm 1, lines 2-5: the quadtree from the sizing function on the previous step's cells (its level set and
   velocity), with the block columns at bodies at the finest level. When it changes, every particle takes its
   block's new level (split into 8 children, or coarsened probabilistically with the survivors taking the
   removed volume: PF-FLIP Sec. 5.1's operations, the same on any rank count), then the grid adapts (grading,
   re-partition by columns, channels moved). Collective. */
PetscErrorCode PffFlowLiquidQuadtreeStep_Private(PffFlow f, PffFlowAdaptStats *st)
{
  PetscInt          nb[3], nblocks, changed = 0, nlocal, *map;
  const PetscInt   *level;
  PetscBool         periodic[3];
  PffParticleArrays pa;
  int8_t           *target;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetRaster(f->grid, nb, &level, NULL));
  PetscCall(PffGridGetSizes(f->grid, NULL, NULL, NULL, NULL, periodic));
  nblocks = nb[0] * nb[1] * nb[2];
  PetscCall(PetscMalloc1(nblocks, &map));
  PetscCall(SmoothLevelSet(f));
  PetscCall(PffTallSizingLevels(f->tall, f->chLSs, f->chUl, map));
  if (f->bodies) PetscCall(PffFlowLiquidRefineBodies(f, nb, map));
  PetscCall(PffGradeLevels(nb, periodic, map));
  for (PetscInt b = 0; b < nblocks; b++) changed += map[b] != level[b];
  if (changed) {
    PetscCall(PffParticlesGetArrays(f->part, &pa));
    PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
    PetscCall(PetscMalloc1(PetscMax(1, pa.start[nlocal]), &target));
    for (PetscInt lb = 0; lb < nlocal; lb++) {
      PffBlockInfo info;
      PetscCall(PffGridGetBlockInfo(f->grid, lb, &info));
      for (PetscInt i = pa.start[lb]; i < pa.start[lb + 1]; i++) target[i] = (int8_t)map[info.gid];
    }
    /* no deferral: the particles follow the quadtree at once (the counters reach the delay of 1 now) */
    PetscCall(PffParticlesAdaptCounters(f->part, target, 1));
    PetscCall(PffParticlesAdaptLevels(f->part, target, 1, (uint64_t)f->step + 1, &st->particles));
    PetscCall(PetscFree(target));
    PetscCall(PffGridAdapt(f->grid, map));
    st->adapted = PETSC_TRUE;
    PetscCall(PffGridGetAdaptInfo(f->grid, &st->grid));
  }
  PetscCall(PetscFree(map));
  PetscFunctionReturn(PETSC_SUCCESS);
}
