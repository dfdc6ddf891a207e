/* World <-> (block, cell) mapping and trilinear interpolation on the adaptive grid.

   The finest-level cell index I = floor((x - origin) / h0) gives the block by a shift,
   I >> log2(n0), and the cell at the block's level l by a mask and a shift, (I & (n0 - 1)) >> l.
   Interpolation uses the lattice of the block containing the point and reaches at most one cell
   into its 26 neighbour regions, whose ghosts are exact (same level) or linear-exact (other
   levels), so linear fields are reproduced exactly across level boundaries. Across a wall (or an
   inactive neighbour) the stencil is clamped to the last cell, except for the wall face itself of a
   MAC component, whose ghost holds the boundary value. */
#include "gridimpl.h"

static inline PetscReal PffWrap(PetscReal x, PetscReal lo, PetscReal len)
{
  PetscReal r = PetscFmodReal(x - lo, len);
  if (r < 0) r += len;
  return lo + r;
}

PetscErrorCode PffGridLocate(PffGrid g, const PetscReal x[3], PetscInt *gid, PetscInt *level, PetscInt cell[3])
{
  PetscInt fi[3], b[3];

  PetscFunctionBeginUser;
  *gid = -1;
  for (int d = 0; d < 3; d++) {
    PetscReal xd = x[d];
    if (g->periodic[d]) xd = PffWrap(xd, g->origin[d], g->h0 * (PetscReal)g->cells[d]);
    const PetscReal s = (xd - g->origin[d]) / g->h0;
    if (!(s >= 0 && s < (PetscReal)g->cells[d])) PetscFunctionReturn(PETSC_SUCCESS);
    fi[d] = (PetscInt)s;
    b[d]  = fi[d] >> g->log2n0;
  }
  const PetscInt id = b[0] + g->nb[0] * (b[1] + g->nb[1] * b[2]);
  if (g->level[id] < 0) PetscFunctionReturn(PETSC_SUCCESS);
  *gid = id;
  if (level) *level = g->level[id];
  if (cell)
    for (int d = 0; d < 3; d++) cell[d] = (fi[d] & (g->n0 - 1)) >> g->level[id];
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridInterpolate(PffGrid g, PetscInt ch, PetscInt np, const PetscReal x[], PetscReal val[])
{
  PetscFunctionBeginUser;
  PetscCheck(ch >= 0 && ch < g->nch, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "no channel %" PetscInt_FMT, ch);
  const PffChannel *c = g->ch[ch];
  PetscCall(PetscLogEventBegin(PFF_GridInterp, 0, 0, 0, 0));
  for (PetscInt p = 0; p < np; p++) {
    PetscInt  gid, level, lb;
    PetscReal xp[3];
    for (int d = 0; d < 3; d++)
      xp[d] = g->periodic[d] ? PffWrap(x[3 * p + d], g->origin[d], g->h0 * (PetscReal)g->cells[d]) : x[3 * p + d];
    PetscCall(PffGridLocate(g, xp, &gid, &level, NULL));
    lb = gid >= 0 ? g->local[gid] : -1;
    PetscCheck(lb >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
               "point (%g, %g, %g) is not in a block owned by this rank", (double)xp[0], (double)xp[1], (double)xp[2]);
    const PetscInt n      = g->n0 >> level,
                   ijk[3] = {gid % g->nb[0], (gid / g->nb[0]) % g->nb[1], gid / (g->nb[0] * g->nb[1])};
    const PetscReal h     = g->h0 * (PetscReal)((PetscInt)1 << level);
    PetscBool       wall[3][2];
    for (int a = 0; a < 3; a++)
      for (int s = 0; s < 2; s++) {
        PetscInt d[3]      = {0, 0, 0};
        d[a]               = s ? 1 : -1;
        const PetscInt nbr = PffRasterNeighbour(g->nb, g->periodic, ijk, d);
        wall[a][s]         = (PetscBool)(nbr < 0 || g->level[nbr] < 0);
      }
    for (PetscInt comp = 0; comp < c->ncomp; comp++) {
      const PffView *views = &c->views[(lb * c->ncomp + comp) * 27];
      PetscInt       i0[3], i1[3];
      PetscReal      t[3];
      for (int a = 0; a < 3; a++) {
        const PetscReal o  = PffChannelOffset_Private(c->kind, comp, a);
        const PetscReal lo = g->origin[a] + (PetscReal)(ijk[a] * g->n0) * g->h0;
        const PetscReal s  = (xp[a] - lo) / h - o;
        i0[a]              = (PetscInt)PetscFloorReal(s);
        t[a]               = s - (PetscReal)i0[a];
        i1[a]              = i0[a] + 1;
        /* clamp across walls; a staggered component keeps its wall face (index n) */
        if (i0[a] < 0 && wall[a][0]) {
          i0[a] = 0;
          t[a]  = 0;
        }
        if (i1[a] >= n && wall[a][1] && !(o == 0.0 && i1[a] == n)) {
          i1[a] = n - 1;
          t[a]  = i0[a] == i1[a] ? 0 : t[a];
          if (i0[a] > n - 1) i0[a] = n - 1;
        }
      }
      PetscReal v = 0;
      for (int q = 0; q < 8; q++) {
        const PetscInt  ii = (q & 1) ? i1[0] : i0[0], jj = (q & 2) ? i1[1] : i0[1], kk = (q & 4) ? i1[2] : i0[2];
        const PetscReal w = ((q & 1) ? t[0] : 1 - t[0]) * ((q & 2) ? t[1] : 1 - t[1]) * ((q & 4) ? t[2] : 1 - t[2]);
        if (w != 0) v += w * (PetscReal)*PffViewsAt(views, ii, jj, kk, n);
      }
      val[p * c->ncomp + comp] = v;
    }
  }
  PetscCall(PetscLogEventEnd(PFF_GridInterp, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}
