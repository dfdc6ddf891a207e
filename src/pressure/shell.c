/* The matrix-free pressure operator (PF-FLIP Eq. 8-10, stage "Pressure"): a MATSHELL that applies
     A = G^T diag(M_f beta_f open_f) G = sum_f c_f g_f g_f^T,   g_f = e_upper - sum_k w_k e_lower_k,
   with the stencil weight c_f = M_f beta_f open_f / d_f^2 and w_k = 1
   (one lower cell) or 1/4 (coarse above fine, the 4 fine cells; faces.c). Face by face,
     flux = c_f (x_upper - sum_k w_k x_lower_k),   y_upper += flux,   y_lower_k -= w_k flux,
   plus the diagonal-only terms of the assembly (operator.c): the Dirichlet wall terms 2 h beta and the
   unit diagonal of cells with every face closed. So the shell is the assembled A up to rounding.

   The cells are walked block by block in the block Morton order of the numbering. Faces inside a block
   (the bulk: all but 3 n^2 of the 3 n^3 faces of a block of n^3 cells) need no index arrays, their
   lower cell is the cell minus the raster stride 1, n or n^2, and their coefficients sit in one
   contiguous array per axis; so a product reads 3 coefficients per cell against the 7 values and 7
   column indices per row of the AIJ matrix. The faces on block sides (same level, coarser, finer) go
   through an explicit list of upper and lower cells, and take their coefficient from the same arrays; the product
   takes the sides between two owned blocks of the same size a plane at a time instead (PffShellPlanes).

   The shell owns the coefficient arrays c_f of every owned face (cf[d * ncells + c], the lower d-face
   of cell c, 0 when closed): the pressure module writes them once per step (operator.c), pffmg reads
   its finest level from them, and nothing else holds face coefficients. The same face lists give the
   projection its divergence G^T M u and its velocity update u -= dt beta G p without the gradient as a
   matrix (M_f / d_f = h^2 of the upper cell, and beta_f / d_f = c_f / h^2 on an open face).

   Communication: a face's upper cell is always owned, its lower cells may belong to another rank.
   Their x values come through a VecScatter into a ghost Vec of the distinct remote lower cells, and
   the contributions to them go back with the reverse scatter (ADD_VALUES); both are built once per
   grid topology. The product is split-phase: the gather is started, the faces whose lower cells are
   all owned are done, the gather is finished, then the faces touching a ghost.

   PffPressureShellUpdate_Private (called from SetCoefficients) rebuilds the diagonal from them. */
#include "pressureimpl.h"

/* The two face lists: [PFF_SHELL_LOCAL] every lower cell owned, [PFF_SHELL_GHOST] at least one not. */
enum { PFF_SHELL_LOCAL, PFF_SHELL_GHOST, PFF_SHELL_NLISTS };

typedef struct {
  PetscInt   ncells;                  /* owned cells */
  PetscInt   nblocks, *bstart;        /* owned blocks: first local cell, [nblocks + 1] */
  PetscInt  *bn;                      /* cells per block edge */
  PetscReal *cf;                      /* [3 ncells] c_f of the lower d-face of cell c at d * ncells + c */
  PetscInt   nface[PFF_SHELL_NLISTS]; /* faces on block sides */
  /* per list, over its faces i: the face's index into cf (d * ncells + upper cell), the local upper
     cell, lower cells lo[off[i] .. off[i+1]-1] (1 or 4 of them, weight 1/count) as local cell numbers,
     ghosts as ncells + ghost index */
  PetscInt *row[PFF_SHELL_NLISTS], *up[PFF_SHELL_NLISTS], *off[PFF_SHELL_NLISTS], *lo[PFF_SHELL_NLISTS];
  PetscInt *pnb; /* [3 nblocks] the owned block of the same size below each block's lower d-side whose n^2 faces
                    the product takes a plane at a time (ShellPlanes), or -1 */
  PetscInt   nmult, *mult;     /* the other faces of the local list, the ones the product takes face by face */
  PetscInt   ndiag, *diagCell; /* cells with a diagonal-only term: Dirichlet walls, or the unit */
  PetscReal *diagVal;          /* diagonal of a cell with every face closed */
  PetscInt   nghost;
  Vec        xg, yg;  /* ghost values of x, contributions to y (sequential) */
  VecScatter scatter; /* owned x -> xg; reversed, yg -> y */
  Vec        diag;
  PetscBool  updated;
} PffShell;

static PetscErrorCode PffShellDestroy(void *ctx)
{
  PffShell *s = (PffShell *)ctx;

  PetscFunctionBeginUser;
  PetscCall(PetscFree(s->bstart));
  PetscCall(PetscFree(s->bn));
  PetscCall(PetscFree(s->cf));
  for (PetscInt l = 0; l < PFF_SHELL_NLISTS; l++) {
    PetscCall(PetscFree(s->row[l]));
    PetscCall(PetscFree(s->up[l]));
    PetscCall(PetscFree(s->off[l]));
    PetscCall(PetscFree(s->lo[l]));
  }
  PetscCall(PetscFree(s->pnb));
  PetscCall(PetscFree(s->mult));
  PetscCall(PetscFree(s->diagCell));
  PetscCall(PetscFree(s->diagVal));
  PetscCall(VecDestroy(&s->xg));
  PetscCall(VecDestroy(&s->yg));
  PetscCall(VecDestroy(&s->diag));
  PetscCall(VecScatterDestroy(&s->scatter));
  PetscCall(PetscFree(s));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Weights of a row's x-faces inside the block: lo (the cell's own lower face) 0 at i = 0, hi (the next cell's) 0 at
   i = n - 1, so that a row runs one loop. */
static inline void PffShellRowEnds(PetscInt n, PetscReal *lo, PetscReal *hi)
{
  for (PetscInt i = 0; i < n; i++) {
    lo[i] = i > 0;
    hi[i] = i < n - 1;
  }
}

/* y = the sum over the faces inside the blocks, cell by cell: each cell gathers c_f (x_c - x_nb) from its up to six
   in-block faces (every interior face is computed twice, once from each side), so that the rows vectorise. The face
   by face form (flux added to the upper cell, subtracted from the lower one) chained every cell of a row to the store
   of the one before and ran at the latency of that chain (the product 15 % faster gathered, test_pressure_shell
   -bench in docs/benchmarks.md). A face to a cell outside the
   block takes offset 0 in y and z (x_c - x_c = 0) and weight 0 in x; the first and last rows of the rank's cells,
   whose ends must not read past x, take the branching path. */
static inline void PffShellInterior(const PffShell *s, const PetscScalar *restrict x, PetscScalar *restrict y)
{
  const PetscReal *restrict cx = s->cf, *restrict cy = s->cf + s->ncells, *restrict cz = s->cf + 2 * s->ncells;
  PetscReal lo[PFF_GRID_BLOCK_SIZE_MAX], hi[PFF_GRID_BLOCK_SIZE_MAX];

  for (PetscInt b = 0; b < s->nblocks; b++) {
    const PetscInt n = s->bn[b], n2 = n * n;
    PffShellRowEnds(n, lo, hi);
    for (PetscInt k = 0; k < n; k++)
      for (PetscInt j = 0; j < n; j++) {
        const PetscInt row = s->bstart[b] + n * (j + n * k);
        const PetscInt sym = j > 0 ? n : 0, syp = j < n - 1 ? n : 0, szm = k > 0 ? n2 : 0, szp = k < n - 1 ? n2 : 0;
        const PetscScalar *restrict xr = x + row;
        PetscScalar *restrict yr       = y + row;
        if (row == 0 || row + n == s->ncells) {
          for (PetscInt i = 0; i < n; i++) {
            const PetscInt c = row + i;
            yr[i] = cy[c] * (x[c] - x[c - sym]) + cy[c + syp] * (x[c] - x[c + syp]) + cz[c] * (x[c] - x[c - szm]) +
                    cz[c + szp] * (x[c] - x[c + szp]);
            if (i > 0) yr[i] += cx[c] * (x[c] - x[c - 1]);
            if (i < n - 1) yr[i] += cx[c + 1] * (x[c] - x[c + 1]);
          }
          continue;
        }
        for (PetscInt i = 0; i < n; i++) {
          const PetscInt    c  = row + i;
          const PetscScalar xc = xr[i];
          yr[i] = lo[i] * cx[c] * (xc - xr[i - 1]) + hi[i] * cx[c + 1] * (xc - xr[i + 1]) + cy[c] * (xc - xr[i - sym]) +
                  cy[c + syp] * (xc - xr[i + syp]) + cz[c] * (xc - xr[i - szm]) + cz[c + szp] * (xc - xr[i + szp]);
        }
      }
  }
}

/* Whether the lower side d of block b goes a plane at a time (s->pnb); then its faces' upper cells are up + q and
   their lower cells lo + q, q = si u + so v for u, v in [0, n). */
static inline PetscBool PffShellPlane(const PffShell *s, PetscInt b, PetscInt d, PetscInt *up, PetscInt *lo,
                                      PetscInt *si, PetscInt *so)
{
  const PetscInt nb = s->pnb[3 * b + d], n = s->bn[b], stride[3] = {1, n, n * n};

  if (nb < 0) return PETSC_FALSE;
  *up = s->bstart[b];
  *lo = s->bstart[nb] + (n - 1) * stride[d];
  *si = d == 0 ? n : 1;
  *so = d == 2 ? n : n * n;
  return PETSC_TRUE;
}

/* y += A x for the faces between each block and the owned block of its size below a lower side (s->pnb), a plane at a
   time: the flux c (x_upper - x_lower) of n^2 faces in one strided loop, instead of one list entry (an index, a
   coefficient and two scattered cells) per face. */
static inline void PffShellPlanes(const PffShell *s, const PetscScalar *restrict x, PetscScalar *y)
{
  for (PetscInt b = 0; b < s->nblocks; b++)
    for (PetscInt d = 0; d < 3; d++) {
      PetscInt up, lo, si, so;
      if (!PffShellPlane(s, b, d, &up, &lo, &si, &so)) continue;
      const PetscInt n            = s->bn[b];
      const PetscReal *restrict c = s->cf + d * s->ncells + up;
      PetscScalar *restrict yu = y + up, *restrict yl = y + lo; /* two blocks: disjoint */
      for (PetscInt v = 0; v < n; v++)
        for (PetscInt u = 0; u < n; u++) {
          const PetscInt    q    = si * u + so * v;
          const PetscScalar flux = c[q] * (x[up + q] - x[lo + q]);
          yu[q] += flux;
          yl[q] -= flux;
        }
    }
}

/* y += A_list x for the faces of one list (of the local one, those not in a plane); xg, yg may be NULL for the local
   list. */
static inline void PffShellFaces(const PffShell *s, PetscInt l, const PetscScalar *x, const PetscScalar *xg,
                                 PetscScalar *y, PetscScalar *yg)
{
  const PetscInt  *up = s->up[l], *off = s->off[l], *lo = s->lo[l], *row = s->row[l], nc = s->ncells;
  const PetscReal *cf = s->cf;

  if (l == PFF_SHELL_LOCAL) {
    for (PetscInt q = 0; q < s->nmult; q++) {
      const PetscInt  i  = s->mult[q];
      const PetscInt  k0 = off[i], k1 = off[i + 1];
      const PetscReal w = k1 - k0 == 1 ? 1.0 : 0.25, c = cf[row[i]];
      PetscScalar     xl = 0;
      if (c == 0) continue; /* closed by the phase field or a solid */
      for (PetscInt k = k0; k < k1; k++) xl += x[lo[k]];
      const PetscScalar flux = c * (x[up[i]] - w * xl), wf = w * flux;
      y[up[i]] += flux;
      for (PetscInt k = k0; k < k1; k++) y[lo[k]] -= wf;
    }
    return;
  }
  for (PetscInt i = 0; i < s->nface[l]; i++) {
    const PetscInt  k0 = off[i], k1 = off[i + 1];
    const PetscReal w = k1 - k0 == 1 ? 1.0 : 0.25, c = cf[row[i]];
    PetscScalar     xl = 0;
    if (c == 0) continue;
    for (PetscInt k = k0; k < k1; k++) xl += lo[k] < nc ? x[lo[k]] : xg[lo[k] - nc];
    const PetscScalar flux = c * (x[up[i]] - w * xl), wf = w * flux;
    y[up[i]] += flux;
    for (PetscInt k = k0; k < k1; k++) {
      if (lo[k] < nc)
        y[lo[k]] -= wf;
      else
        yg[lo[k] - nc] -= wf;
    }
  }
}

static PetscErrorCode MatMult_PffShell(Mat S, Vec x, Vec y)
{
  PffShell          *s;
  const PetscScalar *xa, *xg;
  PetscScalar       *ya, *yg;

  PetscFunctionBeginUser;
  PetscCall(MatShellGetContext(S, &s));
  PetscCheck(s->updated, PetscObjectComm((PetscObject)S), PETSC_ERR_ORDER,
             "pressure shell: no coefficients yet (PffPressureSetCoefficients)");
  PetscCall(VecScatterBegin(s->scatter, x, s->xg, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecGetArrayRead(x, &xa));
  PetscCall(VecGetArrayWrite(y, &ya));
  PffShellInterior(s, xa, ya); /* these four overlap the gather */
  PffShellPlanes(s, xa, ya);
  for (PetscInt q = 0; q < s->ndiag; q++) ya[s->diagCell[q]] += s->diagVal[q] * xa[s->diagCell[q]];
  PffShellFaces(s, PFF_SHELL_LOCAL, xa, NULL, ya, NULL);
  PetscCall(VecScatterEnd(s->scatter, x, s->xg, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecGetArrayRead(s->xg, &xg));
  PetscCall(VecGetArrayWrite(s->yg, &yg));
  PetscCall(PetscArrayzero(yg, s->nghost));
  PffShellFaces(s, PFF_SHELL_GHOST, xa, xg, ya, yg);
  PetscCall(VecRestoreArrayWrite(s->yg, &yg));
  PetscCall(VecRestoreArrayRead(s->xg, &xg));
  PetscCall(VecRestoreArrayWrite(y, &ya));
  PetscCall(VecRestoreArrayRead(x, &xa));
  PetscCall(VecScatterBegin(s->scatter, s->yg, y, ADD_VALUES, SCATTER_REVERSE));
  PetscCall(VecScatterEnd(s->scatter, s->yg, y, ADD_VALUES, SCATTER_REVERSE));
  PetscCall(PetscLogFlops(4.0 * 3 * s->ncells));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode MatGetDiagonal_PffShell(Mat S, Vec d)
{
  PffShell *s;

  PetscFunctionBeginUser;
  PetscCall(MatShellGetContext(S, &s));
  PetscCheck(s->updated, PetscObjectComm((PetscObject)S), PETSC_ERR_ORDER,
             "pressure shell: no coefficients yet (PffPressureSetCoefficients)");
  PetscCall(VecCopy(s->diag, d));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The diagonal of the face terms alone, without the Dirichlet terms and units of the diagonal-only list. */
PetscErrorCode PffPressureShellFaceDiagonal_Private(Mat S, Vec d)
{
  PffShell    *s;
  PetscScalar *a;

  PetscFunctionBeginUser;
  PetscCall(MatShellGetContext(S, &s));
  PetscCall(VecCopy(s->diag, d));
  PetscCall(VecGetArray(d, &a));
  for (PetscInt q = 0; q < s->ndiag; q++) a[s->diagCell[q]] -= s->diagVal[q];
  PetscCall(VecRestoreArray(d, &a));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode MatView_PffShell(Mat S, PetscViewer viewer)
{
  PffShell *s;
  PetscBool isascii;

  PetscFunctionBeginUser;
  PetscCall(MatShellGetContext(S, &s));
  PetscCall(PetscObjectTypeCompare((PetscObject)viewer, PETSCVIEWERASCII, &isascii));
  if (isascii) {
    PetscInt64 n[3] = {s->nface[PFF_SHELL_LOCAL], s->nface[PFF_SHELL_GHOST], s->nghost};
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, n, 3, MPIU_INT64, MPI_SUM, PetscObjectComm((PetscObject)S)));
    PetscCall(PetscViewerASCIIPrintf(viewer,
                                     "pressure operator, matrix-free: block-side faces %" PetscInt64_FMT
                                     " with owned lower cells, %" PetscInt64_FMT " with ghosts; %" PetscInt64_FMT
                                     " ghost cells\n",
                                     n[0], n[1], n[2]));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Local number of global cell g: owned cells directly, others through the sorted ghost list. */
static PetscErrorCode PffShellLocalCell(PffPressure ps, const PetscInt *ghosts, PetscInt nghost, PetscInt g,
                                        PetscInt *loc)
{
  PetscFunctionBeginUser;
  if (g >= ps->rstart && g < ps->rstart + ps->ncells)
    *loc = g - ps->rstart;
  else {
    PetscInt q;
    PetscCall(PetscFindInt(g, nghost, ghosts, &q));
    PetscAssert(q >= 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "pressure shell: cell %" PetscInt_FMT " not a ghost", g);
    *loc = ps->ncells + q;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The block of local cell c, searched from b on (the lists run in cell order). */
static inline PetscInt PffShellBlockOf(const PffShell *s, PetscInt c, PetscInt b)
{
  while (c >= s->bstart[b + 1]) b++;
  return b;
}

/* The lower side d of block b goes a plane at a time (s->pnb) when every one of its n^2 faces is in the local list
   with one lower cell, in one owned block nb != b of the same size, across from it (the same cell with coordinate d
   at n - 1); s->mult lists the other faces of the local list. */
static PetscErrorCode PffShellFindPlanes(PffShell *s)
{
  const PetscInt l = PFF_SHELL_LOCAL, *up = s->up[l], *off = s->off[l], *lo = s->lo[l];
  PetscInt      *count, *side;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(3 * s->nblocks, &s->pnb));
  PetscCall(PetscCalloc1(3 * s->nblocks, &count));
  PetscCall(PetscMalloc1(s->nface[l], &side));
  for (PetscInt q = 0; q < 3 * s->nblocks; q++) s->pnb[q] = -1;
  for (PetscInt i = 0, b = 0; i < s->nface[l]; i++) {
    const PetscInt d = s->row[l][i] / s->ncells, n = s->bn[b = PffShellBlockOf(s, up[i], b)];
    const PetscInt stride[3] = {1, n, n * n};
    PetscInt       nb        = -1;
    side[i]                  = 3 * b + d;
    if (off[i + 1] - off[i] == 1 && lo[off[i]] < s->ncells) { /* one owned lower cell */
      PetscInt k;
      PetscCall(PetscFindInt(lo[off[i]], s->nblocks + 1, s->bstart, &k));
      nb = k >= 0 ? k : -(k + 1) - 1; /* the block whose start is the last one at or below the cell */
      if (nb == b || s->bn[nb] != n || lo[off[i]] - s->bstart[nb] != up[i] - s->bstart[b] + (n - 1) * stride[d])
        nb = -1;
    }
    if (count[3 * b + d] == 0) s->pnb[3 * b + d] = nb;
    if (nb < 0 || nb != s->pnb[3 * b + d]) s->pnb[3 * b + d] = -2; /* not one neighbour across the whole side */
    count[3 * b + d]++;
  }
  for (PetscInt b = 0; b < s->nblocks; b++)
    for (PetscInt d = 0; d < 3; d++)
      if (count[3 * b + d] != s->bn[b] * s->bn[b] || s->pnb[3 * b + d] < 0) s->pnb[3 * b + d] = -1;
  s->nmult = 0;
  for (PetscInt i = 0; i < s->nface[l]; i++) s->nmult += s->pnb[side[i]] < 0;
  PetscCall(PetscMalloc1(s->nmult, &s->mult));
  s->nmult = 0;
  for (PetscInt i = 0; i < s->nface[l]; i++)
    if (s->pnb[side[i]] < 0) s->mult[s->nmult++] = i;
  PetscCall(PetscFree(count));
  PetscCall(PetscFree(side));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureShellCreate_Private(PffPressure ps, Mat *S)
{
  const PetscInt nrows = 3 * ps->ncells, rend = ps->rstart + ps->ncells;
  PffShell      *s;
  PetscInt      *ghosts, nremote = 0, count[PFF_SHELL_NLISTS] = {0}, nlo[PFF_SHELL_NLISTS] = {0};
  IS             is;

  PetscFunctionBeginUser;
  PetscCall(PetscNew(&s));
  s->ncells  = ps->ncells;
  s->nblocks = ps->nlocal;
  PetscCall(PetscMalloc1(ps->nlocal + 1, &s->bstart));
  PetscCall(PetscMalloc1(ps->nlocal, &s->bn));
  PetscCall(PetscArraycpy(s->bstart, ps->blockStart, ps->nlocal + 1));
  for (PetscInt lb = 0; lb < ps->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(ps->grid, lb, &info));
    s->bn[lb] = info.n;
  }
  PetscCall(PetscCalloc1(3 * ps->ncells, &s->cf));

  /* the distinct remote lower cells, and the size of each list */
  PetscCall(PetscMalloc1(nrows + 3 * ps->nfiner, &ghosts));
  for (PetscInt r = 0; r < nrows; r++) {
    PetscInt    cols[5], m;
    PetscBool   remote = PETSC_FALSE;
    PetscScalar vals[5];
    m = PffPressureGradientRow(ps, r, 1, cols, vals);         /* the columns only */
    if (m == 0 || ps->kind[r] == PFF_FACE_INTERIOR) continue; /* wall or inactive: never a flux */
    for (PetscInt q = 1; q < m; q++)
      if (cols[q] < ps->rstart || cols[q] >= rend) {
        ghosts[nremote++] = cols[q];
        remote            = PETSC_TRUE;
      }
    count[remote ? PFF_SHELL_GHOST : PFF_SHELL_LOCAL]++;
    nlo[remote ? PFF_SHELL_GHOST : PFF_SHELL_LOCAL] += m - 1;
  }
  PetscCall(PetscSortRemoveDupsInt(&nremote, ghosts));
  s->nghost = nremote;

  for (PetscInt l = 0; l < PFF_SHELL_NLISTS; l++) {
    PetscCall(PetscMalloc1(count[l], &s->row[l]));
    PetscCall(PetscMalloc1(count[l], &s->up[l]));
    PetscCall(PetscMalloc1(count[l] + 1, &s->off[l]));
    PetscCall(PetscMalloc1(nlo[l], &s->lo[l]));
    s->off[l][0] = 0;
  }
  for (PetscInt r = 0; r < nrows; r++) {
    PetscInt    cols[5], m, l = PFF_SHELL_LOCAL;
    PetscScalar vals[5];
    m = PffPressureGradientRow(ps, r, 1, cols, vals); /* the columns only */
    if (m == 0 || ps->kind[r] == PFF_FACE_INTERIOR) continue;
    for (PetscInt q = 1; q < m; q++)
      if (cols[q] < ps->rstart || cols[q] >= rend) l = PFF_SHELL_GHOST;
    const PetscInt i = s->nface[l]++;
    s->row[l][i]     = (r % 3) * ps->ncells + r / 3;
    s->up[l][i]      = r / 3;
    s->off[l][i + 1] = s->off[l][i] + m - 1;
    for (PetscInt q = 1; q < m; q++)
      PetscCall(PffShellLocalCell(ps, ghosts, nremote, cols[q], &s->lo[l][s->off[l][i] + q - 1]));
  }

  PetscCall(PffShellFindPlanes(s));

  /* the plan, once: owned x -> ghost x; the same plan reversed carries the ghost contributions home */
  PetscCall(VecCreateSeq(PETSC_COMM_SELF, nremote, &s->xg));
  PetscCall(VecDuplicate(s->xg, &s->yg));
  PetscCall(ISCreateGeneral(PETSC_COMM_SELF, nremote, ghosts, PETSC_COPY_VALUES, &is));
  PetscCall(VecScatterCreate(ps->p, is, s->xg, NULL, &s->scatter));
  PetscCall(ISDestroy(&is));
  PetscCall(PetscFree(ghosts));
  PetscCall(VecDuplicate(ps->p, &s->diag));

  PetscCall(MatCreateShell(ps->comm, ps->ncells, ps->ncells, ps->ntotal, ps->ntotal, s, S));
  PetscCall(MatShellSetContextDestroy(*S, PffShellDestroy));
  PetscCall(MatShellSetOperation(*S, MATOP_MULT, (void (*)(void))MatMult_PffShell));
  PetscCall(MatShellSetOperation(*S, MATOP_MULT_TRANSPOSE, (void (*)(void))MatMult_PffShell)); /* symmetric */
  PetscCall(MatShellSetOperation(*S, MATOP_GET_DIAGONAL, (void (*)(void))MatGetDiagonal_PffShell));
  PetscCall(MatShellSetOperation(*S, MATOP_VIEW, (void (*)(void))MatView_PffShell));
  PetscCall(MatSetOption(*S, MAT_SYMMETRIC, PETSC_TRUE));
  PetscCall(MatSetOption(*S, MAT_SYMMETRY_ETERNAL, PETSC_TRUE));
  PetscCall(PetscObjectSetName((PetscObject)*S, "pressure_shell"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Rebuilds the diagonal from the shell's c_f, sum_f c_f (1 on the upper cell, w_k^2 on the lower ones),
   with the ghost part sent home. Then the diagonal-only terms of the assembly (operator.c): the
   Dirichlet wall terms 2 h beta of ps->dirdiag, and 1 for a cell whose diagonal is still exactly zero
   (every face closed, no Dirichlet term), the criterion of the assembly. */
PetscErrorCode PffPressureShellUpdate_Private(PffPressure ps, Mat S)
{
  PffShell          *s;
  const PetscScalar *dd;
  PetscScalar       *d, *dg;

  PetscFunctionBeginUser;
  PetscCall(MatShellGetContext(S, &s));
  PetscCall(VecGetArrayWrite(s->diag, &d));
  PetscCall(VecGetArrayWrite(s->yg, &dg));
  PetscCall(PetscArrayzero(d, s->ncells));
  PetscCall(PetscArrayzero(dg, s->nghost));
  for (PetscInt b = 0; b < s->nblocks; b++) {
    const PetscInt n = s->bn[b], stride[3] = {1, n, n * n};
    for (PetscInt c = s->bstart[b]; c < s->bstart[b + 1]; c++)
      for (PetscInt e = 0; e < 3; e++) {
        if (ps->kind[3 * c + e] != PFF_FACE_INTERIOR) continue;
        const PetscReal cf = s->cf[e * s->ncells + c];
        d[c] += cf;
        d[c - stride[e]] += cf;
      }
  }
  for (PetscInt l = 0; l < PFF_SHELL_NLISTS; l++)
    for (PetscInt i = 0; i < s->nface[l]; i++) {
      const PetscInt  k0 = s->off[l][i], k1 = s->off[l][i + 1];
      const PetscReal w = k1 - k0 == 1 ? 1.0 : 0.25, c = s->cf[s->row[l][i]];
      d[s->up[l][i]] += c;
      for (PetscInt k = k0; k < k1; k++) {
        if (s->lo[l][k] < s->ncells)
          d[s->lo[l][k]] += w * w * c;
        else
          dg[s->lo[l][k] - s->ncells] += w * w * c;
      }
    }
  PetscCall(VecRestoreArrayWrite(s->yg, &dg));
  PetscCall(VecRestoreArrayWrite(s->diag, &d));
  PetscCall(VecScatterBegin(s->scatter, s->yg, s->diag, ADD_VALUES, SCATTER_REVERSE));
  PetscCall(VecScatterEnd(s->scatter, s->yg, s->diag, ADD_VALUES, SCATTER_REVERSE));

  PetscCall(PetscFree(s->diagCell));
  PetscCall(PetscFree(s->diagVal));
  PetscCall(VecGetArray(s->diag, &d));
  dd = NULL;
  if (ps->dirdiag) PetscCall(VecGetArrayRead(ps->dirdiag, &dd));
  s->ndiag = 0;
  for (PetscInt i = 0; i < s->ncells; i++)
    if ((dd && PetscRealPart(dd[i]) != 0) || PetscRealPart(d[i]) == 0) s->ndiag++;
  PetscCall(PetscMalloc1(s->ndiag, &s->diagCell));
  PetscCall(PetscMalloc1(s->ndiag, &s->diagVal));
  s->ndiag = 0;
  for (PetscInt i = 0; i < s->ncells; i++) {
    PetscReal extra = dd ? PetscRealPart(dd[i]) : 0;
    if (PetscRealPart(d[i]) + extra == 0) extra = 1.0; /* no open face and no Dirichlet term */
    if (extra == 0) continue;
    d[i] += extra;
    s->diagCell[s->ndiag]  = i;
    s->diagVal[s->ndiag++] = extra;
  }
  if (ps->dirdiag) PetscCall(VecRestoreArrayRead(ps->dirdiag, &dd));
  PetscCall(VecRestoreArray(s->diag, &d));
  s->updated = PETSC_TRUE;
  /* new values: a PC built from this operator (the matrix-free pffmg) must set up again, and PETSc
     decides that from the Mat's state, which a shell's new context does not change; the assembly does */
  PetscCall(MatAssemblyBegin(S, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(S, MAT_FINAL_ASSEMBLY));
  PetscCall(MatSetNullSpace(S, ps->nullsp));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureShellGetCoefficients_Private(Mat S, PetscReal **cf)
{
  PffShell *s;

  PetscFunctionBeginUser;
  PetscCall(MatShellGetContext(S, &s));
  *cf = s->cf;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* ya = the divergence's part from the faces inside the blocks (the faces with both cells in one block,
   PFF_FACE_INTERIOR: the lower faces of the cells not on a block's lower sides), gathered cell by cell as in
   PffShellInterior: a cell takes h^2 u of its own lower faces and minus that of its upper neighbours' lower faces
   inside the block (only the open ones if openOnly). The face-by-face scatter it replaced chained each cell to the
   store of the one before. The last row of the rank's cells, whose end must not read past u, takes the branching
   path (a cell reads only its own and its upper neighbours' faces, so the first row needs none). */
static void PffShellInteriorDivergence(PffPressure ps, const PffShell *s, const PetscScalar *restrict u,
                                       PetscBool openOnly, PetscScalar *restrict ya)
{
  const PetscReal *restrict cf = s->cf;
  const PetscInt nc            = s->ncells;
  PetscReal      lo[PFF_GRID_BLOCK_SIZE_MAX], hi[PFF_GRID_BLOCK_SIZE_MAX];

  for (PetscInt b = 0; b < s->nblocks; b++) {
    const PetscInt  n = s->bn[b], n2 = n * n;
    const PetscReal h2 = ps->hblock[b] * ps->hblock[b];
    PffShellRowEnds(n, lo, hi);
    for (PetscInt k = 0; k < n; k++)
      for (PetscInt j = 0; j < n; j++) {
        const PetscInt  row = s->bstart[b] + n * (j + n * k);
        const PetscReal ym = j > 0, zm = k > 0;
        const PetscInt  syp = j < n - 1 ? n : 0, szp = k < n - 1 ? n2 : 0; /* 0: the cell's own face, weight 0 */
        const PetscReal yp = syp != 0, zp = szp != 0;
        if (row + n == nc) {
          for (PetscInt i = 0; i < n; i++) {
            const PetscInt c = row + i;
            PetscScalar    v = 0;
            for (PetscInt e = 0; e < 3; e++) {
              const PetscInt up  = e == 0   ? (i < n - 1 ? c + 1 : -1)
                                   : e == 1 ? (j < n - 1 ? c + n : -1)
                                            : (k < n - 1 ? c + n2 : -1);
              const PetscInt own = e == 0 ? i : e == 1 ? j : k;
              if (own > 0 && (!openOnly || cf[e * nc + c] != 0)) v += u[3 * c + e];
              if (up >= 0 && (!openOnly || cf[e * nc + up] != 0)) v -= u[3 * up + e];
            }
            ya[c] = h2 * v;
          }
          continue;
        }
        const PetscReal *restrict cx = cf + row, *restrict cy = cf + nc + row, *restrict cz = cf + 2 * nc + row;
        const PetscScalar *restrict ur = u + 3 * row;
        for (PetscInt i = 0; i < n; i++) {
          const PetscReal ox0 = openOnly ? (cx[i] != 0) : 1, ox1 = openOnly ? (cx[i + 1] != 0) : 1;
          const PetscReal oy0 = openOnly ? (cy[i] != 0) : 1, oy1 = openOnly ? (cy[i + syp] != 0) : 1;
          const PetscReal oz0 = openOnly ? (cz[i] != 0) : 1, oz1 = openOnly ? (cz[i + szp] != 0) : 1;
          ya[row + i] =
              h2 * (lo[i] * ox0 * ur[3 * i] - hi[i] * ox1 * ur[3 * (i + 1)] + ym * oy0 * ur[3 * i + 1] -
                    yp * oy1 * ur[3 * (i + syp) + 1] + zm * oz0 * ur[3 * i + 2] - zp * oz1 * ur[3 * (i + szp) + 2]);
        }
      }
  }
}

/* y = G^T diag(M) (mask u) = sum_f h_upper^2 u_f g_f over the face rows r = 3 c + d of the face Vec u,
   with mask the open faces (c_f != 0) if openOnly, else every face that has a lower cell (walls and
   inactive neighbours have no row in G). -y is V D u, the volume-weighted divergence. */
PetscErrorCode PffPressureShellDivergence_Private(PffPressure ps, Mat S, Vec u, PetscBool openOnly, Vec y)
{
  PffShell          *s;
  const PetscScalar *ua;
  PetscScalar       *ya, *yg;

  PetscFunctionBeginUser;
  PetscCall(MatShellGetContext(S, &s));
  PetscCall(VecGetArrayRead(u, &ua));
  PetscCall(VecGetArrayWrite(y, &ya));
  PetscCall(VecGetArrayWrite(s->yg, &yg));
  PetscCall(PetscArrayzero(yg, s->nghost));
  PffShellInteriorDivergence(ps, s, ua, openOnly, ya);
  for (PetscInt b = 0; b < s->nblocks; b++) /* the block sides that go a plane at a time (PffShellPlanes) */
    for (PetscInt d = 0; d < 3; d++) {
      PetscInt up, lo, si, so;
      if (!PffShellPlane(s, b, d, &up, &lo, &si, &so)) continue;
      const PetscReal h2          = ps->hblock[b] * ps->hblock[b];
      const PetscReal *restrict c = s->cf + d * s->ncells + up;
      for (PetscInt v = 0; v < s->bn[b]; v++)
        for (PetscInt w = 0; w < s->bn[b]; w++) {
          const PetscInt    q = si * w + so * v;
          const PetscScalar f = openOnly && c[q] == 0 ? 0 : h2 * ua[3 * (up + q) + d];
          ya[up + q] += f;
          ya[lo + q] -= f;
        }
    }
  for (PetscInt l = 0; l < PFF_SHELL_NLISTS; l++)
    for (PetscInt q = 0, b = 0; q < (l == PFF_SHELL_LOCAL ? s->nmult : s->nface[l]); q++) {
      const PetscInt  i  = l == PFF_SHELL_LOCAL ? s->mult[q] : q;
      const PetscInt  k0 = s->off[l][i], k1 = s->off[l][i + 1], c = s->up[l][i], e = s->row[l][i] / s->ncells;
      const PetscReal w = k1 - k0 == 1 ? 1.0 : 0.25;
      if (openOnly && s->cf[s->row[l][i]] == 0) continue;
      while (c >= s->bstart[b + 1]) b++; /* the lists run in cell order */
      const PetscScalar f = ps->hblock[b] * ps->hblock[b] * ua[3 * c + e];
      ya[c] += f;
      for (PetscInt k = k0; k < k1; k++) {
        if (s->lo[l][k] < s->ncells)
          ya[s->lo[l][k]] -= w * f;
        else
          yg[s->lo[l][k] - s->ncells] -= w * f;
      }
    }
  PetscCall(VecRestoreArrayWrite(s->yg, &yg));
  PetscCall(VecRestoreArrayWrite(y, &ya));
  PetscCall(VecRestoreArrayRead(u, &ua));
  PetscCall(VecScatterBegin(s->scatter, s->yg, y, ADD_VALUES, SCATTER_REVERSE));
  PetscCall(VecScatterEnd(s->scatter, s->yg, y, ADD_VALUES, SCATTER_REVERSE));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* u_f <- u_f - dt beta_f (G p)_f on the open faces, 0 on the closed ones, in the face Vec u. On an open
   face beta_f (G p)_f = c_f (p_upper - sum_k w_k p_lower_k) / h_upper^2 (see the top of the file). */
PetscErrorCode PffPressureShellProjectVelocity_Private(PffPressure ps, Mat S, Vec p, PetscReal dt, Vec u)
{
  PffShell          *s;
  const PetscScalar *pa, *pg;
  PetscScalar       *ua;

  PetscFunctionBeginUser;
  PetscCall(MatShellGetContext(S, &s));
  PetscCall(VecScatterBegin(s->scatter, p, s->xg, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecGetArrayRead(p, &pa));
  PetscCall(VecGetArray(u, &ua));
  for (PetscInt b = 0; b < s->nblocks; b++) {
    const PetscInt  n = s->bn[b], stride[3] = {1, n, n * n};
    const PetscReal ih2 = dt / (ps->hblock[b] * ps->hblock[b]);
    for (PetscInt c = s->bstart[b]; c < s->bstart[b + 1]; c++)
      for (PetscInt e = 0; e < 3; e++) {
        const PetscInt  r  = 3 * c + e;
        const PetscReal cf = s->cf[e * s->ncells + c];
        if (cf == 0)
          ua[r] = 0; /* closed, a wall or an inactive neighbour */
        else if (ps->kind[r] == PFF_FACE_INTERIOR)
          ua[r] -= ih2 * cf * (pa[c] - pa[c - stride[e]]);
      }
  }
  PetscCall(VecScatterEnd(s->scatter, p, s->xg, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecGetArrayRead(s->xg, &pg));
  for (PetscInt b = 0; b < s->nblocks; b++) /* the block sides that go a plane at a time (PffShellPlanes) */
    for (PetscInt d = 0; d < 3; d++) {
      PetscInt up, lo, si, so;
      if (!PffShellPlane(s, b, d, &up, &lo, &si, &so)) continue;
      const PetscReal ih2         = dt / (ps->hblock[b] * ps->hblock[b]);
      const PetscReal *restrict c = s->cf + d * s->ncells + up;
      for (PetscInt v = 0; v < s->bn[b]; v++)
        for (PetscInt w = 0; w < s->bn[b]; w++) {
          const PetscInt q = si * w + so * v;
          ua[3 * (up + q) + d] -= ih2 * c[q] * (pa[up + q] - pa[lo + q]); /* closed (c = 0): already 0 */
        }
    }
  for (PetscInt l = 0; l < PFF_SHELL_NLISTS; l++)
    for (PetscInt q = 0, b = 0; q < (l == PFF_SHELL_LOCAL ? s->nmult : s->nface[l]); q++) {
      const PetscInt  i  = l == PFF_SHELL_LOCAL ? s->mult[q] : q;
      const PetscInt  k0 = s->off[l][i], k1 = s->off[l][i + 1], c = s->up[l][i], e = s->row[l][i] / s->ncells;
      const PetscReal w = k1 - k0 == 1 ? 1.0 : 0.25, cf = s->cf[s->row[l][i]];
      PetscScalar     pl = 0;
      if (cf == 0) continue;
      while (c >= s->bstart[b + 1]) b++;
      for (PetscInt k = k0; k < k1; k++) pl += s->lo[l][k] < s->ncells ? pa[s->lo[l][k]] : pg[s->lo[l][k] - s->ncells];
      ua[3 * c + e] -= dt * cf * (pa[c] - w * pl) / (ps->hblock[b] * ps->hblock[b]);
    }
  PetscCall(VecRestoreArrayRead(s->xg, &pg));
  PetscCall(VecRestoreArray(u, &ua));
  PetscCall(VecRestoreArrayRead(p, &pa));
  PetscFunctionReturn(PETSC_SUCCESS);
}
