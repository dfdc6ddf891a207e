/* World <-> (block, cell) mapping and trilinear interpolation on the adaptive grid.

   The finest-level cell index I = floor((x - origin) / h0) gives the block by a shift,
   I >> log2(n0), and the cell at the block's level l by a mask and a shift, (I & (n0 - 1)) >> l.
   Interpolation uses the lattice of the block containing the point and reaches at most one cell
   into its 26 neighbour regions, whose ghosts are exact (same level) or linear-exact (other
   levels), so linear fields are reproduced exactly across level boundaries. Across a wall (or an
   inactive neighbour) the stencil is clamped to the last cell, except for the wall face itself of a
   MAC component, whose ghost holds the boundary value. */
#include "gridimpl.h"

/* Position in finest-cell units along axis d, wrapped into [0, cells) on periodic axes. Wrapping in
   index space avoids origin + fmod(...) rounding up to the upper boundary for a point a hair
   below the lower one. */
static inline PetscReal PffIndexCoord(PffGrid g, PetscReal x, int d)
{
  const PetscReal n = (PetscReal)g->cells[d];
  PetscReal       s = (x - g->origin[d]) / g->h0;
  if (g->periodic[d]) {
    s = PetscFmodReal(s, n);
    if (s < 0) s += n;
    if (s >= n) s = 0;
  }
  return s;
}

static void PffLocateIndex(PffGrid g, const PetscReal s[3], PetscInt *gid, PetscInt *level, PetscInt cell[3])
{
  PetscInt fi[3], b[3];

  *gid = -1;
  for (int d = 0; d < 3; d++) {
    if (!(s[d] >= 0 && s[d] < (PetscReal)g->cells[d])) return;
    fi[d] = (PetscInt)s[d];
    b[d]  = fi[d] >> g->log2n0;
  }
  const PetscInt id = b[0] + g->nb[0] * (b[1] + g->nb[1] * b[2]);
  if (g->level[id] < 0) return;
  *gid = id;
  if (level) *level = g->level[id];
  if (cell)
    for (int d = 0; d < 3; d++) cell[d] = (fi[d] & (g->n0 - 1)) >> g->level[id];
}

PetscErrorCode PffGridLocate(PffGrid g, const PetscReal x[3], PetscInt *gid, PetscInt *level, PetscInt cell[3])
{
  PetscReal s[3];

  PetscFunctionBeginUser;
  for (int d = 0; d < 3; d++) s[d] = PffIndexCoord(g, x[d], d);
  PffLocateIndex(g, s, gid, level, cell);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Trilinear interpolation at lp, the position in cell units of local block lb's level relative to
   its lower corner (n cells per axis, hole bits of its 26 neighbour regions), on the block's
   lattice, whose 27 views reach width cells beyond it. */
static PetscReal PffInterpolateInBlock(const PffChannel *c, PetscInt lb, PetscInt n, PetscInt holes,
                                       const PetscReal lp[3], PetscInt comp)
{
  const PffView *views = &c->views[(lb * c->ncomp + comp) * 27];
  PetscInt       i0[3], i1[3];
  PetscReal      t[3], o[3];

  for (int a = 0; a < 3; a++) o[a] = PffChannelOffset_Private(c->kind, comp, a);
  if (!PffStencilClamped(n, holes, o, lp, i0, i1, t)) {
    /* the whole stencil in the block's own cells (most samples): one view, fixed strides, no hole
       test; the same weights and summation order as below, so the value is bit-identical */
    const PffView *v     = &views[13];
    const float   *base  = v->ptr + (v->off + i0[0] * v->sx + i0[1] * v->sy + i0[2] * v->sz);
    const PetscInt st[8] = {0, v->sx, v->sy, v->sx + v->sy, v->sz, v->sx + v->sz, v->sy + v->sz, v->sx + v->sy + v->sz};
    const PetscReal wx[2] = {1 - t[0], t[0]}, wy[2] = {1 - t[1], t[1]}, wz[2] = {1 - t[2], t[2]};
    PetscReal       val = 0;
    for (int q = 0; q < 8; q++) {
      const PetscReal w = wx[q & 1] * wy[(q >> 1) & 1] * wz[(q >> 2) & 1];
      if (w != 0) val += w * (PetscReal)base[st[q]];
    }
    return val;
  }
  PetscReal v = 0;
  for (int q = 0; q < 8; q++) {
    const PetscInt  ii = (q & 1) ? i1[0] : i0[0], jj = (q & 2) ? i1[1] : i0[1], kk = (q & 4) ? i1[2] : i0[2];
    const PetscReal w = ((q & 1) ? t[0] : 1 - t[0]) * ((q & 2) ? t[1] : 1 - t[1]) * ((q & 4) ? t[2] : 1 - t[2]);
    if (w != 0) v += w * (PetscReal)*PffViewsAt(views, ii, jj, kk, n);
  }
  return v;
}

/* Every component of channel c at block-index position sp (finest-cell units) in local block lb:
   the block's place and level are looked up once per point. Division by 2^level is exact, so the
   values are those of dividing per component. */
static inline void PffInterpolatePoint(PffGrid g, const PffChannel *c, PetscInt lb, const PetscReal sp[3],
                                       PetscReal val[])
{
  const PetscInt  gid = g->lgid[lb], level = g->level[gid], n = g->n0 >> level, holes = g->lholes[lb];
  const PetscReal inv = 1.0 / (PetscReal)((PetscInt)1 << level);
  PetscInt        ijk[3];
  PetscReal       lp[3];

  PffGridBlockIJK_Private(g, gid, ijk);
  for (int a = 0; a < 3; a++) lp[a] = (sp[a] - (PetscReal)(ijk[a] * g->n0)) * inv;
  for (PetscInt comp = 0; comp < c->ncomp; comp++) val[comp] = PffInterpolateInBlock(c, lb, n, holes, lp, comp);
}

PetscReal PffGridInterpolateInBlock(PffGrid g, PetscInt ch, PetscInt lb, PetscInt comp, const PetscReal lp[3])
{
  const PffChannel *c = g->ch[ch];
  return PffInterpolateInBlock(c, lb, PffGridBlockN_Private(g, g->lgid[lb]), g->lholes[lb], lp, comp);
}

PetscErrorCode PffGridInterpolate(PffGrid g, PetscInt ch, PetscInt np, const PetscReal x[], PetscReal val[])
{
  PffChannel *c = NULL;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetChannel_Private(g, ch, &c));
  PetscCall(PetscLogEventBegin(PFF_GridInterp, 0, 0, 0, 0));
  for (PetscInt p = 0; p < np; p++) {
    PetscInt  gid, lb;
    PetscReal sp[3];
    for (int d = 0; d < 3; d++) sp[d] = PffIndexCoord(g, x[3 * p + d], d);
    PffLocateIndex(g, sp, &gid, NULL, NULL);
    lb = gid >= 0 ? g->local[gid] : -1;
    PetscCheck(lb >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
               "point (%g, %g, %g) is not in a block owned by this rank", (double)x[3 * p], (double)x[3 * p + 1],
               (double)x[3 * p + 2]);
    PffInterpolatePoint(g, c, lb, sp, &val[p * c->ncomp]);
  }
  PetscCall(PetscLogEventEnd(PFF_GridInterp, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridInterpolateFrom(PffGrid g, PetscInt ch, PetscInt np, const PetscReal x[], const PetscInt lb[],
                                      PetscReal val[])
{
  PffChannel *c = NULL;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetChannel_Private(g, ch, &c));
  PetscCall(PetscLogEventBegin(PFF_GridInterp, 0, 0, 0, 0));
  for (PetscInt p = 0; p < np; p++) {
    PetscCheck(lb[p] >= 0 && lb[p] < g->nlocal, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
               "local block %" PetscInt_FMT " of point %" PetscInt_FMT " is not owned by this rank", lb[p], p);
    const PetscInt gid = g->lgid[lb[p]], level = g->level[gid];
    PetscInt       ijk[3];
    PetscReal      sp[3];
    PffGridBlockIJK_Private(g, gid, ijk);
    for (int d = 0; d < 3; d++) {
      sp[d] = (x[3 * p + d] - g->origin[d]) / g->h0;
      if (g->periodic[d]) { /* the periodic image nearest to the block's centre */
        const PetscReal L = (PetscReal)g->cells[d], centre = (PetscReal)(ijk[d] * g->n0) + 0.5 * (PetscReal)g->n0;
        sp[d] -= L * PetscFloorReal((sp[d] - centre) / L + 0.5);
      }
      const PetscReal reach = (PetscReal)((c->width - 1) << level), lo = (PetscReal)(ijk[d] * g->n0);
      PetscCheck(
          sp[d] >= lo - reach && sp[d] <= lo + (PetscReal)g->n0 + reach, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
          "point %" PetscInt_FMT " lies %g cells outside its block, beyond the halo of channel %s", p,
          (double)(PetscMax(lo - sp[d], sp[d] - lo - (PetscReal)g->n0) / (PetscReal)((PetscInt)1 << level)), c->name);
    }
    PffInterpolatePoint(g, c, lb[p], sp, &val[p * c->ncomp]);
  }
  PetscCall(PetscLogEventEnd(PFF_GridInterp, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}
