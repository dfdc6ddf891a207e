/* Morton layout of a frame (Output stage and restart). A frame stores the active blocks in global
   Morton order, so the file does not depend on the partition: block p occupies row p of /blocks and
   cells [offset[p], offset[p+1]) of every /fields dataset, where offset is the prefix sum of n^3,
   n = n0 >> level. Each rank computes the whole offset array from the replicated raster and selects
   its own blocks as a union of hyperslabs, one per run of consecutive Morton positions: a Morton
   partition gives one run per rank, a METIS partition a few. */
#include "h5util.h"

PetscErrorCode PffIOLayoutCreate_Private(PffGrid grid, PffFrameLayout *L)
{
  const PetscInt *level;
  PetscInt        nb[3], n0, nlocal, k = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscMemzero(L, sizeof(*L)));
  PetscCall(PffGridGetRaster(grid, nb, &level, NULL));
  PetscCall(PffGridGetSizes(grid, &n0, NULL, NULL, NULL, NULL));
  PetscCall(PffGridGetMortonOrder(grid, &L->nactive, &L->order));
  PetscCall(PffGridGetLocalBlocks(grid, &nlocal));
  L->nlocal = nlocal;
  PetscCall(PetscMalloc1(L->nactive + 1, &L->offset));
  PetscCall(PetscMalloc4(nlocal, &L->lpos, nlocal, &L->lb, nlocal, &L->ln, nlocal + 1, &L->run));
  L->offset[0] = 0;
  for (PetscInt p = 0; p < L->nactive; p++) {
    const PetscInt   gid = L->order[p];
    const PetscInt   n   = n0 >> level[gid];
    const PetscInt64 nc  = (PetscInt64)n * n * n;
    PetscInt         lb;

    L->offset[p + 1] = L->offset[p] + nc;
    PetscCall(PffGridGetLocalIndex(grid, gid, &lb));
    if (lb < 0) continue;
    PetscCheck(k < nlocal, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "the grid reports %" PetscInt_FMT " owned blocks but owns more", nlocal);
    L->lpos[k] = p;
    L->lb[k]   = lb;
    L->ln[k]   = n;
    L->ncells += nc;
    if (k == 0 || L->lpos[k - 1] != p - 1) L->run[L->nruns++] = k;
    k++;
  }
  PetscCheck(k == nlocal, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "the grid reports %" PetscInt_FMT " owned blocks but only %" PetscInt_FMT " are in its Morton order",
             nlocal, k);
  L->run[L->nruns] = nlocal;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffIOLayoutDestroy_Private(PffFrameLayout *L)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree(L->offset));
  PetscCall(PetscFree4(L->lpos, L->lb, L->ln, L->run));
  PetscCall(PetscMemzero(L, sizeof(*L)));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffIOSelectBlocks_Private(const PffFrameLayout *L, hid_t space)
{
  hsize_t dims[2] = {0, 1};
  int     ndims;

  PetscFunctionBeginUser;
  PffCallHDF5(ndims = H5Sget_simple_extent_ndims(space));
  PetscCheck(ndims == 1 || ndims == 2, PETSC_COMM_SELF, PETSC_ERR_PLIB, "block dataspaces have 1 or 2 dimensions");
  PffCallHDF5(H5Sget_simple_extent_dims(space, dims, NULL));
  PffCallHDF5(H5Sselect_none(space));
  for (PetscInt r = 0; r < L->nruns; r++) {
    const hsize_t start[2] = {(hsize_t)L->lpos[L->run[r]], 0};
    const hsize_t count[2] = {(hsize_t)(L->run[r + 1] - L->run[r]), dims[1]};
    PffCallHDF5(H5Sselect_hyperslab(space, H5S_SELECT_OR, start, NULL, count, NULL));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffIOSelectCells_Private(const PffFrameLayout *L, hid_t space)
{
  PetscFunctionBeginUser;
  PffCallHDF5(H5Sselect_none(space));
  for (PetscInt r = 0; r < L->nruns; r++) {
    const PetscInt first = L->lpos[L->run[r]], last = L->lpos[L->run[r + 1] - 1];
    const hsize_t  start = (hsize_t)L->offset[first], count = (hsize_t)(L->offset[last + 1] - L->offset[first]);
    PffCallHDF5(H5Sselect_hyperslab(space, H5S_SELECT_OR, &start, NULL, &count, NULL));
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffIOCreateMemSpace_Private(hsize_t n, hsize_t ncol, hid_t *space)
{
  /* HDF5 wants at least one element in a simple dataspace; a rank without blocks selects none of it. */
  const hsize_t dims[2] = {n > 0 ? n : 1, ncol};

  PetscFunctionBeginUser;
  PffCallHDF5(*space = H5Screate_simple(ncol > 0 ? 2 : 1, dims, NULL));
  if (n == 0) PffCallHDF5(H5Sselect_none(*space));
  PetscFunctionReturn(PETSC_SUCCESS);
}
