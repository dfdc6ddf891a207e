/* The private body of the adaptive multigrid preconditioner (pffmg, PF-FLIP Sec. 6): one level per
   multigrid level L, each a set of the owned MSBG blocks at resolution max(l_block, L), the Galerkin
   operator of that level and the block/cell colouring the smoother needs. Only src/pressure/
   includes this header. */
#pragma once

#include "pressureimpl.h"

typedef enum { PFF_MG_SMOOTHER_RBGS, PFF_MG_SMOOTHER_JACOBI } PffMGSmootherType;
PETSC_INTERN const char *const PffMGSmootherTypes[];

/* How the block levels store their operators: matrix-free face coefficients (mgstencil.c) or AIJ
   Galerkin products (MatPtAP, the first implementation, kept for comparison). */
typedef enum { PFF_MG_OPERATOR_STENCIL, PFF_MG_OPERATOR_AIJ } PffMGOperatorType;
PETSC_INTERN const char *const PffMGOperatorTypes[];

/* Storage precision of the matrix-free coefficients (the solve vectors stay double). */
typedef float PffMGReal;

#define MPIU_PFFMGREAL MPI_FLOAT

/* The matrix-free operator of one block level (mgstencil.c), A = sum_f c_f g_f g_f^T + diag(dx):
   each cell owns the coefficients of its three lower faces (cf), the faces inside a block are read
   by raster strides, and the couplings through block sides (same level, coarse-fine) are a small
   per-row list whose values are refreshed from cf at every set-up. The diagonal is the sum of the
   row's face terms, computed where it is used, so every row sums to dx exactly. */
typedef struct {
  PffMGReal *cf;     /* [3 nrows] c of the lower d-face of each cell at cf[d nrows + row] (0: closed) */
  PffMGReal *dx;     /* [nrows] diagonal-only terms: Dirichlet walls, the unit of a cell with no open face */
  PetscReal *ds;     /* [nrows] the diagonal but for the faces inside the block: side faces, dx (double, so that the
                        rows sum to dx exactly) */
  float *adf, *idf;  /* [nrows] a_ii in float (the float block visits), and 1 / a_ii (0: an empty row), its only copy */
  PetscInt  *rowptr; /* [nrows + 1] side couplings of each row to other cells */
  PetscBool *own;    /* [nblk] the block has side terms between its own cells (PffMGStencilBlockRhs_Private) */
  PetscInt  *fnb;    /* [6 nblk] per side, the owned neighbour block of the same size whose couplings go face by face
                        (FaceSums), or -1 */
  PetscInt  *sb;     /* [nblk + 1] the other side entries of block lb: sent[sb[lb] .. sb[lb + 1]), rows srow */
  PetscInt  *srow, *sent;
  PetscInt  *col;               /* local row, or nrows + ghost index */
  PffMGReal *val;               /* matrix entry: fac * c of the face */
  PetscInt  *ref;               /* the face: slot d nrows + row of cf, or 3 nrows + ghost slot */
  PffMGReal *fac;               /* g_f[row] g_f[col] */
  PetscInt   ndiag;             /* side-face terms of the diagonal */
  PetscInt  *drow, *dref;       /* their row and face */
  PffMGReal *dfac;              /* g_f[row]^2 */
  PetscInt   nghost, *ghostRow; /* ghost cells: global rows, increasing */
  PetscInt   nslot;             /* ghost face coefficients (faces owned by another rank's cells) */
  PffMGReal *cghost;            /* [nslot] */
  PetscSF    sfSlot;            /* owned cf -> cghost */
  Mat        Aview;             /* assembled copy for PffPressureMGGetLevel, or NULL */
  PetscInt   nclosed, *closed;  /* level 0: the rows with no open face and no Dirichlet term (inside solids) */
  PetscInt   closedCap;         /* room in closed */
} PffMGStencil;

/* Options (prefix pressure_pffmg_), defaults beside PffMGCreate in mg.c. */
typedef struct {
  PffMGSmootherType smoother;
  PetscBool         adaptive;      /* Algorithm 2 (active block lists); otherwise fixed sweeps */
  PetscBool         blockSweeps;   /* repeat block-local sweeps until the update falls by 1/3 */
  PetscInt          sweeps;        /* fixed pre- and post-sweeps when not adaptive */
  PetscInt          adaptiveSteps; /* N_iter,max of Algorithm 2 */
  PetscInt          blockSweepsMax;
  PffMGOperatorType operatorType;
  PetscReal         omega;
  PetscReal         thetaSigmas; /* theta = mean + thetaSigmas * std of log10 of the block maxima */
  PetscInt          maxLevels;
  PetscInt          coarseMax;   /* add uniform levels below the raster until at most this many cells */
  PetscReal         correction;  /* coarse-grid correction scale */
  PetscInt          kcycleIts;   /* flexible-CG steps per coarse correction, 0: V-cycle */
  PetscReal         kcycleRtol;  /* a coarse correction stops early at this residual reduction; 0: always kcycleIts */
  PetscReal         kcycleRatio; /* K-cycle on a level only if the level above has at least this many times its rows */
  PetscBool         rescale;     /* rediscretisation-consistent coarse coefficients (mglevels.c) */
  PetscInt          ompMinRows;  /* fewest rows per rank for a level's smoothing and products to fork threads */
} PffMGOptions;

/* One multigrid level. Rows are the owned cells: owned blocks in local (Morton) order, cells x
   fastest at the block's resolution at this level. */
typedef struct {
  PetscInt  L;
  PetscBool uniform; /* below the block raster: units are uniform coarse cells, not blocks */
  PetscInt  nblk;    /* units (blocks, or coarse cells on uniform levels) */
  PetscInt *coord;   /* [3 nblk] unit coordinates on uniform levels (block coordinates >> (L - Lr)) */
  Mat       A;       /* level operator: a MATSHELL on matrix-free levels; level 0 with AIJ operators: the
                        pressure module's, referenced */
  PffMGStencil *st;  /* face coefficients (every block level with stencil operators) */
  PetscBool     mf;  /* relaxed and applied matrix-free (every block level but the last) */
  PetscBool     omp; /* enough rows for OpenMP (nrows >= ompMinRows) */
  Mat P; /* prolongation from level L+1 (piecewise constant), NULL on the coarsest; on matrix-free levels the transfers
            run block by block and P is assembled only on request (PffPressureMGGetLevel) */
  KSP       kcycle;        /* K-cycle solver of this level's correction, or NULL */
  Vec       x, b, r;       /* work (x, b unused on level 0, which works on the PC's vectors) */
  PetscInt  nrows, rstart; /* owned rows, first global row */
  PetscInt *n;             /* [nlocal] cells per axis of each block at this level */
  PetscInt *start;         /* [nlocal + 1] first local row of each block */
  PetscInt *order, *split; /* rows of block lb: order[start[lb] .. split[lb]) red, then black (AIJ levels; NULL on
                              matrix-free ones) */
  PetscBool     *relevant; /* [nlocal] relaxed at this level (resolution L, or L+1 beside a block at L) */
  unsigned char *remote;   /* [nblk] the unit has a face neighbour on another rank (relaxed after the ghost exchange) */
  unsigned char *merged, *mergedGhost; /* [nrows], [nghost]: the cell was merged from level L-1 (RescaleCoarse) */
  PetscInt       ncolour[2];           /* blocks of each block colour */
  PetscInt      *colourList;           /* [nlocal] relevant blocks: colour 0 first, then colour 1 */

  /* CSR of the local rows: the diagonal block (local columns) and the off-rank block (ghost columns) */
  Mat                Ad, Ao;
  const PetscInt    *ai, *aj, *bi, *bj, *colmap;
  const PetscScalar *aa, *ba;
  PetscInt           nghost;
  Vec                ghost; /* off-rank values of x, in colmap order */
  VecScatter         scatter;
  PetscScalar       *idiag; /* 1 / a_ii (0 for an empty row); NULL on matrix-free levels, which keep st->idf */
} PffMGLevel;

typedef struct {
  PffGrid          grid;
  PffPressure      ps; /* the coefficients of level 0 (stencil operators) */
  MPI_Comm         comm;
  PffMGOptions     opt;
  PetscInt         nlevels, nlocal;
  PetscInt         nblockLevels; /* levels with blocks; the last of them is AIJ, the others matrix-free (stencil) */
  Mat              Apc;          /* the operator the hierarchy was built for (the PC's Pmat), referenced */
  PffMGLevel      *lev;
  KSP              coarse;    /* coarsest-level solver, options prefix pressure_pffmg_coarse_ */
  MatNullSpace     constants; /* the constants, null space of the singular coarse levels */
  Mat              Apinned;   /* the coarsest operator with its first diagonal entry doubled, when A is singular */
  PetscBool        singular;  /* A has the constants as null space: the coarsest operator is pinned */
  PetscBool        built;     /* hierarchy structure exists (coefficients are refreshed each set-up) */
  PetscObjectState topology;  /* the grid's topology state the hierarchy was built at */
  PetscBool        optionsRead;
  /* per-block scratch for adaptive relaxation */
  PetscInt      *nbr;               /* [6 nlocal] local face neighbour (or -1: none, wall, or remote -2 - gid) */
  PetscInt      *actLeafOf;         /* [6 nlocal] SF leaf of each face with an off-rank neighbour, or -1 */
  PetscInt      *actLeaf, *actRoot; /* activation requests sent (per leaf) and received (per owned block) */
  PetscSF        actSF;             /* leaves -> the neighbour blocks on their owners (BuildActivationSF) */
  PetscInt       nactLeaf;          /* leaves of actSF */
  PetscReal     *bres;              /* [nlocal] per-block effective residual */
  PetscReal     *face;              /* [6 nlocal] per-face border effective residual */
  PetscInt      *list;              /* [nlocal] active blocks */
  PetscInt      *gid;               /* [nlocal] raster index of each owned block */
  unsigned char *next;              /* [nlocal] blocks active in the next adaptive step */
  PetscReal     *r0;                /* [nlocal] first-sweep maxima of the active blocks (theta) */
  PetscReal     *R;                 /* [Rsize * threads] effective residual per cell of the block each thread relaxes */
  size_t         Rsize;             /* n0^3 */
  PetscScalar   *BB;     /* [Rsize * threads] right-hand side of the block each thread relaxes (stencil levels) */
  float         *XF;     /* [XFsize * threads] float copies of x and bb of the block each thread relaxes */
  size_t         XFsize; /* 2 n0^3 + 2 n0 */
  unsigned char *colour; /* [nlocal] block colour (x_b + y_b + z_b) mod 2 */
  PffMGStats     stats;
} PffMG;

/* Piecewise-constant transfer inside block lb: fine row q (cells j = q % nf, k = q / nf) of a block of nf^3 cells
   at level L lies in the block's coarse row starting at this block-local offset of its nc^3 cells at L+1, and
   fine cell i in coarse cell offset + (i >> s), s = 1 where the block merges 2x2x2 (nf = 2 nc), 0 where it keeps
   its resolution. The AIJ P and the matrix-free transfers both use it. */
static inline PetscInt PffMGCoarseRow_Private(PetscInt q, PetscInt nf, PetscInt nc, PetscInt s)
{
  return nc * (((q % nf) >> s) + nc * ((q / nf) >> s));
}

PETSC_INTERN PetscErrorCode PffMGBuildLevels_Private(PffMG *);
PETSC_INTERN PetscErrorCode PffMGUpdateOperators_Private(PffMG *, Mat);
PETSC_INTERN PetscErrorCode PffMGDestroyLevels_Private(PffMG *);
PETSC_INTERN PetscErrorCode PffMGSmooth_Private(PffMG *, PetscInt, Vec, Vec);
PETSC_INTERN PetscErrorCode PffMGSmoothFixed_Private(PffMG *, PetscInt, Vec, Vec, PetscInt);
PETSC_INTERN PetscErrorCode PffMGStencilBuild_Private(PffMG *, PetscInt);
PETSC_INTERN PetscErrorCode PffMGStencilUpdate_Private(PffMG *, PetscInt);
PETSC_INTERN PetscErrorCode PffMGStencilAssemble_Private(PffMG *, PetscInt, Mat *);
PETSC_INTERN PetscErrorCode PffMGStencilCreateShell_Private(PffMG *, PetscInt);
PETSC_INTERN PetscErrorCode PffMGStencilDestroy_Private(PffMGLevel *);
PETSC_INTERN PetscErrorCode PffMGStencilResidualRestrict_Private(PffMG *, PetscInt, Vec, Vec, Vec);
PETSC_INTERN PetscErrorCode PffMGGhostsBegin_Private(PffMGLevel *, Vec);
PETSC_INTERN PetscErrorCode PffMGGhostsEnd_Private(PffMGLevel *, Vec, const PetscScalar **);
PETSC_INTERN PetscErrorCode PffMGStencilProlongAdd_Private(PffMG *, PetscInt, Vec, Vec);
PETSC_INTERN PetscErrorCode PffMGBuildProlongation_Private(PffMG *, PetscInt);
PETSC_INTERN PetscBool      PffMGStencilBlockRhs_Private(const PffMGLevel *, PetscInt, const PetscScalar *,
                                                         const PetscScalar *, const PetscScalar *, PetscScalar *);
PETSC_INTERN PetscBool      PffMGStencilVisitFloat_Private(const PffMGLevel *, PetscInt);
PETSC_INTERN PetscReal PffMGStencilVisitBlock_Private(const PffMGLevel *, PetscInt, const PetscScalar *, PetscScalar *,
                                                      const PetscScalar *, PetscReal, PetscReal *, float *, PetscInt,
                                                      PetscBool, PetscReal *, PetscInt *);
PETSC_INTERN PetscReal PffMGStencilRelaxBlock_Private(const PffMGLevel *, PetscInt, const PetscScalar *, PetscBool,
                                                      PetscScalar *, PetscReal, PetscReal *);
