/* pffmg hierarchy: multiresolution Galerkin coarsening (PF-FLIP Sec. 6.1-6.2, Algorithm 1, Eq. 14).

   Multigrid levels L are separate from the MSBG resolution levels l (Fig. 10): at level L, block b
   has resolution max(l_b, L), so a block without finer cells than L is shared unchanged, and a block
   coarsened from L-1 to L merges its cells 2x2x2. The prolongation P from L to L-1 is piecewise
   constant (unsmoothed aggregation, Shao et al. 2022), R = P^T, and the level operator is the
   Galerkin product A_L = P^T A_{L-1} P (Eq. 14). For our face operator A = sum_f c_f g_f g_f^T this
   is again a face operator whose coarse face coefficients are the sums of the fine face coefficients
   across each coarse face -- Algorithm 1's loop over the 2x2 fine faces, including the coarse-fine
   faces with their Delta_g scaling, which our level-0 coefficients already carry (faces.c). It is
   computed with MatPtAP, numerically once per set-up, symbolically once per grid. The hierarchy
   stops when every block is one cell (L = log2 n0); that level is solved by a PETSc KSP.

   Each level also keeps what the block smoother needs: per block its cell count and rows, the
   rows split into red and black cells, the relevant blocks per block colour, and CSR views of the
   local and off-rank parts of A_L with a ghost scatter for the off-rank columns. */
#include "mgimpl.h"
#include <omp.h>
#include <petscsf.h>

static PetscInt ResolutionAt(PetscInt l, PetscInt L)
{
  return PetscMax(l, L);
}

/* Face neighbour gid of block ijk across face f (0..5: -x, +x, -y, +y, -z, +z), or -1. */
static PetscInt FaceNeighbour(const PetscInt nb[3], const PetscBool periodic[3], const PetscInt ijk[3], PetscInt f)
{
  PetscInt dir[3] = {0, 0, 0};
  dir[f / 2]      = (f % 2) ? 1 : -1;
  return PffRasterNeighbour(nb, periodic, ijk, dir);
}

/* The relevant units of a level sorted by colour: colour 0 first, then colour 1. */
static void BuildColourList(PffMGLevel *lv, const unsigned char *colour)
{
  PetscInt q[2] = {0, 0};

  for (PetscInt u = 0; u < lv->nblk; u++)
    if (lv->relevant[u]) q[colour[u]]++;
  lv->ncolour[0] = q[0];
  lv->ncolour[1] = q[1];
  q[1]           = q[0];
  q[0]           = 0;
  for (PetscInt u = 0; u < lv->nblk; u++)
    if (lv->relevant[u]) lv->colourList[q[colour[u]]++] = u;
}

static PetscErrorCode BuildLevelLayout(PffMG *mg, PetscInt L)
{
  PffMGLevel        *lv = &mg->lev[L];
  PetscInt           nb[3], n0, nlevels;
  const PetscInt    *level;
  const PetscMPIInt *owner;
  PetscBool          periodic[3];
  PetscInt           rstart = 0;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetRaster(mg->grid, nb, &level, &owner));
  PetscCall(PffGridGetSizes(mg->grid, &n0, &nlevels, NULL, NULL, periodic));
  lv->L = L;
  PetscCall(
      PetscMalloc4(mg->nlocal, &lv->n, mg->nlocal + 1, &lv->start, mg->nlocal, &lv->split, mg->nlocal, &lv->relevant));
  lv->start[0] = 0;
  for (PetscInt lb = 0; lb < mg->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(mg->grid, lb, &info));
    lv->n[lb]         = n0 >> ResolutionAt(info.level, L);
    lv->start[lb + 1] = lv->start[lb] + lv->n[lb] * lv->n[lb] * lv->n[lb];
  }
  lv->nrows = lv->start[mg->nlocal];
  lv->nblk  = mg->nlocal;
  PetscCallMPI(MPI_Exscan(&lv->nrows, &rstart, 1, MPIU_INT, MPI_SUM, mg->comm));
  lv->rstart = rstart;

  /* red cells (i + j + k even) first, then black, per block: the row order of the AIJ smoother */
  PetscCall(PetscMalloc1(mg->nlocal, &lv->colourList));
  if (!lv->mf) PetscCall(PetscMalloc1(lv->nrows, &lv->order));
  for (PetscInt lb = 0; lb < mg->nlocal && !lv->mf; lb++) {
    const PetscInt n = lv->n[lb];
    PetscInt       q = lv->start[lb];
    for (PetscInt c = 0; c < 2; c++) {
      for (PetscInt k = 0; k < n; k++)
        for (PetscInt j = 0; j < n; j++)
          for (PetscInt i = (j + k + c) % 2; i < n; i += 2) lv->order[q++] = lv->start[lb] + i + n * (j + n * k);
      if (c == 0) lv->split[lb] = q;
    }
  }

  /* relevant blocks (Algorithm 2's initial list): resolution L, and the blocks at L+1 that touch one */
  for (PetscInt lb = 0; lb < mg->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(mg->grid, lb, &info));
    const PetscInt r   = ResolutionAt(info.level, L);
    PetscBool      rel = (PetscBool)(r == L);
    if (!rel && r == L + 1)
      for (PetscInt f = 0; f < 6 && !rel; f++) {
        const PetscInt g = FaceNeighbour(nb, periodic, info.ijk, f);
        if (g >= 0 && level[g] >= 0 && ResolutionAt(level[g], L) == L) rel = PETSC_TRUE;
      }
    lv->relevant[lb] = rel;
  }
  BuildColourList(lv, mg->colour);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A work vector of a level: n owned rows, sequential on one rank. */
static PetscErrorCode LevelVec(MPI_Comm comm, PetscInt n, Vec *v)
{
  PetscFunctionBeginUser;
  PetscCall(VecCreate(comm, v));
  PetscCall(VecSetSizes(*v, n, PETSC_DETERMINE));
  PetscCall(VecSetType(*v, VECSTANDARD));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Piecewise-constant prolongation from block level L+1 to level L, assembled (AIJ levels, or on request). */
PetscErrorCode PffMGBuildProlongation_Private(PffMG *mg, PetscInt L)
{
  PffMGLevel *f = &mg->lev[L], *c = &mg->lev[L + 1];

  PetscFunctionBeginUser;
  PetscCall(MatCreateAIJ(mg->comm, f->nrows, c->nrows, PETSC_DETERMINE, PETSC_DETERMINE, 1, NULL, 0, NULL, &f->P));
  for (PetscInt lb = 0; lb < mg->nlocal; lb++) {
    const PetscInt nf = f->n[lb], nc = c->n[lb], s = nf > nc;
    for (PetscInt q = 0; q < nf * nf; q++)
      for (PetscInt i = 0; i < nf; i++) {
        const PetscInt row = f->rstart + f->start[lb] + q * nf + i;
        const PetscInt col = c->rstart + c->start[lb] + PffMGCoarseRow_Private(q, nf, nc, s) + (i >> s);
        PetscCall(MatSetValue(f->P, row, col, 1.0, INSERT_VALUES));
      }
  }
  PetscCall(MatAssemblyBegin(f->P, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(f->P, MAT_FINAL_ASSEMBLY));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Uniform levels below the block raster (Sec. 6.2): level Lr + k merges the one-cell blocks of level Lr
   in groups of (2^k)^3 by raster coordinates. A coarse cell belongs to the rank that owns its first
   active block in Morton order; the replicated raster gives every rank the whole numbering without
   communication. Blocks in Morton order have nondecreasing group keys (Morton key >> 3k), so the
   groups are runs of that order. */
typedef struct {
  PetscInt  n;      /* groups */
  uint64_t *key;    /* [n] Morton keys of the groups, increasing */
  PetscInt *global; /* [n] global row of each group */
} PffMGGroups;

static PetscErrorCode BuildGroups(PffMG *mg, PetscInt k, PffMGGroups *g, PffMGLevel *lv)
{
  PetscInt           nb[3], nactive, ns = 0, nown = 0;
  const PetscInt    *gids;
  const PetscInt    *level;
  const PetscMPIInt *owner;
  PetscMPIInt        rank, size;
  PetscInt          *count, *ord;
  PetscMPIInt       *gowner;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(mg->comm, &rank));
  PetscCallMPI(MPI_Comm_size(mg->comm, &size));
  PetscCall(PffGridGetRaster(mg->grid, nb, &level, &owner));
  PetscCall(PffGridGetMortonOrder(mg->grid, &nactive, &gids));
  PetscCall(PetscMalloc2(nactive, &g->key, nactive, &g->global));
  PetscCall(PetscMalloc3(nactive, &gowner, size + 1, &count, nactive, &ord));
  PetscCall(PetscArrayzero(count, size + 1));
  for (PetscInt q = 0; q < nactive; q++) {
    const PetscInt gid = gids[q];
    PetscInt       ijk[3];
    PffRasterCoordinates(nb, gid, ijk);
    const uint64_t key = PffMortonEncode((uint32_t)(ijk[0] >> k), (uint32_t)(ijk[1] >> k), (uint32_t)(ijk[2] >> k));
    if (ns > 0 && g->key[ns - 1] == key) continue;
    PetscCheck(ns == 0 || key > g->key[ns - 1], PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "pffmg: blocks are not in Morton order");
    g->key[ns] = key;
    gowner[ns] = owner[gid];
    ord[ns]    = count[owner[gid]]++;
    ns++;
  }
  g->n = ns;
  {
    PetscInt off = 0;
    for (PetscMPIInt r = 0; r < size; r++) {
      const PetscInt c = count[r];
      count[r]         = off;
      off += c;
    }
  }
  for (PetscInt q = 0; q < ns; q++) g->global[q] = count[gowner[q]] + ord[q];
  if (lv) {
    for (PetscInt q = 0; q < ns; q++)
      if (gowner[q] == rank) nown++;
    lv->nblk   = nown;
    lv->nrows  = nown;
    lv->rstart = count[rank];
    PetscCall(PetscMalloc1(3 * nown, &lv->coord));
    nown = 0;
    for (PetscInt q = 0; q < ns; q++)
      if (gowner[q] == rank) {
        uint32_t x[3];
        PffMortonDecode(g->key[q], &x[0], &x[1], &x[2]);
        for (int a = 0; a < 3; a++) lv->coord[3 * nown + a] = (PetscInt)x[a];
        nown++;
      }
  }
  PetscCall(PetscFree3(gowner, count, ord));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode BuildUniformLevel(PffMG *mg, PetscInt L, PetscInt k)
{
  PffMGLevel    *lv = &mg->lev[L];
  PffMGGroups    g;
  unsigned char *colour;

  PetscFunctionBeginUser;
  lv->L       = L;
  lv->uniform = PETSC_TRUE;
  PetscCall(BuildGroups(mg, k, &g, lv));
  PetscCall(PetscFree2(g.key, g.global));
  PetscCall(PetscMalloc4(lv->nblk, &lv->n, lv->nblk + 1, &lv->start, lv->nblk, &lv->split, lv->nblk, &lv->relevant));
  PetscCall(PetscMalloc1(lv->nblk, &lv->colourList));
  PetscCall(PetscMalloc1(lv->nrows, &lv->order));
  PetscCall(PetscMalloc1(lv->nblk, &colour));
  for (PetscInt q = 0; q < lv->nblk; q++) {
    lv->n[q]        = 1;
    lv->start[q]    = q;
    lv->split[q]    = q + 1;
    lv->order[q]    = q;
    lv->relevant[q] = PETSC_TRUE;
    colour[q]       = (unsigned char)((lv->coord[3 * q] + lv->coord[3 * q + 1] + lv->coord[3 * q + 2]) % 2);
  }
  lv->start[lv->nblk] = lv->nblk;
  BuildColourList(lv, colour);
  PetscCall(PetscFree(colour));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Piecewise-constant prolongation from uniform level L+1 = Lr + k to level L (the one-cell blocks of
   level Lr when k = 1). */
static PetscErrorCode BuildUniformProlongation(PffMG *mg, PetscInt L, PetscInt k)
{
  PffMGLevel *f = &mg->lev[L], *c = &mg->lev[L + 1];
  PffMGGroups g;

  PetscFunctionBeginUser;
  PetscCall(BuildGroups(mg, k, &g, NULL));
  PetscCall(MatCreateAIJ(mg->comm, f->nrows, c->nrows, PETSC_DETERMINE, PETSC_DETERMINE, 1, NULL, 1, NULL, &f->P));
  for (PetscInt q = 0; q < f->nblk; q++) {
    PetscInt x[3], lo = 0, hi = g.n - 1;
    if (f->uniform)
      for (int a = 0; a < 3; a++) x[a] = f->coord[3 * q + a] >> 1;
    else {
      PffBlockInfo info;
      PetscCall(PffGridGetBlockInfo(mg->grid, q, &info));
      for (int a = 0; a < 3; a++) x[a] = info.ijk[a] >> 1;
    }
    const uint64_t key = PffMortonEncode((uint32_t)x[0], (uint32_t)x[1], (uint32_t)x[2]);
    while (lo < hi) {
      const PetscInt mid = (lo + hi) / 2;
      if (g.key[mid] < key)
        lo = mid + 1;
      else
        hi = mid;
    }
    PetscCheck(g.key[lo] == key, PETSC_COMM_SELF, PETSC_ERR_PLIB, "pffmg: coarse group not found");
    PetscCall(MatSetValue(f->P, f->rstart + f->start[q], g.global[lo], 1.0, INSERT_VALUES));
  }
  PetscCall(MatAssemblyBegin(f->P, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(f->P, MAT_FINAL_ASSEMBLY));
  PetscCall(PetscFree2(g.key, g.global));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Ghost scatter for the off-rank columns of A_L (fixed for the life of the pattern). */
static PetscErrorCode BuildGhosts(PffMG *mg, PffMGLevel *lv)
{
  PetscBool isMPI, isSeq;

  PetscFunctionBeginUser;
  PetscCall(PetscObjectBaseTypeCompare((PetscObject)lv->A, MATMPIAIJ, &isMPI));
  PetscCall(PetscObjectBaseTypeCompare((PetscObject)lv->A, MATSEQAIJ, &isSeq));
  PetscCheck(isMPI || isSeq, mg->comm, PETSC_ERR_SUP,
             "pffmg: the pressure operator must be an assembled AIJ matrix (-pressure_pc_type pffmg)");
  if (isMPI) {
    IS is;
    PetscCall(MatMPIAIJGetSeqAIJ(lv->A, &lv->Ad, &lv->Ao, &lv->colmap));
    PetscCall(MatGetSize(lv->Ao, NULL, &lv->nghost));
    PetscCall(ISCreateGeneral(PETSC_COMM_SELF, lv->nghost, lv->colmap, PETSC_USE_POINTER, &is));
    PetscCall(VecCreateSeq(PETSC_COMM_SELF, lv->nghost, &lv->ghost));
    PetscCall(VecScatterCreate(lv->r, is, lv->ghost, NULL, &lv->scatter));
    PetscCall(ISDestroy(&is));
  } else {
    lv->Ad     = lv->A;
    lv->Ao     = NULL;
    lv->nghost = 0;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Which rows of level L (and of its ghost columns) were merged from level L-1: structural, so
   computed and exchanged once per grid, for RescaleCoarse at every set-up. */
static PetscErrorCode BuildMergedFlags(PffMG *mg, PetscInt L)
{
  PffMGLevel        *lv = &mg->lev[L], *f = &mg->lev[L - 1];
  PetscScalar       *fl;
  const PetscScalar *gf;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc2(lv->nrows, &lv->merged, lv->nghost, &lv->mergedGhost));
  PetscCall(VecGetArrayWrite(lv->r, &fl));
  for (PetscInt u = 0; u < lv->nblk; u++)
    for (PetscInt i = lv->start[u]; i < lv->start[u + 1]; i++) {
      lv->merged[i] = (unsigned char)(lv->uniform || lv->n[u] < f->n[u]);
      fl[i]         = lv->merged[i];
    }
  PetscCall(VecRestoreArrayWrite(lv->r, &fl));
  if (lv->scatter) {
    PetscCall(VecScatterBegin(lv->scatter, lv->r, lv->ghost, INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecScatterEnd(lv->scatter, lv->r, lv->ghost, INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecGetArrayRead(lv->ghost, &gf));
    for (PetscInt j = 0; j < lv->nghost; j++) lv->mergedGhost[j] = (unsigned char)(gf[j] != 0);
    PetscCall(VecRestoreArrayRead(lv->ghost, &gf));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* 1 / a_ii of A_L (0 for an empty row), after every numeric update. */
static void ComputeInverseDiagonal(PffMGLevel *lv)
{
  for (PetscInt i = 0; i < lv->nrows; i++) {
    PetscScalar d = 0;
    for (PetscInt k = lv->ai[i]; k < lv->ai[i + 1]; k++)
      if (lv->aj[k] == i) d = lv->aa[k];
    lv->idiag[i] = d != 0 ? 1.0 / d : 0.0;
  }
}

/* CSR pointers of A_L, after every numeric update. */
static PetscErrorCode RefreshLevelArrays(PffMG *mg, PffMGLevel *lv)
{
  PetscInt  nr;
  PetscBool done;

  PetscFunctionBeginUser;
  if (lv->ai) PetscCall(MatRestoreRowIJ(lv->Ad, 0, PETSC_FALSE, PETSC_FALSE, NULL, &lv->ai, &lv->aj, NULL));
  if (lv->bi) PetscCall(MatRestoreRowIJ(lv->Ao, 0, PETSC_FALSE, PETSC_FALSE, NULL, &lv->bi, &lv->bj, NULL));
  PetscCall(MatGetRowIJ(lv->Ad, 0, PETSC_FALSE, PETSC_FALSE, &nr, &lv->ai, &lv->aj, &done));
  PetscCheck(done && nr == lv->nrows, PETSC_COMM_SELF, PETSC_ERR_PLIB, "pffmg: no CSR access to the level operator");
  {
    const PetscScalar *a; /* host memory: the pointer stays valid after the restore (which clears it) */
    PetscCall(MatSeqAIJGetArrayRead(lv->Ad, &a));
    lv->aa = a;
    PetscCall(MatSeqAIJRestoreArrayRead(lv->Ad, &a));
  }
  if (lv->Ao) {
    PetscCall(MatGetRowIJ(lv->Ao, 0, PETSC_FALSE, PETSC_FALSE, &nr, &lv->bi, &lv->bj, &done));
    PetscCheck(done && nr == lv->nrows, PETSC_COMM_SELF, PETSC_ERR_PLIB, "pffmg: no CSR access to the level operator");
    const PetscScalar *a;
    PetscCall(MatSeqAIJGetArrayRead(lv->Ao, &a));
    lv->ba = a;
    PetscCall(MatSeqAIJRestoreArrayRead(lv->Ao, &a));
  }
  if (lv->idiag == NULL) PetscCall(PetscMalloc1(lv->nrows, &lv->idiag));
  (void)mg;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Piecewise-constant aggregation makes P^T A P twice as stiff as the same operator discretised on
   the coarse cells (four fine faces of weight h beta become one of 4 h beta, where 2 h beta is
   consistent), and 4/3 as stiff on a face between a merged block and a block that was already at
   the coarse resolution (the Delta_g = 3/4 distance of the coarse-fine face). We read Algorithm 1's
   resolution-transition factors as this rescaling: each off-diagonal entry of A_L is multiplied by
   1/2 between two merged cells, 3/4 between a merged and a shared cell, 1 between shared cells;
   boundary terms (diagonal minus off-diagonal sum, e.g. Dirichlet walls) by 1/2 on merged cells;
   the diagonal is rebuilt so that rows keep their sums. The result stays symmetric. */
static PetscErrorCode RescaleCoarse(PffMG *mg, PetscInt L)
{
  PffMGLevel  *lv = &mg->lev[L];
  PetscScalar *aa, *ba = NULL;

  PetscFunctionBeginUser;
  PetscCall(MatSeqAIJGetArray(lv->Ad, &aa));
  if (lv->Ao) PetscCall(MatSeqAIJGetArray(lv->Ao, &ba));
  for (PetscInt i = 0; i < lv->nrows; i++) {
    const PetscBool mi     = (PetscBool)lv->merged[i];
    PetscScalar     offOld = 0, offNew = 0;
    PetscInt        kd = -1;
    for (PetscInt k = lv->ai[i]; k < lv->ai[i + 1]; k++) {
      if (lv->aj[k] == i) {
        kd = k;
        continue;
      }
      const PetscBool mj = (PetscBool)lv->merged[lv->aj[k]];
      offOld += aa[k];
      aa[k] *= mi && mj ? 0.5 : (mi || mj ? 0.75 : 1.0);
      offNew += aa[k];
    }
    if (lv->Ao)
      for (PetscInt k = lv->bi[i]; k < lv->bi[i + 1]; k++) {
        const PetscBool mj = (PetscBool)lv->mergedGhost[lv->bj[k]];
        offOld += ba[k];
        ba[k] *= mi && mj ? 0.5 : (mi || mj ? 0.75 : 1.0);
        offNew += ba[k];
      }
    if (kd >= 0) aa[kd] = (mi ? 0.5 : 1.0) * (aa[kd] + offOld) - offNew;
  }
  if (lv->Ao) PetscCall(MatSeqAIJRestoreArray(lv->Ao, &ba));
  PetscCall(MatSeqAIJRestoreArray(lv->Ad, &aa));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Activation requests of adaptive relaxation to blocks on other ranks: one SF leaf per (owned block, face)
   with an off-rank neighbour, rooted at that block on its owner, reduced with MPI_MAX; only neighbouring
   ranks talk. The owner's local index of a block is its position among the owner's blocks in Morton
   order, which the replicated raster gives without communication. */
static PetscErrorCode BuildActivationSF(PffMG *mg, const PetscInt nb[3], const PetscMPIInt *owner)
{
  PetscInt        nactive, nleaf = 0, *lidx;
  const PetscInt *gids;
  PetscMPIInt     size;
  PetscInt       *count;
  PetscSFNode    *remote;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(mg->comm, &size));
  PetscCall(PffGridGetMortonOrder(mg->grid, &nactive, &gids));
  PetscCall(PetscMalloc1(nb[0] * nb[1] * nb[2], &lidx));
  PetscCall(PetscCalloc1(size, &count));
  for (PetscInt q = 0; q < nactive; q++) lidx[gids[q]] = count[owner[gids[q]]]++;
  for (PetscInt e = 0; e < 6 * mg->nlocal; e++) mg->actLeafOf[e] = mg->nbr[e] <= -2 ? nleaf++ : -1;
  PetscCall(PetscMalloc1(nleaf, &remote));
  for (PetscInt e = 0; e < 6 * mg->nlocal; e++)
    if (mg->nbr[e] <= -2) {
      const PetscInt g               = -2 - mg->nbr[e];
      remote[mg->actLeafOf[e]].rank  = owner[g];
      remote[mg->actLeafOf[e]].index = lidx[g];
    }
  PetscCall(PetscSFCreate(mg->comm, &mg->actSF));
  PetscCall(PetscSFSetGraph(mg->actSF, mg->nlocal, nleaf, NULL, PETSC_COPY_VALUES, remote, PETSC_OWN_POINTER));
  PetscCall(PetscSFSetUp(mg->actSF));
  PetscCall(PetscCalloc2(nleaf, &mg->actLeaf, mg->nlocal, &mg->actRoot));
  mg->nactLeaf = nleaf;
  PetscCall(PetscFree(count));
  PetscCall(PetscFree(lidx));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffMGBuildLevels_Private(PffMG *mg)
{
  PetscInt           n0, nb[3], nblockLevels = 1, nmax;
  const PetscInt    *level;
  const PetscMPIInt *owner;
  PetscBool          periodic[3];

  PetscFunctionBeginUser;
  PetscCall(PffGridGetSizes(mg->grid, &n0, NULL, NULL, NULL, periodic));
  PetscCall(PffGridGetRaster(mg->grid, nb, &level, &owner));
  PetscCall(PffGridGetLocalBlocks(mg->grid, &mg->nlocal));

  /* per owned block: raster index, colour, face neighbours (local index, or -2 - gid on another rank),
     and the scratch of adaptive relaxation */
  PetscCall(PetscMalloc5(6 * mg->nlocal, &mg->nbr, 6 * mg->nlocal, &mg->actLeafOf, mg->nlocal, &mg->bres,
                         6 * mg->nlocal, &mg->face, mg->nlocal, &mg->list));
  mg->Rsize = (size_t)n0 * n0 * n0;
  PetscCall(PetscMalloc6(mg->nlocal, &mg->gid, mg->nlocal, &mg->colour, mg->nlocal, &mg->next, mg->nlocal, &mg->r0,
                         mg->Rsize * (size_t)omp_get_max_threads(), &mg->R, mg->Rsize * (size_t)omp_get_max_threads(),
                         &mg->BB));
  mg->XFsize = 2 * mg->Rsize + 2 * (size_t)n0; /* x with its pads, bb */
  PetscCall(PetscMalloc1(mg->XFsize * (size_t)omp_get_max_threads(), &mg->XF));
  for (PetscInt lb = 0; lb < mg->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(mg->grid, lb, &info));
    mg->gid[lb]    = info.gid;
    mg->colour[lb] = (unsigned char)((info.ijk[0] + info.ijk[1] + info.ijk[2]) % 2);
    for (PetscInt f = 0; f < 6; f++) {
      const PetscInt g = FaceNeighbour(nb, periodic, info.ijk, f);
      PetscInt       l = -1;
      if (g >= 0 && level[g] >= 0) {
        PetscCall(PffGridGetLocalIndex(mg->grid, g, &l));
        if (l < 0) l = -2 - g;
      }
      mg->nbr[6 * lb + f] = l;
    }
  }
  PetscCall(BuildActivationSF(mg, nb, owner));

  while ((n0 >> (nblockLevels - 1)) > 1 && nblockLevels < mg->opt.maxLevels) nblockLevels++;
  nmax = mg->opt.maxLevels;
  PetscCall(PetscCalloc1(nmax, &mg->lev));
  mg->nlevels = nblockLevels;
  /* with stencil operators every block level but the last is relaxed, applied and transferred matrix-free */
  for (PetscInt L = 0; L + 1 < nblockLevels; L++)
    mg->lev[L].mf = (PetscBool)(mg->opt.operatorType == PFF_MG_OPERATOR_STENCIL);
  for (PetscInt L = 0; L < nblockLevels; L++) PetscCall(BuildLevelLayout(mg, L));
  if ((n0 >> (nblockLevels - 1)) == 1) {
    /* uniform levels below the raster while the coarsest level is too large for the direct solve */
    for (PetscInt k = 1; mg->nlevels < nmax; k++) {
      PetscInt nrows = mg->lev[mg->nlevels - 1].nrows, nglobal, ncoarse;
      PetscCallMPI(MPI_Allreduce(&nrows, &nglobal, 1, MPIU_INT, MPI_SUM, mg->comm));
      if (nglobal <= mg->opt.coarseMax) break;
      PetscCall(BuildUniformLevel(mg, mg->nlevels, k));
      PetscCallMPI(MPI_Allreduce(&mg->lev[mg->nlevels].nrows, &ncoarse, 1, MPIU_INT, MPI_SUM, mg->comm));
      mg->nlevels++;
      if (ncoarse == nglobal) break;
    }
  }
  for (PetscInt L = 0; L + 1 < mg->nlevels; L++) {
    const PffMGLevel *lv = &mg->lev[L];
    /* a matrix-free level transfers block by block (no P) and keeps its residual inside the block (no r, but
       for the Jacobi smoother) */
    if (mg->lev[L + 1].uniform)
      PetscCall(BuildUniformProlongation(mg, L, L + 1 - (nblockLevels - 1)));
    else if (!lv->mf)
      PetscCall(PffMGBuildProlongation_Private(mg, L));
    PetscCall(LevelVec(mg->comm, mg->lev[L + 1].nrows, &mg->lev[L + 1].x));
    if (!lv->mf || mg->opt.smoother == PFF_MG_SMOOTHER_JACOBI) PetscCall(LevelVec(mg->comm, lv->nrows, &mg->lev[L].r));
    PetscCall(VecDuplicate(mg->lev[L + 1].x, &mg->lev[L + 1].b));
  }
  if (mg->nlevels > 1) PetscCall(VecDuplicate(mg->lev[mg->nlevels - 1].x, &mg->lev[mg->nlevels - 1].r));
  mg->nblockLevels = nblockLevels;
  if (mg->opt.operatorType == PFF_MG_OPERATOR_STENCIL && nblockLevels > 1)
    for (PetscInt L = 0; L < nblockLevels; L++) {
      PetscCall(PffMGStencilBuild_Private(mg, L));
      if (mg->lev[L].mf) PetscCall(PffMGStencilCreateShell_Private(mg, L));
    }
  for (PetscInt L = 0; L < mg->nlevels; L++) {
    PffMGLevel *lv = &mg->lev[L];
    /* a parallel region on a small level (the K-cycle visits level L 2^L times) costs more than it shares */
    lv->omp = (PetscBool)(lv->nrows >= mg->opt.ompMinRows);
    PetscCall(PetscMalloc1(lv->nblk, &lv->remote));
    for (PetscInt q = 0; q < lv->nblk; q++) {
      lv->remote[q] = lv->uniform; /* coarse cells of uniform levels: no neighbour list, always after the exchange */
      for (PetscInt f = 0; f < 6 && !lv->uniform; f++)
        if (mg->nbr[6 * q + f] <= -2) lv->remote[q] = 1;
      /* the stencil's side sums read a block without an off-rank neighbour from owned rows only, unchecked */
      if (lv->st && !lv->remote[q] && q < mg->nlocal)
        for (PetscInt e = lv->st->rowptr[lv->start[q]]; e < lv->st->rowptr[lv->start[q + 1]]; e++)
          PetscCheck(lv->st->col[e] < lv->nrows, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                     "pffmg: block %" PetscInt_FMT " of level %" PetscInt_FMT
                     " couples to another rank's cell but has no off-rank neighbour",
                     q, L);
    }
  }
  mg->built = PETSC_TRUE;
  PetscCall(PffGridGetTopologyState(mg->grid, &mg->topology));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Numeric set-up: the Galerkin operators of every level from the current A (same pattern each
   step), the pin of the coarsest operator when A is singular, the coarse solver's factorisation. */
PetscErrorCode PffMGUpdateOperators_Private(PffMG *mg, Mat A)
{
  MatNullSpace    nsp;
  const PetscBool stencil = (PetscBool)(mg->lev[0].st != NULL);

  PetscFunctionBeginUser;
  PetscCall(MatGetNullSpace(A, &nsp));
  mg->singular = (PetscBool)(nsp != NULL);
  if (mg->Apc != A) {
    PetscCall(PetscObjectReference((PetscObject)A));
    PetscCall(MatDestroy(&mg->Apc));
    mg->Apc = A;
  }
  if (!stencil) {
    if (mg->lev[0].A != A) {
      PetscCall(PetscObjectReference((PetscObject)A));
      PetscCall(MatDestroy(&mg->lev[0].A));
      mg->lev[0].A = A;
      PetscCall(VecScatterDestroy(&mg->lev[0].scatter));
      PetscCall(VecDestroy(&mg->lev[0].ghost));
      if (mg->lev[0].r == NULL) PetscCall(MatCreateVecs(A, NULL, &mg->lev[0].r));
      PetscCall(BuildGhosts(mg, &mg->lev[0]));
    }
    PetscCall(RefreshLevelArrays(mg, &mg->lev[0]));
    ComputeInverseDiagonal(&mg->lev[0]);
  }
  for (PetscInt L = 0; L < mg->nlevels; L++) {
    PffMGLevel *lv = &mg->lev[L];
    if (lv->st) {
      /* Algorithm 1 on the face coefficients; the last block level also as AIJ for the levels below */
      PetscCall(PffMGStencilUpdate_Private(mg, L));
      if (!lv->mf) {
        const PetscBool first = (PetscBool)(lv->A == NULL);
        PetscCall(PffMGStencilAssemble_Private(mg, L, &lv->A));
        if (first) PetscCall(BuildGhosts(mg, lv));
        PetscCall(RefreshLevelArrays(mg, lv));
        ComputeInverseDiagonal(lv);
      }
    } else if (L > 0) {
      if (lv->A == NULL) {
        PetscCall(MatPtAP(mg->lev[L - 1].A, mg->lev[L - 1].P, MAT_INITIAL_MATRIX, 1.5, &lv->A));
        PetscCall(BuildGhosts(mg, lv));
        PetscCall(BuildMergedFlags(mg, L));
      } else
        PetscCall(MatPtAP(mg->lev[L - 1].A, mg->lev[L - 1].P, MAT_REUSE_MATRIX, 1.5, &lv->A));
      PetscCall(RefreshLevelArrays(mg, lv));
      if (mg->opt.rescale) PetscCall(RescaleCoarse(mg, L));
      ComputeInverseDiagonal(lv);
    }
    if (L == 0) continue;
    /* the K-cycle's inner Krylov steps need the constants as null space of the singular levels, or
       they gather a constant component that stalls the outer FCG near 1e-11 (not A's own null-space
       object: with closed cells it is a vector of the fine level) */
    if (mg->singular && mg->constants == NULL)
      PetscCall(MatNullSpaceCreate(mg->comm, PETSC_TRUE, 0, NULL, &mg->constants));
    PetscCall(MatSetNullSpace(lv->A, mg->singular ? mg->constants : NULL));
  }
  {
    PffMGLevel *c = &mg->lev[mg->nlevels - 1];
    if (mg->nlevels == 1 || !mg->singular)
      PetscCall(KSPSetOperators(mg->coarse, c->A, c->A));
    else {
      /* A_c + d e_0 e_0^T: for a rhs orthogonal to the constants its solution is the singular
         system's up to a constant, whatever d > 0 (the constant is removed by the Krylov method);
         one copy per grid, refreshed in place so the coarse factorisation keeps its symbolic part */
      if (mg->Apinned == NULL)
        PetscCall(MatDuplicate(c->A, MAT_COPY_VALUES, &mg->Apinned));
      else
        PetscCall(MatCopy(c->A, mg->Apinned, SAME_NONZERO_PATTERN));
      if (c->rstart == 0 && c->nrows > 0) {
        const PetscScalar d = c->idiag[0] != 0 ? 1.0 / c->idiag[0] : 1.0;
        PetscCall(MatSetValue(mg->Apinned, 0, 0, d, ADD_VALUES));
      }
      PetscCall(MatAssemblyBegin(mg->Apinned, MAT_FINAL_ASSEMBLY));
      PetscCall(MatAssemblyEnd(mg->Apinned, MAT_FINAL_ASSEMBLY));
      PetscCall(KSPSetOperators(mg->coarse, mg->Apinned, mg->Apinned));
    }
    PetscCall(KSPSetUp(mg->coarse));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffMGDestroyLevels_Private(PffMG *mg)
{
  PetscFunctionBeginUser;
  for (PetscInt L = 0; L < mg->nlevels && mg->lev; L++) {
    PffMGLevel *lv = &mg->lev[L];
    if (lv->ai) PetscCall(MatRestoreRowIJ(lv->Ad, 0, PETSC_FALSE, PETSC_FALSE, NULL, &lv->ai, &lv->aj, NULL));
    if (lv->bi) PetscCall(MatRestoreRowIJ(lv->Ao, 0, PETSC_FALSE, PETSC_FALSE, NULL, &lv->bi, &lv->bj, NULL));
    PetscCall(KSPDestroy(&lv->kcycle));
    PetscCall(MatDestroy(&lv->A));
    PetscCall(MatDestroy(&lv->P));
    PetscCall(VecDestroy(&lv->x));
    PetscCall(VecDestroy(&lv->b));
    PetscCall(VecDestroy(&lv->r));
    PetscCall(VecDestroy(&lv->ghost));
    PetscCall(VecScatterDestroy(&lv->scatter));
    PetscCall(PetscFree4(lv->n, lv->start, lv->split, lv->relevant));
    PetscCall(PetscFree(lv->colourList));
    PetscCall(PetscFree(lv->order));
    PetscCall(PetscFree(lv->coord));
    PetscCall(PetscFree(lv->remote));
    PetscCall(PetscFree2(lv->merged, lv->mergedGhost));
    PetscCall(PetscFree(lv->idiag));
    PetscCall(PffMGStencilDestroy_Private(lv));
  }
  PetscCall(PetscFree(mg->lev));
  if (mg->coarse) PetscCall(KSPReset(mg->coarse)); /* the next hierarchy's coarsest level may differ in size */
  PetscCall(MatDestroy(&mg->Apc));
  PetscCall(MatDestroy(&mg->Apinned));
  PetscCall(MatNullSpaceDestroy(&mg->constants));
  if (mg->built) {
    PetscCall(PetscFree5(mg->nbr, mg->actLeafOf, mg->bres, mg->face, mg->list));
    PetscCall(PetscFree2(mg->actLeaf, mg->actRoot));
    PetscCall(PetscSFDestroy(&mg->actSF));
    PetscCall(PetscFree6(mg->gid, mg->colour, mg->next, mg->r0, mg->R, mg->BB));
    PetscCall(PetscFree(mg->XF));
  }
  mg->nlevels = 0;
  mg->built   = PETSC_FALSE;
  PetscFunctionReturn(PETSC_SUCCESS);
}
