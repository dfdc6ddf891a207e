/* The fast row kernel of PffGridApplyLaplacian (streaming stores, corrected end cells) against a
   plain per-cell evaluation through PffViewsAt, on uniform and graded multi-level grids with
   periodic and walled axes, block sizes 8 and 16. Runs at 1, 2 and 4 ranks. */
#include <pff.h>

static PetscReal SmoothField(const PetscReal x[3], PetscInt comp, void *ctx)
{
  return PetscSinReal(3 * x[0] + 1) * PetscCosReal(2 * x[1]) + 0.5 * x[2] * x[2];
}

static PetscErrorCode CheckCase(PetscInt n0, PetscInt levels, PetscBool periodic, PetscInt seed)
{
  PffGrid   grid;
  PetscInt  u, lap, nlocal, nb[3] = {3, 2, 4}, cells[3], *map;
  PetscBool per[3]    = {periodic, PETSC_FALSE, periodic};
  PetscReal origin[3] = {0, 0, 0}, maxerr = 0, maxval = 0, gerr, gval;

  PetscFunctionBeginUser;
  for (int d = 0; d < 3; d++) cells[d] = nb[d] * n0;
  PetscCall(PetscMalloc1(nb[0] * nb[1] * nb[2], &map));
  for (PetscInt b = 0; b < nb[0] * nb[1] * nb[2]; b++)
    map[b] = (PetscInt)(((unsigned)(b * 2654435761u + seed * 40503u) >> 7) % levels);
  PetscCall(PffGridCreate(PETSC_COMM_WORLD, &grid));
  PetscCall(PffGridSetCells(grid, cells));
  PetscCall(PffGridSetBlockSize(grid, n0));
  PetscCall(PffGridSetLevels(grid, levels));
  PetscCall(PffGridSetDomain(grid, origin, 0.1));
  PetscCall(PffGridSetPeriodic(grid, per));
  PetscCall(PffGridSetRefinementMap(grid, map));
  PetscCall(PffGridAddChannel(grid, "u", PFF_CHANNEL_CELL, 1, &u));
  PetscCall(PffGridAddChannel(grid, "lap", PFF_CHANNEL_CELL, 1, &lap));
  PetscCall(PffGridSetUp(grid));
  PetscCall(PffGridGetLocalBlocks(grid, &nlocal));
  PetscCall(PffGridFillChannel(grid, u, SmoothField, NULL));
  PetscCall(PffGridHaloBegin(grid, u));
  PetscCall(PffGridHaloEnd(grid, u));
  PetscCall(PffGridApplyLaplacian(grid, u, lap));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo   info;
    const PffView *views;
    float         *out;
    PetscCall(PffGridGetBlockInfo(grid, lb, &info));
    PetscCall(PffGridGetBlockViews(grid, u, lb, 0, &views));
    PetscCall(PffGridGetBlockData(grid, lap, lb, 0, &out));
    const PetscInt  n   = info.n;
    const PetscReal ih2 = 1.0 / (info.h * info.h);
    for (PetscInt k = 0; k < n; k++)
      for (PetscInt j = 0; j < n; j++)
        for (PetscInt i = 0; i < n; i++) {
          const PetscReal c   = *PffViewsAt(views, i, j, k, n);
          const PetscReal ref = ((PetscReal)*PffViewsAt(views, i - 1, j, k, n) + *PffViewsAt(views, i + 1, j, k, n) +
                                 *PffViewsAt(views, i, j - 1, k, n) + *PffViewsAt(views, i, j + 1, k, n) +
                                 *PffViewsAt(views, i, j, k - 1, n) + *PffViewsAt(views, i, j, k + 1, n) - 6 * c) *
                                ih2;
          maxerr = PetscMax(maxerr, PetscAbsReal(ref - (PetscReal)out[i + n * (j + n * k)]));
          maxval = PetscMax(maxval, PetscAbsReal(c) * ih2);
        }
  }
  PetscCall(MPIU_Allreduce(&maxerr, &gerr, 1, MPIU_REAL, MPIU_MAX, PETSC_COMM_WORLD));
  PetscCall(MPIU_Allreduce(&maxval, &gval, 1, MPIU_REAL, MPIU_MAX, PETSC_COMM_WORLD));
  /* float stencil: the sum of 7 terms of size |c|/h^2 carries a rounding of a few ulps of that */
  PetscCheck(gerr <= 1e-5 * gval, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
             "Laplacian n0=%" PetscInt_FMT " levels=%" PetscInt_FMT " periodic=%d: max error %g against scale %g", n0,
             levels, (int)periodic, (double)gerr, (double)gval);
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "laplacian n0=%" PetscInt_FMT " levels=%" PetscInt_FMT " periodic=%d ok\n",
                        n0, levels, (int)periodic));
  PetscCall(PffGridDestroy(&grid));
  PetscCall(PetscFree(map));
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  PetscCall(PffInitializePackage());
  for (PetscInt seed = 0; seed < 3; seed++) {
    PetscCall(CheckCase(16, 1, PETSC_TRUE, seed));
    PetscCall(CheckCase(16, 3, PETSC_FALSE, seed));
    PetscCall(CheckCase(8, 3, PETSC_TRUE, seed));
    PetscCall(CheckCase(8, 4, PETSC_FALSE, seed));
  }
  PetscCall(PetscFinalize());
  return 0;
}
