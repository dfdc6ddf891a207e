/* Unit test of P2G, G2P and advection at any rank count.

   Kernel sum: an unjittered lattice of one type (density rho) in a fully periodic domain gives
   chMass = rho * rho~_0 on every face to 1e-5 relative, on a uniform grid and on a graded 2-level
   grid at faces more than 2 cells from a level boundary (the maximum deviation at level boundaries
   is printed, not asserted: the cross-level normalisation is approximate, see src/particles/p2g.c).
   Against the definition: mass, momentum and volume of jittered particles of both types on a uniform periodic
   grid agree with a sum over all particles in double, face by face, to 1e-5 of each channel's largest value.
   Constant velocity: v_p = (1, -2, 0.5), P2G, u = mom / mass, du = 0, G2P with alpha 0 and 1 gives
   v_p = (1, -2, 0.5) to 1e-6, on the 2-level periodic grid and on a grid walled in z (the test owns
   the wall ghost faces and sets them to the constant, as boundary conditions would).
   Advection: a uniform field moving 2.5 cells per step (3 sub-steps, particle by particle) and 0.4
   cells per step (one sub-step, the vectorised chunks of whole blocks) in a periodic domain (velocity
   channel of width 4) moves every particle by u t (mod period) to 1e-6 of the domain size (float store)
   after 4 steps, and with one field per particle type (PffParticlesAdvectPerType) each type by its own
   u t; a rigid
   rotation in a walled box keeps every particle inside and the count; zero velocity with a sphere
   solid leaves no particle inside the sphere, and pushed equals the number that were inside.
   Cell values at the particles (PffParticlesInterpolateCell, float tiles in threads) agree with
   PffGridInterpolate to 2e-6 on a graded periodic grid and on walled ones, also where a plateau makes whole tiles
   one value (passed without interpolating), and the callback sees every particle once. Beside walls (whose ghosts hold
   junk that the grid's general path, clamping there, never reads): G2P with alpha 0 agrees with PffGridInterpolate to
   2e-6 relative, and a uniform field along the walls moves every particle by u t to 1e-6 of the box, on 1 and 2 levels.

   Sample run:  mpiexec -n 4 ./test_particles_transfer
   Prints the same lines on any number of ranks. */
#include "pfftest.h"

static const char help[] = "P2G kernel sum, P2G -> G2P, advection and solid push-out.\n";

#define N0 8

static const PetscReal V0[3] = {1.0, -2.0, 0.5};

static PetscErrorCode SeedLiquid(const PetscReal x[3], PetscInt *type, PetscReal v[3], void *ctx)
{
  PetscFunctionBeginUser;
  (void)ctx;
  *type = PFF_PARTICLE_LIQUID;
  for (int a = 0; a < 3; a++) v[a] = V0[a];
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* v = x: the seeding position travels with the particle */
static PetscErrorCode SeedRemember(const PetscReal x[3], PetscInt *type, PetscReal v[3], void *ctx)
{
  PetscFunctionBeginUser;
  (void)ctx;
  *type = PFF_PARTICLE_LIQUID;
  for (int a = 0; a < 3; a++) v[a] = x[a];
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* v = x as SeedRemember; liquid where x < 0.5, air elsewhere */
static PetscErrorCode SeedRememberMixed(const PetscReal x[3], PetscInt *type, PetscReal v[3], void *ctx)
{
  PetscFunctionBeginUser;
  PetscCall(SeedRemember(x, type, v, ctx));
  if (x[0] >= 0.5) *type = PFF_PARTICLE_AIR;
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode CreateParticles(PffTestCtx *ctx, const char jitter[], PffSeedFn fn, PffParticles *part)
{
  PetscFunctionBeginUser;
  PetscCall(PetscOptionsSetValue(NULL, "-particles_jitter", jitter));
  PetscCall(PffParticlesCreate(ctx->grid, part));
  PetscCall(PffParticlesSetFromOptions(*part));
  PetscCall(PetscOptionsClearValue(NULL, "-particles_jitter"));
  PetscCall(PffParticlesSeed(*part, fn, NULL));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode TestKernelSum(PetscInt nlevels, PetscInt uniform)
{
  const PetscInt  nb[3]       = {3, 2, 2};
  const PetscBool periodic[3] = {PETSC_TRUE, PETSC_TRUE, PETSC_TRUE};
  const PetscReal origin[3] = {0, 0, 0}, density[2] = {3.0, 0.5};
  PffTestCtx      ctx;
  PffParticles    part;
  PetscInt        chMass, chMom;
  PetscReal       rho0, err[2] = {0, 0}; /* away from, at level boundaries */

  PetscFunctionBeginUser;
  PetscCall(PffTestCreateGrid(PETSC_COMM_WORLD, nb, periodic, origin, 1.0 / 16, N0, nlevels, uniform, 0, 5, &ctx));
  PetscCall(PffGridAddChannel(ctx.grid, "mass", PFF_CHANNEL_FACE, 1, &chMass));
  PetscCall(PffGridAddChannel(ctx.grid, "mom", PFF_CHANNEL_FACE, 1, &chMom));
  PetscCall(CreateParticles(&ctx, "0", SeedLiquid, &part));
  PetscCall(PffParticlesGetKernelSum(part, &rho0));
  PetscCall(PffParticlesP2G(part, density, chMass, chMom, -1));
  for (PetscInt lb = 0; lb < ctx.nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(ctx.grid, lb, &info));
    const PetscInt n = info.n;
    for (PetscInt comp = 0; comp < 3; comp++) {
      float *m, *mom;
      PetscCall(PffGridGetBlockData(ctx.grid, chMass, lb, comp, &m));
      PetscCall(PffGridGetBlockData(ctx.grid, chMom, lb, comp, &mom));
      for (PetscInt c = 0; c < n * n * n; c++) {
        const PetscInt  cc[3] = {c % n, (c / n) % n, c / (n * n)};
        const PetscReal e     = PetscAbsReal((PetscReal)m[c] / (density[0] * rho0) - 1);
        const int       at    = PffTestAwayFromLevelJumps(&ctx, &info, cc, 2) ? 0 : 1;
        err[at]               = PetscMax(err[at], e);
        PetscCheck(PetscAbsReal((PetscReal)mom[c] - V0[comp] * (PetscReal)m[c]) <= 1e-5 * PetscAbsReal((PetscReal)m[c]),
                   PETSC_COMM_SELF, PETSC_ERR_PLIB, "momentum is not v * mass at a face");
      }
    }
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, err, 2, MPIU_REAL, MPI_MAX, ctx.comm));
  PetscCheck(err[0] <= 1e-5, ctx.comm, PETSC_ERR_PLIB,
             "P2G mass deviates from density * rho0 by %g (relative) away from level boundaries", (double)err[0]);
  PetscCall(PetscPrintf(ctx.comm,
                        "kernel sum (%" PetscInt_FMT " level%s): rho0 %.6f, max rel. deviation %.1e away from level "
                        "boundaries, %.3f at them\n",
                        nlevels, nlevels > 1 ? "s" : "", (double)rho0, (double)err[0], (double)err[1]));
  PetscCall(PffParticlesDestroy(&part));
  PetscCall(PffGridDestroy(&ctx.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* P2G against its definition, face by face: jittered particles of both types with velocity v = x on a uniform periodic
   grid; every rank sums mass, momentum and volume over all particles in double (Eq. 6's weight for the first two, the
   trilinear one for the volume) and compares the faces it owns, to 1e-5 of the channel's largest value. */
static PetscErrorCode TestSplatReference(void)
{
  const PetscInt    nb[3]       = {3, 2, 2};
  const PetscBool   periodic[3] = {PETSC_TRUE, PETSC_TRUE, PETSC_TRUE};
  const PetscReal   origin[3] = {0, 0, 0}, density[2] = {3.0, 0.5};
  const PetscInt    N[3] = {N0 * nb[0], N0 * nb[1], N0 * nb[2]}, nf = N[0] * N[1] * N[2];
  PffTestCtx        ctx;
  PffParticles      part;
  PffParticleArrays a;
  PetscInt          ch[3];
  PetscMPIInt       size, nloc, *cnt, *displ;
  float            *x, *v;
  uint32_t         *word;
  PetscReal        *ref, scale[3] = {0, 0, 0}, err[3] = {0, 0, 0};

  PetscFunctionBeginUser;
  PetscCall(PffTestCreateGrid(PETSC_COMM_WORLD, nb, periodic, origin, 1.0 / 16, N0, 1, 0, 0, 11, &ctx));
  PetscCall(PffGridAddChannel(ctx.grid, "mass", PFF_CHANNEL_FACE, 1, &ch[0]));
  PetscCall(PffGridAddChannel(ctx.grid, "mom", PFF_CHANNEL_FACE, 1, &ch[1]));
  PetscCall(PffGridAddChannel(ctx.grid, "volume", PFF_CHANNEL_FACE, 1, &ch[2]));
  PetscCall(CreateParticles(&ctx, "1", SeedRememberMixed, &part));
  PetscCall(PffParticlesP2G(part, density, ch[0], ch[1], ch[2]));

  /* every particle on every rank */
  PetscCall(PffParticlesGetArrays(part, &a));
  PetscCallMPI(MPI_Comm_size(ctx.comm, &size));
  PetscCall(PetscMalloc2(size, &cnt, size, &displ));
  PetscCall(PetscMPIIntCast(a.n, &nloc));
  PetscCallMPI(MPI_Allgather(&nloc, 1, MPI_INT, cnt, 1, MPI_INT, ctx.comm));
  PetscInt ntot = 0;
  for (PetscMPIInt r = 0; r < size; r++) {
    displ[r] = (PetscMPIInt)ntot;
    ntot += cnt[r];
  }
  PetscCall(PetscMalloc3(3 * ntot, &x, 3 * ntot, &v, ntot, &word));
  PetscCallMPI(MPI_Allgatherv(a.word, nloc, MPI_UINT32_T, word, cnt, displ, MPI_UINT32_T, ctx.comm));
  for (PetscMPIInt r = 0; r < size; r++) {
    cnt[r] *= 3;
    displ[r] *= 3;
  }
  PetscCallMPI(MPI_Allgatherv(a.x, 3 * nloc, MPI_FLOAT, x, cnt, displ, MPI_FLOAT, ctx.comm));
  PetscCallMPI(MPI_Allgatherv(a.v, 3 * nloc, MPI_FLOAT, v, cnt, displ, MPI_FLOAT, ctx.comm));

  /* the reference: ref[(c * 3 + d) * nf + face], c = mass, momentum, volume */
  PetscCall(PetscCalloc1(9 * nf, &ref));
  for (PetscInt p = 0; p < ntot; p++) {
    const PetscReal rho = density[PffParticleWordType(word[p])];
    for (int d = 0; d < 3; d++) {
      PetscInt  base[3];
      PetscReal t[3];
      for (int ax = 0; ax < 3; ax++) {
        const PetscReal g = (PetscReal)x[3 * p + ax] - (ax == d ? 0 : 0.5);
        base[ax]          = (PetscInt)PetscFloorReal(g);
        t[ax]             = g - (PetscReal)base[ax];
      }
      for (int q = 0; q < 8; q++) {
        PetscReal dist2 = 0, tri = 1;
        PetscInt  f[3];
        for (int ax = 0; ax < 3; ax++) {
          const int       o    = (q >> ax) & 1;
          const PetscReal dist = o ? 1 - t[ax] : t[ax];
          dist2 += dist * dist;
          tri *= 1 - dist;
          f[ax] = ((base[ax] + o) % N[ax] + N[ax]) % N[ax];
        }
        const PetscReal w    = PetscPowReal(PetscMax(1 - dist2, 0), 3);
        const PetscInt  face = f[0] + N[0] * (f[1] + N[1] * f[2]);
        ref[(0 * 3 + d) * nf + face] += w * rho;
        ref[(1 * 3 + d) * nf + face] += w * rho * (PetscReal)v[3 * p + d];
        ref[(2 * 3 + d) * nf + face] += tri;
      }
    }
  }
  for (int c = 0; c < 3; c++)
    for (PetscInt i = 0; i < 3 * nf; i++) scale[c] = PetscMax(scale[c], PetscAbsReal(ref[c * 3 * nf + i]));
  for (PetscInt lb = 0; lb < ctx.nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(ctx.grid, lb, &info));
    const PetscInt n = info.n;
    for (int c = 0; c < 3; c++)
      for (int d = 0; d < 3; d++) {
        float *data;
        PetscCall(PffGridGetBlockData(ctx.grid, ch[c], lb, d, &data));
        for (PetscInt k = 0; k < n; k++)
          for (PetscInt j = 0; j < n; j++)
            for (PetscInt i = 0; i < n; i++) {
              const PetscInt face =
                  (info.ijk[0] * n + i) + N[0] * ((info.ijk[1] * n + j) + N[1] * (info.ijk[2] * n + k));
              err[c] =
                  PetscMax(err[c], PetscAbsReal((PetscReal)data[i + n * (j + n * k)] - ref[(c * 3 + d) * nf + face]));
            }
      }
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, err, 3, MPIU_REAL, MPI_MAX, ctx.comm));
  for (int c = 0; c < 3; c++) err[c] /= scale[c];
  PetscCall(PetscPrintf(ctx.comm,
                        "P2G against its definition (%" PetscInt_FMT " particles): max error relative to the "
                        "largest value: mass %.1e, momentum %.1e, volume %.1e\n",
                        ntot, (double)err[0], (double)err[1], (double)err[2]));
  for (int c = 0; c < 3; c++)
    PetscCheck(err[c] <= 1e-5, ctx.comm, PETSC_ERR_PLIB, "P2G channel %d deviates from its definition by %g", c,
               (double)err[c]);
  PetscCall(PetscFree(ref));
  PetscCall(PetscFree3(x, v, word));
  PetscCall(PetscFree2(cnt, displ));
  PetscCall(PffParticlesDestroy(&part));
  PetscCall(PffGridDestroy(&ctx.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscReal Constant(const PetscReal x[3], PetscInt comp, void *ctx)
{
  (void)x;
  return ((const PetscReal *)ctx)[comp];
}

/* Sets every wall ghost region of a channel to the constant vector val (one value per component). */
static PetscErrorCode FillWallGhosts(const PffTestCtx *ctx, PetscInt ch, const PetscReal val[3])
{
  PetscInt width, ncomp;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetChannelInfo(ctx->grid, ch, NULL, NULL, &ncomp, &width));
  for (PetscInt lb = 0; lb < ctx->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(ctx->grid, lb, &info));
    const PetscInt n = info.n;
    for (PetscInt comp = 0; comp < ncomp; comp++) {
      const PffView *views;
      PetscCall(PffGridGetBlockViews(ctx->grid, ch, lb, comp, &views));
      for (PetscInt k = -width; k < n + width; k++)
        for (PetscInt j = -width; j < n + width; j++)
          for (PetscInt i = -width; i < n + width; i++) {
            const PetscInt r = PffRegionIndex(i, j, k, n);
            PetscInt       d[3];
            PffRegionDirection(r, d);
            if (r != 13 && PffRasterNeighbour(ctx->nb, ctx->periodic, info.ijk, d) < 0)
              *PffViewsAt(views, i, j, k, n) = (float)val[comp];
          }
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode TestConstantVelocity(PetscInt nlevels, PetscBool wallz)
{
  const PetscInt  nb[3]       = {3, 2, 2};
  const PetscBool periodic[3] = {PETSC_TRUE, PETSC_TRUE, (PetscBool)!wallz};
  const PetscReal origin[3] = {-0.5, 0.25, 0}, density[2] = {1000.0, 1.0}, zero[3] = {0, 0, 0};
  PetscReal       alpha[2 * PFF_GRID_MAX_LEVELS], err = 0;
  PffTestCtx      ctx;
  PffParticles    part;
  PetscInt        chMass, chMom, chU, chDU;

  PetscFunctionBeginUser;
  PetscCall(PffTestCreateGrid(PETSC_COMM_WORLD, nb, periodic, origin, 1.0 / 16, N0, nlevels, nlevels > 1 ? -1 : 0, 0, 9,
                              &ctx));
  PetscCall(PffGridAddChannel(ctx.grid, "mass", PFF_CHANNEL_FACE, 1, &chMass));
  PetscCall(PffGridAddChannel(ctx.grid, "mom", PFF_CHANNEL_FACE, 1, &chMom));
  PetscCall(PffGridAddChannel(ctx.grid, "u", PFF_CHANNEL_FACE, 2, &chU));
  PetscCall(PffGridAddChannel(ctx.grid, "du", PFF_CHANNEL_FACE, 2, &chDU));
  PetscCall(CreateParticles(&ctx, "1", SeedLiquid, &part));
  PetscCall(PffParticlesP2G(part, density, chMass, chMom, -1));
  for (PetscInt lb = 0; lb < ctx.nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(ctx.grid, lb, &info));
    for (PetscInt comp = 0; comp < 3; comp++) {
      float *m, *mom, *u;
      PetscCall(PffGridGetBlockData(ctx.grid, chMass, lb, comp, &m));
      PetscCall(PffGridGetBlockData(ctx.grid, chMom, lb, comp, &mom));
      PetscCall(PffGridGetBlockData(ctx.grid, chU, lb, comp, &u));
      for (PetscInt c = 0; c < info.n * info.n * info.n; c++) {
        PetscCheck(m[c] > 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "a face received no mass");
        u[c] = mom[c] / m[c];
      }
    }
  }
  PetscCall(PffGridFillChannel(ctx.grid, chDU, Constant, (void *)zero));
  PetscCall(PffGridHaloBegin(ctx.grid, chU));
  PetscCall(PffGridHaloEnd(ctx.grid, chU));
  PetscCall(PffGridHaloBegin(ctx.grid, chDU));
  PetscCall(PffGridHaloEnd(ctx.grid, chDU));
  if (wallz) PetscCall(FillWallGhosts(&ctx, chU, V0));
  for (int pass = 0; pass < 2; pass++) {
    for (PetscInt i = 0; i < 2 * PFF_GRID_MAX_LEVELS; i++) alpha[i] = pass;
    PetscCall(PffParticlesG2P(part, chU, chDU, alpha));
    PffParticleArrays a;
    PetscCall(PffParticlesGetArrays(part, &a));
    for (PetscInt i = 0; i < a.n; i++)
      for (int d = 0; d < 3; d++) err = PetscMax(err, PetscAbsReal(a.v[3 * i + d] - V0[d]));
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &err, 1, MPIU_REAL, MPI_MAX, ctx.comm));
  PetscCheck(err <= 1e-6, ctx.comm, PETSC_ERR_PLIB, "constant velocity changed by %g in P2G -> G2P", (double)err);
  PetscCall(PetscPrintf(ctx.comm, "P2G -> G2P constant velocity (%" PetscInt_FMT " level%s, %s): max error %.1e\n",
                        nlevels, nlevels > 1 ? "s" : "", wallz ? "walls in z" : "periodic", (double)err));
  PetscCall(PffParticlesDestroy(&part));
  PetscCall(PffGridDestroy(&ctx.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* perType: liquid particles (x < 0.5 at seeding) move through one uniform field, air particles through
   another (PffParticlesAdvectPerType); otherwise every particle through the first (PffParticlesAdvect). */
static PetscErrorCode TestUniformAdvection(PetscBool perType, PetscReal cellsPerStep)
{
  const PetscInt   nb[3]       = {3, 2, 2};
  const PetscBool  periodic[3] = {PETSC_TRUE, PETSC_TRUE, PETSC_TRUE};
  const PetscReal  origin[3] = {0.125, -0.5, 0}, uv[2][3] = {{1.25, -0.625, 0.5}, {-0.75, 1.0, -0.625}};
  const PetscInt   nsteps = 4;
  PffTestCtx       ctx;
  PffParticles     part;
  PffParticleStats st;
  PetscInt         chU[2];
  PetscReal        err = 0;
  PetscInt64       c0[2], c1[2];

  PetscFunctionBeginUser;
  PetscCall(PffTestCreateGrid(PETSC_COMM_WORLD, nb, periodic, origin, 1.0 / 16, N0, 1, 0, 0, 3, &ctx));
  for (PetscInt t = 0; t < 2; t++) {
    PetscCall(PffGridAddChannel(ctx.grid, t ? "u_air" : "u", PFF_CHANNEL_FACE, 4, &chU[t]));
    PetscCall(PffGridFillChannel(ctx.grid, chU[t], Constant, (void *)uv[t]));
    PetscCall(PffGridHaloBegin(ctx.grid, chU[t]));
    PetscCall(PffGridHaloEnd(ctx.grid, chU[t]));
  }
  PetscCall(CreateParticles(&ctx, "1", perType ? SeedRememberMixed : SeedRemember, &part));
  PetscCall(PffParticlesGetTotals(part, NULL, c0, NULL));
  const PetscReal *u = uv[0], speed = PetscSqrtReal(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]),
                  dt = cellsPerStep * ctx.h0 / speed;
  for (PetscInt s = 0; s < nsteps; s++) {
    if (perType)
      PetscCall(PffParticlesAdvectPerType(part, chU, dt, NULL, NULL, &st));
    else
      PetscCall(PffParticlesAdvect(part, chU[0], dt, NULL, NULL, &st));
  }
  PetscCall(PffParticlesGetTotals(part, NULL, c1, NULL));
  PffParticleArrays a;
  PetscCall(PffParticlesGetArrays(part, &a));
  for (PetscInt i = 0; i < a.n; i++)
    for (int d = 0; d < 3; d++) {
      const PetscReal  L  = ctx.blen * (PetscReal)ctx.nb[d];
      const PetscReal *ui = uv[perType && PffParticleWordType(a.word[i]) == PFF_PARTICLE_AIR];
      PetscReal        x[3];
      PffParticleArraysWorld(&a, i, x);
      PetscReal e = x[d] - ((PetscReal)a.v[3 * i + d] + ui[d] * dt * (PetscReal)nsteps);
      e -= L * PetscFloorReal(e / L + 0.5);
      err = PetscMax(err, PetscAbsReal(e) / L);
    }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &err, 1, MPIU_REAL, MPI_MAX, ctx.comm));
  PetscCheck(c0[0] == c1[0] && c0[1] == c1[1], ctx.comm, PETSC_ERR_PLIB, "advection changed the particle count");
  PetscCheck(!perType || (c1[0] > 0 && c1[1] > 0), ctx.comm, PETSC_ERR_PLIB, "the per-type test needs both types");
  /* the float store rounds the start (kept in v) and each step's end by 2^-24 of the coordinate */
  PetscCheck(err <= 1e-6, ctx.comm, PETSC_ERR_PLIB, "uniform advection error %g (relative to the period)", (double)err);
  PetscCheck(st.substeps == (PetscInt)PetscCeilReal(cellsPerStep), ctx.comm, PETSC_ERR_PLIB,
             "%" PetscInt_FMT " sub-steps per step at %g cells per step", st.substeps, (double)cellsPerStep);
  PetscCall(PetscPrintf(ctx.comm,
                        "advect uniform %g cells/step%s: %" PetscInt64_FMT " + %" PetscInt64_FMT
                        " particles, %" PetscInt_FMT " sub-steps per step, max error %.1e of the period\n",
                        (double)cellsPerStep, perType ? " (one field per type)" : "", c1[0], c1[1], st.substeps,
                        (double)err));
  PetscCall(PffParticlesDestroy(&part));
  PetscCall(PffGridDestroy(&ctx.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

typedef struct {
  PetscReal c[3], omega, r;
} Rot;

static PetscReal Rotation(const PetscReal x[3], PetscInt comp, void *ctx)
{
  const Rot *r = (const Rot *)ctx;
  /* rotation about the z axis through c */
  if (comp == 0) return -r->omega * (x[1] - r->c[1]);
  if (comp == 1) return r->omega * (x[0] - r->c[0]);
  return 0;
}

static PetscReal Sphere(const PetscReal x[3], PetscReal grad[3], void *ctx)
{
  const Rot *r  = (const Rot *)ctx;
  PetscReal  d2 = 0;
  for (int a = 0; a < 3; a++) d2 += PetscSqr(x[a] - r->c[a]);
  const PetscReal d = PetscSqrtReal(d2);
  for (int a = 0; a < 3; a++) grad[a] = d > 0 ? (x[a] - r->c[a]) / d : (a == 0 ? 1.0 : 0.0);
  return d - r->r;
}

static PetscErrorCode TestWalledRotationAndSolid(void)
{
  const PetscInt   nb[3]       = {3, 3, 2};
  const PetscBool  periodic[3] = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};
  const PetscReal  origin[3] = {0, 0, 0}, zero[3] = {0, 0, 0};
  PffTestCtx       ctx;
  PffParticles     part;
  PffParticleStats st;
  PetscInt         chU, maxsub = 0;
  PetscInt64       c0[2], c1[2], inside = 0, outside = 0, still = 0;

  PetscFunctionBeginUser;
  PetscCall(PffTestCreateGrid(PETSC_COMM_WORLD, nb, periodic, origin, 1.0 / 16, N0, 2, -1, 0, 21, &ctx));
  Rot rot = {{1.5 * ctx.blen, 1.5 * ctx.blen, ctx.blen}, 0, 0.6 * ctx.blen};
  /* the fastest point (a box corner) moves 1.5 finest cells per step */
  rot.omega          = 1.0;
  const PetscReal dt = 1.5 * ctx.h0 / (rot.omega * 1.5 * ctx.blen * PETSC_SQRT2);
  PetscCall(PffGridAddChannel(ctx.grid, "u", PFF_CHANNEL_FACE, 2, &chU));
  PetscCall(PffGridFillChannel(ctx.grid, chU, Rotation, &rot));
  PetscCall(PffGridHaloBegin(ctx.grid, chU));
  PetscCall(PffGridHaloEnd(ctx.grid, chU));
  PetscCall(CreateParticles(&ctx, "1", SeedRemember, &part));
  PetscCall(PffParticlesGetTotals(part, NULL, c0, NULL));
  for (PetscInt s = 0; s < 6; s++) {
    PetscCall(PffParticlesAdvect(part, chU, dt, NULL, NULL, &st));
    maxsub = PetscMax(maxsub, st.substeps);
  }
  PetscCall(PffParticlesGetTotals(part, NULL, c1, NULL));
  PffParticleArrays a;
  PetscCall(PffParticlesGetArrays(part, &a));
  for (PetscInt i = 0; i < a.n; i++)
    for (int d = 0; d < 3; d++) {
      const PetscReal s = a.x[3 * i + d] * ctx.h0; /* from the origin */
      if (!(s > 0 && s < ctx.blen * (PetscReal)ctx.nb[d])) outside++;
    }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &outside, 1, MPIU_INT64, MPI_SUM, ctx.comm));
  PetscCheck(c0[0] == c1[0], ctx.comm, PETSC_ERR_PLIB, "rotation changed the particle count");
  PetscCheck(outside == 0, ctx.comm, PETSC_ERR_PLIB, "%" PetscInt64_FMT " particle coordinates left the box", outside);
  PetscCall(PetscPrintf(ctx.comm,
                        "advect rotation (walls, 2 levels): %" PetscInt64_FMT
                        " particles kept inside, max %" PetscInt_FMT " sub-steps\n",
                        c1[0], maxsub));

  /* solid push-out with zero velocity */
  PetscCall(PffGridFillChannel(ctx.grid, chU, Constant, (void *)zero));
  PetscCall(PffGridHaloBegin(ctx.grid, chU));
  PetscCall(PffGridHaloEnd(ctx.grid, chU));
  PetscCall(PffParticlesGetArrays(part, &a));
  for (PetscInt i = 0; i < a.n; i++) {
    PetscReal g[3], x[3];
    PffParticleArraysWorld(&a, i, x);
    if (Sphere(x, g, &rot) < 0) inside++;
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &inside, 1, MPIU_INT64, MPI_SUM, ctx.comm));
  PetscCall(PffParticlesAdvect(part, chU, dt, Sphere, &rot, &st));
  PetscCall(PffParticlesGetArrays(part, &a));
  for (PetscInt i = 0; i < a.n; i++) {
    PetscReal g[3], x[3];
    PffParticleArraysWorld(&a, i, x);
    if (Sphere(x, g, &rot) < 0) still++;
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &still, 1, MPIU_INT64, MPI_SUM, ctx.comm));
  PetscCall(PffParticlesGetTotals(part, NULL, c1, NULL));
  PetscCheck(inside > 0, ctx.comm, PETSC_ERR_PLIB, "no particle started inside the sphere");
  PetscCheck(still == 0 && st.pushed == inside && c1[0] == c0[0], ctx.comm, PETSC_ERR_PLIB,
             "solid push-out: %" PetscInt64_FMT " of %" PetscInt64_FMT " particles still inside, %" PetscInt64_FMT
             " pushed",
             still, inside, st.pushed);
  PetscCall(PetscPrintf(ctx.comm, "solid push-out: %" PetscInt64_FMT " particles pushed out of the sphere, none left\n",
                        st.pushed));
  PetscCall(PffParticlesDestroy(&part));
  PetscCall(PffGridDestroy(&ctx.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscReal Wavy(const PetscReal x[3], PetscInt comp, void *ctx)
{
  (void)comp;
  (void)ctx;
  return 0.5 + 0.3 * PetscSinReal(2 * PETSC_PI * x[0] / 1.5) * PetscCosReal(2 * PETSC_PI * x[1]) + 0.2 * x[2];
}

/* Wavy with a plateau of 0.75 for -0.1 < x < 0.6: the tiles of the blocks at 0 <= x < 0.5 (and their ghost layer)
   hold one value, which PffParticlesInterpolateCell hands to their particles without interpolating. */
static PetscReal Plateau(const PetscReal x[3], PetscInt comp, void *ctx)
{
  return x[0] > -0.1 && x[0] < 0.6 ? 0.75 : Wavy(x, comp, ctx);
}

typedef struct {
  float     *val;
  PetscInt64 calls; /* particles received */
} CellCtx;

static void StoreCell(PetscInt i0, PetscInt m, const float val[], void *ctx)
{
  CellCtx *c = (CellCtx *)ctx;
  for (PetscInt j = 0; j < m; j++) c->val[i0 + j] = val[j];
#pragma omp atomic
  c->calls += m;
}

/* PffParticlesInterpolateCell against the grid's PffGridInterpolate at the particles' world positions,
   on a graded periodic grid and on grids walled in z, whose wall ghosts hold junk (particles within a cell of
   a wall go point by point). */
static PetscErrorCode TestCellInterpolation(PetscInt nlevels, PetscBool wallz, PetscBool plateau)
{
  const PetscInt  nb[3]       = {3, 2, 2};
  const PetscBool periodic[3] = {PETSC_TRUE, PETSC_TRUE, (PetscBool)!wallz};
  const PetscReal origin[3]   = {-0.5, 0.25, 0};
  PffTestCtx      ctx;
  PffParticles    part;
  PetscInt        ch;
  PetscReal       err = 0, *xw, *ref;
  CellCtx         cc  = {NULL, 0};

  PetscFunctionBeginUser;
  PetscCall(PffTestCreateGrid(PETSC_COMM_WORLD, nb, periodic, origin, 1.0 / 16, N0, nlevels, nlevels > 1 ? -1 : 0, 0, 9,
                              &ctx));
  PetscCall(PffGridAddChannel(ctx.grid, "phi", PFF_CHANNEL_CELL, 1, &ch));
  PetscCall(PffGridFillChannel(ctx.grid, ch, plateau ? Plateau : Wavy, NULL));
  PetscCall(PffGridHaloBegin(ctx.grid, ch));
  PetscCall(PffGridHaloEnd(ctx.grid, ch));
  if (wallz) { /* junk that the general path, which clamps at walls, never reads */
    const PetscReal junk[3] = {1e3, 0, 0};
    PetscCall(FillWallGhosts(&ctx, ch, junk));
  }
  PetscCall(CreateParticles(&ctx, "1", SeedLiquid, &part));
  PffParticleArrays a;
  PetscCall(PffParticlesGetArrays(part, &a));
  PetscCall(PetscMalloc3(a.n + 1, &cc.val, 3 * a.n + 1, &xw, a.n + 1, &ref));
  PetscCall(PffParticlesInterpolateCell(part, ch, StoreCell, &cc));
  for (PetscInt i = 0; i < a.n; i++) PffParticleArraysWorld(&a, i, &xw[3 * i]);
  PetscCall(PffGridInterpolate(ctx.grid, ch, a.n, xw, ref));
  for (PetscInt i = 0; i < a.n; i++) err = PetscMax(err, PetscAbsReal(cc.val[i] - ref[i]));
  PetscInt64 calls = cc.calls, n = a.n;
  PetscCall(PetscFree3(cc.val, xw, ref));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &err, 1, MPIU_REAL, MPI_MAX, ctx.comm));
  PetscCheck(calls == n, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "the callback saw %" PetscInt64_FMT " of %" PetscInt64_FMT " particles", calls, n);
  /* float weights and values against the grid's double path */
  PetscCheck(err <= 2e-6, ctx.comm, PETSC_ERR_PLIB, "cell interpolation differs from PffGridInterpolate by %g",
             (double)err);
  PetscCall(PetscPrintf(ctx.comm, "cell values at particles (%" PetscInt_FMT " level%s, %s%s): max difference %.1e\n",
                        nlevels, nlevels > 1 ? "s" : "", wallz ? "walls in z" : "periodic",
                        plateau ? ", a plateau" : "", (double)err));
  PetscCall(PffParticlesDestroy(&part));
  PetscCall(PffGridDestroy(&ctx.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscReal WavyFace(const PetscReal x[3], PetscInt comp, void *ctx)
{
  return Wavy(x, comp, ctx) + 0.25 * (PetscReal)comp * x[1];
}

/* G2P (alpha 0: v = I(u)) against the grid's PffGridInterpolate at the particles' world positions, on grids
   walled in y and z. The wall ghosts hold junk (|u| = 1000): the general path clamps there and reads only the
   wall face of a normal component, so a tile value read across a wall shows as a large difference. */
static PetscErrorCode TestG2PMatchesGrid(PetscInt nlevels)
{
  const PetscInt  nb[3]       = {3, 2, 2};
  const PetscBool periodic[3] = {PETSC_TRUE, PETSC_FALSE, PETSC_FALSE};
  const PetscReal origin[3] = {-0.5, 0.25, 0}, zero[3] = {0, 0, 0}, junk[3] = {1e3, -1e3, 7e2};
  PetscReal       alpha[2 * PFF_GRID_MAX_LEVELS] = {0}, err = 0, *xw, *ref;
  PffTestCtx      ctx;
  PffParticles    part;
  PetscInt        chU, chDU;

  PetscFunctionBeginUser;
  PetscCall(PffTestCreateGrid(PETSC_COMM_WORLD, nb, periodic, origin, 1.0 / 16, N0, nlevels, nlevels > 1 ? -1 : 0, 0, 9,
                              &ctx));
  PetscCall(PffGridAddChannel(ctx.grid, "u", PFF_CHANNEL_FACE, 2, &chU));
  PetscCall(PffGridAddChannel(ctx.grid, "du", PFF_CHANNEL_FACE, 2, &chDU));
  PetscCall(PffGridFillChannel(ctx.grid, chU, WavyFace, NULL));
  PetscCall(PffGridFillChannel(ctx.grid, chDU, Constant, (void *)zero));
  PetscCall(PffGridHaloBegin(ctx.grid, chU));
  PetscCall(PffGridHaloEnd(ctx.grid, chU));
  PetscCall(PffGridHaloBegin(ctx.grid, chDU));
  PetscCall(PffGridHaloEnd(ctx.grid, chDU));
  PetscCall(FillWallGhosts(&ctx, chU, junk));
  PetscCall(CreateParticles(&ctx, "1", SeedLiquid, &part));
  PetscCall(PffParticlesG2P(part, chU, chDU, alpha));
  PffParticleArrays a;
  PetscCall(PffParticlesGetArrays(part, &a));
  PetscCall(PetscMalloc2(3 * a.n + 1, &xw, 3 * a.n + 1, &ref));
  for (PetscInt i = 0; i < a.n; i++) PffParticleArraysWorld(&a, i, &xw[3 * i]);
  PetscCall(PffGridInterpolate(ctx.grid, chU, a.n, xw, ref));
  for (PetscInt i = 0; i < 3 * a.n; i++)
    err = PetscMax(err, PetscAbsReal(a.v[i] - ref[i]) / PetscMax(1.0, PetscAbsReal(ref[i])));
  PetscCall(PetscFree2(xw, ref));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &err, 1, MPIU_REAL, MPI_MAX, ctx.comm));
  /* float tiles and the float store against the grid's double path */
  PetscCheck(err <= 2e-6, ctx.comm, PETSC_ERR_PLIB, "G2P differs from PffGridInterpolate by %g beside walls",
             (double)err);
  PetscCall(PetscPrintf(ctx.comm,
                        "G2P against the grid's path (%" PetscInt_FMT
                        " level%s, walls in y and z): max relative difference %.1e\n",
                        nlevels, nlevels > 1 ? "s" : "", (double)err));
  PetscCall(PffParticlesDestroy(&part));
  PetscCall(PffGridDestroy(&ctx.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A uniform field along the periodic x axis of a box walled in y and z moves every particle by u t, also those
   beside the walls, whose tangential ghosts hold junk (1000) that the general path never reads. */
static PetscErrorCode TestWalledUniformAdvection(PetscInt nlevels)
{
  const PetscInt   nb[3]       = {3, 2, 2};
  const PetscBool  periodic[3] = {PETSC_TRUE, PETSC_FALSE, PETSC_FALSE};
  const PetscReal  origin[3] = {0.125, -0.5, 0}, u[3] = {0.75, 0, 0}, junk[3] = {1e3, 0, 0};
  const PetscInt   nsteps = 3;
  PffTestCtx       ctx;
  PffParticles     part;
  PffParticleStats st;
  PetscInt         chU;
  PetscReal        err = 0;

  PetscFunctionBeginUser;
  PetscCall(PffTestCreateGrid(PETSC_COMM_WORLD, nb, periodic, origin, 1.0 / 16, N0, nlevels, nlevels > 1 ? -1 : 0, 0, 9,
                              &ctx));
  PetscCall(PffGridAddChannel(ctx.grid, "u", PFF_CHANNEL_FACE, 3, &chU));
  PetscCall(PffGridFillChannel(ctx.grid, chU, Constant, (void *)u));
  PetscCall(PffGridHaloBegin(ctx.grid, chU));
  PetscCall(PffGridHaloEnd(ctx.grid, chU));
  PetscCall(FillWallGhosts(&ctx, chU, junk));
  PetscCall(CreateParticles(&ctx, "1", SeedRemember, &part));
  const PetscReal dt = 0.4 * ctx.h0 / u[0]; /* one sub-step: the vectorised chunks */
  for (PetscInt s = 0; s < nsteps; s++) PetscCall(PffParticlesAdvect(part, chU, dt, NULL, NULL, &st));
  PffParticleArrays a;
  PetscCall(PffParticlesGetArrays(part, &a));
  for (PetscInt i = 0; i < a.n; i++)
    for (int d = 0; d < 3; d++) {
      const PetscReal L = ctx.blen * (PetscReal)ctx.nb[d];
      PetscReal       x[3];
      PffParticleArraysWorld(&a, i, x);
      PetscReal e = x[d] - ((PetscReal)a.v[3 * i + d] + u[d] * dt * (PetscReal)nsteps);
      if (periodic[d]) e -= L * PetscFloorReal(e / L + 0.5);
      err = PetscMax(err, PetscAbsReal(e) / L);
    }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &err, 1, MPIU_REAL, MPI_MAX, ctx.comm));
  PetscCheck(err <= 1e-6, ctx.comm, PETSC_ERR_PLIB, "walled uniform advection error %g (relative to the box)",
             (double)err);
  PetscCall(PetscPrintf(ctx.comm,
                        "advect uniform beside walls (%" PetscInt_FMT " level%s): max error %.1e of the box\n", nlevels,
                        nlevels > 1 ? "s" : "", (double)err));
  PetscCall(PffParticlesDestroy(&part));
  PetscCall(PffGridDestroy(&ctx.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(PffInitializePackage());
  PetscCall(TestKernelSum(1, 0));
  PetscCall(TestKernelSum(2, -1));
  PetscCall(TestSplatReference());
  PetscCall(TestConstantVelocity(2, PETSC_FALSE));
  PetscCall(TestConstantVelocity(1, PETSC_TRUE));
  for (int k = 0; k < 2; k++) {
    PetscCall(TestUniformAdvection(PETSC_FALSE, k ? 0.4 : 2.5));
    PetscCall(TestUniformAdvection(PETSC_TRUE, k ? 0.4 : 2.5));
  }
  PetscCall(TestWalledRotationAndSolid());
  PetscCall(TestCellInterpolation(2, PETSC_FALSE, PETSC_FALSE));
  PetscCall(TestCellInterpolation(1, PETSC_TRUE, PETSC_FALSE));
  PetscCall(TestCellInterpolation(2, PETSC_TRUE, PETSC_FALSE));
  PetscCall(TestCellInterpolation(1, PETSC_FALSE, PETSC_TRUE));
  PetscCall(TestCellInterpolation(2, PETSC_TRUE, PETSC_TRUE));
  PetscCall(TestG2PMatchesGrid(1));
  PetscCall(TestG2PMatchesGrid(2));
  PetscCall(TestWalledUniformAdvection(1));
  PetscCall(TestWalledUniformAdvection(2));
  PetscCall(PetscFinalize());
  return 0;
}
