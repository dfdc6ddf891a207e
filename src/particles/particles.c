/* The particle store: life cycle, options, structure-of-arrays storage with growable capacity,
   appending and removing particles, and global totals (count and mass per type, Eq. 5). */
#include "particlesimpl.h"

const char *const PffParticleTypes[] = {"liquid", "air", "PffParticleType", "PFF_PARTICLE_", NULL};

PetscErrorCode PffParticlesCreate(PffGrid grid, PffParticles *part)
{
  PffParticles p;
  PetscInt     nb[3];

  PetscFunctionBeginUser;
  PetscCheck(grid != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "PffParticlesCreate needs a set-up grid");
  PetscCheck(part != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "PffParticlesCreate: output pointer is NULL");
  PetscCall(PffInitializePackage());
  PetscCall(PetscNew(&p));
  p->grid = grid;
  PetscCall(PffGridGetComm(grid, &p->comm));
  PetscCallMPI(MPI_Comm_rank(p->comm, &p->rank));
  PetscCallMPI(MPI_Comm_size(p->comm, &p->size));
  p->jitter     = PFF_PARTICLES_JITTER_DEFAULT;
  p->jitterBand = PFF_PARTICLES_JITTER_BAND_DEFAULT;
  p->seed       = PFF_PARTICLES_SEED_DEFAULT;
  p->substepCfl = PFF_PARTICLES_SUBSTEP_CFL_DEFAULT;
  p->ioChunk    = PFF_PARTICLES_IO_CHUNK_DEFAULT;
  PetscCall(PffGridGetSizes(grid, &p->n0, &p->nlevels, p->origin, &p->h0, p->periodic));
  PetscCall(PffGridGetRaster(grid, nb, NULL, NULL));
  for (int d = 0; d < 3; d++) {
    p->nb[d]    = nb[d];
    p->cells[d] = nb[d] * p->n0;
  }
  while (((PetscInt)1 << p->log2n0) < p->n0) p->log2n0++;
  *part = p;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffParticlesSetFromOptions(PffParticles p)
{
  PetscInt seed = (PetscInt)p->seed;

  PetscFunctionBeginUser;
  PetscOptionsBegin(p->comm, NULL, "FLIP particles", "PffParticles");
  PetscCall(PffOptionsReal("-particles_jitter", "Jitter of the seeding lattice as a fraction of the sub-cell spacing",
                           "PffParticlesSeed", p->jitter, &p->jitter, NULL));
  PetscCall(PffOptionsInt("-particles_jitter_band",
                          "Cells around the seeding function's type changes whose particles sit on the lattice",
                          "PffParticlesSeed", p->jitterBand, &p->jitterBand, NULL));
  PetscCall(PffOptionsInt("-particles_seed", "Key of the counter-based random number generator", "PffParticlesSeed",
                          seed, &seed, NULL));
  PetscCall(PffOptionsReal("-particles_substep_cfl", "Cells a particle may move per RK3 sub-step", "PffParticlesAdvect",
                           p->substepCfl, &p->substepCfl, NULL));
  PetscCall(PffOptionsBoundedInt("-particles_io_chunk",
                                 "Particles per collective transfer of frames and checkpoints (bounds their buffers)",
                                 "PffParticlesSetIOChunk", p->ioChunk, &p->ioChunk, NULL, 1));
  PetscOptionsEnd();
  PetscCheck(p->jitter >= 0 && p->jitter <= 1, p->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-particles_jitter %g is invalid: must be in [0, 1]", (double)p->jitter);
  PetscCheck(p->jitterBand >= 0 && p->jitterBand <= PFF_PARTICLES_JITTER_BAND_MAX, p->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-particles_jitter_band %" PetscInt_FMT " is invalid: must be in [0, %d]", p->jitterBand,
             PFF_PARTICLES_JITTER_BAND_MAX);
  PetscCheck(seed >= 0, p->comm, PETSC_ERR_ARG_OUTOFRANGE, "-particles_seed %" PetscInt_FMT " is invalid: must be >= 0",
             seed);
  PetscCheck(p->substepCfl > 0 && PetscIsNormalReal(p->substepCfl), p->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-particles_substep_cfl %g is invalid: must be positive", (double)p->substepCfl);
  p->seed = (uint64_t)seed;
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffParticleSoAFree(PffParticleSoA *s)
{
  PetscFunctionBeginUser;
#define PFF_PARTICLE_FIELD_FREE(name, type, k, f) PetscCall(PetscFree(s->name));
  PFF_PARTICLE_FIELDS(PFF_PARTICLE_FIELD_FREE)
#undef PFF_PARTICLE_FIELD_FREE
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffParticlesSetIOChunk(PffParticles p, PetscInt rows)
{
  PetscFunctionBeginUser;
  PetscCheck(rows >= 1, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
             "PffParticlesSetIOChunk: %" PetscInt_FMT " rows, must be >= 1", rows);
  p->ioChunk = rows;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffParticlesGetIOChunk(PffParticles p, PetscInt *rows)
{
  PetscFunctionBeginUser;
  *rows = p->ioChunk;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffParticlesSetJitter(PffParticles p, PetscReal jitter)
{
  PetscFunctionBeginUser;
  PetscCheck(jitter >= 0 && jitter <= 1, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
             "particle jitter %g is invalid: must be in [0, 1]", (double)jitter);
  p->jitter = jitter;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffParticlesDestroy(PffParticles *part)
{
  PetscFunctionBeginUser;
  if (part == NULL || *part == NULL) PetscFunctionReturn(PETSC_SUCCESS);
  PffParticles p = *part;
  PetscCall(PffParticleSoAFree(&p->s));
  PetscCall(PetscFree(p->start));
  PetscCall(PetscFree(p->lgid));
  PetscCall(PetscFree(p->local));
  PetscCall(PetscFree(p->i32work));
  PetscCall(PetscFree(p->fwork));
  for (int k = 0; k < PFF_SCRATCH_N; k++) PetscCall(PetscFree(p->scratch[k]));
  PetscCall(PetscFree(p));
  *part = NULL;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Grows one array set to capacity cap, keeping its entries. In place, field by field: glibc's realloc
   moves a large block by remapping its pages, so a growth does not hold the old and the new store at once (a
   split of many particles during a run would otherwise add a whole store to the peak). The pages not yet written go
   onto huge pages (PffAdviseHugePages). */
static PetscErrorCode PffParticleSoAGrow(PffParticleSoA *s, PetscInt cap)
{
  PetscFunctionBeginUser;
#define PFF_PARTICLE_FIELD_GROW(name, type, k, f)                                                                      \
  PetscCall(PetscRealloc(sizeof(type) * (size_t)(k) * (size_t)cap, &s->name));                                         \
  PffAdviseHugePages(s->name, sizeof(type) * (size_t)(k) * (size_t)cap);
  PFF_PARTICLE_FIELDS(PFF_PARTICLE_FIELD_GROW)
#undef PFF_PARTICLE_FIELD_GROW
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Ensures capacity for m particles (geometric growth); keeps the n stored ones. The slack is never
   touched until used, so it costs address space, not resident memory. */
PetscErrorCode PffParticlesReserve_Private(PffParticles p, PetscInt m)
{
  PetscFunctionBeginUser;
  if (m <= p->cap) PetscFunctionReturn(PETSC_SUCCESS);
  const PetscInt cap = PetscMax(m, PetscMax(1024, p->cap + p->cap / 2));
  PetscCall(PffParticleSoAGrow(&p->s, cap));
  p->cap    = cap;
  p->binned = PETSC_FALSE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffParticlesTrim(PffParticles p)
{
  PetscFunctionBeginUser;
  const PetscInt cap = PetscMax(1024, p->n + p->n / 8);
  if (cap < p->cap) {
    PetscCall(PffParticleSoAGrow(&p->s, cap));
    p->cap = cap;
  }
  PetscCall(PetscFree(p->i32work));
  PetscCall(PetscFree(p->fwork));
  p->ni32work = p->nfwork = 0;
  for (int k = 0; k < PFF_SCRATCH_N; k++) {
    PetscCall(PetscFree(p->scratch[k]));
    p->nscratch[k] = 0;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffParticlesGetIntWork_Private(PffParticles p, size_t n, int32_t **w)
{
  PetscFunctionBeginUser;
  PetscCall(PffParticlesGrowIntWork_Private(p, n, 0, w));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffParticlesGetScratch_Private(PffParticles p, PffScratchSlot slot, PetscInt n, const size_t bytes[],
                                              void *ptrs[])
{
  size_t total = 64;

  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < n; i++) total += (bytes[i] + 63) / 64 * 64;
  if (total > p->nscratch[slot]) {
    PetscCall(PetscFree(p->scratch[slot]));
    p->nscratch[slot] = PetscMax(total, p->nscratch[slot] + p->nscratch[slot] / 2);
    PetscCall(PetscMalloc(p->nscratch[slot], &p->scratch[slot]));
  }
  char *c = (char *)p->scratch[slot];
  c += (64 - (uintptr_t)c % 64) % 64;
  for (PetscInt i = 0; i < n; i++) {
    ptrs[i] = c;
    c += (bytes[i] + 63) / 64 * 64;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffParticlesGrowIntWork_Private(PffParticles p, size_t n, PetscInt keep, int32_t **w)
{
  PetscFunctionBeginUser;
  if (n > p->ni32work) {
    int32_t *t;
    p->ni32work = PetscMax(n, p->ni32work + p->ni32work / 2);
    PetscCall(PetscMalloc1(p->ni32work, &t));
    if (keep > 0) PetscCall(PetscArraycpy(t, p->i32work, keep));
    PetscCall(PetscFree(p->i32work));
    p->i32work = t;
  }
  *w = p->i32work;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffParticlesGetFloatWork_Private(PffParticles p, size_t n, float **f)
{
  PetscFunctionBeginUser;
  if (n > p->nfwork) {
    PetscCall(PetscFree(p->fwork));
    p->nfwork = PetscMax(n, p->nfwork + p->nfwork / 2);
    PetscCall(PetscMalloc1(p->nfwork, &p->fwork));
  }
  *f = p->fwork;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffParticlesReset(PffParticles p)
{
  PetscFunctionBeginUser;
  /* the bins of the old raster stay: the migration reads the particles' blocks from them */
  PetscCall(PffParticlesMigrate(p, NULL));
  PetscCall(PetscInfo(NULL, "particles: rebinned after a grid topology change\n"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Every caller is collective, so all ranks see the same topology state and reset together. */
PetscErrorCode PffParticlesCheckBinned_Private(PffParticles p, const char caller[])
{
  PetscObjectState state;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetTopologyState(p->grid, &state));
  if (p->binned && state != p->topology) PetscCall(PffParticlesReset(p));
  PetscCheck(p->binned, PETSC_COMM_SELF, PETSC_ERR_ORDER,
             "%s needs binned particles: call PffParticlesMigrate (or PffParticlesBin) after adding or removing",
             caller);
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffParticlesGetArrays(PffParticles p, PffParticleArrays *a)
{
  PetscFunctionBeginUser;
  PetscCheck(a != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "PffParticlesGetArrays: output pointer is NULL");
  a->n     = p->n;
  a->x     = p->s.x;
  a->v     = p->s.v;
  a->id    = p->s.id;
  a->word  = p->s.word;
  a->start = p->binned ? p->start : NULL;
  a->h0    = p->h0;
  for (int d = 0; d < 3; d++) a->origin[d] = p->origin[d];
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffParticlesAdd(PffParticles p, PetscInt m, const PetscReal x[], const PetscReal v[],
                               const uint64_t id[], const uint8_t type[], const int8_t level[], const uint8_t flags[])
{
  PetscFunctionBeginUser;
  PetscCheck(m >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "cannot add %" PetscInt_FMT " particles", m);
  if (m == 0) PetscFunctionReturn(PETSC_SUCCESS);
  for (PetscInt i = 0; i < m; i++) {
    PetscCheck(type[i] < PFF_PARTICLE_NTYPES, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
               "particle %" PetscInt_FMT " has type %d, not a PffParticleType", i, (int)type[i]);
    PetscCheck(level[i] >= 0 && level[i] < p->nlevels, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
               "particle %" PetscInt_FMT " has level %d outside the grid's levels 0..%" PetscInt_FMT, i, (int)level[i],
               p->nlevels - 1);
  }
  PetscCall(PffParticlesReserve_Private(p, p->n + m));
  for (PetscInt i = 0; i < m; i++) {
    const PetscInt j = p->n + i;
    for (int d = 0; d < 3; d++) {
      p->s.x[3 * j + d] = (float)((x[3 * i + d] - p->origin[d]) / p->h0);
      p->s.v[3 * j + d] = (float)v[3 * i + d];
    }
    p->s.id[j] = id ? id[i] : 0;
    /* the flags byte of the files holds D_p in its upper half (PffParticleFlagsByte) */
    const uint8_t fl = flags ? flags[i] : 0;
    p->s.word[j]     = PffParticleWordSetLevel(PffParticleWord(type[i], level[i], fl & 0xfu), level[i], fl >> 4);
  }
  p->n += m;
  p->binned = PETSC_FALSE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffParticlesClear(PffParticles p)
{
  PetscFunctionBeginUser;
  p->n      = 0;
  p->binned = PETSC_FALSE;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Compacts [i0, i1) to start at m, keeping the order; whole runs of kept particles move at once. */
static PetscInt CompactRange(PffParticles p, PetscInt i0, PetscInt i1, PetscInt m)
{
  const uint32_t rm = PffParticleWordSetFlags(0, PFF_PARTICLE_FLAG_REMOVE, PETSC_TRUE);

  for (PetscInt i = i0; i < i1;) {
    if (p->s.word[i] & rm) {
      i++;
      continue;
    }
    PetscInt j = i + 1;
    while (j < i1 && !(p->s.word[j] & rm)) j++;
    if (m != i) PffParticlesMoveRange_Private(p, m, i, j - i);
    m += j - i;
    i = j;
  }
  return m;
}

PetscErrorCode PffParticlesRemove(PffParticles p)
{
  PetscInt m = 0;

  PetscFunctionBeginUser;
  if (p->binned) {
    /* compaction keeps the order, so each bin stays contiguous: its new start is where it begins */
    for (PetscInt lb = 0; lb < p->nlocal; lb++) {
      const PetscInt i0 = p->start[lb], i1 = p->start[lb + 1];
      p->start[lb] = m;
      m            = CompactRange(p, i0, i1, m);
    }
    p->start[p->nlocal] = m;
  } else
    m = CompactRange(p, 0, p->n, 0);
  p->n = m;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* h[b] (256 values, zeroed by the caller) += the particles whose word's low byte (type and level) is b, in threads.
   Four interleaved histograms per thread: neighbouring particles mostly share that byte, and one histogram's
   increments waited on each other's stores. */
static void PffParticlesWordHistogram(const uint32_t word[], PetscInt n, PetscInt64 h[256])
{
#pragma omp parallel reduction(+ : h[:256])
  {
    PetscInt64 q[4][256];
    memset(q, 0, sizeof(q));
#pragma omp for schedule(static)
    for (PetscInt i = 0; i < n; i++) q[i & 3][word[i] & 0xff]++;
    for (int b = 0; b < 256; b++) h[b] += q[0][b] + q[1][b] + q[2][b] + q[3][b];
  }
}

PetscErrorCode PffParticlesGetTotals(PffParticles p, const PetscReal density[PFF_PARTICLE_NTYPES],
                                     PetscInt64 count[PFF_PARTICLE_NTYPES], PetscReal mass[PFF_PARTICLE_NTYPES])
{
  PetscInt64 c[PFF_PARTICLE_NTYPES]   = {0};
  PetscReal  vol[PFF_PARTICLE_NTYPES] = {0};
  PetscInt64 h[16 * 16]               = {0}; /* particles per packed type (4 bits) and level (4 bits) */

  PetscFunctionBeginUser;
  /* a histogram of the word's low byte, in threads: the volumes are sums of integers 8^l, exact in any order */
  const uint32_t *word = p->s.word;
  const PetscInt  n    = p->n;
  PffParticlesWordHistogram(word, n, h);
  for (int b = 0; b < 256; b++) {
    if (!h[b]) continue;
    const PetscInt t = PffParticleWordType((uint32_t)b), l = PffParticleWordLevel((uint32_t)b);
    PetscCheck(t < PFF_PARTICLE_NTYPES, PETSC_COMM_SELF, PETSC_ERR_PLIB, "a particle has type %" PetscInt_FMT, t);
    c[t] += h[b];
    vol[t] += (PetscReal)h[b] * (PetscReal)((PetscInt64)1 << (3 * l));
  }
  if (count) PetscCallMPI(MPI_Allreduce(c, count, PFF_PARTICLE_NTYPES, MPIU_INT64, MPI_SUM, p->comm));
  if (mass) {
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, vol, PFF_PARTICLE_NTYPES, MPIU_REAL, MPI_SUM, p->comm));
    for (int t = 0; t < PFF_PARTICLE_NTYPES; t++) mass[t] = (density ? density[t] : 1.0) * vol[t];
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The fields of the list in particlesimpl.h whose files entry is FILE, in list order. */
#define PFF_PARTICLE_FIELD_TYPE(type)                                                                                  \
  _Generic((type *)0, float *: PFF_FIELD_FLOAT, double *: PFF_FIELD_DOUBLE, int32_t *: PFF_FIELD_INT32, \
           uint32_t *: PFF_FIELD_UINT32, int64_t *: PFF_FIELD_INT64, uint64_t *: PFF_FIELD_UINT64)
#define PFF_PARTICLE_FIELD_IS_FILE_FILE 1
#define PFF_PARTICLE_FIELD_IS_FILE_OWN 0
#define PFF_PARTICLE_FIELD_INFO(name, type, k, f)                                                                      \
  {{#name, k, PFF_PARTICLE_FIELD_TYPE(type), sizeof(type)}, PFF_PARTICLE_FIELD_IS_FILE_##f},
static const struct {
  PffParticleFieldInfo info;
  int                  file;
} PffParticleFieldTable[] = {PFF_PARTICLE_FIELDS(PFF_PARTICLE_FIELD_INFO)};

PetscErrorCode PffParticlesGetFileFields(PetscInt *n, PffParticleFieldInfo info[])
{
  PetscInt m = 0;

  PetscFunctionBeginUser;
  for (size_t k = 0; k < sizeof(PffParticleFieldTable) / sizeof(PffParticleFieldTable[0]); k++)
    if (PffParticleFieldTable[k].file) {
      PetscCheck(!info || m < *n, PETSC_COMM_SELF, PETSC_ERR_ARG_SIZ,
                 "PffParticlesGetFileFields: room for %" PetscInt_FMT " fields only", *n);
      if (info) info[m] = PffParticleFieldTable[k].info;
      m++;
    }
  *n = m;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffParticlesGetFieldArray(PffParticles p, const char name[], void **data)
{
  PetscBool match;

  PetscFunctionBeginUser;
  *data = NULL;
#define PFF_PARTICLE_FIELD_ARRAY(fname, type, k, f)                                                                    \
  PetscCall(PetscStrcmp(name, #fname, &match));                                                                        \
  if (match) *data = (void *)p->s.fname;
  PFF_PARTICLE_FIELDS(PFF_PARTICLE_FIELD_ARRAY)
#undef PFF_PARTICLE_FIELD_ARRAY
  PetscCheck(*data || p->cap == 0, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG, "no particle field %s", name);
  PetscFunctionReturn(PETSC_SUCCESS);
}
