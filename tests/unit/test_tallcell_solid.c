/* Solids in the variational tall-cell pressure ([A] of Eq. 1, tall cells Sec. 4.3.2):
   - the open fraction of a square face cut by random planes matches the area measured on a 1000 x 1000
     lattice (the four-triangle rule is exact for a plane; the lattice's own error is below 2e-3);
   - still water around a block on the floor, a pillar through the surface and a box with liquid under it
     stays at rest (|u| <= 1e-6 sqrt(g H)) with p = rho g (H - y), on uniform cubic, uniform tall, quadtree
     tall and quadtree cubic cells: rows of cut faces carry their fractions, cells inside a solid have no
     sample, a run ends at a solid as at a wall;
   - two pools of different heights behind a wall across the tank both stay at rest and hydrostatic, each
     with its own height: the closed faces carry no flux;
   - rigid rotation in a round tank (no gravity) is divergence-free and tangential to the wall, so the
     projection should leave it alone: with the open fractions the largest change of a row velocity is a
     fraction of what the staircase rule of the two-phase path (a face open when its centre is outside the
     solid) makes, on uniform cubic (and at most 0.15 Omega R there) and quadtree tall cells;
   - random quadtrees with the obstacles: the operator is symmetric positive definite and the projection of
     random u* leaves no variational divergence.
   Sample run: mpiexec -n 2 ./test_tallcell_solid     prints one line per check on rank 0. */
#include "talltest.h"

/* Open (positive) fraction of the unit square for phi = nx (x - cx) + ny (y - cy), by the four-triangle rule
   and by counting lattice points. */
static PetscErrorCode Fractions(MPI_Comm comm)
{
  const PetscInt M   = 1000;
  PetscReal      err = 0;

  PetscFunctionBeginUser;
  for (uint64_t q = 0; q < 24; q++) {
    const PetscReal ang = 2 * PETSC_PI * PffTestUniform01(PffTestKey(q, 1, 0, 0));
    const PetscReal cx  = 1.4 * PffTestUniform01(PffTestKey(q, 2, 0, 0)) - 0.2,
                    cy  = 1.4 * PffTestUniform01(PffTestKey(q, 3, 0, 0)) - 0.2;
    const PetscReal nx = PetscCosReal(ang), ny = PetscSinReal(ang);
    const PetscReal corner[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}}; /* cyclic */
    PetscReal       phi[4];
    PetscInt64      open = 0;
    for (PetscInt v = 0; v < 4; v++) phi[v] = nx * (corner[v][0] - cx) + ny * (corner[v][1] - cy);
    for (PetscInt j = 0; j < M; j++)
      for (PetscInt i = 0; i < M; i++) open += nx * ((i + 0.5) / M - cx) + ny * ((j + 0.5) / M - cy) > 0;
    const PetscReal a = PffTallOpenFraction(phi), ref = (PetscReal)open / ((PetscReal)M * M);
    err = PetscMax(err, PetscAbsReal(a - ref));
    PetscCheck(PetscAbsReal(a - ref) <= 2e-3, comm, PETSC_ERR_PLIB,
               "fractions: plane %d: open fraction %.6f, lattice %.6f", (int)q, (double)a, (double)ref);
  }
  PetscCall(PetscPrintf(comm, "fractions: 24 planes, largest |A - lattice area| %.2e (bound 2e-3)\n", (double)err));
  PetscFunctionReturn(PETSC_SUCCESS);
}

#define OMEGA 2.0

static PetscReal Rotation(const PetscReal x[3], PetscInt comp, void *vctx)
{
  (void)vctx;
  return comp == 0 ? -OMEGA * (x[2] - 0.5) : (comp == 2 ? OMEGA * (x[0] - 0.5) : 0.0);
}

/* Largest change of a row velocity that one projection makes to the rotation, relative to Omega R, with the open
   fractions or with the staircase (A >= 1/2 -> 1, else 0). */
static PetscErrorCode RotationChange(MPI_Comm comm, PetscInt uniform, PetscBool staircase, PetscReal *change)
{
  const PetscInt nb[3] = {4, 4, 4};
  Scene          sc    = {0.61, 0, 3, 0};
  Problem        pb;
  PetscInt       chD;

  PetscFunctionBeginUser;
  PetscCall(ProblemCreate(comm, nb, uniform, 11, PETSC_TRUE, &sc, &pb));
  if (staircase) {
    for (PetscInt lb = 0; lb < pb.t.nlocal; lb++)
      for (PetscInt d = 0; d < 3; d++) {
        PffBlockInfo info;
        float       *a;
        PetscCall(PffGridGetBlockInfo(pb.t.grid, lb, &info));
        PetscCall(PffGridGetBlockData(pb.t.grid, pb.A, lb, d, &a));
        for (PetscInt c = 0; c < info.n * info.n * info.n; c++) a[c] = a[c] >= 0.5f ? 1.0f : 0.0f;
      }
    PetscCall(PffGridHaloBegin(pb.t.grid, pb.A));
    PetscCall(PffGridHaloEnd(pb.t.grid, pb.A));
    PetscCall(PffTallBuild(pb.tc, pb.phi));
  }
  PetscCall(PffGridAddChannel(pb.t.grid, "difference", PFF_CHANNEL_FACE, 1, &chD));
  PetscCall(PffGridFillChannel(pb.t.grid, pb.u, Rotation, NULL));
  PetscCall(PffGridFillChannel(pb.t.grid, chD, Rotation, NULL));
  PetscCall(PffTallProject(pb.tc, pb.u, DT, RHO, pb.p, &pb.st));
  for (PetscInt lb = 0; lb < pb.t.nlocal; lb++)
    for (PetscInt d = 0; d < 3; d++) {
      PffBlockInfo info;
      float       *u, *w;
      PetscCall(PffGridGetBlockInfo(pb.t.grid, lb, &info));
      PetscCall(PffGridGetBlockData(pb.t.grid, pb.u, lb, d, &u));
      PetscCall(PffGridGetBlockData(pb.t.grid, chD, lb, d, &w));
      for (PetscInt c = 0; c < info.n * info.n * info.n; c++) w[c] = u[c] - w[c];
    }
  PetscCall(PffTallMaxRowVelocity(pb.tc, chD, change));
  *change /= OMEGA * 0.4;
  PetscCheck(pb.st.reason > 0, comm, PETSC_ERR_PLIB, "rotation: the solve did not converge");
  PetscCall(ProblemDestroy(&pb));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode RotationInTank(MPI_Comm comm)
{
  const char    *name[2]    = {"uniform cubic", "quadtree tall"};
  const PetscInt uniform[2] = {0, -1};

  PetscFunctionBeginUser;
  for (PetscInt q = 0; q < 2; q++) {
    PetscReal frac, stair;
    PetscCall(RotationChange(comm, uniform[q], PETSC_FALSE, &frac));
    PetscCall(RotationChange(comm, uniform[q], PETSC_TRUE, &stair));
    PetscCall(PetscPrintf(comm,
                          "rotation in a round tank, %s: largest row-velocity change / (Omega R) %.3e with the open "
                          "fractions, %.3e with the staircase\n",
                          name[q], (double)frac, (double)stair));
    PetscCheck(
        frac <= 0.5 * stair && (uniform[q] < 0 || frac <= 0.15), comm, PETSC_ERR_PLIB,
        "rotation, %s: the open fractions (%g) do not beat the staircase (%g) by 2x, or above 0.15 on uniform cells",
        name[q], (double)frac, (double)stair);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  PetscCall(Fractions(PETSC_COMM_WORLD));
  {
    const Scene sc = {0.61, 0, 1, 0};
    PetscCall(StillWater(PETSC_COMM_WORLD, "obstacles, uniform cubic", 0, PETSC_FALSE, &sc));
    PetscCall(StillWater(PETSC_COMM_WORLD, "obstacles, uniform tall", 0, PETSC_TRUE, &sc));
    PetscCall(StillWater(PETSC_COMM_WORLD, "obstacles, quadtree tall", -1, PETSC_TRUE, &sc));
    PetscCall(StillWater(PETSC_COMM_WORLD, "obstacles, quadtree cubic", -1, PETSC_FALSE, &sc));
  }
  {
    const Scene sc = {0.61, 3, 2, 0};
    PetscCall(StillWater(PETSC_COMM_WORLD, "two pools behind a wall, uniform cubic", 0, PETSC_FALSE, &sc));
    PetscCall(StillWater(PETSC_COMM_WORLD, "two pools behind a wall, uniform tall", 0, PETSC_TRUE, &sc));
  }
  PetscCall(RotationInTank(PETSC_COMM_WORLD));
  PetscCall(RandomQuadtrees(PETSC_COMM_WORLD, 1));
  PetscCall(PetscFinalize());
  return 0;
}
