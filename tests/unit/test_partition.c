/* Unit test of the block partition of PffGrid (Morton, METIS and columns) at any rank count.

   On three pseudo-random multi-level maps (n0 = 8, 3 levels; walled or partly periodic rasters, with
   and without inactive blocks) and for both partitioners it checks that
     - the raster levels are the graded request (PffGradeLevels of the map given to the grid),
     - inactive blocks have owner -1 and every active block one owner in [0, size),
     - each rank's local blocks are exactly the blocks the owner map gives it (block info, local
       index both ways), and the local counts sum over the ranks to the number of active blocks,
     - the level and owner maps are identical on every rank (compared with rank 0's) and identical
       when the same grid is set up a second time; -partition_type gives the same map as the setter,
     - PffGridGetMortonOrder lists every active block once in increasing Morton key order,
     - PffGridGetPartitionQuality agrees with the owner map: imbalance >= 1 equals
       max work * size / total work (work = cells), and the cut faces are recounted here,
     - Morton: owners are non-decreasing along the Morton order and no rank holds more than its
       share plus one block;
     - columns: every block column along y has one owner, and no rank holds more than its share plus
       one block column.
   On a uniform 4x4x4-block grid the Morton partition has imbalance exactly 1 on 1, 2 and 4 ranks.

   Sample run:  mpiexec -n 4 ./test_partition
   Prints (the same on any number of ranks) one "ok" line per map and partitioner. */
#include "pfftest.h"

static const char help[] = "Partition of the block raster: ownership, determinism, quality.\n";

static PetscInt Draw(uint64_t seed, uint64_t index, PetscInt m)
{
  return (PetscInt)(PffTestHash64(PffTestHash64(seed) ^ index) % (uint64_t)m);
}

typedef struct {
  const char *name;
  PetscInt    nb[3];
  PetscBool   periodic[3];
  PetscBool   inactive; /* some blocks inactive */
  uint64_t    seed;
} Case;

#define N0 8

/* Requested levels 0..2 growing with the distance from a random block, with random jumps that
   grading fixes, and -1 for about one block in eight when the case has inactive blocks. */
static PetscErrorCode BuildRequest(const Case *c, PetscInt **request)
{
  const PetscInt nblocks = c->nb[0] * c->nb[1] * c->nb[2];

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(nblocks, request));
  for (PetscInt b = 0; b < nblocks; b++) {
    const PetscInt ijk[3] = {b % c->nb[0], (b / c->nb[0]) % c->nb[1], b / (c->nb[0] * c->nb[1])};
    PetscReal      d2     = 0;
    for (int a = 0; a < 3; a++) d2 += PetscSqr((PetscReal)(ijk[a] - Draw(c->seed + 100, (uint64_t)a, c->nb[a])));
    const PetscInt l = (PetscInt)(PetscSqrtReal(d2) / 1.5) + Draw(c->seed, (uint64_t)b, 3) - 1;
    (*request)[b]    = PetscMax(0, PetscMin(2, l));
    if (c->inactive && Draw(c->seed + 200, (uint64_t)b, 8) == 0) (*request)[b] = -1;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode CreateGrid(MPI_Comm comm, const Case *c, const PetscInt request[], PffPartitionType ptype,
                                 PetscBool fromOptions, PffGrid *grid)
{
  const PetscInt cells[3] = {N0 * c->nb[0], N0 * c->nb[1], N0 * c->nb[2]};

  PetscFunctionBeginUser;
  PetscCall(PffGridCreate(comm, grid));
  PetscCall(PffGridSetCells(*grid, cells));
  PetscCall(PffGridSetBlockSize(*grid, N0));
  PetscCall(PffGridSetLevels(*grid, 3));
  PetscCall(PffGridSetPeriodic(*grid, c->periodic));
  if (request) PetscCall(PffGridSetRefinementMap(*grid, request));
  if (fromOptions) {
    PetscCall(PetscOptionsSetValue(NULL, "-partition_type", PffPartitionTypes[ptype]));
    PetscCall(PffGridSetFromOptions(*grid));
    PetscCall(PetscOptionsClearValue(NULL, "-partition_type"));
  } else
    PetscCall(PffGridSetPartitionType(*grid, ptype));
  PetscCall(PffGridSetUp(*grid));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode CheckSameMaps(PffGrid a, PffGrid b, const char what[])
{
  PetscInt           nba[3], nbb[3];
  const PetscInt    *la, *lb;
  const PetscMPIInt *oa, *ob;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetRaster(a, nba, &la, &oa));
  PetscCall(PffGridGetRaster(b, nbb, &lb, &ob));
  PetscCheck(nba[0] == nbb[0] && nba[1] == nbb[1] && nba[2] == nbb[2], PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "%s: raster sizes differ", what);
  for (PetscInt g = 0; g < nba[0] * nba[1] * nba[2]; g++)
    PetscCheck(la[g] == lb[g] && oa[g] == ob[g], PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "%s: block %" PetscInt_FMT " has level %" PetscInt_FMT " owner %d, then level %" PetscInt_FMT
               " owner %d",
               what, g, la[g], oa[g], lb[g], ob[g]);
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode CheckPartition(PffGrid grid, const PetscInt request[], PffPartitionType ptype, const char what[],
                                     PetscInt perLevel[3])
{
  MPI_Comm            comm = PETSC_COMM_WORLD;
  PetscMPIInt         rank, size;
  PetscInt            nb[3], nblocks, nactive = 0, nmine = 0, nlocal, nsum, norder;
  const PetscInt     *level, *order;
  const PetscMPIInt  *owner;
  PetscInt           *graded, *replica;
  PetscMPIInt        *orep;
  PetscInt64         *work, total = 0, wmax = 0;
  PetscBool          *seen, periodic[3];
  PffPartitionQuality q;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(PffGridGetRaster(grid, nb, &level, &owner));
  PetscCall(PffGridGetSizes(grid, NULL, NULL, NULL, NULL, periodic));
  nblocks = nb[0] * nb[1] * nb[2];

  /* levels: the graded request */
  PetscCall(PetscMalloc4(nblocks, &graded, nblocks, &replica, nblocks, &orep, nblocks, &seen));
  for (PetscInt g = 0; g < nblocks; g++) graded[g] = request ? request[g] : 0;
  PetscCall(PffGradeLevels(nb, periodic, graded));
  for (PetscInt g = 0; g < nblocks; g++) {
    PetscCheck(level[g] == graded[g], PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "%s: block %" PetscInt_FMT " has level %" PetscInt_FMT ", the graded request is %" PetscInt_FMT, what, g,
               level[g], graded[g]);
    if (level[g] < 0) {
      PetscCheck(owner[g] == -1, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: inactive block %" PetscInt_FMT " has owner %d",
                 what, g, owner[g]);
    } else {
      PetscCheck(owner[g] >= 0 && owner[g] < size, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                 "%s: active block %" PetscInt_FMT " has owner %d on %d ranks", what, g, owner[g], size);
      nactive++;
      if (owner[g] == rank) nmine++;
    }
  }

  /* the local blocks are the owner map's */
  PetscCall(PffGridGetLocalBlocks(grid, &nlocal));
  PetscCheck(nlocal == nmine, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "%s: rank %d has %" PetscInt_FMT " local blocks, the owner map gives it %" PetscInt_FMT, what, rank,
             nlocal, nmine);
  for (PetscInt g = 0; g < nblocks; g++) seen[g] = PETSC_FALSE;
  for (PetscInt lb = 0; lb < nlocal; lb++) {
    PffBlockInfo info;
    PetscInt     back;
    PetscCall(PffGridGetBlockInfo(grid, lb, &info));
    PetscCheck(info.gid >= 0 && info.gid < nblocks && !seen[info.gid] && owner[info.gid] == rank, PETSC_COMM_SELF,
               PETSC_ERR_PLIB,
               "%s: local block %" PetscInt_FMT " is global block %" PetscInt_FMT ", repeated or not owned", what, lb,
               info.gid);
    seen[info.gid] = PETSC_TRUE;
    PetscCheck(info.ijk[0] + nb[0] * (info.ijk[1] + nb[1] * info.ijk[2]) == info.gid && info.level == level[info.gid] &&
                   info.n == N0 >> info.level,
               PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: block info of local block %" PetscInt_FMT " is inconsistent", what,
               lb);
    PetscCall(PffGridGetLocalIndex(grid, info.gid, &back));
    PetscCheck(back == lb, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "%s: local index of global block %" PetscInt_FMT " is %" PetscInt_FMT ", expected %" PetscInt_FMT, what,
               info.gid, back, lb);
  }
  for (PetscInt g = 0; g < nblocks; g++) {
    PetscInt lb;
    PetscCall(PffGridGetLocalIndex(grid, g, &lb));
    PetscCheck(seen[g] || lb == -1, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "%s: block %" PetscInt_FMT " is not local but has local index %" PetscInt_FMT, what, g, lb);
  }
  PetscCallMPI(MPI_Allreduce(&nlocal, &nsum, 1, MPIU_INT, MPI_SUM, comm));
  PetscCheck(nsum == nactive, comm, PETSC_ERR_PLIB,
             "%s: the ranks own %" PetscInt_FMT " blocks in total, there are %" PetscInt_FMT " active", what, nsum,
             nactive);

  /* replicated: every rank holds rank 0's maps */
  for (PetscInt g = 0; g < nblocks; g++) {
    replica[g] = level[g];
    orep[g]    = owner[g];
  }
  PetscCallMPI(MPI_Bcast(replica, (PetscMPIInt)nblocks, MPIU_INT, 0, comm));
  PetscCallMPI(MPI_Bcast(orep, (PetscMPIInt)nblocks, MPI_INT, 0, comm));
  for (PetscInt g = 0; g < nblocks; g++)
    PetscCheck(replica[g] == level[g] && orep[g] == owner[g], PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "%s: block %" PetscInt_FMT " has level %" PetscInt_FMT " owner %d on rank %d but level %" PetscInt_FMT
               " owner %d on rank 0",
               what, g, level[g], owner[g], rank, replica[g], orep[g]);

  /* Morton order: all active blocks, increasing keys; Morton partition: contiguous along it */
  PetscCall(PffGridGetMortonOrder(grid, &norder, &order));
  PetscCheck(norder == nactive, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "%s: Morton order has %" PetscInt_FMT " blocks, %" PetscInt_FMT " are active", what, norder, nactive);
  for (PetscInt g = 0; g < nblocks; g++) seen[g] = PETSC_FALSE;
  for (PetscInt a = 0; a < norder; a++) {
    const PetscInt g = order[a];
    PetscCheck(g >= 0 && g < nblocks && level[g] >= 0 && !seen[g], PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "%s: Morton order entry %" PetscInt_FMT " is block %" PetscInt_FMT ", inactive or repeated", what, a, g);
    seen[g] = PETSC_TRUE;
    if (a > 0) {
      const PetscInt p = order[a - 1];
      const uint64_t kp =
          PffMortonEncode((uint32_t)(p % nb[0]), (uint32_t)((p / nb[0]) % nb[1]), (uint32_t)(p / (nb[0] * nb[1])));
      const uint64_t kg =
          PffMortonEncode((uint32_t)(g % nb[0]), (uint32_t)((g / nb[0]) % nb[1]), (uint32_t)(g / (nb[0] * nb[1])));
      PetscCheck(kp < kg, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: Morton order is not increasing at entry %" PetscInt_FMT,
                 what, a);
      if (ptype == PFF_PARTITION_MORTON)
        PetscCheck(owner[p] <= owner[g], PETSC_COMM_SELF, PETSC_ERR_PLIB,
                   "%s: owners along the Morton order go from %d down to %d at entry %" PetscInt_FMT, what, owner[p],
                   owner[g], a);
    }
  }

  /* quality from the owner map */
  PetscCall(PetscCalloc1(size, &work));
  PetscInt cut = 0;
  for (PetscInt g = 0; g < nblocks; g++) {
    if (level[g] < 0) continue;
    const PetscInt64 n      = N0 >> level[g];
    const PetscInt   ijk[3] = {g % nb[0], (g / nb[0]) % nb[1], g / (nb[0] * nb[1])};
    work[owner[g]] += n * n * n;
    total += n * n * n;
    for (int d = 0; d < 3; d++) {
      PetscInt dd[3]     = {0, 0, 0};
      dd[d]              = 1;
      const PetscInt nbr = PffRasterNeighbour(nb, periodic, ijk, dd);
      if (nbr >= 0 && level[nbr] >= 0 && owner[nbr] != owner[g]) cut++;
    }
  }
  for (PetscMPIInt r = 0; r < size; r++) wmax = PetscMax(wmax, work[r]);
  PetscCall(PetscFree(work));
  PetscCall(PffGridGetPartitionQuality(grid, &q));
  const PetscReal imb = (PetscReal)wmax * size / (PetscReal)total;
  PetscCheck(q.imbalance >= 1 && PetscAbsReal(q.imbalance - imb) <= 1e-12 * imb, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "%s: imbalance %g, the owner map gives %g", what, (double)q.imbalance, (double)imb);
  PetscCheck(q.cutFaces == cut, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "%s: %" PetscInt_FMT " cut faces reported, %" PetscInt_FMT " in the owner map", what, q.cutFaces, cut);
  PetscCheck(size > 1 || (q.imbalance == 1 && cut == 0), PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "%s: one rank, yet imbalance %g and %" PetscInt_FMT " cut faces", what, (double)q.imbalance, cut);
  PetscCheck(q.haloBytesMax >= q.haloBytesMean && q.haloBytesMean >= 0 && (size > 1 || q.haloBytesMax == 0),
             PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: halo bytes max %g mean %g", what, (double)q.haloBytesMax,
             (double)q.haloBytesMean);
  if (ptype == PFF_PARTITION_COLUMNS) {
    PetscInt64 colMax = 0;
    for (PetscInt g = 0; g < nblocks; g++) {
      const PetscInt b0 = g % nb[0] + nb[0] * nb[1] * (g / (nb[0] * nb[1])); /* the column's bottom block */
      PetscInt64     cw = 0;
      PetscCheck(level[g] < 0 || level[b0] < 0 || owner[g] == owner[b0], PETSC_COMM_SELF, PETSC_ERR_PLIB,
                 "%s: block %" PetscInt_FMT " has owner %d, its column's bottom block %d", what, g, owner[g],
                 owner[b0]);
      if (g != b0) continue;
      for (PetscInt j = 0; j < nb[1]; j++) {
        const PetscInt b = b0 + nb[0] * j;
        if (level[b] >= 0) cw += (PetscInt64)(N0 >> level[b]) * (N0 >> level[b]) * (N0 >> level[b]);
      }
      colMax = PetscMax(colMax, cw);
    }
    PetscCheck(wmax * size <= total + (PetscInt64)size * colMax, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "%s: a rank holds %" PetscInt64_FMT " cells, more than its share of %" PetscInt64_FMT " plus one column",
               what, wmax, total);
  }
  if (ptype == PFF_PARTITION_MORTON) {
    /* each rank holds the blocks whose work midpoint falls in its share: at most one block too many */
    PetscCheck(wmax * size <= total + (PetscInt64)size * N0 * N0 * N0, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "%s: a rank holds %" PetscInt64_FMT " cells, more than its share of %" PetscInt64_FMT " plus one block",
               what, wmax, total);
  }
  PetscCall(PetscFree4(graded, replica, orep, seen));
  for (PetscInt l = 0; l < 3; l++) perLevel[l] = 0;
  for (PetscInt g = 0; g < nblocks; g++)
    if (level[g] >= 0) perLevel[level[g]]++;
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  const Case cases[] = {
      {"4x3x5 walls", {4, 3, 5}, {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE}, PETSC_FALSE, 11},
      {"4x3x5 periodic x,z", {4, 3, 5}, {PETSC_TRUE, PETSC_FALSE, PETSC_TRUE}, PETSC_TRUE, 12},
      {"6x5x4 periodic y", {6, 5, 4}, {PETSC_FALSE, PETSC_TRUE, PETSC_FALSE}, PETSC_TRUE, 13},
      {"1x1x2 walls",
       {1, 1, 2},
       {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE},
       PETSC_FALSE,
       14}, /* fewer blocks than ranks */
  };
  PetscMPIInt size;

  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(PffInitializePackage());
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  for (size_t c = 0; c < PETSC_STATIC_ARRAY_LENGTH(cases); c++) {
    PetscInt *request;
    PetscCall(BuildRequest(&cases[c], &request));
    for (PffPartitionType pt = PFF_PARTITION_MORTON; pt <= PFF_PARTITION_COLUMNS; pt++) {
      PffGrid  a, b, o;
      PetscInt nl[3];
      char     what[128];
      PetscCall(PetscSNPrintf(what, sizeof(what), "%s %s", cases[c].name, PffPartitionTypes[pt]));
      PetscCall(CreateGrid(PETSC_COMM_WORLD, &cases[c], request, pt, PETSC_FALSE, &a));
      PetscCall(CheckPartition(a, request, pt, what, nl));
      PetscCall(CreateGrid(PETSC_COMM_WORLD, &cases[c], request, pt, PETSC_FALSE, &b));
      PetscCall(CheckSameMaps(a, b, what));
      PetscCall(CreateGrid(PETSC_COMM_WORLD, &cases[c], request, pt, PETSC_TRUE, &o));
      PetscCall(CheckSameMaps(a, o, what));
      PetscCall(PffGridDestroy(&a));
      PetscCall(PffGridDestroy(&b));
      PetscCall(PffGridDestroy(&o));
      PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                            "partition %s: blocks per level %" PetscInt_FMT " %" PetscInt_FMT " %" PetscInt_FMT " ok\n",
                            what, nl[0], nl[1], nl[2]));
    }
    PetscCall(PetscFree(request));
  }

  /* uniform 4x4x4 blocks: the Morton cut is exact whenever the rank count divides 64 */
  {
    const Case          uniform = {"uniform 4x4x4", {4, 4, 4}, {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE}, PETSC_FALSE, 0};
    PffGrid             grid;
    PetscInt            nl[3];
    PffPartitionQuality q;
    PetscCall(CreateGrid(PETSC_COMM_WORLD, &uniform, NULL, PFF_PARTITION_MORTON, PETSC_FALSE, &grid));
    PetscCall(CheckPartition(grid, NULL, PFF_PARTITION_MORTON, uniform.name, nl));
    PetscCall(PffGridGetPartitionQuality(grid, &q));
    if (64 % size == 0)
      PetscCheck(q.imbalance == 1, PETSC_COMM_WORLD, PETSC_ERR_PLIB,
                 "uniform 4x4x4 Morton partition on %d ranks has imbalance %.17g, expected exactly 1", size,
                 (double)q.imbalance);
    PetscCall(PffGridDestroy(&grid));
    PetscCall(PetscPrintf(PETSC_COMM_WORLD, "partition %s morton: %" PetscInt_FMT " blocks, imbalance 1 ok\n",
                          uniform.name, nl[0]));
  }
  PetscCall(PetscFinalize());
  return 0;
}
