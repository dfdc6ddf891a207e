/* grid_demo: the default scene until the fluid solver lands. It builds an adaptive MSBG from the
   -grid_* options, diffuses a Gaussian blob with explicit steps u += dt nu lap(u) (each step one
   halo exchange and one Laplacian), and writes HDF5 + XDMF frames. It exercises every grid stage
   that later scenes use, so -log_view shows their cost on the user's machine. */
#include "sceneimpl.h"

typedef struct {
  PetscInt  steps, every;
  PetscReal nu, sigma;
  PffGrid   grid;
  PetscInt  u, lap;
} PffGridDemo;

static PetscErrorCode PffGridDemoSetFromOptions(PffScene s)
{
  PffGridDemo *d = (PffGridDemo *)s->data;

  PetscFunctionBeginUser;
  PetscOptionsBegin(s->comm, NULL, "Grid demo scene", "PffScene");
  PetscCall(PffOptionsInt("-demo_steps", "Diffusion steps", NULL, d->steps, &d->steps, NULL));
  PetscCall(PffOptionsInt("-demo_output_every", "Write a frame every this many steps (0: first and last only)", NULL,
                          d->every, &d->every, NULL));
  PetscCall(PffOptionsReal("-demo_nu", "Diffusivity", NULL, d->nu, &d->nu, NULL));
  PetscCall(PffOptionsReal("-demo_sigma", "Width of the initial Gaussian, as a fraction of the x extent", NULL,
                           d->sigma, &d->sigma, NULL));
  PetscOptionsEnd();
  PetscCheck(d->steps >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-demo_steps %" PetscInt_FMT " is invalid: must be >= 0",
             d->steps);
  PetscCheck(d->every >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-demo_output_every %" PetscInt_FMT " is invalid: must be >= 0", d->every);
  PetscCheck(d->nu > 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-demo_nu %g is invalid: must be positive", (double)d->nu);
  PetscCheck(d->sigma > 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-demo_sigma %g is invalid: must be positive",
             (double)d->sigma);
  /* the grid is validated here, before the driver checks for unused options and before any output */
  PetscCall(PffGridCreate(s->comm, &d->grid));
  PetscCall(PffGridSetFromOptions(d->grid));
  PetscCall(PffGridAddChannel(d->grid, "u", PFF_CHANNEL_CELL, 1, &d->u));
  PetscCall(PffGridAddChannel(d->grid, "lap", PFF_CHANNEL_CELL, 1, &d->lap));
  PetscCall(PffGridSetUp(d->grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

typedef struct {
  PetscReal centre[3], sigma;
} PffGaussian;

static PetscReal PffGaussianValue(const PetscReal x[3], PetscInt comp, void *ctx)
{
  const PffGaussian *b  = (const PffGaussian *)ctx;
  PetscReal          r2 = 0;
  for (int a = 0; a < 3; a++) r2 += PetscSqr(x[a] - b->centre[a]);
  return PetscExpReal(-r2 / (2 * b->sigma * b->sigma));
}

static PetscErrorCode PffGridDemoWrite(PffScene s, PffGrid grid, PetscInt frame, PetscReal t, PetscInt step)
{
  char path[PETSC_MAX_PATH_LEN];

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(path, sizeof(path), "%s/frame_%04" PetscInt_FMT ".h5", s->outdir, frame));
  PetscCall(PffIOWriteFrame(grid, path, t, step, s->name));
  PetscCall(PetscPrintf(s->comm, "wrote %s\n", path));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Global max and integral of a cell channel (reductions, so independent of the rank count). */
static PetscErrorCode PffGridDemoStats(MPI_Comm comm, PffGrid grid, PetscInt ch, PetscReal *umax, PetscReal *integral)
{
  PetscInt  nlocal;
  PetscReal loc[2] = {0, 0}, glob[2];

  PetscFunctionBeginUser;
  PetscCall(PffGridGetLocalBlocks(grid, &nlocal));
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    float       *u;
    PetscReal    sum = 0;
    PetscCall(PffGridGetBlockInfo(grid, lb, &info));
    PetscCall(PffGridGetBlockData(grid, ch, lb, 0, &u));
    for (PetscInt c = 0; c < info.n * info.n * info.n; c++) {
      loc[0] = PetscMax(loc[0], (PetscReal)u[c]);
      sum += (PetscReal)u[c];
    }
    loc[1] += sum * info.h * info.h * info.h;
  }
  PetscCall(MPIU_Allreduce(&loc[0], &glob[0], 1, MPIU_REAL, MPIU_MAX, comm));
  PetscCall(MPIU_Allreduce(&loc[1], &glob[1], 1, MPIU_REAL, MPIU_SUM, comm));
  *umax     = glob[0];
  *integral = glob[1];
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffGridDemoRun(PffScene s)
{
  PffGridDemo   *d    = (PffGridDemo *)s->data;
  PffGrid        grid = d->grid;
  const PetscInt u = d->u, lap = d->lap;
  PetscInt       nlocal, n0, cellsx, frame = 0;
  PetscReal      h0, origin[3], t = 0;
  PetscLogStage  stInit, stHalo, stDiffuse, stOutput;
  PffProgress    prog;

  PetscFunctionBeginUser;
  PetscCall(PffSceneMakeOutputDir_Private(s));
  PetscCall(PetscLogStageRegister("Init", &stInit));
  PetscCall(PetscLogStageRegister("Halo", &stHalo));
  PetscCall(PetscLogStageRegister("Diffuse", &stDiffuse));
  PetscCall(PetscLogStageRegister("Output", &stOutput));

  PetscCall(PetscLogStagePush(stInit));
  PetscCall(PffGridView(grid, NULL));
  PetscCall(PffGridGetSizes(grid, &n0, NULL, origin, &h0, NULL));
  PetscCall(PffGridGetLocalBlocks(grid, &nlocal));
  {
    PetscInt nb[3];
    PetscCall(PffGridGetRaster(grid, nb, NULL, NULL));
    cellsx = nb[0] * n0;
  }
  const PetscReal len  = h0 * (PetscReal)cellsx;
  PffGaussian     blob = {{origin[0] + 0.5 * len, origin[1] + 0.5 * len, origin[2] + 0.5 * len}, d->sigma * len};
  PetscCall(PffGridFillChannel(grid, u, PffGaussianValue, &blob));
  PetscCall(PetscLogStagePop());

  /* explicit stability at the finest level: dt nu 12 / h0^2 <= 1 */
  const PetscReal dt = 0.9 * h0 * h0 / (12.0 * d->nu);
  PetscCall(PetscLogStagePush(stOutput));
  PetscCall(PffGridDemoWrite(s, grid, frame++, t, 0));
  PetscCall(PetscLogStagePop());
  PetscCall(PffProgressStart(&prog, t, 0, 0, d->steps));
  for (PetscInt step = 1; step <= d->steps; step++) {
    PetscReal umax = 0, integral = 0;
    char      extra[128];

    PetscCall(PetscLogStagePush(stHalo));
    PetscCall(PffGridHaloBegin(grid, u));
    PetscCall(PffGridHaloEnd(grid, u));
    PetscCall(PetscLogStagePop());
    PetscCall(PetscLogStagePush(stDiffuse));
    PetscCall(PffGridApplyLaplacian(grid, u, lap));
    for (PetscInt lb = 0; lb < nlocal; lb++) {
      PffBlockInfo info;
      float       *v, *l;
      PetscCall(PffGridGetBlockInfo(grid, lb, &info));
      PetscCall(PffGridGetBlockData(grid, u, lb, 0, &v));
      PetscCall(PffGridGetBlockData(grid, lap, lb, 0, &l));
      for (PetscInt c = 0; c < info.n * info.n * info.n; c++) v[c] += (float)(dt * d->nu) * l[c];
    }
    t += dt;
    PetscCall(PffGridDemoStats(s->comm, grid, u, &umax, &integral));
    PetscCall(PetscLogStagePop());
    PetscCall(PetscSNPrintf(extra, sizeof(extra), "max %.6e  integral %.6e", (double)umax, (double)integral));
    PetscCall(PffProgressPrint(s->comm, &prog, step, t, extra));
    if ((d->every > 0 && step % d->every == 0) || step == d->steps) {
      PetscCall(PetscLogStagePush(stOutput));
      PetscCall(PffGridDemoWrite(s, grid, frame++, t, step));
      PetscCall(PetscLogStagePop());
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffGridDemoDestroy(PffScene s)
{
  PetscFunctionBeginUser;
  PetscCall(PffGridDestroy(&((PffGridDemo *)s->data)->grid));
  PetscCall(PetscFree(s->data));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffSceneCreate_GridDemo(PffScene s)
{
  PffGridDemo *d;

  PetscFunctionBeginUser;
  PetscCall(PetscNew(&d));
  d->steps              = 20;
  d->every              = 10;
  d->nu                 = 1.0;
  d->sigma              = 0.1;
  s->data               = d;
  s->ops.setfromoptions = PffGridDemoSetFromOptions;
  s->ops.run            = PffGridDemoRun;
  s->ops.destroy        = PffGridDemoDestroy;
  PetscFunctionReturn(PETSC_SUCCESS);
}
