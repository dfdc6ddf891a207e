/* bodies: rigid bodies that float in the liquid model, coupled two-way through the tall-cell pressure (Narita et
   al. 2025 Sec. 4.4; docs/tallcell.md, "Rigid bodies"). Bullet (libbullet-dev) holds their state and does gravity
   and the contacts between bodies and with the tank's walls; the liquid's pressure changes their velocity in the
   projection (Eq. 14). Every rank holds every body (they are few), and every rank's Bullet world takes the same
   inputs, so the states agree. Bodies are read from the options database:

     -body_<i>_type box|sphere      i = 0, 1, ... without gaps, at most PFF_BODIES_MAX
     -body_<i>_center x,y,z         centre of mass (m); the body must lie inside the domain
     -body_<i>_size sx,sy,sz        a box's full extents (m), > 0
     -body_<i>_radius r             a sphere's radius (m), > 0
     -body_<i>_density rho          kg/m^3, > 0
     -body_<i>_velocity vx,vy,vz    initial velocity (m/s), default 0

   In a YAML scene: body_0: {type: box, center: "0.5,0.6,0.5", size: "0.2,0.2,0.2", density: 500}. */
#pragma once

#include <pff/tallcell.h>

#define PFF_BODIES_MAX 16
#define PFF_BODY_CHECKPOINT_VALUES                                                                                     \
  18 /* per body in a checkpoint: origin, rotation matrix, velocity, angular velocity */

typedef struct _n_PffBodies *PffBodies;

/* Creates the bodies in the box [lo, hi] with gravity g from the options (Bullet's world and walls); *bodies is
   NULL when no -body_0_type is given. Bad input (a body outside the domain, a non-positive density or size, an
   unknown type, a gap in the numbering) fails with one error naming the key. Collective. */
PETSC_EXTERN PetscErrorCode PffBodiesCreateFromOptions(MPI_Comm comm, const PetscReal lo[3], const PetscReal hi[3],
                                                       const PetscReal g[3], PffBodies *bodies);
PETSC_EXTERN PetscErrorCode PffBodiesDestroy(PffBodies *bodies);
PETSC_EXTERN PetscErrorCode PffBodiesGetCount(PffBodies bodies, PetscInt *n);
/* Signed distance to the union of the bodies at their current poses (negative inside) and its gradient (grad
   may be NULL); a PffSolidFn with ctx the PffBodies. */
PETSC_EXTERN PetscReal PffBodiesDistance(const PetscReal x[3], PetscReal grad[3], void *ctx);
/* Whether x lies inside a body (PffBodiesDistance < 0), at the poses of the last PffBodiesGetTall; a point outside a
   body's bounding box is not evaluated. Not collective. */
PETSC_EXTERN PetscBool PffBodiesContain(PffBodies bodies, const PetscReal x[3]);
/* The velocity v + omega x (x - X) of the body whose inside holds x (the nearest, when bodies overlap), in vel;
   returns whether x lies inside a body (vel untouched otherwise). Not collective. */
PETSC_EXTERN PetscBool PffBodiesVelocityAt(PffBodies bodies, const PetscReal x[3], PetscReal vel[3]);
/* The tall-cell view of every body at its current state (pose, bounding box, mass, world inertia, velocity; the
   force and torque of the last projection) for PffTallSetBodies; tall may be NULL. Not collective (every rank holds the
   same). */
PETSC_EXTERN PetscErrorCode PffBodiesGetTall(PffBodies bodies, PetscInt *n, PffTallBody **tall);
/* Algorithm 1, line 7: the tall-cell view at the current poses with the velocity w* = w + g dt, for the projection
   of this step (Eq. 14 turns it into w). Not collective. */
PETSC_EXTERN PetscErrorCode PffBodiesPredict(PffBodies bodies, PetscReal dt, PetscInt *n, PffTallBody **tall);
/* Line 11 and the bodies' part of the advection: Bullet moves the bodies by dt with the velocities the projection
   left in the tall-cell view (contacts between bodies and with the walls included), as the liquid's particles move
   with the projected liquid velocity; the view then holds the new poses. Not collective. */
PETSC_EXTERN PetscErrorCode PffBodiesAdvance(PffBodies bodies, PetscReal dt);
/* Body i's centre of mass, quaternion (w, x, y, z), velocity and angular velocity. */
PETSC_EXTERN PetscErrorCode PffBodiesGetState(PffBodies bodies, PetscInt i, PetscReal x[3], PetscReal q[4],
                                              PetscReal v[3], PetscReal omega[3]);
/* The bodies' state for a checkpoint: *n values (0 without bodies; bodies may be NULL), into s unless it is NULL.
   Setting them back restores every body exactly as Bullet held it. Not collective. */
PETSC_EXTERN PetscErrorCode PffBodiesGetCheckpointState(PffBodies bodies, PetscInt *n, PetscReal s[]);
PETSC_EXTERN PetscErrorCode PffBodiesSetCheckpointState(PffBodies bodies, const PetscReal s[]);
/* Appends one line per body to <dir>/bodies.csv on rank 0 (created with its header at the first call, kept open
   until PffBodiesDestroy, flushed every call): step, t, body, x, y, z, q, v, omega, the pressure's last force and
   torque. Not collective. */
PETSC_EXTERN PetscErrorCode PffBodiesWriteCSV(PffBodies bodies, const char dir[], PetscInt step, PetscReal t);
