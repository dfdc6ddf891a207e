/* Unit test of the 2:1 grading of a block raster: PffGradeLevels and PffRasterNeighbour.

   On 50 pseudo-random rasters (1..7 blocks per axis, random periodic axes, levels 0..5, some maps with
   inactive blocks) it checks after PffGradeLevels that
     - active 26-neighbours differ by at most one level,
     - no level went up (coarser), inactive blocks stayed inactive and no active block became inactive,
     - grading again changes nothing (idempotence),
     - every lowered block has a neighbour exactly one level finer (it was lowered for a reason),
     - the result equals the coarsest graded map below the request, computed here independently
       by relaxing L[b] = min(L[b], L[nbr] + 1) over active neighbours until nothing changes.
   It also checks PffRasterNeighbour (walls give -1, periodic axes wrap, stepping back returns to the
   block) and two hand-computed one-dimensional maps.

   Sample run:  ./test_grade
   Prints:      grade ok: <n> rasters, <b> blocks, <l> lowered */
#include "pfftest.h"

static const char help[] = "2:1 grading of random block rasters.\n";

/* Uniform integer in [0, m) from the key (seed, purpose, index). */
static PetscInt Draw(uint64_t seed, uint64_t purpose, uint64_t index, PetscInt m)
{
  return (PetscInt)(PffTestHash64(PffTestHash64(seed * 1000003ULL + purpose) ^ index) % (uint64_t)m);
}

static void BlockIJK(const PetscInt nb[3], PetscInt b, PetscInt ijk[3])
{
  ijk[0] = b % nb[0];
  ijk[1] = (b / nb[0]) % nb[1];
  ijk[2] = b / (nb[0] * nb[1]);
}

static PetscErrorCode CheckNeighbours(const PetscInt nb[3], const PetscBool periodic[3])
{
  const PetscInt nblocks = nb[0] * nb[1] * nb[2];

  PetscFunctionBeginUser;
  for (PetscInt b = 0; b < nblocks; b++) {
    PetscInt ijk[3];
    BlockIJK(nb, b, ijk);
    for (PetscInt r = 0; r < 27; r++) {
      const PetscInt d[3] = {r % 3 - 1, (r / 3) % 3 - 1, r / 9 - 1}, back[3] = {-d[0], -d[1], -d[2]};
      const PetscInt nbr  = PffRasterNeighbour(nb, periodic, ijk, d);
      PetscBool      wall = PETSC_FALSE;
      PetscInt       expect[3];
      for (int a = 0; a < 3; a++) {
        expect[a] = ijk[a] + d[a];
        if (expect[a] < 0 || expect[a] >= nb[a]) {
          if (!periodic[a]) wall = PETSC_TRUE;
          expect[a] = (expect[a] + nb[a]) % nb[a];
        }
      }
      if (wall) {
        PetscCheck(nbr == -1, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                   "neighbour of block %" PetscInt_FMT " in direction %" PetscInt_FMT " is %" PetscInt_FMT
                   " across a wall, expected -1",
                   b, r, nbr);
        continue;
      }
      PetscCheck(nbr == expect[0] + nb[0] * (expect[1] + nb[1] * expect[2]), PETSC_COMM_SELF, PETSC_ERR_PLIB,
                 "neighbour of block %" PetscInt_FMT " in direction %" PetscInt_FMT " is %" PetscInt_FMT, b, r, nbr);
      PetscInt nijk[3];
      BlockIJK(nb, nbr, nijk);
      PetscCheck(PffRasterNeighbour(nb, periodic, nijk, back) == b, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                 "stepping from block %" PetscInt_FMT " in direction %" PetscInt_FMT " and back does not return", b, r);
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The coarsest map L <= request in which active 26-neighbours differ by at most one level. */
static void ReferenceGrading(const PetscInt nb[3], const PetscBool periodic[3], PetscInt level[])
{
  const PetscInt nblocks = nb[0] * nb[1] * nb[2];
  PetscBool      changed = PETSC_TRUE;

  while (changed) {
    changed = PETSC_FALSE;
    for (PetscInt b = 0; b < nblocks; b++) {
      PetscInt ijk[3];
      if (level[b] < 0) continue;
      BlockIJK(nb, b, ijk);
      for (PetscInt r = 0; r < 27; r++) {
        const PetscInt d[3] = {r % 3 - 1, (r / 3) % 3 - 1, r / 9 - 1};
        const PetscInt nbr  = PffRasterNeighbour(nb, periodic, ijk, d);
        if (nbr < 0 || level[nbr] < 0 || level[b] <= level[nbr] + 1) continue;
        level[b] = level[nbr] + 1;
        changed  = PETSC_TRUE;
      }
    }
  }
}

static PetscErrorCode CheckGraded(PetscInt map, const PetscInt nb[3], const PetscBool periodic[3],
                                  const PetscInt request[], const PetscInt level[], PetscInt *lowered)
{
  const PetscInt nblocks = nb[0] * nb[1] * nb[2];

  PetscFunctionBeginUser;
  for (PetscInt b = 0; b < nblocks; b++) {
    PetscInt ijk[3];
    BlockIJK(nb, b, ijk);
    PetscCheck((request[b] < 0) == (level[b] < 0), PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "map %" PetscInt_FMT " block %" PetscInt_FMT ": requested %" PetscInt_FMT ", graded %" PetscInt_FMT
               " (activity changed)",
               map, b, request[b], level[b]);
    if (level[b] < 0) continue;
    PetscCheck(level[b] <= request[b], PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "map %" PetscInt_FMT " block %" PetscInt_FMT ": grading raised level %" PetscInt_FMT
               " to %" PetscInt_FMT,
               map, b, request[b], level[b]);
    PetscBool finer = PETSC_FALSE;
    for (PetscInt r = 0; r < 27; r++) {
      const PetscInt d[3] = {r % 3 - 1, (r / 3) % 3 - 1, r / 9 - 1};
      const PetscInt nbr  = PffRasterNeighbour(nb, periodic, ijk, d);
      if (nbr < 0 || level[nbr] < 0) continue;
      PetscCheck(PetscAbsInt(level[nbr] - level[b]) <= 1, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                 "map %" PetscInt_FMT ": blocks %" PetscInt_FMT " (level %" PetscInt_FMT ") and %" PetscInt_FMT
                 " (level %" PetscInt_FMT ") are neighbours in direction %" PetscInt_FMT,
                 map, b, level[b], nbr, level[nbr], r);
      if (level[nbr] == level[b] - 1) finer = PETSC_TRUE;
    }
    if (level[b] < request[b]) {
      PetscCheck(finer, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                 "map %" PetscInt_FMT " block %" PetscInt_FMT " was lowered from %" PetscInt_FMT " to %" PetscInt_FMT
                 " but has no neighbour at level %" PetscInt_FMT,
                 map, b, request[b], level[b], level[b] - 1);
      (*lowered)++;
    }
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Two maps whose grading is known by hand: a ramp away from one fine block, walled and periodic. */
static PetscErrorCode CheckKnownMaps(void)
{
  const PetscInt  nb[3]     = {8, 1, 1};
  const PetscBool walls[3]  = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};
  const PetscBool wrapx[3]  = {PETSC_TRUE, PETSC_FALSE, PETSC_FALSE};
  const PetscInt  walled[8] = {0, 1, 2, 3, 4, 5, 5, 5}, wrapped[8] = {0, 1, 2, 3, 4, 3, 2, 1};
  PetscInt        a[8], b[8];

  PetscFunctionBeginUser;
  for (int i = 0; i < 8; i++) a[i] = b[i] = i ? 5 : 0;
  PetscCall(PffGradeLevels(nb, walls, a));
  PetscCall(PffGradeLevels(nb, wrapx, b));
  for (int i = 0; i < 8; i++) {
    PetscCheck(a[i] == walled[i], PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "walled ramp: block %d graded to %" PetscInt_FMT ", expected %" PetscInt_FMT, i, a[i], walled[i]);
    PetscCheck(b[i] == wrapped[i], PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "periodic ramp: block %d graded to %" PetscInt_FMT ", expected %" PetscInt_FMT, i, b[i], wrapped[i]);
  }
  /* an inactive block is not a neighbour: it does not carry the ramp across */
  for (int i = 0; i < 8; i++) a[i] = i ? 5 : 0;
  a[1] = -1;
  PetscCall(PffGradeLevels(nb, walls, a));
  for (int i = 2; i < 8; i++)
    PetscCheck(a[i] == 5, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "block %d behind an inactive block was graded to %" PetscInt_FMT ", expected 5", i, a[i]);
  PetscCheck(a[0] == 0 && a[1] == -1, PETSC_COMM_SELF, PETSC_ERR_PLIB, "grading changed the fine or inactive block");
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  const PetscInt nmaps        = 50;
  PetscInt       nblocksTotal = 0, lowered = 0;

  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(PffInitializePackage());
  PetscCall(CheckKnownMaps());
  for (PetscInt m = 0; m < nmaps; m++) {
    PetscInt  nb[3], nblocks, *request, *level, *again, *ref;
    PetscBool periodic[3];
    for (int a = 0; a < 3; a++) {
      nb[a]       = 1 + Draw((uint64_t)m, 1, (uint64_t)a, 7);
      periodic[a] = (PetscBool)Draw((uint64_t)m, 2, (uint64_t)a, 2);
    }
    nblocks                = nb[0] * nb[1] * nb[2];
    const PetscInt  maxl   = 1 + Draw((uint64_t)m, 3, 0, 5);
    const PetscBool sparse = (PetscBool)(m % 2);
    PetscCall(PetscMalloc4(nblocks, &request, nblocks, &level, nblocks, &again, nblocks, &ref));
    for (PetscInt b = 0; b < nblocks; b++) {
      request[b] = Draw((uint64_t)m, 4, (uint64_t)b, maxl + 1);
      if (sparse && Draw((uint64_t)m, 5, (uint64_t)b, 100) < 15) request[b] = -1;
      level[b] = ref[b] = request[b];
    }
    PetscCall(CheckNeighbours(nb, periodic));
    PetscCall(PffGradeLevels(nb, periodic, level));
    PetscCall(CheckGraded(m, nb, periodic, request, level, &lowered));
    for (PetscInt b = 0; b < nblocks; b++) again[b] = level[b];
    PetscCall(PffGradeLevels(nb, periodic, again));
    ReferenceGrading(nb, periodic, ref);
    for (PetscInt b = 0; b < nblocks; b++) {
      PetscCheck(again[b] == level[b], PETSC_COMM_SELF, PETSC_ERR_PLIB,
                 "map %" PetscInt_FMT " block %" PetscInt_FMT ": grading twice gives %" PetscInt_FMT
                 ", once %" PetscInt_FMT,
                 m, b, again[b], level[b]);
      PetscCheck(ref[b] == level[b], PETSC_COMM_SELF, PETSC_ERR_PLIB,
                 "map %" PetscInt_FMT " block %" PetscInt_FMT ": graded to %" PetscInt_FMT
                 ", the coarsest graded map has %" PetscInt_FMT,
                 m, b, level[b], ref[b]);
    }
    nblocksTotal += nblocks;
    PetscCall(PetscFree4(request, level, again, ref));
  }
  PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                        "grade ok: %" PetscInt_FMT " rasters, %" PetscInt_FMT " blocks, %" PetscInt_FMT " lowered\n",
                        nmaps, nblocksTotal, lowered));
  PetscCall(PetscFinalize());
  return 0;
}
