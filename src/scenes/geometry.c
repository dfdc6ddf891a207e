/* Scene geometry: liquid regions and gas regions (initial condition) and solid obstacles (boundary),
   from options.

   A shape is a box [lo, hi], a sphere |x - c| <= r, or (liquid and gas only) a half-space
   (x - p) . n <= 0. Membership includes the boundary. The initial liquid is

     L = (union of the liquid regions) \ (union of the gas regions) \ (solids),

   so gas regions carve bubbles or cavities out of the liquid; everything outside L and the solids
   is gas. The solids enter the solver through their signed distance phi_s (negative inside), used
   to push particles out along grad phi_s after advection and to mark solid faces for the pressure
   solve:

     box:    q = |x - c| - s (c centre, s half sizes, per axis)
             phi = |max(q, 0)| + min(max_a q_a, 0)            (exact, inside and outside)
     sphere: phi = |x - c| - r                                 (exact)
     union:  phi = min_k phi_k                                 (exact outside the solids)

   The gradient is the unit vector from the nearest surface point (outside a box), the outward
   normal of the nearest face (inside a box), or the radial direction (sphere).

   For static refinement at the initial liquid surface the liquid set L gets the same CSG treatment,
   d_L = max(min_i d_liquid_i, -min_g d_gas_g), with box faces on the domain walls dropped (they
   touch the wall, not the gas). |d_L| is a lower bound of the distance to the surface and d_L is
   1-Lipschitz, so a box with centre c and half diagonal r is at least |d_L(c)| - r from it. */
#include "geometry.h"
#include <pff/shapes.h>

const char *const PffShapeTypes[] = {"box", "sphere", "halfspace", "PffShapeType", "PFF_SHAPE_", NULL};
/* solids are bounded: the same values without the half-space */
static const char *const PffSolidShapeTypes[] = {"box", "sphere", "PffShapeType", "PFF_SHAPE_", NULL};

typedef struct {
  PffShapeType type;
  PetscReal    a[3]; /* box lo, sphere centre, half-space point */
  PetscReal    b[3]; /* box hi, half-space unit normal */
  PetscReal    r;    /* sphere radius */
  PetscReal    v[3]; /* initial velocity (liquid) */
} PffShape;

struct _n_PffGeometry {
  MPI_Comm  comm;
  PetscInt  nliquid, ngas, nsolid;
  PffShape  liquid[PFF_GEOMETRY_MAX_REGIONS], gas[PFF_GEOMETRY_MAX_REGIONS], solid[PFF_GEOMETRY_MAX_REGIONS];
  PetscReal lo[3], hi[3];
};

/* Raw values of one region as read, validated after PetscOptionsEnd. Arrays hold more than 3 values
   so that a wrong count can be reported (PETSc drops values beyond the array size). */
#define PFF_GEOMETRY_MAX_VALUES 8
typedef struct {
  PetscInt  type;
  PetscReal a[PFF_GEOMETRY_MAX_VALUES], b[PFF_GEOMETRY_MAX_VALUES], v[PFF_GEOMETRY_MAX_VALUES], r;
  PetscInt  na, nb, nv;
  PetscBool seta, setb, setr, setv;
} PffShapeInput;

/* parameter names of each shape type: the two that define it */
static const char *const PffShapeKeyA[] = {"lo", "center", "point"};
static const char *const PffShapeKeyB[] = {"hi", "radius", "normal"};

PetscErrorCode PffGeometryCreate(MPI_Comm comm, PffGeometry *geo)
{
  PffGeometry g;

  PetscFunctionBeginUser;
  PetscCall(PetscNew(&g));
  PetscCall(PetscCommDuplicate(comm, &g->comm, NULL));
  *geo = g;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGeometryDestroy(PffGeometry *geo)
{
  PetscFunctionBeginUser;
  if (geo == NULL || *geo == NULL) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscCommDestroy(&(*geo)->comm));
  PetscCall(PetscFree(*geo));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscInt PffGeometryNumSolids(PffGeometry geo)
{
  return geo->nsolid;
}

PetscInt PffGeometryNumLiquids(PffGeometry geo)
{
  return geo->nliquid;
}

PetscInt PffGeometryNumGas(PffGeometry geo)
{
  return geo->ngas;
}

/* Reads the parameters of region i of kind "liquid", "gas" or "solid" whose type is already in in->type. */
static PetscErrorCode PffGeometryReadRegion(PetscOptionItems *PetscOptionsObject, const char *kind, PetscInt i,
                                            PetscBool liquid, PffShapeInput *in)
{
  char key[64], help[160];

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(key, sizeof(key), "-%s_%" PetscInt_FMT "_%s", kind, i, PffShapeKeyA[in->type]));
  PetscCall(PetscSNPrintf(help, sizeof(help), "%s %" PetscInt_FMT ": %s x,y,z", kind, i,
                          in->type == PFF_SHAPE_BOX      ? "lower corner"
                          : in->type == PFF_SHAPE_SPHERE ? "centre"
                                                         : "a point on the bounding plane"));
  in->na = PFF_GEOMETRY_MAX_VALUES;
  PetscCall(PffOptionsRealArray(key, help, "PffGeometrySetFromOptions", in->a, &in->na, &in->seta));
  PetscCall(PetscSNPrintf(key, sizeof(key), "-%s_%" PetscInt_FMT "_%s", kind, i, PffShapeKeyB[in->type]));
  if (in->type == PFF_SHAPE_SPHERE) {
    PetscCall(PetscSNPrintf(help, sizeof(help), "%s %" PetscInt_FMT ": radius", kind, i));
    PetscCall(PffOptionsReal(key, help, "PffGeometrySetFromOptions", in->r, &in->r, &in->setr));
  } else {
    PetscCall(
        PetscSNPrintf(help, sizeof(help), "%s %" PetscInt_FMT ": %s", kind, i,
                      in->type == PFF_SHAPE_BOX ? "upper corner x,y,z" : "normal x,y,z, pointing out of the region"));
    in->nb = PFF_GEOMETRY_MAX_VALUES;
    PetscCall(PffOptionsRealArray(key, help, "PffGeometrySetFromOptions", in->b, &in->nb, &in->setb));
  }
  if (liquid) {
    PetscCall(PetscSNPrintf(key, sizeof(key), "-%s_%" PetscInt_FMT "_velocity", kind, i));
    PetscCall(PetscSNPrintf(help, sizeof(help), "%s %" PetscInt_FMT ": initial velocity x,y,z", kind, i));
    in->nv = PFF_GEOMETRY_MAX_VALUES;
    PetscCall(PffOptionsRealArray(key, help, "PffGeometrySetFromOptions", in->v, &in->nv, &in->setv));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Checks that a vector option was given with 3 values. */
static PetscErrorCode PffGeometryCheckVector(MPI_Comm comm, const char *kind, PetscInt i, const char *name,
                                             PetscBool set, PetscInt n, PetscBool required, const char *type)
{
  PetscFunctionBeginUser;
  PetscCheck(set || !required, comm, PETSC_ERR_ARG_WRONG, "-%s_%" PetscInt_FMT "_%s is missing: a %s needs it", kind, i,
             name, type);
  PetscCheck(!set || n == 3, comm, PETSC_ERR_ARG_SIZ, "-%s_%" PetscInt_FMT "_%s takes 3 values, got %" PetscInt_FMT,
             kind, i, name, n);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Validates region i and stores it in *s. */
static PetscErrorCode PffGeometrySetRegion(PffGeometry g, const char *kind, PetscInt i, const PffShapeInput *in,
                                           PffShape *s)
{
  const char *type = PffShapeTypes[in->type];
  MPI_Comm    comm = g->comm;

  PetscFunctionBeginUser;
  PetscCall(PetscMemzero(s, sizeof(*s)));
  s->type = (PffShapeType)in->type;
  PetscCall(PffGeometryCheckVector(comm, kind, i, PffShapeKeyA[in->type], in->seta, in->na, PETSC_TRUE, type));
  for (int d = 0; d < 3; d++) s->a[d] = in->a[d];
  if (in->type == PFF_SHAPE_SPHERE) {
    PetscCheck(in->setr, comm, PETSC_ERR_ARG_WRONG, "-%s_%" PetscInt_FMT "_radius is missing: a sphere needs it", kind,
               i);
    PetscCheck(in->r > 0, comm, PETSC_ERR_ARG_OUTOFRANGE,
               "-%s_%" PetscInt_FMT "_radius %g is invalid: must be positive", kind, i, (double)in->r);
    s->r = in->r;
  } else {
    PetscCall(PffGeometryCheckVector(comm, kind, i, PffShapeKeyB[in->type], in->setb, in->nb, PETSC_TRUE, type));
    for (int d = 0; d < 3; d++) s->b[d] = in->b[d];
  }
  if (in->type == PFF_SHAPE_BOX) {
    for (int d = 0; d < 3; d++)
      PetscCheck(s->b[d] > s->a[d], comm, PETSC_ERR_ARG_OUTOFRANGE,
                 "-%s_%" PetscInt_FMT "_hi is invalid: hi must exceed lo on every axis, but on %c lo = %g, hi = %g",
                 kind, i, "xyz"[d], (double)s -> a[d], (double)s -> b[d]);
  }
  if (in->type == PFF_SHAPE_HALFSPACE) {
    const PetscReal len = PetscSqrtReal(PetscSqr(s->b[0]) + PetscSqr(s->b[1]) + PetscSqr(s->b[2]));
    PetscCheck(len > 0, comm, PETSC_ERR_ARG_OUTOFRANGE,
               "-%s_%" PetscInt_FMT "_normal is invalid: the normal must not be zero", kind, i);
    for (int d = 0; d < 3; d++) s->b[d] /= len;
  }
  PetscCall(PffGeometryCheckVector(comm, kind, i, "velocity", in->setv, in->nv, PETSC_FALSE, type));
  if (in->setv)
    for (int d = 0; d < 3; d++) s->v[d] = in->v[d];
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Regions 0..n-1 of kind were read and region n is absent: no region may follow the gap (checked up to
   the maximum, where the message says there are too many). */
static PetscErrorCode PffGeometryCheckNumbering(MPI_Comm comm, const char *kind, PetscInt n)
{
  PetscFunctionBeginUser;
  for (PetscInt j = n + 1; j <= PFF_GEOMETRY_MAX_REGIONS; j++) {
    char      key[64];
    PetscBool has;
    PetscCall(PetscSNPrintf(key, sizeof(key), "-%s_%" PetscInt_FMT "_type", kind, j));
    PetscCall(PetscOptionsHasName(NULL, NULL, key, &has));
    PetscCheck(!has || j < PFF_GEOMETRY_MAX_REGIONS, comm, PETSC_ERR_ARG_OUTOFRANGE,
               "%s is invalid: at most %d %s regions (numbered 0 to %d)", key, PFF_GEOMETRY_MAX_REGIONS, kind,
               PFF_GEOMETRY_MAX_REGIONS - 1);
    PetscCheck(!has, comm, PETSC_ERR_ARG_WRONG,
               "%s is given but -%s_%" PetscInt_FMT "_type is not: %s regions are numbered 0, 1, 2, ... without gaps",
               key, kind, n, kind);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGeometrySetFromOptions(PffGeometry geo, const PetscReal lo[3], const PetscReal hi[3])
{
  /* kinds in the order of -help: liquid regions, gas regions carved out of them, solids */
  enum { LIQUID, GAS, SOLID, NKINDS };
  const char *const kinds[NKINDS] = {"liquid", "gas", "solid"};
  const char *const helps[NKINDS] = {
      "Liquid region %" PetscInt_FMT ": box (lo, hi), sphere (center, radius) or halfspace (point, normal), with "
      "velocity; regions are numbered 0, 1, ... without gaps",
      "Gas region %" PetscInt_FMT ": box (lo, hi), sphere (center, radius) or halfspace (point, normal) carved out "
      "of the liquid regions (a bubble); numbered 0, 1, ... without gaps",
      "Solid obstacle %" PetscInt_FMT ": box (lo, hi) or sphere (center, radius) inside the domain; numbered 0, 1, "
      "... without gaps"};
  PffShapeInput *in;
  PetscInt       n[NKINDS] = {0, 0, 0};

  PetscFunctionBeginUser;
  PetscCall(PetscCalloc1(NKINDS * PFF_GEOMETRY_MAX_REGIONS, &in));
  PetscOptionsBegin(geo->comm, NULL, "Scene geometry: liquid regions, gas regions and solid obstacles", "PffGeometry");
  for (int k = 0; k < NKINDS; k++) {
    for (PetscInt i = 0; i < PFF_GEOMETRY_MAX_REGIONS; i++) {
      PffShapeInput *r = &in[k * PFF_GEOMETRY_MAX_REGIONS + i];
      char           key[64], help[256];
      PetscBool      set;
      PetscEnum      type = (PetscEnum)PFF_SHAPE_BOX;

      PetscCall(PetscSNPrintf(key, sizeof(key), "-%s_%" PetscInt_FMT "_type", kinds[k], i));
      PetscCall(PetscSNPrintf(help, sizeof(help), helps[k], i));
      PetscCall(PffOptionsEnum(key, help, "PffGeometrySetFromOptions", k == SOLID ? PffSolidShapeTypes : PffShapeTypes,
                               type, &type, &set));
      if (!set) break;
      r->type = (PetscInt)type;
      PetscCall(PffGeometryReadRegion(PetscOptionsObject, kinds[k], i, (PetscBool)(k == LIQUID), r));
      n[k]++;
    }
  }
  PetscOptionsEnd();

  for (int k = 0; k < NKINDS; k++) PetscCall(PffGeometryCheckNumbering(geo->comm, kinds[k], n[k]));
  for (int d = 0; d < 3; d++) {
    PetscCheck(hi[d] > lo[d], geo->comm, PETSC_ERR_ARG_OUTOFRANGE, "the domain is empty along %c: [%g, %g]", "xyz"[d],
               (double)lo[d], (double)hi[d]);
    geo->lo[d] = lo[d];
    geo->hi[d] = hi[d];
  }
  for (PetscInt i = 0; i < n[LIQUID]; i++)
    PetscCall(PffGeometrySetRegion(geo, "liquid", i, &in[LIQUID * PFF_GEOMETRY_MAX_REGIONS + i], &geo->liquid[i]));
  /* a gas region may reach beyond the domain: only the part inside removes liquid */
  for (PetscInt i = 0; i < n[GAS]; i++)
    PetscCall(PffGeometrySetRegion(geo, "gas", i, &in[GAS * PFF_GEOMETRY_MAX_REGIONS + i], &geo->gas[i]));
  for (PetscInt i = 0; i < n[SOLID]; i++) {
    PffShape *s = &geo->solid[i];
    PetscReal slo[3], shi[3], tol = 0;
    PetscCall(PffGeometrySetRegion(geo, "solid", i, &in[SOLID * PFF_GEOMETRY_MAX_REGIONS + i], s));
    for (int d = 0; d < 3; d++) {
      slo[d] = s->type == PFF_SHAPE_BOX ? s->a[d] : s->a[d] - s->r;
      shi[d] = s->type == PFF_SHAPE_BOX ? s->b[d] : s->a[d] + s->r;
      tol    = PetscMax(tol, 1e-12 * (hi[d] - lo[d]));
    }
    /* touching a wall is fine (a step on the floor); crossing it would cut the obstacle off */
    for (int d = 0; d < 3; d++)
      PetscCheck(slo[d] >= lo[d] - tol && shi[d] <= hi[d] + tol, geo->comm, PETSC_ERR_ARG_OUTOFRANGE,
                 "-solid_%" PetscInt_FMT ": the obstacle extends outside the domain [%g, %g] x [%g, %g] x [%g, %g] "
                 "(along %c it spans [%g, %g])",
                 i, (double)lo[0], (double)hi[0], (double)lo[1], (double)hi[1], (double)lo[2], (double)hi[2], "xyz"[d],
                 (double)slo[d], (double)shi[d]);
  }
  geo->nliquid = n[LIQUID];
  geo->ngas    = n[GAS];
  geo->nsolid  = n[SOLID];
  PetscCall(PetscFree(in));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static inline PetscBool PffShapeContains(const PffShape *s, const PetscReal x[3])
{
  switch (s->type) {
  case PFF_SHAPE_BOX:
    return (PetscBool)(x[0] >= s->a[0] && x[0] <= s->b[0] && x[1] >= s->a[1] && x[1] <= s->b[1] && x[2] >= s->a[2] &&
                       x[2] <= s->b[2]);
  case PFF_SHAPE_SPHERE:
    return (PetscBool)(PetscSqr(x[0] - s->a[0]) + PetscSqr(x[1] - s->a[1]) + PetscSqr(x[2] - s->a[2]) <= s->r * s->r);
  case PFF_SHAPE_HALFSPACE:
    return (PetscBool)((x[0] - s->a[0]) * s->b[0] + (x[1] - s->a[1]) * s->b[1] + (x[2] - s->a[2]) * s->b[2] <= 0);
  }
  return PETSC_FALSE;
}

/* Index of the first gas region containing x, or -1. */
static inline PetscInt PffGeometryGasAt(PffGeometry geo, const PetscReal x[3])
{
  for (PetscInt i = 0; i < geo->ngas; i++)
    if (PffShapeContains(&geo->gas[i], x)) return i;
  return -1;
}

PetscInt PffGeometryLiquidAt(PffGeometry geo, const PetscReal x[3], PetscReal v[3])
{
  if (v != NULL) v[0] = v[1] = v[2] = 0;
  if (PffGeometryGasAt(geo, x) >= 0) return -1;
  for (PetscInt i = 0; i < geo->nliquid; i++) {
    if (!PffShapeContains(&geo->liquid[i], x)) continue;
    if (v != NULL)
      for (int d = 0; d < 3; d++) v[d] = geo->liquid[i].v[d];
    return i;
  }
  return -1;
}

/* Exact signed distance of a box or a sphere, with its unit gradient. */
static PetscReal PffShapeDistance(const PffShape *s, const PetscReal x[3], PetscReal g[3])
{
  PetscReal e[3], half[3];

  for (int d = 0; d < 3; d++) {
    e[d]    = x[d] - (s->type == PFF_SHAPE_SPHERE ? s->a[d] : 0.5 * (s->a[d] + s->b[d]));
    half[d] = 0.5 * (s->b[d] - s->a[d]);
  }
  return s->type == PFF_SHAPE_SPHERE ? PffSphereDistance(e, s->r, g) : PffBoxDistance(e, half, g);
}

PetscReal PffGeometrySolidDistance(const PetscReal x[3], PetscReal grad[3], void *ctx)
{
  PffGeometry geo  = (PffGeometry)ctx;
  PetscReal   dist = PETSC_MAX_REAL, g[3] = {0, 0, 0};

  for (PetscInt k = 0; k < geo->nsolid; k++) {
    PetscReal       gk[3];
    const PetscReal dk = PffShapeDistance(&geo->solid[k], x, gk);
    if (dk < dist) {
      dist = dk;
      for (int d = 0; d < 3; d++) g[d] = gk[d];
    }
  }
  if (grad != NULL)
    for (int d = 0; d < 3; d++) grad[d] = g[d];
  return dist;
}

/* Exact signed distance of one liquid or gas shape (negative inside), where a box face on a domain
   wall or beyond it is no surface: the box continues through the wall. On an axis where both faces
   are such walls the box has no face at all. */
static PetscReal PffShapeSurfaceDistance(PffGeometry geo, const PffShape *s, const PetscReal x[3])
{
  switch (s->type) {
  case PFF_SHAPE_SPHERE:
    return PetscSqrtReal(PetscSqr(x[0] - s->a[0]) + PetscSqr(x[1] - s->a[1]) + PetscSqr(x[2] - s->a[2])) - s->r;
  case PFF_SHAPE_HALFSPACE:
    return (x[0] - s->a[0]) * s->b[0] + (x[1] - s->a[1]) * s->b[1] + (x[2] - s->a[2]) * s->b[2];
  case PFF_SHAPE_BOX:
    break;
  }
  PetscReal out = 0, in = -PETSC_MAX_REAL;
  for (int d = 0; d < 3; d++) {
    const PetscReal tol    = 1e-12 * (geo->hi[d] - geo->lo[d]);
    const PetscBool openlo = (PetscBool)(s->a[d] <= geo->lo[d] + tol),
                    openhi = (PetscBool)(s->b[d] >= geo->hi[d] - tol);
    if (openlo && openhi) continue;
    /* q > 0: outside the slab by q; q <= 0: |q| inside from its nearest (closed) face */
    const PetscReal q = openlo ? x[d] - s->b[d] : (openhi ? s->a[d] - x[d] : PetscMax(s->a[d] - x[d], x[d] - s->b[d]));
    if (q > 0) out += q * q;
    in = PetscMax(in, q);
  }
  return out > 0 ? PetscSqrtReal(out) : in;
}

PetscReal PffGeometryLiquidDistance(PffGeometry geo, const PetscReal x[3])
{
  PetscReal dl = PETSC_MAX_REAL, dg = PETSC_MAX_REAL;

  for (PetscInt i = 0; i < geo->nliquid; i++) dl = PetscMin(dl, PffShapeSurfaceDistance(geo, &geo->liquid[i], x));
  for (PetscInt g = 0; g < geo->ngas; g++) dg = PetscMin(dg, PffShapeSurfaceDistance(geo, &geo->gas[g], x));
  return PetscMax(dl, -dg);
}

/* Lower bound of the distance from a box with centre c and half diagonal r to the liquid surface
   (the signed distance bound is 1-Lipschitz). */
static inline PetscReal PffGeometryBallBound(PffGeometry geo, const PetscReal c[3], PetscReal r)
{
  return PetscMax(0.0, PetscAbsReal(PffGeometryLiquidDistance(geo, c)) - r);
}

PetscReal PffGeometryLiquidBoxDistance(PffGeometry geo, const PetscReal lo[3], const PetscReal hi[3], PetscReal cap)
{
  const PetscInt  S = PFF_GEOMETRY_BOX_SAMPLES;
  PetscReal       c[3], size[3], r = 0, dist;
  const PetscReal half = 0.5;

  for (int d = 0; d < 3; d++) {
    c[d] = half * (lo[d] + hi[d]);
    r += PetscSqr(half * (hi[d] - lo[d]));
  }
  dist = PffGeometryBallBound(geo, c, PetscSqrtReal(r));
  if (dist >= cap) return dist;
  r = 0;
  for (int d = 0; d < 3; d++) {
    size[d] = (hi[d] - lo[d]) / (PetscReal)S;
    r += PetscSqr(half * size[d]);
  }
  r    = PetscSqrtReal(r);
  dist = PETSC_MAX_REAL;
  for (PetscInt k = 0; k < S; k++)
    for (PetscInt j = 0; j < S; j++)
      for (PetscInt i = 0; i < S; i++) {
        const PetscReal x[3] = {lo[0] + ((PetscReal)i + half) * size[0], lo[1] + ((PetscReal)j + half) * size[1],
                                lo[2] + ((PetscReal)k + half) * size[2]};
        dist                 = PetscMin(dist, PffGeometryBallBound(geo, x, r));
        if (dist == 0) return 0;
      }
  return dist;
}

PetscErrorCode PffGeometryCheck(PffGeometry geo, PffGrid grid)
{
  const PetscInt nl = geo->nliquid, ng = geo->ngas, M = PFF_GEOMETRY_MAX_REGIONS;
  /* found[r]: liquid region r keeps a seed; found[nl + g]: gas region g removes one */
  PetscInt found[2 * PFF_GEOMETRY_MAX_REGIONS], nlocal;
  /* the overlapping pair (j, i), i < j, with the smallest j * M + i; M * M means none */
  PetscInt overlap = M * M;
  MPI_Comm comm;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetComm(grid, &comm));
  PetscCall(PffGridGetLocalBlocks(grid, &nlocal));
  for (PetscInt i = 0; i < nl + ng; i++) found[i] = 0;
  for (PetscInt lb = 0; lb < nlocal && nl > 0; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(grid, lb, &info));
    const PetscInt  ns = PFF_PARTICLES_PER_AXIS * info.n;
    const PetscReal hs = info.h / PFF_PARTICLES_PER_AXIS;
    for (PetscInt k = 0; k < ns; k++)
      for (PetscInt j = 0; j < ns; j++)
        for (PetscInt i = 0; i < ns; i++) {
          /* sub-cell points (c + 1/4) h and (c + 3/4) h: the particle lattice of PffParticlesSeed */
          const PetscReal x[3]   = {info.lo[0] + ((PetscReal)i + 0.5) * hs, info.lo[1] + ((PetscReal)j + 0.5) * hs,
                                    info.lo[2] + ((PetscReal)k + 0.5) * hs};
          const PetscBool gas    = (PetscBool)(PffGeometryGasAt(geo, x) >= 0);
          PetscInt        first  = -1;
          PetscBool       liquid = PETSC_FALSE;
          if (PffGeometrySolidDistance(x, NULL, geo) < 0) continue;
          for (PetscInt r = 0; r < nl; r++) {
            if (!PffShapeContains(&geo->liquid[r], x)) continue;
            liquid = PETSC_TRUE;
            if (gas) continue; /* carved out: neither seeded nor ambiguous */
            found[r] = 1;
            if (first < 0)
              first = r;
            else
              overlap = PetscMin(overlap, r * M + first);
          }
          if (liquid && gas)
            for (PetscInt g = 0; g < ng; g++)
              if (PffShapeContains(&geo->gas[g], x)) found[nl + g] = 1;
        }
  }
  PetscMPIInt mn;
  PetscCall(PetscMPIIntCast(nl + ng, &mn));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, found, mn, MPIU_INT, MPI_MAX, comm));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &overlap, 1, MPIU_INT, MPI_MIN, comm));
  for (PetscInt i = 0; i < nl; i++)
    PetscCheck(found[i], comm, PETSC_ERR_ARG_WRONG,
               "-liquid_%" PetscInt_FMT
               ": the region contains no particle seed position (empty, inside a solid or removed by gas regions)",
               i);
  for (PetscInt g = 0; g < ng; g++)
    PetscCheck(found[nl + g], comm, PETSC_ERR_ARG_WRONG,
               "-gas_%" PetscInt_FMT
               ": the region removes no liquid particle seed position (it lies outside the liquid regions, inside a "
               "solid, or between seeds)",
               g);
  if (overlap < M * M) {
    const PetscInt j = overlap / M, i = overlap % M;
    SETERRQ(comm, PETSC_ERR_ARG_INCOMP,
            "-liquid_%" PetscInt_FMT " (%s) overlaps -liquid_%" PetscInt_FMT
            " (%s); liquid regions must not overlap because their initial velocities would be ambiguous",
            j, PffShapeTypes[geo->liquid[j].type], i, PffShapeTypes[geo->liquid[i].type]);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffGeometryViewShape(PetscViewer viewer, const char *kind, PetscInt i, const PffShape *s,
                                           PetscBool liquid)
{
  char line[256] = "";

  PetscFunctionBeginUser;
  switch (s->type) {
  case PFF_SHAPE_BOX:
    PetscCall(PetscSNPrintf(line, sizeof(line), "box lo (%g, %g, %g) hi (%g, %g, %g)", (double)s->a[0], (double)s->a[1],
                            (double)s->a[2], (double)s->b[0], (double)s->b[1], (double)s->b[2]));
    break;
  case PFF_SHAPE_SPHERE:
    PetscCall(PetscSNPrintf(line, sizeof(line), "sphere center (%g, %g, %g) radius %g", (double)s->a[0],
                            (double)s->a[1], (double)s->a[2], (double)s->r));
    break;
  case PFF_SHAPE_HALFSPACE:
    PetscCall(PetscSNPrintf(line, sizeof(line), "halfspace point (%g, %g, %g) normal (%g, %g, %g)", (double)s->a[0],
                            (double)s->a[1], (double)s->a[2], (double)s->b[0], (double)s->b[1], (double)s->b[2]));
    break;
  }
  if (liquid)
    PetscCall(PetscViewerASCIIPrintf(viewer, "  %s_%" PetscInt_FMT ": %s velocity (%g, %g, %g)\n", kind, i, line,
                                     (double)s->v[0], (double)s->v[1], (double)s->v[2]));
  else
    PetscCall(PetscViewerASCIIPrintf(viewer, "  %s_%" PetscInt_FMT ": %s\n", kind, i, line));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGeometryView(PffGeometry geo, PetscViewer viewer)
{
  PetscFunctionBeginUser;
  if (viewer == NULL) viewer = PETSC_VIEWER_STDOUT_(geo->comm);
  PetscCall(PetscViewerASCIIPrintf(viewer,
                                   "Geometry: %" PetscInt_FMT " liquid region%s, %" PetscInt_FMT
                                   " gas region%s, %" PetscInt_FMT " solid%s\n",
                                   geo->nliquid, geo->nliquid == 1 ? "" : "s", geo->ngas, geo->ngas == 1 ? "" : "s",
                                   geo->nsolid, geo->nsolid == 1 ? "" : "s"));
  for (PetscInt i = 0; i < geo->nliquid; i++)
    PetscCall(PffGeometryViewShape(viewer, "liquid", i, &geo->liquid[i], PETSC_TRUE));
  for (PetscInt i = 0; i < geo->ngas; i++) PetscCall(PffGeometryViewShape(viewer, "gas", i, &geo->gas[i], PETSC_FALSE));
  for (PetscInt i = 0; i < geo->nsolid; i++)
    PetscCall(PffGeometryViewShape(viewer, "solid", i, &geo->solid[i], PETSC_FALSE));
  PetscFunctionReturn(PETSC_SUCCESS);
}
