/* PffGrid interface: life cycle, options with their checks, getters, view.
   Every parameter is validated before SetUp allocates anything, and each message names the option
   key that controls the value, so a user can fix a scene file from the error line alone. */
#include "gridimpl.h"

const char *const PffPartitionTypes[] = {"morton", "metis", "columns", "PffPartitionType", "PFF_PARTITION_", NULL};
const char *const PffRefineTypes[]    = {"none", "plane", "sphere", "PffRefineType", "PFF_REFINE_", NULL};
const char *const PffChannelKinds[]   = {"cell", "face", "PffChannelKind", "PFF_CHANNEL_", NULL};

PetscErrorCode PffGridCreate(MPI_Comm comm, PffGrid *grid)
{
  PffGrid g;

  PetscFunctionBeginUser;
  PetscCall(PffInitializePackage());
  PetscCall(PetscNew(&g));
  PetscCallMPI(MPI_Comm_dup(comm, &g->comm));
  PetscCallMPI(MPI_Comm_rank(g->comm, &g->rank));
  PetscCallMPI(MPI_Comm_size(g->comm, &g->size));
  for (int d = 0; d < 3; d++) g->cells[d] = 4 * PFF_GRID_BLOCK_SIZE_DEFAULT;
  g->n0         = PFF_GRID_BLOCK_SIZE_DEFAULT;
  g->nlevels    = PFF_GRID_LEVELS_DEFAULT;
  g->h0         = -1.0; /* 1/cells[0] unless set */
  g->ptype      = PFF_PARTITION_MORTON;
  g->rtype      = PFF_REFINE_NONE;
  g->rnormal[2] = 1.0;
  g->rpoint[0] = g->rpoint[1] = g->rpoint[2] = 0.5;
  g->rradius                                 = 0.25;
  g->rband                                   = 1.0;
  *grid                                      = g;
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffGridCheckNotSetUp(PffGrid g)
{
  PetscFunctionBeginUser;
  PetscCheck(!g->setupcalled, g->comm, PETSC_ERR_ORDER,
             "the grid is already set up; set its parameters before PffGridSetUp()");
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridSetBlockSize(PffGrid g, PetscInt n0)
{
  PetscFunctionBeginUser;
  PetscCall(PffGridCheckNotSetUp(g));
  PetscCheck(n0 >= PFF_GRID_BLOCK_SIZE_MIN && n0 <= PFF_GRID_BLOCK_SIZE_MAX && (n0 & (n0 - 1)) == 0, g->comm,
             PETSC_ERR_ARG_OUTOFRANGE,
             "-grid_block_size %" PetscInt_FMT " is invalid: must be a power of two in [%d, %d]", n0,
             PFF_GRID_BLOCK_SIZE_MIN, PFF_GRID_BLOCK_SIZE_MAX);
  g->n0 = n0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridSetCells(PffGrid g, const PetscInt cells[3])
{
  PetscFunctionBeginUser;
  PetscCall(PffGridCheckNotSetUp(g));
  for (int d = 0; d < 3; d++) {
    PetscCheck(cells[d] > 0 && cells[d] <= (PetscInt)1 << 30, g->comm, PETSC_ERR_ARG_OUTOFRANGE,
               "-grid_cells: %c has %" PetscInt_FMT " cells; must be positive (and at most 2^30)", 'x' + d, cells[d]);
    g->cells[d] = cells[d];
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridSetLevels(PffGrid g, PetscInt nlevels)
{
  PetscFunctionBeginUser;
  PetscCall(PffGridCheckNotSetUp(g));
  PetscCheck(nlevels >= 1 && nlevels <= PFF_GRID_MAX_LEVELS, g->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-grid_levels %" PetscInt_FMT " is invalid: must be in [1, log2(-grid_block_size) + 1]", nlevels);
  g->nlevels = nlevels;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridSetDomain(PffGrid g, const PetscReal origin[3], PetscReal h0)
{
  PetscFunctionBeginUser;
  PetscCall(PffGridCheckNotSetUp(g));
  PetscCheck(h0 > 0 && PetscIsNormalReal(h0), g->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-grid_h %g is invalid: the finest cell size must be positive", (double)h0);
  for (int d = 0; d < 3; d++) {
    PetscCheck(!PetscIsInfOrNanReal(origin[d]), g->comm, PETSC_ERR_ARG_OUTOFRANGE, "-grid_origin must be finite");
    g->origin[d] = origin[d];
  }
  g->h0 = h0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridSetPeriodic(PffGrid g, const PetscBool periodic[3])
{
  PetscFunctionBeginUser;
  PetscCall(PffGridCheckNotSetUp(g));
  for (int d = 0; d < 3; d++) g->periodic[d] = periodic[d];
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridGetPartitionType(PffGrid g, PffPartitionType *type)
{
  PetscFunctionBeginUser;
  *type = g->ptype;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridSetPartitionType(PffGrid g, PffPartitionType type)
{
  PetscFunctionBeginUser;
  PetscCall(PffGridCheckNotSetUp(g));
  g->ptype = type;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridSetRefinementFunction(PffGrid g, PffRefineFn fn, void *ctx)
{
  PetscFunctionBeginUser;
  PetscCall(PffGridCheckNotSetUp(g));
  g->refine    = fn;
  g->refinectx = ctx;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridSetRefinementMap(PffGrid g, const PetscInt level[])
{
  PetscInt nb[3], nblocks = 1;

  PetscFunctionBeginUser;
  PetscCall(PffGridCheckNotSetUp(g));
  for (int d = 0; d < 3; d++) {
    nb[d] = g->cells[d] / g->n0;
    nblocks *= nb[d];
  }
  PetscCall(PetscFree(g->usermap));
  PetscCall(PetscMalloc1(nblocks, &g->usermap));
  PetscCall(PetscArraycpy(g->usermap, level, nblocks));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Reads "x,z"-style axis lists; anything but x, y, z is an error naming the key. */
static PetscErrorCode PffParseAxes(MPI_Comm comm, const char key[], const char list[], PetscBool axes[3])
{
  PetscFunctionBeginUser;
  axes[0] = axes[1] = axes[2] = PETSC_FALSE;
  for (const char *c = list; *c; c++) {
    if (*c == ',' || *c == ' ') continue;
    PetscCheck(*c == 'x' || *c == 'y' || *c == 'z', comm, PETSC_ERR_ARG_OUTOFRANGE,
               "%s \"%s\" is invalid: give a comma-separated list of the axes x, y, z (or none)", key, list);
    PetscCheck(!axes[*c - 'x'], comm, PETSC_ERR_ARG_OUTOFRANGE, "%s \"%s\" is invalid: axis %c is listed twice", key,
               list, *c);
    axes[*c - 'x'] = PETSC_TRUE;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridSetFromOptions(PffGrid g)
{
  PetscInt  cells[3] = {g->cells[0], g->cells[1], g->cells[2]}, ncells = 3, n0 = g->n0, nlevels = g->nlevels;
  PetscReal origin[3] = {g->origin[0], g->origin[1], g->origin[2]}, h0 = g->h0, point[3], normal[3];
  PetscInt  norigin = 3, npoint = 3, nnormal = 3;
  char      periodic[64] = "";
  PetscBool set, hset, pset;
  PetscEnum ptype = (PetscEnum)g->ptype, rtype = (PetscEnum)g->rtype;

  PetscFunctionBeginUser;
  PetscCall(PffGridCheckNotSetUp(g));
  for (int d = 0; d < 3; d++) {
    point[d]  = g->rpoint[d];
    normal[d] = g->rnormal[d];
  }
  PetscOptionsBegin(g->comm, NULL, "Multiresolution sparse block grid (MSBG)", "PffGrid");
  PetscCall(PffOptionsIntArray("-grid_cells", "Finest-level cells per axis nx,ny,nz (multiples of the block size)",
                               "PffGridSetCells", cells, &ncells, &set));
  if (set) {
    PetscCheck(ncells == 3 || ncells == 1, g->comm, PETSC_ERR_ARG_SIZ,
               "-grid_cells takes 3 values nx,ny,nz (or 1 for a cube); got %" PetscInt_FMT, ncells);
    if (ncells == 1) cells[1] = cells[2] = cells[0];
    PetscCall(PffGridSetCells(g, cells));
  }
  PetscCall(PffOptionsInt("-grid_block_size", "Cells per block axis at level 0, a power of two in [4, 64]",
                          "PffGridSetBlockSize", n0, &n0, &set));
  if (set) PetscCall(PffGridSetBlockSize(g, n0));
  PetscCall(PffOptionsInt("-grid_levels", "Number of resolution levels, at most log2(block size) + 1",
                          "PffGridSetLevels", nlevels, &nlevels, &set));
  if (set) PetscCall(PffGridSetLevels(g, nlevels));
  PetscCall(PffOptionsRealArray("-grid_origin", "Lower corner of the domain x,y,z", "PffGridSetDomain", origin,
                                &norigin, &set));
  PetscCheck(!set || norigin == 3, g->comm, PETSC_ERR_ARG_SIZ, "-grid_origin takes 3 values x,y,z");
  PetscCall(
      PffOptionsReal("-grid_h", "Finest cell size (default 1/nx)", "PffGridSetDomain", h0 > 0 ? h0 : 0.0, &h0, &hset));
  if (set || hset) {
    if (!hset && g->h0 <= 0) h0 = 1.0 / (PetscReal)g->cells[0];
    PetscCall(PffGridSetDomain(g, origin, h0));
  }
  PetscCall(PetscOptionsString("-grid_periodic", "Periodic axes, e.g. x,z (others are walls)", "PffGridSetPeriodic",
                               periodic, periodic, sizeof(periodic), &pset));
  if (pset) {
    PetscBool axes[3];
    PetscCall(PffParseAxes(g->comm, "-grid_periodic", periodic, axes));
    PetscCall(PffGridSetPeriodic(g, axes));
  }
  PetscCall(PffOptionsEnum("-partition_type", "Block partitioner", "PffGridSetPartitionType", PffPartitionTypes, ptype,
                           &ptype, NULL));
  g->ptype = (PffPartitionType)ptype;
  PetscCall(PffOptionsEnum("-grid_refine", "Static refinement: level grows with the distance to a plane or sphere",
                           "PffGridSetRefinementFunction", PffRefineTypes, rtype, &rtype, NULL));
  g->rtype = (PffRefineType)rtype;
  PetscCall(PffOptionsRealArray("-grid_refine_point", "Point on the refinement plane, or sphere centre", NULL, point,
                                &npoint, &set));
  PetscCheck(!set || npoint == 3, g->comm, PETSC_ERR_ARG_SIZ, "-grid_refine_point takes 3 values x,y,z");
  PetscCall(PffOptionsRealArray("-grid_refine_normal", "Normal of the refinement plane", NULL, normal, &nnormal, &set));
  PetscCheck(!set || nnormal == 3, g->comm, PETSC_ERR_ARG_SIZ, "-grid_refine_normal takes 3 values x,y,z");
  PetscCall(
      PffOptionsReal("-grid_refine_radius", "Radius of the refinement sphere", NULL, g->rradius, &g->rradius, NULL));
  PetscCall(
      PffOptionsReal("-grid_refine_band", "Width of each level band, in block sizes", NULL, g->rband, &g->rband, NULL));
  PetscCall(PffOptionsBool("-grid_refine_columns",
                           "Every block column along y takes the finest level asked in it (a quadtree for tall cells)",
                           NULL, g->rcolumns, &g->rcolumns, NULL));
  PetscOptionsEnd();
  PetscCheck(g->rband > 0, g->comm, PETSC_ERR_ARG_OUTOFRANGE, "-grid_refine_band %g is invalid: must be positive",
             (double)g->rband);
  PetscCheck(g->rradius >= 0, g->comm, PETSC_ERR_ARG_OUTOFRANGE, "-grid_refine_radius %g is invalid: must be >= 0",
             (double)g->rradius);
  const PetscReal nn = PetscSqrtReal(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
  PetscCheck(nn > 0, g->comm, PETSC_ERR_ARG_OUTOFRANGE, "-grid_refine_normal must not be the zero vector");
  for (int d = 0; d < 3; d++) {
    g->rpoint[d]  = point[d];
    g->rnormal[d] = normal[d] / nn;
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Consistency checks that need several parameters at once; run before any allocation. */
static PetscErrorCode PffGridValidate(PffGrid g)
{
  PetscFunctionBeginUser;
  g->log2n0 = 0;
  while (((PetscInt)1 << g->log2n0) < g->n0) g->log2n0++;
  PetscCheck(g->nlevels - 1 <= g->log2n0, g->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-grid_levels %" PetscInt_FMT " is invalid with -grid_block_size %" PetscInt_FMT
             ": the deepest level must be at most log2(block size) = %" PetscInt_FMT
             ", so -grid_levels <= %" PetscInt_FMT,
             g->nlevels, g->n0, g->log2n0, g->log2n0 + 1);
  for (int d = 0; d < 3; d++) {
    PetscCheck(g->cells[d] % g->n0 == 0, g->comm, PETSC_ERR_ARG_OUTOFRANGE,
               "-grid_cells: %c has %" PetscInt_FMT
               " cells, not a whole number of blocks of -grid_block_size %" PetscInt_FMT,
               'x' + d, g->cells[d], g->n0);
    PetscCheck(g->cells[d] / g->n0 <= ((PetscInt)1 << 21), g->comm, PETSC_ERR_ARG_OUTOFRANGE,
               "-grid_cells: %c has more than 2^21 blocks (the Morton key limit)", 'x' + d);
  }
  const PetscInt64 nblocks = (PetscInt64)(g->cells[0] / g->n0) * (g->cells[1] / g->n0) * (g->cells[2] / g->n0);
  /* every rank holds the whole raster (a few words per block): 2^24 blocks is 16.7 G cells of 16^3 blocks */
  PetscCheck(nblocks <= PFF_GRID_MAX_RASTER_BLOCKS, g->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-grid_cells %" PetscInt_FMT ",%" PetscInt_FMT ",%" PetscInt_FMT
             " is invalid with -grid_block_size %" PetscInt_FMT ": %" PetscInt64_FMT
             " blocks, but the replicated raster holds at most %d (use larger blocks)",
             g->cells[0], g->cells[1], g->cells[2], g->n0, nblocks, PFF_GRID_MAX_RASTER_BLOCKS);
  if (g->h0 <= 0) g->h0 = 1.0 / (PetscReal)g->cells[0];
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridSetUp(PffGrid g)
{
  PetscFunctionBeginUser;
  if (g->setupcalled) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PffGridValidate(g));
  PetscCall(PetscLogEventBegin(PFF_GridSetUp, 0, 0, 0, 0));
  PetscCall(PffGridBuildRaster_Private(g));
  PetscCall(PffGridPartition_Private(g));
  g->setupcalled = PETSC_TRUE;
  for (PetscInt c = 0; c < g->nch; c++) PetscCall(PffGridAllocateChannel_Private(g, g->ch[c], PETSC_TRUE));
  PetscCall(PffGridComputeQuality_Private(g));
  PetscCall(PetscLogEventEnd(PFF_GridSetUp, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridDestroy(PffGrid *grid)
{
  PffGrid g;

  PetscFunctionBeginUser;
  if (!grid || !*grid) PetscFunctionReturn(PETSC_SUCCESS);
  g = *grid;
  for (PetscInt c = 0; c < g->nch; c++) PetscCall(PffGridDestroyChannel_Private(&g->ch[c]));
  for (PetscInt p = 0; p < g->nplans; p++) PetscCall(PffHaloPlanDestroy_Private(&g->plans[p]));
  PetscCall(PetscFree(g->usermap));
  PetscCall(PetscFree(g->level));
  PetscCall(PetscFree(g->owner));
  PetscCall(PetscFree(g->morton));
  PetscCall(PetscFree(g->order));
  PetscCall(PetscFree(g->offset));
  PetscCall(PetscFree(g->rankCellStart));
  PetscCall(PetscFree(g->local));
  PetscCall(PetscFree(g->lgid));
  PetscCall(PetscFree(g->loff));
  PetscCall(PetscFree(g->lholes));
  PetscCall(PetscFree(g->xwork));
  PetscCallMPI(MPI_Comm_free(&g->comm));
  PetscCall(PetscFree(g));
  *grid = NULL;
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffGridCheckSetUp(PffGrid g)
{
  PetscFunctionBeginUser;
  PetscCheck(g->setupcalled, PETSC_COMM_SELF, PETSC_ERR_ORDER, "call PffGridSetUp() first");
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridGetCells(PffGrid g, PetscInt cells[3])
{
  PetscFunctionBeginUser;
  for (int d = 0; d < 3; d++) cells[d] = g->cells[d];
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridGetDomain(PffGrid g, PetscReal lo[3], PetscReal hi[3])
{
  PetscReal h0;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetSizes(g, NULL, NULL, lo, &h0, NULL));
  for (int d = 0; d < 3; d++) hi[d] = lo[d] + h0 * (PetscReal)g->cells[d];
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridGetComm(PffGrid g, MPI_Comm *comm)
{
  PetscFunctionBeginUser;
  *comm = g->comm;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridGetRaster(PffGrid g, PetscInt nb[3], const PetscInt **level, const PetscMPIInt **owner)
{
  PetscFunctionBeginUser;
  PetscCall(PffGridCheckSetUp(g));
  if (nb)
    for (int d = 0; d < 3; d++) nb[d] = g->nb[d];
  if (level) *level = g->level;
  if (owner) *owner = g->owner;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridGetSizes(PffGrid g, PetscInt *n0, PetscInt *nlevels, PetscReal origin[3], PetscReal *h0,
                               PetscBool periodic[3])
{
  PetscFunctionBeginUser;
  if (n0) *n0 = g->n0;
  if (nlevels) *nlevels = g->nlevels;
  if (origin)
    for (int d = 0; d < 3; d++) origin[d] = g->origin[d];
  if (h0) *h0 = g->h0 > 0 ? g->h0 : 1.0 / (PetscReal)g->cells[0];
  if (periodic)
    for (int d = 0; d < 3; d++) periodic[d] = g->periodic[d];
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridGetLocalBlocks(PffGrid g, PetscInt *nlocal)
{
  PetscFunctionBeginUser;
  PetscCall(PffGridCheckSetUp(g));
  *nlocal = g->nlocal;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridGetBlockInfo(PffGrid g, PetscInt lb, PffBlockInfo *info)
{
  PetscFunctionBeginUser;
  PetscCall(PffGridCheckSetUp(g));
  PetscCheck(lb >= 0 && lb < g->nlocal, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
             "local block %" PetscInt_FMT " out of range [0, %" PetscInt_FMT ")", lb, g->nlocal);
  const PetscInt gid = g->lgid[lb];
  info->gid          = gid;
  PffGridBlockIJK_Private(g, gid, info->ijk);
  info->level = g->level[gid];
  info->n     = g->n0 >> info->level;
  info->h     = g->h0 * (PetscReal)((PetscInt)1 << info->level);
  info->holes = g->lholes[lb];
  for (int d = 0; d < 3; d++) info->lo[d] = g->origin[d] + (PetscReal)(info->ijk[d] * g->n0) * g->h0;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridGetMortonOrder(PffGrid g, PetscInt *nactive, const PetscInt **gids)
{
  PetscFunctionBeginUser;
  PetscCall(PffGridCheckSetUp(g));
  *nactive = g->nactive;
  *gids    = g->order;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridGetLocalIndex(PffGrid g, PetscInt gid, PetscInt *lb)
{
  PetscFunctionBeginUser;
  PetscCall(PffGridCheckSetUp(g));
  *lb = (gid >= 0 && gid < g->nblocks) ? g->local[gid] : -1;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridGetCellNumbering(PffGrid g, PetscInt gid, PetscInt64 *first, PetscInt64 *nowned,
                                       PetscInt64 *rstart, PetscInt64 *ntotal)
{
  PetscFunctionBeginUser;
  PetscCall(PffGridCheckSetUp(g));
  if (first) {
    PetscCheck(gid >= 0 && gid < g->nblocks && g->level[gid] >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
               "block %" PetscInt_FMT " is not an active block", gid);
    *first = g->rankCellStart[g->owner[gid]] + g->offset[gid];
  }
  if (nowned) *nowned = g->ncells;
  if (rstart) *rstart = g->rankCellStart[g->rank];
  if (ntotal) *ntotal = g->rankCellStart[g->size];
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridGetPartitionQuality(PffGrid g, PffPartitionQuality *q)
{
  PetscFunctionBeginUser;
  PetscCall(PffGridCheckSetUp(g));
  *q = g->quality;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridGetCellCounts(PffGrid g, PetscInt64 perLevel[PFF_GRID_MAX_LEVELS], PetscInt64 *total)
{
  PetscInt64 sum = 0, pl[PFF_GRID_MAX_LEVELS] = {0};

  PetscFunctionBeginUser;
  PetscCall(PffGridCheckSetUp(g));
  for (PetscInt a = 0; a < g->nactive; a++) {
    const PetscInt   l = g->level[g->order[a]];
    const PetscInt64 n = g->n0 >> l;
    pl[l] += n * n * n;
    sum += n * n * n;
  }
  if (perLevel)
    for (int l = 0; l < PFF_GRID_MAX_LEVELS; l++) perLevel[l] = pl[l];
  if (total) *total = sum;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridView(PffGrid g, PetscViewer viewer)
{
  PetscBool  isascii;
  PetscInt64 pl[PFF_GRID_MAX_LEVELS], total;

  PetscFunctionBeginUser;
  if (!viewer) PetscCall(PetscViewerASCIIGetStdout(g->comm, &viewer));
  PetscCall(PetscObjectTypeCompare((PetscObject)viewer, PETSCVIEWERASCII, &isascii));
  if (!isascii) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PffGridCheckSetUp(g));
  PetscCall(PffGridGetCellCounts(g, pl, &total));
  PetscCall(PetscViewerASCIIPrintf(viewer,
                                   "MSBG: %" PetscInt_FMT "x%" PetscInt_FMT "x%" PetscInt_FMT
                                   " cells, block size %" PetscInt_FMT ", raster %" PetscInt_FMT "x%" PetscInt_FMT
                                   "x%" PetscInt_FMT ", periodic %s%s%s\n",
                                   g->cells[0], g->cells[1], g->cells[2], g->n0, g->nb[0], g->nb[1], g->nb[2],
                                   g->periodic[0] ? "x" : "", g->periodic[1] ? "y" : "", g->periodic[2] ? "z" : ""));
  PetscCall(PetscViewerASCIIPrintf(viewer,
                                   "  active blocks %" PetscInt_FMT " of %" PetscInt_FMT
                                   ", active cells %" PetscInt64_FMT " (%.2f%% of the uniform grid)\n",
                                   g->nactive, g->nblocks, total,
                                   100.0 * (double)total / ((double)g->cells[0] * g->cells[1] * g->cells[2])));
  for (PetscInt l = 0; l < g->nlevels; l++)
    PetscCall(PetscViewerASCIIPrintf(viewer, "  level %" PetscInt_FMT ": %" PetscInt64_FMT " cells\n", l, pl[l]));
  PetscCall(PetscViewerASCIIPrintf(
      viewer,
      "  partition %s on %d ranks: imbalance %.3f, cut faces %" PetscInt_FMT ", halo bytes/rank max %.0f mean %.0f\n",
      PffPartitionTypes[g->ptype], g->size, (double)g->quality.imbalance, g->quality.cutFaces,
      (double)g->quality.haloBytesMax, (double)g->quality.haloBytesMean));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffGridViewFromOptions(PffGrid g, const char name[])
{
  PetscViewer       viewer;
  PetscViewerFormat format;
  PetscBool         flg;

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsGetViewer(g->comm, NULL, NULL, name, &viewer, &format, &flg));
  if (flg) {
    PetscCall(PetscViewerPushFormat(viewer, format));
    PetscCall(PffGridView(g, viewer));
    PetscCall(PetscViewerPopFormat(viewer));
    PetscCall(PetscViewerDestroy(&viewer));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}
