/* Quadtree tall cells (src/tallcell/, Narita et al. 2025 Sec. 4.2-4.3):
   - still water: a pool at a height between cell centres, u* = -g dt on the vertical faces; the projection
     leaves every row at rest (|u| <= 1e-6 sqrt(g H)) and p = rho g (H - y) at every liquid cell centre
     (to the float channel's rounding, 1e-6 rho g H),
     tall cells included, for uniform cubic cells, uniform tall cells and a random quadtree of tall cells;
   - the variational matrix of random quadtrees with a wavy surface, a drop and an air pocket is symmetric
     and positive definite (smallest eigenvalue of the explicit operator > 0), and a projection of random u*
     leaves no variational divergence;
   - the same random problem on this communicator and on one rank gives the same counts and the same
     cell pressures (partition independence);
   - the sizing function: a flat pool at rest asks for the coarsest level everywhere (walls are not
     surfaces), a falling drop above it asks for the finest level over the drop and the coarsest far away;
   - -grid_refine_columns turns a sphere refinement into a quadtree (levels constant along y) that the tall
     cells accept;
   - bad input: levels that change along y, an out-of-range option.
   Sample run: mpiexec -n 4 ./test_tallcell     prints one line per check on rank 0. */
#include "talltest.h"

/* gravity, and -2 m/s inside the drop of shape 2 */
static PetscReal DropU(const PetscReal x[3], PetscInt comp, void *vctx)
{
  const PetscReal d = PetscSqrtReal(PetscSqr(x[0] - 0.45) + PetscSqr(x[1] - 0.8) + PetscSqr(x[2] - 0.45));
  return Gravity(x, comp, vctx) + (comp == 1 && d < 0.1 ? -2.0 : 0.0);
}

/* The same problem on comm and on one rank. */
static PetscErrorCode PartitionIndependence(MPI_Comm comm)
{
  const PetscInt nb[3] = {4, 4, 4};
  Scene          sc    = {0.55, 1, 0, 0};
  Problem        pa, ps;
  PetscReal      ea, es, wa, ws;

  PetscFunctionBeginUser;
  PetscCall(ProblemCreate(comm, nb, -1, 7, PETSC_TRUE, &sc, &pa));
  PetscCall(ProblemCreate(PETSC_COMM_SELF, nb, -1, 7, PETSC_TRUE, &sc, &ps));
  PetscCall(PffGridFillChannel(pa.t.grid, pa.u, Gravity, NULL));
  PetscCall(PffGridFillChannel(ps.t.grid, ps.u, Gravity, NULL));
  PetscCall(PffTallProject(pa.tc, pa.u, DT, RHO, pa.p, &pa.st));
  PetscCall(PffTallProject(ps.tc, ps.u, DT, RHO, ps.p, &ps.st));
  PetscCall(PressureCheck(&pa, &sc, &ea, &wa));
  PetscCall(PressureCheck(&ps, &sc, &es, &ws));
  PetscCall(PetscPrintf(comm,
                        "partition independence: %" PetscInt64_FMT " / %" PetscInt64_FMT " samples, %" PetscInt64_FMT
                        " / %" PetscInt64_FMT " rows, weighted pressure sums %.12e / %.12e\n",
                        pa.st.samples, ps.st.samples, pa.st.rows, ps.st.rows, (double)wa, (double)ws));
  PetscCheck(pa.st.samples == ps.st.samples && pa.st.rows == ps.st.rows && pa.st.cells == ps.st.cells, comm,
             PETSC_ERR_PLIB, "partition independence: the counts differ");
  PetscCheck(PetscAbsReal(wa - ws) <= 1e-8 * PetscAbsReal(ws), comm, PETSC_ERR_PLIB,
             "partition independence: pressures differ (%.12e vs %.12e)", (double)wa, (double)ws);
  PetscCall(ProblemDestroy(&pa));
  PetscCall(ProblemDestroy(&ps));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The sizing function's level map on a uniform grid of 4 x 4 x 4 blocks (block columns of 0.25 x 0.25). */
static PetscErrorCode Sizing(MPI_Comm comm)
{
  const PetscInt nb[3] = {4, 4, 4};
  PetscInt       level[64];

  PetscFunctionBeginUser;
  for (PetscInt shape = 0; shape <= 2; shape += 2) {
    Scene   sc = {0.61, shape, 0, 0};
    Problem pb;
    PetscCall(ProblemCreate(comm, nb, 0, 1, PETSC_TRUE, &sc, &pb));
    PetscCall(PffGridFillChannel(pb.t.grid, pb.u, shape ? DropU : Gravity, NULL));
    PetscCall(PffTallSizingLevels(pb.tc, pb.phi, pb.u, level));
    for (PetscInt b = 0; b < 64; b++)
      PetscCheck(level[b] == level[b % 4 + 16 * (b / 16)], comm, PETSC_ERR_PLIB, "sizing: levels change along y");
    if (shape == 0)
      for (PetscInt b = 0; b < 64; b++)
        PetscCheck(level[b] == 2, comm, PETSC_ERR_PLIB,
                   "sizing, still pool: block %" PetscInt_FMT " asks for level %" PetscInt_FMT, b, level[b]);
    else {
      /* the drop (centre 0.45, radius 0.1) lies over block columns 1..2 in x and z; column (0, 3) is far away */
      PetscCheck(level[1 + 16 * 1] == 0 && level[2 + 16 * 2] == 0 && level[0 + 16 * 3] == 2 && level[3 + 16 * 0] == 2,
                 comm, PETSC_ERR_PLIB,
                 "sizing, drop: levels %" PetscInt_FMT " %" PetscInt_FMT " %" PetscInt_FMT " %" PetscInt_FMT,
                 level[1 + 16], level[2 + 32], level[48], level[3]);
    }
    PetscCall(PetscPrintf(comm,
                          "sizing, %s: block-column levels %" PetscInt_FMT "%" PetscInt_FMT "%" PetscInt_FMT
                          "%" PetscInt_FMT " / %" PetscInt_FMT "%" PetscInt_FMT "%" PetscInt_FMT "%" PetscInt_FMT
                          " / %" PetscInt_FMT "%" PetscInt_FMT "%" PetscInt_FMT "%" PetscInt_FMT " / %" PetscInt_FMT
                          "%" PetscInt_FMT "%" PetscInt_FMT "%" PetscInt_FMT " (z rows)\n",
                          shape ? "falling drop" : "still pool", level[0], level[1], level[2], level[3], level[16],
                          level[17], level[18], level[19], level[32], level[33], level[34], level[35], level[48],
                          level[49], level[50], level[51]));
    PetscCall(ProblemDestroy(&pb));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* -grid_refine sphere with -grid_refine_columns: every block column takes its finest level. */
static PetscErrorCode RefineColumns(MPI_Comm comm)
{
  PffGrid         grid;
  PffTall         tc;
  const PetscInt *level;
  PetscInt        nb[3], hist[3] = {0, 0, 0};

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsSetValue(NULL, "-grid_cells", "64,32,64"));
  PetscCall(PetscOptionsSetValue(NULL, "-grid_block_size", "8"));
  PetscCall(PetscOptionsSetValue(NULL, "-grid_levels", "3"));
  PetscCall(PetscOptionsSetValue(NULL, "-grid_refine", "sphere"));
  PetscCall(PetscOptionsSetValue(NULL, "-grid_refine_point", "0.5,0.2,0.5"));
  PetscCall(PetscOptionsSetValue(NULL, "-grid_refine_radius", "0.1"));
  PetscCall(PetscOptionsSetValue(NULL, "-grid_refine_band", "0.5"));
  PetscCall(PetscOptionsSetValue(NULL, "-grid_refine_columns", "true"));
  PetscCall(PetscOptionsSetValue(NULL, "-partition_type", "columns"));
  PetscCall(PffGridCreate(comm, &grid));
  PetscCall(PffGridSetFromOptions(grid));
  PetscCall(PffGridSetUp(grid));
  const char *keys[] = {"-grid_cells",       "-grid_block_size",     "-grid_levels",
                        "-grid_refine",      "-grid_refine_point",   "-grid_refine_radius",
                        "-grid_refine_band", "-grid_refine_columns", "-partition_type"};
  for (size_t k = 0; k < PETSC_STATIC_ARRAY_LENGTH(keys); k++) PetscCall(PetscOptionsClearValue(NULL, keys[k]));
  PetscCall(PffGridGetRaster(grid, nb, &level, NULL));
  for (PetscInt b = 0; b < nb[0] * nb[1] * nb[2]; b++) {
    const PetscInt b0 = b % nb[0] + nb[0] * nb[1] * (b / (nb[0] * nb[1]));
    PetscCheck(level[b] == level[b0], comm, PETSC_ERR_PLIB,
               "refine columns: block %" PetscInt_FMT " at level %" PetscInt_FMT
               ", its column's bottom at %" PetscInt_FMT,
               b, level[b], level[b0]);
    if (b == b0) hist[level[b]]++;
  }
  PetscCheck(hist[0] > 0 && hist[2] > 0, comm, PETSC_ERR_PLIB,
             "refine columns: block columns per level %" PetscInt_FMT " %" PetscInt_FMT " %" PetscInt_FMT, hist[0],
             hist[1], hist[2]);
  PetscCall(PffTallCreate(grid, &tc));
  PetscCall(PffTallDestroy(&tc));
  PetscCall(PffGridDestroy(&grid));
  PetscCall(PetscPrintf(comm,
                        "refine columns: block columns per level %" PetscInt_FMT " / %" PetscInt_FMT " / %" PetscInt_FMT
                        ", constant along y, accepted\n",
                        hist[0], hist[1], hist[2]));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Bad input: one clear error each. */
static PetscErrorCode BadInput(MPI_Comm comm)
{
  PetscErrorCode ierr;
  PffTestCtx     t;
  PffTall        tc = NULL;
  PetscInt       phi;

  PetscFunctionBeginUser;
  {
    /* levels that change along y */
    const PetscInt  nb[3] = {2, 2, 2}, cells[3] = {2 * N0, 2 * N0, 2 * N0};
    PetscInt        request[8] = {0, 0, 1, 1, 0, 0, 1, 1};
    const PetscReal origin[3]  = {0, 0, 0};
    (void)nb;
    PetscCall(PffGridCreate(comm, &t.grid));
    PetscCall(PffGridSetCells(t.grid, cells));
    PetscCall(PffGridSetBlockSize(t.grid, N0));
    PetscCall(PffGridSetLevels(t.grid, 2));
    PetscCall(PffGridSetDomain(t.grid, origin, 1.0 / (2 * N0)));
    PetscCall(PffGridSetPartitionType(t.grid, PFF_PARTITION_COLUMNS));
    PetscCall(PffGridSetRefinementMap(t.grid, request));
    PetscCall(PffGridSetUp(t.grid));
    PetscCall(PffGridAddChannel(t.grid, "phi", PFF_CHANNEL_CELL, 1, &phi));
    PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
    ierr = PffTallCreate(t.grid, &tc);
    PetscCall(PetscPopErrorHandler());
    PetscCheck(ierr == PETSC_ERR_ARG_WRONG, comm, PETSC_ERR_PLIB, "levels along y: error %d", (int)ierr);
    PetscCall(PffTallDestroy(&tc));
    PetscCall(PffGridDestroy(&t.grid));
  }
  {
    const PetscInt nb[3] = {2, 2, 2};
    Scene          sc    = {0.5, 0, 0, 0};
    Problem        pb;
    PetscCall(ProblemCreate(comm, nb, 0, 1, PETSC_TRUE, &sc, &pb));
    PetscCall(PetscOptionsSetValue(NULL, "-tall_layer_fraction", "2"));
    PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
    ierr = PffTallSetFromOptions(pb.tc);
    PetscCall(PetscPopErrorHandler());
    PetscCall(PetscOptionsClearValue(NULL, "-tall_layer_fraction"));
    PetscCheck(ierr == PETSC_ERR_ARG_OUTOFRANGE, comm, PETSC_ERR_PLIB, "-tall_layer_fraction 2: error %d", (int)ierr);
    PetscCall(ProblemDestroy(&pb));
  }
  PetscCall(PetscPrintf(comm, "bad input: levels along y and -tall_layer_fraction 2 are refused\n"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  {
    const Scene sc = {0.61, 0, 0, 0};
    PetscCall(StillWater(PETSC_COMM_WORLD, "uniform cubic", 0, PETSC_FALSE, &sc));
    PetscCall(StillWater(PETSC_COMM_WORLD, "uniform tall", 0, PETSC_TRUE, &sc));
    PetscCall(StillWater(PETSC_COMM_WORLD, "quadtree tall", -1, PETSC_TRUE, &sc));
    PetscCall(StillWater(PETSC_COMM_WORLD, "quadtree cubic", -1, PETSC_FALSE, &sc));
  }
  PetscCall(RandomQuadtrees(PETSC_COMM_WORLD, 0));
  PetscCall(PartitionIndependence(PETSC_COMM_WORLD));
  PetscCall(Sizing(PETSC_COMM_WORLD));
  PetscCall(RefineColumns(PETSC_COMM_WORLD));
  PetscCall(BadInput(PETSC_COMM_WORLD));
  PetscCall(PetscFinalize());
  return 0;
}
