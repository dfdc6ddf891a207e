/* Rigid bodies of the liquid model (include/pff/bodies.h, docs/tallcell.md "Rigid bodies"): options, poses and
   distances; Bullet (bullet.cpp) integrates them. */
#include <pff.h>
#include <pff/bodies.h>
#include <pff/shapes.h>
#include "bullet.h"

typedef enum { PFF_BODY_BOX, PFF_BODY_SPHERE } PffBodyType;
static const char *const PffBodyTypes[] = {"box", "sphere", "PffBodyType", "PFF_BODY_", NULL};

typedef struct {
  PffBodyType type;
  PetscReal   half[3]; /* a box's half extents; a sphere's radius in half[0] */
  PetscReal   inertia[3];
  PetscReal   x[3], q[4], R[3][3]; /* pose: centre, quaternion (w, x, y, z), rotation body -> world */
} PffBody;

struct _n_PffBodies {
  MPI_Comm        comm;
  PetscMPIInt     rank;
  PetscInt        n;
  PffBody         body[PFF_BODIES_MAX];
  PffTallBody     tall[PFF_BODIES_MAX];
  PffBulletWorld *world;
  PetscReal       g[3]; /* gravity */
  FILE           *csv;  /* rank 0: bodies.csv, open from the first row to PffBodiesDestroy */
};

static void Rotation(const PetscReal q[4], PetscReal R[3][3])
{
  const PetscReal w = q[0], x = q[1], y = q[2], z = q[3];
  R[0][0] = 1 - 2 * (y * y + z * z);
  R[0][1] = 2 * (x * y - w * z);
  R[0][2] = 2 * (x * z + w * y);
  R[1][0] = 2 * (x * y + w * z);
  R[1][1] = 1 - 2 * (x * x + z * z);
  R[1][2] = 2 * (y * z - w * x);
  R[2][0] = 2 * (x * z - w * y);
  R[2][1] = 2 * (y * z + w * x);
  R[2][2] = 1 - 2 * (x * x + y * y);
}

/* Signed distance to one body (negative inside) and its world gradient (grad may be NULL): the shape's distance
   in the body's frame, the gradient rotated back. */
static PetscReal BodyDistance(const PetscReal x[3], PetscReal grad[3], void *ctx)
{
  const PffBody *b = (const PffBody *)ctx;
  PetscReal      l[3], gl[3], d;

  for (PetscInt a = 0; a < 3; a++) /* local coordinates R^T (x - X) */
    l[a] = b->R[0][a] * (x[0] - b->x[0]) + b->R[1][a] * (x[1] - b->x[1]) + b->R[2][a] * (x[2] - b->x[2]);
  d = b->type == PFF_BODY_SPHERE ? PffSphereDistance(l, b->half[0], gl) : PffBoxDistance(l, b->half, gl);
  if (grad)
    for (PetscInt a = 0; a < 3; a++) grad[a] = b->R[a][0] * gl[0] + b->R[a][1] * gl[1] + b->R[a][2] * gl[2];
  return d;
}

PetscReal PffBodiesDistance(const PetscReal x[3], PetscReal grad[3], void *ctx)
{
  const PffBodies bs   = (const PffBodies)ctx;
  PetscReal       dmin = PETSC_MAX_REAL, g[3];

  if (grad) grad[0] = grad[1] = grad[2] = 0;
  for (PetscInt i = 0; i < bs->n; i++) {
    const PetscReal d = BodyDistance(x, g, (void *)&bs->body[i]);
    if (d < dmin) {
      dmin = d;
      if (grad)
        for (PetscInt a = 0; a < 3; a++) grad[a] = g[a];
    }
  }
  return dmin;
}

PetscBool PffBodiesContain(PffBodies bs, const PetscReal x[3])
{
  const PetscReal slack = 1e-9; /* the box's corners reach its bounding box to rounding */

  for (PetscInt i = 0; i < bs->n; i++) {
    const PffTallBody *t   = &bs->tall[i];
    PetscBool          out = PETSC_FALSE;
    for (PetscInt a = 0; a < 3; a++) out = (PetscBool)(out || x[a] < t->lo[a] - slack || x[a] > t->hi[a] + slack);
    if (!out && BodyDistance(x, NULL, (void *)&bs->body[i]) < 0) return PETSC_TRUE;
  }
  return PETSC_FALSE;
}

PetscBool PffBodiesVelocityAt(PffBodies bs, const PetscReal x[3], PetscReal vel[3])
{
  PetscReal dmin = 0;
  PetscInt  in   = -1;

  for (PetscInt i = 0; i < bs->n; i++) {
    const PetscReal d = BodyDistance(x, NULL, (void *)&bs->body[i]);
    if (d < dmin) {
      dmin = d;
      in   = i;
    }
  }
  if (in < 0) return PETSC_FALSE;
  {
    const PffTallBody *t    = &bs->tall[in];
    const PetscReal    r[3] = {x[0] - t->X[0], x[1] - t->X[1], x[2] - t->X[2]};
    vel[0]                  = t->w[0] + t->w[4] * r[2] - t->w[5] * r[1];
    vel[1]                  = t->w[1] + t->w[5] * r[0] - t->w[3] * r[2];
    vel[2]                  = t->w[2] + t->w[3] * r[1] - t->w[4] * r[0];
  }
  return PETSC_TRUE;
}

/* Reads body i; *found is false when -body_<i>_type is absent. */
static PetscErrorCode ReadBody(PetscOptionItems *PetscOptionsObject, PetscInt i, const PetscReal lo[3],
                               const PetscReal hi[3], PffBody *b, PetscReal *density, PetscReal v[3], PetscBool *found)
{
  char      key[64];
  PetscEnum type = (PetscEnum)PFF_BODY_BOX;
  PetscInt  n;
  PetscBool set;
  PetscReal ext[3] = {0, 0, 0};

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(key, sizeof(key), "-body_%" PetscInt_FMT "_type", i));
  PetscCall(
      PffOptionsEnum(key, "Rigid body: box or sphere", "PffBodiesCreateFromOptions", PffBodyTypes, type, &type, found));
  if (!*found) PetscFunctionReturn(PETSC_SUCCESS);
  b->type = (PffBodyType)type;
  PetscCall(PetscSNPrintf(key, sizeof(key), "-body_%" PetscInt_FMT "_center", i));
  n = 3;
  PetscCall(
      PffOptionsRealArray(key, "Rigid body: centre of mass x,y,z (m)", "PffBodiesCreateFromOptions", b->x, &n, &set));
  PetscCheck(set && n == 3, PETSC_COMM_WORLD, PETSC_ERR_USER_INPUT, "%s: give the body's centre as x,y,z", key);
  if (b->type == PFF_BODY_BOX) {
    PetscCall(PetscSNPrintf(key, sizeof(key), "-body_%" PetscInt_FMT "_size", i));
    n = 3;
    PetscCall(
        PffOptionsRealArray(key, "Rigid body: a box's extents x,y,z (m)", "PffBodiesCreateFromOptions", ext, &n, &set));
    PetscCheck(set && n == 3 && ext[0] > 0 && ext[1] > 0 && ext[2] > 0, PETSC_COMM_WORLD, PETSC_ERR_USER_INPUT,
               "%s: give the box's three extents, each > 0", key);
    for (PetscInt a = 0; a < 3; a++) b->half[a] = 0.5 * ext[a];
  } else {
    PetscReal r = 0;
    PetscCall(PetscSNPrintf(key, sizeof(key), "-body_%" PetscInt_FMT "_radius", i));
    PetscCall(PffOptionsReal(key, "Rigid body: a sphere's radius (m)", "PffBodiesCreateFromOptions", r, &r, &set));
    PetscCheck(set && r > 0, PETSC_COMM_WORLD, PETSC_ERR_USER_INPUT, "%s: give the sphere's radius, > 0", key);
    b->half[0] = b->half[1] = b->half[2] = r;
  }
  PetscCall(PetscSNPrintf(key, sizeof(key), "-body_%" PetscInt_FMT "_density", i));
  *density = 0;
  PetscCall(PffOptionsReal(key, "Rigid body: density (kg/m^3)", "PffBodiesCreateFromOptions", *density, density, &set));
  PetscCheck(set && *density > 0 && PetscIsNormalReal(*density), PETSC_COMM_WORLD, PETSC_ERR_USER_INPUT,
             "%s: give the body's density, > 0 (got %g)", key, (double)*density);
  PetscCall(PetscSNPrintf(key, sizeof(key), "-body_%" PetscInt_FMT "_velocity", i));
  n = 3;
  PetscCall(PffOptionsRealArray(key, "Rigid body: initial velocity (m/s)", "PffBodiesCreateFromOptions", v, &n, &set));
  PetscCheck(!set || n == 3, PETSC_COMM_WORLD, PETSC_ERR_USER_INPUT, "%s: give three components", key);
  for (PetscInt a = 0; a < 3; a++)
    PetscCheck(b->x[a] - b->half[a] >= lo[a] && b->x[a] + b->half[a] <= hi[a], PETSC_COMM_WORLD, PETSC_ERR_USER_INPUT,
               "-body_%" PetscInt_FMT "_center: the body [%g, %g] along %c lies outside the domain [%g, %g]", i,
               (double)(b->x[a] - b->half[a]), (double)(b->x[a] + b->half[a]), "xyz"[a], (double)lo[a], (double)hi[a]);
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffBodiesCreateFromOptions(MPI_Comm comm, const PetscReal lo[3], const PetscReal hi[3],
                                          const PetscReal g[3], PffBodies *bodies)
{
  PffBodies bs;
  PetscReal density[PFF_BODIES_MAX], v[PFF_BODIES_MAX][3];

  PetscFunctionBeginUser;
  *bodies = NULL;
  PetscCall(PetscNew(&bs));
  bs->comm = comm;
  PetscCallMPI(MPI_Comm_rank(comm, &bs->rank));
  PetscCall(PetscMemzero(v, sizeof(v)));
  PetscOptionsBegin(comm, NULL, "Rigid bodies of the liquid model", "PffBodies");
  for (PetscInt i = 0; i < PFF_BODIES_MAX; i++) {
    PetscBool found;
    PetscCall(ReadBody(PetscOptionsObject, i, lo, hi, &bs->body[i], &density[i], v[i], &found));
    if (!found) break;
    bs->n++;
  }
  PetscOptionsEnd();
  for (PetscInt j = bs->n + 1; j <= PFF_BODIES_MAX; j++) {
    char      key[64];
    PetscBool has;
    PetscCall(PetscSNPrintf(key, sizeof(key), "-body_%" PetscInt_FMT "_type", j));
    PetscCall(PetscOptionsHasName(NULL, NULL, key, &has));
    PetscCheck(!has, comm, PETSC_ERR_USER_INPUT,
               "%s: bodies are numbered from 0 without gaps (-body_%" PetscInt_FMT "_type is missing), at most %d", key,
               bs->n, PFF_BODIES_MAX);
  }
  if (!bs->n) {
    PetscCall(PetscFree(bs));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  {
    const double gd[3] = {g[0], g[1], g[2]}, lod[3] = {lo[0], lo[1], lo[2]}, hid[3] = {hi[0], hi[1], hi[2]};
    bs->world = PffBulletCreate(gd, lod, hid);
    PetscCheck(bs->world, comm, PETSC_ERR_MEM, "bodies: Bullet could not create its world");
    for (PetscInt a = 0; a < 3; a++) bs->g[a] = g[a];
  }
  for (PetscInt i = 0; i < bs->n; i++) {
    PffBody     *b       = &bs->body[i];
    const double size[3] = {b->half[0], b->half[1], b->half[2]}, x[3] = {b->x[0], b->x[1], b->x[2]};
    double       inertia[3], zero[3] = {0, 0, 0}, vi[3] = {v[i][0], v[i][1], v[i][2]};
    const double volume =
        b->type == PFF_BODY_BOX ? 8 * size[0] * size[1] * size[2] : 4.0 / 3.0 * PETSC_PI * size[0] * size[0] * size[0];
    PffTallBody *t = &bs->tall[i];
    t->mass        = density[i] * volume;
    PetscCheck(PffBulletAddBody(bs->world, b->type == PFF_BODY_BOX ? PFF_BULLET_BOX : PFF_BULLET_SPHERE, size, t->mass,
                                x, inertia) == i,
               comm, PETSC_ERR_PLIB, "bodies: Bullet numbered a body out of order");
    PffBulletSetVelocity(bs->world, (int)i, vi, zero);
    for (PetscInt a = 0; a < 3; a++) b->inertia[a] = inertia[a];
    b->q[0] = 1;
    Rotation(b->q, b->R);
    t->fn  = BodyDistance;
    t->ctx = b;
  }
  {
    PetscInt n;
    PetscCall(PffBodiesGetTall(bs, &n, NULL)); /* the bounding boxes of PffBodiesContain */
  }
  *bodies = bs;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffBodiesDestroy(PffBodies *bodies)
{
  PetscFunctionBeginUser;
  if (!bodies || !*bodies) PetscFunctionReturn(PETSC_SUCCESS);
  PffBulletDestroy((*bodies)->world);
  if ((*bodies)->csv)
    PetscCheck(fclose((*bodies)->csv) == 0, PETSC_COMM_SELF, PETSC_ERR_FILE_WRITE, "bodies: cannot close bodies.csv");
  PetscCall(PetscFree(*bodies));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffBodiesGetCount(PffBodies bs, PetscInt *n)
{
  PetscFunctionBeginUser;
  *n = bs ? bs->n : 0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffBodiesGetState(PffBodies bs, PetscInt i, PetscReal x[3], PetscReal q[4], PetscReal v[3],
                                 PetscReal omega[3])
{
  double xd[3], qd[4], vd[3], wd[3];

  PetscFunctionBeginUser;
  PetscCheck(i >= 0 && i < bs->n, bs->comm, PETSC_ERR_ARG_OUTOFRANGE, "bodies: no body %" PetscInt_FMT, i);
  PffBulletGetState(bs->world, (int)i, xd, qd, vd, wd);
  for (PetscInt a = 0; a < 3; a++) {
    if (x) x[a] = xd[a];
    if (v) v[a] = vd[a];
    if (omega) omega[a] = wd[a];
  }
  for (PetscInt a = 0; a < 4 && q; a++) q[a] = qd[a];
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffBodiesGetTall(PffBodies bs, PetscInt *n, PffTallBody **tall)
{
  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < bs->n; i++) {
    PffBody     *b = &bs->body[i];
    PffTallBody *t = &bs->tall[i];
    PetscReal    v[3], w[3];
    PetscCall(PffBodiesGetState(bs, i, b->x, b->q, v, w));
    Rotation(b->q, b->R);
    for (PetscInt a = 0; a < 3; a++) {
      PetscReal reach = 0; /* half-width of the world bounding box along a */
      for (PetscInt c = 0; c < 3; c++) reach += PetscAbsReal(b->R[a][c]) * b->half[c];
      if (b->type == PFF_BODY_SPHERE) reach = b->half[0];
      t->X[a]     = b->x[a];
      t->lo[a]    = b->x[a] - reach;
      t->hi[a]    = b->x[a] + reach;
      t->w[a]     = v[a];
      t->w[3 + a] = w[a];
    }
    for (PetscInt r = 0; r < 3; r++) /* I_world = R diag(I) R^T */
      for (PetscInt c = 0; c < 3; c++) {
        t->inertia[r][c] = 0;
        for (PetscInt k = 0; k < 3; k++) t->inertia[r][c] += b->R[r][k] * b->inertia[k] * b->R[c][k];
      }
  }
  *n = bs->n;
  if (tall) *tall = bs->tall;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffBodiesPredict(PffBodies bs, PetscReal dt, PetscInt *n, PffTallBody **tall)
{
  PetscFunctionBeginUser;
  PetscCall(PffBodiesGetTall(bs, n, tall));
  for (PetscInt i = 0; i < bs->n; i++)
    for (PetscInt a = 0; a < 3; a++) bs->tall[i].w[a] += dt * bs->g[a];
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Bullet's step adds g dt to the velocity before it moves the body (semi-implicit Euler), so it starts from w - g dt
   and moves the body with w (unless a contact changes it). */
PetscErrorCode PffBodiesAdvance(PffBodies bs, PetscReal dt)
{
  PetscInt n;

  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < bs->n; i++) {
    const PffTallBody *t    = &bs->tall[i];
    const double       v[3] = {t->w[0] - dt * bs->g[0], t->w[1] - dt * bs->g[1], t->w[2] - dt * bs->g[2]};
    const double       w[3] = {t->w[3], t->w[4], t->w[5]};
    PffBulletSetVelocity(bs->world, (int)i, v, w);
  }
  PffBulletStep(bs->world, dt);
  PetscCall(PffBodiesGetTall(bs, &n, NULL));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffBodiesGetCheckpointState(PffBodies bs, PetscInt *n, PetscReal s[])
{
  _Static_assert(PFF_BODY_CHECKPOINT_VALUES == PFF_BULLET_RAW, "the checkpoint holds Bullet's raw state");
  PetscFunctionBeginUser;
  *n = bs ? bs->n * PFF_BULLET_RAW : 0;
  if (!s) PetscFunctionReturn(PETSC_SUCCESS);
  for (PetscInt i = 0; i < bs->n; i++) {
    double raw[PFF_BULLET_RAW];
    PffBulletGetRaw(bs->world, (int)i, raw);
    for (PetscInt k = 0; k < PFF_BULLET_RAW; k++) s[i * PFF_BULLET_RAW + k] = raw[k];
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffBodiesSetCheckpointState(PffBodies bs, const PetscReal s[])
{
  PetscInt n;

  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < bs->n; i++) {
    double raw[PFF_BULLET_RAW];
    for (PetscInt k = 0; k < PFF_BULLET_RAW; k++) raw[k] = s[i * PFF_BULLET_RAW + k];
    PffBulletSetRaw(bs->world, (int)i, raw);
  }
  PetscCall(PffBodiesGetTall(bs, &n, NULL));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffBodiesWriteCSV(PffBodies bs, const char dir[], PetscInt step, PetscReal t)
{
  PetscFunctionBeginUser;
  if (bs->rank) PetscFunctionReturn(PETSC_SUCCESS);
  if (!bs->csv) {
    char path[PETSC_MAX_PATH_LEN];
    PetscCall(PetscSNPrintf(path, sizeof(path), "%s/bodies.csv", dir));
    bs->csv = fopen(path, "w");
    PetscCheck(bs->csv, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "bodies: cannot write %s", path);
    fprintf(bs->csv, "step,t,body,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz,fx,fy,fz,tx,ty,tz\n");
  }
  for (PetscInt i = 0; i < bs->n; i++) {
    PetscReal x[3], q[4], v[3], w[3];
    PetscCall(PffBodiesGetState(bs, i, x, q, v, w));
    fprintf(bs->csv, "%" PetscInt_FMT ",%.9e,%" PetscInt_FMT, step, (double)t, i);
    for (PetscInt a = 0; a < 3; a++) fprintf(bs->csv, ",%.9e", (double)x[a]);
    for (PetscInt a = 0; a < 4; a++) fprintf(bs->csv, ",%.9e", (double)q[a]);
    for (PetscInt a = 0; a < 3; a++) fprintf(bs->csv, ",%.9e", (double)v[a]);
    for (PetscInt a = 0; a < 3; a++) fprintf(bs->csv, ",%.9e", (double)w[a]);
    for (PetscInt a = 0; a < 6; a++) fprintf(bs->csv, ",%.9e", (double)bs->tall[i].force[a]);
    fprintf(bs->csv, "\n");
  }
  PetscCheck(fflush(bs->csv) == 0, PETSC_COMM_SELF, PETSC_ERR_FILE_WRITE, "bodies: cannot write bodies.csv");
  PetscFunctionReturn(PETSC_SUCCESS);
}
