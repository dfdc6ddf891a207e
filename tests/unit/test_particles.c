/* Unit test of particle seeding, binning and migration at any rank count.

   Seeding: a graded 2-level raster (n0 = 8, periodic in x, walls elsewhere). The seeding function
   returns no particle inside a box aligned with level-1 cells, liquid below a plane y = y0 (aligned
   with level-1 cells) and air above, and v = x. Expected per-type counts and the sum and xor of
   hash(id) are computed from the raster alone (every cell holds 8 candidates at its block's level);
   every particle must lie inside the sub-cell its id names, and in the block its bin names. The
   checksum sum hash(id) * round(x / h0 * 2^20) (integer arithmetic, order independent) is printed
   and must be the same on any number of ranks.

   Migration: every particle is displaced by a random offset (keyed by id) of up to a block length per
   axis, then migrated: count, mass per type and the id multiset are unchanged, every particle lies in
   an owned block and in its bin, and the numbers wrapped and clamped (partition independent) match
   a recount from the displaced positions.

   Band: seeded again with -particles_jitter_band 2 (the default), 1 and 0, and with the plane tilted by 0.3 at
   band 2. A cell is in the band when the particle types (liquid, air) at the lattice sub-cells of the cells within
   r cells of it (at its own level; periodic axes wrapped, points beyond a wall ignored) differ and none of those
   sub-cells is crossed by the plane; this is recomputed here point by point. Every particle of a band cell must
   sit at its sub-cell centre, and no particle of another cell may (the jitter puts it there with probability 0);
   the level plane has band cells, band 0 none.

   Sample run:  mpiexec -n 4 ./test_particles
   Prints the same lines on any number of ranks. */
#include "pfftest.h"

static const char help[] = "Particle seeding, binning and migration.\n";

#define N0 8

typedef struct {
  PetscReal holeLo[3], holeHi[3], y0, tilt; /* liquid below y0 + tilt (x - holeLo[0]) */
} SeedCtx;

static PetscErrorCode SeedFn(const PetscReal x[3], PetscInt *type, PetscReal v[3], void *ctx)
{
  const SeedCtx *s = (const SeedCtx *)ctx;

  PetscFunctionBeginUser;
  PetscBool in = PETSC_TRUE;
  for (int a = 0; a < 3; a++) in = (PetscBool)(in && x[a] >= s->holeLo[a] && x[a] < s->holeHi[a]);
  *type = in ? -1 : (x[1] < s->y0 + s->tilt * (x[0] - s->holeLo[0]) ? PFF_PARTICLE_LIQUID : PFF_PARTICLE_AIR);
  for (int a = 0; a < 3; a++) v[a] = x[a];
  PetscFunctionReturn(PETSC_SUCCESS);
}

typedef struct {
  PetscInt64 count[PFF_PARTICLE_NTYPES];
  uint64_t   idsum, idxor, check;
} Summary;

static PetscErrorCode Summarise(PffParticles part, const PffTestCtx *ctx, Summary *s)
{
  PffParticleArrays a;
  uint64_t          loc[2] = {0, 0}, chk = 0;
  const PetscReal   q = 1048576.0;

  PetscFunctionBeginUser;
  PetscCall(PffParticlesGetArrays(part, &a));
  PetscCall(PffParticlesGetTotals(part, NULL, s->count, NULL));
  for (PetscInt i = 0; i < a.n; i++) {
    const uint64_t h = PffTestHash64(a.id[i]);
    loc[0] += h;
    loc[1] ^= h;
    for (int d = 0; d < 3; d++)
      chk +=
          PffTestHash64(a.id[i] + (uint64_t)d) * (uint64_t)(int64_t)PetscFloorReal((PetscReal)a.x[3 * i + d] * q + 0.5);
  }
  PetscCallMPI(MPI_Allreduce(&loc[0], &s->idsum, 1, MPI_UINT64_T, MPI_SUM, ctx->comm));
  PetscCallMPI(MPI_Allreduce(&loc[1], &s->idxor, 1, MPI_UINT64_T, MPI_BXOR, ctx->comm));
  PetscCallMPI(MPI_Allreduce(&chk, &s->check, 1, MPI_UINT64_T, MPI_SUM, ctx->comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Every particle lies in an owned block, the one its bin names. */
static PetscErrorCode CheckBins(PffParticles part, const PffTestCtx *ctx)
{
  PffParticleArrays a;

  PetscFunctionBeginUser;
  PetscCall(PffParticlesGetArrays(part, &a));
  PetscCheck(a.start != NULL && a.start[0] == 0 && a.start[ctx->nlocal] == a.n, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "bins do not cover the %" PetscInt_FMT " particles", a.n);
  for (PetscInt lb = 0; lb < ctx->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(ctx->grid, lb, &info));
    for (PetscInt i = a.start[lb]; i < a.start[lb + 1]; i++) {
      PetscInt  gid;
      PetscReal x[3];
      PffParticleArraysWorld(&a, i, x);
      PetscCall(PffGridLocate(ctx->grid, x, &gid, NULL, NULL));
      PetscCheck(gid == info.gid, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                 "particle %" PetscInt64_FMT " at (%g, %g, %g) is in block %" PetscInt_FMT ", binned in %" PetscInt_FMT,
                 (PetscInt64)a.id[i], (double)x[0], (double)x[1], (double)x[2], gid, info.gid);
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The lattice place a seeded particle's id names: raster block gid, its level l, the block's raster index ijk, the cell
   cc at level l and the sub-cell sub (bit a: upper half along axis a) */
typedef struct {
  PetscInt gid, l, ijk[3], cc[3], sub;
} IdPlace;

static IdPlace PlaceOf(const PffTestCtx *ctx, uint64_t id)
{
  const uint64_t c = (id / 8) % (N0 * N0 * N0);
  IdPlace        q;

  q.sub            = (PetscInt)(id % 8);
  q.gid            = (PetscInt)(id / 8 / (N0 * N0 * N0));
  q.l              = ctx->level[q.gid];
  q.ijk[0]         = q.gid % ctx->nb[0];
  q.ijk[1]         = (q.gid / ctx->nb[0]) % ctx->nb[1];
  q.ijk[2]         = q.gid / (ctx->nb[0] * ctx->nb[1]);
  const uint64_t n = (uint64_t)(N0 >> q.l);
  q.cc[0]          = (PetscInt)(c % n);
  q.cc[1]          = (PetscInt)((c / n) % n);
  q.cc[2]          = (PetscInt)(c / (n * n));
  return q;
}

static PetscErrorCode TestSeed(const PffTestCtx *ctx, const SeedCtx *sc, PffParticles part, Summary *got)
{
  PetscInt64 expect[PFF_PARTICLE_NTYPES] = {0, 0};
  uint64_t   idsum = 0, idxor = 0;

  PetscFunctionBeginUser;
  /* the expectation from the raster alone: every cell centre decides for its 8 candidates */
  for (PetscInt gid = 0; gid < ctx->nblocks; gid++) {
    const PetscInt l = ctx->level[gid];
    if (l < 0) continue;
    const PetscInt n      = N0 >> l,
                   ijk[3] = {gid % ctx->nb[0], (gid / ctx->nb[0]) % ctx->nb[1], gid / (ctx->nb[0] * ctx->nb[1])};
    const PetscReal h     = ctx->h0 * (PetscReal)(1 << l);
    for (PetscInt c = 0; c < n * n * n; c++) {
      const PetscInt cc[3] = {c % n, (c / n) % n, c / (n * n)};
      PetscReal      x[3], v[3];
      PetscInt       type;
      for (int a = 0; a < 3; a++)
        x[a] = ctx->origin[a] + (PetscReal)(ijk[a] * N0) * ctx->h0 + ((PetscReal)cc[a] + 0.5) * h;
      PetscCall(SeedFn(x, &type, v, (void *)sc));
      if (type < 0) continue;
      expect[type] += 8;
      for (uint64_t s = 0; s < 8; s++) {
        const uint64_t h64 = PffTestHash64(((uint64_t)gid * N0 * N0 * N0 + (uint64_t)c) * 8 + s);
        idsum += h64;
        idxor ^= h64;
      }
    }
  }
  PetscCall(PffParticlesSeed(part, SeedFn, (void *)sc));
  PetscCall(Summarise(part, ctx, got));
  PetscCheck(got->count[0] == expect[0] && got->count[1] == expect[1], ctx->comm, PETSC_ERR_PLIB,
             "seeded %" PetscInt64_FMT " liquid and %" PetscInt64_FMT " air particles, expected %" PetscInt64_FMT
             " and %" PetscInt64_FMT,
             got->count[0], got->count[1], expect[0], expect[1]);
  PetscCheck(got->idsum == idsum && got->idxor == idxor, ctx->comm, PETSC_ERR_PLIB,
             "seeded ids differ from the raster's");
  /* each particle inside the sub-cell its id names */
  PffParticleArrays a;
  PetscCall(PffParticlesGetArrays(part, &a));
  for (PetscInt i = 0; i < a.n; i++) {
    const IdPlace   pl = PlaceOf(ctx, a.id[i]);
    const PetscInt  l = pl.l, sub = pl.sub, *ijk = pl.ijk, *cc = pl.cc;
    const PetscReal h = (PetscReal)(1 << l); /* grid units */
    PetscReal       x[3];
    PetscCheck(PffParticleWordLevel(a.word[i]) == l, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "particle level %" PetscInt_FMT ", block level %" PetscInt_FMT, PffParticleWordLevel(a.word[i]), l);
    PffParticleArraysWorld(&a, i, x);
    for (int d = 0; d < 3; d++) {
      /* the float store rounds by at most cells 2^-24 grid units */
      const PetscReal lo  = (PetscReal)(ijk[d] * N0) + ((PetscReal)cc[d] + 0.5 * (PetscReal)((sub >> d) & 1)) * h,
                      eps = 1e-5;
      PetscCheck(a.x[3 * i + d] >= lo - eps && a.x[3 * i + d] <= lo + 0.5 * h + eps, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                 "particle %" PetscInt64_FMT " lies outside its sub-cell along axis %d", (PetscInt64)a.id[i], d);
      /* and strictly inside its cell: rounding must not carry it into the next one */
      const PetscReal cell = (PetscReal)(ijk[d] * N0) + (PetscReal)cc[d] * h;
      PetscCheck(a.x[3 * i + d] >= cell && a.x[3 * i + d] < cell + h, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                 "particle %" PetscInt64_FMT " left its cell along axis %d", (PetscInt64)a.id[i], d);
      /* the callback saw the world point of the stored position (to the rounding of v to float; the
         compiler may fuse origin + h0 g differently in the library and here) */
      PetscCheck(PetscAbsReal(a.v[3 * i + d] - x[d]) <= 1e-7 * (PetscAbsReal(x[d]) + 1), PETSC_COMM_SELF,
                 PETSC_ERR_PLIB, "seeded velocity is not the callback's");
    }
  }
  PetscCall(CheckBins(part, ctx));
  PetscCall(PetscPrintf(ctx->comm,
                        "seed: %" PetscInt64_FMT " liquid %" PetscInt64_FMT " air (as expected), ids ok, sub-cells ok, "
                        "checksum %016" PRIx64 "\n",
                        got->count[0], got->count[1], got->check));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode TestMigrate(const PffTestCtx *ctx, PffParticles part, const Summary *before)
{
  const PetscReal   density[2] = {1000, 1.25};
  PetscReal         m0[2], m1[2];
  PffParticleArrays a;
  PffParticleStats  st;
  PetscInt64        exp[2] = {0, 0}; /* wrapped, clamped */
  Summary           after;

  PetscFunctionBeginUser;
  PetscCall(PffParticlesGetTotals(part, density, NULL, m0));
  PetscCall(PffParticlesGetArrays(part, &a));
  for (PetscInt i = 0; i < a.n; i++) {
    PetscBool w = PETSC_FALSE, c = PETSC_FALSE;
    for (int d = 0; d < 3; d++) {
      const uint64_t  h = PffTestKey(7, a.id[i], (uint64_t)d, 0);
      const PetscReal u = (PetscReal)(h >> 11) / 9007199254740992.0;
      a.x[3 * i + d] += (float)((2 * u - 1) * ctx->blen / ctx->h0);
      const PetscReal L = ctx->blen / ctx->h0 * (PetscReal)ctx->nb[d], s = a.x[3 * i + d]; /* grid units */
      if (s < 0 || s >= L) {
        if (ctx->periodic[d])
          w = PETSC_TRUE;
        else
          c = PETSC_TRUE;
      }
    }
    exp[0] += w;
    exp[1] += c;
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, exp, 2, MPIU_INT64, MPI_SUM, ctx->comm));
  PetscCall(PffParticlesMigrate(part, &st));
  PetscCall(PffParticlesGetTotals(part, density, NULL, m1));
  PetscCall(Summarise(part, ctx, &after));
  PetscCheck(after.count[0] == before->count[0] && after.count[1] == before->count[1], ctx->comm, PETSC_ERR_PLIB,
             "migration changed the counts: %" PetscInt64_FMT " %" PetscInt64_FMT " -> %" PetscInt64_FMT
             " %" PetscInt64_FMT,
             before->count[0], before->count[1], after.count[0], after.count[1]);
  PetscCheck(after.idsum == before->idsum && after.idxor == before->idxor, ctx->comm, PETSC_ERR_PLIB,
             "migration changed the id multiset");
  PetscCheck(m0[0] == m1[0] && m0[1] == m1[1], ctx->comm, PETSC_ERR_PLIB, "migration changed the mass");
  PetscCheck(st.wrapped == exp[0] && st.clamped == exp[1], ctx->comm, PETSC_ERR_PLIB,
             "migration wrapped %" PetscInt64_FMT " and clamped %" PetscInt64_FMT ", expected %" PetscInt64_FMT
             " and %" PetscInt64_FMT,
             st.wrapped, st.clamped, exp[0], exp[1]);
  PetscCall(CheckBins(part, ctx));
  PetscCall(PetscPrintf(ctx->comm,
                        "migrate: counts, mass and ids kept, %" PetscInt64_FMT " wrapped, %" PetscInt64_FMT
                        " clamped, all in owned bins\n",
                        st.wrapped, st.clamped));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The seeding function's particle type at grid position g (level-0 cells), -1 outside the walls (y, z) */
static PetscErrorCode TypeAtGrid(const PffTestCtx *ctx, const SeedCtx *sc, PetscReal g[3], PetscInt *type)
{
  PetscReal x[3], v[3];

  PetscFunctionBeginUser;
  *type = -1;
  for (int a = 0; a < 3; a++) {
    const PetscReal len = (PetscReal)(ctx->nb[a] * N0);
    if (a == 0)
      g[a] = g[a] < 0 ? g[a] + len : g[a] >= len ? g[a] - len : g[a]; /* periodic in x */
    else if (g[a] < 0 || g[a] >= len)
      PetscFunctionReturn(PETSC_SUCCESS);
    x[a] = ctx->origin[a] + ctx->h0 * g[a];
  }
  PetscCall(SeedFn(x, type, v, (void *)sc));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Whether cell cc of raster block gid is in the band of r cells: the particle types (liquid, air; no particle does
   not count) at the sub-cell centres of the cells within r cells of it (at its own level) differ, and no sub-cell
   there is crossed by a change (a corner of the box its particle may jitter in, 1e-6 inside, has another type) */
static PetscErrorCode BandExpected(const PffTestCtx *ctx, const SeedCtx *sc, PetscInt gid, const PetscInt cc[3],
                                   PetscInt r, PetscBool *band)
{
  const PetscInt  l = ctx->level[gid], w = 2 * r + 1;
  const PetscInt  ijk[3] = {gid % ctx->nb[0], (gid / ctx->nb[0]) % ctx->nb[1], gid / (ctx->nb[0] * ctx->nb[1])};
  const PetscReal h      = (PetscReal)(1 << l); /* grid units */
  PetscInt        lo = PFF_PARTICLE_NTYPES, hi = -1;
  PetscBool       crossed = PETSC_FALSE;

  PetscFunctionBeginUser;
  for (PetscInt q = 0; q < 8 * w * w * w; q++) {
    const PetscInt off[3] = {(q / 8) % w - r, (q / 8 / w) % w - r, q / 8 / (w * w) - r};
    PetscReal      centre[3];
    PetscInt       type, clo = PFF_PARTICLE_NTYPES, chi = -1;
    for (int a = 0; a < 3; a++)
      centre[a] = (PetscReal)(ijk[a] * N0) + ((PetscReal)(cc[a] + off[a]) + 0.25 + 0.5 * (PetscReal)((q >> a) & 1)) * h;
    for (PetscInt corner = -1; corner < 8; corner++) { /* -1: the centre itself */
      PetscReal g[3];
      for (int a = 0; a < 3; a++)
        g[a] = centre[a] + (corner < 0 ? 0 : ((corner >> a) & 1 ? 0.25 : -0.25) * (1 - 1e-6) * h);
      PetscCall(TypeAtGrid(ctx, sc, g, &type));
      if (type < 0) continue;
      if (corner < 0) {
        lo = PetscMin(lo, type);
        hi = PetscMax(hi, type);
      }
      clo = PetscMin(clo, type);
      chi = PetscMax(chi, type);
    }
    crossed = (PetscBool)(crossed || chi > clo);
  }
  *band = (PetscBool)(hi > lo && !crossed);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Particles on the lattice inside and outside the band cells, with -particles_jitter_band r; some: the band must
   hold particles */
static PetscErrorCode TestBand(const PffTestCtx *ctx, const SeedCtx *sc, PetscInt r, PetscBool some)
{
  PffParticles      part;
  PffParticleArrays a;
  PetscBool        *band;
  char              val[8];
  PetscInt64        n[4] = {0, 0, 0, 0}; /* band: on lattice, off; other: on, off */

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(val, sizeof(val), "%" PetscInt_FMT, r));
  PetscCall(PetscOptionsSetValue(NULL, "-particles_jitter_band", val));
  PetscCall(PffParticlesCreate(ctx->grid, &part));
  PetscCall(PffParticlesSetFromOptions(part));
  PetscCall(PetscOptionsClearValue(NULL, "-particles_jitter_band"));
  PetscCall(PffParticlesSeed(part, SeedFn, (void *)sc));
  PetscCall(PetscMalloc1(ctx->nblocks * N0 * N0 * N0, &band));
  for (PetscInt gid = 0; gid < ctx->nblocks; gid++) {
    const PetscInt l = ctx->level[gid], nn = N0 >> l;
    if (l < 0) continue;
    for (PetscInt c = 0; c < nn * nn * nn; c++) {
      const PetscInt cc[3] = {c % nn, (c / nn) % nn, c / (nn * nn)};
      PetscCall(BandExpected(ctx, sc, gid, cc, r, &band[gid * N0 * N0 * N0 + c]));
    }
  }
  PetscCall(PffParticlesGetArrays(part, &a));
  for (PetscInt i = 0; i < a.n; i++) {
    const IdPlace pl = PlaceOf(ctx, a.id[i]);
    PetscBool     on = PETSC_TRUE;
    for (int d = 0; d < 3; d++) {
      const PetscReal centre =
          (PetscReal)(pl.ijk[d] * N0) +
          ((PetscReal)pl.cc[d] + 0.25 + 0.5 * (PetscReal)((pl.sub >> d) & 1)) * (PetscReal)(1 << pl.l);
      on = (PetscBool)(on && PetscAbsReal(a.x[3 * i + d] - centre) < 1e-5);
    }
    const PetscInt c = pl.cc[0] + (N0 >> pl.l) * (pl.cc[1] + (N0 >> pl.l) * pl.cc[2]);
    n[(band[pl.gid * N0 * N0 * N0 + c] ? 0 : 2) + (on ? 0 : 1)]++;
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, n, 4, MPIU_INT64, MPI_SUM, ctx->comm));
  PetscCheck(n[1] == 0 && n[2] == 0, ctx->comm, PETSC_ERR_PLIB,
             "band %" PetscInt_FMT ": %" PetscInt64_FMT " particles of band cells off the lattice, %" PetscInt64_FMT
             " of other cells on it",
             r, n[1], n[2]);
  PetscCheck(n[3] > 0 && (!some || n[0] > 0) && (r > 0 || n[0] == 0), ctx->comm, PETSC_ERR_PLIB,
             "band %" PetscInt_FMT ": no cells %s the band", r, n[3] == 0 ? "outside" : "in");
  PetscCall(PetscPrintf(ctx->comm,
                        "band %" PetscInt_FMT ": %" PetscInt64_FMT
                        " particles on the lattice (band cells), %" PetscInt64_FMT " jittered\n",
                        r, n[0], n[3]));
  PetscCall(PetscFree(band));
  PetscCall(PffParticlesDestroy(&part));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Bad options are rejected with the key in the message. */
static PetscErrorCode TestOptions(const PffTestCtx *ctx)
{
  const char *bad[][2] = {
      {"-particles_jitter", "2"}, {"-particles_jitter_band", "9"}, {"-particles_jitter_band", "-1"}};

  PetscFunctionBeginUser;
  for (size_t q = 0; q < sizeof(bad) / sizeof(bad[0]); q++) {
    PffParticles   part;
    PetscErrorCode ierr;
    PetscCall(PffParticlesCreate(ctx->grid, &part));
    PetscCall(PetscOptionsSetValue(NULL, bad[q][0], bad[q][1]));
    PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
    ierr = PffParticlesSetFromOptions(part);
    PetscCall(PetscPopErrorHandler());
    PetscCall(PetscOptionsClearValue(NULL, bad[q][0]));
    PetscCheck(ierr != 0, ctx->comm, PETSC_ERR_PLIB, "%s %s was accepted", bad[q][0], bad[q][1]);
    PetscCall(PffParticlesDestroy(&part));
    PetscCall(PetscPrintf(ctx->comm, "options: %s %s rejected\n", bad[q][0], bad[q][1]));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  const PetscInt  nb[3]       = {3, 2, 2};
  const PetscBool periodic[3] = {PETSC_TRUE, PETSC_FALSE, PETSC_FALSE};
  const PetscReal origin[3]   = {0.375, -1.25, 0.5};
  PffTestCtx      ctx;
  PffParticles    part;
  Summary         s;

  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(PffInitializePackage());
  PetscCall(PffTestCreateGrid(PETSC_COMM_WORLD, nb, periodic, origin, 1.0 / 16, N0, 2, -1, 0, 11, &ctx));
  /* aligned with level-1 cells (2 h0) */
  SeedCtx sc     = {{origin[0] + 4 * ctx.h0, origin[1] + 6 * ctx.h0, origin[2] + 2 * ctx.h0},
                    {origin[0] + 14 * ctx.h0, origin[1] + 12 * ctx.h0, origin[2] + 10 * ctx.h0},
                    origin[1] + 10 * ctx.h0,
                    0};
  SeedCtx tilted = sc;
  tilted.tilt    = 0.3;
  PetscCall(TestOptions(&ctx));
  PetscCall(PffParticlesCreate(ctx.grid, &part));
  PetscCall(PffParticlesSetFromOptions(part));
  PetscCall(TestSeed(&ctx, &sc, part, &s));
  PetscCall(TestMigrate(&ctx, part, &s));
  PetscCall(PffParticlesDestroy(&part));
  PetscCall(TestBand(&ctx, &sc, 2, PETSC_TRUE));
  PetscCall(TestBand(&ctx, &sc, 1, PETSC_TRUE));
  PetscCall(TestBand(&ctx, &sc, 0, PETSC_FALSE));
  PetscCall(TestBand(&ctx, &tilted, 2, PETSC_FALSE));
  PetscCall(PffGridDestroy(&ctx.grid));
  PetscCall(PetscFinalize());
  return 0;
}
