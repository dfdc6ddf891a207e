/* 7-point Laplacian on cell channels, dst = (sum of the 6 neighbours - 6 u) / h^2 at each block's
   own level, with neighbours across block faces read through the region views (ghosts at the
   block's level). It is the bandwidth probe of pff-bench-grid (paper Table 3) and the diffusion of
   the grid demo; the symmetric coarse-fine pressure operator lives in src/pressure/.
   Rows along x are contiguous in every region a row can fall into, so the inner loop is a
   unit-stride, vectorisable sweep; only the two end cells of a row look across x faces. */
#include "gridimpl.h"
#if defined(__AVX__)
#include <immintrin.h>
#endif

/* Address of row (j, k) (i = 0) of the block's neighbourhood: j or k may lie one cell outside. */
static inline const float *PffRow(const PffView *in, PetscInt j, PetscInt k, PetscInt n)
{
  return PffViewsAt(in, 0, j, k, n);
}

/* One block; n is a compile-time constant at the call sites below, so the row loop unrolls into
   whole SIMD vectors. The vector sweep covers the whole row and so reads c[-1] and c[n], which are
   other rows' values (the channel allocation is padded, so they exist); the two end cells are
   then corrected by the difference to their true x neighbours, which costs two operations per row
   instead of two scalar stencils (rounding stays at the level of the stencil's own). */
static inline __attribute__((always_inline)) void PffLaplacianBlockN(const PffView *restrict in, float *restrict out,
                                                                     const PetscInt n, float ih2)
{
  const float   *c0  = in[13].ptr;
  const PffView *vxm = &in[12], *vxp = &in[14];
  for (PetscInt k = 0; k < n; k++) {
    /* per plane: where the z-neighbour rows, the two y-ghost rows and the x-ghost columns start,
       and their strides in j, so the row loop below only adds */
    const float    *zm0 = PffRow(in, 0, k - 1, n), *zp0 = PffRow(in, 0, k + 1, n);
    const ptrdiff_t zms = in[PffRegionIndex(0, 0, k - 1, n)].sy, zps = in[PffRegionIndex(0, 0, k + 1, n)].sy;
    const float    *ymg = PffRow(in, -1, k, n), *ypg = PffRow(in, n, k, n);
    const float    *xm0 = vxm->ptr + (vxm->off - vxm->sx + k * vxm->sz),
                *xp0    = vxp->ptr + (vxp->off + n * vxp->sx + k * vxp->sz);
    const ptrdiff_t xms = vxm->sy, xps = vxp->sy;
    for (PetscInt j = 0; j < n; j++) {
      const float *restrict c  = c0 + n * (j + n * k);
      const float *restrict ym = j > 0 ? c - n : ymg;
      const float *restrict yp = j < n - 1 ? c + n : ypg;
      const float *restrict zm = zm0 + j * zms;
      const float *restrict zp = zp0 + j * zps;
      float *restrict o        = out + n * (j + n * k);
      const float xm           = xm0[j * xms];
      const float xp           = xp0[j * xps];
#if defined(__AVX__)
      if (n % 8 == 0 && ((uintptr_t)o) % 32 == 0) {
        /* the output is not read again while it is in cache: stream it past the caches, so the
           kernel moves 8 bytes per cell like the copy it is measured against, not 12 */
        const __m256 six = _mm256_set1_ps(6.0f), s = _mm256_set1_ps(ih2);
        for (PetscInt i = 0; i < n; i += 8) {
          __m256 v = _mm256_add_ps(_mm256_loadu_ps(c + i - 1), _mm256_loadu_ps(c + i + 1));
          v        = _mm256_add_ps(v, _mm256_add_ps(_mm256_loadu_ps(ym + i), _mm256_loadu_ps(yp + i)));
          v        = _mm256_add_ps(v, _mm256_add_ps(_mm256_loadu_ps(zm + i), _mm256_loadu_ps(zp + i)));
          v        = _mm256_sub_ps(v, _mm256_mul_ps(six, _mm256_loadu_ps(c + i)));
          if (i == 0) v = _mm256_add_ps(v, _mm256_setr_ps(xm - c[-1], 0, 0, 0, 0, 0, 0, 0));
          if (i == n - 8) v = _mm256_add_ps(v, _mm256_setr_ps(0, 0, 0, 0, 0, 0, 0, xp - c[n]));
          _mm256_stream_ps(o + i, _mm256_mul_ps(v, s));
        }
        continue;
      }
#endif
#pragma omp simd
      for (PetscInt i = 0; i < n; i++) o[i] = (c[i - 1] + c[i + 1] + ym[i] + yp[i] + zm[i] + zp[i] - 6.0f * c[i]) * ih2;
      /* the sweep used c[-1] and c[n] (neighbouring rows) at the ends: swap in the true x neighbours */
      o[0] += (xm - c[-1]) * ih2;
      o[n - 1] += (xp - c[n]) * ih2;
    }
  }
}

static void PffLaplacianBlock(const PffView *restrict in, float *restrict out, PetscInt n, float ih2)
{
  switch (n) {
  case 64:
    PffLaplacianBlockN(in, out, 64, ih2);
    break;
  case 32:
    PffLaplacianBlockN(in, out, 32, ih2);
    break;
  case 16:
    PffLaplacianBlockN(in, out, 16, ih2);
    break;
  case 8:
    PffLaplacianBlockN(in, out, 8, ih2);
    break;
  case 4:
    PffLaplacianBlockN(in, out, 4, ih2);
    break;
  default:
    PffLaplacianBlockN(in, out, n, ih2);
    break;
  }
}

PetscErrorCode PffGridApplyLaplacian(PffGrid g, PetscInt src, PetscInt dst)
{
  PffChannel *in = NULL, *out = NULL;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetChannel_Private(g, src, &in));
  PetscCall(PffGridGetChannel_Private(g, dst, &out));
  PetscCheck(src != dst, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG, "the Laplacian needs two different channels");
  PetscCheck(in->kind == PFF_CHANNEL_CELL && out->kind == PFF_CHANNEL_CELL, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG,
             "the Laplacian works on cell channels");
  PetscCall(PetscLogEventBegin(PFF_GridLaplacian, 0, 0, 0, 0));
#pragma omp parallel for schedule(guided)
  for (PetscInt lb = 0; lb < g->nlocal; lb++) {
    const PetscInt  l = g->level[g->lgid[lb]], n = g->n0 >> l;
    const PetscReal h = g->h0 * (PetscReal)((PetscInt)1 << l);
    PffLaplacianBlock(&in->views[lb * 27], out->data + g->loff[lb], n, (float)(1.0 / (h * h)));
  }
#if defined(__AVX__)
  _mm_sfence(); /* streaming stores are weakly ordered */
#endif
  PetscCall(PetscLogEventEnd(PFF_GridLaplacian, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}
