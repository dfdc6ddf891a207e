/* particles: the FLIP particle store (structure of arrays), seeding, binning by block, migration,
   P2G splatting (PF-FLIP Eq. 3-6), G2P transfer (Eq. 11-12) and RK3 advection (Sec. 3.7).
   Particles are owned by the rank that owns the block containing them. */
#pragma once

#include <pff/grid.h>

typedef struct _n_PffParticles *PffParticles;

/* Particle type, fixed for the life of a particle (it sets the mass, Eq. 5). */
typedef enum { PFF_PARTICLE_LIQUID, PFF_PARTICLE_AIR, PFF_PARTICLE_NTYPES } PffParticleType;
PETSC_EXTERN const char *const PffParticleTypes[];

/* The packed word of a particle: type in bits 0-3, level in bits 4-7, flags in bits 8-27, the
   deferred-coarsening counter D_p of PF-FLIP Sec. 5.4 in bits 28-31. */
#define PFF_PARTICLE_FLAG_SHIFT 8
#define PFF_PARTICLE_FLAG_DROPLET 0x1 /* liquid particle found in air (Sec. 3.4): droplet candidate */
#define PFF_PARTICLE_FLAG_REMOVE 0x2  /* marked for PffParticlesRemove */

static inline uint32_t PffParticleWord(PetscInt type, PetscInt level, uint32_t flags)
{
  return (uint32_t)type | (uint32_t)level << 4 | flags << PFF_PARTICLE_FLAG_SHIFT;
}
static inline PetscInt PffParticleWordType(uint32_t w)
{
  return (PetscInt)(w & 0xfu);
}
static inline PetscInt PffParticleWordLevel(uint32_t w)
{
  return (PetscInt)(w >> 4 & 0xfu);
}
static inline uint32_t PffParticleWordFlags(uint32_t w)
{
  return (w >> PFF_PARTICLE_FLAG_SHIFT) & 0xfffffu;
}
static inline PetscInt PffParticleWordCoarsen(uint32_t w)
{
  return (PetscInt)(w >> 28);
}
/* Whether the coarsening of a particle is pending: it asked for a coarser level fewer than delay times in a
   row (PffParticlesAdaptCounters), so it still holds the grid at its own level. */
static inline PetscBool PffParticleWordPending(uint32_t w, PetscInt delay)
{
  const PetscInt d = PffParticleWordCoarsen(w);
  return (PetscBool)(d > 0 && d < delay);
}
/* The flags byte of the files: the flags in bits 0-3, D_p in bits 4-7 (docs/file-format.md). */
static inline uint8_t PffParticleFlagsByte(uint32_t w)
{
  return (uint8_t)((PffParticleWordFlags(w) & 0xfu) | (uint32_t)(w >> 28) << 4);
}
/* w with level l and the deferred-coarsening counter c (saturated at 15) */
static inline uint32_t PffParticleWordSetLevel(uint32_t w, PetscInt l, PetscInt c)
{
  return (w & 0x0fffff0fu) | (uint32_t)l << 4 | (uint32_t)PetscMin(c, 15) << 28;
}
/* One adaptation's deferred-coarsening counter of *w for a particle that asks for level wish (clipped to [0, lmax]):
   it counts while the particle asks for a coarser level than its own and resets otherwise. Returns the level the
   particle asks for with the hold applied: its own while its coarsening is pending (PffParticlesAdaptCounters does
   this for a whole store; the flow's adaptation inline in its pass over the particles). */
static inline PetscInt PffParticleWordCountWish(uint32_t *w, PetscInt wish, PetscInt lmax, PetscInt delay)
{
  const PetscInt l = PffParticleWordLevel(*w), t = PetscClipInterval(wish, 0, lmax);
  *w = PffParticleWordSetLevel(*w, l, t > l ? PetscMin(PffParticleWordCoarsen(*w) + 1, 15) : 0);
  return PffParticleWordPending(*w, delay) ? l : t;
}
/* w with the flag bits set (on true) or cleared (on false) */
static inline uint32_t PffParticleWordSetFlags(uint32_t w, uint32_t flags, PetscBool on)
{
  return on ? w | flags << PFF_PARTICLE_FLAG_SHIFT : w & ~(flags << PFF_PARTICLE_FLAG_SHIFT);
}

#define PFF_PARTICLES_PER_AXIS 2 /* 2 x 2 x 2 = 8 particles per cell at seeding */

/* The arrays of the n particles on this rank (the compact store, 36 B per particle; docs/particles.md);
   borrowed, valid until the next call that adds, removes or moves particles (Seed, Migrate, Remove,
   Advect). After PffParticlesBin (and after Seed and Migrate, which bin) the particles of local block lb
   are [start[lb], start[lb + 1]).

   Positions are floats in grid units, g = (x - origin) / h0 (PffParticleArraysWorld gives x): 24 bits
   of mantissa keep every position within cells * 2^-24 finest cells of the double it was rounded from,
   2^-10 of a cell at 16384 cells per axis, independent of where the domain lies. */
typedef struct {
  PetscInt  n;
  float    *x;    /* [3n] position in grid units */
  float    *v;    /* [3n] velocity (world units) */
  uint64_t *id;   /* [n] unique, deterministic: the same scene gives the same ids on any rank count */
  uint32_t *word; /* [n] PffParticleWord(type, level, flags): level l_p gives radius r_p = h0 2^l_p, volume 8^l_p */
  const PetscInt *start;         /* [nlocal + 1] block bins */
  PetscReal       origin[3], h0; /* the grid's: x = origin + h0 g */
} PffParticleArrays;

/* World position of particle i. */
static inline void PffParticleArraysWorld(const PffParticleArrays *a, PetscInt i, PetscReal x[3])
{
  for (int d = 0; d < 3; d++) x[d] = a->origin[d] + a->h0 * (PetscReal)a->x[3 * i + d];
}

/* Seeding callback: type of the particle at x (PFF_PARTICLE_LIQUID, PFF_PARTICLE_AIR, or -1 for no
   particle, e.g. inside a solid) and its initial velocity v. Must be deterministic. */
typedef PetscErrorCode (*PffSeedFn)(const PetscReal x[3], PetscInt *type, PetscReal v[3], void *ctx);

/* Signed distance to the solid boundary, negative inside a solid; grad receives its gradient. It must be
   1-Lipschitz (|phi(x) - phi(y)| <= |x - y|, as an exact signed distance or a union of them is), since the
   push-out skips whole blocks whose centre lies farther from the solids than their half diagonal, and
   thread-safe: it is called from OpenMP threads. */
typedef PetscReal (*PffSolidFn)(const PetscReal x[3], PetscReal grad[3], void *ctx);

/* Counters of one PffParticlesMigrate/Advect call, summed over ranks. */
typedef struct {
  PetscInt64 sent;     /* particles that changed rank */
  PetscInt64 wrapped;  /* particles moved across a periodic boundary */
  PetscInt64 clamped;  /* particles pulled back inside a wall */
  PetscInt64 pushed;   /* particles pushed out of a solid */
  PetscInt   substeps; /* maximum RK3 sub-steps of any particle (Advect only) */
} PffParticleStats;

/* Life cycle. Create borrows grid (it must outlive the particles and be set up). SetFromOptions reads
   -particles_jitter j   jitter of the seeding lattice as a fraction of the sub-cell spacing, [0, 1] (default 1)
   -particles_jitter_band b  cells within b of a change of the seeding function's type are seeded on the lattice,
                         so that the initial interface is as smooth as the lattice's, [0, 8] (default 2)
   -particles_seed s     key of the counter-based RNG (default 0)
   -particles_substep_cfl c  cells a particle may move per RK3 sub-step (default 1)
   -particles_io_chunk r  particles per collective transfer when frames and checkpoints write or read the store
                         (default 1048576): the conversion buffers hold r rows whatever the count */
PETSC_EXTERN PetscErrorCode PffParticlesCreate(PffGrid grid, PffParticles *p);
PETSC_EXTERN PetscErrorCode PffParticlesSetFromOptions(PffParticles p);
/* Jitter of the next Seed, as -particles_jitter (0 = the regular lattice). Not collective. */
PETSC_EXTERN PetscErrorCode PffParticlesSetJitter(PffParticles p, PetscReal jitter);
/* Particles per collective transfer of frames and checkpoints, as -particles_io_chunk (>= 1). Not collective,
   but every rank must set the same value before a write or a read. */
PETSC_EXTERN PetscErrorCode PffParticlesSetIOChunk(PffParticles p, PetscInt rows);
PETSC_EXTERN PetscErrorCode PffParticlesGetIOChunk(PffParticles p, PetscInt *rows);
PETSC_EXTERN PetscErrorCode PffParticlesDestroy(PffParticles *p);

/* Seeds 2 x 2 x 2 jittered particles per cell of every owned block at the block's level (particle
   level = block level), asking fn for type and velocity. Ids come from the global cell and sub-cell
   index, jitter from a counter-based RNG keyed by (seed, id): identical on any rank count. Collective. */
PETSC_EXTERN PetscErrorCode PffParticlesSeed(PffParticles p, PffSeedFn fn, void *ctx);
/* The same for the local blocks lb in [lb0, lb1) with mask[lb] (mask may be NULL: all) only (the same
   particles and ids as PffParticlesSeed gives there), e.g. to splat a reference lattice a batch of blocks
   at a time. Bins the particles. Not collective. */
PETSC_EXTERN PetscErrorCode PffParticlesSeedBlocks(PffParticles p, PffSeedFn fn, void *ctx, PetscInt lb0, PetscInt lb1,
                                                   const PetscBool mask[]);
/* Reseeding: the lattice particles of the given cells only (cells[2q] a local block, cells[2q + 1] its cell index,
   x fastest), at the block's level, as PffParticlesSeed places them, with ids hashed from the lattice ids and key
   (non-zero, e.g. the step; top bit set) so that they do not repeat the ids of the cell's first seeding. Bins the
   particles. Not collective. */
PETSC_EXTERN PetscErrorCode PffParticlesSeedCells(PffParticles p, PffSeedFn fn, void *ctx, PetscInt ncells,
                                                  const PetscInt cells[], uint64_t key);
PETSC_EXTERN PetscErrorCode PffParticlesGetArrays(PffParticles p, PffParticleArrays *a);
/* Counting sort of the local particles by owned block (every particle must lie in an owned block). */
PETSC_EXTERN PetscErrorCode PffParticlesBin(PffParticles p);
/* Wraps periodic axes, clamps into walled axes, sends every particle to the owner of its block, bins.
   Nothing is lost: a particle in an inactive block is an error. Collective. */
PETSC_EXTERN PetscErrorCode PffParticlesMigrate(PffParticles p, PffParticleStats *stats);
/* Follows a change of the grid's topology (PffGridAdapt): every particle goes to the new owner of its
   block and the bins are rebuilt. The particle operations call it themselves when the grid's topology
   state differs from the one their bins were built at. Every particle must lie in an active block.
   Collective. */
PETSC_EXTERN PetscErrorCode PffParticlesReset(PffParticles p);
/* Removes the particles flagged PFF_PARTICLE_FLAG_REMOVE (keeps the order of the others; binned particles
   stay binned, with their bins shrunk). Not collective. */
PETSC_EXTERN PetscErrorCode PffParticlesRemove(PffParticles p);
/* Gives back memory after many particles were removed: the store's capacity shrinks to an eighth above the count
   and the scratch is freed (it grows again on demand). The particles and their bins are kept. Not collective. */
PETSC_EXTERN PetscErrorCode PffParticlesTrim(PffParticles p);
/* Removes every particle (the store keeps its capacity). Not collective. */
PETSC_EXTERN PetscErrorCode PffParticlesClear(PffParticles p);
/* What one PffParticlesAdaptLevels did, summed over ranks. */
typedef struct {
  PetscInt64 split, children;                   /* particles split, and the children that replaced them */
  PetscInt64 marked, removed;                   /* marked for coarsening (D_p reached the delay), removed of them */
  PetscReal  volumeBefore[PFF_PARTICLE_NTYPES]; /* particle volume per type (sum 8^l_p, in finest cells / 8) */
  PetscReal  volumeAfter[PFF_PARTICLE_NTYPES];
} PffParticleAdaptStats;

/* The deferred-coarsening counters of particle adaptivity (PF-FLIP Sec. 5.1). wish[i] is the level the
   refinement criterion asks of local particle i (clamped to the grid's levels): where wish > l_p the
   counter D_p grows by one (it saturates at 15), elsewhere it returns to 0. On return wish[i] is the level
   the particle holds the grid at (Sec. 5.4 step 1): l_p while its coarsening is pending (wish > l_p and
   D_p < delay), its wish otherwise, so that a block coarsens only after its particles asked for it delay
   times in a row. Not collective. */
PETSC_EXTERN PetscErrorCode PffParticlesAdaptCounters(PffParticles p, int8_t wish[], PetscInt delay);
/* Particle adaptivity (PF-FLIP Sec. 5.1 and Sec. 5.4 step 6). target[i] is the level local particle i is
   to take (clamped to the grid's levels), D_p the counter of PffParticlesAdaptCounters.
   - target < l_p: the particle splits into 8^(l_p - target) children of level target with its velocity
     and type, so mass and momentum are exact. The splitting particles of one cell C of level l_p share
     C's finer sub-cells (docs/particles.md, "Adaptive particles"), so a split leaves no finer cell empty.
   - target > l_p and D_p >= delay: the particle is removed with probability 1 - 8^-(target - l_p), and
     otherwise takes level target (and the volume of the removed ones: mass is conserved in expectation)
     with D_p = 0. With D_p < delay it stays as it is.
   The randomness is the counter-based RNG keyed by (seed, id, purpose, key): pass the step number as key,
   so that the result is the same on any number of ranks and threads. Children get ids hashed from their
   parent's with the top bit set (unique with probability 1 - n^2 2^-64). Particles stay in their blocks;
   the store must be binned on the current grid and is binned again. Collective (the statistics). */
PETSC_EXTERN PetscErrorCode PffParticlesAdaptLevels(PffParticles p, const int8_t target[], PetscInt delay, uint64_t key,
                                                    PffParticleAdaptStats *stats);
/* Global count and mass per type (mass = density[type] * particle volume). Collective. */
PETSC_EXTERN PetscErrorCode PffParticlesGetTotals(PffParticles p, const PetscReal density[PFF_PARTICLE_NTYPES],
                                                  PetscInt64 count[PFF_PARTICLE_NTYPES],
                                                  PetscReal  mass[PFF_PARTICLE_NTYPES]);

/* rho~_0: the kernel-weight sum at a face for the perfectly uniform lattice of 8 particles per cell
   of unit volume (Eq. 7), for a particle at the grid's level. Computed once, independent of h. */
PETSC_EXTERN PetscErrorCode PffParticlesGetKernelSum(PffParticles p, PetscReal *rho0);

/* P2G (Eq. 3-6): zeroes the face channels chMass and chMom and accumulates
     chMass[f] = sum_p w_fp m_p / 8^l_f,   chMom[f] = sum_p w_fp m_p v_p,d / 8^l_f
   with w the cubic-in-r^2 kernel (Eq. 6) of radius r_p = h of the block the particle lies in, m_p =
   density[type] * V_p and l_f the level of the face's block, so that a uniform lattice of one type
   gives chMass = density * rho~_0 at every level. chVolume (a face channel, or -1) receives the
   type-blind particle volume sum_p t_fp V_p / 8^l_f with the trilinear weight t_fp of the same 2 x 2 x 2
   faces (a partition of unity: its expectation is the same for a lattice and for randomly placed
   particles, which Eq. 6's kernel sum is not, by 1.7 %), for the liquid model's volume correction (docs/tallcell.md;
   the two-phase model measures on the cell centres, PffParticlesSplatVolume). Splatting is
   lock-free by 8-colour blocks (OpenMP); contributions to ghost faces are summed into their owners by the reverse halo.
   Collective. */
PETSC_EXTERN PetscErrorCode PffParticlesP2G(PffParticles p, const PetscReal density[PFF_PARTICLE_NTYPES],
                                            PetscInt chMass, PetscInt chMom, PetscInt chVolume);

/* Zeroes the cell channel chVolume (one component, halo width >= 1) and accumulates the particles' volume on the cell
   centres, chVolume[c] = sum_p t_cp 8^l_p: t_cp the trilinear weight of cell centre c of the lattice of the block the
   particle lies in, 8^l_p its volume in level-0 particles. Absolute volumes, so the reverse halo's conservative
   cross-level transfer keeps each particle's volume whole across level boundaries (walls drop what lies beyond them).
   The measure of the two-phase volume correction (docs/flow.md). Lock-free by 8-colour blocks (OpenMP). Collective. */
PETSC_EXTERN PetscErrorCode PffParticlesSplatVolume(PffParticles p, PetscInt chVolume);

/* Trilinear interpolation of cell channel ch (ghosts current) at every particle, in float: fn receives
   the values of particles [i0, i0 + m) of one block and may change their words (for example flag
   them). fn runs in OpenMP threads, several calls at once, each on its own particles: it must be
   thread-safe (shared counters need atomics). In a block whose cells and ghost layer hold one value c, every
   particle gets c exactly (the interpolation would round it by a few 1e-8). Not collective. */
typedef void (*PffParticleCellFn)(PetscInt i0, PetscInt m, const float val[], void *ctx);
PETSC_EXTERN PetscErrorCode PffParticlesInterpolateCell(PffParticles p, PetscInt ch, PffParticleCellFn fn, void *ctx);

/* G2P (Eq. 12): v_p <- alpha (v_p + I(du, x_p)) + (1 - alpha) I(u, x_p) with
   alpha = alpha[type * nlevels + level of the block containing p]. Ghosts of chU and chDU must be
   current. Not collective. */
PETSC_EXTERN PetscErrorCode PffParticlesG2P(PffParticles p, PetscInt chU, PetscInt chDU, const PetscReal alpha[]);

/* Advection through the face velocity channel chU (ghosts current, halo width >= 2) over dt with
   third-order Runge-Kutta, each particle taking its own sub-steps so that no stage moves it more than
   -particles_substep_cfl cells; velocity samples may reach into the halo of the particle's block.
   Afterwards particles inside a solid (solid != NULL) are pushed out along the distance gradient,
   and the particles are migrated. Collective. */
PETSC_EXTERN PetscErrorCode PffParticlesAdvect(PffParticles p, PetscInt chU, PetscReal dt, PffSolidFn solid,
                                               void *solidctx, PffParticleStats *stats);
/* As PffParticlesAdvect, but particles of type t sample chU[t] (PF-FLIP Sec. 3.7: liquid particles move
   with the liquid velocity extrapolated into the air). Samples reach as far as the narrower of the two
   halos allows. Collective. */
PETSC_EXTERN PetscErrorCode PffParticlesAdvectPerType(PffParticles p, const PetscInt chU[PFF_PARTICLE_NTYPES],
                                                      PetscReal dt, PffSolidFn solid, void *solidctx,
                                                      PffParticleStats *stats);

/* Appends m particles anywhere in the domain, ids chosen by the caller, from world positions (rounded to
   the store's float grid units; a position the store wrote comes back exactly) and velocities; flags
   (the files' byte, PffParticleFlagsByte: flags in bits 0-3, D_p in bits 4-7) may be NULL; id may be NULL (0,
   for a caller that fills the fields of PffParticlesGetFileFields itself, as the files' reader does). Call
   PffParticlesMigrate next to send them to their owners and bin them. For restart and tests. Not collective. */
PETSC_EXTERN PetscErrorCode PffParticlesAdd(PffParticles p, PetscInt m, const PetscReal x[], const PetscReal v[],
                                            const uint64_t id[], const uint8_t type[], const int8_t level[],
                                            const uint8_t flags[]);

/* The per-particle fields that frames and checkpoints store by themselves, one dataset /particles/<name> each
   (the field list of src/particles/particlesimpl.h, entries marked FILE; the others have their own code in
   src/io/particles.c). A field added to the list with FILE is written, checked and read back with no change to
   the files' code. */
typedef enum {
  PFF_FIELD_FLOAT,
  PFF_FIELD_DOUBLE,
  PFF_FIELD_INT32,
  PFF_FIELD_UINT32,
  PFF_FIELD_INT64,
  PFF_FIELD_UINT64
} PffFieldType;
typedef struct {
  const char  *name;
  PetscInt     ncomp; /* values per particle */
  PffFieldType type;
  size_t       size; /* bytes per value */
} PffParticleFieldInfo;
/* With info NULL: *n = the number of such fields; otherwise *n is the room in info on entry and the number on exit. */
PETSC_EXTERN PetscErrorCode PffParticlesGetFileFields(PetscInt *n, PffParticleFieldInfo info[]);
/* The store's array of field name (particle i at [ncomp i, ncomp i + ncomp)); valid until the store changes. */
PETSC_EXTERN PetscErrorCode PffParticlesGetFieldArray(PffParticles p, const char name[], void **data);
