/* Phase volumes for the conservation checks of the scene driver (issue 10): with the cell phase field
   phi of PF-FLIP Sec. 3.3 (Eq. 7, the mean over a cell's open faces),

     V_l = sum_c phi_c V_c,   V_g = sum_c (1 - phi_c) V_c,   V_c = h_c^3,

   over the fluid cells c: those with at least one open face (chOpen > 0 on any of the six). A cell
   with every face closed lies inside a solid; its phi is only the plain face mean that phase.c keeps
   there, so it counts for neither phase and V_l + V_g is the fluid volume of the domain. The upper
   faces of a cell are the lower faces of its +x, +y, +z neighbours, read through the halo of chOpen
   (current after PffFlowSetUp; across a domain wall the ghost is 0, a closed face). Serves the
   driver after each step; it does not update the phase field. */
#include "flowimpl.h"

PetscErrorCode PffFlowGetPhaseVolumes(PffFlow f, PetscReal *liquid, PetscReal *gas)
{
  PetscInt  nlocal;
  PetscReal loc[2] = {0, 0}; /* liquid, gas */

  PetscFunctionBeginUser;
  PetscCheck(f->setupcalled, f->comm, PETSC_ERR_ORDER, "PffFlowSetUp() must come before PffFlowGetPhaseVolumes()");
  PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo   info;
    const PffView *vopen[3];
    float         *phi;
    PetscReal      s[2] = {0, 0};

    PetscCall(PffGridGetBlockInfo(f->grid, lb, &info));
    PetscCall(PffGridGetBlockData(f->grid, f->chPhi, lb, 0, &phi));
    for (PetscInt d = 0; d < 3; d++) PetscCall(PffGridGetBlockViews(f->grid, f->chOpen, lb, d, &vopen[d]));
    const PetscInt n = info.n;
    for (PetscInt k = 0; k < n; k++)
      for (PetscInt j = 0; j < n; j++)
        for (PetscInt i = 0; i < n; i++) {
          if (!PffFlowCellOpen_Private(vopen, i, j, k, n)) continue;
          const PetscReal p = (PetscReal)phi[i + n * (j + n * k)];
          s[0] += p;
          s[1] += 1 - p;
        }
    const PetscReal v = info.h * info.h * info.h;
    loc[0] += s[0] * v;
    loc[1] += s[1] * v;
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, loc, 2, MPIU_REAL, MPI_SUM, f->comm));
  if (liquid) *liquid = loc[0];
  if (gas) *gas = loc[1];
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Where the liquid is, over the same fluid cells: the largest x and y reached by a cell with phi >= 1/2 (its
   upper face) and the centroid sum phi V x_c / sum phi V. */
PetscErrorCode PffFlowGetLiquidExtent(PffFlow f, PetscReal front[2], PetscReal centroid[3])
{
  PetscInt  nlocal;
  PetscReal mx[2] = {-PETSC_MAX_REAL, -PETSC_MAX_REAL}, s[4] = {0, 0, 0, 0};

  PetscFunctionBeginUser;
  PetscCheck(f->setupcalled, f->comm, PETSC_ERR_ORDER, "PffFlowSetUp() must come before PffFlowGetLiquidExtent()");
  PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo   info;
    const PffView *vopen[3];
    float         *phi;
    PetscCall(PffGridGetBlockInfo(f->grid, lb, &info));
    PetscCall(PffGridGetBlockData(f->grid, f->chPhi, lb, 0, &phi));
    for (PetscInt d = 0; d < 3; d++) PetscCall(PffGridGetBlockViews(f->grid, f->chOpen, lb, d, &vopen[d]));
    const PetscInt  n = info.n;
    const PetscReal h = info.h, v = h * h * h;
    for (PetscInt k = 0; k < n; k++)
      for (PetscInt j = 0; j < n; j++)
        for (PetscInt i = 0; i < n; i++) {
          if (!PffFlowCellOpen_Private(vopen, i, j, k, n)) continue;
          const PetscReal p    = (PetscReal)phi[i + n * (j + n * k)];
          const PetscReal x[3] = {info.lo[0] + (i + 0.5) * h, info.lo[1] + (j + 0.5) * h, info.lo[2] + (k + 0.5) * h};
          if (p >= 0.5) {
            mx[0] = PetscMax(mx[0], x[0] + 0.5 * h);
            mx[1] = PetscMax(mx[1], x[1] + 0.5 * h);
          }
          for (int a = 0; a < 3; a++) s[a] += p * v * x[a];
          s[3] += p * v;
        }
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, mx, 2, MPIU_REAL, MPI_MAX, f->comm));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, s, 4, MPIU_REAL, MPI_SUM, f->comm));
  for (int a = 0; a < 2; a++) front[a] = mx[a] > -PETSC_MAX_REAL ? mx[a] : 0;
  for (int a = 0; a < 3; a++) centroid[a] = s[3] > 0 ? s[a] / s[3] : 0;
  PetscFunctionReturn(PETSC_SUCCESS);
}
