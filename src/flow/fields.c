/* Face-velocity fields of the step: u~* = P / m after P2G (Eq. 4), forces, the velocity change
   du = u - u~* for FLIP (Eq. 11), open faces from walls and solids (the liquid model: open area fractions), the FLIP
   ratios per particle type and level (Eq. 13, Sec. 5.3), escaped particles (Sec. 3.4) and vorticity for output. */
#include "flowimpl.h"

/* The liquid model's open fractions and cell distances. After the bodies moved (moved) only the blocks within
   reach of their boxes, at the new poses and at the last fill's, are filled again: the fractions and the clipped
   distances elsewhere are the static solids', the same as a whole fill's (PffTallFillSolid); filling every block
   evaluated every body's distance at every node of the grid each step. */
static PetscErrorCode LiquidOpenFaces(PffFlow f, PetscBool moved)
{
  PetscInt   nb[3], nblocks, nlevels;
  PetscReal  h;
  PetscBool *r = NULL;

  PetscFunctionBeginUser;
  if (f->bodies) {
    PetscCall(PffGridGetRaster(f->grid, nb, NULL, NULL));
    PetscCall(PffGridGetSizes(f->grid, NULL, &nlevels, NULL, &h, NULL));
    nblocks = nb[0] * nb[1] * nb[2];
    if (!f->openBody) PetscCall(PetscCalloc1(nblocks, &f->openBody));
    PetscCall(PetscCalloc1(nblocks, &r));
    /* a distance is clipped at PFF_TALL_SOLID_DISTANCE_MAX cells of its block's level, the coarsest at most */
    PetscCall(PffFlowBodyBlocks_Private(f, (PFF_TALL_SOLID_DISTANCE_MAX + 1) * h * (PetscReal)(1 << (nlevels - 1)), r));
    PffFlowBlocksSince_Private(nblocks, r, f->openBody);
  }
  PetscCall(PffTallFillSolid(f->grid, f->solid, f->solidCtx, f->chOpen, f->chSolidD, moved ? r : NULL));
  PetscCall(PetscFree(r));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowOpenFaces_Private(PffFlow f, PetscBool moved)
{
  PetscInt  nlocal;
  PetscBool periodic[3];

  PetscFunctionBeginUser;
  if (f->chSolidD >= 0) { /* the liquid model's variational pressure takes the open area fractions */
    PetscCall(LiquidOpenFaces(f, moved));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PetscCall(PffGridGetSizes(f->grid, NULL, NULL, NULL, NULL, periodic));
  PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(f->grid, lb, &info));
    const PetscInt n = info.n;
    for (PetscInt d = 0; d < 3; d++) {
      float *open;
      PetscCall(PffGridGetBlockData(f->grid, f->chOpen, lb, d, &open));
      for (PetscInt k = 0; k < n; k++)
        for (PetscInt j = 0; j < n; j++)
          for (PetscInt i = 0; i < n; i++) {
            const PetscInt idx[3] = {i, j, k};
            PetscReal      x[3], g[3];
            PetscBool      isopen = PETSC_TRUE;
            /* the lower domain wall; the upper one is a ghost across the wall, zero by construction */
            if (!periodic[d] && info.ijk[d] == 0 && idx[d] == 0) isopen = PETSC_FALSE;
            if (isopen && f->solid) {
              PffFacePosition(&info, i, j, k, d, x);
              isopen = f->solid(x, g, f->solidCtx) > 0 ? PETSC_TRUE : PETSC_FALSE;
            }
            open[i + n * (j + n * k)] = isopen ? 1.0f : 0.0f;
          }
    }
  }
  PetscCall(PffGridHaloBegin(f->grid, f->chOpen));
  PetscCall(PffGridHaloEnd(f->grid, f->chOpen));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* u~* = P / m into chUt (in place) and u* = u~* + dt g into chU on open faces. */
PetscErrorCode PffFlowFaceVelocity_Private(PffFlow f, PetscReal dt)
{
  const PetscInt ch[4] = {f->chMass, f->chUt, f->chU, f->chOpen};
  PetscInt       nlocal;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
  for (PetscInt lb = 0; lb < nlocal; lb++)
    for (PetscInt d = 0; d < 3; d++) {
      float      *a[4];
      PetscInt    n3 = 0;
      const float gd = (float)(dt * f->gravity[d]);
      PetscCall(PffFlowBlockData_Private(f, lb, d, 4, ch, a, &n3));
      float *m = a[0], *ut = a[1], *u = a[2], *open = a[3];
      /* the liquid model has no air: a face no particle reaches is left at rest (the projection does not see it,
         and the extrapolation of the liquid velocity fills the layers next to the surface) */
      const PetscBool airAtRest = (PetscBool)(f->model == PFF_FLOW_LIQUID);
      for (PetscInt c = 0; c < n3; c++) {
        ut[c] = m[c] > 0 ? ut[c] / m[c] : 0.0f;
        u[c]  = open[c] > 0 && (m[c] > 0 || !airAtRest) ? ut[c] + gd : 0.0f;
      }
    }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* du = u - u~* into chUt (in place). */
PetscErrorCode PffFlowVelocityChange_Private(PffFlow f)
{
  const PetscInt ch[2] = {f->chUt, f->chU};
  PetscInt       nlocal;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
  for (PetscInt lb = 0; lb < nlocal; lb++)
    for (PetscInt d = 0; d < 3; d++) {
      float   *a[2];
      PetscInt n3 = 0;
      PetscCall(PffFlowBlockData_Private(f, lb, d, 2, ch, a, &n3));
      for (PetscInt c = 0; c < n3; c++) a[0][c] = a[1][c] - a[0][c];
    }
  PetscFunctionReturn(PETSC_SUCCESS);
}

typedef struct {
  PffFlow   f;
  PetscReal t;
} PffPrescribeCtx;

static PetscReal PffPrescribedValue(const PetscReal x[3], PetscInt comp, void *ctx)
{
  const PffPrescribeCtx *pc = (const PffPrescribeCtx *)ctx;
  return pc->f->prescribed(x, comp, pc->t, pc->f->prescribedCtx);
}

PetscErrorCode PffFlowPrescribe_Private(PffFlow f, PetscReal t)
{
  PffPrescribeCtx pc = {f, t};

  PetscFunctionBeginUser;
  if (!f->prescribedAmp) {
    PetscCall(PffGridFillChannel(f->grid, f->chU, PffPrescribedValue, &pc));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  {
    PetscObjectState state;
    PetscCall(PffGridGetTopologyState(f->grid, &state));
    if (f->shapeState != state + 1) { /* +1: a grid that never changed has state 0, "never sampled" here */
      pc.t = 0;
      PetscCall(PffGridFillChannel(f->grid, f->chShape, PffPrescribedValue, &pc));
      f->shapeState = state + 1;
    }
  }
  PetscCall(PffGridScaleChannel(f->grid, f->chU, f->prescribedAmp(t, f->prescribedCtx), f->chShape));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Vorticity magnitude at cell centres from central differences of the cell-centred velocity
   (mean of the two faces) of face channel ch, whose halo it exchanges first. Collective. */
PetscErrorCode PffFlowVorticity_Private(PffFlow f, PetscInt ch)
{
  PetscInt nlocal;

  PetscFunctionBeginUser;
  PetscCall(PffGridHaloBegin(f->grid, ch));
  PetscCall(PffGridHaloEnd(f->grid, ch));
  PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo   info;
    const PffView *vu[3];
    float         *w;
    PetscCall(PffGridGetBlockInfo(f->grid, lb, &info));
    PetscCall(PffGridGetBlockData(f->grid, f->chVort, lb, 0, &w));
    for (PetscInt d = 0; d < 3; d++) PetscCall(PffGridGetBlockViews(f->grid, ch, lb, d, &vu[d]));
    const PetscInt  n   = info.n;
    const PetscReal inv = 1.0 / (2 * info.h);
    for (PetscInt k = 0; k < n; k++)
      for (PetscInt j = 0; j < n; j++)
        for (PetscInt i = 0; i < n; i++) {
          PetscReal du[3][3]; /* du[c][a] = d u_c / d x_a */
          for (PetscInt c = 0; c < 3; c++)
            for (PetscInt a = 0; a < 3; a++) {
              const PetscInt e[3] = {c == 0, c == 1, c == 2}, s[3] = {a == 0, a == 1, a == 2};
              if (a == c) {
                du[c][a] = 0;
                continue;
              }
              const PetscReal up = 0.5 * (*PffViewsAt(vu[c], i + s[0], j + s[1], k + s[2], n) +
                                          *PffViewsAt(vu[c], i + s[0] + e[0], j + s[1] + e[1], k + s[2] + e[2], n));
              const PetscReal dn = 0.5 * (*PffViewsAt(vu[c], i - s[0], j - s[1], k - s[2], n) +
                                          *PffViewsAt(vu[c], i - s[0] + e[0], j - s[1] + e[1], k - s[2] + e[2], n));
              du[c][a]           = (up - dn) * inv;
            }
          const PetscReal ox = du[2][1] - du[1][2], oy = du[0][2] - du[2][0], oz = du[1][0] - du[0][1];
          w[i + n * (j + n * k)] = (float)PetscSqrtReal(ox * ox + oy * oy + oz * oz);
        }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* FLIP ratio per type and level (Eq. 13): with a physical viscosity nu, alpha = 1 - 6 nu dt / h_l^2;
   without one, the numerical viscosity of -flow_flip at the finest level is kept equal on every
   level (Sec. 5.3): alpha_l = 1 - (1 - flip) / 4^l. Clamped to [0, 1]. */
PetscErrorCode PffFlowFlipRatios_Private(PffFlow f, PetscReal dt, PetscReal alpha[])
{
  PetscInt  nlevels;
  PetscReal h0;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetSizes(f->grid, NULL, &nlevels, NULL, &h0, NULL));
  for (PetscInt t = 0; t < PFF_PARTICLE_NTYPES; t++)
    for (PetscInt l = 0; l < nlevels; l++) {
      const PetscReal h      = h0 * (PetscReal)((PetscInt)1 << l);
      PetscReal       a      = f->nu[t] > 0 ? 1 - 6 * f->nu[t] * dt / (h * h) : 1 - (1 - f->flip) / (h * h / (h0 * h0));
      alpha[t * nlevels + l] = PetscMax(0, PetscMin(1, a));
    }
  PetscFunctionReturn(PETSC_SUCCESS);
}

typedef struct {
  PffParticleArrays a;
  PetscReal         lo, hi; /* 0.5 -+ deltaPhi */
  PetscBool         del;
  PetscInt64        bubbles, droplets;
} PffEscapedCtx;

/* Classifies particles [i0, i0 + m) by the phase field at them (runs in threads). */
static void PffEscapedClassify(PetscInt i0, PetscInt m, const float phi[], void *ctx)
{
  PffEscapedCtx *e  = (PffEscapedCtx *)ctx;
  PetscInt64     nb = 0, nd = 0;
  for (PetscInt j = 0; j < m; j++) {
    const PetscInt i = i0 + j, type = PffParticleWordType(e->a.word[i]);
    PetscBool      drop = PETSC_FALSE, rm = PETSC_FALSE;
    if (type == PFF_PARTICLE_AIR && phi[j] > e->hi) {
      rm = e->del;
      nb++;
    } else if (type == PFF_PARTICLE_LIQUID && phi[j] < e->lo) {
      drop = PETSC_TRUE;
      nd++;
    }
    e->a.word[i] = PffParticleWordSetFlags(e->a.word[i], PFF_PARTICLE_FLAG_DROPLET, drop);
    e->a.word[i] = PffParticleWordSetFlags(e->a.word[i], PFF_PARTICLE_FLAG_REMOVE, rm);
  }
#pragma omp atomic
  e->bubbles += nb;
#pragma omp atomic
  e->droplets += nd;
}

/* Escaped particles (Sec. 3.4): air deep in liquid is deleted (bubbles), liquid deep in air is
   flagged as a droplet candidate. Reads the cell phase field (ghosts current) through the particles'
   block tiles, in threads, without per-particle scratch. */
PetscErrorCode PffFlowEscaped_Private(PffFlow f, PetscInt64 *bubbles, PetscInt64 *droplets)
{
  PffEscapedCtx e;

  PetscFunctionBeginUser;
  PetscCall(PffParticlesGetArrays(f->part, &e.a));
  e.lo       = 0.5 - f->deltaPhi;
  e.hi       = 0.5 + f->deltaPhi;
  e.del      = f->deleteBubbles;
  e.bubbles  = 0;
  e.droplets = 0;
  PetscCall(PffParticlesInterpolateCell(f->part, f->chPhi, PffEscapedClassify, &e));
  if (f->deleteBubbles && e.bubbles) PetscCall(PffParticlesRemove(f->part));
  PetscInt64 cnt[2] = {e.bubbles, e.droplets};
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, cnt, 2, MPIU_INT64, MPI_SUM, f->comm));
  *bubbles  = cnt[0];
  *droplets = cnt[1];
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowMaxParticleSpeed_Private(PffFlow f, PetscReal *umax)
{
  PffParticleArrays a;
  PetscReal         m[2] = {0, 0}; /* max |v|^2, and 1 where a velocity is not finite (a max drops NaNs) */

  PetscFunctionBeginUser;
  PetscCall(PffParticlesGetArrays(f->part, &a));
  {
    const float *v   = a.v;
    PetscReal    mx  = 0;
    int          bad = 0;
    /* in threads and vectorised (simd: the stride-3 loads with the conversion to double kept it scalar, 7 ms per
       step for 1.75 M particles); s >= 0, so !(s <= max) holds exactly for NaN and +inf, and a max is the same in
       any order */
#pragma omp parallel for simd reduction(max : mx) reduction(| : bad) schedule(static)
    for (PetscInt i = 0; i < a.n; i++) {
      const PetscReal vx = v[3 * i], vy = v[3 * i + 1], vz = v[3 * i + 2], s = vx * vx + vy * vy + vz * vz;
      mx = s > mx ? s : mx;
      bad |= !(s <= PETSC_MAX_REAL);
    }
    m[0] = mx;
    m[1] = bad;
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, m, 2, MPIU_REAL, MPI_MAX, f->comm));
  PetscCheck(m[1] == 0 && !PetscIsInfOrNanReal(m[0]), f->comm, PETSC_ERR_NOT_CONVERGED,
             "step %" PetscInt_FMT
             " (t = %g): a particle velocity is not finite at the start of the step (the run went "
             "unstable): lower -flow_cfl or -flow_dt_max",
             f->step + 1, (double)f->t);
  *umax = PetscSqrtReal(m[0]);
  PetscFunctionReturn(PETSC_SUCCESS);
}
