/* Phase field (PF-FLIP Sec. 3.3, Eq. 7) from the raw face densities of P2G, cell tags, face
   densities and coefficients (Eq. 9).

   chMass holds rho~ normalised so that a uniform lattice of liquid particles gives rho_l rho~_0
   (see PffParticlesP2G); Eq. 7 is then applied literally with rho~_min = eta_phi rho_g rho~_0 and
   eta_phi = log(rho_l / rho_g). A cell's phase value is the mean over its open faces; cells below
   1/2 are air. Faces between two liquid cells get phi = 1, between two air cells phi = 0, and cells
   whose faces are then all 1 (0) get 1 (0). */
#include "flowimpl.h"

static inline PetscReal PffPhi(PetscReal rt, PetscReal rtmin, PetscReal scale)
{
  if (rt < rtmin) return 0;
  return PetscMin(PetscSqrtReal(PetscMax(rt - rtmin, 0) / scale), 1.0);
}

/* The mean of one cell from its faces: lo[d], hi[d] the face phi below and above it along axis d, olo, ohi their open
   fractions, into *out; with bulkOnly a cell whose open faces are not all 1 or all 0 is left alone. */
static inline void PffCellMean(const PetscReal lo[3], const PetscReal hi[3], const PetscReal olo[3],
                               const PetscReal ohi[3], PetscBool perAxis, PetscBool bulkOnly, float *out)
{
  PetscReal sum = 0, w = 0, all = 0, lo1 = 1, hi0 = 0, axes = 0, naxes = 0;
  for (PetscInt d = 0; d < 3; d++) {
    sum += olo[d] * lo[d] + ohi[d] * hi[d];
    w += olo[d] + ohi[d];
    if (perAxis && olo[d] + ohi[d] > 0) {
      axes += (olo[d] * lo[d] + ohi[d] * hi[d]) / (olo[d] + ohi[d]);
      naxes++;
    }
    all += lo[d] + hi[d];
    if (olo[d] > 0) {
      lo1 = PetscMin(lo1, lo[d]);
      hi0 = PetscMax(hi0, lo[d]);
    }
    if (ohi[d] > 0) {
      lo1 = PetscMin(lo1, hi[d]);
      hi0 = PetscMax(hi0, hi[d]);
    }
  }
  if (bulkOnly && !(w > 0 && (lo1 == 1 || hi0 == 0))) return;
  *out = (float)(w > 0 ? (perAxis ? axes / naxes : sum / w) : all / 6);
}

/* Cell phi = mean of the face phi over the cell's open faces (chPhiF's halo current); a cell with every
   face closed (inside a solid) keeps the plain mean. With bulkOnly only cells whose open faces are all 1
   (or all 0) are set, the others keep their value. The liquid model takes the mean over the axes of each
   axis' mean instead: its level set reads phi at the free surface, where the vertical faces differ from the
   horizontal ones, and the plain mean weighs them otherwise in a cell beside a wall (one side face fewer):
   a still pool's surface cells read 0.930 at the walls against 0.939 inside, and the pool moved at 1.2e-2 m/s.
   Cells whose upper faces lie in the block read the block's own storage; the others go through the views. */
static PetscErrorCode PffFlowCellPhase(PffFlow f, PetscInt nlocal, PetscBool bulkOnly)
{
  const PetscBool perAxis = (PetscBool)(f->model == PFF_FLOW_LIQUID);

  PetscFunctionBeginUser;
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo   info;
    const PffView *vphi[3], *vopen[3];
    float         *cell, *phi[3], *open[3];
    PetscCall(PffGridGetBlockInfo(f->grid, lb, &info));
    PetscCall(PffGridGetBlockData(f->grid, f->chPhi, lb, 0, &cell));
    for (PetscInt d = 0; d < 3; d++) {
      PetscCall(PffGridGetBlockViews(f->grid, f->chPhiF, lb, d, &vphi[d]));
      PetscCall(PffGridGetBlockViews(f->grid, f->chOpen, lb, d, &vopen[d]));
      PetscCall(PffGridGetBlockData(f->grid, f->chPhiF, lb, d, &phi[d]));
      PetscCall(PffGridGetBlockData(f->grid, f->chOpen, lb, d, &open[d]));
    }
    const PetscInt n = info.n, st[3] = {1, n, n * n};
    for (PetscInt k = 0; k < n; k++)
      for (PetscInt j = 0; j < n; j++)
        for (PetscInt i = 0; i < n; i++) {
          const PetscInt c = i + n * (j + n * k);
          PetscReal      lo[3], hi[3], olo[3], ohi[3];
          if (i < n - 1 && j < n - 1 && k < n - 1)
            for (PetscInt d = 0; d < 3; d++) {
              lo[d]  = phi[d][c];
              hi[d]  = phi[d][c + st[d]];
              olo[d] = open[d][c];
              ohi[d] = open[d][c + st[d]];
            }
          else
            for (PetscInt d = 0; d < 3; d++) {
              const PetscInt e[3] = {d == 0, d == 1, d == 2};
              lo[d]               = *PffViewsAt(vphi[d], i, j, k, n);
              hi[d]               = *PffViewsAt(vphi[d], i + e[0], j + e[1], k + e[2], n);
              olo[d]              = *PffViewsAt(vopen[d], i, j, k, n);
              ohi[d]              = *PffViewsAt(vopen[d], i + e[0], j + e[1], k + e[2], n);
            }
          PffCellMean(lo, hi, olo, ohi, perAxis, bulkOnly, &cell[c]);
        }
  }
  PetscCall(PffGridHaloBegin(f->grid, f->chPhi));
  PetscCall(PffGridHaloEnd(f->grid, f->chPhi));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* face phi from the raw density (Eq. 7), normalised by the lattice reference */
static PetscErrorCode PffFlowRawPhase(PffFlow f, PetscInt nlocal)
{
  const PetscReal eta = PetscLogReal(f->rho[0] / f->rho[1]), rtmin = eta * f->rho[1] * f->rho0,
                  scale = f->alphaPhi * f->rho0 * f->rho[0];

  PetscFunctionBeginUser;
  const PetscInt ch[3] = {f->chMass, f->chPhiF, f->chMassRef};
  for (PetscInt lb = 0; lb < nlocal; lb++)
    for (PetscInt d = 0; d < 3; d++) {
      float   *a[3];
      PetscInt n3 = 0;
      PetscCall(PffFlowBlockData_Private(f, lb, d, 3, ch, a, &n3));
      for (PetscInt c = 0; c < n3; c++) {
        /* rho~ as the full kernel would see it: beside walls, solids and level boundaries the lattice
           reference (correction.c) is below rho~_0, and a uniform fluid would look rarefied there */
        const PetscReal norm = a[2][c] > 0 ? f->rho0 / (PetscReal)a[2][c] : 1;
        a[1][c]              = (float)PffPhi(a[0][c] * norm, rtmin, scale);
      }
    }
  PetscCall(PffGridHaloBegin(f->grid, f->chPhiF));
  PetscCall(PffGridHaloEnd(f->grid, f->chPhiF));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffFlowPhaseField_Private(PffFlow f)
{
  PetscInt nlocal;

  PetscFunctionBeginUser;
  PetscCall(PetscLogEventBegin(PFF_PhaseField, 0, 0, 0, 0));
  PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
  PetscCall(PffFlowRawPhase(f, nlocal));
  PetscCall(PffFlowCellPhase(f, nlocal, PETSC_FALSE));
  /* tags clean the face values away from the interface; density and beta follow (Eq. 9) */
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo   info;
    const PffView *vcell;
    PetscCall(PffGridGetBlockInfo(f->grid, lb, &info));
    PetscCall(PffGridGetBlockViews(f->grid, f->chPhi, lb, 0, &vcell));
    const PetscInt n = info.n;
    for (PetscInt d = 0; d < 3; d++) {
      float *phi, *beta = NULL, *open;
      PetscCall(PffGridGetBlockData(f->grid, f->chPhiF, lb, d, &phi));
      if (f->chBeta >= 0) PetscCall(PffGridGetBlockData(f->grid, f->chBeta, lb, d, &beta));
      PetscCall(PffGridGetBlockData(f->grid, f->chOpen, lb, d, &open));
      for (PetscInt k = 0; k < n; k++)
        for (PetscInt j = 0; j < n; j++)
          for (PetscInt i = 0; i < n; i++) {
            const PetscInt c = i + n * (j + n * k);
            PetscBool      mine, lower;
            PffFlowFaceTags_Private(vcell, i, j, k, d, n, &lower, &mine);
            /* across a closed face (wall, solid) the other side is not fluid: use this cell's tag */
            const PetscBool other = open[c] > 0 ? lower : mine;
            if (mine && other)
              phi[c] = 1;
            else if (!mine && !other)
              phi[c] = 0;
          }
      if (beta) { /* after the tags, in a loop of its own that vectorises its divisions */
        const PetscReal rg = f->rho[1], dr = f->rho[0] - f->rho[1];
        const PetscInt  n3 = n * n * n;
#pragma omp simd
        for (PetscInt c = 0; c < n3; c++) beta[c] = (float)(1.0 / (rg + (PetscReal)phi[c] * dr));
      }
    }
  }
  /* cells whose faces are all cleaned to 1 (0) become exactly 1 (0), so FLIP noise in the bulk (where the
     clamp of Eq. 7 cuts only the upper half of the fluctuations) does not bias sum(phi V) or the
     escaped-particle test; interface cells keep the raw mean (the rt3d spike tip reads their phi = 1/2) */
  PetscCall(PffGridHaloBegin(f->grid, f->chPhiF));
  PetscCall(PffGridHaloEnd(f->grid, f->chPhiF));
  PetscCall(PffFlowCellPhase(f, nlocal, PETSC_TRUE));
  PetscCall(PetscLogEventEnd(PFF_PhaseField, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}
