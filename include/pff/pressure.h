/* pressure: the two-phase pressure projection (PF-FLIP Eq. 8-10) on the multiresolution grid.

   Discretisation. The unknowns are cell pressures, numbered globally rank by rank, owned blocks in
   Morton order, cells x fastest. The face unknowns are the faces a face channel stores: component d
   of a cell is its lower d-face. A face f has an area A_f, a centre distance d_f and one cell or a
   set of cells with weights on each side:
     same level       one cell each side, d_f = h, A_f = h^2;
     fine above coarse the fine cell's lower face, lower side = the coarse cell, d_f = Delta_g 2h, A_f = h^2;
     coarse above fine the coarse cell's lower face, lower side = the 4 fine cells (weight 1/4 each),
                       d_f = Delta_g 2h_fine, A_f = (2h_fine)^2;  Delta_g = 3/4 (Losasso 2004, Fig. 9c).
   The gradient is (G p)_f = (p_upper - p_lower) / d_f and the volume-weighted divergence is its
   adjoint, V D u = -G^T M u with M_f = A_f d_f, so the operator
     A = G^T diag(M_f beta_f open_f) G
   is symmetric positive semi-definite (definite when some boundary is open or the null space is
   removed) and equals the textbook 7-point stencil on a uniform grid. Faces with open_f = 0 (domain
   walls, solids) carry no flux; periodic axes wrap. A Dirichlet wall (p = 0 at the wall face) adds
   2 h beta to the diagonal of each cell beside it, which makes A definite.

   Numbering (the Vecs and Mats below): cell rows are PffGridGetCellNumbering's global cell numbers;
   face rows are 3 * (global cell) + d for the lower d-face of the cell, so 3 face rows per owned cell
   (rows of wall and inactive-neighbour faces exist but are always closed). docs/pressure.md has more.

   The operator sits behind a small interface (apply, diagonal, face coefficients per level); the
   adaptive multigrid preconditioner pffmg (below) builds its hierarchy from the assembled A. The Krylov
   method applies either that A or a matrix-free MATSHELL of it (-pressure_operator aij|shell). */
#pragma once

#include <pff/grid.h>
#include <petscksp.h>

typedef struct _n_PffPressure *PffPressure;

#define PFF_PRESSURE_DELTA_G 0.75

/* Per-solve statistics. */
typedef struct {
  PetscInt           its;   /* Krylov iterations */
  PetscReal          rnorm; /* final residual norm (relative to the rhs norm) */
  KSPConvergedReason reason;
  PetscReal          divBefore; /* max |div u| (1/s) before the projection; -1 unless the divergence is monitored
                                   (PffPressureSetMonitorDivergence) */
  PetscReal divAfter;           /* max |div u| after it, of the double-precision u before it is stored in the
                                   float channel (PffPressureMaxDivergence of the channel adds float rounding,
                                   about 1e-7 |u| / h); -1 unless monitored */
  PetscLogDouble setupTime;     /* KSP/PC set-up inside Project (non-zero after SetCoefficients) */
  PetscLogDouble solveTime;     /* KSPSolve */
} PffPressureStats;

/* Life cycle. Create borrows grid (set up). SetFromOptions reads the KSP with options prefix
   "pressure_": -pressure_ksp_type (default fcg), -pressure_ksp_rtol (default 1e-4, on the true residual:
   the norm type defaults to unpreconditioned), -pressure_pc_type pffmg|gamg|hypre|bjacobi|jacobi (default pffmg;
   bjacobi uses ICC(0) on its blocks unless -pressure_sub_pc_type is given), -pressure_assembly
   ptap|direct (how A is assembled, default ptap), -pressure_dirichlet_walls none|<list of xmin,xmax,ymin,ymax,
   zmin,zmax> (PffPressureSetDirichletWalls; default none), -pressure_operator aij|shell (the operator the
   Krylov method applies, PffPressureSetOperatorType), -pressure_monitor_divergence (PffPressureSetMonitorDivergence),
   and every other PETSc KSP/PC option under that prefix. */
PETSC_EXTERN PetscErrorCode PffPressureCreate(PffGrid grid, PffPressure *ps);
PETSC_EXTERN PetscErrorCode PffPressureSetFromOptions(PffPressure ps);
/* The operator that the Krylov method applies (the KSP's Amat): the assembled MATMPIAIJ A, or the
   matrix-free MATSHELL of the same A (src/pressure/shell.c: one face loop, split-phase ghost exchange
   through a VecScatter built once). The preconditioner matrix (Pmat) is the assembled A in both cases,
   so every PETSc PC and pffmg keep working; A is assembled either way. */
typedef enum { PFF_PRESSURE_OPERATOR_AIJ, PFF_PRESSURE_OPERATOR_SHELL } PffPressureOperatorType;

/* -pressure_on_failure: what a solve that did not converge does to the run. */
typedef enum { PFF_PRESSURE_FAILURE_STOP, PFF_PRESSURE_FAILURE_WARN } PffPressureFailureType;
PETSC_EXTERN const char *const PffPressureFailureTypes[];

/* Acts on the outcome of a PffPressureProject() by -pressure_on_failure. A solve that converged passes.
   Otherwise "stop" (the default) raises PETSC_ERR_NOT_CONVERGED with one line naming the step, t, the
   stage, the KSP and PC, the converged reason, the iterations and the residual, and hint (the options
   to change); "warn" prints that line on rank 0 and goes on. A non-finite residual, KSP_DIVERGED_NANORINF
   or KSP_DIVERGED_PC_FAILED stops the run under either policy, since the fields are spoilt. Collective. */
PETSC_EXTERN PetscErrorCode    PffPressureCheckSolve(PffPressure ps, const PffPressureStats *st, const char stage[],
                                                     PetscInt step, PetscReal t, const char hint[]);
PETSC_EXTERN const char *const PffPressureOperatorTypes[];

/* The bytes the last solve's Krylov vectors and operator products must move, summed over ranks, with st its
   statistics; the preconditioner's share is pffmg's (PffPressureMGGetStats). A count of PETSc 3.18's KSPFCG, each
   operation streaming its vectors once (src/pressure/traffic.c); *known is false for other KSP types. Collective. */
PETSC_EXTERN PetscErrorCode PffPressureGetSolveTraffic(PffPressure ps, const PffPressureStats *st,
                                                       PetscLogDouble *bytes, PetscBool *known);

/* Sets the KSP's Amat type (default PFF_PRESSURE_OPERATOR_AIJ); option -pressure_operator aij|shell.
   Takes effect at the next SetCoefficients. Logically collective. */
PETSC_EXTERN PetscErrorCode PffPressureSetOperatorType(PffPressure ps, PffPressureOperatorType type);
PETSC_EXTERN PetscErrorCode PffPressureGetOperatorType(PffPressure ps, PffPressureOperatorType *type);
/* Whether PffPressureProject measures the largest |div u| before and after the projection (the stats' divBefore
   and divAfter, also printed by -info); option -pressure_monitor_divergence, default off: the two measures are two
   divergence passes with their ghost exchange, about 3 % of an rt3d step. Logically collective. */
PETSC_EXTERN PetscErrorCode PffPressureSetMonitorDivergence(PffPressure ps, PetscBool flg);

/* Builds the numbering, the face list and the gradient once per grid topology (and the shell's
   communication plan when the operator type is shell). Collective. */
PETSC_EXTERN PetscErrorCode PffPressureSetUp(PffPressure ps);
/* Frees everything derived from the grid's topology (numbering, face lists, operators, vectors, the
   preconditioner's set-up); the KSP keeps its type and options. The pressure calls it and sets itself
   up again when the grid's topology state (PffGridAdapt) differs from the one it was set up at; the
   coefficients must then be set again. Collective. */
PETSC_EXTERN PetscErrorCode PffPressureReset(PffPressure ps);
PETSC_EXTERN PetscErrorCode PffPressureDestroy(PffPressure *ps);

/* Dirichlet walls: walls[w] = PETSC_TRUE sets p = 0 on domain wall w, in the order -x, +x, -y, +y,
   -z, +z (option -pressure_dirichlet_walls). The value sits at the wall face, half a cell outside the
   centre of the boundary cell, so each boundary cell of size h gets the one-sided face weight
   c_D = A_f beta / d_f = h^2 beta / (h / 2) = 2 h beta on its diagonal. beta is the face channel value of
   the cell's own lower face along the wall's axis: the wall face itself at a -wall, the opposite face of
   the same cell at a +wall (which has no face storage). With any Dirichlet wall A is symmetric positive
   definite and has no null space (MatGetNullSpace(A) gives NULL); the rhs is not projected. The wall face
   stays closed in the face list: its u* does not enter the rhs and its velocity is not updated (a +wall
   face has no storage, a -wall face keeps u = 0), so the outflow 2 dt beta p / h through it is implied by
   p but not stored, and D u of the stored u is not zero in the boundary cells. Takes effect at the next
   SetCoefficients. Errors on a periodic axis. Logically collective (same values on every rank). */
PETSC_EXTERN PetscErrorCode PffPressureSetDirichletWalls(PffPressure ps, const PetscBool walls[6]);
/* The Dirichlet walls in the order of PffPressureSetDirichletWalls. Not collective. */
PETSC_EXTERN PetscErrorCode PffPressureGetDirichletWalls(PffPressure ps, PetscBool walls[6]);

/* Face coefficients from face channels: chBeta = 1/rho (Eq. 9), chOpen = 1 for a fluid face and 0
   for a face in or on a solid (domain walls and faces to inactive blocks are closed regardless;
   chOpen = -1 means every other face is open). beta must be positive and finite on open faces.
   Re-assembles the operator. Collective. */
PETSC_EXTERN PetscErrorCode PffPressureSetCoefficients(PffPressure ps, PetscInt chBeta, PetscInt chOpen);

/* Projection (Eq. 8): solves  dt A p = -V (D u* + c_div)  and sets u <- u* - dt beta G p on
   the open faces of face channel chU (closed faces are set to zero), p into cell channel chP.
   chCdiv (cell channel, or -1) holds the volume-correction term c_div in 1/s. Where no boundary is
   open the constant null space is removed. The previous p is the initial guess. Collective. */
/* Without Dirichlet walls (walls, solids and periodic axes only) the constants span the null space:
   attached to A, removed from the rhs (a mean of c_div is dropped), and p is defined up to a constant.
   With a Dirichlet wall A is definite, no null space is attached and the rhs is solved as it is. Non-convergence of any
   kind is reported in stats->reason and stats->rnorm, not raised: the caller passes them to
   PffPressureCheckSolve(), which knows the step. The caller exchanges the halos of chU and chP afterwards. */
PETSC_EXTERN PetscErrorCode PffPressureProject(PffPressure ps, PetscInt chU, PetscReal dt, PetscInt chCdiv,
                                               PetscInt chP, PffPressureStats *stats);
/* The same projection with u* = 0: u <- -dt beta G p with dt A p = -V c_div, the velocity that c_div alone asks for
   (the volume correction's displacement). chU's values are not read, so the caller need not zero them and no
   divergence of u* is taken. chCdiv must be a channel. Collective. */
PETSC_EXTERN PetscErrorCode PffPressureProjectSource(PffPressure ps, PetscInt chU, PetscReal dt, PetscInt chCdiv,
                                                     PetscInt chP, PffPressureStats *stats);

/* Max |D u| over owned cells of face channel chU (1/s), for checks and the step log. Collective. */
PETSC_EXTERN PetscErrorCode PffPressureMaxDivergence(PffPressure ps, PetscInt chU, PetscReal *maxdiv);

/* The operator interface for preconditioners (borrowed objects, valid until the next
   SetCoefficients): the assembled A (MATMPIAIJ, without the dt factor; assembled on the first call
   when nothing else needed it), its diagonal, and the face coefficients of the owned faces as three
   arrays of the owned cells, cf[d][c] for the lower d-face of local cell c (0 when closed). The coefficient is the
   stencil weight c_f = M_f beta_f open_f / d_f^2 = A_f beta_f open_f / d_f (h beta on a uniform grid),
   so that A = sum_f c_f (e_upper - sum w e_lower)(...)^T; the 1/d_f^2 makes it agree with A = G^T
   diag(M beta open) G, where G carries 1/d_f. (An earlier version of this comment said "/ d_f".)
   A and diag include the Dirichlet wall terms; the face coefficients do not (those faces have no row):
   GetDirichletDiagonal returns them as a cell Vec (sum of 2 h beta per cell, 0 away from Dirichlet
   walls), so A = sum_f c_f (...)(...)^T + diag(dirichlet). MatGetNullSpace(A) tells whether A is
   singular (constants, or the connected cells when solids isolate cells) or definite (NULL). */
PETSC_EXTERN PetscErrorCode PffPressureGetOperator(PffPressure ps, Mat *A);
PETSC_EXTERN PetscErrorCode PffPressureGetDiagonal(PffPressure ps, Vec *diag);
PETSC_EXTERN PetscErrorCode PffPressureGetFaceCoefficients(PffPressure ps, const PetscReal *cf[3]);
PETSC_EXTERN PetscErrorCode PffPressureGetDirichletDiagonal(PffPressure ps, Vec *dirdiag);
/* The matrix-free operator (MATSHELL: MatMult, MatMultTranspose, MatGetDiagonal, MatView) equal to the
   assembled A, including its diagonal-only terms (Dirichlet walls, the unit diagonal of cells with every
   face closed); borrowed, valid until PffPressureDestroy and kept current by SetCoefficients. Needs
   SetCoefficients first. */
PETSC_EXTERN PetscErrorCode PffPressureGetShellOperator(PffPressure ps, Mat *S);
PETSC_EXTERN PetscErrorCode PffPressureGetKSP(PffPressure ps, KSP *ksp);
/* For a KSP whose PC is block Jacobi (after PCSetUp, when the blocks exist): ICC(0) on every block, since the
   pressure systems are symmetric positive definite, unless -<prefix>sub_pc_type was given. Collective. */
PETSC_EXTERN PetscErrorCode PffKSPDefaultSubICC(KSP ksp, const char prefix[]);

/* The adaptive multigrid preconditioner of PF-FLIP Sec. 6, -pressure_pc_type pffmg (a PCSHELL inside
   the pressure KSP; docs/pressure.md). Options, prefix pressure_: -pffmg_smoother rbgs|jacobi (two-stage
   red-black hybrid Gauss-Seidel, default, or weighted Jacobi), -pffmg_adaptive (adaptive relaxation,
   Algorithm 2, default true), -pffmg_block_sweeps (repeat block-local sweeps until the update falls by 1/3,
   default true), -pffmg_block_sweeps_max (4), -pffmg_adaptive_steps (10), -pffmg_sweeps (fixed pre/post
   sweeps without adaptivity, 2), -pffmg_omega (6/7), -pffmg_theta_sigmas (2), -pffmg_max_levels, -pffmg_rescale (coarse
   coefficients consistent with the coarse discretisation, default true), -pffmg_kcycle (most flexible-CG steps per
   coarse correction, default 4; 0 = V-cycle), -pffmg_kcycle_rtol (a coarse correction stops when its residual has
   fallen by this factor, default 0.25; 0 = always -pffmg_kcycle steps), -pffmg_kcycle_ratio (a level gets the K-cycle
   only if the level above has at least this many times its rows, default 2.5; the others one cycle), -pffmg_correction
   (coarse-correction scale, 1),
   and the coarsest-level KSP under pressure_pffmg_coarse_ (default preonly + redundant LU). The functions below need
   pffmg as the PC and a KSPSetUp or solve before them. */
typedef struct {
  PetscInt   levels;           /* multigrid levels; the last is solved by the coarse KSP */
  PetscInt64 applications;     /* V-cycles (PC applications) on this rank */
  PetscInt64 blockRelaxations; /* block relaxations, summed over ranks by GetStats */
  PetscInt64 cellUpdates;      /* cell updates, summed over ranks by GetStats */
  PetscInt64 cellUpdatesMax;   /* the largest rank's cell updates (GetStats); max/mean is the smoothing imbalance */
  PetscInt64 cellVisits; /* cells brought in by block visits (a visit's repeated in-cache sweeps count once), summed */
  PetscLogDouble bytesTransfer; /* bytes of the cycles' transfers: x zeroed, residual and restriction, prolongation */
  PetscLogDouble bytesKCycle;   /* bytes of the K-cycles' Krylov vectors and level products (src/pressure/traffic.c) */
  PetscInt64     adaptiveSteps; /* steps of Algorithm 2 on this rank */
} PffMGStats;

/* The bytes a block visit moves per cell: b and x (read and written) in double, three float face coefficients,
   the float diagonal and its inverse. Smoothing moves cellVisits x this. */
#define PFF_MG_VISIT_BYTES 44.0

/* Statistics since the last reset (collective: sums over ranks). The byte counts are a model, not a measurement:
   each operation reads and writes its arrays once (src/pressure/traffic.c); a block visit moves PFF_MG_VISIT_BYTES
   per cell (cellVisits), the coarsest level's direct solve is not counted. */
PETSC_EXTERN PetscErrorCode PffPressureMGGetStats(PffPressure ps, PffMGStats *stats);
PETSC_EXTERN PetscErrorCode PffPressureMGResetStats(PffPressure ps);
/* Level L's Galerkin operator and the prolongation from level L+1 (NULL on the coarsest); borrowed. On a
   matrix-free level the operator is an AIJ copy assembled from the face coefficients at this call. */
PETSC_EXTERN PetscErrorCode PffPressureMGGetLevel(PffPressure ps, PetscInt L, Mat *A, Mat *P);
/* Applies level L's smoother to A_L x = b in place: sweeps > 0 fixed hybrid sweeps (or Jacobi), sweeps = 0
   the configured pre-smoother (adaptive when on). Collective. */
PETSC_EXTERN PetscErrorCode PffPressureMGSmooth(PffPressure ps, PetscInt L, Vec b, Vec x, PetscInt sweeps);
