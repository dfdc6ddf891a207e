/* The particles' volume on the cell centres (the measure of the two-phase volume correction, docs/flow.md):
     chVolume[c] = sum_p t_cp 8^l_p,
   t_cp the trilinear weight of cell centre c of the particle's block (a partition of unity), 8^l_p the particle's
   volume in units of a level-0 particle. The values are absolute volumes, not densities: the grid's conservative
   reverse halo then puts a fine ghost cell's volume whole into the coarse cell that contains it and shares a coarse
   ghost cell's volume equally among the 8 fine cells under it, so every particle adds exactly its volume to the cells
   around it, across level boundaries as well (walls drop the part beyond them, which the lattice reference holds
   too).

   Why cell centres and not the faces of P2G: the face measure of a cell sums its six faces, and at a level boundary
   those faces hold values moved across levels in densities (P2G's "8^-l_f" is not applied to them, up to 157 % off
   for a lattice; only the lattice reference hid that). With it the multi-level still pools lost phase-field volume at
   their surface (0.51 % in 1000 steps without the volume control), the control lowered its target without end, and
   the pools reached 1-2 m/s within 1000 steps; with the cell measure they lose 0.02 % and stay below 0.01 m/s
   (docs/validation.md, "Long still pools on multi-level grids", which also shows what it does not change). */
#include "particlesimpl.h"
#include <omp.h>

/* One block's particles [i0, i1) into the thread's tile of (n + 2)^3 cells from cell -1, then the tile's own cells
   into data and its shell into the views. */
static void PffSplatVolumeBlock(const PffParticleSoA *s, PetscInt i0, PetscInt i1, const PffBlockInfo *info,
                                const PffView *views, float *data, PetscInt n0, float *tile)
{
  const PetscInt n = info->n, m = n + 2;
  float          lo[3], ih;

  memset(tile, 0, sizeof(float) * (size_t)(m * m * m));
  PffBlockCorner_Private(n0, info->ijk, info->level, lo, &ih);
  for (PetscInt j0 = i0; j0 < i1; j0 += PFF_CHUNK) {
    const PetscInt  cnt = PetscMin(PFF_CHUNK, i1 - j0);
    float           vol[PFF_CHUNK];
    PffChunkLattice L; /* the half lattice (ih, th) is the cell centres' */
    for (PetscInt j = 0; j < cnt; j++) vol[j] = (float)(1u << (3 * PffParticleWordLevel(s->word[j0 + j])));
    PffChunkLattice_Private(&s->x[3 * j0], cnt, lo, ih, n, &L);
    for (PetscInt j = 0; j < cnt; j++) {
      const float tx = L.th[0][j], ty = L.th[1][j], tz = L.th[2][j];
      float      *t     = tile + (L.ih[0][j] + 1) + m * ((L.ih[1][j] + 1) + m * (L.ih[2][j] + 1));
      const float wz[2] = {vol[j] * (1 - tz), vol[j] * tz}, wy[2] = {1 - ty, ty};
      for (int dk = 0; dk < 2; dk++)
        for (int dj = 0; dj < 2; dj++) {
          float      *r = t + m * (dj + m * dk);
          const float w = wz[dk] * wy[dj];
          r[0] += w * (1 - tx);
          r[1] += w * tx;
        }
    }
  }
  for (PetscInt k = 0; k < n; k++)
    for (PetscInt j = 0; j < n; j++) {
      const float *row = tile + 1 + m * ((j + 1) + m * (k + 1));
      float       *dst = data + n * (j + n * k);
      for (PetscInt i = 0; i < n; i++) dst[i] += row[i];
    }
  PffTileShell_Private(views, n, 1, tile, PETSC_TRUE);
}

PetscErrorCode PffParticlesSplatVolume(PffParticles p, PetscInt chVolume)
{
  PffChannelKind  kind;
  PetscInt        ncomp, width, cstart[28], *order = NULL, *colour = NULL;
  const char     *name;
  PffBlockInfo   *info;
  const PffView **views;
  float         **data, *tiles;

  PetscFunctionBeginUser;
  PetscCall(PffParticlesCheckBinned_Private(p, "PffParticlesSplatVolume"));
  PetscCall(PffGridGetChannelInfo(p->grid, chVolume, &name, &kind, &ncomp, &width));
  PetscCheck(kind == PFF_CHANNEL_CELL && ncomp == 1 && width >= 1, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG,
             "PffParticlesSplatVolume: channel %s must be a cell channel of one component with a halo of width >= 1",
             name);
  const PetscInt nlocal = p->nlocal;
  PetscCall(PetscLogEventBegin(PFF_P2G, 0, 0, 0, 0));
  PetscCall(PffParticlesSplatScratch_Private(p, PFF_SCRATCH_VOLUME, 1, &info, &views, &data, &order, &colour));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PetscCall(PffGridGetBlockInfo(p->grid, lb, &info[lb]));
    PetscCall(PffGridGetBlockViews(p->grid, chVolume, lb, 0, &views[lb]));
    PetscCall(PffGridGetBlockData(p->grid, chVolume, lb, 0, &data[lb]));
  }
  /* the ghost boxes may hold a forward halo's values, and splatting adds to them */
  PetscCall(PffGridZeroChannel(p->grid, chVolume));
  PffParticlesColourOrder_Private(p, info, colour, order, cstart);
  const size_t tsize = (size_t)(p->n0 + 2) * (size_t)(p->n0 + 2) * (size_t)(p->n0 + 2);
  PetscCall(PffParticlesGetFloatWork_Private(p, tsize * (size_t)PetscMax(omp_get_max_threads(), 1), &tiles));
  const PffParticleSoA *s     = &p->s;
  const PetscInt       *start = p->start;
  for (int c = 0; c < 27; c++) {
#pragma omp parallel for schedule(dynamic, 1)
    for (PetscInt e = cstart[c]; e < cstart[c + 1]; e++) {
      const PetscInt lb = order[e];
      if (start[lb + 1] > start[lb])
        PffSplatVolumeBlock(s, start[lb], start[lb + 1], &info[lb], views[lb], data[lb], p->n0,
                            tiles + tsize * (size_t)omp_get_thread_num());
    }
  }
  PetscCall(PffGridHaloReverseBegin(p->grid, chVolume));
  PetscCall(PffGridHaloReverseEnd(p->grid, chVolume));
  PetscCall(PetscLogEventEnd(PFF_P2G, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}
