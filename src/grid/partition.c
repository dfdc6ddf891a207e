/* Partition of the active blocks over the ranks (DESIGN.md Sec. 5).

   morton: the blocks in Morton order carry work weights (cells at their level); their prefix sum is
   cut into equal parts, so each rank owns one contiguous stretch of the space-filling curve.
   metis:  k-way partition of the face-adjacency graph of active blocks, vertex weight = cells, edge
           weight = cells on the shared face at the finer side. Computed on rank 0 with a fixed seed
           and broadcast, so every rank holds the same owner map.
   columns: every block column along y (the blocks with the same x and z index) goes to one rank; the
           columns in 2D Morton order of (x, z) carry the summed work of their blocks, and the prefix sum
           is cut as for morton. The tall-cell solver needs whole columns on a rank (docs/tallcell.md).
   All three are deterministic. Owned blocks are stored in Morton order either way. */
#include "gridimpl.h"
#include <metis.h>

static PetscInt64 PffBlockCells(PffGrid g, PetscInt gid)
{
  const PetscInt64 n = g->n0 >> g->level[gid];
  return n * n * n;
}

/* Cells at the block's level, plus the extra work set by PffGridSetBlockWork (particles, say). */
static PetscInt64 PffBlockWork(PffGrid g, PetscInt gid)
{
  return PffBlockCells(g, gid) + (g->xwork ? g->xwork[gid] : 0);
}

/* max over ranks of the work per rank / its mean, from the replicated raster */
static PetscErrorCode PffGridImbalance(PffGrid g, PetscReal *imbalance)
{
  PetscInt64 *work, wmax = 0, wsum = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscCalloc1(g->size, &work));
  for (PetscInt a = 0; a < g->nactive; a++) work[g->owner[g->order[a]]] += PffBlockWork(g, g->order[a]);
  for (PetscMPIInt r = 0; r < g->size; r++) {
    wmax = PetscMax(wmax, work[r]);
    wsum += work[r];
  }
  PetscCall(PetscFree(work));
  *imbalance = wsum > 0 ? (PetscReal)wmax * (PetscReal)g->size / (PetscReal)wsum : 1;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridSetBlockWork(PffGrid g, const PetscInt64 extra[])
{
  PetscFunctionBeginUser;
  PetscCheck(g->setupcalled, g->comm, PETSC_ERR_ORDER, "PffGridSetBlockWork: call PffGridSetUp() first");
  if (!extra)
    PetscCall(PetscFree(g->xwork));
  else {
    if (!g->xwork) PetscCall(PetscMalloc1(g->nblocks, &g->xwork));
    for (PetscInt b = 0; b < g->nblocks; b++) {
      PetscCheck(extra[b] >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
                 "PffGridSetBlockWork: negative work %" PetscInt64_FMT " at block %" PetscInt_FMT, extra[b], b);
      g->xwork[b] = extra[b];
    }
  }
  PetscCall(PffGridImbalance(g, &g->quality.imbalance));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffPartitionMorton(PffGrid g)
{
  PetscInt64 total = 0, acc = 0;

  PetscFunctionBeginUser;
  for (PetscInt a = 0; a < g->nactive; a++) total += PffBlockWork(g, g->order[a]);
  for (PetscInt a = 0; a < g->nactive; a++) {
    const PetscInt64 w = PffBlockWork(g, g->order[a]);
    /* the block goes to the rank whose share holds the block's midpoint */
    const PetscInt64 r    = ((2 * acc + w) * (PetscInt64)g->size) / (2 * total);
    g->owner[g->order[a]] = (PetscMPIInt)PetscMin(r, (PetscInt64)g->size - 1);
    acc += w;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffPartitionColumns(PffGrid g)
{
  const PetscInt nc = g->nb[0] * g->nb[2];
  PetscInt      *order;
  uint64_t      *key;
  PetscInt64    *work, total = 0, acc = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc3(nc, &order, nc, &key, nc, &work));
  for (PetscInt c = 0; c < nc; c++) {
    order[c] = c;
    key[c]   = PffMortonEncode((uint32_t)(c % g->nb[0]), 0, (uint32_t)(c / g->nb[0]));
    work[c]  = 0;
  }
  for (PetscInt b = 0; b < g->nblocks; b++)
    if (g->level[b] >= 0) work[b % g->nb[0] + g->nb[0] * (b / (g->nb[0] * g->nb[1]))] += PffBlockWork(g, b);
  /* insertion sort by key: the raster has at most a few thousand columns */
  for (PetscInt a = 1; a < nc; a++)
    for (PetscInt q = a; q > 0 && key[order[q]] < key[order[q - 1]]; q--) {
      const PetscInt tmp = order[q];
      order[q]           = order[q - 1];
      order[q - 1]       = tmp;
    }
  for (PetscInt c = 0; c < nc; c++) total += work[c];
  for (PetscInt a = 0; a < nc; a++) {
    const PetscInt   c = order[a];
    const PetscInt64 w = work[c], r = total > 0 ? ((2 * acc + w) * (PetscInt64)g->size) / (2 * total) : 0;
    for (PetscInt j = 0; j < g->nb[1]; j++) {
      const PetscInt b = c % g->nb[0] + g->nb[0] * (j + g->nb[1] * (c / g->nb[0]));
      if (g->level[b] >= 0) g->owner[b] = (PetscMPIInt)PetscMin(r, (PetscInt64)g->size - 1);
    }
    acc += w;
  }
  PetscCall(PetscFree3(order, key, work));
  PetscFunctionReturn(PETSC_SUCCESS);
}

#define PffCallMETIS(call)                                                                                             \
  do {                                                                                                                 \
    int _st = (call);                                                                                                  \
    PetscCheck(_st == METIS_OK, PETSC_COMM_SELF, PETSC_ERR_LIB, "METIS call %s failed with status %d", #call, _st);    \
  } while (0)

static PetscErrorCode PffPartitionMetis(PffGrid g)
{
  PetscMPIInt *part = NULL;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(g->nactive, &part));
  if (g->rank == 0) {
    PetscInt *pos; /* Morton position of each active block */
    idx_t *xadj, *adjncy, *vwgt, *adjwgt, *mpart, nvtxs = (idx_t)g->nactive, ncon = 1, nparts = (idx_t)g->size, objval;
    idx_t  options[METIS_NOPTIONS];
    PetscInt nedge = 0;

    PetscCall(PetscMalloc1(g->nblocks, &pos));
    for (PetscInt a = 0; a < g->nactive; a++) pos[g->order[a]] = a;
    PetscCall(PetscMalloc5(g->nactive + 1, &xadj, 6 * g->nactive, &adjncy, g->nactive, &vwgt, 6 * g->nactive, &adjwgt,
                           g->nactive, &mpart));
    xadj[0] = 0;
    for (PetscInt a = 0; a < g->nactive; a++) {
      const PetscInt gid = g->order[a];
      PetscInt       ijk[3];
      PffGridBlockIJK_Private(g, gid, ijk);
      const idx_t first = (idx_t)nedge;
      vwgt[a]           = (idx_t)PffBlockWork(g, gid);
      for (int f = 0; f < 6; f++) {
        PetscInt d[3]      = {0, 0, 0};
        d[f / 2]           = (f % 2) ? 1 : -1;
        const PetscInt nbr = PffRasterNeighbour(g->nb, g->periodic, ijk, d);
        if (nbr < 0 || nbr == gid || g->level[nbr] < 0) continue;
        PetscBool dup = PETSC_FALSE; /* periodic axes of two blocks meet the same neighbour twice */
        for (idx_t e = first; e < (idx_t)nedge; e++) dup = (PetscBool)(dup || adjncy[e] == (idx_t)pos[nbr]);
        if (dup) continue;
        const PetscInt64 nf = g->n0 >> PetscMin(g->level[gid], g->level[nbr]);
        adjncy[nedge]       = (idx_t)pos[nbr];
        adjwgt[nedge++]     = (idx_t)(nf * nf);
      }
      xadj[a + 1] = (idx_t)nedge;
    }
    if (g->size == 1) {
      for (PetscInt a = 0; a < g->nactive; a++) mpart[a] = 0;
    } else {
      PffCallMETIS(METIS_SetDefaultOptions(options));
      options[METIS_OPTION_SEED]      = 7;
      options[METIS_OPTION_NUMBERING] = 0;
      PffCallMETIS(METIS_PartGraphKway(&nvtxs, &ncon, xadj, adjncy, vwgt, NULL, adjwgt, &nparts, NULL, NULL, options,
                                       &objval, mpart));
    }
    for (PetscInt a = 0; a < g->nactive; a++) part[a] = (PetscMPIInt)mpart[a];
    PetscCall(PetscFree5(xadj, adjncy, vwgt, adjwgt, mpart));
    PetscCall(PetscFree(pos));
  }
  PetscMPIInt cnt;
  PetscCall(PetscMPIIntCast(g->nactive, &cnt));
  PetscCallMPI(MPI_Bcast(part, cnt, MPI_INT, 0, g->comm));
  for (PetscInt a = 0; a < g->nactive; a++) g->owner[g->order[a]] = part[a];
  PetscCall(PetscFree(part));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridPartition_Private(PffGrid g)
{
  PetscInt64 *next;

  PetscFunctionBeginUser;
  PetscCall(PetscLogEventBegin(PFF_GridPartition, 0, 0, 0, 0));
  for (PetscInt b = 0; b < g->nblocks; b++) {
    g->owner[b]  = -1;
    g->offset[b] = -1;
    g->local[b]  = -1;
  }
  if (g->ptype == PFF_PARTITION_METIS)
    PetscCall(PffPartitionMetis(g));
  else if (g->ptype == PFF_PARTITION_COLUMNS)
    PetscCall(PffPartitionColumns(g));
  else
    PetscCall(PffPartitionMorton(g));

  /* storage offsets on every owner, so any rank can address a neighbour's cells remotely */
  PetscCall(PetscCalloc1(g->size, &next));
  g->nlocal = 0;
  for (PetscInt a = 0; a < g->nactive; a++) {
    const PetscInt gid = g->order[a];
    g->offset[gid]     = next[g->owner[gid]];
    next[g->owner[gid]] += PffBlockCells(g, gid);
    if (g->owner[gid] == g->rank) g->nlocal++;
  }
  g->ncells = next[g->rank];
  PetscCall(PetscFree(g->rankCellStart));
  PetscCall(PetscMalloc1(g->size + 1, &g->rankCellStart));
  g->rankCellStart[0] = 0;
  for (PetscMPIInt r = 0; r < g->size; r++) g->rankCellStart[r + 1] = g->rankCellStart[r] + next[r];
  PetscCall(PetscFree(next));
  PetscCall(PetscFree(g->lgid));
  PetscCall(PetscFree(g->loff));
  PetscCall(PetscFree(g->lholes));
  PetscCall(PetscMalloc1(g->nlocal, &g->lgid));
  PetscCall(PetscCalloc1(g->nlocal, &g->lholes));
  PetscCall(PetscMalloc1(g->nlocal + 1, &g->loff));
  for (PetscInt a = 0, lb = 0; a < g->nactive; a++) {
    const PetscInt gid = g->order[a];
    if (g->owner[gid] != g->rank) continue;
    g->local[gid] = lb;
    g->lgid[lb]   = gid;
    g->loff[lb++] = g->offset[gid];
  }
  g->loff[g->nlocal] = g->ncells;
  /* interpolation and boundary handling ask this per point; the raster answers it once per block */
  for (PetscInt lb = 0; lb < g->nlocal; lb++)
    for (PetscInt r = 0; r < 27; r++)
      if (r != 13 && PffGridActiveNeighbour_Private(g, g->lgid[lb], r) < 0) g->lholes[lb] |= (PetscInt)1 << r;
  PetscCall(PetscLogEventEnd(PFF_GridPartition, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridComputeQuality_Private(PffGrid g)
{
  PffHaloPlan *plan;
  PetscInt     cut = 0;
  PetscReal    recv, rsum, rmax;

  PetscFunctionBeginUser;
  for (PetscInt a = 0; a < g->nactive; a++) {
    const PetscInt gid = g->order[a];
    PetscInt       ijk[3];
    PffGridBlockIJK_Private(g, gid, ijk);
    for (int d = 0; d < 3; d++) { /* each face counted once, from its lower block */
      PetscInt dd[3]     = {0, 0, 0};
      dd[d]              = 1;
      const PetscInt nbr = PffRasterNeighbour(g->nb, g->periodic, ijk, dd);
      if (nbr >= 0 && g->level[nbr] >= 0 && g->owner[nbr] != g->owner[gid]) cut++;
    }
  }
  PetscCall(PffGridImbalance(g, &g->quality.imbalance));
  g->quality.cutFaces = cut;
  PetscCall(PffHaloPlanGet_Private(g, PFF_CHANNEL_CELL, 1, &plan));
  recv = 4.0 * (PetscReal)plan->recvRemote;
  PetscCall(MPIU_Allreduce(&recv, &rsum, 1, MPIU_REAL, MPIU_SUM, g->comm));
  PetscCall(MPIU_Allreduce(&recv, &rmax, 1, MPIU_REAL, MPIU_MAX, g->comm));
  g->quality.haloBytesMax  = rmax;
  g->quality.haloBytesMean = rsum / (PetscReal)g->size;
  PetscFunctionReturn(PETSC_SUCCESS);
}
