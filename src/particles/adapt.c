/* Particle split and probabilistic coarsening (PF-FLIP Sec. 5.1, 5.4 step 6; docs/particles.md,
   "Adaptive particles").

   A split goes one level at a time: a particle of level l becomes 8 particles of level l - 1, one in
   each octant of the level-(l - 1) cell that contains it, at a uniformly random place inside its octant.
   Seeding puts 8 particles per cell at their sub-cell centres, so a split particle's children sample
   its cell of the finer level as seeding at that level would (with jitter 1). Further levels repeat
   this per child. Splits only append, and the parent's slot is reused by its first child, so particles
   keep their block and the store is binned again without a migration. */
#include "particlesimpl.h"

/* Children of the parent at g (grid units, level l) down to level t, appended at out; returns the count. */
static PetscInt SplitParticle(PffParticles p, const float g[3], uint64_t id, PetscInt l, PetscInt t, float *xout,
                              uint64_t *idout)
{
  if (l == t) {
    for (int a = 0; a < 3; a++) xout[a] = g[a];
    idout[0] = id;
    return 1;
  }
  const PetscReal s = (PetscReal)((PetscInt)1 << (l - 1)); /* cell size of the children's level */
  PetscInt        m = 0;
  for (PetscInt oct = 0; oct < 8; oct++) {
    const uint64_t cid = PffHash64_Private(id ^ (0x9e3779b97f4a7c15ULL * (uint64_t)(oct + 1))) | (1ULL << 63);
    float          c[3];
    for (int a = 0; a < 3; a++) {
      const PetscReal lo = PetscFloorReal((PetscReal)g[a] / s) * s, half = 0.5 * s;
      const PetscReal u = PffRandom01_Private(p->seed, cid, PFF_RNG_SPLIT, (uint64_t)a);
      const PetscReal x = lo + half * ((PetscReal)((oct >> a) & 1) + u);
      /* rounding must not carry a child into the next cell (or block) */
      c[a] = PetscMin((float)x, nextafterf((float)(lo + s), 0));
    }
    m += SplitParticle(p, c, cid, l - 1, t, xout + 3 * m, idout + m);
  }
  return m;
}

PetscErrorCode PffParticlesAdaptLevels(PffParticles p, const int8_t target[], PetscInt delay, uint64_t key,
                                       PffParticleAdaptStats *stats)
{
  PffParticleAdaptStats st = {0};
  const PetscInt        n = p->n, lmax = p->nlevels - 1;
  const uint32_t        rm    = PffParticleWordSetFlags(0, PFF_PARTICLE_FLAG_REMOVE, PETSC_TRUE);
  PetscInt64            extra = 0, nsplit = 0, marked = 0, removed = 0;
  PetscReal             vl0 = 0, va0 = 0, dl = 0, da = 0; /* volumes before, and their changes, per type */

  PetscFunctionBeginUser;
  PetscCheck(delay >= 1 && delay <= 15, p->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "PffParticlesAdaptLevels: the coarsening delay %" PetscInt_FMT " must be in [1, 15]", delay);
  PetscCall(PetscLogEventBegin(PFF_PartAdapt, 0, 0, 0, 0));
  /* counters and coarsening in threads (each particle on its own); splits only counted here */
#pragma omp parallel for reduction(+ : extra, nsplit, marked, removed, vl0, va0, dl, da) schedule(static)
  for (PetscInt i = 0; i < n; i++) {
    const uint32_t  w = p->s.word[i];
    const PetscInt  l = PffParticleWordLevel(w), t = PetscClipInterval((PetscInt)target[i], 0, lmax);
    const PetscBool liquid = (PetscBool)(PffParticleWordType(w) == PFF_PARTICLE_LIQUID);
    const PetscReal vol    = (PetscReal)((PetscInt64)1 << (3 * l));
    PetscReal       dv     = 0;
    if (liquid)
      vl0 += vol;
    else
      va0 += vol;
    if (t < l) {
      extra += ((PetscInt64)1 << (3 * (l - t))) - 1;
      nsplit++;
    } else if (t > l) {
      const PetscInt d = PffParticleWordCoarsen(w) + 1;
      if (d < delay)
        p->s.word[i] = PffParticleWordSetLevel(w, l, d);
      else {
        marked++;
        if (PffRandom01_Private(p->seed, p->s.id[i], PFF_RNG_COARSEN, key) >=
            1.0 / (PetscReal)((PetscInt64)1 << (3 * (t - l)))) {
          p->s.word[i] = w | rm;
          removed++;
          dv = -vol;
        } else {
          p->s.word[i] = PffParticleWordSetLevel(w, t, 0);
          dv           = (PetscReal)((PetscInt64)1 << (3 * t)) - vol;
        }
      }
    } else if (PffParticleWordCoarsen(w))
      p->s.word[i] = PffParticleWordSetLevel(w, l, 0);
    if (liquid)
      dl += dv;
    else
      da += dv;
  }
  PetscCheck(n + extra < PETSC_MAX_INT, PETSC_COMM_SELF, PETSC_ERR_SUP,
             "the split would give %" PetscInt64_FMT " particles on one rank", (PetscInt64)n + extra);
  if (nsplit) {
    float           *cx;
    uint64_t        *cid;
    int32_t         *dst = NULL;
    PetscInt         m   = n;
    PetscObjectState state;
    /* binned on the current raster: the children's bins are their parents', so the sort needs no locate */
    PetscCall(PffGridGetTopologyState(p->grid, &state));
    const PetscBool rebin = (PetscBool)(p->binned && p->topology == state);
    if (rebin) PetscCall(PffParticlesGetIntWork_Private(p, (size_t)(n + extra) + 1, &dst));
    PetscCall(PffParticlesReserve_Private(p, n + (PetscInt)extra)); /* the store may move */
    PetscCall(PetscMalloc2(3 * ((size_t)1 << (3 * lmax)), &cx, (size_t)1 << (3 * lmax), &cid));
    for (PetscInt lb = 0, i = 0; i < n; i++) {
      if (rebin) {
        while (i >= p->start[lb + 1]) lb++;
        dst[i] = (int32_t)lb | PFF_SORT_STAYS;
      }
      const uint32_t w = p->s.word[i];
      const PetscInt l = PffParticleWordLevel(w), t = PetscClipInterval((PetscInt)target[i], 0, lmax);
      if (t >= l) continue;
      const PetscInt nc = SplitParticle(p, &p->s.x[3 * i], p->s.id[i], l, t, cx, cid);
      const uint32_t wc = PffParticleWordSetLevel(w, t, 0);
      for (PetscInt c = 0; c < nc; c++) {
        const PetscInt j = c == 0 ? i : m++;
        for (int a = 0; a < 3; a++) {
          p->s.x[3 * j + a] = cx[3 * c + a];
          p->s.v[3 * j + a] = p->s.v[3 * i + a];
        }
        p->s.id[j]   = cid[c];
        p->s.word[j] = wc;
        if (rebin && j >= n) dst[j] = (int32_t)lb;
      }
    }
    PetscCall(PetscFree2(cx, cid));
    p->n = m;
    if (rebin)
      PetscCall(PffParticlesSort_Private(p)); /* bins again (the children are the movers) */
    else
      p->binned = PETSC_FALSE;
  }

  /* a store that only changed levels keeps its bins */
  if (removed) PetscCall(PffParticlesRemove(p));
  if (!p->binned) PetscCall(PffParticlesBin(p));
  {
    PetscReal v[4] = {vl0, va0, dl, da};
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, v, 4, MPIU_REAL, MPI_SUM, p->comm));
    st.volumeBefore[PFF_PARTICLE_LIQUID] = v[0];
    st.volumeBefore[PFF_PARTICLE_AIR]    = v[1];
    st.volumeAfter[PFF_PARTICLE_LIQUID]  = v[0] + v[2];
    st.volumeAfter[PFF_PARTICLE_AIR]     = v[1] + v[3];
  }
  st.split    = nsplit;
  st.children = nsplit + extra;
  st.marked   = marked;
  st.removed  = removed;
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &st.split, 4, MPIU_INT64, MPI_SUM, p->comm));
  PetscCall(PetscLogEventEnd(PFF_PartAdapt, 0, 0, 0, 0));
  if (stats) *stats = st;
  PetscFunctionReturn(PETSC_SUCCESS);
}
