/* Rayleigh–Taylor instability in 3D.
   rt3d: the set-up shared by eight published models (De Rosis & Enan, Phys. Fluids 33, 043315,
   2021): domain W x 4W x W, y along gravity, walls at y = 0 and 4W, periodic in x and z; heavy fluid
   (rho_h = rho_l (1 + A) / (1 - A)) above y = 2W + 0.05W [cos(2 pi x / W) + cos(2 pi z / W)];
   nu = W sqrt(g W) / Re in both fluids; time unit t0 = sqrt(W / g). The spike tip (lowest point of
   the heavy fluid, at x = z = W/2) is written as y/W against t/t0 for comparison with their Table IX.
   rt_paper: the PF-FLIP paper's configuration (Sec. 8.2): A = 0.9, 256 x 64 x 64 cells, W = 0.05 m,
   nu = 4e-5 m^2/s, g = 9.81, alpha_phi = 0.5, CFL 0.5. */
#include "flowscene.h"

typedef struct {
  PetscReal width, atwood, reynolds, gravity, amplitude, nu;
  PetscReal spike; /* y of the latest diagnostics row */
  PetscInt  resolution;
  PetscBool paper;
} PffRT;

static PetscErrorCode PffRTSetFromOptions(PffFlowScene *fs)
{
  PffRT *rt = (PffRT *)fs->ctx;
  char   buf[128];

  PetscFunctionBeginUser;
  PetscOptionsBegin(fs->scene->comm, NULL, "Rayleigh-Taylor scene", "PffScene");
  PetscCall(
      PffOptionsReal("-rt_width", "Domain width W (the domain is W x 4W x W)", NULL, rt->width, &rt->width, NULL));
  PetscCall(PffOptionsInt("-rt_resolution", "Cells across W", NULL, rt->resolution, &rt->resolution, NULL));
  PetscCall(PffOptionsReal("-rt_atwood", "Atwood number (rho_h - rho_l) / (rho_h + rho_l)", NULL, rt->atwood,
                           &rt->atwood, NULL));
  PetscCall(
      PffOptionsReal("-rt_gravity", "Gravitational acceleration g (along -y)", NULL, rt->gravity, &rt->gravity, NULL));
  PetscCall(PffOptionsReal("-rt_amplitude", "Interface perturbation amplitude, in units of W", NULL, rt->amplitude,
                           &rt->amplitude, NULL));
  if (!rt->paper)
    PetscCall(
        PffOptionsReal("-rt_reynolds", "Reynolds number W sqrt(g W) / nu", NULL, rt->reynolds, &rt->reynolds, NULL));
  PetscOptionsEnd();
  PetscCheck(rt->width > 0, fs->scene->comm, PETSC_ERR_ARG_OUTOFRANGE, "-rt_width %g is invalid: must be positive",
             (double)rt->width);
  PetscCheck(rt->resolution >= 4 && rt->resolution % 4 == 0 && rt->resolution <= 4096, fs->scene->comm,
             PETSC_ERR_ARG_OUTOFRANGE,
             "-rt_resolution %" PetscInt_FMT " is invalid: must be a multiple of 4 in [4, 4096]", rt->resolution);
  PetscCheck(rt->atwood > 0 && rt->atwood < 1, fs->scene->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-rt_atwood %g is invalid: must be in (0, 1)", (double)rt->atwood);
  PetscCheck(rt->gravity > 0, fs->scene->comm, PETSC_ERR_ARG_OUTOFRANGE, "-rt_gravity %g is invalid: must be positive",
             (double)rt->gravity);
  PetscCheck(rt->paper || rt->reynolds > 0, fs->scene->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-rt_reynolds %g is invalid: must be positive", (double)rt->reynolds);
  PetscCheck(rt->amplitude >= 0 && rt->amplitude < 0.5, fs->scene->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-rt_amplitude %g is invalid: must be in [0, 0.5)", (double)rt->amplitude);
  if (!rt->paper) rt->nu = rt->width * PetscSqrtReal(rt->gravity * rt->width) / rt->reynolds;
  const PetscInt N = rt->resolution, bs = N % 16 == 0 ? 16 : (N % 8 == 0 ? 8 : 4);
  PetscCall(PetscSNPrintf(buf, sizeof(buf), "%" PetscInt_FMT ",%" PetscInt_FMT ",%" PetscInt_FMT, N, 4 * N, N));
  PetscCall(PffFlowSceneDefault("-grid_cells", buf));
  PetscCall(PffFlowSceneDefaultReal("-grid_h", rt->width / (PetscReal)N));
  PetscCall(PffFlowSceneDefaultReal("-grid_block_size", (PetscReal)bs));
  PetscCall(PffFlowSceneDefault("-grid_periodic", "x,z"));
  PetscCall(PffFlowSceneDefaultReal("-rho_gas", 1.0));
  PetscCall(PffFlowSceneDefaultReal("-rho_liquid", (1 + rt->atwood) / (1 - rt->atwood)));
  PetscCall(PffFlowSceneDefaultReal("-nu_liquid", rt->nu));
  PetscCall(PffFlowSceneDefaultReal("-nu_gas", rt->nu));
  PetscCall(PetscSNPrintf(buf, sizeof(buf), "0,%.17g,0", -(double)rt->gravity));
  PetscCall(PffFlowSceneDefault("-gravity", buf));
  /* both fluids are conserved in a validation run: no bubble deletion (a water-air device) */
  PetscCall(PffFlowSceneDefault("-flow_delete_bubbles", "false"));
  if (rt->paper) {
    PetscCall(PffFlowSceneDefault("-flow_alpha_phi", "0.5"));
    PetscCall(PffFlowSceneDefault("-flow_cfl", "0.5"));
  }
  fs->timeUnit = PetscSqrtReal(rt->width / rt->gravity);
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffRTSeed(const PetscReal x[3], PetscInt *type, PetscReal v[3], void *ctx)
{
  const PffRT    *rt = (const PffRT *)ctx;
  const PetscReal W  = rt->width;
  const PetscReal y0 =
      2 * W + rt->amplitude * W * (PetscCosReal(2 * PETSC_PI * x[0] / W) + PetscCosReal(2 * PETSC_PI * x[2] / W));

  PetscFunctionBeginUser;
  *type = x[1] > y0 ? PFF_PARTICLE_LIQUID : PFF_PARTICLE_AIR;
  v[0] = v[1] = v[2] = 0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The spike tip: the lowest crossing of phi = 1/2 on the vertical line x = z = W/2, from phi sampled
   every half cell (each rank samples its own blocks; a max-reduction assembles the column). */
static PetscErrorCode PffRTSpike(PffFlowScene *fs, PetscReal *ytip)
{
  PffRT    *rt = (PffRT *)fs->ctx;
  PetscInt  phi, n0, nb[3];
  PetscReal h0, lo[3], hi[3], *col;

  PetscFunctionBeginUser;
  PetscCall(PffFlowGetChannels(fs->flow, &phi, NULL, NULL, NULL));
  PetscCall(PffGridGetSizes(fs->grid, &n0, NULL, NULL, &h0, NULL));
  PetscCall(PffGridGetRaster(fs->grid, nb, NULL, NULL));
  PetscCall(PffFlowSceneDomain(fs, lo, hi));
  const PetscInt ns = 2 * nb[1] * n0;
  PetscCall(PetscMalloc1(ns, &col));
  for (PetscInt k = 0; k < ns; k++) {
    const PetscReal x[3] = {lo[0] + 0.5 * rt->width, lo[1] + (k + 0.5) * 0.5 * h0, lo[2] + 0.5 * rt->width};
    PetscInt        gid, lb = -1;
    col[k] = -1;
    PetscCall(PffGridLocate(fs->grid, x, &gid, NULL, NULL));
    if (gid >= 0) PetscCall(PffGridGetLocalIndex(fs->grid, gid, &lb));
    if (lb >= 0) PetscCall(PffGridInterpolate(fs->grid, phi, 1, x, &col[k]));
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, col, (PetscMPIInt)ns, MPIU_REAL, MPI_MAX, fs->scene->comm));
  *ytip = hi[1];
  for (PetscInt k = 0; k < ns; k++) {
    if (col[k] < 0.5) continue;
    const PetscReal yk = lo[1] + (k + 0.5) * 0.5 * h0;
    if (k == 0)
      *ytip = yk;
    else
      *ytip = yk - 0.5 * h0 * (col[k] - 0.5) / (col[k] - col[k - 1]);
    break;
  }
  PetscCall(PetscFree(col));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffRTDiagnose(PffFlowScene *fs, PetscReal t, char row[], size_t len)
{
  PffRT    *rt = (PffRT *)fs->ctx;
  PetscReal y;

  PetscFunctionBeginUser;
  PetscCall(PffRTSpike(fs, &y));
  rt->spike = y;
  PetscCall(PetscSNPrintf(row, len, ",%.6f", (double)(y / rt->width)));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffRTFinish(PffFlowScene *fs)
{
  PffRT          *rt = (PffRT *)fs->ctx;
  const PetscReal y  = rt->spike; /* the final row's */
  PetscReal       t;

  PetscFunctionBeginUser;
  PetscCall(PffFlowGetTime(fs->flow, &t, NULL));
  PetscCall(PetscPrintf(fs->scene->comm, "%s: spike tip y/W %.4f at t/t0 %.4f (Atwood %g, nu %.4e)\n", fs->scene->name,
                        (double)(y / rt->width), (double)(t / fs->timeUnit), (double)rt->atwood, (double)rt->nu));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffSceneCreate_RTCommon(PffScene s, PetscBool paper)
{
  PffRT                *rt;
  const PffFlowSceneOps ops = {.setfromoptions = PffRTSetFromOptions,
                               .seed           = PffRTSeed,
                               .diagHeader     = ",spike_over_W",
                               .diagnose       = PffRTDiagnose,
                               .finish         = PffRTFinish};

  PetscFunctionBeginUser;
  PetscCall(PetscNew(&rt));
  rt->paper      = paper;
  rt->width      = paper ? 0.05 : 1.0;
  rt->atwood     = paper ? 0.9 : 0.5;
  rt->gravity    = paper ? 9.81 : 1.0;
  rt->reynolds   = 256;
  rt->nu         = 4e-5;
  rt->amplitude  = 0.05;
  rt->resolution = paper ? 64 : 32;
  PetscCall(PffFlowSceneCreate_Private(s, &ops, rt));
  ((PffFlowScene *)s->data)->tEnd = 3;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffSceneCreate_RT3D(PffScene s)
{
  PetscFunctionBeginUser;
  PetscCall(PffSceneCreate_RTCommon(s, PETSC_FALSE));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffSceneCreate_RTPaper(PffScene s)
{
  PetscFunctionBeginUser;
  PetscCall(PffSceneCreate_RTCommon(s, PETSC_TRUE));
  PetscFunctionReturn(PETSC_SUCCESS);
}
