/* Exact signed distances of the primitive shapes, shared by the scene geometry (static solids), the rigid bodies
   (in their own frame) and the tests: negative inside, with the unit gradient. */
#pragma once

#include <petscsys.h>

/* A box of half extents half centred at the origin, at the point e (relative to the centre). Outside: towards
   the nearest surface point; inside or on the surface: the outward normal of the nearest face. g may be NULL. */
static inline PetscReal PffBoxDistance(const PetscReal e[3], const PetscReal half[3], PetscReal g[3])
{
  PetscReal q[3], out = 0, qmax = PETSC_MIN_REAL;
  int       amax = 0;

  for (int d = 0; d < 3; d++) {
    q[d] = PetscAbsReal(e[d]) - half[d];
    if (q[d] > 0) out += q[d] * q[d];
    if (q[d] > qmax) {
      qmax = q[d];
      amax = d;
    }
  }
  if (out > 0) {
    out = PetscSqrtReal(out);
    if (g)
      for (int d = 0; d < 3; d++) g[d] = q[d] > 0 ? (e[d] < 0 ? -1.0 : 1.0) * q[d] / out : 0.0;
    return out;
  }
  if (g)
    for (int d = 0; d < 3; d++) g[d] = d == amax ? (e[d] < 0 ? -1.0 : 1.0) : 0.0;
  return qmax;
}

/* A sphere of radius r centred at the origin, at the point e; at the centre any unit vector is the gradient. */
static inline PetscReal PffSphereDistance(const PetscReal e[3], PetscReal r, PetscReal g[3])
{
  const PetscReal len = PetscSqrtReal(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);

  if (g)
    for (int d = 0; d < 3; d++) g[d] = len > 0 ? e[d] / len : (d == 2 ? 1.0 : 0.0);
  return len - r;
}
