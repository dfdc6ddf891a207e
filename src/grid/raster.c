/* Block raster (PF-FLIP paper Sec. 4.2): the refinement map M[b] from a callback, an explicit map
   or a static plane/sphere criterion, 2:1 grading, and Morton keys computed once per block.

   Grading runs over all 26 neighbours, not only the 6 face neighbours: P2G and trilinear
   interpolation reach across block edges and corners, and their ghost regions then never span more
   than one level. Levels are processed finest first, so each pass only lowers neighbours that a
   finer pass has fixed: O(levels x blocks x 26). */
#include "gridimpl.h"

PetscInt PffRasterNeighbour(const PetscInt nb[3], const PetscBool periodic[3], const PetscInt ijk[3],
                            const PetscInt d[3])
{
  PetscInt c[3];
  for (int a = 0; a < 3; a++) {
    c[a] = ijk[a] + d[a];
    if (c[a] < 0 || c[a] >= nb[a]) {
      if (!periodic[a]) return -1;
      c[a] = (c[a] + nb[a]) % nb[a];
    }
  }
  return c[0] + nb[0] * (c[1] + nb[1] * c[2]);
}

PetscErrorCode PffGradeLevels(const PetscInt nb[3], const PetscBool periodic[3], PetscInt level[])
{
  const PetscInt nblocks = nb[0] * nb[1] * nb[2];
  PetscInt       maxl    = -1;

  PetscFunctionBeginUser;
  for (PetscInt b = 0; b < nblocks; b++) maxl = PetscMax(maxl, level[b]);
  for (PetscInt l = 0; l < maxl; l++) {
    for (PetscInt b = 0; b < nblocks; b++) {
      if (level[b] != l) continue;
      PetscInt ijk[3];
      PffRasterCoordinates(nb, b, ijk);
      for (PetscInt dz = -1; dz <= 1; dz++)
        for (PetscInt dy = -1; dy <= 1; dy++)
          for (PetscInt dx = -1; dx <= 1; dx++) {
            const PetscInt d[3] = {dx, dy, dz};
            const PetscInt nbr  = PffRasterNeighbour(nb, periodic, ijk, d);
            if (nbr >= 0 && level[nbr] > l + 1) level[nbr] = l + 1;
          }
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Distance from the box [lo, hi] to the refinement surface (0 when the box touches it). */
static PetscReal PffGridSurfaceDistance(PffGrid g, const PetscReal lo[3], const PetscReal hi[3])
{
  if (g->rtype == PFF_REFINE_PLANE) {
    PetscReal smin = PETSC_MAX_REAL, smax = -PETSC_MAX_REAL;
    for (int c = 0; c < 8; c++) {
      PetscReal s = 0;
      for (int d = 0; d < 3; d++) s += g->rnormal[d] * (((c >> d) & 1 ? hi[d] : lo[d]) - g->rpoint[d]);
      smin = PetscMin(smin, s);
      smax = PetscMax(smax, s);
    }
    return (smin <= 0 && smax >= 0) ? 0.0 : PetscMin(PetscAbsReal(smin), PetscAbsReal(smax));
  }
  PetscReal dmin = 0, dmax = 0;
  for (int d = 0; d < 3; d++) {
    const PetscReal c = g->rpoint[d], near = c < lo[d] ? lo[d] - c : (c > hi[d] ? c - hi[d] : 0.0);
    const PetscReal far = PetscMax(PetscAbsReal(c - lo[d]), PetscAbsReal(c - hi[d]));
    dmin += near * near;
    dmax += far * far;
  }
  dmin = PetscSqrtReal(dmin);
  dmax = PetscSqrtReal(dmax);
  if (g->rradius < dmin) return dmin - g->rradius;
  if (g->rradius > dmax) return g->rradius - dmax;
  return 0.0;
}

static PetscErrorCode PffGridRequestedLevels(PffGrid g)
{
  const PetscReal blen = g->h0 * (PetscReal)g->n0;

  PetscFunctionBeginUser;
  for (PetscInt b = 0; b < g->nblocks; b++) {
    const PetscInt ijk[3] = {b % g->nb[0], (b / g->nb[0]) % g->nb[1], b / (g->nb[0] * g->nb[1])};
    PetscReal      lo[3], hi[3];
    PetscInt       l = 0;
    for (int d = 0; d < 3; d++) {
      lo[d] = g->origin[d] + (PetscReal)ijk[d] * blen;
      hi[d] = lo[d] + blen;
    }
    if (g->usermap)
      l = g->usermap[b];
    else if (g->refine)
      PetscCall(g->refine(g, lo, hi, &l, g->refinectx));
    else if (g->rtype != PFF_REFINE_NONE) {
      const PetscReal dist = PffGridSurfaceDistance(g, lo, hi);
      l                    = (PetscInt)PetscMin((PetscReal)(g->nlevels - 1), PetscFloorReal(dist / (g->rband * blen)));
    }
    PetscCheck(l >= -1 && l < g->nlevels, g->comm, PETSC_ERR_ARG_OUTOFRANGE,
               "refinement map asks for level %" PetscInt_FMT " at block %" PetscInt_FMT
               "; levels must be in [-1, -grid_levels - 1 = %" PetscInt_FMT "]",
               l, b, g->nlevels - 1);
    g->level[b] = l;
  }
  if (g->rcolumns) /* the quadtree image of the map: the finest active level of each block column */
    for (PetscInt k = 0; k < g->nb[2]; k++)
      for (PetscInt i = 0; i < g->nb[0]; i++) {
        PetscInt lmin = PETSC_MAX_INT;
        for (PetscInt j = 0; j < g->nb[1]; j++) {
          const PetscInt l = g->level[i + g->nb[0] * (j + g->nb[1] * k)];
          if (l >= 0) lmin = PetscMin(lmin, l);
        }
        for (PetscInt j = 0; j < g->nb[1]; j++)
          if (g->level[i + g->nb[0] * (j + g->nb[1] * k)] >= 0) g->level[i + g->nb[0] * (j + g->nb[1] * k)] = lmin;
      }
  PetscFunctionReturn(PETSC_SUCCESS);
}

static int PffCompareKeys(const void *a, const void *b, void *ctx)
{
  const uint64_t *key = (const uint64_t *)ctx;
  const uint64_t  ka = key[*(const PetscInt *)a], kb = key[*(const PetscInt *)b];
  return ka < kb ? -1 : (ka > kb ? 1 : 0);
}

PetscErrorCode PffGridBuildRaster_Private(PffGrid g)
{
  PetscFunctionBeginUser;
  PetscCall(PetscLogEventBegin(PFF_GridRefine, 0, 0, 0, 0));
  g->nblocks = 1;
  for (int d = 0; d < 3; d++) {
    g->nb[d] = g->cells[d] / g->n0;
    g->nblocks *= g->nb[d];
  }
  PetscCall(PetscMalloc1(g->nblocks, &g->level));
  PetscCall(PetscMalloc1(g->nblocks, &g->owner));
  PetscCall(PetscMalloc1(g->nblocks, &g->morton));
  PetscCall(PetscMalloc1(g->nblocks, &g->local));
  PetscCall(PetscMalloc1(g->nblocks, &g->offset));
  PetscCall(PffGridRequestedLevels(g));
  PetscCall(PffGradeLevels(g->nb, g->periodic, g->level));
  g->nactive = 0;
  for (PetscInt b = 0; b < g->nblocks; b++) {
    g->morton[b] = PffMortonEncode((uint32_t)(b % g->nb[0]), (uint32_t)((b / g->nb[0]) % g->nb[1]),
                                   (uint32_t)(b / (g->nb[0] * g->nb[1])));
    if (g->level[b] >= 0) g->nactive++;
  }
  PetscCheck(g->nactive > 0, g->comm, PETSC_ERR_ARG_WRONG, "the refinement map leaves no active block");
  PetscCall(PetscMalloc1(g->nactive, &g->order));
  for (PetscInt b = 0, a = 0; b < g->nblocks; b++)
    if (g->level[b] >= 0) g->order[a++] = b;
  PetscCall(PetscTimSort(g->nactive, g->order, sizeof(PetscInt), PffCompareKeys, g->morton));
  PetscCall(PetscLogEventEnd(PFF_GridRefine, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}
