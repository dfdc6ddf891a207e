/* Private state of PffGrid; only src/grid/ includes this. */
#pragma once

#include <pff.h>
#include <petscsf.h>
#include <petscviewer.h>

/* One region of one block component that is not read directly from a neighbour's storage. */
typedef struct {
  PetscInt   lb, comp, region;
  PetscInt   nbgid;  /* neighbour block, -1 across a wall or towards an inactive block */
  PetscInt   rel;    /* level(neighbour) - level(block): 0, +1 (coarser) or -1 (finer) */
  PetscInt   glo[3]; /* first ghost cell, block-local coordinates at the block's level */
  PetscInt   gn[3];  /* ghost box extent */
  PetscInt   slo[3]; /* first source cell, neighbour-local coordinates at the neighbour's level */
  PetscInt   sn[3];  /* source box extent (cross-level only) */
  PetscInt64 goff;   /* ghost box offset in the halo buffer */
  PetscInt64 soff;   /* source box offset in the halo buffer (cross-level only) */
} PffHaloXfer;

/* Communication plan shared by every channel of one kind and width; rebuilt when the raster changes. */
typedef struct {
  PffChannelKind kind;
  PetscInt       width, ncomp;
  PetscInt64     nhalo; /* floats in the halo buffer: the SF's leaves, then the ghost boxes no exchange writes */
  PetscInt64    *goff;  /* [nlocal][ncomp][27] ghost box offset, -1 for a direct (same rank, same level) view */
  PetscInt       nxfer;
  PffHaloXfer   *xfer;
  PetscSF        sf;         /* roots: channel data; leaves: halo buffer */
  PetscInt64     recvRemote; /* leaves fed by other ranks (floats) */
} PffHaloPlan;

/* The face layers of a cell channel block that a 7-point stencil reads, taken from its 27 views
   (PffView) and packed into 64 bytes: a sweep over many small blocks would otherwise stream about
   1 kB of views per block, more than a 4^3 block's own cells in and out. face[] is the address of
   the first cell of the layers x-, x+, y-, y+, z-, z+, i.e. of block-local cells (-1,0,0), (n,0,0),
   (0,-1,0), (0,n,0), (0,0,-1), (0,0,n); sy[] are the j strides of the two x layers, sz[] the k
   strides of the x and y layers. Rows of the z layers, like the block's own, are n apart. */
typedef struct {
  const float *face[6];
  int16_t      sy[2], sz[4];
} PffFaceViews;

typedef struct {
  char            name[64];
  PffChannelKind  kind;
  PetscInt        ncomp, width;
  float          *data;               /* owned values, [local block][comp][n^3] */
  float          *alloc;              /* data - PFF_CHANNEL_PAD: row kernels may read one value past either end */
  float          *halo;               /* ghost and source boxes of the plan */
  size_t          nalloc, nhaloAlloc; /* floats allocated at alloc and halo (an adapt reuses them when they fit) */
  PffView        *views;              /* [nlocal][ncomp][27] */
  PffFaceViews   *faces;              /* [nlocal], cell channels only (NULL otherwise) */
  PffHaloPlan    *plan;               /* borrowed from the grid */
  PetscBool       output;             /* written to frames (PffGridSetChannelOutput); checkpoints write every channel */
  PffTransferType transfer;           /* how the values follow an adapt (PffGridSetChannelTransfer) */
} PffChannel;

struct _n_PffGrid {
  MPI_Comm    comm;
  PetscMPIInt rank, size;
  PetscBool   setupcalled;

  /* parameters */
  PetscInt         cells[3], n0, log2n0, nlevels;
  PetscReal        origin[3], h0;
  PetscBool        periodic[3];
  PffPartitionType ptype;
  PffRefineType    rtype;
  PetscReal        rpoint[3], rnormal[3], rradius, rband;
  PetscBool        rcolumns; /* -grid_refine_columns: each block column takes the finest level asked in it */
  PffRefineFn      refine;
  void            *refinectx;
  PetscInt        *usermap;

  /* replicated raster */
  PetscInt     nb[3], nblocks, nactive;
  PetscInt    *level;         /* [nblocks], -1 inactive */
  PetscMPIInt *owner;         /* [nblocks], -1 inactive */
  uint64_t    *morton;        /* [nblocks] */
  PetscInt    *order;         /* [nactive] active blocks by Morton key */
  PetscInt64  *offset;        /* [nblocks] cell offset of the block in its owner's storage */
  PetscInt64  *rankCellStart; /* [size + 1] global number of the first cell of each rank */
  PetscInt    *local;         /* [nblocks] local index on this rank or -1 */
  PetscInt64  *xwork;         /* [nblocks] extra partition work per block (PffGridSetBlockWork), or NULL */

  /* owned blocks, Morton order */
  PetscInt    nlocal;
  PetscInt   *lgid;   /* [nlocal] */
  PetscInt   *lholes; /* [nlocal] bit r set: region r lies across a wall or faces an inactive block */
  PetscInt64 *loff;   /* [nlocal + 1] cell offsets */
  PetscInt64  ncells; /* owned cells */

  PetscInt     nch;
  PffChannel  *ch[PFF_GRID_MAX_CHANNELS];
  PetscInt     nplans;
  PffHaloPlan *plans[2 * PFF_GRID_MAX_WIDTH];

  PffPartitionQuality quality;
  PetscObjectState    topology; /* increased by every PffGridAdapt */
  PffAdaptInfo        adaptInfo;
};

#define PFF_CHANNEL_PAD 16

static inline PetscInt PffGridBlockN_Private(PffGrid g, PetscInt gid)
{
  return g->n0 >> g->level[gid];
}

static inline void PffGridBlockIJK_Private(PffGrid g, PetscInt gid, PetscInt ijk[3])
{
  ijk[0] = gid % g->nb[0];
  ijk[1] = (gid / g->nb[0]) % g->nb[1];
  ijk[2] = gid / (g->nb[0] * g->nb[1]);
}

/* Neighbour of block gid in the direction of region r, or -1 across a wall or towards an inactive block. */
static inline PetscInt PffGridActiveNeighbour_Private(PffGrid g, PetscInt gid, PetscInt r)
{
  PetscInt ijk[3], d[3];
  PffGridBlockIJK_Private(g, gid, ijk);
  PffRegionDirection(r, d);
  const PetscInt nbr = PffRasterNeighbour(g->nb, g->periodic, ijk, d);
  return (nbr >= 0 && g->level[nbr] >= 0) ? nbr : -1;
}

PETSC_INTERN PetscErrorCode PffGridBuildRaster_Private(PffGrid);
PETSC_INTERN PetscErrorCode PffGridPartition_Private(PffGrid);
PETSC_INTERN PetscErrorCode PffGridAllocateChannel_Private(PffGrid, PffChannel *, PetscBool);
PETSC_INTERN PetscErrorCode PffGridDestroyChannel_Private(PffChannel **);
PETSC_INTERN PetscErrorCode PffHaloPlanGet_Private(PffGrid, PffChannelKind, PetscInt, PffHaloPlan **);
PETSC_INTERN PetscErrorCode PffHaloPlanDestroy_Private(PffHaloPlan **);
PETSC_INTERN PetscErrorCode PffGridComputeQuality_Private(PffGrid);
/* Channel ch of a set-up grid, or an error naming what is wrong. */
PETSC_INTERN PetscErrorCode PffGridGetChannel_Private(PffGrid, PetscInt, PffChannel **);
PETSC_INTERN void           PffZeroFloats_Private(float *, PetscInt64);
/* Lattice offset (0 or 1/2 cell) of component comp of a channel kind along axis d. */
static inline PetscReal PffChannelOffset_Private(PffChannelKind kind, PetscInt comp, PetscInt d)
{
  return (kind == PFF_CHANNEL_FACE && comp == d) ? 0.0 : 0.5;
}
