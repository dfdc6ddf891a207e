/* The particles' volume on the cell centres (the measure of the two-phase volume correction, docs/flow.md):
     chVolume[c] = sum_p t_cp 8^l_p,
   t_cp the trilinear weight of cell centre c of the particle's block (a partition of unity), 8^l_p the particle's
   volume in units of a level-0 particle. The values are absolute volumes, not densities: the grid's conservative
   reverse halo then puts a fine ghost cell's volume whole into the coarse cell that contains it and shares a coarse
   ghost cell's volume equally among the 8 fine cells under it, so every particle adds exactly its volume to the cells
   around it, across level boundaries as well (walls drop the part beyond them, which the lattice reference holds
   too).

   Why cell centres and not the faces of P2G: the face measure of a cell, summed over its six faces, weighs a
   particle by where it sits in the cell, and at a level boundary the faces mix the two levels' lattices. A particle
   a fraction of a cell below a coarse-fine boundary counted half as much in its coarse cell as one in the cell's
   middle, so the correction could meet its target by packing particles into that sliver instead of moving volume:
   the multi-level pools gathered a few per cent of a cell layer there within a few hundred steps, lowered their
   surface, and the volume control, chasing the lost phase-field volume, drove them to 1-2 m/s within 1000 steps
   (docs/validation.md, "Long still pools on multi-level grids"). */
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
