/* grid: the distributed Multiresolution Sparse Block Grid (MSBG, PF-FLIP paper Sec. 4.2).

   The domain is a raster of nb[0] x nb[1] x nb[2] blocks of equal geometric size. Block b has a
   level l (-1 = inactive) and n0 >> l cells per axis. The raster (level, owner, Morton key) is
   replicated on every rank; cell data lives only on the owning rank, one contiguous float array
   per channel per block, x fastest. Face neighbours, edge neighbours and corner neighbours of an
   active block differ by at most one level (2:1 grading over all 26 neighbours). */
#pragma once

#include <pff/core.h>

typedef struct _n_PffGrid *PffGrid;

/* columns: whole block columns along y on one rank (the tall-cell solver's columns, src/tallcell/) */
typedef enum { PFF_PARTITION_MORTON, PFF_PARTITION_METIS, PFF_PARTITION_COLUMNS } PffPartitionType;
PETSC_EXTERN const char *const PffPartitionTypes[];

typedef enum { PFF_REFINE_NONE, PFF_REFINE_PLANE, PFF_REFINE_SPHERE } PffRefineType;
PETSC_EXTERN const char *const PffRefineTypes[];

/* A cell channel holds one value per cell; a face channel holds the three MAC components,
   component d at the lower d-face of each cell (position (i + 1/2 - e_d/2) h). */
typedef enum { PFF_CHANNEL_CELL, PFF_CHANNEL_FACE } PffChannelKind;
PETSC_EXTERN const char *const PffChannelKinds[];

#define PFF_GRID_BLOCK_SIZE_DEFAULT 16
#define PFF_GRID_BLOCK_SIZE_MIN 4
#define PFF_GRID_BLOCK_SIZE_MAX 64
#define PFF_GRID_LEVELS_DEFAULT 1
#define PFF_GRID_MAX_LEVELS 7
#define PFF_GRID_MAX_CHANNELS 32
#define PFF_GRID_MAX_WIDTH 4
#define PFF_GRID_MAX_RASTER_BLOCKS (1 << 24) /* blocks of the raster every rank holds */

/* Requested level of the block with box [lo, hi]; -1 makes the block inactive. */
typedef PetscErrorCode (*PffRefineFn)(PffGrid grid, const PetscReal lo[3], const PetscReal hi[3], PetscInt *level,
                                      void *ctx);

/* Where the values of block-neighbourhood region r (see PffRegionIndex) live: the value at block-local
   cell (i, j, k) is ptr[off + i*sx + j*sy + k*sz]. For a same-level neighbour on this rank ptr is the
   neighbour's own storage (reads see its current values, writes land in it); otherwise ptr is a ghost
   buffer filled by PffGridHaloBegin/End and summed back by PffGridHaloReverseBegin/End. Regions
   across a wall or facing an inactive block have a zero ghost buffer that no exchange touches. */
typedef struct {
  float    *ptr;
  ptrdiff_t off, sx, sy, sz;
} PffView;

typedef struct {
  PetscInt  gid;    /* global block index in the raster, x fastest */
  PetscInt  ijk[3]; /* block coordinates in the raster */
  PetscInt  level;  /* resolution level */
  PetscInt  n;      /* cells per axis, n0 >> level */
  PetscReal lo[3];  /* lower corner */
  PetscReal h;      /* cell size h0 * 2^level */
  PetscInt  holes;  /* bit r: neighbour region r (PffRegionIndex) lies across a wall or faces an inactive block */
} PffBlockInfo;

typedef struct {
  PetscReal imbalance;     /* max over ranks of work / mean work */
  PetscInt  cutFaces;      /* block faces whose two blocks have different owners */
  PetscReal haloBytesMax;  /* bytes received per rank by one exchange of a width-1 cell channel */
  PetscReal haloBytesMean; /* mean of the same over ranks */
} PffPartitionQuality;

/* Region index 0..26 of block-local cell (i, j, k) for a block with n cells per axis; PFF_REGION_SELF is the block
   itself (its view reads the block's own storage). */
#define PFF_REGION_SELF 13
static inline PetscInt PffRegionIndex(PetscInt i, PetscInt j, PetscInt k, PetscInt n)
{
  const PetscInt rx = i < 0 ? 0 : (i >= n ? 2 : 1), ry = j < 0 ? 0 : (j >= n ? 2 : 1),
                 rz = k < 0 ? 0 : (k >= n ? 2 : 1);
  return rx + 3 * ry + 9 * rz;
}
/* Direction d in {-1, 0, 1}^3 of region r (the inverse of PffRegionIndex). */
static inline void PffRegionDirection(PetscInt r, PetscInt d[3])
{
  d[0] = r % 3 - 1;
  d[1] = (r / 3) % 3 - 1;
  d[2] = r / 9 - 1;
}
/* The 2 x 2 x 2 stencil of the grid's trilinear interpolation (PffGridInterpolate) at lp, the position in cell units
   of a block of n cells per axis from its lower corner, for a lattice offset o per axis (0.5 at cell centres and
   across a face, 0 along its normal): lower and upper index per axis and fraction. Each region of the holes mask (bit
   r: neighbour region r across a wall or facing an inactive block) that the stencil reaches clamps every axis it
   steps across to the block's last cell (constant extrapolation), except the wall face itself (index n) of a
   staggered component. Returns whether the stencil leaves the block's own cells. */
static inline PetscBool PffStencilClamped(PetscInt n, PetscInt holes, const PetscReal o[3], const PetscReal lp[3],
                                          PetscInt i0[3], PetscInt i1[3], PetscReal t[3])
{
  PetscInt  side[3];
  PetscBool clamp[3][2] = {{PETSC_FALSE, PETSC_FALSE}, {PETSC_FALSE, PETSC_FALSE}, {PETSC_FALSE, PETSC_FALSE}};

  for (int a = 0; a < 3; a++) {
    const PetscReal s = lp[a] - o[a];
    i0[a]             = (PetscInt)PetscFloorReal(s);
    t[a]              = s - (PetscReal)i0[a];
    i1[a]             = i0[a] + 1;
    side[a]           = i0[a] < 0 ? -1 : (i1[a] >= n ? 1 : 0);
  }
  if (!side[0] && !side[1] && !side[2]) return PETSC_FALSE;
  for (int q = 1; q < 8; q++) {
    PetscInt r = 13;
    for (int a = 0, m = 1; a < 3; a++, m *= 3)
      if ((q >> a) & 1) r += side[a] * m;
    if (r == 13 || !((holes >> r) & 1)) continue;
    for (int a = 0; a < 3; a++)
      if (((q >> a) & 1) && side[a]) clamp[a][side[a] > 0] = PETSC_TRUE;
  }
  for (int a = 0; a < 3; a++) {
    if (i0[a] < 0 && clamp[a][0]) {
      i0[a] = 0;
      if (i1[a] < 0) i1[a] = 0;
      t[a] = 0;
    }
    if (i1[a] >= n && clamp[a][1] && !(o[a] == 0.0 && i1[a] == n)) {
      i1[a] = n - 1;
      if (i0[a] > n - 1) i0[a] = n - 1;
      if (i0[a] == i1[a]) t[a] = 0;
    }
  }
  return PETSC_TRUE;
}
/* Address of block-local cell (i, j, k), -width <= i,j,k < n + width, through the block's 27 views. */
static inline float *PffViewsAt(const PffView *views, PetscInt i, PetscInt j, PetscInt k, PetscInt n)
{
  const PffView *v = &views[PffRegionIndex(i, j, k, n)];
  return v->ptr + (v->off + i * v->sx + j * v->sy + k * v->sz);
}

/* Block-local coordinates p of cell (u, v) of the layer `layer` along axis f / 2, for side f = 0..5 (-x, +x, -y,
   +y, -z, +z): the block's own side cells with layer 0 or n - 1, the ghost cells next to the side with -1 or n. */
static inline void PffBlockSideCell(PetscInt f, PetscInt layer, PetscInt u, PetscInt v, PetscInt p[3])
{
  const PetscInt a = f / 2;
  p[a]             = layer;
  p[(a + 1) % 3]   = u;
  p[(a + 2) % 3]   = v;
}

/* Life cycle. Create: collective, duplicates comm. SetFromOptions reads
   -grid_cells nx,ny,nz        finest-level cells per axis (multiples of the block size)
   -grid_block_size n0         cells per block axis at level 0, power of two in [4, 64]
   -grid_levels L              resolution levels 0..L-1, L-1 <= log2(n0)
   -grid_origin x,y,z          lower corner of the domain
   -grid_h h0                  finest cell size (default 1/nx)
   -grid_periodic x,z          periodic axes (any of x, y, z; others are walls)
   -grid_refine none|plane|sphere, -grid_refine_point, -grid_refine_normal, -grid_refine_radius,
   -grid_refine_band b         static refinement: level = floor(distance / (b block sizes))
   -grid_refine_columns        each block column along y takes the finest level asked in it (a quadtree,
                               for tall cells)
   -partition_type morton|metis|columns
   SetUp builds the raster, grades it, partitions it and allocates the channels; it validates every
   parameter first and allocates nothing when one is impossible. Destroy is NULL-safe. */
PETSC_EXTERN PetscErrorCode PffGridCreate(MPI_Comm comm, PffGrid *grid);
PETSC_EXTERN PetscErrorCode PffGridSetFromOptions(PffGrid grid);
PETSC_EXTERN PetscErrorCode PffGridSetUp(PffGrid grid);
PETSC_EXTERN PetscErrorCode PffGridDestroy(PffGrid *grid);
PETSC_EXTERN PetscErrorCode PffGridView(PffGrid grid, PetscViewer viewer);
PETSC_EXTERN PetscErrorCode PffGridViewFromOptions(PffGrid grid, const char name[]);

/* Setters (before SetUp; not collective but every rank must pass the same values). */
PETSC_EXTERN PetscErrorCode PffGridSetCells(PffGrid grid, const PetscInt cells[3]);
PETSC_EXTERN PetscErrorCode PffGridSetBlockSize(PffGrid grid, PetscInt n0);
PETSC_EXTERN PetscErrorCode PffGridSetLevels(PffGrid grid, PetscInt nlevels);
PETSC_EXTERN PetscErrorCode PffGridSetDomain(PffGrid grid, const PetscReal origin[3], PetscReal h0);
PETSC_EXTERN PetscErrorCode PffGridSetPeriodic(PffGrid grid, const PetscBool periodic[3]);
PETSC_EXTERN PetscErrorCode PffGridSetPartitionType(PffGrid grid, PffPartitionType type);
/* The partitioner (-partition_type). Not collective. */
PETSC_EXTERN PetscErrorCode PffGridGetPartitionType(PffGrid grid, PffPartitionType *type);
/* Refinement by callback, evaluated per block on every rank (must be deterministic). */
PETSC_EXTERN PetscErrorCode PffGridSetRefinementFunction(PffGrid grid, PffRefineFn fn, void *ctx);
/* Refinement from an explicit requested-level map over the raster (copied); -1 = inactive. */
PETSC_EXTERN PetscErrorCode PffGridSetRefinementMap(PffGrid grid, const PetscInt level[]);

/* Finest-level cells per axis as set (-grid_cells); also before SetUp, e.g. to place a refinement
   function's geometry in the domain. Not collective. */
PETSC_EXTERN PetscErrorCode PffGridGetCells(PffGrid grid, PetscInt cells[3]);
/* The domain [lo, hi] (origin to origin + cells h0), from the set parameters: also before set-up. Not collective. */
PETSC_EXTERN PetscErrorCode PffGridGetDomain(PffGrid grid, PetscReal lo[3], PetscReal hi[3]);

/* The grid's (duplicated) communicator; borrowed. Not collective. */
PETSC_EXTERN PetscErrorCode PffGridGetComm(PffGrid grid, MPI_Comm *comm);

/* Getters (after SetUp, not collective). */
PETSC_EXTERN PetscErrorCode PffGridGetRaster(PffGrid grid, PetscInt nb[3], const PetscInt **level,
                                             const PetscMPIInt **owner);
PETSC_EXTERN PetscErrorCode PffGridGetSizes(PffGrid grid, PetscInt *n0, PetscInt *nlevels, PetscReal origin[3],
                                            PetscReal *h0, PetscBool periodic[3]);
PETSC_EXTERN PetscErrorCode PffGridGetLocalBlocks(PffGrid grid, PetscInt *nlocal);
PETSC_EXTERN PetscErrorCode PffGridGetBlockInfo(PffGrid grid, PetscInt lb, PffBlockInfo *info);
/* Active blocks in global Morton order (the order of files and checksums); borrowed. */
PETSC_EXTERN PetscErrorCode PffGridGetMortonOrder(PffGrid grid, PetscInt *nactive, const PetscInt **gids);
/* Local index of global block gid, or -1 when another rank owns it. */
PETSC_EXTERN PetscErrorCode PffGridGetLocalIndex(PffGrid grid, PetscInt gid, PetscInt *lb);
PETSC_EXTERN PetscErrorCode PffGridGetPartitionQuality(PffGrid grid, PffPartitionQuality *q);
/* Extra work per raster block (e.g. its particles in cell-equivalents), added to the cells at its level in
   the partition weights of the next partition (PffGridAdapt, also with a NULL map) and in the imbalance
   of PffGridGetPartitionQuality, which it updates at once. NULL: cells only. Not collective, but every
   rank must pass the same values. */
PETSC_EXTERN PetscErrorCode PffGridSetBlockWork(PffGrid grid, const PetscInt64 extra[]);
/* Global number of active cells at each level and in total (collective-free: from the raster). */
PETSC_EXTERN PetscErrorCode PffGridGetCellCounts(PffGrid grid, PetscInt64 perLevel[PFF_GRID_MAX_LEVELS],
                                                 PetscInt64 *total);

/* Global cell numbering: ranks in order, each rank's owned blocks in Morton order, cells x fastest
   at the block's level. *first = global number of cell 0 of active block gid (on any rank), *nowned =
   cells owned by this rank, *rstart = global number of its first cell, *ntotal = all active cells.
   Any output pointer may be NULL. Not collective. */
PETSC_EXTERN PetscErrorCode PffGridGetCellNumbering(PffGrid grid, PetscInt gid, PetscInt64 *first, PetscInt64 *nowned,
                                                    PetscInt64 *rstart, PetscInt64 *ntotal);
/* Channels. AddChannel may be called before or after SetUp; the data is zeroed. width is the halo
   width in cells of the block's own level, 1..PFF_GRID_MAX_WIDTH and at most the cells per axis
   of the coarsest block. *ch receives the channel index (required). Not collective, but every rank must
   add the same channels in the same order. */
PETSC_EXTERN PetscErrorCode PffGridAddChannel(PffGrid grid, const char name[], PffChannelKind kind, PetscInt width,
                                              PetscInt *ch);
PETSC_EXTERN PetscErrorCode PffGridGetChannelInfo(PffGrid grid, PetscInt ch, const char **name, PffChannelKind *kind,
                                                  PetscInt *ncomp, PetscInt *width);
PETSC_EXTERN PetscErrorCode PffGridGetNumChannels(PffGrid grid, PetscInt *nch);
/* Whether channel ch is written to output frames (PffIOWriteFrame, PffIOWriteFrameParticles; default
   PETSC_TRUE). Checkpoints write every channel regardless. Not collective, but every rank must set the
   same flags before writing a frame. */
PETSC_EXTERN PetscErrorCode PffGridSetChannelOutput(PffGrid grid, PetscInt ch, PetscBool write);
PETSC_EXTERN PetscErrorCode PffGridGetChannelOutput(PffGrid grid, PetscInt ch, PetscBool *write);
/* Owned values of component comp of local block lb: n^3 floats, x fastest. Borrowed. */
PETSC_EXTERN PetscErrorCode PffGridGetBlockData(PffGrid grid, PetscInt ch, PetscInt lb, PetscInt comp, float **data);
/* The 27 region views of component comp of local block lb (see PffView). Borrowed. */
PETSC_EXTERN PetscErrorCode PffGridGetBlockViews(PffGrid grid, PetscInt ch, PetscInt lb, PetscInt comp,
                                                 const PffView **views);

/* Zeroes channel ch: its owned values and every ghost box its views reach (not the neighbours' storage beyond
   them), with the threads; what a kernel that adds into a block's neighbourhood (P2G) needs before it starts. */
PETSC_EXTERN PetscErrorCode PffGridZeroChannel(PffGrid grid, PetscInt ch);
/* dst = a src on the owned values (not the ghosts), with the threads; the channels must have the same kind. */
PETSC_EXTERN PetscErrorCode PffGridScaleChannel(PffGrid grid, PetscInt dst, PetscReal a, PetscInt src);

/* How a channel's values follow their block when PffGridAdapt changes its level (blocks keep their place
   and size; only their cells per axis change):
     linear    restriction by the mean of the fine samples (8 cells, or the 4 coplanar faces); prolongation
               by limited slopes (MC) inside the coarse block, one-sided at its edges. Both conserve the
               integral of a cell channel and the flux through every coarse face, are exact for linear
               fields, and restricting a prolonged block returns it to rounding. The default.
     constant  the same restriction; a fine sample takes the value of the coarse sample at or below it.
     none      not transferred: zero after an adapt (scratch that is recomputed before it is read).
   Blocks that become active start at zero in every channel. */
typedef enum { PFF_TRANSFER_LINEAR, PFF_TRANSFER_CONSTANT, PFF_TRANSFER_NONE } PffTransferType;
PETSC_EXTERN const char *const PffTransferTypes[];
/* Not collective, but every rank must set the same type. */
PETSC_EXTERN PetscErrorCode PffGridSetChannelTransfer(PffGrid grid, PetscInt ch, PffTransferType type);
PETSC_EXTERN PetscErrorCode PffGridGetChannelTransfer(PffGrid grid, PetscInt ch, PffTransferType *type);

/* What the last PffGridAdapt did, summed over ranks (imbalance and cut faces: PffGridGetPartitionQuality). */
typedef struct {
  PetscInt   refined, coarsened, activated, deactivated; /* blocks whose level changed, or that appeared or went */
  PetscInt   moved;                                      /* blocks that changed owner */
  PetscInt64 bytesMoved;                                 /* channel bytes received from other ranks */
  PetscReal  seconds;                                    /* wall time of the adapt on the slowest rank */
} PffAdaptInfo;

/* Topology change (PF-FLIP Sec. 5.4): level[] is the new requested level of every raster block (-1
   inactive; NULL keeps the current levels and only re-partitions). The map is graded 2:1 as at set-up and
   partitioned again with the grid's partitioner; every channel's values move to the block's new owner
   and level (PffTransferType), views and halo plans are rebuilt, and the topology state increases.
   Collective; every rank passes the same map. Halos are not current afterwards. */
PETSC_EXTERN PetscErrorCode PffGridAdapt(PffGrid grid, const PetscInt level[]);
PETSC_EXTERN PetscErrorCode PffGridGetAdaptInfo(PffGrid grid, PffAdaptInfo *info);
/* A counter that each PffGridAdapt increases. An object that caches anything derived from the raster
   (block lists, halo plans, operators, particle bins) keeps the value it was built at and rebuilds when
   it differs. Not collective. */
PETSC_EXTERN PetscErrorCode PffGridGetTopologyState(PffGrid grid, PetscObjectState *state);

/* Pure per-block kernels of the transfer, exposed for tests: component comp of a channel of the given kind
   (staggered along comp for faces) from a block of nf cells per axis to one of nf / 2 (restrict), and from
   nc to 2 nc (prolong). */
PETSC_EXTERN void PffBlockRestrict(PffChannelKind kind, PetscInt comp, PetscInt nf, const float fine[], float coarse[]);
PETSC_EXTERN void PffBlockProlong(PffChannelKind kind, PetscInt comp, PffTransferType type, PetscInt nc,
                                  const float coarse[], float fine[]);

/* Halo exchange of block face, edge and corner layers of width w (the channel's), across ranks and
   levels: same level copies, a coarser neighbour is interpolated (trilinear, linear extrapolation
   inside the neighbour), a finer neighbour is averaged. Split phase: work that does not read ghosts
   may run between Begin and End. Collective. */
PETSC_EXTERN PetscErrorCode PffGridHaloBegin(PffGrid grid, PetscInt ch);
PETSC_EXTERN PetscErrorCode PffGridHaloEnd(PffGrid grid, PetscInt ch);
/* Reverse halo: sums what was written into ghost buffers back into the owners' cells (for splatting),
   conserving the global sum, and zeroes the ghost buffers. Collective. */
PETSC_EXTERN PetscErrorCode PffGridHaloReverseBegin(PffGrid grid, PetscInt ch);
PETSC_EXTERN PetscErrorCode PffGridHaloReverseEnd(PffGrid grid, PetscInt ch);

/* World position -> block and cell at the block's level (shifts and masks). gid = -1 outside the
   domain or in an inactive block. Not collective. */
PETSC_EXTERN PetscErrorCode PffGridLocate(PffGrid grid, const PetscReal x[3], PetscInt *gid, PetscInt *level,
                                          PetscInt cell[3]);
/* Trilinear interpolation of channel ch at np points x[3*np] that lie in locally owned blocks; val
   receives ncomp values per point (MAC components each on their own staggered lattice). Ghosts must be
   current (PffGridHaloBegin/End). Exact for linear fields, also across level boundaries. Not collective. */
PETSC_EXTERN PetscErrorCode PffGridInterpolate(PffGrid grid, PetscInt ch, PetscInt np, const PetscReal x[],
                                               PetscReal val[]);

/* As PffGridInterpolate, but point p is interpolated on the lattice of local block lb[p] and may lie
   outside it, as far as the channel's halo width minus one cell (periodic images are unwrapped
   towards the block). For particles that left their block during one advection step. Not collective. */
/* Component comp of channel ch at lp, in cell units of local block lb's level from its lower corner,
   interpolated exactly as PffGridInterpolateFrom() does on the block's lattice (stencils reaching into
   the halo included). For kernels that loop over the particles of a block: not collective,
   thread-safe (reads only), no logging and no argument checks (ch, lb and comp must be valid and lp
   within the channel's halo). */
PETSC_EXTERN PetscReal      PffGridInterpolateInBlock(PffGrid grid, PetscInt ch, PetscInt lb, PetscInt comp,
                                                      const PetscReal lp[3]);
PETSC_EXTERN PetscErrorCode PffGridInterpolateFrom(PffGrid grid, PetscInt ch, PetscInt np, const PetscReal x[],
                                                   const PetscInt lb[], PetscReal val[]);
/* Sets every owned value of channel ch to fn at its sample position x (the cell centre, or the lower
   comp-face of a face channel). Not collective; ghosts are not touched. */
typedef PetscReal (*PffFieldFn)(const PetscReal x[3], PetscInt comp, void *ctx);
PETSC_EXTERN PetscErrorCode PffGridFillChannel(PffGrid grid, PetscInt ch, PffFieldFn fn, void *ctx);

/* 7-point Laplacian dst = lap(src) on cell channels, using src's ghosts (exchanged by the caller). */
PETSC_EXTERN PetscErrorCode PffGridApplyLaplacian(PffGrid grid, PetscInt src, PetscInt dst);

/* Pure helpers on a raster of nb blocks (x fastest), exposed for tests and tools. */
/* Refines (never coarsens) level[] so that active 26-neighbours differ by at most one level. */
PETSC_EXTERN PetscErrorCode PffGradeLevels(const PetscInt nb[3], const PetscBool periodic[3], PetscInt level[]);
/* Raster coordinates of block gid (x fastest). */
static inline void PffRasterCoordinates(const PetscInt nb[3], PetscInt gid, PetscInt ijk[3])
{
  ijk[0] = gid % nb[0];
  ijk[1] = (gid / nb[0]) % nb[1];
  ijk[2] = gid / (nb[0] * nb[1]);
}
/* Global index of the neighbour of block (i,j,k) in direction d[3] in {-1,0,1}^3, or -1 across a wall. */
PETSC_EXTERN PetscInt PffRasterNeighbour(const PetscInt nb[3], const PetscBool periodic[3], const PetscInt ijk[3],
                                         const PetscInt d[3]);
