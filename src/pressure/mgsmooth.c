/* pffmg smoothers (PF-FLIP Sec. 6.3-6.4, Algorithm 2).

   Two-stage red-black hybrid Gauss-Seidel: the blocks of one colour ((x_b + y_b + z_b) mod 2) are
   relaxed in parallel while the other colour is frozen, so a block reads its face neighbours in
   place and no second buffer is needed; inside a block the cells are relaxed in place, red cells
   then black, each update delta = omega (b_j - A_j x) / a_jj with omega = 6/7. Off-rank neighbours
   are read from a ghost copy refreshed once per block colour (one exchange per half-sweep).

   Adaptive relaxation (Algorithm 2): a list of active blocks, initially the relevant ones of the
   level; an active block is relaxed repeatedly until its largest update falls by 1/3 (or k_max
   sweeps), and stays active when its effective residual -- the largest |delta| a_jj of its cells,
   which equalises the air and water phases -- exceeds theta; a face neighbour joins when the
   effective residual on the shared border exceeds theta (across ranks too, through a PetscSF between
   neighbouring ranks). theta is the mean plus
   two standard deviations of log10 of the per-block maxima of the initial effective residual, the
   omega |b_j - A_j x| each block sees in its first sweep. The loop ends after a fixed number of steps; the result is
   not a symmetric operator, which is why the Krylov method is flexible CG. The blocks of one colour are
   relaxed by the OpenMP threads in parallel, in fixed sweeps and in adaptive relaxation. */
#include "mgimpl.h"
#include <omp.h>
#include <petscsf.h>

const char *const PffMGSmootherTypes[] = {"rbgs", "jacobi", "PffMGSmootherType", "PFF_MG_SMOOTHER_", NULL};

/* Both smoothers split the ghost exchange of a half-sweep (PffMGGhostsBegin_Private, PffMGGhostsEnd_Private): blocks
   without an off-rank neighbour are relaxed between Begin and End. In a half-sweep of colour c the values other ranks
   need from us for their colour-c blocks are our colour 1-c cells, which this half-sweep does not change. */

/* Relaxes rows order[q0..q1) in place; R (or NULL) receives |delta| a_jj per row, indexed from the
   block's first row. Returns the largest |delta| a_jj. */
static inline PetscReal RelaxRows(const PffMGLevel *lv, PetscInt q0, PetscInt q1, PetscInt row0, const PetscScalar *b,
                                  PetscScalar *x, const PetscScalar *g, PetscReal omega, PetscReal *R)
{
  PetscReal rmax = 0;
  for (PetscInt q = q0; q < q1; q++) {
    const PetscInt i = lv->order[q];
    PetscScalar    s = b[i];
    for (PetscInt k = lv->ai[i]; k < lv->ai[i + 1]; k++) s -= lv->aa[k] * x[lv->aj[k]];
    if (g)
      for (PetscInt k = lv->bi[i]; k < lv->bi[i + 1]; k++) s -= lv->ba[k] * g[lv->bj[k]];
    x[i] += omega * s * lv->idiag[i];
    const PetscReal eff = lv->idiag[i] != 0 ? PetscAbsScalar(omega * s) : 0.0;
    if (R) R[i - row0] = eff;
    rmax = PetscMax(rmax, eff);
  }
  return rmax;
}

/* Largest R over the cells of face f (0..5: -x, +x, -y, +y, -z, +z) of an n^3 block. */
static PetscReal FaceMax(const PetscReal *R, PetscInt n, PetscInt f)
{
  PetscReal m = 0;
  for (PetscInt v = 0; v < n; v++)
    for (PetscInt u = 0; u < n; u++) {
      PetscInt c[3];
      PffBlockSideCell(f, (f % 2) ? n - 1 : 0, u, v, c);
      m = PetscMax(m, R[c[0] + n * (c[1] + n * c[2])]);
    }
  return m;
}

/* One visit of local block lb: in-place red-black sweeps, one, or in adaptive relaxation until the update
   falls by 1/3 (at most maxSweeps). A matrix-free level folds the side couplings into the block's
   right-hand side bb once for the visit
   (PffMGStencilBlockRhs_Private); an AIJ level relaxes its permuted rows. first receives the first
   sweep's largest |delta| a_jj, the return value the last one's; k the number of sweeps; face (or NULL) the last
   sweep's largest |delta| a_jj on each side of the block (R: scratch of the block's size). */
static inline PetscReal VisitBlock(const PffMG *mg, const PffMGLevel *lv, PetscInt lb, const PetscScalar *b,
                                   PetscScalar *x, const PetscScalar *g, PetscScalar *bb, PetscReal *R, PetscReal *face,
                                   PetscInt maxSweeps, PetscBool adaptive, PetscReal *first, PetscInt *k)
{
  const PetscReal omega = mg->opt.omega;
  PetscReal       r     = 0;
  PetscBool       own   = PETSC_FALSE;

  if (lv->mf && PffMGStencilVisitFloat_Private(lv, lb))
    return PffMGStencilVisitBlock_Private(lv, lb, b, x, g, omega, face,
                                          mg->XF + mg->XFsize * (size_t)omp_get_thread_num(), maxSweeps, adaptive,
                                          first, k);
  if (lv->mf) own = PffMGStencilBlockRhs_Private(lv, lb, b, x, g, bb);
  if (!face) R = NULL;
  for (*k = 0; *k < maxSweeps;) {
    if (lv->mf)
      r = PffMGStencilRelaxBlock_Private(lv, lb, bb, own, x, omega, R);
    else {
      const PetscReal r0 = RelaxRows(lv, lv->start[lb], lv->split[lb], lv->start[lb], b, x, g, omega, R);
      const PetscReal r1 = RelaxRows(lv, lv->split[lb], lv->start[lb + 1], lv->start[lb], b, x, g, omega, R);
      r                  = PetscMax(r0, r1);
    }
    if ((*k)++ == 0) *first = r;
    /* repeated block-local sweeps (Algorithm 2): until the update falls by 1/3 */
    if (!adaptive || !(*first > 0) || r < *first / 3) break;
  }
  if (face)
    for (PetscInt f = 0; f < 6; f++) face[f] = r > 0 ? FaceMax(R, lv->n[lb], f) : 0.0;
  return r;
}

static PetscErrorCode SmoothJacobi(PffMG *mg, PffMGLevel *lv, Vec b, Vec x, PetscInt sweeps)
{
  PetscFunctionBeginUser;
  for (PetscInt s = 0; s < sweeps; s++) {
    PetscScalar       *xa;
    const PetscScalar *ra;
    PetscCall(MatMult(lv->A, x, lv->r));
    PetscCall(VecAYPX(lv->r, -1.0, b));
    PetscCall(VecGetArray(x, &xa));
    PetscCall(VecGetArrayRead(lv->r, &ra));
    for (PetscInt q = 0; q < lv->ncolour[0] + lv->ncolour[1]; q++) { /* every relevant block, colours do not matter */
      const PetscInt lb = lv->colourList[q];
      for (PetscInt i = lv->start[lb]; i < lv->start[lb + 1]; i++)
        xa[i] += mg->opt.omega * ra[i] * (lv->mf ? (PetscReal)lv->st->idf[i] : lv->idiag[i]);
      mg->stats.blockRelaxations++;
      mg->stats.cellUpdates += lv->start[lb + 1] - lv->start[lb];
      mg->stats.cellVisits += lv->start[lb + 1] - lv->start[lb];
    }
    PetscCall(VecRestoreArrayRead(lv->r, &ra));
    PetscCall(VecRestoreArray(x, &xa));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* sweeps full hybrid red-black sweeps over the relevant blocks of level L. */
PetscErrorCode PffMGSmoothFixed_Private(PffMG *mg, PetscInt L, Vec b, Vec x, PetscInt sweeps)
{
  PffMGLevel *lv = &mg->lev[L];

  PetscFunctionBeginUser;
  PetscCall(PetscLogEventBegin(PFF_MGSmooth, 0, 0, 0, 0));
  if (mg->opt.smoother == PFF_MG_SMOOTHER_JACOBI) {
    PetscCall(SmoothJacobi(mg, lv, b, x, sweeps));
    PetscCall(PetscLogEventEnd(PFF_MGSmooth, 0, 0, 0, 0));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  for (PetscInt s = 0; s < sweeps; s++)
    for (PetscInt c = 0; c < 2; c++) {
      const PetscInt q0 = c == 0 ? 0 : lv->ncolour[0], q1 = c == 0 ? lv->ncolour[0] : lv->ncolour[0] + lv->ncolour[1];
      PetscScalar   *xa;
      const PetscScalar *ba, *ga = NULL;
      PetscInt64         cells = 0;
      PetscCall(PffMGGhostsBegin_Private(lv, x));
      PetscCall(VecGetArray(x, &xa));
      PetscCall(VecGetArrayRead(b, &ba));
      for (PetscInt pass = 0; pass < 2; pass++) {
        if (pass == 1) PetscCall(PffMGGhostsEnd_Private(lv, x, &ga));
#pragma omp parallel for reduction(+ : cells) schedule(dynamic, 1) if (q1 - q0 >= 8 && lv->omp)
        for (PetscInt q = q0; q < q1; q++) {
          const PetscInt lb = lv->colourList[q];
          PetscReal      first;
          PetscInt       k;
          if (lv->remote[lb] != pass) continue;
          (void)VisitBlock(mg, lv, lb, ba, xa, ga, mg->BB + mg->Rsize * (size_t)omp_get_thread_num(), NULL, NULL, 1,
                           PETSC_FALSE, &first, &k);
          cells += lv->start[lb + 1] - lv->start[lb];
        }
      }
      if (ga) PetscCall(VecRestoreArrayRead(lv->ghost, &ga));
      PetscCall(VecRestoreArrayRead(b, &ba));
      PetscCall(VecRestoreArray(x, &xa));
      mg->stats.blockRelaxations += q1 - q0;
      mg->stats.cellUpdates += cells;
      mg->stats.cellVisits += cells;
    }
  PetscCall(PetscLogEventEnd(PFF_MGSmooth, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* theta of Algorithm 2: 10^(mean + thetaSigmas sd) of log10 of the blocks' initial effective
   residuals r0 (the largest omega |b_j - A_j x| a block saw in its first sweep), over all ranks. */
static PetscErrorCode Threshold(PffMG *mg, const PetscReal *r0, PetscInt n, PetscReal *theta)
{
  PetscReal sum[3] = {0, 0, 0};

  PetscFunctionBeginUser;
  for (PetscInt q = 0; q < n; q++)
    if (r0[q] > 0) {
      const PetscReal lg = PetscLog10Real(r0[q]);
      sum[0] += 1;
      sum[1] += lg;
      sum[2] += lg * lg;
    }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, sum, 3, MPIU_REAL, MPI_SUM, mg->comm));
  if (sum[0] == 0)
    *theta = PETSC_MAX_REAL; /* nothing to relax */
  else {
    const PetscReal mean = sum[1] / sum[0], var = PetscMax(0.0, sum[2] / sum[0] - mean * mean);
    *theta = PetscPowReal(10.0, mean + mg->opt.thetaSigmas * PetscSqrtReal(var));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* One adaptive step over the active list, one block colour at a time: relax each block (repeated
   block-local sweeps), keep its final effective residual in bres and its border maxima in face;
   r0 (or NULL) receives the first sweep's maximum per list entry. The blocks of one colour share no
   face, so they are relaxed in parallel, each thread with its own scratch R (n0^3 per thread). */
static PetscErrorCode RelaxActive(PffMG *mg, PffMGLevel *lv, Vec b, Vec x, PetscInt nactive, PetscReal *r0)
{
  PetscFunctionBeginUser;
  for (PetscInt c = 0; c < 2; c++) {
    PetscScalar       *xa;
    const PetscScalar *ba, *ga = NULL;
    PetscCall(PffMGGhostsBegin_Private(lv, x));
    PetscCall(VecGetArray(x, &xa));
    PetscCall(VecGetArrayRead(b, &ba));
    for (PetscInt pass = 0; pass < 2; pass++) {
      PetscInt64 relax = 0, cells = 0, visited = 0;
      if (pass == 1) PetscCall(PffMGGhostsEnd_Private(lv, x, &ga));
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : relax, cells, visited) if (nactive >= 8 && lv->omp)
      for (PetscInt q = 0; q < nactive; q++) {
        const PetscInt lb = mg->list[q];
        if (mg->colour[lb] != c || lv->remote[lb] != pass) continue;
        const size_t    t = mg->Rsize * (size_t)omp_get_thread_num();
        PetscReal      *R = mg->R + t, first = 0;
        PetscInt        k;
        const PetscReal r =
            VisitBlock(mg, lv, lb, ba, xa, ga, mg->BB + t, R, mg->face + 6 * lb,
                       mg->opt.blockSweeps ? mg->opt.blockSweepsMax : 1, mg->opt.blockSweeps, &first, &k);
        if (r0) r0[q] = first;
        mg->bres[lb] = r;
        relax += k;
        cells += (PetscInt64)k * (lv->start[lb + 1] - lv->start[lb]);
        visited += lv->start[lb + 1] - lv->start[lb];
      }
      mg->stats.blockRelaxations += relax;
      mg->stats.cellUpdates += cells;
      mg->stats.cellVisits += visited;
    }
    if (ga) PetscCall(VecRestoreArrayRead(lv->ghost, &ga));
    PetscCall(VecRestoreArrayRead(b, &ba));
    PetscCall(VecRestoreArray(x, &xa));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode SmoothAdaptive(PffMG *mg, PffMGLevel *lv, Vec b, Vec x)
{
  PetscReal      theta = 0, *r0 = mg->r0;
  PetscMPIInt    size;
  unsigned char *next = mg->next;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(mg->comm, &size));
  PetscCall(PetscArrayzero(next, mg->nlocal));
  for (PetscInt q = 0; q < lv->ncolour[0] + lv->ncolour[1]; q++) next[lv->colourList[q]] = 1;
  for (PetscInt it = 0; it < mg->opt.adaptiveSteps; it++) {
    PetscInt nactive = 0, nglobal;
    /* the active list in local (Morton) order, for coherent memory access */
    for (PetscInt lb = 0; lb < mg->nlocal; lb++)
      if (next[lb]) mg->list[nactive++] = lb;
    PetscCall(PetscArrayzero(next, mg->nlocal));
    PetscCallMPI(MPI_Allreduce(&nactive, &nglobal, 1, MPIU_INT, MPI_SUM, mg->comm));
    if (nglobal == 0) break;
    PetscCall(RelaxActive(mg, lv, b, x, nactive, it == 0 ? r0 : NULL));
    if (it == 0) PetscCall(Threshold(mg, r0, nactive, &theta));
    for (PetscInt q = 0; q < nactive; q++) {
      const PetscInt lb = mg->list[q];
      if (mg->bres[lb] <= theta) continue;
      next[lb] = 1;
      for (PetscInt f = 0; f < 6; f++) {
        const PetscInt nb = mg->nbr[6 * lb + f];
        if (nb == -1 || mg->face[6 * lb + f] <= theta) continue;
        if (nb >= 0) {
          if (lv->relevant[nb]) next[nb] = 1;
        } else
          mg->actLeaf[mg->actLeafOf[6 * lb + f]] = 1; /* another rank's block: sent below */
      }
    }
    if (size > 1) { /* requests go to the neighbouring ranks only */
      PetscCall(PetscArrayzero(mg->actRoot, mg->nlocal));
      PetscCall(PetscSFReduceBegin(mg->actSF, MPIU_INT, mg->actLeaf, mg->actRoot, MPI_MAX));
      PetscCall(PetscSFReduceEnd(mg->actSF, MPIU_INT, mg->actLeaf, mg->actRoot, MPI_MAX));
      for (PetscInt lb = 0; lb < mg->nlocal; lb++)
        if (mg->actRoot[lb] && lv->relevant[lb]) next[lb] = 1;
      PetscCall(PetscArrayzero(mg->actLeaf, mg->nactLeaf));
    }
    mg->stats.adaptiveSteps++;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Pre- or post-smoothing of level L as configured (adaptive or fixed sweeps). */
PetscErrorCode PffMGSmooth_Private(PffMG *mg, PetscInt L, Vec b, Vec x)
{
  PffMGLevel *lv = &mg->lev[L];

  PetscFunctionBeginUser;
  if (!mg->opt.adaptive || mg->opt.smoother == PFF_MG_SMOOTHER_JACOBI || lv->uniform) {
    PetscCall(PffMGSmoothFixed_Private(mg, L, b, x, mg->opt.sweeps));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PetscCall(PetscLogEventBegin(PFF_MGSmooth, 0, 0, 0, 0));
  PetscCall(SmoothAdaptive(mg, lv, b, x));
  PetscCall(PetscLogEventEnd(PFF_MGSmooth, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}
