/* 7-point Laplacian on cell channels, dst = (sum of the 6 neighbours - 6 u) / h^2 at each block's
   own level, with neighbours across block faces read through the block's packed face views
   (PffFaceViews: the six face layers of its region views, ghosts at the block's level). It is the bandwidth probe of
   pff-bench-grid (paper Table 3) and the diffusion of the grid demo; the symmetric coarse-fine pressure operator lives
   in src/pressure/. Rows along x are contiguous in every region a row can fall into, so the inner loop is a
   unit-stride, vectorisable sweep; only the two end cells of a row look across x faces. */
#include "gridimpl.h"
#if defined(__AVX__) || defined(__AVX512F__)
#include <immintrin.h>
#endif

/* Address of row j = 0 of plane k, -1 <= k <= n, of the block's neighbourhood. */
static inline const float *PffPlane(const float *c0, const PffFaceViews *f, PetscInt k, PetscInt n)
{
  return k < 0 ? f->face[4] : (k >= n ? f->face[5] : c0 + n * n * k);
}

/* One block; n is a compile-time constant at the call sites below, so the row loop unrolls into
   whole SIMD vectors. The vector sweep covers the whole row and so reads c[-1] and c[n], which are
   other rows' values (the channel allocation is padded, so they exist); the two end cells are
   then corrected by the difference to their true x neighbours, which costs two operations per row
   instead of two scalar stencils (rounding stays at the level of the stencil's own). */
static inline __attribute__((always_inline)) void PffLaplacianBlockN(const float *restrict c0,
                                                                     const PffFaceViews *restrict f,
                                                                     float *restrict out, const PetscInt n, float ih2)
{
  const ptrdiff_t zms = n, zps = n, xms = f->sy[0], xps = f->sy[1];
  for (PetscInt k = 0; k < n; k++) {
    /* per plane: where the z-neighbour rows, the two y-ghost rows and the x-ghost columns start,
       so the row loop below only adds */
    const float *zm0 = PffPlane(c0, f, k - 1, n), *zp0 = PffPlane(c0, f, k + 1, n);
    const float *ymg = f->face[2] + k * f->sz[2], *ypg = f->face[3] + k * f->sz[3];
    const float *xm0 = f->face[0] + k * f->sz[0], *xp0 = f->face[1] + k * f->sz[1];
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

#if defined(__AVX512F__) && defined(__AVX512DQ__)
/* Lane l of the result is x[row[l]]: the x-ghost value of each row in every lane of that row.
   Scalar loads and one permute, because a gather of so few scattered values costs more here. */
static inline __m512 PffSpreadRows(__m512i row, __m128 x)
{
  return _mm512_permutexvar_ps(row, _mm512_castps128_ps512(x));
}

/* Coarse blocks (n = 4 and 8) as whole planes: a 4^3 plane is one 16-float vector and an 8^3
   plane four, two rows each, so the per-row pointer set-up, end corrections and short (or masked)
   vectors of the row kernel above, which cost more than the cells themselves when a row holds 4
   or 8 floats, are paid once per plane or per two rows. The y neighbours are the plane shifted by
   one row with the ghost row inserted at the end lane group; the z neighbours are whole planes
   because the block and its z-face layers both store rows n apart (storage.c). The sums are formed
   in the same order as the row kernel's for that n (its omp simd loop for n = 4, its AVX loop for
   n = 8, including that loop's addition of zeros), so the results are bit for bit the same. */
static inline void PffLaplacianBlock4Planes(const float *restrict c0, const PffFaceViews *restrict f,
                                            float *restrict out, float ih2)
{
  const __m512    six = _mm512_set1_ps(6.0f), s = _mm512_set1_ps(ih2);
  const __m512i   row = _mm512_setr_epi32(0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3);
  const ptrdiff_t xms = f->sy[0], xps = f->sy[1];
  const __mmask16 first = 0x1111, last = 0x8888; /* x = 0 and x = 3 of each row */
  for (PetscInt k = 0; k < 4; k++) {
    const float *c  = c0 + 16 * k;
    const float *xm = f->face[0] + k * f->sz[0], *xp = f->face[1] + k * f->sz[1];
    const __m512 cc = _mm512_load_ps(c), cm = _mm512_loadu_ps(c - 1), cp = _mm512_loadu_ps(c + 1);
    const __m512 ym = _mm512_insertf32x4(_mm512_loadu_ps(c - 4), _mm_loadu_ps(f->face[2] + k * f->sz[2]), 0);
    const __m512 yp = _mm512_insertf32x4(_mm512_loadu_ps(c + 4), _mm_loadu_ps(f->face[3] + k * f->sz[3]), 3);
    __m512       v  = _mm512_add_ps(cm, cp);
    v               = _mm512_add_ps(v, ym);
    v               = _mm512_add_ps(v, yp);
    v               = _mm512_add_ps(v, _mm512_loadu_ps(PffPlane(c0, f, k - 1, 4)));
    v               = _mm512_add_ps(v, _mm512_loadu_ps(PffPlane(c0, f, k + 1, 4)));
    v               = _mm512_mul_ps(_mm512_sub_ps(v, _mm512_mul_ps(six, cc)), s);
    /* masked, not added as zeros, because the row kernel for n = 4 corrects only the end cells */
    const __m512 xmv = PffSpreadRows(row, _mm_setr_ps(xm[0], xm[xms], xm[2 * xms], xm[3 * xms]));
    const __m512 xpv = PffSpreadRows(row, _mm_setr_ps(xp[0], xp[xps], xp[2 * xps], xp[3 * xps]));
    v                = _mm512_mask_add_ps(v, first, v, _mm512_mul_ps(_mm512_sub_ps(xmv, cm), s));
    v                = _mm512_mask_add_ps(v, last, v, _mm512_mul_ps(_mm512_sub_ps(xpv, cp), s));
    _mm512_stream_ps(out + 16 * k, v);
  }
}

static inline void PffLaplacianBlock8Planes(const float *restrict c0, const PffFaceViews *restrict f,
                                            float *restrict out, float ih2)
{
  const __m512    six = _mm512_set1_ps(6.0f), s = _mm512_set1_ps(ih2);
  const __m512i   row = _mm512_setr_epi32(0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 1, 1, 1, 1);
  const ptrdiff_t xms = f->sy[0], xps = f->sy[1];
  const __mmask16 first = 0x0101, last = 0x8080; /* x = 0 and x = 7 of each row */
  for (PetscInt k = 0; k < 8; k++) {
    const float *zm = PffPlane(c0, f, k - 1, 8), *zp = PffPlane(c0, f, k + 1, 8);
    const float *xm = f->face[0] + k * f->sz[0], *xp = f->face[1] + k * f->sz[1];
    for (PetscInt m = 0; m < 4; m++) {
      const float *c  = c0 + 64 * k + 16 * m;
      const __m512 cc = _mm512_load_ps(c), cm = _mm512_loadu_ps(c - 1), cp = _mm512_loadu_ps(c + 1);
      __m512       ym = _mm512_loadu_ps(c - 8), yp = _mm512_loadu_ps(c + 8);
      if (m == 0) ym = _mm512_insertf32x8(ym, _mm256_loadu_ps(f->face[2] + k * f->sz[2]), 0);
      if (m == 3) yp = _mm512_insertf32x8(yp, _mm256_loadu_ps(f->face[3] + k * f->sz[3]), 1);
      __m512 v = _mm512_add_ps(_mm512_add_ps(cm, cp), _mm512_add_ps(ym, yp));
      v        = _mm512_add_ps(v, _mm512_add_ps(_mm512_loadu_ps(zm + 16 * m), _mm512_loadu_ps(zp + 16 * m)));
      v        = _mm512_sub_ps(v, _mm512_mul_ps(six, cc));
      /* zeros in the other lanes, as the row kernel adds them */
      const __m512 xmv = PffSpreadRows(row, _mm_setr_ps(xm[2 * m * xms], xm[(2 * m + 1) * xms], 0, 0));
      const __m512 xpv = PffSpreadRows(row, _mm_setr_ps(xp[2 * m * xps], xp[(2 * m + 1) * xps], 0, 0));
      v                = _mm512_add_ps(v, _mm512_maskz_sub_ps(first, xmv, cm));
      v                = _mm512_add_ps(v, _mm512_maskz_sub_ps(last, xpv, cp));
      _mm512_stream_ps(out + 64 * k + 16 * m, _mm512_mul_ps(v, s));
    }
  }
}
#endif

static void PffLaplacianBlock(const float *restrict c0, const PffFaceViews *restrict f, float *restrict out, PetscInt n,
                              float ih2)
{
  switch (n) {
  case 64:
    PffLaplacianBlockN(c0, f, out, 64, ih2);
    break;
  case 32:
    PffLaplacianBlockN(c0, f, out, 32, ih2);
    break;
  case 16:
    PffLaplacianBlockN(c0, f, out, 16, ih2);
    break;
#if defined(__AVX512F__) && defined(__AVX512DQ__)
  /* the plane kernels load and stream whole 64-byte vectors; PETSc aligns allocations to 16 bytes only */
  case 8:
    if (((uintptr_t)c0 | (uintptr_t)out) % 64 == 0)
      PffLaplacianBlock8Planes(c0, f, out, ih2);
    else
      PffLaplacianBlockN(c0, f, out, 8, ih2);
    break;
  case 4:
    if (((uintptr_t)c0 | (uintptr_t)out) % 64 == 0)
      PffLaplacianBlock4Planes(c0, f, out, ih2);
    else
      PffLaplacianBlockN(c0, f, out, 4, ih2);
    break;
#else
  case 8:
    PffLaplacianBlockN(c0, f, out, 8, ih2);
    break;
  case 4:
    PffLaplacianBlockN(c0, f, out, 4, ih2);
    break;
#endif
  default:
    PffLaplacianBlockN(c0, f, out, n, ih2);
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
    PffLaplacianBlock(in->data + g->loff[lb], &in->faces[lb], out->data + g->loff[lb], n, (float)(1.0 / (h * h)));
  }
#if defined(__AVX__)
  _mm_sfence(); /* streaming stores are weakly ordered */
#endif
  PetscCall(PetscLogEventEnd(PFF_GridLaplacian, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}
