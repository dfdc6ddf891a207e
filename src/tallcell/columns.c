/* Columns of the tall-cell grid: liquid runs, bands of cubic cells under free surfaces, tall cells, the
   pressure samples and the vertical gradient rows (tall cells Sec. 4.2), and the ghost records of the lower
   neighbour columns on other ranks (one PetscSF).

   A run is a maximal stretch of liquid cells (phi < 0) in a column. An end of a run next to an air cell is
   a free surface; an end at the floor or the ceiling is a wall. Under (and over) each free-surface end a
   band of max(layer_min, ceil(layer_fraction m)) cubic cells stays, m the run's cells; when what is left
   has at least 3 cells and merging is on, it becomes one tall cell with samples at the centres of its
   lowest and highest sub-cells. The points of a run, bottom to top, are the free surface below (p = 0 at
   y = y_c - theta s), the samples, and the free surface above; theta = phi_liquid / (phi_liquid - phi_air)
   is the liquid fraction between the two cell centres, at least theta_min. */
#include "tallimpl.h"
#include <petscsf.h>

typedef struct {
  PetscReal y;
  PetscInt  id; /* local sample number, or PFF_TALL_SURFACE */
} Point;

/* Local block of block (bi, bj, bk), which this rank owns. */
static PetscErrorCode LocalBlock(PffTall tc, PetscInt bi, PetscInt bj, PetscInt bk, PetscInt *lb)
{
  PetscFunctionBeginUser;
  PetscCall(PffGridGetLocalIndex(tc->grid, bi + tc->nb[0] * (bj + tc->nb[1] * bk), lb));
  PetscCheck(*lb >= 0, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "tallcell: block (%" PetscInt_FMT ",%" PetscInt_FMT ",%" PetscInt_FMT ") of an owned column is not local",
             bi, bj, bk);
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscReal Theta(PffTall tc, PetscReal phiLiquid, PetscReal phiAir)
{
  const PetscReal den = phiLiquid - phiAir;
  const PetscReal th  = den < 0 ? phiLiquid / den : 1;
  return PetscMin(1.0, PetscMax(tc->thetaMin, th));
}

/* The runs of one column: records (with local sample ids) and, when rows is true, its vertical rows.
   phi[ny] at the cell centres; face location of the lower y-face of cell j: lbOf[j / n], cell index
   cellOf(j). Returns the samples made. */
typedef struct {
  PetscInt        ny, n, ci, ck; /* cells in the column, per block axis, and the column in its block */
  PetscReal       s, y0;         /* cell size, domain bottom */
  const PetscInt *lbOf;          /* [nb[1]] local block of each block of the column */
} ColumnGeom;

static PetscInt FaceCell(const ColumnGeom *cg, PetscInt j)
{
  return cg->ci + cg->n * ((j % cg->n) + cg->n * cg->ck);
}

static PetscErrorCode BuildColumn(PffTall tc, const ColumnGeom *cg, const PetscReal phi[], const PetscBool solid[],
                                  Point pts[], PetscInt *ri, PetscReal *rr, float *height, PetscInt idBase,
                                  PetscBool rows, PetscInt *nsamp, PetscInt64 *ncells, PetscInt64 *ntall)
{
  const PetscReal s  = cg->s;
  PetscInt        id = 0, j = 0;

  PetscFunctionBeginUser;
  while (j < cg->ny) {
    if (!(phi[j] < 0) || solid[j]) {
      if (ri) {
        for (PetscInt q = 0; q < 4; q++) ri[PFF_TALL_RI * j + q] = PFF_TALL_SURFACE;
        ri[PFF_TALL_RI * j + 4] = solid[j] ? PFF_TALL_SOLID : PFF_TALL_AIR;
        for (PetscInt q = 0; q < 4; q++) rr[PFF_TALL_RR * j + q] = 0;
        rr[PFF_TALL_RR * j + 4] = phi[j];
        height[j]               = 0;
      }
      j++;
      continue;
    }
    const PetscInt j0 = j;
    while (j < cg->ny && phi[j] < 0 && !solid[j]) j++;
    const PetscInt j1 = j - 1, m = j1 - j0 + 1;
    /* an end at a solid cell is a wall, like the floor */
    const PetscBool lowSurf = (PetscBool)(j0 > 0 && !solid[j0 - 1]),
                    upSurf  = (PetscBool)(j1 < cg->ny - 1 && !solid[j1 + 1]);
    const PetscInt  L       = PetscMax(tc->layerMin, (PetscInt)PetscCeilReal(tc->layerFraction * (PetscReal)m - 1e-9));
    const PetscInt  lo = lowSurf ? PetscMin(L, m) : 0, up = upSurf ? PetscMin(L, m - lo) : 0, mid = m - lo - up;
    const PetscBool tall = (PetscBool)(tc->merge && mid >= 3);
    const PetscInt  t0 = j0 + lo, t1 = j0 + lo + mid - 1; /* the tall cell's sub-cells when tall */
    PetscReal       thLow = 1, thUp = 1;
    PetscInt        np = 0, tallId = -1;

#define YC(k) (cg->y0 + ((PetscReal)(k) + 0.5) * s)
    if (lowSurf) {
      thLow        = Theta(tc, phi[j0], phi[j0 - 1]);
      pts[np].y    = YC(j0) - thLow * s;
      pts[np++].id = PFF_TALL_SURFACE;
    }
    for (PetscInt k = j0; k <= j1; k++) {
      if (tall && k == t0) {
        tallId       = idBase + id;
        pts[np].y    = YC(t0);
        pts[np++].id = idBase + id++;
        pts[np].y    = YC(t1);
        pts[np++].id = idBase + id++;
        k            = t1;
        (*ncells)++;
        (*ntall)++;
      } else {
        pts[np].y    = YC(k);
        pts[np++].id = idBase + id++;
        (*ncells)++;
      }
    }
    if (upSurf) {
      thUp         = Theta(tc, phi[j1], phi[j1 + 1]);
      pts[np].y    = YC(j1) + thUp * s;
      pts[np++].id = PFF_TALL_SURFACE;
    }
    if (ri) {
      for (PetscInt k = j0; k <= j1; k++) {
        for (PetscInt h = 0; h < 2; h++) {
          const PetscReal yq = YC(k) + (h ? 0.25 : -0.25) * s;
          PetscInt        a  = 0;
          while (a + 1 < np && pts[a + 1].y <= yq) a++;
          if (a + 1 >= np) a = PetscMax(0, np - 2); /* above the last point: extrapolate the last segment */
          const PetscInt b                = PetscMin(a + 1, np - 1);
          ri[PFF_TALL_RI * k + 2 * h]     = pts[a].id;
          ri[PFF_TALL_RI * k + 2 * h + 1] = pts[b].id;
          rr[PFF_TALL_RR * k + 2 * h]     = pts[a].y;
          rr[PFF_TALL_RR * k + 2 * h + 1] = pts[b].y;
        }
        const PetscBool member  = (PetscBool)(tall && k >= t0 && k <= t1);
        ri[PFF_TALL_RI * k + 4] = member ? tallId : PFF_TALL_CUBIC;
        rr[PFF_TALL_RR * k + 4] = phi[k];
        height[k]               = member ? (float)mid : 1.0f;
      }
    }
    if (rows) {
      /* one row per pair of consecutive points; a free-surface row spans the cell centre to the air cell's */
      for (PetscInt a = 0; a + 1 < np; a++) {
        PffTallRow row = {0};
        PetscInt   lbs[1], comps[1], cells[1];
        if (pts[a].id == PFF_TALL_SURFACE) {
          row.n      = 1;
          row.col[0] = pts[a + 1].id;
          row.val[0] = 1 / s;
          lbs[0]     = cg->lbOf[j0 / cg->n];
          comps[0]   = 1;
          cells[0]   = FaceCell(cg, j0);
          PetscCall(PffTallAddRow_Private(tc, &row, 1 / thLow, s * s * s, PETSC_TRUE, 1, lbs, comps, cells));
        } else if (pts[a + 1].id == PFF_TALL_SURFACE) {
          row.n      = 1;
          row.col[0] = pts[a].id;
          row.val[0] = -1 / s;
          lbs[0]     = cg->lbOf[(j1 + 1) / cg->n];
          comps[0]   = 1;
          cells[0]   = FaceCell(cg, j1 + 1);
          PetscCall(PffTallAddRow_Private(tc, &row, 1 / thUp, s * s * s, PETSC_TRUE, 1, lbs, comps, cells));
        } else {
          const PetscReal d  = pts[a + 1].y - pts[a].y;
          const PetscInt  ka = (PetscInt)PetscFloorReal((pts[a].y - cg->y0) / s);
          const PetscInt  kb = (PetscInt)PetscFloorReal((pts[a + 1].y - cg->y0) / s);
          PetscInt        nf = kb - ka, *fl, *fc, *fcell;
          row.n              = 2;
          row.col[0]         = pts[a + 1].id;
          row.val[0]         = 1 / d;
          row.col[1]         = pts[a].id;
          row.val[1]         = -1 / d;
          PetscCall(PetscMalloc3(nf, &fl, nf, &fc, nf, &fcell));
          for (PetscInt q = 0; q < nf; q++) { /* the lower y-faces of cells ka + 1 .. kb */
            fl[q]    = cg->lbOf[(ka + 1 + q) / cg->n];
            fc[q]    = 1;
            fcell[q] = FaceCell(cg, ka + 1 + q);
          }
          PetscCall(PffTallAddRow_Private(tc, &row, 1, s * s * d, PETSC_FALSE, nf, fl, fc, fcell));
          PetscCall(PetscFree3(fl, fc, fcell));
        }
      }
    }
#undef YC
  }
  *nsamp = id;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Reads phi of column (ci, ck) of owned block column (bi, bk) into phi[ny], and into solid[ny] whether each
   cell lies inside the solids (no flux can enter it: it gets no sample). */
static PetscErrorCode ReadColumn(PffTall tc, PetscInt chPhi, const ColumnGeom *cg, PetscReal phi[], PetscBool solid[])
{
  PetscFunctionBeginUser;
  for (PetscInt bj = 0; bj < tc->nb[1]; bj++) {
    float         *data, *sd = NULL;
    const PetscInt base = cg->ci + cg->n * cg->n * cg->ck;
    PetscCall(PffGridGetBlockData(tc->grid, chPhi, cg->lbOf[bj], 0, &data));
    if (tc->chSolid >= 0) PetscCall(PffGridGetBlockData(tc->grid, tc->chSolid, cg->lbOf[bj], 0, &sd));
    for (PetscInt cj = 0; cj < cg->n; cj++) {
      phi[bj * cg->n + cj]   = data[base + cg->n * cj];
      solid[bj * cg->n + cj] = (PetscBool)(sd && sd[base + cg->n * cj] <= -1);
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Ghost columns: the outermost layer of every lower x and z neighbour block column on another rank. */
static PetscErrorCode BuildGhosts(PffTall tc)
{
  PetscInt     cap = 64, ng = 0, nleaves = 0;
  PetscInt64  *keys;
  PetscSF      sf;
  PetscSFNode *remote;
  MPI_Datatype ti, tr;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(cap, &keys));
  for (PetscInt bc = 0; bc < tc->nbc; bc++) {
    if (tc->bcOwner[bc] != tc->rank) continue;
    const PetscInt bi = bc % tc->nb[0], bk = bc / tc->nb[0];
    for (PetscInt a = 0; a < 3; a += 2) {
      PetscInt dir[3] = {0, 0, 0}, ijk[3] = {bi, 0, bk};
      dir[a]             = -1;
      const PetscInt nbr = PffRasterNeighbour(tc->nb, tc->periodic, ijk, dir);
      if (nbr < 0) continue;
      const PetscInt nbc = nbr % tc->nb[0] + tc->nb[0] * (nbr / (tc->nb[0] * tc->nb[1]));
      if (tc->bcOwner[nbc] == tc->rank) continue;
      const PetscInt l = tc->bcLevel[nbc], n = tc->n0 >> l, nx = nbc % tc->nb[0], nz = nbc / tc->nb[0];
      for (PetscInt t = 0; t < n; t++) {
        const PetscInt gx = a == 0 ? nx * n + n - 1 : nx * n + t, gz = a == 0 ? nz * n + t : nz * n + n - 1;
        if (ng == cap) {
          PetscInt64 *more;
          PetscCall(PetscMalloc1(2 * cap, &more));
          PetscCall(PetscArraycpy(more, keys, ng));
          PetscCall(PetscFree(keys));
          keys = more;
          cap *= 2;
        }
        keys[ng++] = PffTallColumnKey(tc, l, gx, gz);
      }
    }
  }
  PetscCall(PetscSortInt64(ng, keys));
  {
    PetscInt u = 0;
    for (PetscInt q = 0; q < ng; q++)
      if (!u || keys[q] != keys[u - 1]) keys[u++] = keys[q];
    ng = u;
  }
  tc->nghost = ng;
  tc->gkey   = keys;
  PetscCall(PetscMalloc1(ng + 1, &tc->gstart));
  tc->gstart[0] = 0;
  for (PetscInt g = 0; g < ng; g++) {
    const PetscInt64 nx = (PetscInt64)tc->nb[0] * tc->n0, nz = (PetscInt64)tc->nb[2] * tc->n0;
    const PetscInt   l = (PetscInt)(keys[g] / (nx * nz));
    tc->gstart[g + 1]  = tc->gstart[g] + tc->nb[1] * (tc->n0 >> l);
  }
  nleaves = tc->gstart[ng];
  PetscCall(PetscMalloc1(nleaves, &remote));
  for (PetscInt g = 0; g < ng; g++) {
    const PetscInt64 nx = (PetscInt64)tc->nb[0] * tc->n0, nz = (PetscInt64)tc->nb[2] * tc->n0;
    const PetscInt   l = (PetscInt)(keys[g] / (nx * nz)), gx = (PetscInt)((keys[g] / nz) % nx),
                   gz = (PetscInt)(keys[g] % nz), n = tc->n0 >> l, ny = tc->nb[1] * n;
    const PetscInt bc = gx / n + tc->nb[0] * (gz / n);
    for (PetscInt j = 0; j < ny; j++) {
      remote[tc->gstart[g] + j].rank  = tc->bcOwner[bc];
      remote[tc->gstart[g] + j].index = tc->bcOffset[bc] + ((gz % n) * n + gx % n) * ny + j;
    }
  }
  PetscCall(PetscSFCreate(tc->comm, &sf));
  PetscCall(PetscSFSetGraph(sf, tc->nrec, nleaves, NULL, PETSC_OWN_POINTER, remote, PETSC_OWN_POINTER));
  PetscCall(PetscSFSetUp(sf));
  PetscCall(PetscMalloc2(PFF_TALL_RI * nleaves, &tc->gi, PFF_TALL_RR * nleaves, &tc->gr));
  PetscCallMPI(MPI_Type_contiguous(PFF_TALL_RI, MPIU_INT, &ti));
  PetscCallMPI(MPI_Type_commit(&ti));
  PetscCallMPI(MPI_Type_contiguous(PFF_TALL_RR, MPIU_REAL, &tr));
  PetscCallMPI(MPI_Type_commit(&tr));
  PetscCall(PetscSFBcastBegin(sf, ti, tc->ri, tc->gi, MPI_REPLACE));
  PetscCall(PetscSFBcastBegin(sf, tr, tc->rr, tc->gr, MPI_REPLACE));
  PetscCall(PetscSFBcastEnd(sf, ti, tc->ri, tc->gi, MPI_REPLACE));
  PetscCall(PetscSFBcastEnd(sf, tr, tc->rr, tc->gr, MPI_REPLACE));
  PetscCallMPI(MPI_Type_free(&ti));
  PetscCallMPI(MPI_Type_free(&tr));
  PetscCall(PetscSFDestroy(&sf));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffTallCheckGrid_Private(PffTall tc)
{
  const PetscInt    *level;
  const PetscMPIInt *owner;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetRaster(tc->grid, NULL, &level, &owner));
  for (PetscInt bc = 0; bc < tc->nbc; bc++) {
    const PetscInt bi = bc % tc->nb[0], bk = bc / tc->nb[0], g0 = bi + tc->nb[0] * tc->nb[1] * bk;
    PetscCheck(level[g0] >= 0, tc->comm, PETSC_ERR_ARG_WRONG,
               "tallcell: inactive blocks are not supported (block column %" PetscInt_FMT ", %" PetscInt_FMT ")", bi,
               bk);
    for (PetscInt bj = 1; bj < tc->nb[1]; bj++) {
      const PetscInt g = g0 + tc->nb[0] * bj;
      PetscCheck(level[g] == level[g0], tc->comm, PETSC_ERR_ARG_WRONG,
                 "tallcell: block column (%" PetscInt_FMT ", %" PetscInt_FMT ") changes level along y; the tall-cell "
                 "grid needs levels constant along y (a column refinement map, not -grid_refine plane or sphere)",
                 bi, bk);
      PetscCheck(owner[g] == owner[g0], tc->comm, PETSC_ERR_ARG_WRONG,
                 "tallcell: block column (%" PetscInt_FMT ", %" PetscInt_FMT ") lies on several ranks; the tall-cell "
                 "grid needs -partition_type columns",
                 bi, bk);
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffTallBuildColumns_Private(PffTall tc, PetscInt chPhi)
{
  const PetscInt *level;
  PetscInt       *next, *lbOf, nyMax = tc->nb[1] * tc->n0;
  PetscReal      *phi;
  PetscBool      *solid;
  Point          *pts;
  PetscInt64      cnt[3] = {0, 0, 0}, sum[3]; /* cells, tall cells, liquid cells */

  PetscFunctionBeginUser;
  PetscCall(PffTallCheckGrid_Private(tc));
  PetscCall(PffGridGetRaster(tc->grid, NULL, &level, NULL));
  /* block columns: level, owner, record offsets on the owner */
  PetscCall(PetscMalloc3(tc->nbc, &tc->bcLevel, tc->nbc, &tc->bcOwner, tc->nbc, &tc->bcOffset));
  PetscCall(PetscCalloc1(tc->size, &next));
  {
    const PetscMPIInt *owner;
    PetscCall(PffGridGetRaster(tc->grid, NULL, NULL, &owner));
    for (PetscInt bc = 0; bc < tc->nbc; bc++) {
      const PetscInt bi = bc % tc->nb[0], bk = bc / tc->nb[0], g0 = bi + tc->nb[0] * tc->nb[1] * bk;
      tc->bcLevel[bc]  = level[g0];
      tc->bcOwner[bc]  = owner[g0];
      const PetscInt n = tc->n0 >> level[g0];
      tc->bcOffset[bc] = next[owner[g0]];
      next[owner[g0]] += n * n * tc->nb[1] * n;
    }
  }
  tc->nrec = next[tc->rank];
  PetscCall(PetscFree(next));
  PetscCall(PetscMalloc3(PFF_TALL_RI * tc->nrec, &tc->ri, PFF_TALL_RR * tc->nrec, &tc->rr, tc->nrec, &tc->height));
  PetscCall(PetscMalloc4(nyMax, &phi, nyMax, &solid, nyMax + 2, &pts, tc->nb[1], &lbOf));

  /* pass 1: samples per rank, for the global numbering; pass 2: records and vertical rows */
  for (PetscInt pass = 0; pass < 2; pass++) {
    PetscInt total = 0;
    for (PetscInt bc = 0; bc < tc->nbc; bc++) {
      if (tc->bcOwner[bc] != tc->rank) continue;
      const PetscInt bi = bc % tc->nb[0], bk = bc / tc->nb[0], l = tc->bcLevel[bc], n = tc->n0 >> l;
      ColumnGeom     cg = {tc->nb[1] * n, n, 0, 0, tc->h0 * (PetscReal)(1 << l), tc->origin[1], lbOf};
      for (PetscInt bj = 0; bj < tc->nb[1]; bj++) PetscCall(LocalBlock(tc, bi, bj, bk, &lbOf[bj]));
      for (cg.ck = 0; cg.ck < n; cg.ck++)
        for (cg.ci = 0; cg.ci < n; cg.ci++) {
          const PetscInt off = tc->bcOffset[bc] + (cg.ck * n + cg.ci) * cg.ny;
          PetscInt       ns  = 0;
          PetscCall(ReadColumn(tc, chPhi, &cg, phi, solid));
          if (pass == 0) {
            PetscInt64 c = 0, t = 0;
            PetscCall(BuildColumn(tc, &cg, phi, solid, pts, NULL, NULL, NULL, 0, PETSC_FALSE, &ns, &c, &t));
          } else {
            PetscCall(BuildColumn(tc, &cg, phi, solid, pts, tc->ri + PFF_TALL_RI * off, tc->rr + PFF_TALL_RR * off,
                                  tc->height + off, tc->sstart + total, PETSC_TRUE, &ns, &cnt[0], &cnt[1]));
            for (PetscInt j = 0; j < cg.ny; j++)
              if (phi[j] < 0 && !solid[j]) cnt[2] += (PetscInt64)1 << (3 * l);
          }
          if (pass == 1)
            for (PetscInt q = 0; q < ns; q++) tc->sampleS[total + q] = cg.s;
          total += ns;
        }
    }
    if (pass == 0) {
      tc->nsamp = total;
      PetscCallMPI(MPI_Exscan(&total, &tc->sstart, 1, MPIU_INT, MPI_SUM, tc->comm));
      if (tc->rank == 0) tc->sstart = 0;
      PetscCall(PetscMalloc1(tc->nsamp, &tc->sampleS));
    }
  }
  PetscCall(PetscFree4(phi, solid, pts, lbOf));
  PetscCallMPI(MPIU_Allreduce(cnt, sum, 3, MPIU_INT64, MPI_SUM, tc->comm));
  tc->cells       = sum[0];
  tc->tallCells   = sum[1];
  tc->liquidCells = sum[2];
  PetscCall(BuildGhosts(tc));
  PetscFunctionReturn(PETSC_SUCCESS);
}
