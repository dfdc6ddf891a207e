/* Horizontal gradient rows of the tall-cell grid (tall cells Sec. 4.3.1, Eq. 2-5) and the assembly of
   [grad] and A = [grad]^T V F [grad].

   Every owned column U makes the rows of the lower x- and z-faces of its cells (the faces the MSBG face
   channel stores at U). The lower side is one column (same level, or coarser: the column holding the
   face) or two (finer: the two columns across U's face, weight 1/2 each). A face's row compares the two
   sides' pressures at the face's mid height, each from its column's piecewise-linear function, over the
   distance of the column centres: s, 1.5 s (coarser) or 0.75 s (finer, s being U's cell size). Faces whose
   cells on both sides are the same tall cells as the face below merge with it into one row, whose u* is
   the mean of its faces (Eq. 5, the "collapsed" average of Fig. 4). */
#include "tallimpl.h"

PetscErrorCode PffTallAddRow_Private(PffTall tc, const PffTallRow *row, PetscReal F, PetscReal V, PetscBool surface,
                                     PetscInt nf, const PetscInt lb[], const PetscInt comp[], const PetscInt cell[])
{
  PetscReal asum = 0;

  PetscFunctionBeginUser;
  if (tc->nrows == tc->rowsCap) {
    const PetscInt cap = PetscMax(1024, 2 * tc->rowsCap);
    PetscCall(PetscRealloc(sizeof(PetscReal) * cap, &tc->rowF));
    PetscCall(PetscRealloc(sizeof(PetscReal) * cap, &tc->rowV));
    PetscCall(PetscRealloc(sizeof(PetscReal) * cap, &tc->rowA));
    PetscCall(PetscRealloc(sizeof(PetscInt) * (cap + 1), &tc->rowFace));
    PetscCall(PetscRealloc(sizeof(PffTallRow) * cap, &tc->rowEnt));
    if (!tc->rowsCap) tc->rowFace[0] = 0;
    tc->rowsCap = cap;
  }
  if (tc->nfaces + nf > tc->facesCap) {
    const PetscInt cap = PetscMax(PetscMax(4096, 2 * tc->facesCap), tc->nfaces + nf);
    PetscCall(PetscRealloc(sizeof(PetscInt) * cap, &tc->faceLb));
    PetscCall(PetscRealloc(sizeof(PetscInt) * cap, &tc->faceComp));
    PetscCall(PetscRealloc(sizeof(PetscInt) * cap, &tc->faceCell));
    PetscCall(PetscRealloc(sizeof(float) * cap, &tc->faceA));
    tc->facesCap = cap;
  }
  for (PetscInt q = 0; q < nf; q++) {
    float a = 1;
    if (tc->chA >= 0) {
      float *data;
      PetscCall(PffGridGetBlockData(tc->grid, tc->chA, lb[q], comp[q], &data));
      a = PetscMax(0.0f, PetscMin(1.0f, data[cell[q]]));
    }
    tc->faceLb[tc->nfaces + q]   = lb[q];
    tc->faceComp[tc->nfaces + q] = comp[q];
    tc->faceCell[tc->nfaces + q] = cell[q];
    tc->faceA[tc->nfaces + q]    = a;
    asum += a;
  }
  if (!(asum > 0)) PetscFunctionReturn(PETSC_SUCCESS); /* closed by solids: no flux, no row */
  tc->nfaces += nf;
  tc->rowF[tc->nrows]      = F;
  tc->rowV[tc->nrows]      = V;
  tc->rowA[tc->nrows]      = asum / (PetscReal)nf;
  tc->rowEnt[tc->nrows]    = *row;
  tc->rowFace[++tc->nrows] = tc->nfaces;
  if (surface) tc->nsurface++; /* local count; summed in Build */
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The records of column (gx, gz) at level l, owned or ghost: record j is ri + PFF_TALL_RI j, rr + PFF_TALL_RR j
   (a column's records are consecutive in both stores). Resolved once per column, not per record: a ghost column
   is a binary search. */
static PetscErrorCode ColumnRecords(PffTall tc, PetscInt l, PetscInt gx, PetscInt gz, const PetscInt **ri,
                                    const PetscReal **rr)
{
  const PetscInt n = tc->n0 >> l, ny = tc->nb[1] * n, bc = gx / n + tc->nb[0] * (gz / n);

  PetscFunctionBeginUser;
  if (tc->bcOwner[bc] == tc->rank) {
    const PetscInt r = tc->bcOffset[bc] + ((gz % n) * n + gx % n) * ny;
    *ri              = tc->ri + PFF_TALL_RI * r;
    *rr              = tc->rr + PFF_TALL_RR * r;
  } else {
    const PetscInt64 key = PffTallColumnKey(tc, l, gx, gz);
    PetscInt         lo = 0, hi = tc->nghost - 1, g = -1;
    while (lo <= hi) { /* the ghost keys are sorted */
      const PetscInt mid = (lo + hi) / 2;
      if (tc->gkey[mid] == key) {
        g = mid;
        break;
      }
      if (tc->gkey[mid] < key)
        lo = mid + 1;
      else
        hi = mid - 1;
    }
    PetscCheck(g >= 0, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "tallcell: column (%" PetscInt_FMT ", %" PetscInt_FMT ") at level %" PetscInt_FMT
               " is neither owned nor a ghost",
               gx, gz, l);
    *ri = tc->gi + PFF_TALL_RI * tc->gstart[g];
    *rr = tc->gr + PFF_TALL_RR * tc->gstart[g];
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Adds scale * p(y) of a liquid record (cell centre yc) to row. */
static void AddPressure(const PetscInt ri[], const PetscReal rr[], PetscReal yc, PetscReal y, PetscReal scale,
                        PffTallRow *row)
{
  const PetscInt  h = y < yc ? 0 : 1, ia = ri[2 * h], ib = ri[2 * h + 1];
  const PetscReal ya = rr[2 * h], yb = rr[2 * h + 1];
  const PetscReal t     = yb != ya ? (y - ya) / (yb - ya) : 0;
  const PetscInt  id[2] = {ia, ib};
  const PetscReal w[2]  = {1 - t, t};

  for (PetscInt q = 0; q < 2; q++) {
    if (id[q] < 0 || w[q] == 0) continue; /* the free surface: p = 0 */
    PetscInt e = 0;
    while (e < row->n && row->col[e] != id[q]) e++;
    if (e == row->n) {
      row->col[row->n]   = id[q];
      row->val[row->n++] = 0;
    }
    row->val[e] += scale * w[q];
  }
}

/* The lower side of a face: its columns (level, x, z) and the distance of the centres. */
typedef struct {
  PetscInt         nc, l, gx[2], gz[2];
  PetscReal        d;
  const PetscInt  *ri[2]; /* the columns' records (ColumnRecords) */
  const PetscReal *rr[2];
} LowerSide;

/* What the lower side has at height y. Its phi there is the mean over its columns of phi interpolated
   linearly between the cell centres around y; the side is liquid where that is negative. A column whose cell
   holding y lies wholly inside a solid is left out of the mean (*nside counts the others; 0: no lower side).
   When asked, adds -scale p_c(y) / nside to row for every column c liquid at y, p_c from the liquid cell
   around y (the cell holding y, or the neighbour towards y when that one is air: the run's function
   extrapolates to the surface). Also returns, per lower column, the kinds of the lowest and highest cell
   touching [ylo, yhi]. */
static PetscErrorCode LowerAt(PffTall tc, const LowerSide *ls, PetscReal y, PetscReal ylo, PetscReal yhi,
                              PetscReal scale, PffTallRow *row, PetscReal *phiMean, PetscInt *nside, PetscInt kinds[4])
{
  const PetscReal  s = tc->h0 * (PetscReal)(1 << ls->l), y0 = tc->origin[1];
  const PetscInt   ny = tc->nb[1] * (tc->n0 >> ls->l);
  const PetscReal  t  = (y - y0) / s - 0.5;
  const PetscInt   ja = PetscMax(0, PetscMin(ny - 1, (PetscInt)PetscFloorReal(t))), jb = PetscMin(ny - 1, ja + 1);
  const PetscReal  f     = PetscMax(0.0, PetscMin(1.0, t - (PetscReal)ja));
  const PetscBool  upper = (PetscBool)(f >= 0.5); /* the cell holding y is jb */
  const PetscInt  *ra[2], *rb[2];
  const PetscReal *xa[2], *xb[2];
  PetscReal        sum = 0, phic[2];
  PetscInt         n   = 0;

  PetscFunctionBeginUser;
  for (PetscInt c = 0; c < ls->nc; c++) {
    ra[c]   = ls->ri[c] + PFF_TALL_RI * ja;
    xa[c]   = ls->rr[c] + PFF_TALL_RR * ja;
    rb[c]   = ls->ri[c] + PFF_TALL_RI * jb;
    xb[c]   = ls->rr[c] + PFF_TALL_RR * jb;
    phic[c] = (1 - f) * xa[c][4] + f * xb[c][4];
    if ((upper ? rb[c] : ra[c])[4] == PFF_TALL_SOLID) continue;
    sum += phic[c];
    n++;
  }
  for (PetscInt c = 0; row && c < ls->nc; c++) {
    if ((upper ? rb[c] : ra[c])[4] == PFF_TALL_SOLID || !(phic[c] < 0)) continue;
    const PetscBool useB = upper ? PffTallLiquidKind(rb[c][4]) : (PetscBool)!PffTallLiquidKind(ra[c][4]);
    AddPressure(useB ? rb[c] : ra[c], useB ? xb[c] : xa[c], y0 + ((PetscReal)(useB ? jb : ja) + 0.5) * s, y,
                -scale / (PetscReal)n, row);
  }
  for (PetscInt c = 0; kinds && c < ls->nc; c++) {
    const PetscInt jl = (PetscInt)PetscFloorReal((ylo - y0) / s + 1e-9),
                   jh = (PetscInt)PetscCeilReal((yhi - y0) / s - 1e-9) - 1;
    kinds[2 * c]      = ls->ri[c][PFF_TALL_RI * jl + 4];
    kinds[2 * c + 1]  = ls->ri[c][PFF_TALL_RI * jh + 4];
  }
  *phiMean = n ? sum / (PetscReal)n : PETSC_MAX_REAL;
  if (nside) *nside = n;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Whether a face lies wholly in tall cells on both sides: sig = U's kind, then the kinds of the lowest and
   highest lower cell per lower column; consecutive faces with equal such signatures merge into one row. */
static PetscBool InTall(const PetscInt sig[5], PetscInt nc)
{
  if (sig[0] < 0) return PETSC_FALSE;
  for (PetscInt c = 0; c < nc; c++)
    if (sig[1 + 2 * c] < 0 || sig[1 + 2 * c] != sig[2 + 2 * c]) return PETSC_FALSE;
  return PETSC_TRUE;
}

static PetscBool SameTall(const PetscInt a[5], const PetscInt b[5], PetscInt nc)
{
  if (!InTall(a, nc) || !InTall(b, nc)) return PETSC_FALSE;
  for (PetscInt q = 0; q < 1 + 2 * nc; q++)
    if (a[q] != b[q]) return PETSC_FALSE;
  return PETSC_TRUE;
}

/* The rows of U's lower faces along axis a (0 = x, 2 = z). */
static PetscErrorCode ColumnFaceRows(PffTall tc, PetscInt l, PetscInt gx, PetscInt gz, PetscInt a,
                                     const PetscInt lbOf[])
{
  const PetscInt   n = tc->n0 >> l, ny = tc->nb[1] * n, ci = gx % n, ck = gz % n;
  const PetscReal  s = tc->h0 * (PetscReal)(1 << l), y0 = tc->origin[1];
  const PetscInt   g[3] = {gx, 0, gz}, e = 2 - a; /* e: the tangential horizontal axis */
  LowerSide        ls;
  PetscInt         lnb;
  const PetscInt  *uri; /* U's records */
  const PetscReal *urr;
  PetscInt        *sig, *fl, *fc, *fcell;

  PetscFunctionBeginUser;
  /* the lower side's level */
  if (g[a] % n)
    lnb = l;
  else {
    PetscInt dir[3] = {0, 0, 0}, ijk[3] = {gx / n, 0, gz / n};
    dir[a]             = -1;
    const PetscInt nbr = PffRasterNeighbour(tc->nb, tc->periodic, ijk, dir);
    if (nbr < 0) PetscFunctionReturn(PETSC_SUCCESS); /* a wall: closed */
    lnb = tc->bcLevel[nbr % tc->nb[0] + tc->nb[0] * (nbr / (tc->nb[0] * tc->nb[1]))];
  }
  {
    const PetscInt64 a0 = (PetscInt64)g[a] << l, span = (PetscInt64)tc->nb[a] * tc->n0; /* in finest cells */
    const PetscInt64 lowCell = ((a0 - 1 + span) % span) >> lnb;
    const PetscInt64 e0      = (PetscInt64)g[e] << l;
    ls.l                     = lnb;
    ls.nc                    = lnb == l - 1 ? 2 : 1;
    ls.d                     = lnb == l ? s : (lnb > l ? 1.5 * s : 0.75 * s);
    for (PetscInt c = 0; c < ls.nc; c++) {
      const PetscInt tcell = (PetscInt)((e0 >> lnb) + c);
      ls.gx[c]             = a == 0 ? (PetscInt)lowCell : tcell;
      ls.gz[c]             = a == 0 ? tcell : (PetscInt)lowCell;
      PetscCall(ColumnRecords(tc, ls.l, ls.gx[c], ls.gz[c], &ls.ri[c], &ls.rr[c]));
    }
  }
  PetscCall(ColumnRecords(tc, l, gx, gz, &uri, &urr));
  PetscCall(PetscMalloc4(5 * ny, &sig, ny, &fl, ny, &fc, ny, &fcell));
  for (PetscInt j = 0; j < ny; j++) {
    PetscReal phiL;
    sig[5 * j] = uri[PFF_TALL_RI * j + 4];
    PetscCall(
        LowerAt(tc, &ls, y0 + (j + 0.5) * s, y0 + j * s, y0 + (j + 1) * s, 0, NULL, &phiL, NULL, &sig[5 * j + 1]));
    for (PetscInt q = 1 + 2 * ls.nc; q < 5; q++) sig[5 * j + q] = 0;
    fl[j]    = lbOf[j / n];
    fc[j]    = a;
    fcell[j] = ci + n * ((j % n) + n * ck);
  }
  for (PetscInt j0 = 0; j0 < ny;) {
    PetscInt j1 = j0 + 1;
    while (j1 < ny && SameTall(&sig[5 * j1], &sig[5 * j0], ls.nc)) j1++;
    const PetscReal  ylo = y0 + j0 * s, yhi = y0 + j1 * s, ym = 0.5 * (ylo + yhi);
    const PetscInt   ju = (PetscInt)PetscFloorReal((ym - y0) / s);
    const PetscInt  *ri = uri + PFF_TALL_RI * PetscMin(ju, ny - 1);
    const PetscReal *rr = urr + PFF_TALL_RR * PetscMin(ju, ny - 1);
    PetscReal        phiL;
    PetscInt         nside;
    PffTallRow       row  = {0};
    const PetscBool  uliq = PffTallLiquidKind(ri[4]);
    const PetscReal  phiU = rr[4];
    PetscCall(LowerAt(tc, &ls, ym, ylo, yhi, 0, NULL, &phiL, &nside, NULL));
    const PetscBool lliq = (PetscBool)(phiL < 0);
    /* a solid on either side closes the face: its fraction is zero, and so is its row */
    if ((uliq || lliq) && nside && ri[4] != PFF_TALL_SOLID) {
      PetscReal F = 1;
      if (uliq) AddPressure(ri, rr, y0 + (PetscMin(ju, ny - 1) + 0.5) * s, ym, 1 / ls.d, &row);
      if (lliq && uliq) PetscCall(LowerAt(tc, &ls, ym, ylo, yhi, 1 / ls.d, &row, &phiL, NULL, NULL));
      if (uliq != lliq) {
        const PetscReal pl = uliq ? phiU : phiL, pa = uliq ? phiL : phiU, den = pl - pa;
        const PetscReal th = PetscMin(1.0, PetscMax(tc->thetaMin, den < 0 ? pl / den : 1));
        F                  = 1 / th;
        if (lliq) PetscCall(LowerAt(tc, &ls, ym, ylo, yhi, 1 / ls.d, &row, &phiL, NULL, NULL));
      }
      if (row.n)
        PetscCall(PffTallAddRow_Private(tc, &row, F, s * (yhi - ylo) * ls.d, (PetscBool)(uliq != lliq), j1 - j0,
                                        &fl[j0], &fc[j0], &fcell[j0]));
    }
    j0 = j1;
  }
  PetscCall(PetscFree4(sig, fl, fc, fcell));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A sample whose rows the solids all closed (a liquid cell boxed in by closed faces) has an empty row in A: it
   gets a unit diagonal, so that it solves to p = 0 (its right-hand side is zero) and the matrix stays
   definite. */
static PetscErrorCode IsolatedSamples(PffTall tc)
{
  Vec                diag;
  const PetscScalar *d;
  PetscInt           nzero = 0, any;

  PetscFunctionBeginUser;
  if (tc->chA < 0) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(MatCreateVecs(tc->A, &diag, NULL));
  PetscCall(MatGetDiagonal(tc->A, diag));
  PetscCall(VecGetArrayRead(diag, &d));
  for (PetscInt i = 0; i < tc->nsamp; i++) nzero += d[i] == 0;
  PetscCallMPI(MPIU_Allreduce(&nzero, &any, 1, MPIU_INT, MPI_SUM, tc->comm));
  if (any) {
    PetscCall(MatSetOption(tc->A, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_FALSE));
    for (PetscInt i = 0; i < tc->nsamp; i++)
      if (d[i] == 0) PetscCall(MatSetValue(tc->A, tc->sstart + i, tc->sstart + i, 1.0, INSERT_VALUES));
    PetscCall(MatAssemblyBegin(tc->A, MAT_FINAL_ASSEMBLY));
    PetscCall(MatAssemblyEnd(tc->A, MAT_FINAL_ASSEMBLY));
  }
  PetscCall(VecRestoreArrayRead(diag, &d));
  PetscCall(VecDestroy(&diag));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffTallBuildRows_Private(PffTall tc)
{
  PetscInt *lbOf;
  Vec       sw;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(tc->nb[1], &lbOf));
  for (PetscInt bc = 0; bc < tc->nbc; bc++) {
    if (tc->bcOwner[bc] != tc->rank) continue;
    const PetscInt bi = bc % tc->nb[0], bk = bc / tc->nb[0], l = tc->bcLevel[bc], n = tc->n0 >> l;
    for (PetscInt bj = 0; bj < tc->nb[1]; bj++) {
      PetscCall(PffGridGetLocalIndex(tc->grid, bi + tc->nb[0] * (bj + tc->nb[1] * bk), &lbOf[bj]));
    }
    for (PetscInt ck = 0; ck < n; ck++)
      for (PetscInt ci = 0; ci < n; ci++)
        for (PetscInt a = 0; a < 3; a += 2) PetscCall(ColumnFaceRows(tc, l, bi * n + ci, bk * n + ck, a, lbOf));
  }
  PetscCall(PetscFree(lbOf));

  /* [grad]: rows x samples; A = B^T B with B = diag(sqrt(V F)) [grad] */
  PetscCallMPI(MPI_Exscan(&tc->nrows, &tc->rstart, 1, MPIU_INT, MPI_SUM, tc->comm));
  if (tc->rank == 0) tc->rstart = 0;
  PetscCall(MatCreateAIJ(tc->comm, tc->nrows, tc->nsamp, PETSC_DETERMINE, PETSC_DETERMINE, PFF_TALL_ROW_MAX, NULL,
                         PFF_TALL_ROW_MAX, NULL, &tc->G));
  PetscCall(MatSetOption(tc->G, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE));
  for (PetscInt r = 0; r < tc->nrows; r++) {
    const PetscInt grow = tc->rstart + r;
    PetscCall(MatSetValues(tc->G, 1, &grow, tc->rowEnt[r].n, tc->rowEnt[r].col, tc->rowEnt[r].val, INSERT_VALUES));
  }
  PetscCall(MatAssemblyBegin(tc->G, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(tc->G, MAT_FINAL_ASSEMBLY));
  PetscCall(MatCreateVecs(tc->G, &tc->p, &tc->urow));
  PetscCall(VecDuplicate(tc->p, &tc->b));
  PetscCall(VecDuplicate(tc->urow, &tc->grow));
  PetscCall(VecDuplicate(tc->urow, &tc->w));
  {
    Mat          B;
    PetscScalar *sv;
    PetscCall(VecDuplicate(tc->urow, &sw));
    PetscCall(VecGetArray(sw, &sv));
    for (PetscInt r = 0; r < tc->nrows; r++) sv[r] = PetscSqrtReal(tc->rowV[r] * tc->rowA[r] * tc->rowF[r]);
    PetscCall(VecRestoreArray(sw, &sv));
    PetscCall(MatDuplicate(tc->G, MAT_COPY_VALUES, &B));
    PetscCall(MatDiagonalScale(B, sw, NULL));
    PetscCall(MatTransposeMatMult(B, B, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &tc->A));
    PetscCall(MatDestroy(&B));
    PetscCall(VecDestroy(&sw));
  }
  PetscCall(IsolatedSamples(tc));
  {
    PetscInt64 loc = tc->nsurface;
    PetscCallMPI(MPIU_Allreduce(&loc, &tc->nsurface, 1, MPIU_INT64, MPI_SUM, tc->comm));
  }
  if (!tc->nsurface) { /* no free surface: p up to a constant */
    MatNullSpace nsp;
    PetscCall(MatNullSpaceCreate(tc->comm, PETSC_TRUE, 0, NULL, &nsp));
    PetscCall(MatSetNullSpace(tc->A, nsp));
    PetscCall(MatNullSpaceDestroy(&nsp));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
