/* The private body of PffPressure: the face list of the owned cells, the gradient matrix, the
   assembled operator and the Krylov solver. Only src/pressure/ includes this header. */
#pragma once

#include <pff.h>

/* How the lower face of an owned cell along one axis sits in the block raster. */
typedef enum {
  PFF_FACE_INTERIOR, /* both cells in the same block */
  PFF_FACE_SAME,     /* lower cell in a same-level neighbour block */
  PFF_FACE_COARSER,  /* fine above coarse: lower side = one coarse cell, d_f = Delta_g 2h, A_f = h^2 */
  PFF_FACE_FINER,    /* coarse above fine: lower side = 4 fine cells (1/4 each), d_f = Delta_g h, A_f = h^2 */
  PFF_FACE_WALL,     /* domain wall (closed) */
  PFF_FACE_INACTIVE, /* inactive neighbour block (closed) */
  PFF_FACE_NKINDS
} PffFaceKind;

PETSC_INTERN const char *const PffFaceKinds[];

typedef enum { PFF_PRESSURE_ASSEMBLY_PTAP, PFF_PRESSURE_ASSEMBLY_DIRECT } PffPressureAssemblyType;
PETSC_INTERN const char *const PffPressureAssemblyTypes[];

struct _n_PffPressure {
  PffGrid          grid;
  MPI_Comm         comm; /* the grid's, borrowed */
  PetscBool        setup, coefficientsSet;
  PetscObjectState topology; /* the grid's topology state at SetUp; a different one resets (PffPressureReset) */

  /* cell numbering: owned cells are global rows rstart .. rstart + ncells - 1 */
  PetscInt  nlocal, ncells, rstart, ntotal;
  PetscInt *blockStart; /* [nlocal + 1] first local cell of each owned block */

  /* face list, structure of arrays over the owned face rows r = 3 * (local cell) + d
     (global face row = 3 * (global cell) + d): */
  unsigned char *kind;   /* PffFaceKind */
  PetscInt      *lower;  /* global lower cell; for PFF_FACE_FINER the index of its 4-cell set; -1 when closed */
  PetscInt      *lower4; /* [4 * nfiner] the fine cells under each coarse face */
  PetscInt       nfiner;
  PetscReal     *hblock;                 /* [nlocal] cell size of each owned block; d_f from it and the kind */
  PetscInt64     nkind[PFF_FACE_NKINDS]; /* global counts per class, for PffPressureView-style info */

  /* G, W, w and A exist only when something needs A's entries (PffPressureCreateOperator_Private):
     the projection itself and the matrix-free pffmg go through the shell's face lists */
  Mat          G;      /* gradient: 3 ncells x ncells rows, (G p)_f = (p_upper - sum w_c p_c) / d_f */
  Mat          W;      /* diag(M_f beta_f open_f) on the face rows, for MatPtAP */
  Vec          w;      /* its diagonal, M_f beta_f open_f = c_f d_f^2 */
  Mat          A;      /* G^T W G */
  Mat          S;      /* the matrix-free A (shell.c), always: it owns the face coefficients */
  PetscReal   *cf;     /* [3 ncells] c_f of the lower d-face of cell c at d * ncells + c (the shell's) */
  MatNullSpace nullsp; /* constants (or the connected cells), NULL when a Dirichlet wall makes A definite */
  KSP          ksp;

  PetscBool dirichlet[6]; /* p = 0 on wall -x, +x, -y, +y, -z, +z (at the wall face, half a cell out) */
  Vec       dirdiag;      /* cell Vec: the Dirichlet terms sum 2 h beta added to diag(A) */

  Vec p, b, vcell, diag; /* cell Vecs: pressure, rhs, work, diag(A) */
  Vec uf;                /* velocity, 3 per owned cell (a sequential Vec: faces are numbered per rank only) */

  PffPressureAssemblyType assembly;
  PffPressureOperatorType operatorType;    /* the KSP's Amat */
  PetscBool               operatorTypeSet; /* chosen by the user; otherwise shell under the matrix-free pffmg */
  PffPressureFailureType  onFailure;       /* -pressure_on_failure */
  PetscBool               subPCDefaultApplied;
  PetscBool               monitorDivergence; /* -pressure_monitor_divergence: two divergence passes per solve */
};

/* Whether any wall is Dirichlet (then A is definite and has no null space). */
static inline PetscBool PffPressureHasDirichlet_Private(PffPressure ps)
{
  for (PetscInt w = 0; w < 6; w++)
    if (ps->dirichlet[w]) return PETSC_TRUE;
  return PETSC_FALSE;
}

/* d_f of a face of the given kind below a cell of size h, the distance between the cell centres on both
   sides (faces.c); 0 when closed. */
static inline PetscReal PffPressureFaceDistance(PetscInt kind, PetscReal h)
{
  switch (kind) {
  case PFF_FACE_INTERIOR:
  case PFF_FACE_SAME:
    return h;
  case PFF_FACE_COARSER:
    return PFF_PRESSURE_DELTA_G * 2 * h;
  case PFF_FACE_FINER:
    return PFF_PRESSURE_DELTA_G * 2 * (h / 2); /* Delta_g 2 h_fine */
  default:
    return 0;
  }
}

/* Columns and values of face row r of G, the row of a cell of size h: at most 5 (the cell, and 1 or 4
   lower cells). */
static inline PetscInt PffPressureGradientRow(PffPressure ps, PetscInt r, PetscReal h, PetscInt cols[5],
                                              PetscScalar vals[5])
{
  const PetscInt  kind = ps->kind[r];
  const PetscReal df = PffPressureFaceDistance(kind, h), id = df > 0 ? 1.0 / df : 0.0;

  if (kind == PFF_FACE_WALL || kind == PFF_FACE_INACTIVE) return 0;
  cols[0] = ps->rstart + r / 3;
  vals[0] = id;
  if (kind != PFF_FACE_FINER) {
    cols[1] = ps->lower[r];
    vals[1] = -id;
    return 2;
  }
  for (PetscInt q = 0; q < 4; q++) {
    cols[1 + q] = ps->lower4[4 * ps->lower[r] + q];
    vals[1 + q] = -0.25 * id;
  }
  return 5;
}

PETSC_INTERN PetscErrorCode PffPressureBuildFaces_Private(PffPressure);
PETSC_INTERN PetscErrorCode PffPressureBuildGradient_Private(PffPressure);
PETSC_INTERN PetscErrorCode PffPressureAssemble_Private(PffPressure, PetscInt, PetscInt);
PETSC_INTERN PetscErrorCode PffPressureCreateOperator_Private(PffPressure);
PETSC_INTERN PetscErrorCode PffPressureAssembleOperator_Private(PffPressure);
PETSC_INTERN PetscErrorCode PffPressureNullSpace_Private(PffPressure);
PETSC_INTERN PetscErrorCode PffPressureShellFaceDiagonal_Private(Mat, Vec);
PETSC_INTERN PetscErrorCode PffPressureMGUsesStencil_Private(PC, PetscBool *);
PETSC_INTERN PetscErrorCode PffPressureShellCreate_Private(PffPressure, Mat *);
PETSC_INTERN PetscErrorCode PffPressureShellUpdate_Private(PffPressure, Mat);
PETSC_INTERN PetscErrorCode PffPressureShellGetCoefficients_Private(Mat, PetscReal **);
PETSC_INTERN PetscErrorCode PffPressureShellDivergence_Private(PffPressure, Mat, Vec, PetscBool, Vec);
PETSC_INTERN PetscErrorCode PffPressureShellProjectVelocity_Private(PffPressure, Mat, Vec, PetscReal, Vec);
PETSC_INTERN PetscErrorCode PffPressureChannelToVec_Private(PffPressure, PetscInt, PffChannelKind, Vec);
PETSC_INTERN PetscErrorCode PffPressureVecToChannel_Private(PffPressure, Vec, PffChannelKind, PetscInt);
PETSC_INTERN PetscErrorCode PffPressureMaxDivergenceVec_Private(PffPressure, Vec, PetscReal *);
PETSC_INTERN PetscErrorCode PffPressureMGRegister_Private(void);
PETSC_INTERN PetscErrorCode PffPressureFCGBytes_Private(KSP, PetscInt, PetscInt, PetscLogDouble *, PetscBool *);
PETSC_INTERN PetscErrorCode PffPressureProductBytes_Private(Mat, PetscReal, PetscLogDouble *);
PETSC_INTERN PetscErrorCode PffPressureMGIsActive_Private(PC, PetscBool *);
PETSC_INTERN PetscErrorCode PffPressureMGSetFromOptions_Private(PC);
PETSC_INTERN PetscErrorCode PffPressureMGComposePressure_Private(PC, PffPressure);
