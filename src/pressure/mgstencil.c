/* pffmg matrix-free block levels (PF-FLIP Sec. 6.1-6.3, Algorithm 1).

   The pressure operator is a face operator, A = sum_f c_f g_f g_f^T + diag(dx), g_f = e_upper -
   sum_k w_k e_lower_k (w = 1, or 1/4 for the 4 fine cells under a coarse face), and dx the
   diagonal-only terms (Dirichlet walls, the unit of a cell with every face closed). At every
   multigrid level every cell owns the coefficients of its three lower faces, in float (cf). With
   piecewise-constant aggregation the Galerkin product P^T A P is again such a face operator (a
   level's faces never mix blocks in another way: under 2:1 grading a coarse-above-fine face only
   joins two blocks that both keep their resolution), so the coarse coefficients follow from the fine
   ones without forming any product (Algorithm 1):
     - a block that keeps its resolution copies its faces;
     - a block that merges 2x2x2 sums the 4 fine faces across each coarse face;
     - the diagonal-only terms sum over the 8 fine cells;
   and then the resolution-transition rescaling of mglevels.c: x 1/2 on faces between two merged
   cells, 3/4 between a merged and a kept cell, 1/2 on the diagonal-only terms of merged cells. (As
   entries of A_L this is exactly what RescaleCoarse does to the AIJ product.)

   Application reads the faces inside a block by raster strides (the 7-point stencil with 3
   coefficients per cell). The couplings through block sides -- same level, coarse-fine, on this rank
   or another -- are a small list per row, built once per grid with the face each entry comes from,
   and refreshed from cf at every set-up; the coefficients of faces owned by another rank's cells come
   through a PetscSF, the values of other ranks' cells through a VecScatter. */
#include "mgimpl.h"
#include <petscsf.h>
#include <omp.h>
#include <string.h>
#if defined(__AVX512F__) && defined(PETSC_USE_REAL_DOUBLE) && !defined(PETSC_USE_COMPLEX)
#include <immintrin.h>
#define PFF_MG_AVX512 1
#endif

const char *const PffMGOperatorTypes[] = {"stencil", "aij", "PffMGOperatorType", "PFF_MG_OPERATOR_", NULL};

/* The global numbering of one level: first row of every raster block, first row of every rank. */
typedef struct {
  PetscInt           n0, L, nb[3], nraster;
  const PetscInt    *level;
  const PetscMPIInt *owner;
  PetscInt          *first; /* [nraster] global first row (-1: inactive) */
  PetscInt          *rs;    /* [size + 1] */
  PetscMPIInt        size;
} PffMGNumbering;

static inline PetscInt CellsPerAxis(const PffMGNumbering *t, PetscInt gid)
{
  const PetscInt l = t->level[gid];
  return t->n0 >> (l > t->L ? l : t->L);
}

static PetscErrorCode NumberingCreate(PffMG *mg, PetscInt L, PffMGNumbering *t)
{
  PetscInt        nactive, *off;
  const PetscInt *gids;

  PetscFunctionBeginUser;
  t->L = L;
  PetscCall(PffGridGetSizes(mg->grid, &t->n0, NULL, NULL, NULL, NULL));
  PetscCall(PffGridGetRaster(mg->grid, t->nb, &t->level, &t->owner));
  PetscCall(PffGridGetMortonOrder(mg->grid, &nactive, &gids));
  PetscCallMPI(MPI_Comm_size(mg->comm, &t->size));
  t->nraster = t->nb[0] * t->nb[1] * t->nb[2];
  PetscCall(PetscMalloc1(t->nraster, &t->first));
  PetscCall(PetscCalloc1(t->size + 1, &t->rs));
  PetscCall(PetscCalloc1(t->size + 1, &off));
  for (PetscInt g = 0; g < t->nraster; g++) t->first[g] = -1;
  for (PetscInt q = 0; q < nactive; q++) {
    const PetscInt n = CellsPerAxis(t, gids[q]);
    t->rs[t->owner[gids[q]] + 1] += n * n * n;
  }
  for (PetscMPIInt r = 0; r < t->size; r++) t->rs[r + 1] += t->rs[r];
  for (PetscMPIInt r = 0; r < t->size; r++) off[r] = t->rs[r];
  /* each rank numbers its blocks in Morton order (the local order), so the global Morton order
     visits every rank's blocks in its numbering order */
  for (PetscInt q = 0; q < nactive; q++) {
    const PetscInt g = gids[q], n = CellsPerAxis(t, g);
    t->first[g] = off[t->owner[g]];
    off[t->owner[g]] += n * n * n;
  }
  PetscCall(PetscFree(off));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode NumberingDestroy(PffMGNumbering *t)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree(t->first));
  PetscCall(PetscFree(t->rs));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static inline PetscInt CellIndex(const PetscInt p[3], PetscInt n)
{
  return p[0] + n * (p[1] + n * p[2]);
}

/* One term of the side couplings while they are collected: row, and the column and face as handles,
   a local index (>= 0) or -2 - (global cell | global face 3 cell + d) on another rank. */
typedef struct {
  PetscInt   row;
  PetscInt64 col, ref; /* col = -1: a diagonal term */
  PffMGReal  fac;
} PffMGTerm;

typedef struct {
  PffMGTerm *t;
  PetscInt   n, cap;
  PetscBool  count; /* first pass: only count, so that the list is allocated once at its size */
} PffMGTerms;

static PetscErrorCode TermsAdd(PffMGTerms *T, PetscInt row, PetscInt64 col, PetscInt64 ref, PffMGReal fac)
{
  PetscFunctionBeginUser;
  if (T->count) {
    T->n++;
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PetscCheck(T->n < T->cap, PETSC_COMM_SELF, PETSC_ERR_PLIB, "pffmg: more side terms than counted");
  T->t[T->n++] = (PffMGTerm){row, col, ref, fac};
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The sides of each block whose couplings go face by face (st->fnb: an owned neighbour of the same size, one
   coupling -c x per cell; FaceSums), and the list of the remaining side entries (coarse-fine, another rank's
   neighbour, the block's own cells), which go entry by entry (SideCouplings). */
static PetscErrorCode SplitSides(const PffMG *mg, const PffMGLevel *lv, PffMGStencil *st)
{
  PetscInt ns = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc2(6 * lv->nblk, &st->fnb, lv->nblk + 1, &st->sb));
  for (PetscInt lb = 0; lb < lv->nblk; lb++)
    for (PetscInt s = 0; s < 6; s++) {
      const PetscInt nb   = mg->nbr[6 * lb + s];
      st->fnb[6 * lb + s] = nb >= 0 && nb != lb && lv->n[nb] == lv->n[lb] ? nb : -1;
    }
  for (PetscInt pass = 0; pass < 2; pass++) {
    ns = 0;
    for (PetscInt lb = 0; lb < lv->nblk; lb++) {
      st->sb[lb] = ns;
      for (PetscInt r = lv->start[lb]; r < lv->start[lb + 1]; r++)
        for (PetscInt e = st->rowptr[r]; e < st->rowptr[r + 1]; e++) {
          PetscBool fast = PETSC_FALSE;
          for (PetscInt s = 0; s < 6; s++) {
            const PetscInt nb = st->fnb[6 * lb + s];
            if (nb >= 0 && st->col[e] >= lv->start[nb] && st->col[e] < lv->start[nb + 1]) fast = PETSC_TRUE;
          }
          if (fast) continue;
          if (pass) {
            st->srow[ns] = r;
            st->sent[ns] = e;
          }
          ns++;
        }
    }
    st->sb[lv->nblk] = ns;
    if (!pass) PetscCall(PetscMalloc2(ns, &st->srow, ns, &st->sent));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Handle of cell p of raster block gid (local block lb, or -1) with n cells per axis. */
static inline PetscInt64 CellHandle(const PffMGLevel *lv, const PffMGNumbering *t, PetscInt gid, PetscInt lb,
                                    const PetscInt p[3], PetscInt n)
{
  const PetscInt c = CellIndex(p, n);
  return lb >= 0 ? (PetscInt64)(lv->start[lb] + c) : -2 - (PetscInt64)(t->first[gid] + c);
}

/* Handle of the lower d-face of cell p of block gid. */
static inline PetscInt64 FaceHandle(const PffMGLevel *lv, const PffMGNumbering *t, PetscInt gid, PetscInt lb,
                                    const PetscInt p[3], PetscInt n, PetscInt d)
{
  const PetscInt c = CellIndex(p, n);
  return lb >= 0 ? (PetscInt64)d * lv->nrows + lv->start[lb] + c : -2 - (3 * (PetscInt64)(t->first[gid] + c) + d);
}

/* The face neighbour of local block lb across side s (mglevels.c's neighbour table): its raster index
   (-1: wall or inactive) and its local index (-1: another rank's). */
static inline void SideNeighbour(const PffMG *mg, PetscInt lb, PetscInt s, PetscInt *g, PetscInt *l)
{
  const PetscInt nb = mg->nbr[6 * lb + s];
  *l                = nb >= 0 ? nb : -1;
  *g                = nb >= 0 ? mg->gid[nb] : (nb <= -2 ? -2 - nb : -1);
}

/* The couplings of the cells of local block lb through its side s (axis d = s / 2, upper if s odd).
   A lower side carries faces of this block's cells; an upper side faces of the neighbour's cells
   (their lower faces). n, m: cells per axis here and in the neighbour (m = n, n / 2 or 2 n). */
static PetscErrorCode CollectSide(PffMG *mg, const PffMGLevel *lv, const PffMGNumbering *t, PetscInt lb, PetscInt s,
                                  PffMGTerms *T)
{
  const PetscInt d = s / 2, a1 = (d + 1) % 3, a2 = (d + 2) % 3, upper = s % 2;
  PetscInt       gN, lN, n, m;

  PetscFunctionBeginUser;
  SideNeighbour(mg, lb, s, &gN, &lN);
  if (gN < 0) PetscFunctionReturn(PETSC_SUCCESS); /* wall or inactive: closed */
  n = lv->n[lb];
  m = CellsPerAxis(t, gN);
  PetscCheck(m == n || 2 * m == n || m == 2 * n, PETSC_COMM_SELF, PETSC_ERR_PLIB, "pffmg: blocks are not 2:1 graded");
  for (PetscInt v = 0; v < n; v++)
    for (PetscInt u = 0; u < n; u++) {
      PetscInt p[3], q[3];
      p[d]               = upper ? n - 1 : 0;
      p[a1]              = u;
      p[a2]              = v;
      const PetscInt row = lv->start[lb] + CellIndex(p, n);
      if (!upper) {
        const PetscInt64 ref = (PetscInt64)d * lv->nrows + row; /* this cell's own lower face */
        q[d]                 = m - 1;
        PetscCall(TermsAdd(T, row, -1, ref, 1));
        if (m == 2 * n) /* coarse above 4 fine cells: w = 1/4 each */
          for (PetscInt k = 0; k < 4; k++) {
            q[a1] = 2 * u + k % 2;
            q[a2] = 2 * v + k / 2;
            PetscCall(TermsAdd(T, row, CellHandle(lv, t, gN, lN, q, m), ref, -0.25f));
          }
        else {
          q[a1] = m == n ? u : u / 2;
          q[a2] = m == n ? v : v / 2;
          PetscCall(TermsAdd(T, row, CellHandle(lv, t, gN, lN, q, m), ref, -1));
        }
      } else if (m == n || m == 2 * n) { /* 1 or 4 faces of the neighbour's cells, each with this cell below */
        const PetscInt r = m / n;
        q[d]             = 0;
        for (PetscInt k = 0; k < r * r; k++) {
          q[a1]                = r * u + k % r;
          q[a2]                = r * v + k / r;
          const PetscInt64 ref = FaceHandle(lv, t, gN, lN, q, m, d);
          PetscCall(TermsAdd(T, row, -1, ref, 1));
          PetscCall(TermsAdd(T, row, CellHandle(lv, t, gN, lN, q, m), ref, -1));
        }
      } else { /* the neighbour is coarser: its cell's face has 4 lower cells here, this one among them */
        q[d]                 = 0;
        q[a1]                = u / 2;
        q[a2]                = v / 2;
        const PetscInt64 ref = FaceHandle(lv, t, gN, lN, q, m, d);
        PetscCall(TermsAdd(T, row, -1, ref, 1.0f / 16));
        PetscCall(TermsAdd(T, row, CellHandle(lv, t, gN, lN, q, m), ref, -0.25f));
        for (PetscInt k = 0; k < 4; k++) {
          PetscInt f[3];
          f[d]  = n - 1;
          f[a1] = 2 * (u / 2) + k % 2;
          f[a2] = 2 * (v / 2) + k / 2;
          if (f[a1] == u && f[a2] == v) continue;
          PetscCall(TermsAdd(T, row, lv->start[lb] + CellIndex(f, n), ref, 1.0f / 16));
        }
      }
    }
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscInt FindInt64(PetscInt64 key, PetscInt n, const PetscInt64 *a)
{
  PetscInt lo = 0, hi = n - 1;
  while (lo < hi) {
    const PetscInt mid = (lo + hi) / 2;
    if (a[mid] < key)
      lo = mid + 1;
    else
      hi = mid;
  }
  return n > 0 && a[lo] == key ? lo : -1;
}

/* Distinct remote handles of one kind (cells or faces), increasing by global number. */
static PetscErrorCode RemoteHandles(const PffMGTerms *T, PetscBool faces, PetscInt *n, PetscInt64 **g)
{
  PetscInt cnt = 0;

  PetscFunctionBeginUser;
  for (PetscInt e = 0; e < T->n; e++)
    if ((faces ? T->t[e].ref : T->t[e].col) <= -2) cnt++;
  PetscCall(PetscMalloc1(cnt, g));
  cnt = 0;
  for (PetscInt e = 0; e < T->n; e++) {
    const PetscInt64 h = faces ? T->t[e].ref : T->t[e].col;
    if (h <= -2) (*g)[cnt++] = -2 - h;
  }
  PetscCall(PetscSortInt64(cnt, *g));
  *n = 0;
  for (PetscInt q = 0; q < cnt; q++)
    if (*n == 0 || (*g)[q] != (*g)[*n - 1]) (*g)[(*n)++] = (*g)[q];
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscMPIInt RankOfRow(const PffMGNumbering *t, PetscInt64 row)
{
  PetscMPIInt lo = 0, hi = t->size - 1;
  while (lo < hi) { /* the last rank r with rs[r] <= row */
    const PetscMPIInt mid = (lo + hi + 1) / 2;
    if (t->rs[mid] <= row)
      lo = mid;
    else
      hi = mid - 1;
  }
  return lo;
}

/* Structure of level L, once per grid: the side couplings as CSR with their faces, the ghost cells
   and the SF of the ghost face coefficients. */
PetscErrorCode PffMGStencilBuild_Private(PffMG *mg, PetscInt L)
{
  PffMGLevel    *lv = &mg->lev[L];
  PffMGStencil  *st;
  PffMGNumbering t;
  PffMGTerms     T = {NULL, 0, 0, PETSC_TRUE};
  PetscInt64    *gcell, *gface;
  PetscInt      *cursor;
  PetscMPIInt    rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(mg->comm, &rank));
  PetscCall(NumberingCreate(mg, L, &t));
  PetscCall(PetscNew(&st));
  lv->st = st;
  for (PetscInt lb = 0; lb < mg->nlocal; lb++) {
    PetscCheck(t.first[mg->gid[lb]] - t.rs[rank] == lv->start[lb], PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "pffmg: the level numbering does not follow the Morton order");
    for (PetscInt s = 0; s < 6; s++) PetscCall(CollectSide(mg, lv, &t, lb, s, &T));
  }
  T.cap   = T.n;
  T.n     = 0;
  T.count = PETSC_FALSE;
  PetscCall(PetscMalloc1(T.cap, &T.t));
  for (PetscInt lb = 0; lb < mg->nlocal; lb++)
    for (PetscInt s = 0; s < 6; s++) PetscCall(CollectSide(mg, lv, &t, lb, s, &T));

  /* ghosts: cells by global row, faces by global face 3 row + d, both increasing */
  PetscCall(RemoteHandles(&T, PETSC_FALSE, &st->nghost, &gcell));
  PetscCall(RemoteHandles(&T, PETSC_TRUE, &st->nslot, &gface));
  PetscCall(PetscMalloc1(st->nghost, &st->ghostRow));
  for (PetscInt q = 0; q < st->nghost; q++) st->ghostRow[q] = (PetscInt)gcell[q];
  {
    PetscSFNode *remote;
    PetscCall(PetscMalloc1(st->nslot, &remote));
    for (PetscInt q = 0; q < st->nslot; q++) {
      const PetscInt64  row = gface[q] / 3, d = gface[q] % 3;
      const PetscMPIInt r = RankOfRow(&t, row);
      remote[q].rank      = r;
      remote[q].index     = (PetscInt)(d * (t.rs[r + 1] - t.rs[r]) + (row - t.rs[r]));
    }
    PetscCall(PetscSFCreate(mg->comm, &st->sfSlot));
    PetscCall(
        PetscSFSetGraph(st->sfSlot, 3 * lv->nrows, st->nslot, NULL, PETSC_COPY_VALUES, remote, PETSC_OWN_POINTER));
    PetscCall(PetscSFSetUp(st->sfSlot));
  }

  /* CSR of the couplings to other cells, rows in order, the terms of a row in collection order; the
     diagonal terms in a list of their own */
  PetscCall(PetscCalloc1(lv->nrows + 1, &st->rowptr));
  for (PetscInt e = 0; e < T.n; e++) {
    if (T.t[e].col == -1)
      st->ndiag++;
    else
      st->rowptr[T.t[e].row + 1]++;
  }
  PetscCall(PetscMalloc4(T.n - st->ndiag, &st->col, T.n - st->ndiag, &st->val, T.n - st->ndiag, &st->ref,
                         T.n - st->ndiag, &st->fac));
  PetscCall(PetscMalloc3(st->ndiag, &st->drow, st->ndiag, &st->dref, st->ndiag, &st->dfac));
  PetscCall(PetscMalloc1(lv->nrows, &cursor));
  for (PetscInt r = 0; r < lv->nrows; r++) {
    st->rowptr[r + 1] += st->rowptr[r];
    cursor[r] = st->rowptr[r];
  }
  for (PetscInt e = 0, nd = 0; e < T.n; e++) {
    const PffMGTerm *m   = &T.t[e];
    const PetscInt   ref = m->ref >= 0 ? (PetscInt)m->ref : 3 * lv->nrows + FindInt64(-2 - m->ref, st->nslot, gface);
    if (m->col == -1) {
      st->drow[nd] = m->row;
      st->dref[nd] = ref;
      st->dfac[nd] = m->fac;
      nd++;
      continue;
    }
    const PetscInt k = cursor[m->row]++;
    st->ref[k]       = ref;
    st->col[k]       = m->col >= 0 ? (PetscInt)m->col : lv->nrows + FindInt64(-2 - m->col, st->nghost, gcell);
    st->fac[k]       = m->fac;
  }
  PetscCall(PetscFree(cursor));
  PetscCall(PetscFree(T.t));
  PetscCall(PetscMalloc1(lv->nblk, &st->own));
  for (PetscInt lb = 0; lb < lv->nblk; lb++) {
    st->own[lb] = PETSC_FALSE;
    for (PetscInt e = st->rowptr[lv->start[lb]]; e < st->rowptr[lv->start[lb + 1]]; e++)
      if (st->col[e] >= lv->start[lb] && st->col[e] < lv->start[lb + 1]) st->own[lb] = PETSC_TRUE;
  }
  PetscCall(SplitSides(mg, lv, st));
  PetscCall(PetscFree(gcell));
  PetscCall(PetscFree(gface));
  PetscCall(NumberingDestroy(&t));

  PetscCall(PetscMalloc4(3 * lv->nrows, &st->cf, lv->nrows, &st->dx, lv->nrows, &st->ds, st->nslot, &st->cghost));
  PetscCall(PetscMalloc2(lv->nrows, &st->adf, lv->nrows, &st->idf));
  /* a matrix-free level keeps 1 / a_ii in float only (idf); the last block level, assembled, in double too */
  if (lv->idiag == NULL && !lv->mf) PetscCall(PetscMalloc1(lv->nrows, &lv->idiag));
  if (lv->mf) {
    IS is;
    PetscCall(ISCreateGeneral(PETSC_COMM_SELF, st->nghost, st->ghostRow, PETSC_USE_POINTER, &is));
    PetscCall(VecCreateSeq(PETSC_COMM_SELF, st->nghost, &lv->ghost));
    Vec layout; /* the level's row layout, no storage: a matrix-free level keeps no residual vector */
    PetscCall(VecCreateMPIWithArray(mg->comm, 1, lv->nrows, PETSC_DETERMINE, NULL, &layout));
    PetscCall(VecScatterCreate(layout, is, lv->ghost, NULL, &lv->scatter));
    PetscCall(VecDestroy(&layout));
    PetscCall(ISDestroy(&is));
    lv->nghost = st->nghost;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffMGStencilDestroy_Private(PffMGLevel *lv)
{
  PffMGStencil *st = lv->st;

  PetscFunctionBeginUser;
  if (!st) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscFree(st->rowptr));
  PetscCall(PetscFree(st->own));
  PetscCall(PetscFree2(st->fnb, st->sb));
  PetscCall(PetscFree2(st->srow, st->sent));
  PetscCall(PetscFree4(st->col, st->val, st->ref, st->fac));
  PetscCall(PetscFree3(st->drow, st->dref, st->dfac));
  PetscCall(PetscFree(st->ghostRow));
  PetscCall(PetscFree4(st->cf, st->dx, st->ds, st->cghost));
  PetscCall(PetscFree2(st->adf, st->idf));
  PetscCall(PetscFree(st->closed));
  PetscCall(PetscSFDestroy(&st->sfSlot));
  PetscCall(MatDestroy(&st->Aview));
  PetscCall(PetscFree(lv->st));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Level 0: the pressure module's face coefficients and Dirichlet terms, in float. */
static PetscErrorCode CoefficientsFine(PffMG *mg)
{
  PffMGLevel        *lv  = &mg->lev[0];
  PffMGStencil      *st  = lv->st;
  PffPressure        ps  = mg->ps;
  const PetscScalar *dd  = NULL;
  const PetscBool    dir = PffPressureHasDirichlet_Private(ps);

  PetscFunctionBeginUser;
  PetscCheck(ps->ncells == lv->nrows, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "pffmg: level 0 does not match the pressure cells");
  /* the same axis-major layout: cf[d * nrows + r] */
  for (PetscInt q = 0; q < 3 * lv->nrows; q++) st->cf[q] = (PffMGReal)ps->cf[q];
  if (dir) PetscCall(VecGetArrayRead(ps->dirdiag, &dd));
  for (PetscInt r = 0; r < lv->nrows; r++) st->dx[r] = dd ? (PffMGReal)PetscRealPart(dd[r]) : 0;
  if (dir) PetscCall(VecRestoreArrayRead(ps->dirdiag, &dd));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Algorithm 1: the coefficients of level L from those of level L - 1 (see the top of the file). */
static PetscErrorCode CoefficientsCoarse(PffMG *mg, PetscInt L)
{
  const PffMGLevel *f = &mg->lev[L - 1], *c = &mg->lev[L];
  const PffMGReal  *cff = f->st->cf, *dxf = f->st->dx;
  PffMGReal        *cfc = c->st->cf, *dxc = c->st->dx;
  const PetscInt   *level;
  const PetscBool   rs = mg->opt.rescale;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetRaster(mg->grid, NULL, &level, NULL));
  for (PetscInt lb = 0; lb < mg->nlocal; lb++) {
    const PetscInt  nf = f->n[lb], nc = c->n[lb], of = f->start[lb], oc = c->start[lb];
    const PetscBool merged = (PetscBool)(nc < nf);
    PffMGReal       sside[3];
    for (PetscInt d = 0; d < 3; d++) { /* the lower side of axis d: side 2 d */
      PetscInt g, l;
      SideNeighbour(mg, lb, 2 * d, &g, &l);
      const PetscBool mN = (PetscBool)(g >= 0 && level[g] < L); /* the neighbour merged into level L */
      sside[d]           = !rs ? 1 : (merged && mN ? 0.5f : (merged || mN ? 0.75f : 1));
    }
    if (!merged) {
      for (PetscInt k = 0; k < nc; k++)
        for (PetscInt j = 0; j < nc; j++)
          for (PetscInt i = 0; i < nc; i++) {
            const PetscInt p[3] = {i, j, k}, q = i + nc * (j + nc * k);
            for (PetscInt d = 0; d < 3; d++)
              cfc[d * c->nrows + oc + q] = cff[d * f->nrows + of + q] * (p[d] == 0 ? sside[d] : 1);
            dxc[oc + q] = dxf[of + q];
          }
      continue;
    }
    for (PetscInt k = 0; k < nc; k++)
      for (PetscInt j = 0; j < nc; j++)
        for (PetscInt i = 0; i < nc; i++) {
          const PetscInt P[3] = {i, j, k}, q = i + nc * (j + nc * k);
          PffMGReal      sdx = 0;
          for (PetscInt e = 0; e < 8; e++)
            sdx += dxf[of + (2 * i + e % 2) + nf * ((2 * j + (e / 2) % 2) + nf * (2 * k + e / 4))];
          dxc[oc + q] = (rs ? 0.5f : 1) * sdx;
          for (PetscInt d = 0; d < 3; d++) {
            const PetscInt a1 = (d + 1) % 3, a2 = (d + 2) % 3;
            PffMGReal      sum = 0;
            for (PetscInt e = 0; e < 4; e++) {
              PetscInt x[3];
              x[d]  = 2 * P[d];
              x[a1] = 2 * P[a1] + e % 2;
              x[a2] = 2 * P[a2] + e / 2;
              sum += cff[d * f->nrows + of + x[0] + nf * (x[1] + nf * x[2])];
            }
            cfc[d * c->nrows + oc + q] = sum * (P[d] == 0 ? sside[d] : (rs ? 0.5f : 1));
          }
        }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Face coefficients of the in-block neighbours of the cells of one row (j, k) of a block: the strides
   to the y and z neighbours, 0 with a zero weight where the neighbour is outside the block (the
   coupling is then a side term), so that every row runs the same loop. */
typedef struct {
  PetscInt  sym, syp, szm, szp;
  PetscReal mym, myp, mzm, mzp;
} PffMGRowMask;

static inline PffMGRowMask RowMask(PetscInt j, PetscInt k, PetscInt n)
{
  PffMGRowMask m;
  m.sym = j > 0 ? n : 0;
  m.syp = j < n - 1 ? n : 0;
  m.szm = k > 0 ? n * n : 0;
  m.szp = k < n - 1 ? n * n : 0;
  m.mym = j > 0;
  m.myp = j < n - 1;
  m.mzm = k > 0;
  m.mzp = k < n - 1;
  return m;
}

/* The in-block part of the diagonal of cell r; the rest (side faces, diagonal-only terms) is ds[r]. */
static inline PetscReal DiagonalInBlock(const PffMGStencil *st, PetscInt nr, PetscInt r, PetscInt i, PetscInt j,
                                        PetscInt k, PetscInt n)
{
  const PffMGReal *cx = st->cf, *cy = cx + nr, *cz = cy + nr;
  PetscReal        d = 0;

  if (i > 0) d += cx[r];
  if (i < n - 1) d += cx[r + 1];
  if (j > 0) d += cy[r];
  if (j < n - 1) d += cy[r + n];
  if (k > 0) d += cz[r];
  if (k < n - 1) d += cz[r + n * n];
  return d;
}

static inline PetscReal Diagonal(const PffMGStencil *st, PetscInt nr, PetscInt r, PetscInt i, PetscInt j, PetscInt k,
                                 PetscInt n)
{
  return DiagonalInBlock(st, nr, r, i, j, k, n) + st->ds[r];
}

/* Coefficients, side-coupling values and inverse diagonal of level L, at every set-up (levels in order). */
PetscErrorCode PffMGStencilUpdate_Private(PffMG *mg, PetscInt L)
{
  PffMGLevel    *lv = &mg->lev[L];
  PffMGStencil  *st = lv->st;
  const PetscInt nr = lv->nrows;

  PetscFunctionBeginUser;
  if (L == 0)
    PetscCall(CoefficientsFine(mg));
  else
    PetscCall(CoefficientsCoarse(mg, L));
  PetscCall(PetscSFBcastBegin(st->sfSlot, MPIU_PFFMGREAL, st->cf, st->cghost, MPI_REPLACE));
  PetscCall(PetscSFBcastEnd(st->sfSlot, MPIU_PFFMGREAL, st->cf, st->cghost, MPI_REPLACE));
  for (PetscInt e = 0; e < st->rowptr[nr]; e++) {
    const PetscInt r = st->ref[e];
    st->val[e]       = st->fac[e] * (r < 3 * nr ? st->cf[r] : st->cghost[r - 3 * nr]);
  }
  for (PetscInt r = 0; r < nr; r++) st->ds[r] = 0;
  st->nclosed = 0;
  for (PetscInt e = 0; e < st->ndiag; e++) {
    const PetscInt r = st->dref[e];
    st->ds[st->drow[e]] += (PetscReal)st->dfac[e] * (r < 3 * nr ? st->cf[r] : st->cghost[r - 3 * nr]);
  }
  for (PetscInt lb = 0; lb < mg->nlocal; lb++) {
    const PetscInt n = lv->n[lb], o = lv->start[lb];
    for (PetscInt k = 0; k < n; k++)
      for (PetscInt j = 0; j < n; j++)
        for (PetscInt i = 0; i < n; i++) {
          const PetscInt r = o + i + n * (j + n * k);
          /* no open face and no Dirichlet term (inside a solid): an identity row on level 0, kept out of dx, which
             Algorithm 1 sums into the coarse cells: there it acted as a Dirichlet condition p = 0 at the solid's
             cells, a wall that is not there, and the K-cycle, which solves the coarse problems more exactly, took
             more FCG iterations than a V-cycle in the dam breaks with their obstacle (docs/benchmarks.md) */
          const PetscBool closed =
              (PetscBool)(L == 0 && DiagonalInBlock(st, nr, r, i, j, k, n) + st->ds[r] + st->dx[r] == 0);
          st->ds[r] += st->dx[r] + (closed ? 1 : 0);
          if (closed) {
            if (st->nclosed == st->closedCap) { /* grows only: the set is found again at every update */
              st->closedCap = PetscMax(1024, 2 * st->closedCap);
              PetscCall(PetscRealloc(sizeof(PetscInt) * (size_t)st->closedCap, &st->closed));
            }
            st->closed[st->nclosed++] = r;
          }
          /* a zero row is legitimate on a coarse level: a cell that aggregates a region whose every outer
             face is closed (on the last level, a closed box of one block); it is not relaxed, as on the
             AIJ levels, and the pinned coarsest operator takes care of it */
          const PetscReal d = Diagonal(st, nr, r, i, j, k, n);
          st->adf[r]        = (float)d;
          st->idf[r]        = (float)(d > 0 ? 1.0 / d : 0.0);
          if (lv->idiag) lv->idiag[r] = d > 0 ? 1.0 / d : 0.0;
        }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The in-block part of (A x)_r, the general path for a cell that must not read past x. */
static inline PetscScalar RowInBlock(const PffMGStencil *st, PetscInt nr, PetscInt r, PetscInt i, PetscInt j,
                                     PetscInt k, PetscInt n, const PetscScalar *x)
{
  const PffMGReal *cx = st->cf, *cy = cx + nr, *cz = cy + nr;
  const PetscInt   n2  = n * n;
  PetscScalar      off = 0;

  if (i > 0) off -= cx[r] * x[r - 1];
  if (i < n - 1) off -= cx[r + 1] * x[r + 1];
  if (j > 0) off -= cy[r] * x[r - n];
  if (j < n - 1) off -= cy[r + n] * x[r + n];
  if (k > 0) off -= cz[r] * x[r - n2];
  if (k < n - 1) off -= cz[r + n2] * x[r + n2];
  return Diagonal(st, nr, r, i, j, k, n) * x[r] + off;
}

/* The couplings -c x_nb of the cells of local block lb through side s to the owned neighbour of the same size
   st->fnb (the side list's entries -c, a plane at a time instead of entry by entry): subtracted from the float
   right-hand side bs of a visit, or else added to yd times add. The face's c is the lower cell's, this block's on a
   lower side and the neighbour's on an upper one. */
static void FaceSums(const PffMGLevel *lv, PetscInt lb, PetscInt s, const PetscScalar *x, PetscReal add,
                     float *restrict bs, PetscScalar *restrict yd)
{
  const PffMGStencil *st = lv->st;
  const PetscInt      n = lv->n[lb], d = s / 2, upper = s % 2, nb = st->fnb[6 * lb + s];
  const PetscInt      stride[3] = {1, n, n * n};
  const PetscInt      si = d == 0 ? n : 1, so = d == 2 ? n : n * n; /* inner and outer strides in the plane */
  const PetscInt      own = upper ? (n - 1) * stride[d] : 0, far = upper ? 0 : (n - 1) * stride[d];
  const PetscScalar *restrict xn = x + lv->start[nb] + far;
  const float *restrict c        = st->cf + d * lv->nrows + (upper ? lv->start[nb] + far : lv->start[lb] + own);

  if (bs) {
    float *restrict o = bs + own;
    for (PetscInt v = 0; v < n; v++)
      for (PetscInt u = 0; u < n; u++) o[si * u + so * v] += c[si * u + so * v] * (float)xn[si * u + so * v];
  } else {
    PetscScalar *restrict o = yd + own;
    for (PetscInt v = 0; v < n; v++)
      for (PetscInt u = 0; u < n; u++) o[si * u + so * v] -= add * c[si * u + so * v] * xn[si * u + so * v];
  }
}

/* The couplings val x_col of the cells of local block lb to other cells through the block's sides, block-local:
   face by face to the owned neighbours of the same size (FaceSums), entry by entry to the others (coarse-fine,
   another rank's: st->sent). Subtracted from the float right-hand side bs, or else added to yd times add (1: a
   product, -1: a right-hand side). inBlock: also the side terms between the block's own cells (a coarse level's
   cells under one coarse face above the block), which a right-hand side leaves to OwnSums. */
static void SideCouplings(const PffMGLevel *lv, PetscInt lb, const PetscScalar *x, const PetscScalar *g, PetscReal add,
                          PetscBool inBlock, float *restrict bs, PetscScalar *restrict yd)
{
  const PffMGStencil *st = lv->st;
  const PetscInt      nr = lv->nrows, r0 = lv->start[lb], r1 = lv->start[lb + 1];

  for (PetscInt s = 0; s < 6; s++)
    if (st->fnb[6 * lb + s] >= 0) FaceSums(lv, lb, s, x, add, bs, yd);
  for (PetscInt q = st->sb[lb]; q < st->sb[lb + 1]; q++) {
    const PetscInt e = st->sent[q], c = st->col[e];
    if (!inBlock && c >= r0 && c < r1) continue;
    const PetscScalar t = st->val[e] * (c < nr ? x[c] : g[c - nr]);
    if (bs)
      bs[st->srow[q] - r0] -= (float)t;
    else
      yd[st->srow[q] - r0] += add * t;
  }
}

/* bb = b - (the side couplings of the cells of local block lb to other blocks), block-local. The blocks
   around are frozen while a block is relaxed (the other block colour, or ghosts), so their part of each
   row is a constant of the block's visit: it is gathered once (SideCouplings),
   for all the sweeps of the visit, and the sweeps run one uniform loop. The side terms between cells
   of the block itself (fine cells under one coarse face above the block) change within a sweep; they
   are left out here and added row by row (OwnSums); st->own[lb] says whether the block has any (made at build),
   and is returned. */
PetscBool PffMGStencilBlockRhs_Private(const PffMGLevel *lv, PetscInt lb, const PetscScalar *b, const PetscScalar *x,
                                       const PetscScalar *g, PetscScalar *bb)
{
  const PffMGStencil *st = lv->st;
  const PetscInt      n = lv->n[lb], r0 = lv->start[lb], nc = n * n * n;

  for (PetscInt i = 0; i < nc; i++) bb[i] = b[r0 + i];
  SideCouplings(lv, lb, x, g, -1, PETSC_FALSE, NULL, bb);
  return st->own[lb];
}

/* tb = bb - the in-block side terms of the cells i0, i0 + 2, ... of the row starting at base (see above),
   with the current x; the other cells keep bb. */
static inline void OwnSums(const PffMGLevel *lv, PetscInt r0, PetscInt nc, PetscInt base, PetscInt i0, PetscInt n,
                           const PetscScalar *bb, const PetscScalar *x, PetscScalar *tb)
{
  const PffMGStencil *st = lv->st;

  for (PetscInt i = 0; i < n; i++) tb[i] = bb[i];
  for (PetscInt i = i0; i < n; i += 2)
    for (PetscInt e = st->rowptr[base + i]; e < st->rowptr[base + i + 1]; e++) {
      const PetscInt c = st->col[e];
      if (c >= r0 && c < r0 + nc) tb[i] -= st->val[e] * x[c];
    }
}

/* Relaxes the cell at one x end of its row; returns |omega (bb - A x)_r| and stores it in R. */
static inline PetscReal RelaxEnd(const PffMGLevel *lv, const PffMGStencil *st, PetscInt r, PetscInt i, PetscInt j,
                                 PetscInt k, PetscInt n, PetscScalar bb, PetscScalar *x, PetscReal omega, PetscReal *R,
                                 PetscInt r0)
{
  const PetscScalar s   = bb - RowInBlock(st, lv->nrows, r, i, j, k, n, x);
  const PetscReal   eff = PetscAbsScalar(omega * s);
  x[r] += omega * s * (PetscReal)st->idf[r];
  if (R) R[r - r0] = eff;
  return eff;
}

/* Weights of the x-faces of the cells of a row: 0 where the neighbour is outside the block (its
   coupling is a side term), so that the whole row runs one loop; and the colour masks of a row, 1 on
   the cells i0, i0 + 2, ... (col[i0]). */
typedef struct {
  PetscReal lo[PFF_GRID_BLOCK_SIZE_MAX], hi[PFF_GRID_BLOCK_SIZE_MAX], col[2][PFF_GRID_BLOCK_SIZE_MAX];
} PffMGRowEnds;

static inline void RowEnds(PetscInt n, PffMGRowEnds *e)
{
  for (PetscInt i = 0; i < n; i++) {
    e->lo[i]     = i > 0;
    e->hi[i]     = i < n - 1;
    e->col[0][i] = (i & 1) == 0;
    e->col[1][i] = (i & 1) == 1;
  }
}

/* Relaxes the cells of colour c of the row starting at r0 (n cells, (i + j + k) % 2 == c for i =
   i0, i0 + 2, ...): the candidate values of every cell are computed from x into a buffer, then those
   of the colour are stored. Both loops run over contiguous cells and vectorise (a loop over one colour
   has 8 cells for n = 16, too few for an 8-wide vector): the first only reads x and computes twice the
   cells for no extra memory traffic, the second blends by the colour mask. The x-neighbours outside the
   block are read (the cells around the row in memory, never outside the array: the first and last rows
   go through RelaxRowEnds) and weighted 0; bb is the row's right-hand side with its side couplings
   (PffMGStencilBlockRhs_Private). R (or NULL) receives |omega (bb - A x)| of the colour's cells, and mx
   the running per-lane maximum of it, so that no reduction runs per row. */
static inline void RelaxRow(const PffMGStencil *st, PetscInt          nr, const PetscScalar *restrict bb,
                            const float *restrict idiag, PetscScalar *x, PetscInt r0, PetscInt i0, PetscInt n,
                            PffMGRowMask m, const PffMGRowEnds *restrict e, PetscReal omega, PetscReal *restrict R,
                            PetscReal *restrict mx)
{
  const PffMGReal *restrict cx = st->cf, *restrict cy = cx + nr, *restrict cz = cy + nr;
  const PetscReal *restrict ds = st->ds, *restrict cm = e->col[i0];
  const PetscScalar *restrict xr = x;
  PetscScalar *restrict xw       = x + r0;
  PetscScalar nx[PFF_GRID_BLOCK_SIZE_MAX];
  PetscReal   ev[PFF_GRID_BLOCK_SIZE_MAX];

  for (PetscInt i = 0; i < n; i++) {
    const PetscInt    r  = r0 + i;
    const PetscReal   c0 = e->lo[i] * cx[r], c1 = e->hi[i] * cx[r + 1], c2 = m.mym * cy[r], c3 = m.myp * cy[r + m.syp];
    const PetscReal   c4 = m.mzm * cz[r], c5 = m.mzp * cz[r + m.szp];
    const PetscReal   d = c0 + c1 + c2 + c3 + c4 + c5 + ds[r];
    const PetscScalar s = bb[i] - d * xr[r] + c0 * xr[r - 1] + c1 * xr[r + 1] + c2 * xr[r - m.sym] +
                          c3 * xr[r + m.syp] + c4 * xr[r - m.szm] + c5 * xr[r + m.szp];
    ev[i] = cm[i] * PetscAbsReal(omega * s);
    nx[i] = xr[r] + omega * s * idiag[r]; /* idiag = 0: a zero row is not relaxed */
  }
  for (PetscInt i = 0; i < n; i++) {
    xw[i] = cm[i] != 0 ? nx[i] : xw[i];
    mx[i] = mx[i] > ev[i] ? mx[i] : ev[i];
  }
  if (R)
    for (PetscInt i = 0; i < n; i++) R[i] = cm[i] != 0 ? ev[i] : R[i];
}

#if defined(PFF_MG_AVX512)
/* RelaxRow for n = 16 with AVX-512: the 8 cells of the colour only, gathered from the row's two 8-wide
   vectors by lane permutes (the x-neighbours are the other colour's lanes), so each row costs one
   vector of arithmetic instead of two; the new values and R go back to the colour's lanes by masked
   permutes. Reads nothing outside the row. Equal to RelaxRow to rounding (fused multiply-adds);
   about 1.7x faster in isolation (docs/pressure.md). */
static inline void RelaxRow16(const PffMGStencil *st, PetscInt          nr, const PetscScalar *restrict bb,
                              const float *restrict idiag, PetscScalar *x, PetscInt r0, PetscInt i0, PffMGRowMask m,
                              PetscReal omega, PetscReal *restrict R, PetscReal *restrict mx)
{
  const PffMGReal *cx = st->cf, *cy = cx + nr, *cz = cy + nr;
  /* lanes of the colour's cells i0 + 2t in the row's 16 values, and of their x-neighbours (an unused lane
     where the neighbour is outside the row: its face weight is 0) */
  const __m512i  ic = i0 ? _mm512_setr_epi64(1, 3, 5, 7, 9, 11, 13, 15) : _mm512_setr_epi64(0, 2, 4, 6, 8, 10, 12, 14);
  const __m512i  il = i0 ? _mm512_setr_epi64(0, 2, 4, 6, 8, 10, 12, 14) : _mm512_setr_epi64(0, 1, 3, 5, 7, 9, 11, 13);
  const __m512i  ir = i0 ? _mm512_setr_epi64(2, 4, 6, 8, 10, 12, 14, 15) : _mm512_setr_epi64(1, 3, 5, 7, 9, 11, 13, 15);
  const __m512i  fc = i0 ? _mm512_setr_epi32(1, 3, 5, 7, 9, 11, 13, 15, 0, 0, 0, 0, 0, 0, 0, 0)
                         : _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 0, 0, 0, 0, 0, 0, 0, 0);
  const __m512i  fr = i0 ? _mm512_setr_epi32(2, 4, 6, 8, 10, 12, 14, 15, 0, 0, 0, 0, 0, 0, 0, 0)
                         : _mm512_setr_epi32(1, 3, 5, 7, 9, 11, 13, 15, 0, 0, 0, 0, 0, 0, 0, 0);
  const __mmask8 mk = i0 ? 0xAA : 0x55;
  const __m512i  back0 = i0 ? _mm512_setr_epi64(0, 0, 0, 1, 0, 2, 0, 3) : _mm512_setr_epi64(0, 0, 1, 0, 2, 0, 3, 0);
  const __m512i  back1 = i0 ? _mm512_setr_epi64(0, 4, 0, 5, 0, 6, 0, 7) : _mm512_setr_epi64(4, 0, 5, 0, 6, 0, 7, 0);
#define PFF_COLOUR_PD(p) _mm512_permutex2var_pd(_mm512_loadu_pd(p), ic, _mm512_loadu_pd((p) + 8))
#define PFF_COLOUR_PS(p, ix) _mm512_cvtps_pd(_mm512_castps512_ps256(_mm512_permutexvar_ps(ix, _mm512_loadu_ps(p))))
  const __m512d X0 = _mm512_loadu_pd(x + r0), X1 = _mm512_loadu_pd(x + r0 + 8);
  const __m512d xc = _mm512_permutex2var_pd(X0, ic, X1), xl = _mm512_permutex2var_pd(X0, il, X1),
                xr = _mm512_permutex2var_pd(X0, ir, X1);
  __m512d c0 = PFF_COLOUR_PS(cx + r0, fc), c1 = PFF_COLOUR_PS(cx + r0, fr);
  if (!i0)
    c0 = _mm512_mask_mov_pd(c0, 0x01, _mm512_setzero_pd()); /* cell 0: its -x face is a side face */
  else
    c1 = _mm512_mask_mov_pd(c1, 0x80, _mm512_setzero_pd()); /* cell 15: its +x face is a side face */
  const __m512d c2 = _mm512_mul_pd(_mm512_set1_pd(m.mym), PFF_COLOUR_PS(cy + r0, fc)),
                c3 = _mm512_mul_pd(_mm512_set1_pd(m.myp), PFF_COLOUR_PS(cy + r0 + m.syp, fc)),
                c4 = _mm512_mul_pd(_mm512_set1_pd(m.mzm), PFF_COLOUR_PS(cz + r0, fc)),
                c5 = _mm512_mul_pd(_mm512_set1_pd(m.mzp), PFF_COLOUR_PS(cz + r0 + m.szp, fc));
  const __m512d d  = _mm512_add_pd(_mm512_add_pd(_mm512_add_pd(c0, c1), _mm512_add_pd(c2, c3)),
                                   _mm512_add_pd(_mm512_add_pd(c4, c5), PFF_COLOUR_PD(st->ds + r0)));
  __m512d       s  = _mm512_fnmadd_pd(d, xc, PFF_COLOUR_PD(bb));
  s                = _mm512_fmadd_pd(c0, xl, s);
  s                = _mm512_fmadd_pd(c1, xr, s);
  s                = _mm512_fmadd_pd(c2, PFF_COLOUR_PD(x + r0 - m.sym), s);
  s                = _mm512_fmadd_pd(c3, PFF_COLOUR_PD(x + r0 + m.syp), s);
  s                = _mm512_fmadd_pd(c4, PFF_COLOUR_PD(x + r0 - m.szm), s);
  s                = _mm512_fmadd_pd(c5, PFF_COLOUR_PD(x + r0 + m.szp), s);
  const __m512d os = _mm512_mul_pd(_mm512_set1_pd(omega), s), ev = _mm512_abs_pd(os);
  const __m512d nx = _mm512_fmadd_pd(os, PFF_COLOUR_PS(idiag + r0, fc), xc); /* idiag = 0: not relaxed */
#undef PFF_COLOUR_PD
#undef PFF_COLOUR_PS
  _mm512_storeu_pd(mx, _mm512_max_pd(_mm512_loadu_pd(mx), ev));
  _mm512_storeu_pd(x + r0, _mm512_mask_permutexvar_pd(X0, mk, back0, nx));
  _mm512_storeu_pd(x + r0 + 8, _mm512_mask_permutexvar_pd(X1, mk, back1, nx));
  if (R) {
    _mm512_storeu_pd(R, _mm512_mask_permutexvar_pd(_mm512_loadu_pd(R), mk, back0, ev));
    _mm512_storeu_pd(R + 8, _mm512_mask_permutexvar_pd(_mm512_loadu_pd(R + 8), mk, back1, ev));
  }
}
#endif

/* The same for the first and the last row of the rank's cells, whose ends must not read past x: the
   cells by the general path. */
static inline PetscReal RelaxRowEnds(const PffMGLevel *lv, const PffMGStencil *st, PetscInt base, PetscInt i0,
                                     PetscInt j, PetscInt k, PetscInt n, const PetscScalar *bb, PetscScalar *x,
                                     PetscReal omega, PetscReal *R, PetscInt r0)
{
  PetscReal rmax = 0;
  for (PetscInt i = i0; i < n; i += 2) {
    const PetscReal e = RelaxEnd(lv, st, base + i, i, j, k, n, bb[i], x, omega, R, r0);
    rmax              = rmax > e ? rmax : e;
  }
  return rmax;
}

/* Whether a visit of local block lb runs in float (PffMGStencilVisitBlock_Private): blocks of at least 4^3 cells
   without in-block side terms (own, a coarse level's cells under one coarse face above the block). */
PetscBool PffMGStencilVisitFloat_Private(const PffMGLevel *lv, PetscInt lb)
{
  return (PetscBool)(!lv->st->own[lb] && lv->n[lb] >= 4);
}

/* bs = b - (the side couplings of the cells of local block lb to other blocks), block-local, in float: as
   PffMGStencilBlockRhs_Private for a block without in-block side terms (b rounded once, then each side term added). */
static void BlockRhsFloat(const PffMGLevel *lv, PetscInt lb, const PetscScalar *b, const PetscScalar *x,
                          const PetscScalar *g, float *restrict bs)
{
  const PffMGStencil *st = lv->st;
  const PetscInt      r0 = lv->start[lb], nc = lv->n[lb] * lv->n[lb] * lv->n[lb];

  const PetscInt nr = lv->nrows, line = 64 / sizeof(float);

  /* the first sweep's coefficients (five float arrays) are requested while b streams in, a cache line at a time */
  for (PetscInt i0 = 0; i0 < nc; i0 += line) {
    __builtin_prefetch(st->cf + r0 + i0, 0, 2);
    __builtin_prefetch(st->cf + nr + r0 + i0, 0, 2);
    __builtin_prefetch(st->cf + 2 * nr + r0 + i0, 0, 2);
    __builtin_prefetch(st->adf + r0 + i0, 0, 2);
    __builtin_prefetch(st->idf + r0 + i0, 0, 2);
    for (PetscInt i = i0; i < PetscMin(i0 + line, nc); i++) bs[i] = (float)b[r0 + i];
  }
  SideCouplings(lv, lb, x, g, -1, PETSC_FALSE, bs, NULL);
}

/* One row group of SweepFloat: the candidate values nx and |omega s| ev of its w cells, the colour's only (mo: omega
   on the colour's lanes, 0 on the others); mx keeps the running maximum per lane. lo, hi, ym, yp weigh the faces to
   the cells around in x and y per lane, mzm, mzp those in z (0 at the block's sides, where the coupling is in bs);
   szm, szp are the z offsets (0 at the z sides, so that nothing outside the block and its pads is read). */
static inline __attribute__((always_inline)) void
RowFloat(PetscInt w, PetscInt n, const float *restrict cx, const float *restrict cy, const float *restrict cz,
         const float *restrict ad, const float *restrict id, const float *restrict bs, const float *restrict xr,
         const float *restrict lo, const float *restrict hi, const float *restrict ym, const float *restrict yp,
         const float *restrict mo, float mzm, float mzp, PetscInt szm, PetscInt szp, float *restrict nx,
         float *restrict ev, float *restrict mx)
{
  for (PetscInt i = 0; i < w; i++) {
    const float c0 = lo[i] * cx[i], c1 = hi[i] * cx[i + 1], c2 = ym[i] * cy[i], c3 = yp[i] * cy[i + n];
    const float c4 = mzm * cz[i], c5 = mzp * cz[i + szp];
    const float s = bs[i] - ad[i] * xr[i] + c0 * xr[i - 1] + c1 * xr[i + 1] + c2 * xr[i - n] + c3 * xr[i + n] +
                    c4 * xr[i - szm] + c5 * xr[i + szp];
    const float os = mo[i] * s;
    ev[i]          = os < 0 ? -os : os;
    nx[i]          = xr[i] + os * id[i]; /* id = 0: a zero row is not relaxed */
    mx[i]          = mx[i] > ev[i] ? mx[i] : ev[i];
  }
}

/* The order of 0 .. m-1 that takes the odd ones first: no two consecutive entries are neighbours, and entry m/2
   follows m/2 - 1 only where m = 2. */
static inline PetscInt OddFirst(PetscInt q, PetscInt m)
{
  return q < m / 2 ? 2 * q + 1 : 2 * (q - m / 2);
}

/* One red-black sweep of a block in float: xs holds the block's x (x fastest) with a pad of n before and after,
   bs its right-hand side with the side couplings folded in. The cells go in groups of G whole rows, G = 16 / n for
   n = 4 and 8 (a plane of 4^3 block, two rows of an 8^3 one) and 1 for n >= 16, so that a group is one 16-float
   vector. Each group computes all its cells from the values before the colour's update and adds the update to the
   cells of the colour only (the others add 0, so they keep their value bit for bit), as RelaxRow does. The group
   goes through a buffer and back with whole-vector stores: a masked store into x stalls the next loads of it (no
   store forwarding from masked stores). The faces to cells outside the block have weight 0 (their couplings are in
   bs), so a group reads the pads or its block's other cells there, never a value it uses. The cells of a colour
   read only the other colour's, so the order of the groups does not change the result: the odd groups (and
   planes) go first, so that consecutive groups are not neighbours (in plain order a group's loads of its -y
   neighbour wait for the store of the group just computed, a chain through the whole sweep at the latency of its
   arithmetic). Returns the largest |omega s| of the sweep; face (or NULL) receives its largest value on each of the
   block's six sides (-x, +x, -y, +y, -z, +z), kept as running maxima per lane (the other colour's lanes hold 0), so
   that adaptive relaxation needs no per-cell record. Inlined with n constant for 16, 8 and 4. */
static inline __attribute__((always_inline)) PetscReal SweepFloat(const PffMGStencil *st, PetscInt nr, PetscInt r0,
                                                                  const PetscInt n, const float *restrict bs, float *xs,
                                                                  float omega, PetscReal *face)
{
  const float *restrict cx = st->cf + r0, *restrict cy = st->cf + nr + r0, *restrict cz = st->cf + 2 * nr + r0;
  const float *restrict ad = st->adf + r0, *restrict id = st->idf + r0;
  const PetscInt G = n < 16 && 16 % n == 0 ? 16 / n : 1, w = G * n, ng = n / G, n2 = n * n;
  float          lo[PFF_GRID_BLOCK_SIZE_MAX], hi[PFF_GRID_BLOCK_SIZE_MAX], one[PFF_GRID_BLOCK_SIZE_MAX];
  float          ym0[PFF_GRID_BLOCK_SIZE_MAX], yp1[PFF_GRID_BLOCK_SIZE_MAX], mx[PFF_GRID_BLOCK_SIZE_MAX];
  float          mo[2][PFF_GRID_BLOCK_SIZE_MAX], fm[4][PFF_GRID_BLOCK_SIZE_MAX]; /* -y, +y, -z, +z */
  PetscReal      rmax = 0;

  for (PetscInt l = 0; l < w; l++) {
    const PetscInt i = l % n, j = l / n; /* the lane's cell in the group: row j of G */
    lo[l]    = i > 0;
    hi[l]    = i < n - 1;
    one[l]   = 1;
    ym0[l]   = j > 0; /* the -y weights of the first group, and the +y ones of the last */
    yp1[l]   = j < G - 1;
    mx[l]    = 0;
    mo[0][l] = ((i + j) & 1) == 0 ? omega : 0;
    mo[1][l] = ((i + j) & 1) == 1 ? omega : 0;
    for (PetscInt f = 0; f < 4; f++) fm[f][l] = 0;
  }
  for (PetscInt c = 0; c < 2; c++)
    for (PetscInt kk = 0; kk < n; kk++) {
      const PetscInt k = ng > 1 ? kk : OddFirst(kk, n); /* planes in order but for a group per plane */
      for (PetscInt gg = 0; gg < ng; gg++) {
        const PetscInt g = OddFirst(gg, ng), o = n * (G * g + n * k);
        const float *restrict m = mo[(G * g + k + c) & 1];
        float nx[PFF_GRID_BLOCK_SIZE_MAX], ev[PFF_GRID_BLOCK_SIZE_MAX];
        RowFloat(w, n, cx + o, cy + o, cz + o, ad + o, id + o, bs + o, xs + o, lo, hi, g > 0 ? one : ym0,
                 g < ng - 1 ? one : yp1, m, k > 0, k<n - 1, k> 0 ? n2 : 0, k < n - 1 ? n2 : 0, nx, ev, mx);
        /* one whole-vector copy: a loop here was peeled for the alignment of xs, and its narrow loads of nx right
           after nx's vector store could not be forwarded (a third of the sweep's time stalled there) */
        memcpy(xs + o, nx, (size_t)w * sizeof(float));
        if (!face) continue;
        if (g == 0)
          for (PetscInt l = 0; l < w; l++) fm[0][l] = fm[0][l] > ev[l] ? fm[0][l] : ev[l];
        if (g == ng - 1)
          for (PetscInt l = 0; l < w; l++) fm[1][l] = fm[1][l] > ev[l] ? fm[1][l] : ev[l];
        if (k == 0)
          for (PetscInt l = 0; l < w; l++) fm[2][l] = fm[2][l] > ev[l] ? fm[2][l] : ev[l];
        if (k == n - 1)
          for (PetscInt l = 0; l < w; l++) fm[3][l] = fm[3][l] > ev[l] ? fm[3][l] : ev[l];
      }
    }
  for (PetscInt l = 0; l < w; l++) rmax = PetscMax(rmax, (PetscReal)mx[l]);
  if (face) {
    for (PetscInt f = 0; f < 6; f++) face[f] = 0;
    for (PetscInt l = 0; l < w; l++) {
      const PetscInt i = l % n, j = l / n;
      if (i == 0) face[0] = PetscMax(face[0], (PetscReal)mx[l]); /* the x sides: every row's ends */
      if (i == n - 1) face[1] = PetscMax(face[1], (PetscReal)mx[l]);
      if (j == 0) face[2] = PetscMax(face[2], (PetscReal)fm[0][l]); /* the first group's first row */
      if (j == G - 1) face[3] = PetscMax(face[3], (PetscReal)fm[1][l]);
      face[4] = PetscMax(face[4], (PetscReal)fm[2][l]);
      face[5] = PetscMax(face[5], (PetscReal)fm[3][l]);
    }
  }
  return rmax;
}

static PetscReal SweepFloatN(const PffMGStencil *st, PetscInt nr, PetscInt r0, PetscInt n, const float *bs, float *xs,
                             float omega, PetscReal *face)
{
  switch (n) {
  case 16:
    return SweepFloat(st, nr, r0, 16, bs, xs, omega, face);
  case 8:
    return SweepFloat(st, nr, r0, 8, bs, xs, omega, face);
  case 4:
    return SweepFloat(st, nr, r0, 4, bs, xs, omega, face);
  default:
    return SweepFloat(st, nr, r0, n, bs, xs, omega, face);
  }
}

/* One visit of local block lb in float (PffMGStencilVisitFloat_Private): x and the block's right-hand side with its
   side couplings (BlockRhsFloat) go into float copies once, the block-local sweeps run on
   them (one, or in adaptive relaxation until the update falls by 1/3, at most maxSweeps), and x comes back once.
   The visit is the smoother's inner loop: in float a row of 16 cells is one vector and no lane permutes are
   needed, and the block's working set halves. The smoother is a preconditioner's, so the float rounding of x
   (relative 6e-8 per visit) is far below what it reduces per cycle; the outer FCG works in double. first receives
   the first sweep's largest |omega s|, the return value the last one's, face (or NULL) the last one's per block
   side, k the sweeps. */
PetscReal PffMGStencilVisitBlock_Private(const PffMGLevel *lv, PetscInt lb, const PetscScalar *b, PetscScalar *x,
                                         const PetscScalar *g, PetscReal omega, PetscReal *face, float *scratch,
                                         PetscInt maxSweeps, PetscBool adaptive, PetscReal *first, PetscInt *k)
{
  const PetscInt n = lv->n[lb], r0 = lv->start[lb], nc = n * n * n;
  float *restrict xs = scratch + n, *restrict bs = scratch + nc + 2 * n; /* pads of n floats around xs */
  PetscReal r = 0;

  BlockRhsFloat(lv, lb, b, x, g, bs);
  for (PetscInt i = 0; i < n; i++) xs[i - n] = xs[nc + i] = 0;
  for (PetscInt i = 0; i < nc; i++) xs[i] = (float)x[r0 + i];
  for (*k = 0; *k < maxSweeps;) {
    r = SweepFloatN(lv->st, lv->nrows, r0, n, bs, xs, (float)omega, face);
    if ((*k)++ == 0) *first = r;
    if (!adaptive || !(*first > 0) || r < *first / 3) break;
  }
  for (PetscInt i = 0; i < nc; i++) x[r0 + i] = xs[i];
  return r;
}

/* One in-place red-black sweep over the cells of local block lb (cells (i + j + k) even, then odd),
   with bb from PffMGStencilBlockRhs_Private. R (or NULL) receives |omega (b - A x)| per cell of the
   block; FaceMax reads the cells of its sides. */
PetscReal PffMGStencilRelaxBlock_Private(const PffMGLevel *lv, PetscInt lb, const PetscScalar *bb, PetscBool own,
                                         PetscScalar *x, PetscReal omega, PetscReal *R)
{
  const PffMGStencil *st = lv->st;
  const PetscInt      n = lv->n[lb], r0 = lv->start[lb], nr = lv->nrows, nc = n * n * n;
  PffMGRowEnds        ends;
  PetscScalar         tb[PFF_GRID_BLOCK_SIZE_MAX];
  PetscReal           mx[PFF_GRID_BLOCK_SIZE_MAX], rmax = 0;

  RowEnds(n, &ends);
  for (PetscInt i = 0; i < n; i++) mx[i] = 0;
  for (PetscInt c = 0; c < 2; c++)
    for (PetscInt k = 0; k < n; k++)
      for (PetscInt j = 0; j < n; j++) {
        const PetscInt     base = r0 + n * (j + n * k), i0 = (j + k + c) & 1;
        const PetscScalar *rb = bb + (base - r0);
        if (own) { /* in-block side terms sit on the block's upper sides only */
          const PetscInt from = (j == n - 1 || k == n - 1) ? i0 : n - 1 - ((n - 1 - i0) & 1);
          OwnSums(lv, r0, nc, base, from, n, rb, x, tb);
          rb = tb;
        }
        if (base == 0 || base + n == nr || n < 3) {
          const PetscReal e = RelaxRowEnds(lv, st, base, i0, j, k, n, rb, x, omega, R, r0);
          rmax              = rmax > e ? rmax : e;
        } else {
#if defined(PFF_MG_AVX512)
          if (n == 16) {
            RelaxRow16(st, nr, rb, st->idf, x, base, i0, RowMask(j, k, n), omega, R ? R + (base - r0) : NULL, mx);
            continue;
          }
#endif
          RelaxRow(st, nr, rb, st->idf, x, base, i0, n, RowMask(j, k, n), &ends, omega, R ? R + (base - r0) : NULL, mx);
        }
      }
  for (PetscInt i = 0; i < n; i++) rmax = rmax > mx[i] ? rmax : mx[i];
  return rmax;
}

/* yb = (A x) over the cells of local block lb, block-local (yb[0] is row start[lb]); g: the ghost values. */
static inline void BlockProduct(const PffMGLevel *lv, PetscInt lb, const PetscScalar *x, const PetscScalar *g,
                                PetscScalar *restrict yb)
{
  const PffMGStencil *st = lv->st;
  const PetscInt      nr = lv->nrows, n = lv->n[lb], r0 = lv->start[lb];
  const PffMGReal *restrict cx = st->cf, *restrict cy = cx + nr, *restrict cz = cy + nr;
  const PetscReal *restrict ds = st->ds;
  PffMGRowEnds e;

  RowEnds(n, &e);
  /* the side couplings first, face by face to the neighbours of the same size and entry by entry to the others;
     the rows add their in-block part */
  for (PetscInt i = 0; i < n * n * n; i++) yb[i] = 0;
  SideCouplings(lv, lb, x, g, 1, PETSC_TRUE, NULL, yb);
  for (PetscInt k = 0; k < n; k++)
    for (PetscInt j = 0; j < n; j++) {
      const PetscInt     base  = r0 + n * (j + n * k);
      const PffMGRowMask m     = RowMask(j, k, n);
      PetscScalar *restrict yr = yb + (base - r0);
      if (base == 0 || base + n == nr || n < 3) {
        for (PetscInt i = 0; i < n; i++) yr[i] += RowInBlock(st, nr, base + i, i, j, k, n, x);
        continue;
      }
      for (PetscInt i = 0; i < n; i++) {
        const PetscInt    r  = base + i;
        const PetscScalar xc = x[r];
        const PetscReal c0 = e.lo[i] * cx[r], c1 = e.hi[i] * cx[r + 1], c2 = m.mym * cy[r], c3 = m.myp * cy[r + m.syp],
                        c4 = m.mzm * cz[r], c5 = m.mzp * cz[r + m.szp];
        yr[i] += c0 * (xc - x[r - 1]) + c1 * (xc - x[r + 1]) + c2 * (xc - x[r - m.sym]) + c3 * (xc - x[r + m.syp]) +
                 c4 * (xc - x[r - m.szm]) + c5 * (xc - x[r + m.szp]) + ds[r] * xc;
      }
    }
}

/* The ghost values of level L's x: started, then finished (ga: their array, or NULL on one rank). Between the two,
   the callers work on the blocks without a neighbour on another rank (lv->remote). */
PetscErrorCode PffMGGhostsBegin_Private(PffMGLevel *lv, Vec x)
{
  PetscFunctionBeginUser;
  if (lv->scatter) PetscCall(VecScatterBegin(lv->scatter, x, lv->ghost, INSERT_VALUES, SCATTER_FORWARD));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffMGGhostsEnd_Private(PffMGLevel *lv, Vec x, const PetscScalar **ga)
{
  PetscFunctionBeginUser;
  *ga = NULL;
  if (lv->scatter) {
    PetscCall(VecScatterEnd(lv->scatter, x, lv->ghost, INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecGetArrayRead(lv->ghost, ga));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* y = A x on a matrix-free level. */
static PetscErrorCode StencilMult(Mat A, Vec xv, Vec yv)
{
  PffMGLevel        *lv;
  const PetscScalar *x, *g = NULL;
  PetscScalar       *y;

  PetscFunctionBeginUser;
  PetscCall(MatShellGetContext(A, &lv));
  PetscCall(PffMGGhostsBegin_Private(lv, xv));
  PetscCall(VecGetArrayRead(xv, &x));
  PetscCall(VecGetArrayWrite(yv, &y));
  for (PetscInt pass = 0; pass < 2; pass++) { /* the blocks that need no ghost while the ghosts come */
    if (pass == 1) PetscCall(PffMGGhostsEnd_Private(lv, xv, &g));
#pragma omp parallel for schedule(static) if (lv->nblk >= 8 && lv->omp)
    for (PetscInt lb = 0; lb < lv->nblk; lb++)
      if (lv->remote[lb] == pass) BlockProduct(lv, lb, x, g, y + lv->start[lb]);
  }
  PetscCall(VecRestoreArrayWrite(yv, &y));
  PetscCall(VecRestoreArrayRead(xv, &x));
  if (g) PetscCall(VecRestoreArrayRead(lv->ghost, &g));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* cb = P^T (b - A x) from matrix-free level L to block level L+1 in one pass: the residual of a block
   stays in the thread's block buffer, and the piecewise-constant restriction of each block lands in
   that block's own coarse cells, so the blocks run in parallel without a residual vector, P, or
   write conflicts. */
PetscErrorCode PffMGStencilResidualRestrict_Private(PffMG *mg, PetscInt L, Vec bv, Vec xv, Vec cbv)
{
  PffMGLevel        *lv = &mg->lev[L];
  const PffMGLevel  *c  = &mg->lev[L + 1];
  const PetscScalar *x, *b, *g = NULL;
  PetscScalar       *cb;

  PetscFunctionBeginUser;
  PetscCall(PffMGGhostsBegin_Private(lv, xv));
  PetscCall(VecGetArrayRead(xv, &x));
  PetscCall(VecGetArrayRead(bv, &b));
  PetscCall(VecGetArrayWrite(cbv, &cb));
  for (PetscInt pass = 0; pass < 2; pass++) { /* the blocks that need no ghost while the ghosts come */
    if (pass == 1) PetscCall(PffMGGhostsEnd_Private(lv, xv, &g));
#pragma omp parallel for schedule(static) if (lv->nblk >= 8 && lv->omp)
    for (PetscInt lb = 0; lb < lv->nblk; lb++) {
      if (lv->remote[lb] != pass) continue;
      PetscScalar *restrict yb = mg->BB + mg->Rsize * (size_t)omp_get_thread_num();
      const PetscInt nf = lv->n[lb], nc = c->n[lb], r0 = lv->start[lb];
      PetscScalar *restrict cr = cb + c->start[lb];
      const PetscInt s         = nf > nc;
      BlockProduct(lv, lb, x, g, yb);
      for (PetscInt i = 0; i < nc * nc * nc; i++) cr[i] = 0;
      /* the pairs of a fine row summed first: one add per coarse cell and fine row, so that the adds into a coarse
         cell do not follow each other through its store */
      for (PetscInt q = 0; q < nf * nf; q++) {
        const PetscInt o               = PffMGCoarseRow_Private(q, nf, nc, s);
        const PetscScalar *restrict br = b + r0 + q * nf, *restrict yr = yb + q * nf;
        if (s)
          for (PetscInt u = 0; u < nc; u++) cr[o + u] += (br[2 * u] - yr[2 * u]) + (br[2 * u + 1] - yr[2 * u + 1]);
        else
          for (PetscInt u = 0; u < nc; u++) cr[o + u] += br[u] - yr[u];
      }
    }
  }
  PetscCall(VecRestoreArrayWrite(cbv, &cb));
  PetscCall(VecRestoreArrayRead(bv, &b));
  PetscCall(VecRestoreArrayRead(xv, &x));
  if (g) PetscCall(VecRestoreArrayRead(lv->ghost, &g));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* x += P cx from block level L+1 to matrix-free level L (piecewise constant, block by block). */
PetscErrorCode PffMGStencilProlongAdd_Private(PffMG *mg, PetscInt L, Vec cxv, Vec xv)
{
  const PffMGLevel  *lv = &mg->lev[L], *c = &mg->lev[L + 1];
  const PetscScalar *cx;
  PetscScalar       *x;

  PetscFunctionBeginUser;
  PetscCall(VecGetArrayRead(cxv, &cx));
  PetscCall(VecGetArray(xv, &x));
#pragma omp parallel for schedule(static) if (lv->nblk >= 8 && lv->omp)
  for (PetscInt lb = 0; lb < lv->nblk; lb++) {
    const PetscInt nf = lv->n[lb], nc = c->n[lb], s = nf > nc;
    PetscScalar *restrict xr       = x + lv->start[lb];
    const PetscScalar *restrict cr = cx + c->start[lb];
    for (PetscInt q = 0; q < nf * nf; q++) {
      const PetscInt o = PffMGCoarseRow_Private(q, nf, nc, s);
      for (PetscInt i = 0; i < nf; i++) xr[q * nf + i] += cr[o + (i >> s)];
    }
  }
  /* P leaves the cells inside solids alone (their identity rows are not part of the coarse operator, see
     PffMGStencilUpdate_Private), so x stays 0 there and so does their residual */
  for (PetscInt e = 0; e < lv->st->nclosed; e++) x[lv->st->closed[e]] = 0;
  PetscCall(VecRestoreArray(xv, &x));
  PetscCall(VecRestoreArrayRead(cxv, &cx));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode StencilGetDiagonal(Mat A, Vec dv)
{
  PffMGLevel  *lv;
  PetscScalar *d;

  PetscFunctionBeginUser;
  PetscCall(MatShellGetContext(A, &lv));
  PetscCall(VecGetArrayWrite(dv, &d));
  for (PetscInt lb = 0; lb < lv->nblk; lb++) {
    const PetscInt n = lv->n[lb];
    for (PetscInt k = 0, r = lv->start[lb]; k < n; k++)
      for (PetscInt j = 0; j < n; j++)
        for (PetscInt i = 0; i < n; i++, r++) {
          const PetscReal a = Diagonal(lv->st, lv->nrows, r, i, j, k, n);
          d[r]              = a > 0 ? a : 0.0;
        }
  }
  PetscCall(VecRestoreArrayWrite(dv, &d));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The MATSHELL of a matrix-free level (its operator for the residual and the K-cycle). */
PetscErrorCode PffMGStencilCreateShell_Private(PffMG *mg, PetscInt L)
{
  PffMGLevel *lv = &mg->lev[L];

  PetscFunctionBeginUser;
  PetscCall(MatCreateShell(mg->comm, lv->nrows, lv->nrows, PETSC_DETERMINE, PETSC_DETERMINE, lv, &lv->A));
  PetscCall(MatShellSetOperation(lv->A, MATOP_MULT, (void (*)(void))StencilMult));
  PetscCall(MatShellSetOperation(lv->A, MATOP_MULT_TRANSPOSE, (void (*)(void))StencilMult));
  PetscCall(MatShellSetOperation(lv->A, MATOP_GET_DIAGONAL, (void (*)(void))StencilGetDiagonal));
  PetscCall(MatSetOption(lv->A, MAT_SYMMETRIC, PETSC_TRUE));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The level as an AIJ matrix: created on the first call (*A NULL), refilled in place after. For the
   last block level (the coarse levels below it are AIJ Galerkin products) and for inspection. */
PetscErrorCode PffMGStencilAssemble_Private(PffMG *mg, PetscInt L, Mat *A)
{
  PffMGLevel         *lv = &mg->lev[L];
  const PffMGStencil *st = lv->st;
  const PetscInt      nr = lv->nrows;

  PetscFunctionBeginUser;
  if (*A == NULL) {
    PetscInt *dnz, *onz;
    PetscCall(PetscCalloc2(nr, &dnz, nr, &onz));
    for (PetscInt r = 0; r < nr; r++) {
      dnz[r] = 7;
      for (PetscInt e = st->rowptr[r]; e < st->rowptr[r + 1]; e++) {
        if (st->col[e] < nr)
          dnz[r]++;
        else
          onz[r]++;
      }
      dnz[r] = PetscMin(dnz[r], nr);
    }
    PetscCall(MatCreateAIJ(mg->comm, nr, nr, PETSC_DETERMINE, PETSC_DETERMINE, 0, dnz, 0, onz, A));
    PetscCall(PetscFree2(dnz, onz));
  } else
    PetscCall(MatZeroEntries(*A));
  for (PetscInt lb = 0; lb < mg->nlocal; lb++) {
    const PetscInt n = lv->n[lb], o = lv->start[lb], s[3] = {1, n, n * n};
    for (PetscInt k = 0; k < n; k++)
      for (PetscInt j = 0; j < n; j++)
        for (PetscInt i = 0; i < n; i++) {
          const PetscInt p[3] = {i, j, k}, r = o + i + n * (j + n * k), grow = lv->rstart + r;
          PetscCall(MatSetValue(*A, grow, grow, Diagonal(st, nr, r, i, j, k, n), ADD_VALUES));
          for (PetscInt d = 0; d < 3; d++) {
            if (p[d] > 0) PetscCall(MatSetValue(*A, grow, grow - s[d], -st->cf[d * nr + r], ADD_VALUES));
            if (p[d] < n - 1) PetscCall(MatSetValue(*A, grow, grow + s[d], -st->cf[d * nr + r + s[d]], ADD_VALUES));
          }
          for (PetscInt e = st->rowptr[r]; e < st->rowptr[r + 1]; e++) {
            const PetscInt c = st->col[e], gc = c < nr ? lv->rstart + c : st->ghostRow[c - nr];
            PetscCall(MatSetValue(*A, grow, gc, st->val[e], ADD_VALUES));
          }
        }
  }
  PetscCall(MatAssemblyBegin(*A, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*A, MAT_FINAL_ASSEMBLY));
  PetscFunctionReturn(PETSC_SUCCESS);
}
