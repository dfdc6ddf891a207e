/* The liquid model's volume correction (docs/tallcell.md, "Volume correction of the liquid model").

   Inside a tall cell the projected velocity is divergence-free only on average over the tall cell, so the
   particles there drift apart in some cubic cells and crowd in others; the crowded cells still read phi = 1, the
   rarefied ones less, and the liquid's phase-field volume falls (uniform tall cells lost 7 % and the quadtree 12 %
   in 0.4 s of the breaking dam, cubic cells 0.2 %). The correction moves particles from over-dense to under-dense
   cells by a displacement d added to the liquid's advection velocity as d / dt, as the two-phase correction does
   (correction.c), but local: one Jacobi step of D d = kappa (s - 1) from a zero potential,

     d = kappa h / 6 (e_lo - e_hi)  on the face between cells lo and hi (along +axis), e = s - 1,

   which removes the share kappa of an isolated cell's excess per step (a cell's e changes by -kappa/6 times the sum
   of its 6 differences: monotone for kappa <= 1). Only interior cells, whose 6 neighbours are liquid too, have a
   target: a surface cell is partly full by nature, and a target there would fill it from below and expand the
   liquid. A face between an interior cell and another cell takes e = 0 on the other side, so a crowded interior
   cell spreads into a surface cell (the surface rises) and a rarefied one draws from it (the surface falls). Cells
   whose centre lies in a solid or whose lattice target is less than half a fluid cell's have no target, and d on
   a face is scaled by its open fraction. Near moving bodies
   the lattice target follows their poses (PffFlowReferenceBodies_Private): the particles a body pushes out of
   itself pile up at its surface, and this spreads them again. No solve: the tall cells' own system is too coarse
   to see the cubic cells' imbalance, and a cubic one would cost what the tall cells save. */
#include "flowimpl.h"

#define PFF_LIQCORR_FREE (-1000.0f) /* not an interior cell; any resampled mix with it stays below -1 */

/* e = s - 1 of the interior cells into chCdiv, PFF_LIQCORR_FREE elsewhere; counts and sums of e for the log */
static PetscErrorCode LiquidExcess(PffFlow f, PetscReal sums[3])
{
  PetscInt nlocal;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo   info;
    const PffView *vw[3], *vr[3], *vo[3], *vls;
    float         *e, *sd = NULL;
    PetscCall(PffGridGetBlockInfo(f->grid, lb, &info));
    PetscCall(PffGridGetBlockData(f->grid, f->chCdiv, lb, 0, &e));
    PetscCall(PffGridGetBlockViews(f->grid, f->chLS, lb, 0, &vls));
    if (f->chSolidD >= 0) PetscCall(PffGridGetBlockData(f->grid, f->chSolidD, lb, 0, &sd));
    for (PetscInt d = 0; d < 3; d++) {
      PetscCall(PffGridGetBlockViews(f->grid, f->chVol, lb, d, &vw[d]));
      PetscCall(PffGridGetBlockViews(f->grid, f->chVolRef, lb, d, &vr[d]));
      PetscCall(PffGridGetBlockViews(f->grid, f->chOpen, lb, d, &vo[d]));
    }
    const PetscInt  n    = info.n;
    const PetscReal full = PFF_PARTICLES_PER_AXIS * PFF_PARTICLES_PER_AXIS * PFF_PARTICLES_PER_AXIS;
    for (PetscInt k = 0; k < n; k++)
      for (PetscInt j = 0; j < n; j++)
        for (PetscInt i = 0; i < n; i++) {
          const PetscInt  c = i + n * (j + n * k);
          const PetscBool interior =
              (PetscBool)(*PffViewsAt(vls, i, j, k, n) < 0 && !(sd && sd[c] < 0) &&
                          PffFlowFaceNeighbours_Private(&info, vls, i, j, k, n, 0, PETSC_FALSE) == 6);
          PetscReal w = 0, wref = 0;
          PetscInt  nopen = 0;
          if (interior) PffFlowCellVolumes_Private(vw, vr, vo, i, j, k, n, &w, &wref, &nopen);
          /* a face inside the fluid has W_ref = 8 (the lattice's 8 particles per cell, of unit volume at their
             block's level, trilinear weights); a cell that a solid cuts deeply has a target of a few lattice
             particles, and s is their noise */
          if (!interior || !(wref >= 0.5 * (PetscReal)nopen * full)) {
            e[c] = PFF_LIQCORR_FREE;
            continue;
          }
          e[c] = (float)(w / wref - 1);
          sums[0] += 1;
          sums[1] += e[c];
          sums[2] += e[c] * e[c];
        }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* chUa = chUl + d / dt on every owned face, d bounded by -flow_volume_correction_max_displacement cells */
static PetscErrorCode LiquidDisplacement(PffFlow f, PetscReal dt)
{
  PetscInt nlocal;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetLocalBlocks(f->grid, &nlocal));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo   info;
    const PffView *ve;
    PetscCall(PffGridGetBlockInfo(f->grid, lb, &info));
    PetscCall(PffGridGetBlockViews(f->grid, f->chCdiv, lb, 0, &ve));
    const PetscInt  n    = info.n;
    const PetscReal gain = f->volCorr * info.h / 6, bound = f->volCorrMaxDisp * info.h, idt = 1.0 / dt;
    for (PetscInt d = 0; d < 3; d++) {
      const PetscInt ch[3] = {f->chUl, f->chUa, f->chOpen};
      float         *a[3];
      PetscCall(PffFlowBlockData_Private(f, lb, d, 3, ch, a, NULL));
      const float *ul = a[0], *open = a[2];
      float       *ua = a[1];
      for (PetscInt k = 0; k < n; k++)
        for (PetscInt j = 0; j < n; j++)
          for (PetscInt i = 0; i < n; i++) {
            const PetscInt c  = i + n * (j + n * k);
            PetscReal      dd = 0;
            if (open[c] > 0) {
              const PetscReal ehi = *PffViewsAt(ve, i, j, k, n);
              const PetscReal elo = *PffViewsAt(ve, i - (d == 0), j - (d == 1), k - (d == 2), n);
              const PetscBool hi = (PetscBool)(ehi >= -1), lo = (PetscBool)(elo >= -1);
              if (hi || lo) dd = gain * ((lo ? elo : 0) - (hi ? ehi : 0));
              dd = open[c] * PetscMax(-bound, PetscMin(bound, dd));
            }
            ua[c] = (float)(ul[c] + idt * dd);
          }
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* After the liquid model's G2P (chUl holds the extrapolated liquid velocity): chUa, the liquid's advection
   velocity with the displacement. Collective. */
PetscErrorCode PffFlowLiquidCorrection_Private(PffFlow f, PetscReal dt)
{
  PetscReal sums[3] = {0, 0, 0};

  PetscFunctionBeginUser;
  PetscCall(PffGridHaloBegin(f->grid, f->chVol));
  PetscCall(PffGridHaloBegin(f->grid, f->chLS));
  PetscCall(PffGridHaloEnd(f->grid, f->chVol));
  PetscCall(PffGridHaloEnd(f->grid, f->chLS));
  PetscCall(LiquidExcess(f, sums));
  PetscCall(PffGridHaloBegin(f->grid, f->chCdiv));
  PetscCall(PffGridHaloEnd(f->grid, f->chCdiv));
  PetscCall(LiquidDisplacement(f, dt));
  PetscCall(PffGridHaloBegin(f->grid, f->chUa));
  PetscCall(PffGridHaloEnd(f->grid, f->chUa));
  if (PetscLogPrintInfo) {
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, sums, 3, MPIU_REAL, MPI_SUM, f->comm));
    const PetscReal m = sums[0] > 0 ? sums[1] / sums[0] : 0;
    PetscCall(PetscInfo(NULL, "liquid volume correction: %.0f interior cells, mean s - 1 %.3e, rms %.3e\n",
                        (double)sums[0], (double)m, (double)(sums[0] > 0 ? PetscSqrtReal(sums[2] / sums[0]) : 0)));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
