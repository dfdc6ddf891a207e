/* Block storage: per channel one allocation holding each owned block's components contiguously
   ([block][comp][n^3], x fastest, blocks in Morton order), and the 27 region views per block
   component through which kernels reach the block's neighbourhood without branching on where
   the data lives (own storage, a same-level neighbour on this rank, or a ghost buffer). */
#include "gridimpl.h"

PetscErrorCode PffGridAddChannel(PffGrid g, const char name[], PffChannelKind kind, PetscInt width, PetscInt *ch)
{
  PffChannel *c;

  PetscFunctionBeginUser;
  PetscCheck(ch != NULL, g->comm, PETSC_ERR_ARG_NULL, "PffGridAddChannel: the channel index argument must not be NULL");
  PetscCheck(g->nch < PFF_GRID_MAX_CHANNELS, g->comm, PETSC_ERR_SUP, "at most %d channels", PFF_GRID_MAX_CHANNELS);
  PetscCheck(width >= 1 && width <= PFF_GRID_MAX_WIDTH, g->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "channel %s: halo width %" PetscInt_FMT " must be in [1, %d]", name, width, PFF_GRID_MAX_WIDTH);
  for (PetscInt i = 0; i < g->nch; i++)
    PetscCheck(strcmp(g->ch[i]->name, name), g->comm, PETSC_ERR_ARG_WRONG, "channel %s exists already", name);
  PetscCall(PetscNew(&c));
  PetscCall(PetscStrncpy(c->name, name, sizeof(c->name)));
  c->kind   = kind;
  c->ncomp  = kind == PFF_CHANNEL_FACE ? 3 : 1;
  c->width  = width;
  c->output = PETSC_TRUE;
  if (g->setupcalled) PetscCall(PffGridAllocateChannel_Private(g, c, PETSC_TRUE));
  g->ch[g->nch] = c;
  *ch           = g->nch++;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Storage of n floats at *buf (capacity *cap), zeroed if zero: kept when it fits without wasting more than a
   quarter of it. An adapt reallocates every channel; fresh pages cost a page fault each on their first touch (and
   zeroing touches them all), about 30 % of GridAdapt in a profile of an adaptive run. New storage goes onto huge
   pages (PffAdviseHugePages). */
static PetscErrorCode ReuseFloats(size_t n, PetscBool zero, float **buf, size_t *cap)
{
  PetscFunctionBeginUser;
  if (*buf && *cap >= n && *cap - n <= n / 4) {
    if (zero) PetscCall(PetscArrayzero(*buf, n));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PetscCall(PetscFree(*buf));
  PetscCall(PetscMalloc1(n, buf));
  PffAdviseHugePages(*buf, sizeof(float) * n); /* before the first write */
  if (zero) PetscCall(PetscArrayzero(*buf, n));
  *cap = n;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* zero: the owned values start at 0; otherwise only the pads do (the caller writes every block). Storage the
   channel already has is reused when it fits (an adapt frees the views, faces and halo plan, not the storage). */
PetscErrorCode PffGridAllocateChannel_Private(PffGrid g, PffChannel *c, PetscBool zero)
{
  const PetscInt nmin = g->n0 >> (g->nlevels - 1);
  const size_t   nown = (size_t)(c->ncomp * g->ncells), nall = nown + 3 * PFF_CHANNEL_PAD;

  PetscFunctionBeginUser;
  PetscCheck(c->width <= nmin, g->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "channel %s: halo width %" PetscInt_FMT " exceeds the %" PetscInt_FMT
             " cells per axis of the coarsest blocks; lower -grid_levels or raise -grid_block_size",
             c->name, c->width, nmin);
  PetscCall(PffHaloPlanGet_Private(g, c->kind, c->width, &c->plan));
  PetscCall(ReuseFloats(nall, zero, &c->alloc, &c->nalloc));
  /* rows of n >= 16 cells then start on 64-byte boundaries, which streaming stores need */
  c->data = c->alloc + PFF_CHANNEL_PAD;
  while (((uintptr_t)c->data) % 64) c->data++;
  if (!zero) {
    PetscCall(PetscArrayzero(c->alloc, c->data - c->alloc));
    PetscCall(PetscArrayzero(c->data + nown, c->alloc + nall - (c->data + nown)));
  }
  PetscCall(ReuseFloats((size_t)PetscMax(c->plan->nhalo, 1), PETSC_TRUE, &c->halo, &c->nhaloAlloc));
  PetscCall(PetscMalloc1(g->nlocal * c->ncomp * 27, &c->views));
  for (PetscInt lb = 0; lb < g->nlocal; lb++) {
    const PetscInt gid = g->lgid[lb], n = PffGridBlockN_Private(g, gid);
    for (PetscInt comp = 0; comp < c->ncomp; comp++) {
      for (PetscInt r = 0; r < 27; r++) {
        PffView         *v  = &c->views[(lb * c->ncomp + comp) * 27 + r];
        const PetscInt64 go = c->plan->goff[(lb * c->ncomp + comp) * 27 + r];
        PetscInt         d[3];
        PffRegionDirection(r, d);
        if (r == 13 || go < 0) {
          /* own storage, or a same-level neighbour on this rank read in place */
          const PetscInt src = r == 13 ? gid : PffGridActiveNeighbour_Private(g, gid, r);
          v->ptr             = c->data + c->ncomp * g->offset[src] + comp * n * n * n;
          v->off             = -(ptrdiff_t)(d[0] * n + d[1] * n * n + d[2] * n * n * n);
          v->sx              = 1;
          v->sy              = n;
          v->sz              = n * n;
        } else {
          PetscInt lo[3], ext[3];
          for (int a = 0; a < 3; a++) {
            lo[a]  = d[a] < 0 ? -c->width : (d[a] > 0 ? n : 0);
            ext[a] = d[a] ? c->width : n;
          }
          v->ptr = c->halo + go;
          v->sx  = 1;
          v->sy  = ext[0];
          v->sz  = ext[0] * ext[1];
          v->off = -(ptrdiff_t)(lo[0] + lo[1] * v->sy + lo[2] * v->sz);
        }
      }
    }
  }
  if (c->kind == PFF_CHANNEL_CELL) {
    PetscCall(PetscMalloc1(g->nlocal, &c->faces));
    for (PetscInt lb = 0; lb < g->nlocal; lb++) {
      const PetscInt n = PffGridBlockN_Private(g, g->lgid[lb]);
      const PffView *v = &c->views[lb * 27];
      PffFaceViews  *f = &c->faces[lb];
      f->face[0]       = PffViewsAt(v, -1, 0, 0, n);
      f->face[1]       = PffViewsAt(v, n, 0, 0, n);
      f->face[2]       = PffViewsAt(v, 0, -1, 0, n);
      f->face[3]       = PffViewsAt(v, 0, n, 0, n);
      f->face[4]       = PffViewsAt(v, 0, 0, -1, n);
      f->face[5]       = PffViewsAt(v, 0, 0, n, n);
      /* strides are at most n^2 <= 4096 (storage above), so they fit the packed fields */
      f->sy[0] = (int16_t)v[12].sy;
      f->sy[1] = (int16_t)v[14].sy;
      f->sz[0] = (int16_t)v[12].sz;
      f->sz[1] = (int16_t)v[14].sz;
      f->sz[2] = (int16_t)v[10].sz;
      f->sz[3] = (int16_t)v[16].sz;
      PetscAssert(v[4].sy == n && v[22].sy == n, PETSC_COMM_SELF, PETSC_ERR_PLIB, "z-face rows must be n apart");
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridDestroyChannel_Private(PffChannel **c)
{
  PetscFunctionBeginUser;
  if (!*c) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscFree((*c)->alloc));
  PetscCall(PetscFree((*c)->halo));
  PetscCall(PetscFree((*c)->views));
  PetscCall(PetscFree((*c)->faces));
  PetscCall(PetscFree(*c));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridGetChannel_Private(PffGrid g, PetscInt ch, PffChannel **c)
{
  PetscFunctionBeginUser;
  PetscCheck(ch >= 0 && ch < g->nch, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "no channel %" PetscInt_FMT, ch);
  PetscCheck(g->setupcalled, PETSC_COMM_SELF, PETSC_ERR_ORDER, "call PffGridSetUp() first");
  *c = g->ch[ch];
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridGetNumChannels(PffGrid g, PetscInt *nch)
{
  PetscFunctionBeginUser;
  *nch = g->nch;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridGetChannelInfo(PffGrid g, PetscInt ch, const char **name, PffChannelKind *kind, PetscInt *ncomp,
                                     PetscInt *width)
{
  PetscFunctionBeginUser;
  PetscCheck(ch >= 0 && ch < g->nch, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "no channel %" PetscInt_FMT, ch);
  if (name) *name = g->ch[ch]->name;
  if (kind) *kind = g->ch[ch]->kind;
  if (ncomp) *ncomp = g->ch[ch]->ncomp;
  if (width) *width = g->ch[ch]->width;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridSetChannelOutput(PffGrid g, PetscInt ch, PetscBool write)
{
  PetscFunctionBeginUser;
  PetscCheck(ch >= 0 && ch < g->nch, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
             "PffGridSetChannelOutput: no channel %" PetscInt_FMT " (the grid has %" PetscInt_FMT ")", ch, g->nch);
  g->ch[ch]->output = write;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridGetChannelOutput(PffGrid g, PetscInt ch, PetscBool *write)
{
  PetscFunctionBeginUser;
  PetscCheck(ch >= 0 && ch < g->nch, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
             "PffGridGetChannelOutput: no channel %" PetscInt_FMT " (the grid has %" PetscInt_FMT ")", ch, g->nch);
  *write = g->ch[ch]->output;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridGetBlockData(PffGrid g, PetscInt ch, PetscInt lb, PetscInt comp, float **data)
{
  PetscFunctionBeginUser;
  PffChannel *c = NULL;
  PetscCall(PffGridGetChannel_Private(g, ch, &c));
  PetscCheck(lb >= 0 && lb < g->nlocal && comp >= 0 && comp < c->ncomp, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
             "block %" PetscInt_FMT " component %" PetscInt_FMT " out of range", lb, comp);
  const PetscInt n = PffGridBlockN_Private(g, g->lgid[lb]);
  *data            = c->data + c->ncomp * g->loff[lb] + comp * n * n * n;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Large zeroings of the storage split over the threads, in pieces of whole cache lines. */
void PffZeroFloats_Private(float *a, PetscInt64 n)
{
  const PetscInt64 piece = 1 << 16, npieces = (n + piece - 1) / piece;
#pragma omp parallel for schedule(static) if (npieces > 1)
  for (PetscInt64 q = 0; q < npieces; q++)
    memset(a + q * piece, 0, sizeof(float) * (size_t)PetscMin(piece, n - q * piece));
}

PetscErrorCode PffGridZeroChannel(PffGrid g, PetscInt ch)
{
  PffChannel *c = NULL;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetChannel_Private(g, ch, &c));
  PffZeroFloats_Private(c->data, c->ncomp * g->ncells);
  PffZeroFloats_Private(c->halo, c->plan->nhalo);
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridScaleChannel(PffGrid g, PetscInt dst, PetscReal a, PetscInt src)
{
  PffChannel *d = NULL, *s = NULL;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetChannel_Private(g, dst, &d));
  PetscCall(PffGridGetChannel_Private(g, src, &s));
  PetscCheck(d->kind == s->kind, PETSC_COMM_SELF, PETSC_ERR_ARG_INCOMP,
             "PffGridScaleChannel: channels %" PetscInt_FMT " and %" PetscInt_FMT " are not of the same kind", dst,
             src);
  {
    float *restrict y       = d->data;
    const float *restrict x = s->data;
    const PetscInt64 n      = (PetscInt64)d->ncomp * g->ncells;
    const float      af     = (float)a;
#pragma omp parallel for simd schedule(static)
    for (PetscInt64 i = 0; i < n; i++) y[i] = af * x[i];
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridGetBlockViews(PffGrid g, PetscInt ch, PetscInt lb, PetscInt comp, const PffView **views)
{
  PetscFunctionBeginUser;
  PffChannel *c = NULL;
  PetscCall(PffGridGetChannel_Private(g, ch, &c));
  PetscCheck(lb >= 0 && lb < g->nlocal && comp >= 0 && comp < c->ncomp, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
             "block %" PetscInt_FMT " component %" PetscInt_FMT " out of range", lb, comp);
  *views = &c->views[(lb * c->ncomp + comp) * 27];
  PetscFunctionReturn(PETSC_SUCCESS);
}
