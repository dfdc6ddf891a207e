/* Extrapolation of the liquid velocity into the air (PF-FLIP Sec. 3.7): "the liquid velocity is
   extrapolated into the air phase by a few cells to ensure that liquid particles are advected with
   the corresponding velocities". It serves the Advect stage: liquid particles sample the result,
   air particles the mixture velocity u of the projection.

   Layer 0 is the set of liquid faces, open faces with phi_f >= 1/2; they keep u. Layer L = 1..N:
   every open face not yet valid whose valid face-neighbours of the same component (the 6 neighbours
   in that component's lattice) number k > 0 takes their mean and becomes valid for layer L + 1.
   Validity is read from layer L - 1 only, so the result depends neither on the loop order nor on the
   rank count. Faces beyond N layers keep u; closed faces (walls, solids) are never sources and hold 0.

   Ghosts come from the grid's halo exchange of the mask m (1 valid, 0 not) and of m u. Across a
   level boundary a ghost is an interpolation (coarser neighbour; weights leave [0, 1] where the grid
   extrapolates linearly near the neighbour's edge) or a mean (finer neighbour) of both; it counts as
   valid when its interpolated mask is >= 1/2 (at least half the weight on valid faces) and its value
   is (m u)/m, the mean of the valid sources only. Same-level ghosts have m in {0, 1} and are exact. */
#include "flowimpl.h"

/* A face made valid in the current layer is marked pending (m = -1 < 1/2): a neighbour read in place
   (same level, same rank) then still sees it as invalid, as a copied ghost would. */
#define PFF_EXTRAP_PENDING -1.0f

/* Channels of one call: phi_f, open, mask, then (u, ul) per extrapolated field; every field shares the mask, so
   that the layers, their halo exchanges of the mask and the neighbour scans are done once for all of them. */
#define PFF_EXTRAP_MAXF 2
#define PFF_EXTRAP_NCH(nf) (3 + 2 * (nf))

typedef enum {
  PFF_EXTRAP_INIT,   /* layer 0: m = 1 on open liquid faces, ul = m u */
  PFF_EXTRAP_COMMIT, /* pending faces become valid */
  PFF_EXTRAP_LAST    /* the same, then faces never made valid take u (0 if closed) */
} PffExtrapPass;

/* A face-by-face pass over every owned face of every component. */
static PetscErrorCode PffExtrapolatePass(PffGrid grid, const PetscInt ch[], PetscInt nf, PetscInt nlocal,
                                         PffExtrapPass pass)
{
  PetscFunctionBeginUser;
  for (PetscInt lb = 0; lb < nlocal; lb++)
    for (PetscInt d = 0; d < 3; d++) {
      float   *a[PFF_EXTRAP_NCH(PFF_EXTRAP_MAXF)];
      PetscInt n3 = 0;
      PetscCall(PffFlowGridBlockData_Private(grid, lb, d, PFF_EXTRAP_NCH(nf), ch, a, &n3));
      const float *phi = a[0], *open = a[1];
      float       *m = a[2];
      for (PetscInt c = 0; c < n3; c++) {
        if (pass == PFF_EXTRAP_INIT) {
          const PetscBool valid = open[c] > 0 && phi[c] >= 0.5f;
          m[c]                  = valid ? 1.0f : 0.0f;
          for (PetscInt q = 0; q < nf; q++) a[4 + 2 * q][c] = valid ? a[3 + 2 * q][c] : 0.0f;
          continue;
        }
        if (m[c] == PFF_EXTRAP_PENDING) m[c] = 1.0f;
        if (pass == PFF_EXTRAP_LAST && m[c] == 0)
          for (PetscInt q = 0; q < nf; q++) a[4 + 2 * q][c] = open[c] > 0 ? a[3 + 2 * q][c] : 0.0f;
      }
    }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Whether a layer can reach a face of the block: a valid face (m >= 1/2) inside it or in the ghost cells
   next to its sides, which are all that the layer reads. Most of the air is not reached, and a layer
   that skips it does the same work as one that scans it. */
static PetscBool PffExtrapolateBlockReached(const PffView *vm, const float *m, PetscInt n)
{
  PetscInt valid = 0;
  for (PetscInt c = 0; c < n * n * n; c++) valid += m[c] >= 0.5f;
  /* a side's ghost cells all lie in one region of the views: its view once, then plain strides */
  for (PetscInt f = 0; f < 6 && !valid; f++) {
    PetscInt p[3];
    PffBlockSideCell(f, f % 2 ? n : -1, 0, 0, p);
    const PffView  *w = &vm[PffRegionIndex(p[0], p[1], p[2], n)];
    const float    *g = w->ptr + w->off + p[0] * w->sx + p[1] * w->sy + p[2] * w->sz;
    const PetscInt  a = f / 2, su = (a + 1) % 3, sv = (a + 2) % 3; /* u runs along axis su, v along sv */
    const ptrdiff_t st[3] = {w->sx, w->sy, w->sz};
    for (PetscInt v = 0; v < n; v++)
      for (PetscInt u = 0; u < n; u++) valid += g[u * st[su] + v * st[sv]] >= 0.5f;
  }
  return (PetscBool)(valid > 0);
}

/* One layer on component d of local block lb; ghosts of m and of every ul are current. Returns the faces it
   made valid (marked pending). */
static PetscErrorCode PffExtrapolateLayerBlock(PffGrid grid, const PetscInt ch[], PetscInt nf, PetscInt lb, PetscInt d,
                                               PetscInt *count)
{
  PffBlockInfo   info;
  const PffView *vm, *vu[PFF_EXTRAP_MAXF];
  float         *a[PFF_EXTRAP_NCH(PFF_EXTRAP_MAXF)];
  PetscInt       added = 0;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetBlockInfo(grid, lb, &info));
  PetscCall(PffFlowGridBlockData_Private(grid, lb, d, PFF_EXTRAP_NCH(nf), ch, a, NULL));
  PetscCall(PffGridGetBlockViews(grid, ch[2], lb, d, &vm));
  for (PetscInt q = 0; q < nf; q++) PetscCall(PffGridGetBlockViews(grid, ch[4 + 2 * q], lb, d, &vu[q]));
  const float   *open = a[1];
  float         *m    = a[2];
  const PetscInt n    = info.n;
  if (!PffExtrapolateBlockReached(vm, m, n)) PetscFunctionReturn(PETSC_SUCCESS);
  for (PetscInt k = 0; k < n; k++)
    for (PetscInt j = 0; j < n; j++)
      for (PetscInt i = 0; i < n; i++) {
        const PetscInt c = i + n * (j + n * k);
        if (m[c] != 0 || !(open[c] > 0)) continue;
        PetscReal sum[PFF_EXTRAP_MAXF] = {0};
        PetscInt  cnt                  = 0;
        for (PetscInt q = 0; q < 6; q++) {
          const PetscInt  s = q % 2 ? 1 : -1, ax = q / 2;
          const PetscInt  ii = i + (ax == 0 ? s : 0), jj = j + (ax == 1 ? s : 0), kk = k + (ax == 2 ? s : 0);
          const PetscReal mq = *PffViewsAt(vm, ii, jj, kk, n);
          if (!(mq >= 0.5)) continue;
          for (PetscInt f = 0; f < nf; f++) sum[f] += (PetscReal)*PffViewsAt(vu[f], ii, jj, kk, n) / mq;
          cnt++;
        }
        if (!cnt) continue;
        for (PetscInt f = 0; f < nf; f++) a[4 + 2 * f][c] = (float)(sum[f] / (PetscReal)cnt);
        m[c] = PFF_EXTRAP_PENDING;
        added++;
      }
  *count += added;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The layers' result from the work channels into the results (owned faces; the caller's exchange does the rest). */
static PetscErrorCode PffExtrapolateCopyWork(PffGrid grid, PetscInt nf, const PetscInt ch[], const PetscInt chUl[],
                                             PetscInt nlocal)
{
  PetscFunctionBeginUser;
  for (PetscInt q = 0; q < nf; q++) {
    if (ch[4 + 2 * q] == chUl[q]) continue;
    for (PetscInt lb = 0; lb < nlocal; lb++)
      for (PetscInt d = 0; d < 3; d++) {
        const PetscInt pair[2] = {ch[4 + 2 * q], chUl[q]};
        float         *a[2];
        PetscInt       n3 = 0;
        PetscCall(PffFlowGridBlockData_Private(grid, lb, d, 2, pair, a, &n3));
        PetscCall(PetscArraycpy(a[1], a[0], n3));
      }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffExtrapolateLiquidVelocities(PffGrid grid, PetscInt nf, const PetscInt chU[], PetscInt chPhiF,
                                              PetscInt chOpen, PetscInt layers, PetscInt chMask, const PetscInt chUl[],
                                              const PetscInt chWork[], PetscInt64 *faces)
{
  PetscInt ch[PFF_EXTRAP_NCH(PFF_EXTRAP_MAXF)], nlocal, added = 0, nwork = 0;
  MPI_Comm comm;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetComm(grid, &comm));
  PetscCheck(layers >= 0, comm, PETSC_ERR_ARG_OUTOFRANGE, "extrapolation layers %" PetscInt_FMT " must be >= 0",
             layers);
  PetscCheck(nf >= 1 && nf <= PFF_EXTRAP_MAXF, comm, PETSC_ERR_ARG_OUTOFRANGE,
             "extrapolation of %" PetscInt_FMT " fields: 1 to %d at once", nf, PFF_EXTRAP_MAXF);
  ch[0] = chPhiF;
  ch[1] = chOpen;
  ch[2] = chMask;
  for (PetscInt q = 0; q < nf; q++) {
    const PetscBool work = (PetscBool)(chWork && chWork[q] >= 0);
    ch[3 + 2 * q]        = chU[q];
    ch[4 + 2 * q]        = work ? chWork[q] : chUl[q];
    nwork += work;
  }
  for (PetscInt k = 0; k < PFF_EXTRAP_NCH(nf); k++) {
    const char    *name;
    PffChannelKind kind;
    PetscCall(PffGridGetChannelInfo(grid, ch[k], &name, &kind, NULL, NULL));
    PetscCheck(kind == PFF_CHANNEL_FACE, comm, PETSC_ERR_ARG_WRONG, "extrapolation channel %s must be a face channel",
               name);
  }
  for (PetscInt q = 0; q < nf; q++) {
    PetscBool distinct =
        (PetscBool)(chMask != chUl[q] && chUl[q] != chU[q] && ch[4 + 2 * q] != chMask && ch[4 + 2 * q] != chU[q]);
    for (PetscInt r = 0; r < nf; r++)
      if (r != q) distinct = (PetscBool)(distinct && chUl[r] != chUl[q] && ch[4 + 2 * r] != ch[4 + 2 * q]);
    PetscCheck(distinct, comm, PETSC_ERR_ARG_WRONG,
               "extrapolation needs distinct mask, source, result and work channels");
  }
  PetscCall(PetscLogEventBegin(PFF_FlowExtrap, 0, 0, 0, 0));
  PetscCall(PffGridGetLocalBlocks(grid, &nlocal));
  PetscCall(PffExtrapolatePass(grid, ch, nf, nlocal, PFF_EXTRAP_INIT));
  for (PetscInt l = 1; l <= layers; l++) {
    PetscCall(PffGridHaloBegin(grid, chMask));
    for (PetscInt q = 0; q < nf; q++) PetscCall(PffGridHaloBegin(grid, ch[4 + 2 * q]));
    PetscCall(PffGridHaloEnd(grid, chMask));
    for (PetscInt q = 0; q < nf; q++) PetscCall(PffGridHaloEnd(grid, ch[4 + 2 * q]));
    for (PetscInt lb = 0; lb < nlocal; lb++)
      for (PetscInt d = 0; d < 3; d++) PetscCall(PffExtrapolateLayerBlock(grid, ch, nf, lb, d, &added));
    PetscCall(PffExtrapolatePass(grid, ch, nf, nlocal, l == layers ? PFF_EXTRAP_LAST : PFF_EXTRAP_COMMIT));
  }
  if (layers == 0) PetscCall(PffExtrapolatePass(grid, ch, nf, nlocal, PFF_EXTRAP_LAST));
  if (nwork) PetscCall(PffExtrapolateCopyWork(grid, nf, ch, chUl, nlocal));
  for (PetscInt q = 0; q < nf; q++) PetscCall(PffGridHaloBegin(grid, chUl[q]));
  for (PetscInt q = 0; q < nf; q++) PetscCall(PffGridHaloEnd(grid, chUl[q]));
  PetscCall(PetscLogEventEnd(PFF_FlowExtrap, 0, 0, 0, 0));
  if (faces) {
    PetscInt64 g = added;
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &g, 1, MPIU_INT64, MPI_SUM, comm));
    *faces = g;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffExtrapolateLiquidVelocity(PffGrid grid, PetscInt chU, PetscInt chPhiF, PetscInt chOpen,
                                            PetscInt layers, PetscInt chMask, PetscInt chUl, PetscInt chWork,
                                            PetscInt64 *faces)
{
  PetscFunctionBeginUser;
  PetscCall(PffExtrapolateLiquidVelocities(grid, 1, &chU, chPhiF, chOpen, layers, chMask, &chUl, &chWork, faces));
  PetscFunctionReturn(PETSC_SUCCESS);
}
