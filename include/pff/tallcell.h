/* tallcell: the variational pressure projection on quadtree tall cells (Narita et al. 2025, "tall
   cells" Sec. 4.2-4.3) for a liquid with a free surface, on the MSBG.

   The grid is the quadtree: its level map must be constant along y in every block column (the x-z image
   of levels is the quadtree, graded 2:1 by the grid) and the grid must be partitioned by whole columns
   (-partition_type columns), so that every column of cells lies on one rank. A column of cells of size s
   is cut into liquid runs (level set phi < 0 at the cell centre; the input is a cell channel). Near each
   free-surface end of a run a band of cubic cells stays; the rest of the run merges into one tall cell.
   A cubic cell carries one pressure sample at its centre, a tall cell two (the centres of its lowest and
   highest sub-cells). Inside a run the pressure is the piecewise-linear function of y through the samples
   and p = 0 at the free surface (ghost fluid), extrapolated linearly at a wall.

   Gradient rows (the faces of [grad] in Eq. 1):
     vertical    between consecutive samples of a run (d = their distance, V = s^2 d; the y-faces between
                 them are averaged, Eq. 5), and from the last sample to the air cell across a free
                 surface (d = s, F = 1/theta);
     horizontal  per stored lower x- or z-face of a column's cells (same level: d = s; coarser lower
                 side: d = 1.5 s; finer lower side, two fine columns averaged: d = 0.75 s), the pressure
                 of each side evaluated at the face's mid height (Eq. 2-4). Consecutive faces whose cells
                 on both sides lie in the same tall cells merge into one row (Eq. 5). A face between a
                 liquid and an air cell gets F = 1/theta and p = 0 on the air side.
   With solids, every row carries [A], the mean open area fraction of its faces (rows of closed faces are
   dropped), and cells wholly inside a solid have no sample: a run of liquid ends there at a wall.
   The system [grad]^T V A F [grad] p = (rho/dt) [grad]^T V A u* (Eq. 1, static solids at rest) is
   symmetric positive definite and assembled as a MATMPIAIJ, solved by a PETSc KSP (prefix tall_,
   default CG with block Jacobi / ICC(0), rtol 1e-4). docs/tallcell.md has the derivation and choices. */
#pragma once

#include <pff/grid.h>
#include <pff/particles.h>
#include <petscksp.h>

typedef struct _n_PffTall *PffTall;

typedef struct {
  PetscInt64         cells;       /* pressure cells: cubic cells plus tall cells (each tall cell counts once) */
  PetscInt64         tallCells;   /* of which tall */
  PetscInt64         samples;     /* unknowns */
  PetscInt64         rows;        /* gradient rows */
  PetscInt64         liquidCells; /* liquid cells of the grid (the cubic cells a uniform discretisation would solve) */
  PetscInt           its;
  PetscReal          res0, res; /* absolute residual inf-norm at the initial guess and at the end (Table 2) */
  PetscReal          rnorm;     /* final residual 2-norm relative to the rhs */
  KSPConvergedReason reason;
  PetscLogDouble     assembleTime, solveTime;
} PffTallStats;

/* Life cycle. Create borrows grid (set up, columns partition, column-constant levels, y not periodic; Create
   refuses another grid with one error naming the missing property, and so does Build after an adapt).
   SetFromOptions reads -tall_merge (merge the deep part of runs into tall cells, default true; false gives
   cubic cells everywhere), -tall_layer_fraction (band of cubic cells under each free surface as a fraction
   of the run's height, default 0.25), -tall_layer_min (at least this many cells, default 2), -tall_theta_min
   (smallest liquid fraction of a free-surface gradient, default 0.01), and the KSP options under tall_. */
PETSC_EXTERN PetscErrorCode PffTallCreate(PffGrid grid, PffTall *tc);
PETSC_EXTERN PetscErrorCode PffTallSetFromOptions(PffTall tc);
PETSC_EXTERN PetscErrorCode PffTallDestroy(PffTall *tc);
/* Whether the deep part of each run merges into a tall cell (-tall_merge); takes effect at the next Build.
   Not collective, but every rank must pass the same value. */
PETSC_EXTERN PetscErrorCode PffTallSetMerge(PffTall tc, PetscBool merge);

/* The quadtree from the sizing function (tall cells Sec. 4.1): near the free surface (|phi| < 1.5 s) the wanted
   cell size is min(c_kappa / |kappa|, c_u / |grad u|) (curvature of phi, velocity gradient of face channel chU,
   or chU = -1 for none); every block column asks for the coarsest level whose cells are no larger, and level[]
   (the raster, nb[0] nb[1] nb[2], x fastest) receives it for all its blocks. Pass level[] to PffGridAdapt (or
   PffGridSetRefinementMap before set-up), whose 2:1 grading is the paper's smoothing of neighbour sizes.
   Options (SetFromOptions): -tall_sizing_curvature c_kappa (rad per cell, default 0.3), -tall_sizing_velocity
   c_u (m/s per cell, default 0.05), -tall_levels (levels used, default the grid's). Halos of chPhi and chU are
   exchanged here. Collective; every rank gets the same map. */
PETSC_EXTERN PetscErrorCode PffTallSizingLevels(PffTall tc, PetscInt chPhi, PetscInt chU, PetscInt level[]);
/* Whether a user of the module (the liquid flow model) should build the quadtree from the sizing function
   (-tall_sizing, default true; false keeps the grid's own map, e.g. -grid_refine ... -grid_refine_columns), and
   every how many steps it rebuilds it during the run (-tall_quadtree_interval, Algorithm 1 lines 2-5; default 0:
   only at t = 0; always 0 without the sizing function). Either may be NULL. */
PETSC_EXTERN PetscErrorCode PffTallGetSizing(PffTall tc, PetscBool *sizing, PetscInt *interval);

/* Solids (Sec. 4.3.2, [A] of Eq. 1). Face channel chA holds every face's open area fraction in [0, 1]; cell
   channel chSolid the solids' signed distance at the cell centre in cells, at most -1 for a cell wholly
   inside (it has no sample; a run of liquid ends there as at a wall). Both -1 for no solid (the default).
   A row's [A] is the mean fraction of its faces; a row of closed faces is dropped. Takes effect at the next
   Build. */
PETSC_EXTERN PetscErrorCode PffTallSetSolid(PffTall tc, PetscInt chA, PetscInt chSolid);
/* Fills chA and chSolid for PffTallSetSolid from the signed distance fn (negative inside the solids): a face's
   fraction from fn at its corners (exact for a planar boundary; lower domain walls 0), a cell's distance from
   fn at its centre in cells, set to at most -1 when all eight corners are inside and to at most
   PFF_TALL_SOLID_DISTANCE_MAX. blocks (NULL: all) marks the raster blocks to fill, the others keep their values:
   where the solids changed only within a region, filling the blocks within PFF_TALL_SOLID_DISTANCE_MAX + 1 cells
   of it before and after the change gives what a whole fill gives (the clipped distance is the same elsewhere).
   Exchanges both halos. Collective. */
#define PFF_TALL_SOLID_DISTANCE_MAX 2.0
PETSC_EXTERN PetscErrorCode PffTallFillSolid(PffGrid grid, PffSolidFn fn, void *ctx, PetscInt chA, PetscInt chSolid,
                                             const PetscBool blocks[]);
/* Open fraction of a square face from the signed distance at its corners phi[4], in cyclic order. */
PETSC_EXTERN PetscReal PffTallOpenFraction(const PetscReal phi[4]);

/* A rigid body coupled two-way through the pressure (Sec. 4.4, Eq. 6-14). The body must also be in the solid
   fractions (PffTallSetSolid): the open fractions exclude it. */
typedef struct {
  PffSolidFn fn;            /* signed distance to the body, negative inside, world frame */
  void      *ctx;           /* for fn */
  PetscReal  lo[3], hi[3];  /* world bounding box */
  PetscReal  X[3];          /* centre of mass */
  PetscReal  mass;          /* > 0 */
  PetscReal  inertia[3][3]; /* inertia tensor about X, world frame, symmetric positive definite */
  PetscReal  w[6];          /* in: (v, omega) before the projection, w*; out (Project): after, w* + dt M^-1 J p */
  PetscReal  force[6];      /* out (Project): the pressure's force and torque about X, J p (Eq. 6-7) */
} PffTallBody;

/* Couples the n bodies (borrowed; read at Build, w and force written by Project) two-way: the system becomes
   ([grad]^T V A F [grad] + rho J^T M^-1 J) p = (rho/dt)([grad]^T V A u* - J^T w*) (Eq. 14), solved with the
   KSP on a PETSc MATLRC operator preconditioned by the liquid part. n = 0 removes them. Takes effect at the next
   Build. */
PETSC_EXTERN PetscErrorCode PffTallSetBodies(PffTall tc, PetscInt n, PffTallBody bodies[]);

/* Builds the columns, samples, rows and the operator from the level set in cell channel chPhi (negative in
   liquid); the ghost columns of neighbouring ranks come through one PetscSF. Collective. */
PETSC_EXTERN PetscErrorCode PffTallBuild(PffTall tc, PetscInt chPhi);
/* Projection: solves the system with u* from face channel chU, sets u <- u* - dt/rho F grad p on every face
   that belongs to a row (the rows' faces get their row's gradient), and writes p at every cell centre into
   cell channel chP (the column's function; 0 in air). stats may be NULL. Collective. */
PETSC_EXTERN PetscErrorCode PffTallProject(PffTall tc, PetscInt chU, PetscReal dt, PetscReal rho, PetscInt chP,
                                           PffTallStats *stats);
/* Largest |[grad]^T V u_row| / (cell volume) over the samples for the velocity in chU (1/s): the variational
   divergence the projection removes. Collective. */
PETSC_EXTERN PetscErrorCode PffTallMaxDivergence(PffTall tc, PetscInt chU, PetscReal *maxdiv);
/* Largest |u_row| over the rows (the row averages of chU). Collective. */
PETSC_EXTERN PetscErrorCode PffTallMaxRowVelocity(PffTall tc, PetscInt chU, PetscReal *umax);
/* The liquid's momentum (x, y, z) in the projection's own measure: the sum over the rows of rho V A u_row / F, the
   weights of the kinetic energy the variational projection minimises (a free-surface row, F = 1 / theta, counts
   the liquid part theta of its control volume), which the projection changes only by the pressure's impulse on
   the walls and the bodies. Collective. */
PETSC_EXTERN PetscErrorCode PffTallLiquidMomentum(PffTall tc, PetscInt chU, PetscReal rho, PetscReal mom[3]);
/* The assembled operator [grad]^T V F [grad] (borrowed, valid until the next Build) and the solution of
   the last projection (samples, global numbering). */
PETSC_EXTERN PetscErrorCode PffTallGetOperator(PffTall tc, Mat *A);
PETSC_EXTERN PetscErrorCode PffTallGetSolution(PffTall tc, Vec *p);
PETSC_EXTERN PetscErrorCode PffTallGetKSP(PffTall tc, KSP *ksp);
/* Counts of the last Build (the solve fields of the stats are zero). Collective. */
PETSC_EXTERN PetscErrorCode PffTallGetCounts(PffTall tc, PffTallStats *stats);
/* Writes the pressure-cell height (in cells of the column's size: 1 cubic, m for a tall cell's sub-cells,
   0 in air) into cell channel ch, for frames. Not collective. */
PETSC_EXTERN PetscErrorCode PffTallWriteCellHeight(PffTall tc, PetscInt ch);
