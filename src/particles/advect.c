/* Advection (PF-FLIP Sec. 3.7; DESIGN.md Sec. 4 step 7): every particle integrates dx/dt = u(x)
   through the face velocity channel with Ralston's third-order Runge-Kutta (Bridson 2015),
     k1 = u(x), k2 = u(x + dt/2 k1), k3 = u(x + 3dt/4 k2), x += dt (2 k1 + 3 k2 + 4 k3) / 9,
   in its own sub-steps: n_sub = ceil(|u(x)| dt / (cfl h)), 1 <= n_sub <= PFF_PARTICLES_MAX_SUBSTEPS,
   h the cell size of its block (locally adaptive time stepping).

   Each particle type has its own velocity channel (liquid particles sample the liquid velocity
   extrapolated into the air, Sec. 3.7); the batches are grouped by type so that each channel is
   interpolated in one call.

   Velocity samples use PffGridInterpolateFrom on the lattice of a "current" owned block, which may
   reach (width - 1) cells of that block's level beyond it. A stage point within that reach keeps the
   block; a point beyond it that lies in another owned block switches to that block; a point beyond
   it on another rank (or across a wall) has its displacement clamped, per axis, to the reach of the
   current block (logged with PetscInfo). So within one call a particle may travel about (width - 1)
   cells past its rank's blocks exactly; further motion is truncated until the next call.

   The particles are processed in batches (all particles still sub-stepping, stage by stage); the
   samples and the arithmetic are OpenMP-parallel. The samples are those of PffGridInterpolateFrom,
   through the block table of PffSampler (bit-identical, without its per-point checks). Afterwards particles inside a
   solid are pushed out along the distance gradient and all particles are migrated (which wraps periodic axes and clamps
   walls). */
#include "particlesimpl.h"

typedef struct {
  PetscReal c[3];  /* block centre */
  PetscReal bound; /* largest allowed |x - c| per axis for a velocity sample */
  PetscReal h;
} PffAdvectBlock;

/* Chooses the block to sample position xs from (cur first) and clamps xs into cur's reach if no owned
   block can serve it. Returns PETSC_TRUE when it clamped. */
static PetscBool PffAdvectFix(PffParticles p, const PffAdvectBlock *blocks, const PetscInt level[], PetscInt cur,
                              PetscReal xs[3], PetscInt *out)
{
  const PffAdvectBlock *b      = &blocks[cur];
  PetscBool             within = PETSC_TRUE;
  PetscReal             rel[3];

  for (int a = 0; a < 3; a++) {
    rel[a] = xs[a] - b->c[a];
    if (p->periodic[a]) {
      const PetscReal L = (PetscReal)p->cells[a] * p->h0;
      rel[a] -= L * PetscFloorReal(rel[a] / L + 0.5);
    }
    if (PetscAbsReal(rel[a]) > b->bound) within = PETSC_FALSE;
  }
  *out = cur;
  if (within) return PETSC_FALSE;
  const PetscInt gid = PffParticlesLocate_Private(p, xs, level);
  if (gid >= 0 && p->local[gid] >= 0) {
    *out = p->local[gid];
    return PETSC_FALSE;
  }
  for (int a = 0; a < 3; a++) {
    if (rel[a] > b->bound)
      xs[a] = b->c[a] + b->bound;
    else if (rel[a] < -b->bound)
      xs[a] = b->c[a] - b->bound;
    else
      xs[a] = b->c[a] + rel[a];
  }
  return PETSC_TRUE;
}

/* Velocity samples at the m packed points (xs, bl): the first m0 from the sampler's first channel,
   the others from its last, in threads (no lookup, check or log call per point). */
static void PffAdvectSample(PffParticles p, const PffSampler *s, PetscInt m0, PetscInt m, const PetscReal xs[],
                            const PetscInt bl[], PetscReal k[])
{
#pragma omp parallel for schedule(static)
  for (PetscInt j = 0; j < m; j++) {
    const PetscInt ch = j < m0 ? 0 : s->nch - 1;
    PetscReal      lp[3];
    PffSamplerLocal_Private(p, &s->blocks[bl[j]], &xs[3 * j], lp);
    for (PetscInt d = 0; d < 3; d++) PffSamplerFace_Private(s, bl[j], ch, 1, d, lp, &k[3 * j + d]);
  }
}

/* ord: the local particles with the liquid ones first (all in order when both types share a channel);
   returns how many sample ch[0]. */
static PetscInt PffAdvectOrder(PffParticles p, const PetscInt chU[PFF_PARTICLE_NTYPES], PetscInt ord[])
{
  PetscInt m0 = 0, m = 0;

  if (chU[PFF_PARTICLE_LIQUID] == chU[PFF_PARTICLE_AIR]) {
    for (PetscInt i = 0; i < p->n; i++) ord[i] = i;
    return p->n;
  }
  for (PetscInt i = 0; i < p->n; i++)
    if (p->s.type[i] == PFF_PARTICLE_LIQUID) ord[m0++] = i;
  m = m0;
  for (PetscInt i = 0; i < p->n; i++)
    if (p->s.type[i] != PFF_PARTICLE_LIQUID) ord[m++] = i;
  return m0;
}

PetscErrorCode PffParticlesAdvect(PffParticles p, PetscInt chU, PetscReal dt, PffSolidFn solid, void *solidctx,
                                  PffParticleStats *stats)
{
  const PetscInt ch[PFF_PARTICLE_NTYPES] = {chU, chU};

  PetscFunctionBeginUser;
  PetscCall(PffParticlesAdvectPerType(p, ch, dt, solid, solidctx, stats));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffParticlesAdvectPerType(PffParticles p, const PetscInt chU[PFF_PARTICLE_NTYPES], PetscReal dt,
                                         PffSolidFn solid, void *solidctx, PffParticleStats *stats)
{
  PetscInt        width = PFF_GRID_MAX_WIDTH, nb[3], maxsub = 0, nclamp = 0, nliq;
  const PetscInt *level;
  const PetscInt  n = p->n;
  PetscReal      *work, *k1, *k2, *k3, *xs, *xa, *hsub;
  PetscInt       *iwork, *cur, *nsub, *act, *bl, *ord;
  PffAdvectBlock *blocks;
  PffSampler      sampler;
  PetscInt64      pushed = 0;

  PetscFunctionBeginUser;
  PetscCall(PffParticlesCheckBinned_Private(p, "PffParticlesAdvect"));
  for (PetscInt t = 0; t < PFF_PARTICLE_NTYPES; t++) {
    PffChannelKind kind;
    PetscInt       w;
    const char    *name;
    PetscCall(PffGridGetChannelInfo(p->grid, chU[t], &name, &kind, NULL, &w));
    PetscCheck(kind == PFF_CHANNEL_FACE, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG,
               "advection channel %s must be a face channel", name);
    PetscCheck(w >= 2, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG,
               "advection channel %s has halo width %" PetscInt_FMT ": needs >= 2", name, w);
    /* the reach of a sample is that of the narrower halo */
    width = PetscMin(width, w);
  }
  PetscCheck(dt >= 0 && PetscIsNormalReal(dt + 1), PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
             "advection time step %g is invalid", (double)dt);
  PetscCall(PetscLogEventBegin(PFF_Advect, 0, 0, 0, 0));
  PetscCall(PffGridGetRaster(p->grid, nb, &level, NULL));
  PetscCall(PffParticlesGetWork_Private(p, (size_t)(16 * n), &work, (size_t)(5 * n), &iwork));
  k1   = work;
  k2   = k1 + 3 * n;
  k3   = k2 + 3 * n;
  xs   = k3 + 3 * n;
  xa   = xs + 3 * n; /* positions of the active particles, packed */
  hsub = xa + 3 * n; /* sub-step length */
  cur  = iwork;
  nsub = cur + n;
  act  = nsub + n;
  bl   = act + n;
  ord  = bl + n;
  nliq = PffAdvectOrder(p, chU, ord);
  PetscCall(PffSamplerCreate_Private(p, chU[0] == chU[1] ? 1 : 2, chU, &sampler));
  PetscCall(PetscMalloc1(PetscMax(p->nlocal, 1), &blocks));
  for (PetscInt lb = 0; lb < p->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(p->grid, lb, &info));
    const PetscReal half = 0.5 * (PetscReal)info.n * info.h;
    for (int a = 0; a < 3; a++) blocks[lb].c[a] = info.lo[a] + half;
    /* a millionth of a cell inside the reach PffGridInterpolateFrom accepts */
    blocks[lb].bound = half + ((PetscReal)(width - 1) - 1e-6) * info.h;
    blocks[lb].h     = info.h;
  }

  /* sub-step counts from the velocity at the start, sampled in the order of ord (the first sub-step's k1) */
  PetscReal *x = p->s.x;
  if (nliq == n) /* one channel for both types: ord is the identity, no packed copy */
    PffAdvectSample(p, &sampler, n, n, x, p->blk, k1);
  else {
    for (PetscInt j = 0; j < n; j++) {
      for (int a = 0; a < 3; a++) xa[3 * j + a] = x[3 * ord[j] + a];
      bl[j] = p->blk[ord[j]];
    }
    PffAdvectSample(p, &sampler, nliq, n, xa, bl, k1);
  }
#pragma omp parallel for reduction(max : maxsub) schedule(static)
  for (PetscInt j = 0; j < n; j++) {
    const PetscInt  i = ord[j];
    const PetscReal speed =
        PetscSqrtReal(k1[3 * j] * k1[3 * j] + k1[3 * j + 1] * k1[3 * j + 1] + k1[3 * j + 2] * k1[3 * j + 2]);
    const PetscReal cells = speed * dt / (p->substepCfl * blocks[p->blk[i]].h);
    PetscInt        m =
        cells < (PetscReal)PFF_PARTICLES_MAX_SUBSTEPS ? (PetscInt)PetscCeilReal(cells) : PFF_PARTICLES_MAX_SUBSTEPS;
    m       = PetscMax(1, m);
    nsub[i] = m;
    hsub[i] = dt / (PetscReal)m;
    cur[i]  = p->blk[i];
    maxsub  = PetscMax(maxsub, m);
  }

  for (PetscInt sub = 0; sub < maxsub; sub++) {
    PetscInt m = 0, m0 = 0;
    for (PetscInt j = 0; j < n; j++)
      if (nsub[ord[j]] > sub) {
        act[m++] = ord[j];
        if (j < nliq) m0 = m;
      }
    /* k1 (already sampled for the first sub-step, where every particle is active in the order of ord) */
    if (sub > 0) {
      for (PetscInt j = 0; j < m; j++) {
        for (int a = 0; a < 3; a++) xa[3 * j + a] = x[3 * act[j] + a];
        bl[j] = cur[act[j]];
      }
      PffAdvectSample(p, &sampler, m0, m, xa, bl, k1);
    }
    /* k2 at x + dt/2 k1, k3 at x + 3 dt/4 k2 */
    for (int stage = 0; stage < 2; stage++) {
      const PetscReal  f  = stage == 0 ? 0.5 : 0.75;
      const PetscReal *kp = stage == 0 ? k1 : k2;
#pragma omp parallel for reduction(+ : nclamp) schedule(static)
      for (PetscInt j = 0; j < m; j++) {
        const PetscInt i = act[j];
        for (int a = 0; a < 3; a++) xs[3 * j + a] = x[3 * i + a] + f * hsub[i] * kp[3 * j + a];
        nclamp += PffAdvectFix(p, blocks, level, cur[i], &xs[3 * j], &bl[j]);
      }
      PffAdvectSample(p, &sampler, m0, m, xs, bl, stage == 0 ? k2 : k3);
    }
#pragma omp parallel for reduction(+ : nclamp) schedule(static)
    for (PetscInt j = 0; j < m; j++) {
      const PetscInt i = act[j];
      for (int a = 0; a < 3; a++)
        x[3 * i + a] += hsub[i] * (2 * k1[3 * j + a] + 3 * k2[3 * j + a] + 4 * k3[3 * j + a]) / 9;
      nclamp += PffAdvectFix(p, blocks, level, cur[i], &x[3 * i], &cur[i]);
    }
  }
  PetscCall(PetscFree(blocks));
  PetscCall(PffSamplerDestroy_Private(&sampler));
  if (nclamp) PetscCall(PetscInfo(NULL, "%" PetscInt_FMT " advection stages clamped to the halo reach\n", nclamp));

  /* push out of solids along the distance gradient (a few Newton-like steps) */
  if (solid != NULL) {
    for (PetscInt i = 0; i < n; i++) {
      PetscBool moved = PETSC_FALSE;
      for (int it = 0; it < 4; it++) {
        PetscReal       g[3];
        const PetscReal phi = solid(&x[3 * i], g, solidctx);
        if (!(phi < 0)) break;
        const PetscReal gn = PetscSqrtReal(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
        if (!(gn > 0)) break;
        /* phi < 0 is the (approximate) distance to the surface: step just beyond it */
        const PetscReal step = -phi * (1 + 1e-3) + 1e-9 * p->h0;
        for (int a = 0; a < 3; a++) x[3 * i + a] += step * g[a] / gn;
        moved = PETSC_TRUE;
      }
      pushed += moved;
    }
  }
  PetscCall(PetscLogEventEnd(PFF_Advect, 0, 0, 0, 0));

  PffParticleStats ms;
  PetscCall(PffParticlesMigrate(p, &ms));
  PetscInt64 loc[2] = {pushed, maxsub};
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &loc[0], 1, MPIU_INT64, MPI_SUM, p->comm));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &loc[1], 1, MPIU_INT64, MPI_MAX, p->comm));
  if (stats) {
    *stats          = ms;
    stats->pushed   = loc[0];
    stats->substeps = (PetscInt)loc[1];
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
