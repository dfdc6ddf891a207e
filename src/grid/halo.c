/* Halo exchange across ranks and levels (DESIGN.md Sec. 5), one PetscSF per channel kind and width.

   Every owned block has 26 neighbour regions of width w at its own level. A region whose neighbour
   is on this rank at the same level is read in place (no copy, see storage.c). Every other region
   gets a ghost box in the channel's halo buffer:
     same level, other rank:  the ghost cells are SF leaves of the neighbour's cells;
     coarser neighbour:       SF brings the neighbour's cells under the region (source box), and
                              the ghosts are their trilinear interpolation at the ghost positions,
                              extrapolated linearly inside the neighbour, so linear fields are exact;
     finer neighbour:         SF brings the 2w fine layers, and each ghost is the mean of the fine
                              cells (or coplanar fine faces) it covers;
     wall or inactive:        a zero box that no exchange touches (boundary conditions own it).
   The reverse exchange is the conservative counterpart: ghost contributions are spread onto the
   source cells with non-negative weights summing to one, and PetscSFReduce adds them into the
   owners, so the global sum is unchanged. Plans are built once per raster and shared by channels. */
#include "gridimpl.h"

/* A ghost box spans at most a block (64 cells) along an axis, or the halo width across it. */
#define PFF_HALO_MAX_EXTENT 64

/* Per-axis interpolation stencil in the coarser neighbour: first index and weight of the second. */
static inline void PffCoarseStencil(PetscInt i, PetscReal o, PetscInt shift, PetscInt nn, PetscInt *i0, PetscReal *t)
{
  const PetscReal c = ((PetscReal)(i - shift) + o) * 0.5 - o;
  if (nn == 1) {
    *i0 = 0;
    *t  = 0.0;
    return;
  }
  PetscInt f = (PetscInt)PetscFloorReal(c);
  f          = PetscMax(0, PetscMin(nn - 2, f));
  *i0        = f;
  *t         = c - (PetscReal)f;
}

/* Conservative spreading weights of a fine ghost cell onto the coarse lattice along one axis:
   the whole value goes to the coarse cell containing the fine cell, or half to each neighbour when
   the fine face lies mid-way between two coarse faces (staggered axis, odd index). */
static inline PetscInt PffCoarseSpread(PetscInt i, PetscReal o, PetscInt shift, PetscInt nn, PetscInt idx[2],
                                       PetscReal w[2])
{
  const PetscReal c = ((PetscReal)(i - shift) + o) * 0.5 - o;
  const PetscReal r = PetscFloorReal(c + 0.5);
  if (PetscAbsReal(c - r) <= 0.25 + 1e-12) {
    idx[0] = PetscMax(0, PetscMin(nn - 1, (PetscInt)r));
    w[0]   = 1.0;
    return 1;
  }
  const PetscInt f = (PetscInt)PetscFloorReal(c);
  idx[0]           = PetscMax(0, PetscMin(nn - 1, f));
  idx[1]           = PetscMax(0, PetscMin(nn - 1, f + 1));
  w[0] = w[1] = 0.5;
  return 2;
}

/* Fine cells under coarse ghost i along one axis: 2 for a cell lattice, 1 (coplanar) for a face lattice. */
static inline PetscInt PffFineCover(PetscInt i, PetscReal o, PetscInt shift, PetscInt *f0)
{
  *f0 = 2 * (i - shift);
  return o > 0.25 ? 2 : 1;
}

/* The halo buffer holds the SF's leaves first, in the order of the transfers (a same-level ghost box from another
   rank, or a cross-level source box), so that they are contiguous and the SF needs no leaf indices (PETSc then packs
   and unpacks them as one block); then the ghost boxes that no exchange writes: the cross-level ones (filled from
   their sources) and those across walls or towards inactive blocks. */
static PetscErrorCode PffHaloPlanBuild(PffGrid g, PffHaloPlan *p)
{
  const PetscInt w = p->width, nc = p->ncomp;
  PetscInt64     nfloat = 0;
  PetscInt       nxfer = 0, cap = 64, nwall = 0, wcap = 64, *wall;
  PetscSFNode   *iremote;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(g->nlocal * nc * 27, &p->goff));
  PetscCall(PetscMalloc1(cap, &p->xfer));
  PetscCall(PetscMalloc1(wcap, &wall)); /* goff entries of the ghost boxes across walls, and their sizes */
  for (PetscInt lb = 0; lb < g->nlocal; lb++) {
    const PetscInt gid = g->lgid[lb], n = PffGridBlockN_Private(g, gid);
    for (PetscInt comp = 0; comp < nc; comp++) {
      for (PetscInt r = 0; r < 27; r++) {
        PetscInt       d[3];
        const PetscInt e = (lb * nc + comp) * 27 + r;
        p->goff[e]       = -1;
        if (r == 13) continue;
        PffRegionDirection(r, d);
        const PetscInt  nbr    = PffGridActiveNeighbour_Private(g, gid, r);
        const PetscBool active = (PetscBool)(nbr >= 0);
        if (active && g->level[nbr] == g->level[gid] && g->owner[nbr] == g->rank) continue;
        PffHaloXfer x = {0};
        x.lb          = lb;
        x.comp        = comp;
        x.region      = r;
        x.nbgid       = active ? nbr : -1;
        x.rel         = active ? g->level[nbr] - g->level[gid] : 0;
        for (int a = 0; a < 3; a++) {
          x.glo[a] = d[a] < 0 ? -w : (d[a] > 0 ? n : 0);
          x.gn[a]  = d[a] ? w : n;
          PetscAssert(x.gn[a] <= PFF_HALO_MAX_EXTENT, PETSC_COMM_SELF, PETSC_ERR_PLIB, "ghost box wider than a block");
        }
        if (!active) {
          if (nwall + 2 > wcap) {
            PetscCall(PetscRealloc(sizeof(PetscInt) * 2 * wcap, &wall));
            wcap *= 2;
          }
          wall[nwall++] = e;
          wall[nwall++] = x.gn[0] * x.gn[1] * x.gn[2];
          continue;
        }
        PetscAssert(PetscAbsInt(x.rel) <= 1, PETSC_COMM_SELF, PETSC_ERR_PLIB, "grading violated");
        if (x.rel != 0) {
          for (int a = 0; a < 3; a++) {
            const PetscReal o     = PffChannelOffset_Private(p->kind, comp, a);
            const PetscInt  shift = d[a] * n;
            PetscInt        lo = PETSC_MAX_INT, hi = -1;
            if (x.rel > 0) {
              const PetscInt nn = n / 2;
              for (PetscInt i = x.glo[a]; i < x.glo[a] + x.gn[a]; i++) {
                PetscInt  i0;
                PetscReal t;
                PffCoarseStencil(i, o, shift, nn, &i0, &t);
                lo = PetscMin(lo, i0);
                hi = PetscMax(hi, nn == 1 ? i0 : i0 + 1);
              }
            } else {
              for (PetscInt i = x.glo[a]; i < x.glo[a] + x.gn[a]; i++) {
                PetscInt f0, cnt = PffFineCover(i, o, shift, &f0);
                lo = PetscMin(lo, f0);
                hi = PetscMax(hi, f0 + cnt - 1);
              }
            }
            x.slo[a] = lo;
            x.sn[a]  = hi - lo + 1;
          }
        }
        if (nxfer == cap) {
          PffHaloXfer *nx;
          PetscCall(PetscMalloc1(2 * cap, &nx));
          PetscCall(PetscArraycpy(nx, p->xfer, nxfer));
          PetscCall(PetscFree(p->xfer));
          p->xfer = nx;
          cap *= 2;
        }
        p->xfer[nxfer++] = x;
      }
    }
  }
  /* the leaves, then the boxes that no exchange writes */
  for (PetscInt e = 0; e < nxfer; e++) {
    PffHaloXfer *x = &p->xfer[e];
    if (x->rel == 0) {
      x->goff = nfloat;
      nfloat += x->gn[0] * x->gn[1] * x->gn[2];
    } else {
      x->soff = nfloat;
      nfloat += x->sn[0] * x->sn[1] * x->sn[2];
    }
  }
  const PetscInt64 nleaves = nfloat;
  for (PetscInt e = 0; e < nxfer; e++) {
    PffHaloXfer *x = &p->xfer[e];
    if (x->rel != 0) {
      x->goff = nfloat;
      nfloat += x->gn[0] * x->gn[1] * x->gn[2];
    }
    p->goff[(x->lb * nc + x->comp) * 27 + x->region] = x->goff;
  }
  for (PetscInt q = 0; q < nwall; q += 2) {
    p->goff[wall[q]] = nfloat;
    nfloat += wall[q + 1];
  }
  PetscCall(PetscFree(wall));
  p->nxfer = nxfer;
  p->nhalo = nfloat;
  PetscCheck(p->nhalo < PETSC_MAX_INT && nc * g->ncells < PETSC_MAX_INT, PETSC_COMM_SELF, PETSC_ERR_SUP,
             "more halo or owned values on one rank than PetscInt holds: use more ranks");

  /* each leaf names its owner's cell */
  PetscCall(PetscMalloc1(nleaves, &iremote));
  p->recvRemote = 0;
  for (PetscInt e = 0, l = 0; e < nxfer; e++) {
    const PffHaloXfer *x = &p->xfer[e];
    const PetscInt     n = PffGridBlockN_Private(g, g->lgid[x->lb]), nn = PffGridBlockN_Private(g, x->nbgid);
    PetscInt           d[3];
    PffRegionDirection(x->region, d);
    const PetscInt64 base = nc * g->offset[x->nbgid] + (PetscInt64)x->comp * nn * nn * nn;
    const PetscInt  *lo = x->rel == 0 ? x->glo : x->slo, *ext = x->rel == 0 ? x->gn : x->sn;
    if (g->owner[x->nbgid] != g->rank) p->recvRemote += ext[0] * ext[1] * ext[2];
    for (PetscInt k = 0; k < ext[2]; k++)
      for (PetscInt j = 0; j < ext[1]; j++)
        for (PetscInt i = 0; i < ext[0]; i++, l++) {
          /* same level: ghost coordinates shift by one block into the neighbour */
          const PetscInt ii = lo[0] + i - (x->rel == 0 ? d[0] * n : 0);
          const PetscInt jj = lo[1] + j - (x->rel == 0 ? d[1] * n : 0);
          const PetscInt kk = lo[2] + k - (x->rel == 0 ? d[2] * n : 0);
          PetscAssert(ii >= 0 && ii < nn && jj >= 0 && jj < nn && kk >= 0 && kk < nn, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                      "halo source outside the neighbour block");
          iremote[l].rank  = g->owner[x->nbgid];
          iremote[l].index = (PetscInt)(base + ii + nn * (jj + nn * (PetscInt64)kk));
        }
  }
  PetscCall(PetscSFCreate(g->comm, &p->sf));
  PetscCall(PetscSFSetGraph(p->sf, (PetscInt)(nc * g->ncells), (PetscInt)nleaves, NULL, PETSC_OWN_POINTER, iremote,
                            PETSC_OWN_POINTER));
  PetscCall(PetscSFSetUp(p->sf));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffHaloPlanGet_Private(PffGrid g, PffChannelKind kind, PetscInt width, PffHaloPlan **plan)
{
  PffHaloPlan *p;

  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < g->nplans; i++) {
    if (g->plans[i]->kind == kind && g->plans[i]->width == width) {
      *plan = g->plans[i];
      PetscFunctionReturn(PETSC_SUCCESS);
    }
  }
  PetscCheck(g->nplans < (PetscInt)PETSC_STATIC_ARRAY_LENGTH(g->plans), PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "too many plans");
  PetscCall(PetscLogEventBegin(PFF_HaloSetUp, 0, 0, 0, 0));
  PetscCall(PetscNew(&p));
  p->kind  = kind;
  p->width = width;
  p->ncomp = kind == PFF_CHANNEL_FACE ? 3 : 1;
  PetscCall(PffHaloPlanBuild(g, p));
  g->plans[g->nplans++] = p;
  *plan                 = p;
  PetscCall(PetscLogEventEnd(PFF_HaloSetUp, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffHaloPlanDestroy_Private(PffHaloPlan **p)
{
  PetscFunctionBeginUser;
  if (!*p) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscSFDestroy(&(*p)->sf));
  PetscCall(PetscFree((*p)->goff));
  PetscCall(PetscFree((*p)->xfer));
  PetscCall(PetscFree(*p));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridHaloBegin(PffGrid g, PetscInt ch)
{
  PffChannel *c = NULL;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetChannel_Private(g, ch, &c));
  PetscCall(PetscLogEventBegin(PFF_HaloBegin, 0, 0, 0, 0));
  PetscCall(PetscSFBcastBegin(c->plan->sf, MPI_FLOAT, c->data, c->halo, MPI_REPLACE));
  PetscCall(PetscLogEventEnd(PFF_HaloBegin, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Ghost values from the neighbour's source box: interpolation from a coarser, averaging of a finer one. */
static void PffHaloFillCrossLevel(PffGrid g, const PffHaloPlan *p, const PffHaloXfer *x, float *halo)
{
  const PetscInt n = PffGridBlockN_Private(g, g->lgid[x->lb]), nn = PffGridBlockN_Private(g, x->nbgid);
  PetscInt       d[3];
  PffRegionDirection(x->region, d);
  const float   *src = halo + x->soff;
  float         *gh  = halo + x->goff;
  const PetscInt sy = x->sn[0], sz = x->sn[0] * x->sn[1], step[3] = {1, sy, sz};
  /* the stencils are separable: one per ghost row of each axis (a ghost box is at most a block wide), not one per
     ghost cell and axis; off[a][i] is the source offset of the row's first cell along axis a */
  PetscInt  off[3][PFF_HALO_MAX_EXTENT], cnt[3][PFF_HALO_MAX_EXTENT];
  PetscReal w0[3][PFF_HALO_MAX_EXTENT], w1[3][PFF_HALO_MAX_EXTENT];
  for (int a = 0; a < 3; a++) {
    const PetscReal o = PffChannelOffset_Private(p->kind, x->comp, a);
    for (PetscInt i = 0; i < x->gn[a]; i++) {
      PetscInt i0;
      if (x->rel > 0) {
        PffCoarseStencil(x->glo[a] + i, o, d[a] * n, nn, &i0, &w1[a][i]);
        w0[a][i] = 1 - w1[a][i];
      } else
        cnt[a][i] = PffFineCover(x->glo[a] + i, o, d[a] * n, &i0);
      off[a][i] = (i0 - x->slo[a]) * step[a];
    }
  }
  if (x->rel > 0) {
    /* trilinear in the coarser neighbour, the corners summed in the order x, y, z fastest first */
    const PetscInt dx = nn > 1, dy = nn > 1 ? sy : 0, dz = nn > 1 ? sz : 0;
    for (PetscInt k = 0; k < x->gn[2]; k++)
      for (PetscInt j = 0; j < x->gn[1]; j++) {
        float *row = gh + x->gn[0] * (j + x->gn[1] * k);
        for (PetscInt i = 0; i < x->gn[0]; i++) {
          const float    *c  = src + off[0][i] + off[1][j] + off[2][k];
          const PetscReal x0 = w0[0][i], x1 = w1[0][i], y0 = w0[1][j], y1 = w1[1][j], z0 = w0[2][k], z1 = w1[2][k];
          PetscReal       v = 0.0; /* not the first term: a zero sum stays +0, as before */
          v += x0 * y0 * z0 * (PetscReal)c[0];
          v += x1 * y0 * z0 * (PetscReal)c[dx];
          v += x0 * y1 * z0 * (PetscReal)c[dy];
          v += x1 * y1 * z0 * (PetscReal)c[dx + dy];
          v += x0 * y0 * z1 * (PetscReal)c[dz];
          v += x1 * y0 * z1 * (PetscReal)c[dx + dz];
          v += x0 * y1 * z1 * (PetscReal)c[dy + dz];
          v += x1 * y1 * z1 * (PetscReal)c[dx + dy + dz];
          row[i] = (float)v;
        }
      }
    return;
  }
  /* the mean of the finer neighbour's cells (or coplanar faces) under the ghost */
  for (PetscInt k = 0; k < x->gn[2]; k++)
    for (PetscInt j = 0; j < x->gn[1]; j++)
      for (PetscInt i = 0; i < x->gn[0]; i++) {
        const float *c = src + off[0][i] + off[1][j] + off[2][k];
        PetscReal    v = 0.0;
        for (PetscInt kk = 0; kk < cnt[2][k]; kk++)
          for (PetscInt jj = 0; jj < cnt[1][j]; jj++)
            for (PetscInt ii = 0; ii < cnt[0][i]; ii++) v += (PetscReal)c[ii + jj * sy + kk * sz];
        gh[i + x->gn[0] * (j + x->gn[1] * k)] = (float)(v / (PetscReal)(cnt[0][i] * cnt[1][j] * cnt[2][k]));
      }
}

#define SRC(i, j, k) src[((i)-x->slo[0]) + x->sn[0] * (((j)-x->slo[1]) + x->sn[1] * ((k)-x->slo[2]))]
/* The conservative reverse of PffHaloFillCrossLevel: ghost values spread onto the source box. */
static void PffHaloSpreadCrossLevel(PffGrid g, const PffHaloPlan *p, const PffHaloXfer *x, float *halo)
{
  const PetscInt n = PffGridBlockN_Private(g, g->lgid[x->lb]), nn = PffGridBlockN_Private(g, x->nbgid);
  PetscInt       d[3];
  PffRegionDirection(x->region, d);
  float       *src = halo + x->soff;
  const float *gh  = halo + x->goff;
  PetscReal    o[3];
  for (int a = 0; a < 3; a++) o[a] = PffChannelOffset_Private(p->kind, x->comp, a);
  PetscArrayzero(src, x->sn[0] * x->sn[1] * x->sn[2]);
  for (PetscInt k = 0; k < x->gn[2]; k++)
    for (PetscInt j = 0; j < x->gn[1]; j++)
      for (PetscInt i = 0; i < x->gn[0]; i++) {
        const PetscInt  c[3] = {x->glo[0] + i, x->glo[1] + j, x->glo[2] + k};
        const PetscReal v    = (PetscReal)gh[i + x->gn[0] * (j + x->gn[1] * k)];
        if (v == 0) continue;
        if (x->rel > 0) {
          PetscInt  idx[3][2], m[3];
          PetscReal wt[3][2];
          for (int a = 0; a < 3; a++) m[a] = PffCoarseSpread(c[a], o[a], d[a] * n, nn, idx[a], wt[a]);
          for (PetscInt kk = 0; kk < m[2]; kk++)
            for (PetscInt jj = 0; jj < m[1]; jj++)
              for (PetscInt ii = 0; ii < m[0]; ii++)
                SRC(idx[0][ii], idx[1][jj], idx[2][kk]) += (float)(v * wt[0][ii] * wt[1][jj] * wt[2][kk]);
        } else {
          PetscInt f0[3], cnt[3];
          for (int a = 0; a < 3; a++) cnt[a] = PffFineCover(c[a], o[a], d[a] * n, &f0[a]);
          const float share = (float)(v / (PetscReal)(cnt[0] * cnt[1] * cnt[2]));
          for (PetscInt kk = 0; kk < cnt[2]; kk++)
            for (PetscInt jj = 0; jj < cnt[1]; jj++)
              for (PetscInt ii = 0; ii < cnt[0]; ii++) SRC(f0[0] + ii, f0[1] + jj, f0[2] + kk) += share;
        }
      }
#undef SRC
}

PetscErrorCode PffGridHaloEnd(PffGrid g, PetscInt ch)
{
  PffChannel *c = NULL;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetChannel_Private(g, ch, &c));
  PetscCall(PetscLogEventBegin(PFF_HaloEnd, 0, 0, 0, 0));
  PetscCall(PetscSFBcastEnd(c->plan->sf, MPI_FLOAT, c->data, c->halo, MPI_REPLACE));
  const PffHaloPlan *p = c->plan;
#pragma omp parallel for schedule(dynamic, 16)
  for (PetscInt e = 0; e < p->nxfer; e++)
    if (p->xfer[e].nbgid >= 0 && p->xfer[e].rel != 0) PffHaloFillCrossLevel(g, p, &p->xfer[e], c->halo);
  PetscCall(PetscLogEventEnd(PFF_HaloEnd, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridHaloReverseBegin(PffGrid g, PetscInt ch)
{
  PffChannel *c = NULL;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetChannel_Private(g, ch, &c));
  PetscCall(PetscLogEventBegin(PFF_HaloRevBegin, 0, 0, 0, 0));
  const PffHaloPlan *p = c->plan;
#pragma omp parallel for schedule(dynamic, 16)
  for (PetscInt e = 0; e < p->nxfer; e++)
    if (p->xfer[e].nbgid >= 0 && p->xfer[e].rel != 0) PffHaloSpreadCrossLevel(g, p, &p->xfer[e], c->halo);
  PetscCall(PetscSFReduceBegin(p->sf, MPI_FLOAT, c->halo, c->data, MPI_SUM));
  PetscCall(PetscLogEventEnd(PFF_HaloRevBegin, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridHaloReverseEnd(PffGrid g, PetscInt ch)
{
  PffChannel *c = NULL;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetChannel_Private(g, ch, &c));
  PetscCall(PetscLogEventBegin(PFF_HaloRevEnd, 0, 0, 0, 0));
  PetscCall(PetscSFReduceEnd(c->plan->sf, MPI_FLOAT, c->halo, c->data, MPI_SUM));
  PffZeroFloats_Private(c->halo, c->plan->nhalo);
  PetscCall(PetscLogEventEnd(PFF_HaloRevEnd, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}
