/* Unit test of the scene geometry (src/scenes/geometry.c).

   Each case builds a geometry from an option string in a fresh options database, in the unit cube:
     - a box, a sphere and a half-space of liquid and a box and a sphere solid: PffGeometryLiquidAt
       (inside, on a boundary, outside, velocities) and PffGeometrySolidDistance (values and unit
       gradients at points with known answers, outside and inside each solid, and the gradient
       against central differences), then PffGeometryCheck on a 32^3 grid must pass;
     - gas regions (a sphere, a box and a half-space) carved out of a liquid box, and two liquid boxes
       whose overlap lies inside a gas box: LiquidAt inside, on the boundary of and outside each gas
       region, and PffGeometryCheck must pass (an overlap removed by gas is not ambiguous);
     - bad input: every error of PffGeometrySetFromOptions and PffGeometryCheck must be raised (on
       every rank, for Check) with a message naming the key, gas regions included (one that
       removes no liquid, one inside a solid, a liquid region that a gas region swallows); the message is caught by an
   error handler and compared.

   Sample run:  mpiexec -n 2 ./test_geometry
   Prints (the same on any number of ranks) the view of the good geometry and one line per case. */
#include "pfftest.h"
#include "geometry.h"

static const char help[] = "Scene geometry: liquid regions, solid distance, option errors.\n";

typedef struct {
  PetscErrorCode code;
  char           msg[1024];
} Caught;

/* Records the first message of an error and passes the code up without printing. */
static PetscErrorCode CatchError(MPI_Comm comm, int line, const char *fun, const char *file, PetscErrorCode n,
                                 PetscErrorType p, const char *mess, void *ctx)
{
  Caught *c = (Caught *)ctx;
  if (p == PETSC_ERROR_INITIAL) {
    c->code = n;
    if (mess != NULL) PetscStrncpy(c->msg, mess, sizeof(c->msg));
  }
  return n;
}

static const PetscReal dlo[3] = {0, 0, 0}, dhi[3] = {1, 1, 1};

/* Builds a geometry from opts in a fresh options database. *code receives the error (0 on success, the
   message in caught->msg); on error *geo is destroyed. With grid != NULL, PffGeometryCheck runs too. */
static PetscErrorCode Build(MPI_Comm comm, const char *opts, PffGrid grid, PffGeometry *geo, Caught *caught)
{
  PetscOptions db;

  PetscFunctionBeginUser;
  caught->code   = 0;
  caught->msg[0] = '\0';
  PetscCall(PetscOptionsCreate(&db));
  PetscCall(PetscOptionsPush(db));
  PetscCall(PetscOptionsInsertString(db, opts));
  PetscCall(PffGeometryCreate(comm, geo));
  PetscCall(PetscPushErrorHandler(CatchError, caught));
  PetscErrorCode ierr = PffGeometrySetFromOptions(*geo, dlo, dhi);
  if (!ierr && grid != NULL) ierr = PffGeometryCheck(*geo, grid);
  PetscCall(PetscPopErrorHandler());
  PetscCall(PetscOptionsPop());
  PetscCall(PetscOptionsDestroy(&db));
  PetscCheck(ierr == caught->code, PETSC_COMM_SELF, PETSC_ERR_PLIB, "error code %d but caught %d", (int)ierr,
             (int)caught->code);
  if (ierr) PetscCall(PffGeometryDestroy(geo));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* A bad-input case: the build must fail on this rank with a message containing expect. */
static PetscErrorCode ExpectError(MPI_Comm comm, const char *name, const char *opts, PffGrid grid, const char *expect)
{
  PffGeometry geo = NULL;
  Caught      c;
  char       *hit = NULL;

  PetscFunctionBeginUser;
  PetscCall(Build(comm, opts, grid, &geo, &c));
  PetscCheck(c.code != 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "case %s: no error for %s", name, opts);
  PetscCall(PetscStrstr(c.msg, expect, &hit));
  PetscCheck(hit != NULL, PETSC_COMM_SELF, PETSC_ERR_PLIB, "case %s: message \"%s\" lacks \"%s\"", name, c.msg, expect);
  PetscCheck(geo == NULL, PETSC_COMM_SELF, PETSC_ERR_PLIB, "case %s: geometry not destroyed", name);
  PetscCall(PetscPrintf(comm, "case %-22s error ok: %s\n", name, expect));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode ExpectLiquid(PffGeometry geo, PetscReal x, PetscReal y, PetscReal z, PetscInt want,
                                   const PetscReal vwant[3])
{
  const PetscReal p[3] = {x, y, z};
  PetscReal       v[3] = {-1, -1, -1};

  PetscFunctionBeginUser;
  const PetscInt got = PffGeometryLiquidAt(geo, p, v);
  PetscCheck(got == want, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "LiquidAt(%g, %g, %g) = %" PetscInt_FMT ", expected %" PetscInt_FMT, (double)x, (double)y, (double)z, got,
             want);
  for (int d = 0; d < 3; d++)
    PetscCheck(v[d] == vwant[d], PETSC_COMM_SELF, PETSC_ERR_PLIB, "LiquidAt(%g, %g, %g): v[%d] = %g, expected %g",
               (double)x, (double)y, (double)z, d, (double)v[d], (double)vwant[d]);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Distance and gradient at x against known values, and the gradient against central differences. */
static PetscErrorCode ExpectDistance(PffGeometry geo, PetscReal x, PetscReal y, PetscReal z, PetscReal dwant,
                                     PetscReal gx, PetscReal gy, PetscReal gz)
{
  const PetscReal p[3] = {x, y, z}, gwant[3] = {gx, gy, gz}, eps = 1e-6, tol = 1e-12;
  PetscReal       g[3];

  PetscFunctionBeginUser;
  const PetscReal dist = PffGeometrySolidDistance(p, g, geo);
  PetscCheck(PetscAbsReal(dist - dwant) < tol, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "SolidDistance(%g, %g, %g) = %.15g, expected %.15g", (double)x, (double)y, (double)z, (double)dist,
             (double)dwant);
  for (int d = 0; d < 3; d++) {
    PetscReal pp[3] = {x, y, z}, pm[3] = {x, y, z};
    pp[d] += eps;
    pm[d] -= eps;
    const PetscReal fd =
        (PffGeometrySolidDistance(pp, NULL, geo) - PffGeometrySolidDistance(pm, NULL, geo)) / (2 * eps);
    PetscCheck(PetscAbsReal(g[d] - gwant[d]) < tol, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "SolidDistance(%g, %g, %g): grad[%d] = %.15g, expected %.15g", (double)x, (double)y, (double)z, d,
               (double)g[d], (double)gwant[d]);
    PetscCheck(PetscAbsReal(fd - g[d]) < 1e-6, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "SolidDistance(%g, %g, %g): grad[%d] = %g but the central difference is %g", (double)x, (double)y,
               (double)z, d, (double)g[d], (double)fd);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Liquid: a box with a velocity, a sphere, the half-space z <= 0.2 (normal not normalised).
   Solids: a box standing in the half-space, a sphere between the half-space and the liquid sphere. */
static const char good[] = "-liquid_0_type box -liquid_0_lo 0,0,0.25 -liquid_0_hi 0.4,0.6,1 -liquid_0_velocity 1,2,3 "
                           "-liquid_1_type sphere -liquid_1_center 0.7,0.7,0.7 -liquid_1_radius 0.1 "
                           "-liquid_2_type halfspace -liquid_2_point 0,0,0.2 -liquid_2_normal 0,0,2 "
                           "-solid_0_type box -solid_0_lo 0.5,0.1,0.1 -solid_0_hi 0.9,0.3,0.3 "
                           "-solid_1_type sphere -solid_1_center 0.7,0.7,0.3 -solid_1_radius 0.1";

/* A liquid box with a velocity, carved by a gas sphere (a bubble), a gas box and the gas half-space
   y >= 0.9 (its normal points down, out of the region). */
static const char bubbles[] = "-liquid_0_type box -liquid_0_lo 0,0,0 -liquid_0_hi 1,1,1 -liquid_0_velocity 0,1,0 "
                              "-gas_0_type sphere -gas_0_center 0.5,0.5,0.5 -gas_0_radius 0.25 "
                              "-gas_1_type box -gas_1_lo 0.1,0.1,0.1 -gas_1_hi 0.2,0.2,0.2 "
                              "-gas_2_type halfspace -gas_2_point 0,0.9,0 -gas_2_normal 0,-3,0";

static PetscErrorCode TestGas(MPI_Comm comm, PffGrid grid)
{
  PffGeometry     geo;
  Caught          c;
  const PetscReal zero[3] = {0, 0, 0}, v0[3] = {0, 1, 0};

  PetscFunctionBeginUser;
  PetscCall(Build(comm, bubbles, grid, &geo, &c));
  PetscCheck(c.code == 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "gas geometry failed: %s", c.msg);
  PetscCall(PffGeometryView(geo, NULL));
  PetscCheck(PffGeometryNumLiquids(geo) == 1 && PffGeometryNumGas(geo) == 3 && PffGeometryNumSolids(geo) == 0,
             PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "%" PetscInt_FMT " liquids, %" PetscInt_FMT " gas regions and %" PetscInt_FMT
             " solids, expected 1, 3 and 0",
             PffGeometryNumLiquids(geo), PffGeometryNumGas(geo), PffGeometryNumSolids(geo));
  PetscCall(ExpectLiquid(geo, 0.5, 0.5, 0.5, -1, zero));  /* bubble centre */
  PetscCall(ExpectLiquid(geo, 0.5, 0.74, 0.5, -1, zero)); /* inside the bubble */
  /* on the bubble (radius and offset exact in binary, so this tests <= against <): boundaries belong to the gas */
  PetscCall(ExpectLiquid(geo, 0.5, 0.75, 0.5, -1, zero));
  PetscCall(ExpectLiquid(geo, 0.5, 0.76, 0.5, 0, v0)); /* just outside: the liquid's velocity */
  PetscCall(ExpectLiquid(geo, 0.15, 0.15, 0.15, -1, zero));
  PetscCall(ExpectLiquid(geo, 0.2, 0.2, 0.2, -1, zero)); /* gas box corner */
  PetscCall(ExpectLiquid(geo, 0.25, 0.15, 0.15, 0, v0));
  PetscCall(ExpectLiquid(geo, 0.5, 0.9, 0.5, -1, zero)); /* the half-space's plane */
  PetscCall(ExpectLiquid(geo, 0.5, 0.95, 0.5, -1, zero));
  PetscCall(ExpectLiquid(geo, 0.5, 0.85, 0.5, 0, v0));
  PetscCall(PffGeometryDestroy(&geo));
  PetscCall(PetscPrintf(comm, "case %-22s ok\n", "gas"));

  /* liquid boxes overlapping on [0.4, 0.6] x [0, 1] x [0, 1], which a gas box removes */
  PetscCall(Build(comm,
                  "-liquid_0_type box -liquid_0_lo 0,0,0 -liquid_0_hi 0.6,1,1 -liquid_0_velocity 1,0,0 "
                  "-liquid_1_type box -liquid_1_lo 0.4,0,0 -liquid_1_hi 1,1,1 -liquid_1_velocity -1,0,0 "
                  "-gas_0_type box -gas_0_lo 0.4,-1,-1 -gas_0_hi 0.6,2,2",
                  grid, &geo, &c));
  PetscCheck(c.code == 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "overlap inside gas failed: %s", c.msg);
  {
    const PetscReal vl[3] = {1, 0, 0}, vr[3] = {-1, 0, 0};
    PetscCall(ExpectLiquid(geo, 0.3, 0.5, 0.5, 0, vl));
    PetscCall(ExpectLiquid(geo, 0.5, 0.5, 0.5, -1, zero));
    PetscCall(ExpectLiquid(geo, 0.7, 0.5, 0.5, 1, vr));
  }
  PetscCall(PffGeometryDestroy(&geo));
  PetscCall(PetscPrintf(comm, "case %-22s ok\n", "gas_removes_overlap"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode TestGood(MPI_Comm comm, PffGrid grid)
{
  PffGeometry     geo;
  Caught          c;
  const PetscReal zero[3] = {0, 0, 0}, v0[3] = {1, 2, 3}, r2 = PetscSqrtReal(0.5);

  PetscFunctionBeginUser;
  PetscCall(Build(comm, good, grid, &geo, &c));
  PetscCheck(c.code == 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "good geometry failed: %s", c.msg);
  PetscCall(PffGeometryView(geo, NULL));
  PetscCheck(PffGeometryNumLiquids(geo) == 3 && PffGeometryNumSolids(geo) == 2, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "%" PetscInt_FMT " liquids and %" PetscInt_FMT " solids, expected 3 and 2", PffGeometryNumLiquids(geo),
             PffGeometryNumSolids(geo));

  PetscCall(ExpectLiquid(geo, 0.2, 0.3, 0.5, 0, v0));
  PetscCall(ExpectLiquid(geo, 0.4, 0.6, 1.0, 0, v0)); /* a corner: boundaries belong to the region */
  PetscCall(ExpectLiquid(geo, 0.7, 0.7, 0.75, 1, zero));
  PetscCall(ExpectLiquid(geo, 0.7, 0.75, 0.7, 1, zero));
  PetscCall(ExpectLiquid(geo, 0.9, 0.9, 0.1, 2, zero));
  PetscCall(ExpectLiquid(geo, 0.2, 0.3, 0.2, 2, zero)); /* the half-space's plane, below the box */
  PetscCall(ExpectLiquid(geo, 0.2, 0.3, 0.22, -1, zero));
  PetscCall(ExpectLiquid(geo, 0.9, 0.9, 0.5, -1, zero));

  /* box solid: centre (0.7, 0.2, 0.2), half sizes (0.2, 0.1, 0.1) */
  PetscCall(ExpectDistance(geo, 0.3, 0.2, 0.2, 0.2, -1, 0, 0));
  PetscCall(ExpectDistance(geo, 0.7, 0.2, 0.0, 0.1, 0, 0, -1));
  PetscCall(ExpectDistance(geo, 0.55, 0.2, 0.2, -0.05, -1, 0, 0));
  PetscCall(ExpectDistance(geo, 0.7, 0.25, 0.2, -0.05, 0, 1, 0));
  PetscCall(ExpectDistance(geo, 1.0, 0.4, 0.2, PetscSqrtReal(0.02), r2, r2, 0));
  PetscCall(ExpectDistance(geo, 0.3, 0.0, 0.5, 0.3, -2.0 / 3, -1.0 / 3, 2.0 / 3));
  /* sphere solid: centre (0.7, 0.7, 0.3), radius 0.1 */
  PetscCall(ExpectDistance(geo, 0.7, 0.95, 0.3, 0.15, 0, 1, 0));
  PetscCall(ExpectDistance(geo, 0.7, 0.7, 0.35, -0.05, 0, 0, 1));
  PetscCall(ExpectDistance(geo, 0.7 - 0.3, 0.7 + 0.4, 0.3, 0.4, -0.6, 0.8, 0));
  PetscCall(PffGeometryDestroy(&geo));
  PetscCheck(geo == NULL, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Destroy did not clear the handle");
  PetscCall(PffGeometryDestroy(&geo)); /* NULL-safe */
  PetscCall(PetscPrintf(comm, "case %-22s ok\n", "good"));

  /* no solids: far away everywhere, no gradient; touching liquid boxes do not overlap on the lattice */
  PetscCall(Build(comm,
                  "-liquid_0_type box -liquid_0_lo 0,0,0 -liquid_0_hi 0.5,0.5,0.5 "
                  "-liquid_1_type box -liquid_1_lo 0.5,0,0 -liquid_1_hi 1,0.5,0.5",
                  grid, &geo, &c));
  PetscCheck(c.code == 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "touching boxes failed: %s", c.msg);
  {
    const PetscReal x[3] = {0.5, 0.5, 0.5};
    PetscReal       g[3] = {1, 1, 1};
    const PetscReal d    = PffGeometrySolidDistance(x, g, geo);
    PetscCheck(d >= 1e30 && g[0] == 0 && g[1] == 0 && g[2] == 0, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "without solids the distance is %g, grad (%g, %g, %g)", (double)d, (double)g[0], (double)g[1],
               (double)g[2]);
    PetscCheck(PffGeometryNumSolids(geo) == 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "solids without -solid_0_type");
  }
  PetscCall(PffGeometryDestroy(&geo));
  PetscCall(PetscPrintf(comm, "case %-22s ok\n", "touching_no_solids"));

  /* nothing at all: an empty geometry is valid */
  PetscCall(Build(comm, "", grid, &geo, &c));
  PetscCheck(c.code == 0 && PffGeometryNumLiquids(geo) == 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "empty geometry: %s",
             c.msg);
  PetscCall(PffGeometryDestroy(&geo));
  PetscCall(PetscPrintf(comm, "case %-22s ok\n", "empty"));
  PetscFunctionReturn(PETSC_SUCCESS);
}

typedef struct {
  const char *name, *opts, *expect;
  PetscBool   check; /* the error comes from PffGeometryCheck on the grid */
} BadCase;

static const BadCase bad[] = {
    {"lo_two_values", "-liquid_0_type box -liquid_0_lo 0,0 -liquid_0_hi 1,1,1", "-liquid_0_lo takes 3 values, got 2",
     PETSC_FALSE},
    {"velocity_four_values", "-liquid_0_type box -liquid_0_lo 0,0,0 -liquid_0_hi 1,1,1 -liquid_0_velocity 1,2,3,4",
     "-liquid_0_velocity takes 3 values, got 4", PETSC_FALSE},
    {"box_hi_le_lo", "-liquid_0_type box -liquid_0_lo 0,0.5,0 -liquid_0_hi 1,0.5,1",
     "-liquid_0_hi is invalid: hi must exceed lo on every axis, but on y", PETSC_FALSE},
    {"radius_zero", "-solid_0_type sphere -solid_0_center 0.5,0.5,0.5 -solid_0_radius 0",
     "-solid_0_radius 0. is invalid: must be positive", PETSC_FALSE},
    {"radius_missing", "-liquid_0_type sphere -liquid_0_center 0.5,0.5,0.5", "-liquid_0_radius is missing",
     PETSC_FALSE},
    {"hi_missing", "-solid_0_type box -solid_0_lo 0.1,0.1,0.1", "-solid_0_hi is missing", PETSC_FALSE},
    {"normal_zero", "-liquid_0_type halfspace -liquid_0_point 0,0,0.5 -liquid_0_normal 0,0,0",
     "-liquid_0_normal is invalid: the normal must not be zero", PETSC_FALSE},
    {"gap",
     "-liquid_0_type box -liquid_0_lo 0,0,0 -liquid_0_hi 1,1,0.5 "
     "-liquid_2_type sphere -liquid_2_center 0.5,0.5,0.8 -liquid_2_radius 0.1",
     "-liquid_2_type is given but -liquid_1_type is not", PETSC_FALSE},
    {"solid_gap", "-solid_1_type sphere -solid_1_center 0.5,0.5,0.5 -solid_1_radius 0.1",
     "-solid_1_type is given but -solid_0_type is not", PETSC_FALSE},
    {"too_many", "-liquid_0_type box -liquid_0_lo 0,0,0 -liquid_0_hi 1,1,1 -liquid_64_type box",
     "-liquid_64_type is invalid: at most 64 liquid regions", PETSC_FALSE},
    {"solid_halfspace", "-solid_0_type halfspace -solid_0_point 0,0,0 -solid_0_normal 0,0,1", "-solid_0_type",
     PETSC_FALSE},
    {"solid_outside",
     "-solid_0_type box -solid_0_lo 0,0,0 -solid_0_hi 1,0.2,0.2 "
     "-solid_1_type sphere -solid_1_center 0.95,0.5,0.5 -solid_1_radius 0.1",
     "-solid_1: the obstacle extends outside the domain", PETSC_FALSE},
    {"liquid_tiny",
     "-liquid_0_type box -liquid_0_lo 0,0,0 -liquid_0_hi 1,1,0.3 "
     "-liquid_1_type sphere -liquid_1_center 0.5,0.5,0.5 -liquid_1_radius 0.001",
     "-liquid_1: the region contains no particle seed position (empty, inside a solid or removed by gas regions)",
     PETSC_TRUE},
    {"liquid_in_solid",
     "-liquid_0_type sphere -liquid_0_center 0.5,0.5,0.5 -liquid_0_radius 0.05 "
     "-solid_0_type sphere -solid_0_center 0.5,0.5,0.5 -solid_0_radius 0.2",
     "-liquid_0: the region contains no particle seed position", PETSC_TRUE},
    {"overlap",
     "-liquid_0_type box -liquid_0_lo 0,0,0 -liquid_0_hi 0.5,0.5,0.5 "
     "-liquid_1_type halfspace -liquid_1_point 0,0,0.9 -liquid_1_normal 0,0,-1 "
     "-liquid_2_type sphere -liquid_2_center 0.5,0.5,0.5 -liquid_2_radius 0.2",
     "-liquid_2 (sphere) overlaps -liquid_0 (box); liquid regions must not overlap", PETSC_TRUE},
    {"gas_radius_negative",
     "-liquid_0_type box -liquid_0_lo 0,0,0 -liquid_0_hi 1,1,1 "
     "-gas_0_type sphere -gas_0_center 0.5,0.5,0.5 -gas_0_radius -0.1",
     "-gas_0_radius -0.1 is invalid: must be positive", PETSC_FALSE},
    {"gas_center_two_values",
     "-liquid_0_type box -liquid_0_lo 0,0,0 -liquid_0_hi 1,1,1 -gas_0_type sphere -gas_0_center 0.5,0.5 "
     "-gas_0_radius 0.1",
     "-gas_0_center takes 3 values, got 2", PETSC_FALSE},
    {"gas_box_hi_le_lo",
     "-liquid_0_type box -liquid_0_lo 0,0,0 -liquid_0_hi 1,1,1 -gas_0_type box -gas_0_lo 0.5,0.5,0.5 "
     "-gas_0_hi 0.6,0.6,0.4",
     "-gas_0_hi is invalid: hi must exceed lo on every axis, but on z", PETSC_FALSE},
    {"gas_gap",
     "-liquid_0_type box -liquid_0_lo 0,0,0 -liquid_0_hi 1,1,1 "
     "-gas_1_type sphere -gas_1_center 0.5,0.5,0.5 -gas_1_radius 0.1",
     "-gas_1_type is given but -gas_0_type is not", PETSC_FALSE},
    {"gas_in_air",
     "-liquid_0_type box -liquid_0_lo 0,0,0 -liquid_0_hi 1,0.5,1 "
     "-gas_0_type sphere -gas_0_center 0.3,0.3,0.3 -gas_0_radius 0.1 "
     "-gas_1_type sphere -gas_1_center 0.5,0.8,0.5 -gas_1_radius 0.1",
     "-gas_1: the region removes no liquid particle seed position", PETSC_TRUE},
    {"gas_in_solid",
     "-liquid_0_type box -liquid_0_lo 0,0,0 -liquid_0_hi 1,1,1 "
     "-gas_0_type sphere -gas_0_center 0.5,0.5,0.5 -gas_0_radius 0.05 "
     "-solid_0_type sphere -solid_0_center 0.5,0.5,0.5 -solid_0_radius 0.2",
     "-gas_0: the region removes no liquid particle seed position", PETSC_TRUE},
    {"liquid_inside_gas",
     "-liquid_0_type box -liquid_0_lo 0,0,0 -liquid_0_hi 1,0.3,1 "
     "-liquid_1_type sphere -liquid_1_center 0.5,0.7,0.5 -liquid_1_radius 0.1 "
     "-gas_0_type box -gas_0_lo 0.3,0.5,0.3 -gas_0_hi 0.7,0.9,0.7",
     "-liquid_1: the region contains no particle seed position (empty, inside a solid or removed by gas regions)",
     PETSC_TRUE},
};

int main(int argc, char **argv)
{
  const PetscInt  nb[3]       = {4, 4, 4};
  const PetscBool periodic[3] = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};
  PffTestCtx      ctx;
  MPI_Comm        comm;

  PetscFunctionBeginUser;
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  comm = PETSC_COMM_WORLD;
  PetscCall(PffTestCreateGrid(comm, nb, periodic, dlo, 1.0 / 32, 8, 1, 0, 0, 1, &ctx));
  PetscCall(TestGood(comm, ctx.grid));
  PetscCall(TestGas(comm, ctx.grid));
  for (size_t i = 0; i < PETSC_STATIC_ARRAY_LENGTH(bad); i++)
    PetscCall(ExpectError(comm, bad[i].name, bad[i].opts, bad[i].check ? ctx.grid : NULL, bad[i].expect));
  PetscCall(PffGridDestroy(&ctx.grid));
  PetscCall(PetscPrintf(comm, "test_geometry: all cases passed\n"));
  PetscCall(PetscFinalize());
  return 0;
}
