/* The quadtree from a sizing function (tall cells Sec. 4.1).

   The sizing function is evaluated on the current cells, at the free surface only (|phi| < 1.5 s and a sign
   change of phi towards a face neighbour):
   the wanted cell size there is h_t = min(c_kappa / |kappa|, c_u / |grad u|), so that the surface turns by at
   most c_kappa radians and the velocity changes by at most c_u m/s across one cell (Ando et al. 2013 use
   curvature and velocity variation). A vertical scan takes the smallest h_t of every block column (the
   paper's 2D image), each block column asks for the coarsest level whose cells are no larger, and the
   grid's 2:1 grading of the map is the paper's smoothing of neighbour sizes. The quadtree's leaves are
   therefore block columns here, not single columns of cells: docs/tallcell.md says why. */
#include "tallimpl.h"

/* Value at block-local (i, j, k), the index clamped to the block along every axis whose step leaves the block
   across a wall (holes bit of that single-axis region): constant extrapolation, so that a wall does not
   look like a surface or a shear layer. */
static PetscReal At(const PffView *v, PetscInt holes, PetscInt n, PetscInt i, PetscInt j, PetscInt k)
{
  PetscInt c[3] = {i, j, k};
  for (PetscInt a = 0; a < 3; a++) {
    if (c[a] >= 0 && c[a] < n) continue;
    PetscInt t[3] = {0, 0, 0};
    t[a]          = c[a];
    if ((holes >> PffRegionIndex(t[0], t[1], t[2], n)) & 1) c[a] = c[a] < 0 ? 0 : n - 1;
  }
  return (PetscReal)*PffViewsAt(v, c[0], c[1], c[2], n);
}

PetscErrorCode PffTallSizingLevels(PffTall tc, PetscInt chPhi, PetscInt chU, PetscInt level[])
{
  PffGrid         grid   = tc->grid;
  const PetscReal cKappa = tc->sizingKappa, cU = tc->sizingU;
  PetscInt        nb[3], glevels, nlevels, nlocal, nbc;
  PetscReal       h0;
  PetscReal      *want, *wantAll;
  MPI_Comm        comm = tc->comm;

  PetscFunctionBeginUser;
  PetscCall(PetscLogEventBegin(PFF_TallSizing, 0, 0, 0, 0));
  PetscCall(PffGridGetRaster(grid, nb, NULL, NULL));
  PetscCall(PffGridGetSizes(grid, NULL, &glevels, NULL, &h0, NULL));
  nlevels = tc->levels > 0 ? PetscMin(tc->levels, glevels) : glevels;
  nbc     = nb[0] * nb[2];
  PetscCall(PetscMalloc2(nbc, &want, nbc, &wantAll));
  for (PetscInt c = 0; c < nbc; c++) want[c] = PETSC_MAX_REAL;
  PetscCall(PffGridHaloBegin(grid, chPhi));
  PetscCall(PffGridHaloEnd(grid, chPhi));
  if (chU >= 0) {
    PetscCall(PffGridHaloBegin(grid, chU));
    PetscCall(PffGridHaloEnd(grid, chU));
  }
  PetscCall(PffGridGetLocalBlocks(grid, &nlocal));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo   info;
    const PffView *vp, *vu[3] = {NULL, NULL, NULL};
    PetscCall(PffGridGetBlockInfo(grid, lb, &info));
    PetscCall(PffGridGetBlockViews(grid, chPhi, lb, 0, &vp));
    if (chU >= 0)
      for (PetscInt a = 0; a < 3; a++) PetscCall(PffGridGetBlockViews(grid, chU, lb, a, &vu[a]));
    const PetscInt  n = info.n, bc = info.ijk[0] + nb[0] * info.ijk[2];
    const PetscReal s = info.h;
    for (PetscInt k = 0; k < n; k++)
      for (PetscInt j = 0; j < n; j++)
        for (PetscInt i = 0; i < n; i++) {
#define P(a, b, c) At(vp, info.holes, n, i + (a), j + (b), k + (c))
          const PetscReal p0 = P(0, 0, 0);
          if (PetscAbsReal(p0) >= 1.5 * s) continue;
          /* a surface cell: the level set changes sign towards a face neighbour (a level set from particles is
             only a distance across the interface layer, |phi| < s also deep inside, where it is noise) */
          if (!((P(1, 0, 0) < 0) != (p0 < 0) || (P(-1, 0, 0) < 0) != (p0 < 0) || (P(0, 1, 0) < 0) != (p0 < 0) ||
                (P(0, -1, 0) < 0) != (p0 < 0) || (P(0, 0, 1) < 0) != (p0 < 0) || (P(0, 0, -1) < 0) != (p0 < 0)))
            continue;
          /* curvature div(grad phi / |grad phi|) from central differences */
          const PetscReal px = (P(1, 0, 0) - P(-1, 0, 0)) / (2 * s), py = (P(0, 1, 0) - P(0, -1, 0)) / (2 * s),
                          pz  = (P(0, 0, 1) - P(0, 0, -1)) / (2 * s);
          const PetscReal pxx = (P(1, 0, 0) - 2 * p0 + P(-1, 0, 0)) / (s * s),
                          pyy = (P(0, 1, 0) - 2 * p0 + P(0, -1, 0)) / (s * s),
                          pzz = (P(0, 0, 1) - 2 * p0 + P(0, 0, -1)) / (s * s);
          const PetscReal pxy = (P(1, 1, 0) - P(1, -1, 0) - P(-1, 1, 0) + P(-1, -1, 0)) / (4 * s * s),
                          pxz = (P(1, 0, 1) - P(1, 0, -1) - P(-1, 0, 1) + P(-1, 0, -1)) / (4 * s * s),
                          pyz = (P(0, 1, 1) - P(0, 1, -1) - P(0, -1, 1) + P(0, -1, -1)) / (4 * s * s);
#undef P
          const PetscReal g2 = px * px + py * py + pz * pz;
          PetscReal       ht = PETSC_MAX_REAL;
          if (g2 > 1e-12) {
            const PetscReal num = px * px * (pyy + pzz) + py * py * (pxx + pzz) + pz * pz * (pxx + pyy) -
                                  2 * (px * py * pxy + px * pz * pxz + py * pz * pyz);
            const PetscReal kappa = PetscAbsReal(num) / PetscPowReal(g2, 1.5);
            /* a cell resolves no curvature above 1 / s: keep the estimate within that */
            if (kappa > 0) ht = PetscMin(ht, cKappa / PetscMin(kappa, 1 / s));
          }
          if (chU >= 0) {
            PetscReal du2 = 0;
            for (PetscInt a = 0; a < 3; a++) {
              const PffView *v  = vu[a];
              const PetscInt hl = info.holes;
              du2 += PetscSqr((At(v, hl, n, i + 1, j, k) - At(v, hl, n, i - 1, j, k)) / (2 * s)) +
                     PetscSqr((At(v, hl, n, i, j + 1, k) - At(v, hl, n, i, j - 1, k)) / (2 * s)) +
                     PetscSqr((At(v, hl, n, i, j, k + 1) - At(v, hl, n, i, j, k - 1)) / (2 * s));
            }
            if (du2 > 0) ht = PetscMin(ht, cU / PetscSqrtReal(du2));
          }
          want[bc] = PetscMin(want[bc], ht);
        }
  }
  PetscCallMPI(MPIU_Allreduce(want, wantAll, (PetscMPIInt)nbc, MPIU_REAL, MPIU_MIN, comm));
  for (PetscInt c = 0; c < nbc; c++) {
    PetscInt l = nlevels - 1;
    while (l > 0 && h0 * (PetscReal)(1 << l) > wantAll[c]) l--;
    for (PetscInt bj = 0; bj < nb[1]; bj++) level[c % nb[0] + nb[0] * (bj + nb[1] * (c / nb[0]))] = l;
  }
  PetscCall(PetscFree2(want, wantAll));
  PetscCall(PetscLogEventEnd(PFF_TallSizing, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}
