/* Helpers of the tall-cell unit tests (test_tallcell.c, test_tallcell_solid.c): a unit box of 8-cell blocks
   with levels constant along y, partitioned by columns; analytic level sets (a pool, a wavy surface with a
   drop and an air pocket, a pool and a drop); box obstacles; a built PffTall on them. */
#pragma once

#include "pfftest.h"
#include <pff/shapes.h>

#define N0 8
#define G 9.81
#define RHO 1000.0
#define DT 0.01

typedef struct {
  PetscReal H;     /* pool height */
  PetscInt  shape; /* 0 flat pool; 1 wavy surface, a drop and an air pocket; 2 flat pool and a drop;
                      3 two pools, H for z < 1/2 and H - 0.2 beyond (with the wall of solid 2) */
  PetscInt solid;  /* 0 none, 1 the three obstacles of Obstacles(), 2 a wall across z = 1/2, 3 a round tank,
                      4 the floating box */
  PetscReal lift;  /* the floating box raised by this from FLOAT_LO, FLOAT_HI (m) */
} Scene;

/* Signed distance to the union of boxes, none aligned with the cells (h = 1/32 on the finest level). Solid 1:
   a block on the floor under the surface, a pillar from the floor to the ceiling through the surface, and a
   box through the surface with liquid under it (an overhang, as under a floating body). Solid 2: a wall
   across the tank, 0.12 thick around z = 1/2. Solid 3: a round tank, solid outside the vertical cylinder of
   radius 0.4 around x = z = 1/2. ctx is the Scene. */
/* The floating box of solid 4: its bottom at a cell centre of the finest level (13.5 h), its sides between faces. */
static const PetscReal FLOAT_LO[3] = {0.4, 0.421875, 0.4}, FLOAT_HI[3] = {0.6, 0.621875, 0.6};

static PetscReal Obstacles(const PetscReal x[3], PetscReal grad[3], void *ctx)
{
  const PetscReal box[5][2][3] = {{{0.1, -1, 0.55}, {0.35, 0.25, 0.8}},
                                  {{0.6, -1, 0.2}, {0.75, 2, 0.33}},
                                  {{0.3, 0.45, 0.15}, {0.55, 0.75, 0.4}},
                                  {{-1, -1, 0.44}, {2, 2, 0.56}},
                                  {{FLOAT_LO[0], FLOAT_LO[1], FLOAT_LO[2]}, {FLOAT_HI[0], FLOAT_HI[1], FLOAT_HI[2]}}};
  const PetscInt  first[5] = {1, 0, 3, 1, 4}, last[5] = {0, 2, 3, 0, 4}; /* the boxes of solids 1, 2 and 4 */
  const Scene    *sc   = (const Scene *)ctx;
  PetscReal       dmin = PETSC_MAX_REAL;

  if (grad) grad[0] = grad[1] = grad[2] = 0; /* not used by the fractions */
  if (sc->solid == 3) return 0.4 - PetscSqrtReal(PetscSqr(x[0] - 0.5) + PetscSqr(x[2] - 0.5));
  for (PetscInt b = first[sc->solid]; b <= last[sc->solid]; b++) {
    PetscReal e[3], half[3];
    for (PetscInt a = 0; a < 3; a++) {
      e[a]    = x[a] - 0.5 * (box[b][0][a] + box[b][1][a]) - (b == 4 && a == 1 ? sc->lift : 0);
      half[a] = 0.5 * (box[b][1][a] - box[b][0][a]);
    }
    dmin = PetscMin(dmin, PffBoxDistance(e, half, NULL));
  }
  return dmin;
}

/* The still surface height over (x, z). */
static PetscReal SurfaceHeight(const Scene *sc, const PetscReal x[3])
{
  return sc->shape == 3 && x[2] > 0.5 ? sc->H - 0.2 : sc->H;
}

static PetscReal Phi(const PetscReal x[3], PetscInt comp, void *vctx)
{
  const Scene *sc = (const Scene *)vctx;
  (void)comp;
  if (sc->shape == 0 || sc->shape == 3) return x[1] - SurfaceHeight(sc, x);
  if (sc->shape == 2)
    return PetscMin(x[1] - sc->H,
                    PetscSqrtReal(PetscSqr(x[0] - 0.45) + PetscSqr(x[1] - 0.8) + PetscSqr(x[2] - 0.45)) - 0.1);
  const PetscReal surf   = sc->H + 0.06 * PetscSinReal(9 * x[0]) * PetscCosReal(7 * x[2]);
  const PetscReal drop   = PetscSqrtReal(PetscSqr(x[0] - 0.4) + PetscSqr(x[1] - 0.85) + PetscSqr(x[2] - 0.55)) - 0.09;
  const PetscReal pocket = 0.1 - PetscSqrtReal(PetscSqr(x[0] - 0.7) + PetscSqr(x[1] - 0.25) + PetscSqr(x[2] - 0.3));
  return PetscMin(PetscMax(x[1] - surf, pocket), drop);
}

static PetscReal Gravity(const PetscReal x[3], PetscInt comp, void *vctx)
{
  (void)vctx;
  return comp == 1 && x[1] > 1e-9 ? -G * DT : 0;
}

static PetscReal RandomU(const PetscReal x[3], PetscInt comp, void *vctx)
{
  const PffTestCtx *t = (const PffTestCtx *)vctx;
  if (PetscAbsReal(x[comp]) < 1e-9) return 0; /* a lower wall */
  return 2 * PffTestUniform01(PffTestPositionKey(t, x, comp, 5)) - 1;
}

/* A unit box of nb blocks, levels constant along y: uniform >= 0, or random per block column in 0..2
   (graded by the grid), partitioned by columns. */
static PetscErrorCode CreateGrid(MPI_Comm comm, const PetscInt nb[3], PetscInt uniform, uint64_t seed, PffTestCtx *t)
{
  PetscInt       *request;
  const PetscInt  cells[3]  = {N0 * nb[0], N0 * nb[1], N0 * nb[2]};
  const PetscReal origin[3] = {0, 0, 0};
  const PetscBool per[3]    = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(nb[0] * nb[1] * nb[2], &request));
  for (PetscInt b = 0; b < nb[0] * nb[1] * nb[2]; b++) {
    const PetscInt bi = b % nb[0], bk = b / (nb[0] * nb[1]);
    request[b] = uniform >= 0 ? uniform : (PetscInt)(PffTestKey(seed, (uint64_t)bi, (uint64_t)bk, 3) % 3);
  }
  PetscCall(PetscMemzero(t, sizeof(*t)));
  PetscCall(PffGridCreate(comm, &t->grid));
  PetscCall(PffGridSetCells(t->grid, cells));
  PetscCall(PffGridSetBlockSize(t->grid, N0));
  PetscCall(PffGridSetLevels(t->grid, 3));
  PetscCall(PffGridSetDomain(t->grid, origin, 1.0 / (PetscReal)cells[0]));
  PetscCall(PffGridSetPeriodic(t->grid, per));
  PetscCall(PffGridSetPartitionType(t->grid, PFF_PARTITION_COLUMNS));
  PetscCall(PffGridSetRefinementMap(t->grid, request));
  PetscCall(PffGridSetUp(t->grid));
  PetscCall(PetscFree(request));
  t->comm = comm;
  PetscCallMPI(MPI_Comm_rank(comm, &t->rank));
  PetscCall(PffGridGetRaster(t->grid, t->nb, &t->level, &t->owner));
  PetscCall(PffGridGetSizes(t->grid, NULL, NULL, t->origin, &t->h0, t->periodic));
  PetscCall(PffGridGetLocalBlocks(t->grid, &t->nlocal));
  t->blen = N0 * t->h0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

typedef struct {
  PffTestCtx   t;
  PffTall      tc;
  PetscInt     phi, u, p, A, sd; /* A, sd: solid fractions and distances (-1 without solids) */
  PetscInt     solid;            /* the scene's solid */
  PffTallStats st;
} Problem;

/* Whether cell (i, j, k) of local block lb lies inside the obstacles (all eight corners, and the verticals
   through them half a cell below and above, where the control volumes of its y-faces reach): the cells without a
   pressure sample. */
static PetscErrorCode CellClosed(Problem *pb, PetscInt lb, PetscInt i, PetscInt j, PetscInt k, PetscBool *closed)
{
  PffBlockInfo info;
  Scene        sc = {0, 0, pb->solid, 0};

  PetscFunctionBeginUser;
  *closed = (PetscBool)(pb->A >= 0);
  if (!*closed) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PffGridGetBlockInfo(pb->t.grid, lb, &info));
  for (PetscInt v = 0; v < 16 && *closed; v++) { /* the corners, and half a cell below and above them */
    const PetscInt  q[3] = {i + (v & 1), j + ((v >> 1) & 1), k + ((v >> 2) & 1)};
    const PetscReal dy   = v < 8 ? 0 : (((v >> 1) & 1) ? 0.5 : -0.5) * info.h;
    const PetscReal x[3] = {info.lo[0] + q[0] * info.h, info.lo[1] + q[1] * info.h + dy, info.lo[2] + q[2] * info.h};
    *closed              = (PetscBool)(Obstacles(x, NULL, &sc) <= 0);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode ProblemCreate(MPI_Comm comm, const PetscInt nb[3], PetscInt uniform, uint64_t seed,
                                    PetscBool merge, Scene *sc, Problem *pb)
{
  KSP ksp;

  PetscFunctionBeginUser;
  PetscCall(CreateGrid(comm, nb, uniform, seed, &pb->t));
  PetscCall(PffGridAddChannel(pb->t.grid, "phi", PFF_CHANNEL_CELL, 1, &pb->phi));
  PetscCall(PffGridAddChannel(pb->t.grid, "u", PFF_CHANNEL_FACE, 1, &pb->u));
  PetscCall(PffGridAddChannel(pb->t.grid, "p", PFF_CHANNEL_CELL, 1, &pb->p));
  PetscCall(PffGridFillChannel(pb->t.grid, pb->phi, Phi, sc));
  PetscCall(PffTallCreate(pb->t.grid, &pb->tc));
  PetscCall(PffTallSetFromOptions(pb->tc));
  PetscCall(PffTallSetMerge(pb->tc, merge));
  pb->A = pb->sd = -1;
  pb->solid      = sc->solid;
  if (sc->solid) {
    PetscCall(PffGridAddChannel(pb->t.grid, "A", PFF_CHANNEL_FACE, 1, &pb->A));
    PetscCall(PffGridAddChannel(pb->t.grid, "sd", PFF_CHANNEL_CELL, 1, &pb->sd));
    PetscCall(PffTallFillSolid(pb->t.grid, Obstacles, sc, pb->A, pb->sd, NULL));
    PetscCall(PffTallSetSolid(pb->tc, pb->A, pb->sd));
  }
  PetscCall(PffTallGetKSP(pb->tc, &ksp));
  PetscCall(KSPSetTolerances(ksp, 1e-12, 1e-30, PETSC_DEFAULT, 2000));
  PetscCall(PffTallBuild(pb->tc, pb->phi));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode ProblemDestroy(Problem *pb)
{
  PetscFunctionBeginUser;
  PetscCall(PffTallDestroy(&pb->tc));
  PetscCall(PffGridDestroy(&pb->t.grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Largest |p - rho g (H - y)| over the liquid cell centres (not wholly inside a solid), and a position-weighted
   sum of p (the same on any partition). */
static PetscErrorCode PressureCheck(Problem *pb, const Scene *sc, PetscReal *err, PetscReal *wsum)
{
  PetscReal e = 0, w = 0;

  PetscFunctionBeginUser;
  for (PetscInt lb = 0; lb < pb->t.nlocal; lb++) {
    PffBlockInfo info;
    float       *p, *phi;
    PetscCall(PffGridGetBlockInfo(pb->t.grid, lb, &info));
    PetscCall(PffGridGetBlockData(pb->t.grid, pb->p, lb, 0, &p));
    PetscCall(PffGridGetBlockData(pb->t.grid, pb->phi, lb, 0, &phi));
    for (PetscInt k = 0; k < info.n; k++)
      for (PetscInt j = 0; j < info.n; j++)
        for (PetscInt i = 0; i < info.n; i++) {
          const PetscInt c[3] = {i, j, k}, q = i + info.n * (j + info.n * k);
          PetscReal      x[3];
          PffTestSamplePosition(&info, PFF_CHANNEL_CELL, 0, c, x);
          PetscBool closed;
          PetscCall(CellClosed(pb, lb, i, j, k, &closed));
          if (phi[q] < 0 && !closed) e = PetscMax(e, PetscAbsReal(p[q] - RHO * G * (SurfaceHeight(sc, x) - x[1])));
          w += p[q] * info.h * info.h * info.h * (1 + PffTestUniform01(PffTestPositionKey(&pb->t, x, 0, 9)));
        }
  }
  PetscCallMPI(MPIU_Allreduce(&e, err, 1, MPIU_REAL, MPI_MAX, pb->t.comm));
  PetscCallMPI(MPIU_Allreduce(&w, wsum, 1, MPIU_REAL, MPI_SUM, pb->t.comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Still water on 4 x 4 x 4 blocks: u* = -g dt; after one projection every row is at rest (|u| <= 1e-6 sqrt(g H)),
   p = rho g (H - y) at every liquid cell centre, and the cell-height channel is positive exactly in the liquid
   outside the solids. */
static PETSC_UNUSED PetscErrorCode StillWater(MPI_Comm comm, const char *name, PetscInt uniform, PetscBool merge,
                                              const Scene *scIn)
{
  const PetscInt nb[3] = {4, 4, 4};
  Scene          sc    = *scIn;
  Problem        pb;
  PetscReal      umax, err, wsum;

  PetscFunctionBeginUser;
  PetscCall(ProblemCreate(comm, nb, uniform, 11, merge, &sc, &pb));
  PetscCall(PffGridFillChannel(pb.t.grid, pb.u, Gravity, NULL));
  PetscCall(PffTallProject(pb.tc, pb.u, DT, RHO, pb.p, &pb.st));
  PetscCall(PffTallMaxRowVelocity(pb.tc, pb.u, &umax));
  PetscCall(PressureCheck(&pb, &sc, &err, &wsum));
  { /* the cell-height channel for frames: > 0 exactly in the liquid, tall cells at least 3 high */
    PetscInt  chH, bad = 0;
    PetscReal hmax = 0;
    PetscCall(PffGridAddChannel(pb.t.grid, "height", PFF_CHANNEL_CELL, 1, &chH));
    PetscCall(PffTallWriteCellHeight(pb.tc, chH));
    for (PetscInt lb = 0; lb < pb.t.nlocal; lb++) {
      PffBlockInfo info;
      float       *h, *phi;
      PetscCall(PffGridGetBlockInfo(pb.t.grid, lb, &info));
      PetscCall(PffGridGetBlockData(pb.t.grid, chH, lb, 0, &h));
      PetscCall(PffGridGetBlockData(pb.t.grid, pb.phi, lb, 0, &phi));
      for (PetscInt c = 0; c < info.n * info.n * info.n; c++) {
        PetscBool closed;
        PetscCall(CellClosed(&pb, lb, c % info.n, (c / info.n) % info.n, c / (info.n * info.n), &closed));
        bad += (phi[c] < 0 && !closed) != (h[c] > 0);
        hmax = PetscMax(hmax, h[c]);
      }
    }
    PetscCallMPI(MPIU_Allreduce(MPI_IN_PLACE, &bad, 1, MPIU_INT, MPI_SUM, comm));
    PetscCallMPI(MPIU_Allreduce(MPI_IN_PLACE, &hmax, 1, MPIU_REAL, MPI_MAX, comm));
    PetscCheck(!bad && (merge ? hmax >= 3 : hmax == 1), comm, PETSC_ERR_PLIB,
               "still water, %s: cell heights: %" PetscInt_FMT " cells disagree with phi, max %g", name, bad,
               (double)hmax);
  }
  PetscCall(PetscPrintf(comm,
                        "still water, %s: %" PetscInt64_FMT " cells (%" PetscInt64_FMT " tall) for %" PetscInt64_FMT
                        " liquid cells, %" PetscInt64_FMT " samples, %" PetscInt_FMT " its, max |u| %.2e (bound %.2e), "
                        "max |p - rho g (H - y)| %.2e Pa\n",
                        name, pb.st.cells, pb.st.tallCells, pb.st.liquidCells, pb.st.samples, pb.st.its, (double)umax,
                        (double)(1e-6 * PetscSqrtReal(G * sc.H)), (double)err));
  PetscCheck(pb.st.reason > 0, comm, PETSC_ERR_PLIB, "still water, %s: the solve did not converge (%s)", name,
             KSPConvergedReasons[pb.st.reason]);
  PetscCheck(umax <= 1e-6 * PetscSqrtReal(G * sc.H), comm, PETSC_ERR_PLIB, "still water, %s: max |u| %g m/s", name,
             (double)umax);
  PetscCheck(err <= 1e-6 * RHO * G * sc.H, comm, PETSC_ERR_PLIB, "still water, %s: pressure off hydrostatic by %g Pa",
             name, (double)err);
  PetscCheck(merge == (pb.st.tallCells > 0), comm, PETSC_ERR_PLIB, "still water, %s: %" PetscInt64_FMT " tall cells",
             name, pb.st.tallCells);
  PetscCheck(merge || pb.st.cells == pb.st.liquidCells || uniform < 0, comm, PETSC_ERR_PLIB,
             "still water, %s: %" PetscInt64_FMT " cells for %" PetscInt64_FMT " liquid cells", name, pb.st.cells,
             pb.st.liquidCells);
  PetscCall(ProblemDestroy(&pb));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Symmetric positive definite on random quadtrees (wavy surface, drop, air pocket; with the obstacles of
   Obstacles() when solid is 1); the projection of a random u* is divergence-free. */
static PETSC_UNUSED PetscErrorCode RandomQuadtrees(MPI_Comm comm, PetscInt solid)
{
  const PetscInt nb[3] = {4, 2, 4};

  PetscFunctionBeginUser;
  for (uint64_t seed = 1; seed <= 3; seed++) {
    Scene      sc = {0.5, 1, solid, 0};
    Problem    pb;
    Mat        A;
    KSP        eig;
    PetscBool  sym;
    PetscReal *re, *im, lmin = PETSC_MAX_REAL, lmax = 0, div0, div1;
    PetscInt   n;

    PetscCall(ProblemCreate(comm, nb, -1, seed, PETSC_TRUE, &sc, &pb));
    PetscCall(PffTallGetOperator(pb.tc, &A));
    PetscCall(MatIsSymmetric(A, 1e-10, &sym));
    PetscCheck(sym, comm, PETSC_ERR_PLIB, "random quadtree %d: the operator is not symmetric", (int)seed);
    PetscCall(MatGetSize(A, &n, NULL));
    PetscCall(KSPCreate(comm, &eig));
    PetscCall(KSPSetOperators(eig, A, A));
    PetscCall(KSPSetType(eig, KSPGMRES));
    {
      PC pc;
      PetscCall(KSPGetPC(eig, &pc));
      PetscCall(PCSetType(pc, PCNONE));
    }
    PetscCall(KSPSetUp(eig));
    PetscCall(PetscMalloc2(n, &re, n, &im));
    PetscCall(KSPComputeEigenvaluesExplicitly(eig, n, re, im));
    for (PetscInt q = 0; q < n; q++) {
      lmin = PetscMin(lmin, re[q]);
      lmax = PetscMax(lmax, re[q]);
    }
    PetscCall(PetscFree2(re, im));
    PetscCall(KSPDestroy(&eig));
    { /* the explicit eigenvalues exist on rank 0 only */
      PetscReal ext[2] = {lmin, lmax};
      PetscCallMPI(MPI_Bcast(ext, 2, MPIU_REAL, 0, comm));
      lmin = ext[0];
      lmax = ext[1];
    }
    PetscCall(PffGridFillChannel(pb.t.grid, pb.u, RandomU, &pb.t));
    PetscCall(PffTallMaxDivergence(pb.tc, pb.u, &div0));
    PetscCall(PffTallProject(pb.tc, pb.u, DT, RHO, pb.p, &pb.st));
    PetscCall(PffTallMaxDivergence(pb.tc, pb.u, &div1));
    PetscCall(PetscPrintf(comm,
                          "random quadtree %d%s: %" PetscInt64_FMT " cells (%" PetscInt64_FMT " tall), %" PetscInt_FMT
                          " samples, symmetric, eigenvalues in [%.3e, %.3e], %" PetscInt_FMT
                          " its, max divergence %.2e -> %.2e 1/s\n",
                          (int)seed, solid ? " with solids" : "", pb.st.cells, pb.st.tallCells, n, (double)lmin,
                          (double)lmax, pb.st.its, (double)div0, (double)div1));
    PetscCheck(pb.st.tallCells > 0 && pb.st.cells < pb.st.liquidCells, comm, PETSC_ERR_PLIB,
               "random quadtree %d: no tall cells", (int)seed);
    PetscCheck(lmin > 1e-12 * lmax, comm, PETSC_ERR_PLIB, "random quadtree %d: smallest eigenvalue %g", (int)seed,
               (double)lmin);
    PetscCheck(pb.st.reason > 0 && div1 <= 1e-6 * div0, comm, PETSC_ERR_PLIB,
               "random quadtree %d: divergence %g after the projection (%g before)", (int)seed, (double)div1,
               (double)div0);
    PetscCall(ProblemDestroy(&pb));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
