/* Solid fractions of the variational pressure (tall cells Sec. 4.3.2, [A] of Eq. 1, after Ando & Batty 2020):
   the open area fraction of every face from a solid signed distance, and the distance at every cell centre.

   A cell inside the solids (all six faces closed) gets a centre distance of at most -1 cell, which PffTall reads
   as "no sample"; any other cell's centre lies less than about a cell deep. A face's fraction comes from the
   distance at its four corners: the square is cut into four triangles around its centre (the corners' mean
   there) and the distance is linear on each triangle, so a planar solid boundary gets its exact fraction and a
   curved one a second-order one. A face normal to y that a horizontal boundary crosses within half a cell takes
   the open part of its control volume instead (PffTallYFaceOpen_Private), so that a body's bottom between two
   cell centres shares its area between the two cells' J in proportion and the buoyancy follows the draft
   continuously, not in steps of a cell. The nodes of a block (and the heights half a cell between them) are
   evaluated once and shared by the faces that meet there. */
#include "tallimpl.h"
#include <pff/particles.h>

/* Area fraction of a triangle where the linear function through its vertex values a, b, c is positive. */
static PetscReal TriangleOpen(PetscReal a, PetscReal b, PetscReal c)
{
  const PetscInt np = (a > 0) + (b > 0) + (c > 0);

  if (np == 0) return 0;
  if (np == 3) return 1;
  /* rotate so that a is the vertex alone on its side */
  if (np == 1) {
    if (b > 0) return TriangleOpen(b, c, a);
    if (c > 0) return TriangleOpen(c, a, b);
    return (a / (a - b)) * (a / (a - c));
  }
  if (!(b > 0)) return TriangleOpen(b, c, a);
  if (!(c > 0)) return TriangleOpen(c, a, b);
  return 1 - (a / (a - b)) * (a / (a - c)); /* a <= 0 alone: its corner is the closed part */
}

PetscReal PffTallOpenFraction(const PetscReal phi[4])
{
  const PetscReal m   = 0.25 * (phi[0] + phi[1] + phi[2] + phi[3]);
  PetscReal       sum = 0;

  for (PetscInt q = 0; q < 4; q++) sum += TriangleOpen(phi[q], phi[(q + 1) % 4], m);
  return 0.25 * sum;
}

PetscReal PffTallCellFaceOpen(const PetscReal corner[8], PetscInt a, PetscInt side)
{
  const PetscInt e1 = (a + 1) % 3, e2 = (a + 2) % 3;
  PetscReal      phi[4];

  for (PetscInt v = 0; v < 4; v++) /* the face's corners in cyclic order */
    phi[v] = corner[(side << a) | ((PetscInt)(v == 1 || v == 2) << e1) | ((PetscInt)(v >= 2) << e2)];
  return PffTallOpenFraction(phi);
}

PetscReal PffTallYFaceOpen_Private(PffSolidFn fn, void *ctx, const PetscReal x0[3], PetscReal s,
                                   const PetscReal below[4], const PetscReal face[4], const PetscReal above[4])
{
  PetscReal sum = 0, g[3];
  PetscInt  n   = 0;

  for (PetscInt q = 0; q < 4; q++) {
    if ((below[q] > 0) == (above[q] > 0)) continue;
    const PetscBool lowOpen = (PetscBool)(below[q] > 0);
    PetscReal       a = x0[1] - 0.5 * s, b = x0[1] + 0.5 * s;
    PetscReal       x[3] = {x0[0] + (PetscReal)(q >= 2) * s, 0, x0[2] + (PetscReal)(q == 1 || q == 2) * s};
    for (PetscInt it = 0; it < 32; it++) { /* bisection: a box's distance is not linear along an edge near its sides */
      x[1] = 0.5 * (a + b);
      if ((fn(x, g, ctx) > 0) == lowOpen)
        a = x[1];
      else
        b = x[1];
    }
    sum += 0.5 * (a + b);
    n++;
  }
  if (!n) return PffTallOpenFraction(face);
  const PetscReal t = (sum / (PetscReal)n - (x0[1] - 0.5 * s)) / s;
  return t * PffTallOpenFraction(below) + (1 - t) * PffTallOpenFraction(above);
}

/* Open fraction of the lower y-face of cell (i, j, k) of a block (j = n: the face on top of the block) from the
   block's nodes and half-height nodes. */
static PetscReal YFace(PffSolidFn fn, void *ctx, const PffBlockInfo *info, const PetscReal node[],
                       const PetscReal half[], PetscInt i, PetscInt j, PetscInt k)
{
  const PetscInt m = info->n + 1;
  PetscReal      below[4], face[4], above[4], x0[3];

  for (PetscInt q = 0; q < 4; q++) {
    const PetscInt ii = i + (q >= 2), kk = k + (q == 1 || q == 2), h0 = ii + m * (j + (m + 1) * kk);
    below[q] = half[h0];
    above[q] = half[h0 + m];
    face[q]  = node[ii + m * (j + m * kk)];
  }
  x0[0] = info->lo[0] + (PetscReal)i * info->h;
  x0[1] = info->lo[1] + (PetscReal)j * info->h;
  x0[2] = info->lo[2] + (PetscReal)k * info->h;
  return PffTallYFaceOpen_Private(fn, ctx, x0, info->h, below, face, above);
}

PetscErrorCode PffTallFillSolid(PffGrid grid, PffSolidFn fn, void *ctx, PetscInt chA, PetscInt chSolid,
                                const PetscBool blocks[])
{
  PetscInt   nlocal, n0;
  PetscBool  periodic[3];
  PetscReal *node, *half;

  PetscFunctionBeginUser;
  PetscCheck(fn != NULL, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "tallcell: no solid distance function");
  PetscCall(PffGridGetSizes(grid, &n0, NULL, NULL, NULL, periodic));
  PetscCall(PetscMalloc2((n0 + 1) * (n0 + 1) * (n0 + 1), &node, (n0 + 1) * (n0 + 2) * (n0 + 1), &half));
  PetscCall(PffGridGetLocalBlocks(grid, &nlocal));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    float       *a[3], *sd;
    PetscReal    x[3], g[3];
    PetscCall(PffGridGetBlockInfo(grid, lb, &info));
    if (blocks && !blocks[info.gid]) continue;
    const PetscInt n = info.n, m = n + 1;
    for (PetscInt k = 0; k <= n; k++)
      for (PetscInt j = 0; j <= n + 1; j++)
        for (PetscInt i = 0; i <= n; i++) {
          const PetscInt ijk[3] = {i, j, k};
          for (PetscInt d = 0; d < 3; d++) x[d] = info.lo[d] + (PetscReal)ijk[d] * info.h;
          if (j <= n) node[i + m * (j + m * k)] = fn(x, g, ctx);
          x[1] -= 0.5 * info.h; /* the y-faces' control volumes reach half a cell below and above them */
          half[i + m * (j + (m + 1) * k)] = fn(x, g, ctx);
        }
    for (PetscInt d = 0; d < 3; d++) PetscCall(PffGridGetBlockData(grid, chA, lb, d, &a[d]));
    PetscCall(PffGridGetBlockData(grid, chSolid, lb, 0, &sd));
    for (PetscInt k = 0; k < n; k++)
      for (PetscInt j = 0; j < n; j++)
        for (PetscInt i = 0; i < n; i++) {
          const PetscInt c = i + n * (j + n * k), ijk[3] = {i, j, k};
          PetscReal      corner[8];
          PetscBool      inside = PETSC_TRUE; /* all eight corners: then all six faces are closed */
          for (PetscInt v = 0; v < 8; v++) {
            corner[v] = node[(i + (v & 1)) + m * ((j + ((v >> 1) & 1)) + m * (k + (v >> 2)))];
            inside    = (PetscBool)(inside && corner[v] <= 0);
          }
          for (PetscInt d = 0; d < 3; d++) {
            const PetscBool wall = (PetscBool)(!periodic[d] && info.ijk[d] == 0 && ijk[d] == 0);
            a[d][c] =
                wall ? 0.0f
                     : (float)(d == 1 ? YFace(fn, ctx, &info, node, half, i, j, k) : PffTallCellFaceOpen(corner, d, 0));
          }
          /* a cell with its corners inside may still open downwards or upwards over a y-face's control volume */
          if (inside) inside = (PetscBool)(a[1][c] == 0 && YFace(fn, ctx, &info, node, half, i, j + 1, k) == 0);
          for (PetscInt d = 0; d < 3; d++) x[d] = info.lo[d] + ((PetscReal)ijk[d] + 0.5) * info.h;
          sd[c] = (float)PetscMin(fn(x, g, ctx) / info.h, PFF_TALL_SOLID_DISTANCE_MAX);
          if (inside) sd[c] = PetscMin(sd[c], -1.0f);
        }
  }
  PetscCall(PetscFree2(node, half));
  PetscCall(PffGridHaloBegin(grid, chA));
  PetscCall(PffGridHaloEnd(grid, chA));
  PetscCall(PffGridHaloBegin(grid, chSolid));
  PetscCall(PffGridHaloEnd(grid, chSolid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffTallSetSolid(PffTall tc, PetscInt chA, PetscInt chSolid)
{
  PetscFunctionBeginUser;
  PetscCheck((chA < 0) == (chSolid < 0), tc->comm, PETSC_ERR_ARG_WRONG,
             "tallcell: give both the face fractions and the cell distances of the solids, or neither");
  tc->chA     = chA;
  tc->chSolid = chSolid;
  PetscFunctionReturn(PETSC_SUCCESS);
}
