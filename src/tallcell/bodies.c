/* Two-way coupled rigid bodies in the variational tall-cell pressure (tall cells Sec. 4.4, Eq. 6-14, after
   Batty et al. 2007).

   For body b and a liquid cell c of size s at centre x, with A' the fraction of each of the cell's faces that
   the body covers (the same corner rule as the open fractions),
     J_c = s^2 (dA_x, dA_y, dA_z, r x dA),   dA_a = A'(upper a-face) - A'(lower a-face),   r = x - X_com,
   is the body's share of the cell's boundary (Eq. 8-13): (J_c . w) is the volume the body's motion w = (v,
   omega) pushes out of the cell per unit time, and p_c J_c the force and torque the cell's pressure exerts on
   the body (Eq. 6-7). The cell pressures come from the samples through the column functions, p_c = P_c p, so
   on the samples J = J_cells P (6 x samples). Minimising the kinetic energy of liquid and bodies under
   incompressibility gives
     ([grad]^T V A F [grad] + rho J^T M^-1 J) p = (rho / dt) ([grad]^T V A u* - J^T w*),
     u = u* - dt / rho F [grad] p,   w = w* + dt M^-1 J p,
   Eq. 14 in our scaling. The coupling term is dense among the samples around a body but has rank 6 per body,
   so the operator is PETSc's MATLRC, A + U diag(rho) U^T with U = J^T L (L L^T = M^-1), and the
   preconditioner is built from A alone. */
#include "tallimpl.h"

PetscErrorCode PffTallSetBodies(PffTall tc, PetscInt n, PffTallBody *bodies)
{
  PetscFunctionBeginUser;
  PetscCheck(n >= 0 && (n == 0 || bodies), tc->comm, PETSC_ERR_ARG_WRONG, "tallcell: %" PetscInt_FMT " bodies", n);
  for (PetscInt b = 0; b < n; b++)
    PetscCheck(bodies[b].mass > 0 && PetscIsNormalReal(bodies[b].mass), tc->comm, PETSC_ERR_ARG_OUTOFRANGE,
               "tallcell: body %" PetscInt_FMT ": mass %g must be positive", b, (double)bodies[b].mass);
  tc->nbodies = n;
  tc->bodies  = bodies;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Lower-triangular L with L L^T = M^-1 for the body's mass matrix M = diag(m, m, m, I) (I about the centre of
   mass, world frame): the translational block is 1 / sqrt(m), the rotational one the Cholesky factor of I^-1. */
static PetscErrorCode MassFactor(const PffTallBody *body, PetscReal L[6][6])
{
  PetscReal inv[3][3], det;
  const PetscReal(*In)[3] = body->inertia;

  PetscFunctionBeginUser;
  PetscCall(PetscMemzero(L, sizeof(PetscReal) * 36));
  for (PetscInt a = 0; a < 3; a++) L[a][a] = 1 / PetscSqrtReal(body->mass);
  det = In[0][0] * (In[1][1] * In[2][2] - In[1][2] * In[2][1]) -
        In[0][1] * (In[1][0] * In[2][2] - In[1][2] * In[2][0]) + In[0][2] * (In[1][0] * In[2][1] - In[1][1] * In[2][0]);
  PetscCheck(det > 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "tallcell: a body's inertia tensor is not positive");
  for (PetscInt i = 0; i < 3; i++)
    for (PetscInt j = 0; j < 3; j++) {
      const PetscInt i1 = (j + 1) % 3, i2 = (j + 2) % 3, j1 = (i + 1) % 3, j2 = (i + 2) % 3;
      inv[i][j] = (In[i1][j1] * In[i2][j2] - In[i1][j2] * In[i2][j1]) / det; /* adjugate: cofactor (j, i) */
    }
  for (PetscInt j = 0; j < 3; j++) /* Cholesky of inv */
    for (PetscInt i = j; i < 3; i++) {
      PetscReal v = inv[i][j];
      for (PetscInt k = 0; k < j; k++) v -= L[3 + i][3 + k] * L[3 + j][3 + k];
      if (i == j) {
        PetscCheck(v > 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
                   "tallcell: a body's inertia tensor is not positive definite");
        L[3 + i][3 + j] = PetscSqrtReal(v);
      } else
        L[3 + i][3 + j] = v / L[3 + j][3 + j];
    }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* J of body b on the samples: 6 Vecs, from every liquid cell of the owned columns within one cell of the body's
   bounding box. */
static PetscErrorCode BodyJacobian(PffTall tc, const PffTallBody *body, Vec J[6])
{
  PetscFunctionBeginUser;
  for (PetscInt n = 0; n < 6; n++) PetscCall(VecSet(J[n], 0));
  for (PetscInt bc = 0; bc < tc->nbc; bc++) {
    if (tc->bcOwner[bc] != tc->rank) continue;
    const PetscInt  bi = bc % tc->nb[0], bk = bc / tc->nb[0], l = tc->bcLevel[bc], n = tc->n0 >> l, ny = tc->nb[1] * n;
    const PetscReal s = tc->h0 * (PetscReal)(1 << l);
    PetscInt        lo[3], hi[3];
    const PetscInt  base[3] = {bi * n, 0, bk * n}, top[3] = {(bi + 1) * n, ny, (bk + 1) * n};
    for (PetscInt a = 0; a < 3; a++) { /* the cells of this block column within one cell of the bounding box */
      lo[a] = PetscMax(base[a], (PetscInt)PetscFloorReal((body->lo[a] - tc->origin[a]) / s) - 1);
      hi[a] = PetscMin(top[a], (PetscInt)PetscCeilReal((body->hi[a] - tc->origin[a]) / s) + 1);
    }
    for (PetscInt gk = lo[2]; gk < hi[2]; gk++)
      for (PetscInt gi = lo[0]; gi < hi[0]; gi++)
        for (PetscInt j = lo[1]; j < hi[1]; j++) {
          const PetscInt   rec  = tc->bcOffset[bc] + ((gk - base[2]) * n + (gi - base[0])) * ny + j;
          const PetscInt  *ri   = tc->ri + PFF_TALL_RI * rec;
          const PetscReal *rr   = tc->rr + PFF_TALL_RR * rec;
          const PetscInt   g[3] = {gi, j, gk};
          PetscReal        corner[8], x[3], grad[3], jc[6], dA[3], r[3];
          if (!PffTallLiquidKind(ri[4])) continue;
          for (PetscInt v = 0; v < 8; v++) {
            for (PetscInt a = 0; a < 3; a++) x[a] = tc->origin[a] + (PetscReal)(g[a] + ((v >> a) & 1)) * s;
            corner[v] = body->fn(x, grad, body->ctx);
          }
          for (PetscInt a = 0; a < 3; a++) { /* the covered fractions 1 - open of the upper and the lower face */
            if (a != 1)
              dA[a] = s * s * ((1 - PffTallCellFaceOpen(corner, a, 1)) - (1 - PffTallCellFaceOpen(corner, a, 0)));
            r[a] = tc->origin[a] + ((PetscReal)g[a] + 0.5) * s - body->X[a];
          }
          { /* y-faces over their control volumes, as PffTallFillSolid fills them (their own area without a crossing) */
            PetscReal lvl[3][4], face[2][4], open[2];
            for (PetscInt q = 0; q < 4; q++) {
              const PetscInt dx = q >= 2, dz = q == 1 || q == 2;
              x[0] = tc->origin[0] + (PetscReal)(gi + dx) * s;
              x[2] = tc->origin[2] + (PetscReal)(gk + dz) * s;
              for (PetscInt e = 0; e < 3; e++) { /* the centre heights of the cells below, this one and above */
                x[1]      = tc->origin[1] + ((PetscReal)j - 0.5 + (PetscReal)e) * s;
                lvl[e][q] = body->fn(x, grad, body->ctx);
              }
              for (PetscInt side = 0; side < 2; side++) face[side][q] = corner[(side << 1) | (dz << 2) | dx];
            }
            for (PetscInt side = 0; side < 2; side++) {
              x[0]       = tc->origin[0] + (PetscReal)gi * s;
              x[1]       = tc->origin[1] + (PetscReal)(j + side) * s;
              x[2]       = tc->origin[2] + (PetscReal)gk * s;
              open[side] = PffTallYFaceOpen_Private(body->fn, body->ctx, x, s, lvl[side], face[side], lvl[side + 1]);
            }
            dA[1] = s * s * ((1 - open[1]) - (1 - open[0]));
          }
          if (dA[0] == 0 && dA[1] == 0 && dA[2] == 0) continue;
          jc[0] = dA[0];
          jc[1] = dA[1];
          jc[2] = dA[2];
          jc[3] = r[1] * dA[2] - r[2] * dA[1];
          jc[4] = r[2] * dA[0] - r[0] * dA[2];
          jc[5] = r[0] * dA[1] - r[1] * dA[0];
          { /* p_c from the samples: the column function at the centre */
            PetscInt  id[2];
            PetscReal w[2];
            PffTallCentreWeights(ri, rr, tc->origin[1] + ((PetscReal)j + 0.5) * s, id, w);
            for (PetscInt q = 0; q < 2; q++) {
              if (id[q] < 0 || w[q] == 0) continue;
              for (PetscInt m = 0; m < 6; m++) PetscCall(VecSetValue(J[m], id[q], w[q] * jc[m], ADD_VALUES));
            }
          }
        }
  }
  for (PetscInt m = 0; m < 6; m++) {
    PetscCall(VecAssemblyBegin(J[m]));
    PetscCall(VecAssemblyEnd(J[m]));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffTallBuildBodies_Private(PffTall tc)
{
  PetscInt     k = 6 * tc->nbodies, mloc;
  PetscScalar *u;

  PetscFunctionBeginUser;
  tc->nbodiesBuilt = tc->nbodies;
  if (!tc->nbodies) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(VecDuplicateVecs(tc->p, k, &tc->J));
  PetscCall(VecGetLocalSize(tc->p, &mloc));
  PetscCall(MatCreateDense(tc->comm, mloc, PETSC_DECIDE, PETSC_DETERMINE, k, NULL, &tc->U));
  PetscCall(PetscMalloc1(tc->nbodies, &tc->massL));
  PetscCall(MatDenseGetArrayWrite(tc->U, &u));
  for (PetscInt i = 0; i < k * mloc; i++) u[i] = 0;
  for (PetscInt b = 0; b < tc->nbodies; b++) {
    PetscReal(*L)[6] = tc->massL[b];
    PetscCall(MassFactor(&tc->bodies[b], L));
    PetscCall(BodyJacobian(tc, &tc->bodies[b], &tc->J[6 * b]));
    for (PetscInt n = 0; n < 6; n++) {
      const PetscScalar *jn;
      PetscCall(VecGetArrayRead(tc->J[6 * b + n], &jn));
      for (PetscInt c = 0; c < 6; c++) /* U[:, 6b + c] = sum_n J_n L[n][c] */
        if (L[n][c] != 0)
          for (PetscInt i = 0; i < mloc; i++) u[(6 * b + c) * mloc + i] += jn[i] * L[n][c];
      PetscCall(VecRestoreArrayRead(tc->J[6 * b + n], &jn));
    }
  }
  PetscCall(MatDenseRestoreArrayWrite(tc->U, &u));
  PetscCall(MatAssemblyBegin(tc->U, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(tc->U, MAT_FINAL_ASSEMBLY));
  PetscCall(VecCreateSeq(PETSC_COMM_SELF, k, &tc->lrcC));
  PetscCall(VecSet(tc->lrcC, 1.0)); /* rho is set by each Project */
  PetscCall(MatCreateLRC(tc->A, tc->U, tc->lrcC, NULL, &tc->N));
  {
    MatNullSpace nsp; /* a closed tank: constants stay a null space, since J 1 = 0 around a body */
    PetscCall(MatGetNullSpace(tc->A, &nsp));
    if (nsp) PetscCall(MatSetNullSpace(tc->N, nsp));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffTallBodiesRHS_Private(PffTall tc, PetscReal dt, PetscReal rho)
{
  PetscFunctionBeginUser;
  if (!tc->nbodiesBuilt) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(VecSet(tc->lrcC, rho));
  for (PetscInt b = 0; b < tc->nbodiesBuilt; b++) { /* b -= (rho / dt) J^T w* */
    PetscScalar alpha[6];
    for (PetscInt n = 0; n < 6; n++) alpha[n] = -rho / dt * tc->bodies[b].w[n];
    PetscCall(VecMAXPY(tc->b, 6, alpha, &tc->J[6 * b]));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffTallBodiesUpdate_Private(PffTall tc, PetscReal dt)
{
  PetscFunctionBeginUser;
  for (PetscInt b = 0; b < tc->nbodiesBuilt; b++) {
    PffTallBody *body = &tc->bodies[b];
    PetscScalar  f[6];
    PetscReal    lf[6];
    PetscReal(*L)[6] = tc->massL[b];
    PetscCall(VecMDot(tc->p, 6, &tc->J[6 * b], f));
    for (PetscInt c = 0; c < 6; c++) { /* M^-1 f = L (L^T f) */
      lf[c] = 0;
      for (PetscInt n = 0; n < 6; n++) lf[c] += L[n][c] * PetscRealPart(f[n]);
    }
    for (PetscInt n = 0; n < 6; n++) {
      PetscReal minvf = 0;
      for (PetscInt c = 0; c < 6; c++) minvf += L[n][c] * lf[c];
      body->force[n] = PetscRealPart(f[n]);
      body->w[n] += dt * minvf;
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffTallFreeBodies_Private(PffTall tc)
{
  PetscFunctionBeginUser;
  if (tc->J) PetscCall(VecDestroyVecs(6 * tc->nbodiesBuilt, &tc->J));
  tc->nbodiesBuilt = 0;
  PetscCall(PetscFree(tc->massL));
  PetscCall(MatDestroy(&tc->U));
  PetscCall(MatDestroy(&tc->N));
  PetscCall(VecDestroy(&tc->lrcC));
  PetscFunctionReturn(PETSC_SUCCESS);
}
