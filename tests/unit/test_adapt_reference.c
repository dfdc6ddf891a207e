/* The reference lattice after a topology change (docs/flow.md, "Adaptivity"): made again only on the blocks whose
   level changed and in slabs of their neighbours, it must equal the reference of a flow set up on the new map.

   A 32^3 box of 8^3 blocks on three levels: level 1 with a 2 x 2 x 2 cluster of level-0 blocks and a level-2
   corner. Map B moves the cluster by one block along x and the level-2 block to another corner, so that most blocks
   keep their level and some of them see a neighbour change. Two cases: a closed box with a solid sphere, and a box
   periodic along x and z. Per raster block, channel (mass_ref on the faces, volume_ref on the cells) and component the
   test sums the values with weights that differ from face to face, on the adapted flow and on a flow set up on map B,
   and requires them to agree to 1e-5 of the block's sum of |values| (the lattice is splatted in other batches, so
   rounding may differ). It also requires that some blocks which kept their level changed their reference: the slabs are
   what the test checks.

   Sample run:  mpiexec -n 4 ./test_adapt_reference
   Prints one line per case. */
#include "pfftest.h"

static const char help[] = "The reference lattice made again after an adapt equals a fresh one.\n";

#define NB 4
#define NBLOCKS (NB * NB * NB)
#define NSUM (NBLOCKS * 2 * 3 * 2) /* per block, channel, component: weighted sum and sum of |v| */

static PetscReal Sphere(const PetscReal x[3], PetscReal grad[3], void *ctx)
{
  const PetscReal c[3] = {0.3, 0.6, 0.5};
  PetscReal       r    = 0;

  (void)ctx;
  for (int a = 0; a < 3; a++) r += PetscSqr(x[a] - c[a]);
  r = PetscSqrtReal(r);
  for (int a = 0; a < 3 && grad; a++) grad[a] = r > 0 ? (x[a] - c[a]) / r : 0;
  return r - 0.15;
}

static void Maps(PetscInt a[], PetscInt b[])
{
  for (PetscInt k = 0; k < NB; k++)
    for (PetscInt j = 0; j < NB; j++)
      for (PetscInt i = 0; i < NB; i++) {
        const PetscInt  g  = i + NB * (j + NB * k);
        const PetscBool yz = (PetscBool)(j >= 1 && j <= 2 && k >= 1 && k <= 2);
        a[g]               = yz && i >= 1 && i <= 2 ? 0 : (i == 3 && j == 3 && k == 3 ? 2 : 1);
        b[g]               = yz && i >= 2 ? 0 : (i == 0 && j == 3 && k == 0 ? 2 : 1);
      }
}

static PetscErrorCode CreateFlow(MPI_Comm comm, const PetscInt map[], PetscBool periodic, PffGrid *grid, PffFlow *flow)
{
  const PetscInt  nb[3]     = {NB, NB, NB};
  const PetscBool per[3]    = {periodic, PETSC_FALSE, periodic};
  const PetscReal origin[3] = {0, 0, 0};
  PffTestCtx      tc;

  PetscFunctionBeginUser;
  PetscCall(PffTestCreateGridFromMap(comm, nb, per, origin, 1.0 / (8 * NB), 8, 3, map, &tc));
  *grid = tc.grid;
  PetscCall(PffFlowCreate(*grid, flow));
  PetscCall(PffFlowSetFromOptions(*flow));
  if (!periodic) PetscCall(PffFlowSetSolid(*flow, Sphere, NULL));
  PetscCall(PffFlowSetUp(*flow));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode FindChannel(PffGrid grid, const char name[], PetscInt *ch)
{
  PetscInt nch;

  PetscFunctionBeginUser;
  *ch = -1;
  PetscCall(PffGridGetNumChannels(grid, &nch));
  for (PetscInt c = 0; c < nch; c++) {
    const char *nm;
    PetscCall(PffGridGetChannelInfo(grid, c, &nm, NULL, NULL, NULL));
    if (!strcmp(nm, name)) *ch = c;
  }
  PetscCheck(*ch >= 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "no channel %s", name);
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* sums[((gid * 2 + channel) * 3 + component) * 2 + {0: weighted, 1: |v|}] over all ranks */
static PetscErrorCode Sums(MPI_Comm comm, PffGrid grid, PetscReal sums[])
{
  const char *names[2] = {"mass_ref", "volume_ref"};
  PetscInt    nlocal;

  PetscFunctionBeginUser;
  PetscCall(PetscArrayzero(sums, NSUM));
  PetscCall(PffGridGetLocalBlocks(grid, &nlocal));
  for (PetscInt m = 0; m < 2; m++) {
    PetscInt ch;
    PetscCall(FindChannel(grid, names[m], &ch));
    for (PetscInt lb = 0; lb < nlocal; lb++) {
      PffBlockInfo info;
      PetscCall(PffGridGetBlockInfo(grid, lb, &info));
      const PetscInt n3 = info.n * info.n * info.n;
      PffChannelKind kind;
      PetscCall(PffGridGetChannelInfo(grid, ch, NULL, &kind, NULL, NULL));
      for (PetscInt d = 0; d < (kind == PFF_CHANNEL_FACE ? 3 : 1); d++) {
        float     *v;
        PetscReal *s = &sums[((info.gid * 2 + m) * 3 + d) * 2];
        PetscCall(PffGridGetBlockData(grid, ch, lb, d, &v));
        for (PetscInt c = 0; c < n3; c++) {
          s[0] += (1 + (PetscReal)((c * 7919 + d * 131) % 1000) / 1000) * v[c];
          s[1] += PetscAbsReal(v[c]);
        }
      }
    }
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, sums, NSUM, MPIU_REAL, MPI_SUM, comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode Run(MPI_Comm comm, PetscBool periodic)
{
  PetscInt   mapA[NBLOCKS], mapB[NBLOCKS], kept = 0, keptChanged = 0, bad = 0;
  PffGrid    gridA, gridB;
  PffFlow    flowA, flowB;
  PetscReal *before, *after, *fresh;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc3(NSUM, &before, NSUM, &after, NSUM, &fresh));
  Maps(mapA, mapB);
  PetscCall(CreateFlow(comm, mapA, periodic, &gridA, &flowA));
  PetscCall(PffFlowReset(flowA)); /* the reference is made at the first step's topology check */
  PetscCall(Sums(comm, gridA, before));
  PetscCall(PffGridAdapt(gridA, mapB));
  PetscCall(PffFlowReset(flowA)); /* what the next step's topology check does */
  PetscCall(Sums(comm, gridA, after));
  PetscCall(CreateFlow(comm, mapB, periodic, &gridB, &flowB));
  PetscCall(PffFlowReset(flowB));
  PetscCall(Sums(comm, gridB, fresh));
  for (PetscInt g = 0; g < NBLOCKS; g++) {
    PetscBool moved = PETSC_FALSE;
    for (PetscInt e = 0; e < 6; e++) {
      const PetscReal *a = &after[(g * 6 + e) * 2], *f = &fresh[(g * 6 + e) * 2], *b = &before[(g * 6 + e) * 2];
      if (PetscAbsReal(a[0] - f[0]) > 1e-5 * (f[1] + 1e-30)) {
        if (bad < 5)
          PetscCall(PetscPrintf(comm,
                                "block %" PetscInt_FMT " channel %d component %d: %.9g after the adapt, %.9g fresh\n",
                                g, (int)(e / 3), (int)(e % 3), (double)a[0], (double)f[0]));
        bad++;
      }
      if (mapA[g] == mapB[g] && PetscAbsReal(b[0] - f[0]) > 1e-5 * (f[1] + 1e-30)) moved = PETSC_TRUE;
    }
    if (mapA[g] == mapB[g]) {
      kept++;
      keptChanged += moved;
    }
  }
  PetscCall(PetscPrintf(comm,
                        "%s: %" PetscInt_FMT " blocks kept their level, %" PetscInt_FMT
                        " of them with a new reference; %" PetscInt_FMT " sums differ from a fresh set-up\n",
                        periodic ? "periodic along x and z" : "closed box with a sphere", kept, keptChanged, bad));
  PetscCheck(bad == 0, comm, PETSC_ERR_PLIB, "the reference made again after the adapt differs from a fresh one");
  PetscCheck(keptChanged > 0, comm, PETSC_ERR_PLIB, "no block that kept its level has a new reference: nothing tested");
  PetscCall(PffFlowDestroy(&flowA));
  PetscCall(PffFlowDestroy(&flowB));
  PetscCall(PffGridDestroy(&gridA));
  PetscCall(PffGridDestroy(&gridB));
  PetscCall(PetscFree3(before, after, fresh));
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  PetscFunctionBeginUser;
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(Run(PETSC_COMM_WORLD, PETSC_FALSE));
  PetscCall(Run(PETSC_COMM_WORLD, PETSC_TRUE));
  PetscCall(PetscFinalize());
  return 0;
}
