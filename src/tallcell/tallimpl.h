/* The private body of PffTall (include/pff/tallcell.h). Only src/tallcell/ includes this header.

   Columns. A block column (the blocks with one x and z index) has one level and one owner. Its columns of
   cells are numbered ck * n + ci (n cells per axis at its level) and each holds ny = nb[1] * n records, one
   per cell from the bottom. The records of a block column lie at bcOffset[bc] on its owner, in raster order
   of the block columns (x fastest, then z), so any rank can address any record of any rank.

   A record says how the pressure varies over its cell: for the lower and the upper half of the cell, a
   segment between two points (sample id, height); id PFF_TALL_SURFACE is the free surface (p = 0). The
   pressure at height y in that half is the linear function through the two points. */
#pragma once

#include <pff.h>
#include <pff/tallcell.h>

#define PFF_TALL_SURFACE (-1) /* segment point: the free surface, p = 0 */
#define PFF_TALL_AIR (-2)     /* record kind: an air cell */
#define PFF_TALL_SOLID (-3)   /* record kind: a cell inside the solids (chSolid <= -1) */
#define PFF_TALL_CUBIC (-1)   /* record kind: a cubic cell (otherwise the id of its tall cell's lowest sample) */
#define PFF_TALL_RI 5         /* ints per record: 4 segment ids, kind */
#define PFF_TALL_RR 5         /* reals per record: 4 segment heights, phi */
#define PFF_TALL_ROW_MAX 6    /* entries of a gradient row (2 samples above, 2 x 2 below at a finer side) */

typedef struct {
  PetscInt  n; /* entries */
  PetscInt  col[PFF_TALL_ROW_MAX];
  PetscReal val[PFF_TALL_ROW_MAX];
} PffTallRow;

struct _n_PffTall {
  PffGrid     grid;
  MPI_Comm    comm; /* the grid's, borrowed */
  PetscMPIInt rank, size;

  /* options */
  PetscBool merge;
  PetscReal layerFraction, thetaMin;
  PetscInt  layerMin;
  PetscReal sizingKappa, sizingU; /* the sizing function's turn (rad) and velocity jump (m/s) per cell */
  PetscInt  levels;               /* quadtree levels the sizing function uses (0: the grid's) */
  PetscBool sizing;               /* -tall_sizing: the liquid model builds the quadtree from the sizing function */
  PetscInt  quadInterval;         /* -tall_quadtree_interval: and rebuilds it every this many steps (0: never) */
  PetscInt  chA, chSolid;         /* solids: face open fractions, cell-centre distance in cells (-1: none) */

  /* raster */
  PetscInt     nb[3], n0;
  PetscReal    h0, origin[3];
  PetscBool    periodic[3];
  PetscInt     nbc;      /* block columns nb[0] * nb[2] */
  PetscInt    *bcLevel;  /* [nbc] */
  PetscMPIInt *bcOwner;  /* [nbc] */
  PetscInt    *bcOffset; /* [nbc] first record on the owner */

  /* owned records */
  PetscInt   nrec;
  PetscInt  *ri;     /* [PFF_TALL_RI nrec] */
  PetscReal *rr;     /* [PFF_TALL_RR nrec] */
  float     *height; /* [nrec] pressure-cell height in cells (0 air, 1 cubic, m tall) */

  /* ghost records of the lower x and z neighbour columns on other ranks */
  PetscInt    nghost; /* ghost columns */
  PetscInt64 *gkey;   /* [nghost] sorted column keys (ColumnKey) */
  PetscInt   *gstart; /* [nghost + 1] first ghost record */
  PetscInt   *gi;     /* [PFF_TALL_RI gstart[nghost]] */
  PetscReal  *gr;     /* [PFF_TALL_RR gstart[nghost]] */

  /* samples (unknowns): global numbers sstart .. sstart + nsamp - 1 */
  PetscInt   nsamp, sstart;
  PetscReal *sampleS; /* [nsamp] cell size of the sample's column */

  /* rows: local rows 0 .. nrows - 1, global rstart + r */
  PetscInt    nrows, rstart, rowsCap;
  PetscReal  *rowF, *rowV, *rowA; /* [nrows] F (1 or 1 / theta), V (area times distance), A (open fraction) */
  PetscInt   *rowFace;            /* [nrows + 1] CSR into the face list */
  PetscInt    nfaces, facesCap;
  PetscInt   *faceLb, *faceComp, *faceCell; /* [nfaces] local block, component, cell index in the block */
  float      *faceA;                        /* [nfaces] open fraction of the face */
  PffTallRow *rowEnt;                       /* [nrows] entries (global sample ids) */
  PetscInt64  nsurface;                     /* global free-surface rows: none leaves A singular */

  PetscInt64 cells, tallCells, liquidCells; /* global counts */

  /* rigid bodies (bodies.c): borrowed array; per built body 6 Vecs J (samples), U = J^T L, N = A + U rho U^T */
  PetscInt     nbodies, nbodiesBuilt;
  PffTallBody *bodies;
  PetscReal (*massL)[6][6]; /* [nbodiesBuilt] L with L L^T = M^-1 */
  Vec *J, lrcC;
  Mat  U, N;

  Mat            G, A;
  Vec            p, b, urow, grow, w; /* samples: p, b; rows: u*, G p, work */
  KSP            ksp;
  PetscBool      subPCDefaultApplied, built;
  PetscLogDouble assembleTime;
};

/* Key of the column (gx, gz) of cells at level l. */
static inline PetscInt64 PffTallColumnKey(const struct _n_PffTall *tc, PetscInt l, PetscInt gx, PetscInt gz)
{
  const PetscInt64 nx = (PetscInt64)tc->nb[0] * tc->n0, nz = (PetscInt64)tc->nb[2] * tc->n0;
  return ((PetscInt64)l * nx + gx) * nz + gz;
}

PETSC_INTERN PetscErrorCode PffTallCheckGrid_Private(PffTall);
PETSC_INTERN PetscErrorCode PffTallBuildColumns_Private(PffTall, PetscInt chPhi);
PETSC_INTERN PetscErrorCode PffTallBuildRows_Private(PffTall);
PETSC_INTERN PetscErrorCode PffTallFreeBuild_Private(PffTall);
PETSC_INTERN PetscErrorCode PffTallBuildBodies_Private(PffTall);
PETSC_INTERN PetscErrorCode PffTallBodiesRHS_Private(PffTall, PetscReal dt, PetscReal rho);
PETSC_INTERN PetscErrorCode PffTallBodiesUpdate_Private(PffTall, PetscReal dt);
PETSC_INTERN PetscErrorCode PffTallFreeBodies_Private(PffTall);
PETSC_INTERN PetscErrorCode PffTallAddRow_Private(PffTall, const PffTallRow *, PetscReal F, PetscReal V,
                                                  PetscBool surface, PetscInt nf, const PetscInt lb[],
                                                  const PetscInt comp[], const PetscInt cell[]);

/* The pressure at a liquid record's cell centre yc as weights of at most two samples (the upper half's segment of
   the column function; id -1 or weight 0: none), for writing p to cells and for the bodies' J. */
static inline void PffTallCentreWeights(const PetscInt ri[], const PetscReal rr[], PetscReal yc, PetscInt id[2],
                                        PetscReal w[2])
{
  const PetscReal t = rr[3] != rr[2] ? (yc - rr[2]) / (rr[3] - rr[2]) : 0;
  id[0]             = ri[2];
  id[1]             = ri[3];
  w[0]              = 1 - t;
  w[1]              = t;
}

/* Open fraction of face `side` (0 lower, 1 upper) normal to axis a of a cell, from the signed distance at its
   eight corners (corner v at offset (v & 1, v >> 1 & 1, v >> 2) cells). */
PETSC_INTERN PetscReal PffTallCellFaceOpen(const PetscReal corner[8], PetscInt a, PetscInt side);

/* Open fraction of the face normal to y with lower corner x0 (its height y_f) and size s, over its control volume
   y_f -+ s/2: where a solid's boundary crosses a corner's vertical in it, the open areas at y_f - s/2 and y_f + s/2
   weighted by the mean crossing height, otherwise the face's own open area. below, face, above: the signed
   distance fn at the face's corners, in the cyclic order (x, z) offsets (0,0), (0,1), (1,1), (1,0), at the
   heights y_f - s/2, y_f, y_f + s/2. */
PETSC_INTERN PetscReal PffTallYFaceOpen_Private(PffSolidFn fn, void *ctx, const PetscReal x0[3], PetscReal s,
                                                const PetscReal below[4], const PetscReal face[4],
                                                const PetscReal above[4]);

/* Whether a record kind is a liquid cell (cubic or part of a tall cell). */
static inline PetscBool PffTallLiquidKind(PetscInt kind)
{
  return (PetscBool)(kind >= PFF_TALL_CUBIC);
}
