/* The pressure operator of the projection (PF-FLIP Eq. 8-10) from the face coefficients, and the
   transfers between grid channels and PETSc Vecs.

   With the gradient G (faces.c), the face weights M_f = A_f d_f and w_f = M_f beta_f open_f,
     A = G^T diag(w) G,            V D u = -G^T diag(M) u,
   so A is symmetric positive semi-definite by construction, its rows sum to zero (G 1 = 0) and on a
   uniform grid it is the 7-point stencil with h beta_f per face. Two assemblies of the same matrix:
   MatPtAP with the diagonal face matrix (numeric phase only after the first call), or direct
   MatSetValues of the 2x2 / 5x5 face blocks into the fixed pattern (rows of other ranks through
   the stash). -pressure_assembly picks one; docs/pressure.md has the timings.

   Dirichlet walls (p = 0 at the wall face, half a cell outside the boundary cell's centre) have no
   face row: each adds its one-sided face weight c_D = A_f beta / d_f = h^2 beta / (h / 2) = 2 h beta
   to the diagonal of the boundary cell, after either assembly. beta is the value of the cell's own
   lower d-face in the face channel: at a -wall that is the wall face itself, at a +wall (whose face
   has no storage) the opposite face of the same cell. A then stays symmetric and becomes definite. */
#include "pressureimpl.h"

/* Copies between a channel's owned values and a Vec in cell (or face, 3 per cell) numbering. */
static PetscErrorCode PffPressureCopy(PffPressure ps, PetscInt ch, PffChannelKind kind, Vec v, PetscBool toVec)
{
  PffChannelKind ck;
  PetscScalar   *a;
  const PetscInt ncomp = kind == PFF_CHANNEL_CELL ? 1 : 3;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetChannelInfo(ps->grid, ch, NULL, &ck, NULL, NULL));
  PetscCheck(ck == kind, ps->comm, PETSC_ERR_ARG_WRONG, "pressure: channel %" PetscInt_FMT " is a %s channel, need %s",
             ch, PffChannelKinds[ck], PffChannelKinds[kind]);
  if (toVec)
    PetscCall(VecGetArrayWrite(v, &a));
  else
    PetscCall(VecGetArray(v, &a));
  for (PetscInt lb = 0; lb < ps->nlocal; lb++) {
    const PetscInt c0 = ps->blockStart[lb], nc = ps->blockStart[lb + 1] - c0;
    float         *data[3];
    for (PetscInt d = 0; d < ncomp; d++) PetscCall(PffGridGetBlockData(ps->grid, ch, lb, d, &data[d]));
    PetscScalar *restrict ab = a + ncomp * c0;
    /* a face Vec interleaves the three components: one pass over it, not one strided pass per component */
    if (ncomp == 1 && toVec)
      for (PetscInt c = 0; c < nc; c++) ab[c] = data[0][c];
    else if (ncomp == 1)
      for (PetscInt c = 0; c < nc; c++) data[0][c] = (float)PetscRealPart(ab[c]);
    else if (toVec) {
      const float *restrict x = data[0], *restrict y = data[1], *restrict z = data[2];
      for (PetscInt c = 0; c < nc; c++) {
        ab[3 * c]     = x[c];
        ab[3 * c + 1] = y[c];
        ab[3 * c + 2] = z[c];
      }
    } else {
      float *restrict x = data[0], *restrict y = data[1], *restrict z = data[2];
      for (PetscInt c = 0; c < nc; c++) {
        x[c] = (float)PetscRealPart(ab[3 * c]);
        y[c] = (float)PetscRealPart(ab[3 * c + 1]);
        z[c] = (float)PetscRealPart(ab[3 * c + 2]);
      }
    }
  }
  if (toVec)
    PetscCall(VecRestoreArrayWrite(v, &a));
  else
    PetscCall(VecRestoreArray(v, &a));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureChannelToVec_Private(PffPressure ps, PetscInt ch, PffChannelKind kind, Vec v)
{
  PetscFunctionBeginUser;
  PetscCall(PffPressureCopy(ps, ch, kind, v, PETSC_TRUE));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureVecToChannel_Private(PffPressure ps, Vec v, PffChannelKind kind, PetscInt ch)
{
  PetscFunctionBeginUser;
  PetscCall(PffPressureCopy(ps, ch, kind, v, PETSC_FALSE));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* max_i |(V D u)_i| / V_i with V D u = -G^T M u (the shell's face lists); uses the work Vec vcell. */
PetscErrorCode PffPressureMaxDivergenceVec_Private(PffPressure ps, Vec u, PetscReal *maxdiv)
{
  const PetscScalar *y;
  PetscReal          m = 0;

  PetscFunctionBeginUser;
  PetscCall(PffPressureShellDivergence_Private(ps, ps->S, u, PETSC_FALSE, ps->vcell));
  PetscCall(VecGetArrayRead(ps->vcell, &y));
  for (PetscInt lb = 0; lb < ps->nlocal; lb++) {
    const PetscReal h = ps->hblock[lb], iv = 1.0 / (h * h * h);
    for (PetscInt c = ps->blockStart[lb]; c < ps->blockStart[lb + 1]; c++) m = PetscMax(m, PetscAbsScalar(y[c]) * iv);
  }
  PetscCall(VecRestoreArrayRead(ps->vcell, &y));
  PetscCall(MPIU_Allreduce(&m, maxdiv, 1, MPIU_REAL, MPIU_MAX, ps->comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A = 0, then the face blocks w_f g g^T with g the row of G, added into the fixed pattern. */
static PetscErrorCode AssembleDirect(PffPressure ps)
{
  const PetscScalar *w;

  PetscFunctionBeginUser;
  PetscCall(MatZeroEntries(ps->A));
  PetscCall(VecGetArrayRead(ps->w, &w));
  for (PetscInt lb = 0; lb < ps->nlocal; lb++)
    for (PetscInt r = 3 * ps->blockStart[lb]; r < 3 * ps->blockStart[lb + 1]; r++) {
      PetscInt    cols[5], m;
      PetscScalar g[5], vals[25];
      if (w[r] == 0) continue;
      m = PffPressureGradientRow(ps, r, ps->hblock[lb], cols, g);
      for (PetscInt a = 0; a < m; a++)
        for (PetscInt b = 0; b < m; b++) vals[a * m + b] = w[r] * g[a] * g[b];
      PetscCall(MatSetValues(ps->A, m, cols, m, cols, vals, ADD_VALUES));
    }
  PetscCall(VecRestoreArrayRead(ps->w, &w));
  PetscCall(MatAssemblyBegin(ps->A, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(ps->A, MAT_FINAL_ASSEMBLY));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* dirdiag += the Dirichlet terms 2 h beta of block lb (see the top of the file), with beta[d] the block's
   data of the beta channel. Returns in *bad a local face row with a bad beta (unchanged if none). */
static PetscErrorCode PffPressureDirichletTerms(PffPressure ps, PetscInt lb, const PetscInt nb[3], float *const beta[3],
                                                PetscScalar *dd, PetscInt *bad)
{
  PffBlockInfo info;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetBlockInfo(ps->grid, lb, &info));
  const PetscInt n = info.n, c0 = ps->blockStart[lb];
  for (PetscInt w = 0; w < 6; w++) {
    const PetscInt d = w / 2, upper = w % 2;
    if (!ps->dirichlet[w] || info.ijk[d] != (upper ? nb[d] - 1 : 0)) continue;
    /* the layer c[d] = 0 or n - 1 of the block, the other two indices free */
    for (PetscInt b = 0; b < n; b++)
      for (PetscInt a = 0; a < n; a++) {
        PetscInt       c[3] = {0, 0, 0}, e = 0;
        const PetscInt ab[2] = {a, b};
        for (PetscInt q = 0; q < 3; q++) c[q] = q == d ? (upper ? n - 1 : 0) : ab[e++];
        const PetscInt  cell = c0 + c[0] + n * (c[1] + n * c[2]);
        const PetscReal bf   = beta[d][cell - c0];
        if (!(bf > 0 && PetscIsNormalReal(bf))) *bad = 3 * cell + d;
        dd[cell] += 2 * info.h * bf;
      }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Cells with every face closed (inside a solid) and no Dirichlet term have an empty row: they get a
   unit diagonal, so every preconditioner sees a definite block there. The null space is attached
   afresh on every assembly: none when a Dirichlet wall exists (A is definite on the cells connected
   to it), otherwise the constants, or the indicator of the non-empty rows when isolated cells exist. */
PetscErrorCode PffPressureNullSpace_Private(PffPressure ps)
{
  PetscScalar *d, *z;
  PetscInt     n, nisolated = 0;
  Vec          ind;

  PetscFunctionBeginUser;
  PetscCall(MatNullSpaceDestroy(&ps->nullsp));
  PetscCall(VecGetLocalSize(ps->diag, &n));
  PetscCall(VecDuplicate(ps->diag, &ind));
  PetscCall(VecGetArray(ps->diag, &d));
  PetscCall(VecGetArrayWrite(ind, &z));
  for (PetscInt i = 0; i < n; i++) {
    const PetscBool empty = PetscRealPart(d[i]) == 0 ? PETSC_TRUE : PETSC_FALSE;
    z[i]                  = empty ? 0.0 : 1.0;
    if (empty) nisolated++;
  }
  PetscCall(VecRestoreArrayWrite(ind, &z));
  PetscCall(VecRestoreArray(ps->diag, &d));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &nisolated, 1, MPIU_INT, MPI_SUM, ps->comm));
  if (nisolated > 0) {
    Vec one;
    PetscCall(VecDuplicate(ind, &one));
    PetscCall(VecSet(one, 1.0));
    PetscCall(VecAXPY(one, -1.0, ind)); /* 1 on the empty rows */
    if (ps->A) PetscCall(MatDiagonalSet(ps->A, one, ADD_VALUES));
    PetscCall(VecAXPY(ps->diag, 1.0, one));
    PetscCall(VecDestroy(&one));
  }
  if (PffPressureHasDirichlet_Private(ps)) {
    /* nothing to attach */
  } else if (nisolated > 0) {
    PetscReal nrm;
    PetscCall(VecNorm(ind, NORM_2, &nrm));
    PetscCall(VecScale(ind, 1.0 / nrm));
    PetscCall(MatNullSpaceCreate(ps->comm, PETSC_FALSE, 1, &ind, &ps->nullsp));
  } else
    PetscCall(MatNullSpaceCreate(ps->comm, PETSC_TRUE, 0, NULL, &ps->nullsp));
  if (ps->A) PetscCall(MatSetNullSpace(ps->A, ps->nullsp));
  PetscCall(VecDestroy(&ind));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* c_f = M_f beta_f open_f / d_f^2 = h^2 beta_f / d_f on the open faces, 0 on the closed ones, straight
   from the channels into the shell's coefficient arrays; the Dirichlet terms; A if it exists. */
PetscErrorCode PffPressureAssemble_Private(PffPressure ps, PetscInt chBeta, PetscInt chOpen)
{
  PetscScalar    *dd      = NULL;
  const PetscBool dir     = PffPressureHasDirichlet_Private(ps);
  PetscInt        bad     = -1, gbad, nb[3];
  PetscReal       badBeta = 0;
  const PetscInt  nc      = ps->ncells;
  PffChannelKind  kb, ko = PFF_CHANNEL_FACE;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetChannelInfo(ps->grid, chBeta, NULL, &kb, NULL, NULL));
  if (chOpen >= 0) PetscCall(PffGridGetChannelInfo(ps->grid, chOpen, NULL, &ko, NULL, NULL));
  PetscCheck(kb == PFF_CHANNEL_FACE && ko == PFF_CHANNEL_FACE, ps->comm, PETSC_ERR_ARG_WRONG,
             "pressure: the beta and open channels must be face channels");
  PetscCall(PffGridGetRaster(ps->grid, nb, NULL, NULL));
  if (dir && !ps->dirdiag) PetscCall(VecDuplicate(ps->p, &ps->dirdiag));
  if (ps->dirdiag) {
    PetscCall(VecSet(ps->dirdiag, 0.0));
    PetscCall(VecGetArray(ps->dirdiag, &dd));
  }
  for (PetscInt lb = 0; lb < ps->nlocal; lb++) {
    float          *beta[3], *open[3] = {NULL, NULL, NULL};
    const PetscReal h = ps->hblock[lb], h2 = h * h;
    const PetscInt  c0 = ps->blockStart[lb], c1 = ps->blockStart[lb + 1];
    for (PetscInt d = 0; d < 3; d++) {
      PetscCall(PffGridGetBlockData(ps->grid, chBeta, lb, d, &beta[d]));
      if (chOpen >= 0) PetscCall(PffGridGetBlockData(ps->grid, chOpen, lb, d, &open[d]));
    }
    for (PetscInt d = 0; d < 3; d++)
      for (PetscInt c = c0; c < c1; c++) {
        const PetscInt  r  = 3 * c + d;
        const PetscReal bf = beta[d][c - c0];
        const PetscBool op = (PetscBool)(ps->kind[r] != PFF_FACE_WALL && ps->kind[r] != PFF_FACE_INACTIVE &&
                                         (!open[d] || open[d][c - c0] > 0.5f));
        if (op && !(bf > 0 && PetscIsNormalReal(bf))) {
          bad     = r;
          badBeta = bf;
        }
        ps->cf[d * nc + c] = op ? h2 * bf / PffPressureFaceDistance(ps->kind[r], h) : 0.0;
      }
    if (bad < 0 && dir) {
      PetscCall(PffPressureDirichletTerms(ps, lb, nb, beta, dd, &bad));
      if (bad >= 0) badBeta = beta[bad % 3][bad / 3 - c0];
    }
  }
  if (ps->dirdiag) PetscCall(VecRestoreArray(ps->dirdiag, &dd));
  PetscCall(MPIU_Allreduce(&bad, &gbad, 1, MPIU_INT, MPI_MAX, ps->comm));
  PetscCheck(
      gbad < 0, ps->comm, PETSC_ERR_ARG_OUTOFRANGE,
      "pressure: beta = 1/rho must be positive and finite on open faces and beside Dirichlet walls; a rank found "
      "%g (%s)",
      (double)badBeta, bad >= 0 ? "this rank" : "another rank");

  if (ps->A) PetscCall(PffPressureAssembleOperator_Private(ps));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The assembled A and, for the ptap assembly, W = diag(M beta open) with its diagonal in place, so
   that A = G^T W G keeps one pattern. Created only when something needs entries: an AIJ Amat, a PC
   other than the matrix-free pffmg, or PffPressureGetOperator. */
PetscErrorCode PffPressureCreateOperator_Private(PffPressure ps)
{
  const PetscInt nrows = 3 * ps->ncells;

  PetscFunctionBeginUser;
  if (ps->A) PetscFunctionReturn(PETSC_SUCCESS);
  if (!ps->G) PetscCall(PffPressureBuildGradient_Private(ps));
  PetscCall(VecCreateMPI(ps->comm, nrows, 3 * ps->ntotal, &ps->w));
  PetscCall(MatCreateAIJ(ps->comm, nrows, nrows, 3 * ps->ntotal, 3 * ps->ntotal, 1, NULL, 0, NULL, &ps->W));
  for (PetscInt r = 0; r < nrows; r++) {
    const PetscInt row = 3 * ps->rstart + r;
    PetscCall(MatSetValue(ps->W, row, row, 1.0, INSERT_VALUES));
  }
  PetscCall(MatAssemblyBegin(ps->W, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(ps->W, MAT_FINAL_ASSEMBLY));
  PetscCall(MatPtAP(ps->W, ps->G, MAT_INITIAL_MATRIX, 2.0, &ps->A));
  PetscCall(MatSetOption(ps->A, MAT_NEW_NONZERO_LOCATION_ERR, PETSC_TRUE));
  PetscCall(MatSetOption(ps->A, MAT_SYMMETRIC, PETSC_TRUE));
  PetscCall(MatSetOption(ps->A, MAT_SYMMETRY_ETERNAL, PETSC_TRUE));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A from the current face coefficients and Dirichlet terms, its diagonal and null space. */
PetscErrorCode PffPressureAssembleOperator_Private(PffPressure ps)
{
  PetscScalar *w;

  PetscFunctionBeginUser;
  PetscCall(VecGetArrayWrite(ps->w, &w));
  for (PetscInt lb = 0; lb < ps->nlocal; lb++)
    for (PetscInt c = ps->blockStart[lb]; c < ps->blockStart[lb + 1]; c++)
      for (PetscInt d = 0; d < 3; d++) {
        const PetscReal df = PffPressureFaceDistance(ps->kind[3 * c + d], ps->hblock[lb]);
        w[3 * c + d]       = ps->cf[d * ps->ncells + c] * df * df;
      }
  PetscCall(VecRestoreArrayWrite(ps->w, &w));
  if (ps->assembly == PFF_PRESSURE_ASSEMBLY_PTAP) {
    PetscCall(MatDiagonalSet(ps->W, ps->w, INSERT_VALUES));
    PetscCall(MatPtAP(ps->W, ps->G, MAT_REUSE_MATRIX, 2.0, &ps->A));
  } else
    PetscCall(AssembleDirect(ps));
  if (PffPressureHasDirichlet_Private(ps)) PetscCall(MatDiagonalSet(ps->A, ps->dirdiag, ADD_VALUES));
  PetscCall(MatGetDiagonal(ps->A, ps->diag));
  PetscCall(PffPressureNullSpace_Private(ps));
  PetscFunctionReturn(PETSC_SUCCESS);
}
