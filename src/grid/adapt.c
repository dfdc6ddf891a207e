/* Topology change of the grid (PF-FLIP Sec. 5.4; docs/grid.md, "Adaptation").

   PffGridAdapt builds the new raster exactly as set-up does (requested map, 2:1 grading, Morton order,
   partition), so a grid adapted to a map equals a grid set up with it, on any rank count. The channels
   then move one at a time, which bounds the extra memory by two copies of one channel: a PetscSF whose
   roots are the old storage and whose leaves are, for each new local block that was active before, a
   copy of its old block; each block is then resampled to its new level (resample.c). The SF moves
   units of nmin^3 floats (nmin: the cells per axis of the coarsest level), which every block size is a
   multiple of, so its graph has one entry per coarsest-block's worth of data rather than per value.
   Views, halo buffers and halo plans are rebuilt from the new raster; the topology state tells every
   object that cached anything derived from the old one. */
#include "gridimpl.h"
#include <omp.h>

const char *const PffTransferTypes[] = {"linear", "constant", "none", "PffTransferType", "PFF_TRANSFER_", NULL};

PetscErrorCode PffGridSetChannelTransfer(PffGrid g, PetscInt ch, PffTransferType type)
{
  PffChannel *c;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetChannel_Private(g, ch, &c));
  PetscCheck(type >= PFF_TRANSFER_LINEAR && type <= PFF_TRANSFER_NONE, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
             "PffGridSetChannelTransfer: unknown transfer type %d", (int)type);
  c->transfer = type;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridGetChannelTransfer(PffGrid g, PetscInt ch, PffTransferType *type)
{
  PffChannel *c;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetChannel_Private(g, ch, &c));
  *type = c->transfer;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridGetTopologyState(PffGrid g, PetscObjectState *state)
{
  PetscFunctionBeginUser;
  *state = g->topology;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridGetAdaptInfo(PffGrid g, PffAdaptInfo *info)
{
  PetscFunctionBeginUser;
  *info = g->adaptInfo;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The raster arrays that the transfer reads after the new raster replaced them. */
typedef struct {
  PetscInt    *level;
  PetscMPIInt *owner;
  PetscInt64  *offset;
  PetscInt64   ncells;
} OldRaster;

/* The SF from the old storage of a channel of ncomp components to, for each new local block that was
   active before, a copy of its old block at leaf float offset start[lb] (-1: the block is new). */
static PetscErrorCode TransferSF(PffGrid g, const OldRaster *old, PetscInt ncomp, PetscInt unit, PetscSF *sf,
                                 PetscInt64 start[], PetscInt64 *nleafFloats, PetscInt64 *remoteFloats)
{
  PetscInt64   nleaves = 0, remote = 0, nroots = ncomp * old->ncells / unit;
  PetscSFNode *iremote;

  PetscFunctionBeginUser;
  for (PetscInt lb = 0; lb < g->nlocal; lb++) {
    const PetscInt gid = g->lgid[lb];
    start[lb]          = -1;
    if (old->level[gid] < 0) continue;
    const PetscInt64 no = g->n0 >> old->level[gid];
    start[lb]           = nleaves * unit;
    nleaves += ncomp * no * no * no / unit;
  }
  PetscCheck(nleaves <= PETSC_MAX_INT && nroots <= PETSC_MAX_INT, PETSC_COMM_SELF, PETSC_ERR_SUP,
             "adapt transfer of %" PetscInt64_FMT " units exceeds the index range; configure with -DPFF_PETSC64=ON",
             PetscMax(nleaves, nroots));
  PetscCall(PetscMalloc1(nleaves, &iremote));
  for (PetscInt lb = 0; lb < g->nlocal; lb++) {
    if (start[lb] < 0) continue;
    const PetscInt   gid = g->lgid[lb];
    const PetscInt64 no = g->n0 >> old->level[gid], units = ncomp * no * no * no / unit;
    const PetscInt64 first = ncomp * old->offset[gid] / unit, e0 = start[lb] / unit;
    for (PetscInt64 u = 0; u < units; u++) {
      iremote[e0 + u].rank  = old->owner[gid];
      iremote[e0 + u].index = (PetscInt)(first + u);
    }
    if (old->owner[gid] != g->rank) remote += units * unit;
  }
  PetscCall(PetscSFCreate(g->comm, sf));
  PetscCall(
      PetscSFSetGraph(*sf, (PetscInt)nroots, (PetscInt)nleaves, NULL, PETSC_OWN_POINTER, iremote, PETSC_OWN_POINTER));
  PetscCall(PetscSFSetUp(*sf));
  *nleafFloats  = nleaves * unit;
  *remoteFloats = remote;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* One block component from no to nn cells per axis by repeated halving or doubling; t0, t1: scratch of
   n0^3 floats each. */
static void ResampleBlock(PffChannelKind kind, PetscInt comp, PffTransferType type, PetscInt no, const float *src,
                          PetscInt nn, float *dst, float *t0, float *t1)
{
  const float *in = src;
  PetscInt     n  = no;

  if (no == nn) {
    memcpy(dst, src, sizeof(float) * (size_t)(nn * nn * nn));
    return;
  }
  while (n != nn) {
    const PetscInt next = n > nn ? n / 2 : 2 * n;
    float         *out  = next == nn ? dst : (in == t0 ? t1 : t0);
    if (n > nn)
      PffBlockRestrict(kind, comp, n, in, out);
    else
      PffBlockProlong(kind, comp, type, n, in, out);
    in = out;
    n  = next;
  }
}

/* The transfer of the channels of ncomp components: one SF (and leaf layout) serves every such channel,
   since blocks move alike whatever they hold; built on first use. */
typedef struct {
  PetscSF     sf;
  PetscInt64 *start, nleaf, remote;
} Transfer;

/* Moves one channel to the new raster: views and halo buffer for it; old values resampled. The old blocks come
   into recv (*nrecv floats, grown as needed and shared by the channels of one adapt), so the storage itself can be
   reused when the new one fits in it. */
static PetscErrorCode TransferChannel(PffGrid g, PffChannel *c, const OldRaster *old, PetscInt unit,
                                      MPI_Datatype unitType, float *scratch, Transfer *tr, float **recv, size_t *nrecv,
                                      PetscInt64 *bytesMoved)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree(c->views));
  PetscCall(PetscFree(c->faces));
  if (c->transfer != PFF_TRANSFER_NONE) {
    if (!tr->sf) {
      PetscCall(PetscMalloc1(g->nlocal, &tr->start));
      PetscCall(TransferSF(g, old, c->ncomp, unit, &tr->sf, tr->start, &tr->nleaf, &tr->remote));
    }
    if ((size_t)tr->nleaf > *nrecv) {
      PetscCall(PetscFree(*recv));
      *nrecv = (size_t)tr->nleaf;
      PetscCall(PetscMalloc1(*nrecv, recv));
    }
    PetscCall(PetscSFBcastBegin(tr->sf, unitType, c->data, *recv, MPI_REPLACE));
    PetscCall(PetscSFBcastEnd(tr->sf, unitType, c->data, *recv, MPI_REPLACE));
    *bytesMoved += (PetscInt64)sizeof(float) * tr->remote;
  }
  /* zeroed here only where nothing is transferred: blocks that were inactive, or every block */
  PetscCall(PffGridAllocateChannel_Private(g, c, (PetscBool)(c->transfer == PFF_TRANSFER_NONE)));
  if (c->transfer != PFF_TRANSFER_NONE) {
    const PetscInt64 *start = tr->start;
    const float      *in    = *recv;
    const PetscInt    n0    = g->n0;
#pragma omp parallel for schedule(dynamic, 1)
    for (PetscInt lb = 0; lb < g->nlocal; lb++) {
      if (start[lb] < 0) {
        memset(c->data + c->ncomp * g->loff[lb], 0,
               sizeof(float) * (size_t)(c->ncomp * (g->loff[lb + 1] - g->loff[lb])));
        continue;
      }
      const PetscInt gid = g->lgid[lb], no = n0 >> old->level[gid], nn = n0 >> g->level[gid];
      float         *t0 = scratch + (size_t)2 * n0 * n0 * n0 * (size_t)omp_get_thread_num(), *t1 = t0 + n0 * n0 * n0;
      for (PetscInt comp = 0; comp < c->ncomp; comp++)
        ResampleBlock(c->kind, comp, c->transfer, no, in + start[lb] + comp * no * no * no, nn,
                      c->data + c->ncomp * g->loff[lb] + comp * nn * nn * nn, t0, t1);
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Block counts of the change, the same on every rank (the rasters are replicated). */
static void CountChanges(PffGrid g, const OldRaster *old, PffAdaptInfo *info)
{
  for (PetscInt b = 0; b < g->nblocks; b++) {
    const PetscInt lo = old->level[b], ln = g->level[b];
    if (lo < 0 && ln >= 0) info->activated++;
    if (lo >= 0 && ln < 0) info->deactivated++;
    if (lo >= 0 && ln >= 0) {
      if (ln < lo) info->refined++;
      if (ln > lo) info->coarsened++;
      if (old->owner[b] != g->owner[b]) info->moved++;
    }
  }
}

PetscErrorCode PffGridAdapt(PffGrid g, const PetscInt level[])
{
  OldRaster      old;
  PffAdaptInfo   info = {0};
  const PetscInt nmin = g->n0 >> (g->nlevels - 1), unit = nmin * nmin * nmin;
  MPI_Datatype   unitType;
  float         *scratch;
  PetscLogDouble t0, t1;

  PetscFunctionBeginUser;
  PetscCheck(g->setupcalled, g->comm, PETSC_ERR_ORDER, "PffGridAdapt: call PffGridSetUp() first");
  PetscCall(PetscLogEventBegin(PFF_GridAdapt, 0, 0, 0, 0));
  PetscCall(PetscTime(&t0));
  /* the request, checked before anything changes: the given map, or the current (graded) levels */
  if (level) {
    PetscInt nact = 0;
    for (PetscInt b = 0; b < g->nblocks; b++) {
      PetscCheck(level[b] >= -1 && level[b] < g->nlevels, g->comm, PETSC_ERR_ARG_OUTOFRANGE,
                 "PffGridAdapt: the map asks for level %" PetscInt_FMT " at block %" PetscInt_FMT
                 "; levels must be in [-1, -grid_levels - 1 = %" PetscInt_FMT "]",
                 level[b], b, g->nlevels - 1);
      nact += level[b] >= 0;
    }
    PetscCheck(nact > 0, g->comm, PETSC_ERR_ARG_WRONG, "PffGridAdapt: the map leaves no active block");
  }
  if (!g->usermap) PetscCall(PetscMalloc1(g->nblocks, &g->usermap));
  for (PetscInt b = 0; b < g->nblocks; b++) g->usermap[b] = level ? level[b] : g->level[b];
  old.level  = g->level;
  old.owner  = g->owner;
  old.offset = g->offset;
  old.ncells = g->ncells;
  g->level   = NULL;
  g->owner   = NULL;
  g->offset  = NULL;
  PetscCall(PetscFree(g->morton));
  PetscCall(PetscFree(g->local));
  PetscCall(PetscFree(g->order));
  PetscCall(PffGridBuildRaster_Private(g));
  PetscCall(PffGridPartition_Private(g));
  for (PetscInt p = 0; p < g->nplans; p++) PetscCall(PffHaloPlanDestroy_Private(&g->plans[p]));
  g->nplans = 0;
  CountChanges(g, &old, &info);

  PetscCallMPI(MPI_Type_contiguous((int)unit, MPI_FLOAT, &unitType));
  PetscCallMPI(MPI_Type_commit(&unitType));
  PetscCall(PetscMalloc1((size_t)2 * g->n0 * g->n0 * g->n0 * (size_t)omp_get_max_threads(), &scratch));
  {
    Transfer tr[2] = {{NULL, NULL, 0, 0}, {NULL, NULL, 0, 0}}; /* cell channels, face channels */
    float   *recv  = NULL;
    size_t   nrecv = 0;
    for (PetscInt c = 0; c < g->nch; c++)
      PetscCall(TransferChannel(g, g->ch[c], &old, unit, unitType, scratch, &tr[g->ch[c]->ncomp == 3], &recv, &nrecv,
                                &info.bytesMoved));
    PetscCall(PetscFree(recv));
    for (int k = 0; k < 2; k++) {
      PetscCall(PetscSFDestroy(&tr[k].sf));
      PetscCall(PetscFree(tr[k].start));
    }
  }
  PetscCall(PetscFree(scratch));
  PetscCallMPI(MPI_Type_free(&unitType));
  PetscCall(PetscFree(old.level));
  PetscCall(PetscFree(old.owner));
  PetscCall(PetscFree(old.offset));
  PetscCall(PffGridComputeQuality_Private(g));
  g->topology++;

  PetscCall(PetscTime(&t1));
  PetscReal sec = (PetscReal)(t1 - t0);
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &info.bytesMoved, 1, MPIU_INT64, MPI_SUM, g->comm));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &sec, 1, MPIU_REAL, MPI_MAX, g->comm));
  info.seconds = sec;
  g->adaptInfo = info;
  PetscCall(PetscLogEventEnd(PFF_GridAdapt, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}
