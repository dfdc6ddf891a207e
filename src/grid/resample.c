/* Per-block transfer of channel values between levels (PffGridAdapt, PF-FLIP Sec. 5.4).

   A block keeps its place and size when its level changes, so each new block is resampled from its own
   old block alone and needs no ghosts. Restriction averages the fine samples a coarse sample covers
   (8 cells, or the 4 fine faces coplanar with a coarse face): for cells that conserves the integral,
   for faces the flux through every coarse face. Linear prolongation reconstructs each coarse cell with
   slopes limited by the monotonised central (MC) limiter, so no new extremum appears inside the block,
   a linear field is reproduced exactly, and the children average back to the parent: restricting a
   prolonged block returns it to rounding. At a block edge only one neighbour is in the block, and the
   slope is that one-sided difference (a jump at the edge can overshoot by a quarter of it). For a face
   component the faces coplanar with coarse faces are reconstructed the same way in their plane; the
   faces mid-way between two coarse faces are the mean of their fine neighbours along the normal, or
   extrapolated linearly at the block's upper side, whose coarse face belongs to the next block. */
#include "gridimpl.h"

/* MC-limited slope of the samples a - b - c (b the centre); one-sided when a or c is missing. */
static inline float SlopeMC(const float *a, float b, const float *c)
{
  if (!a && !c) return 0.0f;
  if (!a) return *c - b;
  if (!c) return b - *a;
  const float dl = b - *a, dr = *c - b;
  if (dl * dr <= 0.0f) return 0.0f;
  const float m = fminf(fabsf(0.5f * (dl + dr)), 2.0f * fminf(fabsf(dl), fabsf(dr)));
  return dl > 0 ? m : -m;
}

void PffBlockRestrict(PffChannelKind kind, PetscInt comp, PetscInt nf, const float fine[], float coarse[])
{
  const PetscInt nc = nf / 2, s = kind == PFF_CHANNEL_FACE ? comp : -1;

  for (PetscInt ck = 0; ck < nc; ck++)
    for (PetscInt cj = 0; cj < nc; cj++)
      for (PetscInt ci = 0; ci < nc; ci++) {
        const PetscInt C3[3] = {ci, cj, ck};
        double         sum   = 0;
        PetscInt       cnt   = 0;
        for (PetscInt q = 0; q < 8; q++) {
          PetscInt  f[3];
          PetscBool skip = PETSC_FALSE;
          for (int a = 0; a < 3; a++) {
            const PetscInt bit = (q >> a) & 1;
            if (a == s && bit) skip = PETSC_TRUE; /* a face: only the layer coplanar with the coarse face */
            f[a] = 2 * C3[a] + bit;
          }
          if (skip) continue;
          sum += fine[f[0] + nf * (f[1] + nf * f[2])];
          cnt++;
        }
        coarse[ci + nc * (cj + nc * ck)] = (float)(sum / (double)cnt);
      }
}

/* Value of the child at fine offset (bit a of q along axis a) of coarse sample C3: the sample plus its
   limited slope times the child's offset (+-1/4 coarse cell) along each axis but the staggered one (s). */
static inline float Child(PffTransferType type, PetscInt nc, const float coarse[], const PetscInt C3[3], PetscInt q,
                          PetscInt s)
{
  const PetscInt c = C3[0] + nc * (C3[1] + nc * C3[2]);
  float          v = coarse[c];

  if (type != PFF_TRANSFER_LINEAR) return v;
  for (int a = 0, st = 1; a < 3; a++, st *= (int)nc) {
    if (a == s) continue;
    const float *lo = C3[a] > 0 ? &coarse[c - st] : NULL, *hi = C3[a] < nc - 1 ? &coarse[c + st] : NULL;
    const float  slope = SlopeMC(lo, coarse[c], hi);
    v += ((q >> a) & 1 ? 0.25f : -0.25f) * slope;
  }
  return v;
}

void PffBlockProlong(PffChannelKind kind, PetscInt comp, PffTransferType type, PetscInt nc, const float coarse[],
                     float fine[])
{
  const PetscInt nf = 2 * nc, s = kind == PFF_CHANNEL_FACE ? comp : -1;

  for (PetscInt ck = 0; ck < nc; ck++)
    for (PetscInt cj = 0; cj < nc; cj++)
      for (PetscInt ci = 0; ci < nc; ci++) {
        const PetscInt C3[3] = {ci, cj, ck};
        for (PetscInt q = 0; q < 8; q++) {
          PetscInt f[3];
          if (s >= 0 && ((q >> s) & 1)) continue; /* mid-way faces: below */
          for (int a = 0; a < 3; a++) f[a] = 2 * C3[a] + ((q >> a) & 1);
          fine[f[0] + nf * (f[1] + nf * f[2])] = Child(type, nc, coarse, C3, q, s);
        }
      }
  if (s < 0) return;
  /* faces at odd indices along s lie mid-way between coplanar layers 2I and 2I + 2 */
  const PetscInt st = s == 0 ? 1 : (s == 1 ? nf : nf * nf);
  for (PetscInt k = 0; k < nf; k++)
    for (PetscInt j = 0; j < nf; j++)
      for (PetscInt i = 0; i < nf; i++) {
        const PetscInt f[3] = {i, j, k}, r = i + nf * (j + nf * k);
        if (!(f[s] & 1)) continue;
        const float lo = fine[r - st];
        if (type != PFF_TRANSFER_LINEAR)
          fine[r] = lo;
        else if (f[s] + 1 < nf)
          fine[r] = 0.5f * (lo + fine[r + st]);
        else
          fine[r] = nc > 1 ? 1.5f * lo - 0.5f * fine[r - 3 * st] : lo;
      }
}
