/* The C interface of the Bullet wrapper (bullet.cpp). Units: SI, world frame, quaternions (w, x, y, z). */
#pragma once

#ifdef __cplusplus
extern "C" {
#endif

typedef struct PffBulletWorld PffBulletWorld;

enum { PFF_BULLET_BOX = 0, PFF_BULLET_SPHERE = 1 };

/* A world with gravity and the six walls of the box [lo, hi]; NULL when out of memory. */
PffBulletWorld *PffBulletCreate(const double gravity[3], const double lo[3], const double hi[3]);
/* Adds a dynamic body: a box of half extents size[0..2] or a sphere of radius size[0], centred at x, at rest.
   Returns its index (0, 1, ...) and its principal moments of inertia (Bullet's, from the shape and mass). */
int PffBulletAddBody(PffBulletWorld *w, int type, const double size[3], double mass, const double x[3],
                     double inertia[3]);
/* Advances gravity, contacts and positions by dt. */
void PffBulletStep(PffBulletWorld *w, double dt);
void PffBulletGetState(const PffBulletWorld *w, int i, double x[3], double q[4], double v[3], double omega[3]);
void PffBulletSetVelocity(PffBulletWorld *w, int i, const double v[3], const double omega[3]);
/* Body i's state exactly as Bullet holds it (origin, basis row by row, velocity, angular velocity), for checkpoints:
   setting what get gave restores the body bit for bit. */
#define PFF_BULLET_RAW 18
void PffBulletGetRaw(const PffBulletWorld *w, int i, double s[PFF_BULLET_RAW]);
void PffBulletSetRaw(PffBulletWorld *w, int i, const double s[PFF_BULLET_RAW]);
void PffBulletDestroy(PffBulletWorld *w);

#ifdef __cplusplus
}
#endif
