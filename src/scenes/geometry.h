/* Scene geometry (private to src/scenes/): the initial liquid regions, the gas regions carved out of
   them and the solid obstacles of a scene, read from the options database, so that a scene is
   defined entirely in its YAML file:

     liquid_0: {type: box, lo: [0, 0, 0], hi: [0.4, 0.6, 1], velocity: [0, 0, 0]}
     gas_0:    {type: sphere, center: [0.2, 0.3, 0.5], radius: 0.05}
     solid_0:  {type: sphere, center: [0.7, 0.5, 0.2], radius: 0.1}

   PETSc's YAML reader turns each mapping into options -liquid_0_type box -liquid_0_lo 0,0,0 ...
   The keys are listed in docs/scenes.md. */
#pragma once

#include <pff.h>

typedef struct _n_PffGeometry *PffGeometry;

typedef enum { PFF_SHAPE_BOX, PFF_SHAPE_SPHERE, PFF_SHAPE_HALFSPACE } PffShapeType;
PETSC_INTERN const char *const PffShapeTypes[];

#define PFF_GEOMETRY_MAX_REGIONS 64 /* liquid regions, and separately gas regions and solids */

/* Creates an empty geometry (no liquid, no solid) on a duplicate of comm. Collective. */
PETSC_INTERN PetscErrorCode PffGeometryCreate(MPI_Comm comm, PffGeometry *geo);

/* Reads -liquid_<i>_*, -gas_<i>_* and -solid_<i>_* for i = 0, 1, ... until -liquid_<i>_type (resp.
   -gas_<i>_type, -solid_<i>_type) is absent; at most PFF_GEOMETRY_MAX_REGIONS each, numbered without
   gaps.
     liquid_<i>_type box|sphere|halfspace
       box: lo, hi (3 values each); sphere: center (3), radius; halfspace: point (3), normal (3), the
       liquid filling {x : (x - point) . normal <= 0}; velocity (3 values, default 0)
     gas_<i>_type box|sphere|halfspace, same parameters, no velocity: removed from the liquid regions
       (a bubble); it may reach beyond the domain
     solid_<i>_type box|sphere, same parameters, no velocity; must lie inside the domain [lo, hi]
   Only the keys of the given type are read, so a key of another type is reported as unused by the
   driver. Every error names its key. Collective; replaces what an earlier call read. */
PETSC_INTERN PetscErrorCode PffGeometrySetFromOptions(PffGeometry geo, const PetscReal lo[3], const PetscReal hi[3]);

/* NULL-safe; sets *geo = NULL. Collective. */
PETSC_INTERN PetscErrorCode PffGeometryDestroy(PffGeometry *geo);

/* Index of the first liquid region containing x (boundaries included), or -1 when none does or x
   lies in a gas region (boundaries included); v (may be NULL) receives its initial velocity, or
   zero. Solids are not considered. Not collective. */
PETSC_INTERN PetscInt PffGeometryLiquidAt(PffGeometry geo, const PetscReal x[3], PetscReal v[3]);

/* Signed distance to the union of the solids (negative inside) and its unit gradient, as a PffSolidFn
   with ctx = the PffGeometry. Exact for each box and sphere; for the union it is the minimum over the
   solids (exact outside the solids). Without solids: PETSC_MAX_REAL and a zero gradient. grad may be
   NULL. Not collective. */
PETSC_INTERN PetscReal PffGeometrySolidDistance(const PetscReal x[3], PetscReal grad[3], void *ctx);

/* Signed distance bound to the initial liquid surface (negative in the liquid): the CSG combination
   max(min_i d_liquid_i, -min_g d_gas_g) of the exact signed distances of the shapes, where the faces
   of a box that lie on a domain wall (or beyond) are no surface, so a liquid box against the walls
   has its free faces only. |value| never exceeds the distance to the surface (min/max of exact
   distances underestimate inside unions and outside intersections). Solids are not considered; with
   no surface at all (a box that fills the domain) the value is -PETSC_MAX_REAL. Not collective. */
PETSC_INTERN PetscReal PffGeometryLiquidDistance(PffGeometry geo, const PetscReal x[3]);

/* A lower bound of the distance from the box [lo, hi] to the initial liquid surface, 0 when the
   surface may cross the box: the minimum over PFF_GEOMETRY_BOX_SAMPLES^3 sub-boxes of
   max(0, |PffGeometryLiquidDistance(centre)| - half diagonal), tighter than the true distance by at
   most about one sub-box diagonal. A bound of the whole box at or beyond cap is returned without
   sub-boxes (cap = PETSC_MAX_REAL: always refine the bound). Deterministic. Not collective. */
#define PFF_GEOMETRY_BOX_SAMPLES 8
PETSC_INTERN PetscReal PffGeometryLiquidBoxDistance(PffGeometry geo, const PetscReal lo[3], const PetscReal hi[3],
                                                    PetscReal cap);

PETSC_INTERN PetscInt PffGeometryNumSolids(PffGeometry geo);
PETSC_INTERN PetscInt PffGeometryNumLiquids(PffGeometry geo);
PETSC_INTERN PetscInt PffGeometryNumGas(PffGeometry geo);

/* Discrete checks on the seeding lattice of a set-up grid: the 2 x 2 x 2 points (i + 1/4 | 3/4) h of
   every cell of every owned block, at the block's level, reduced over the grid's ranks.
     - every liquid region contains a seed point outside the solids and the gas regions (else it
       would get no particle);
     - every gas region contains a seed point outside the solids that lies in a liquid region (else
       it removes nothing and is probably misplaced);
     - no seed point outside the solids and the gas regions lies in two liquid regions (the initial
       velocity would be ambiguous).
   The error names the lowest offending region and is raised on every rank. Collective. */
PETSC_INTERN PetscErrorCode PffGeometryCheck(PffGeometry geo, PffGrid grid);

/* One line per region (type, parameters, velocity); viewer NULL means stdout of the geometry's
   communicator. Collective. */
PETSC_INTERN PetscErrorCode PffGeometryView(PffGeometry geo, PetscViewer viewer);
