/* HDF5 plumbing of the io module (the Output stage and restart): error messages from the HDF5 error
   stack, the property lists of a collective MPI-IO frame, attribute helpers and the missing-file check.

   Collective metadata (H5Pset_all_coll_metadata_ops, H5Pset_coll_metadata_write) makes rank 0 read
   each attribute once and broadcast it, instead of every rank hitting the file system; it requires
   every rank to make the same metadata calls in the same order, which the writer and reader do. */
#include <errno.h>
#include <string.h>
#include <unistd.h>
#include "h5util.h"

typedef struct {
  char  *buf;
  size_t len;
} PffH5ErrorWalk;

static herr_t PffH5KeepDescription(unsigned n, const H5E_error2_t *err, void *ctx)
{
  PffH5ErrorWalk *w = (PffH5ErrorWalk *)ctx;

  (void)n;
  /* Walking downward, the last entry is the innermost one: it says what actually went wrong. */
  if (err->desc && err->desc[0]) snprintf(w->buf, w->len, "%s() %s", err->func_name ? err->func_name : "?", err->desc);
  return 0;
}

void PffHDF5ErrorMessage_Private(char buf[], size_t len)
{
  PffH5ErrorWalk w = {buf, len};

  if (len == 0) return;
  buf[0] = '\0';
  if (H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, PffH5KeepDescription, &w) < 0) buf[0] = '\0';
}

PetscErrorCode PffIOInitialize_Private(void)
{
  PetscFunctionBeginUser;
  PffCallHDF5(H5Eset_auto2(H5E_DEFAULT, NULL, NULL));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffIOGetComm_Private(PffGrid grid, MPI_Comm *comm)
{
  PetscFunctionBeginUser;
  PetscCall(PffGridGetComm(grid, comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffIOCheckReadable_Private(MPI_Comm comm, const char path[])
{
  PetscMPIInt rank;
  int         err = 0;

  PetscFunctionBeginUser;
  /* HDF5's own message for a missing file is a page of stack; check first, on one rank. */
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0 && access(path, R_OK) != 0) err = errno ? errno : EACCES;
  PetscCallMPI(MPI_Bcast(&err, 1, MPI_INT, 0, comm));
  PetscCheck(err != ENOENT, comm, PETSC_ERR_FILE_OPEN, "cannot open frame %s: no such file", path);
  PetscCheck(err == 0, comm, PETSC_ERR_FILE_OPEN, "cannot open frame %s: %s", path, strerror(err));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffIOCreateAccessList_Private(MPI_Comm comm, hid_t *fapl)
{
  PetscFunctionBeginUser;
  PffCallHDF5(*fapl = H5Pcreate(H5P_FILE_ACCESS));
  PffCallHDF5(H5Pset_fapl_mpio(*fapl, comm, MPI_INFO_NULL));
  PffCallHDF5(H5Pset_all_coll_metadata_ops(*fapl, 1));
  PffCallHDF5(H5Pset_coll_metadata_write(*fapl, 1));
  /* The 1.8 object format stores many or large attributes (the option set) densely; older readers
     (h5py, ParaView, VisIt) all read it. */
  PffCallHDF5(H5Pset_libver_bounds(*fapl, H5F_LIBVER_V18, H5F_LIBVER_V18));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffIOCreateTransferList_Private(hid_t *dxpl)
{
  PetscFunctionBeginUser;
  PffCallHDF5(*dxpl = H5Pcreate(H5P_DATASET_XFER));
  PffCallHDF5(H5Pset_dxpl_mpio(*dxpl, H5FD_MPIO_COLLECTIVE));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffH5WriteAttribute_Private(hid_t obj, const char name[], hid_t filetype, hid_t memtype, hsize_t n,
                                           const void *buf)
{
  hid_t space, attr;

  PetscFunctionBeginUser;
  if (n == 0)
    PffCallHDF5(space = H5Screate(H5S_SCALAR));
  else
    PffCallHDF5(space = H5Screate_simple(1, &n, NULL));
  PffCallHDF5(attr = H5Acreate2(obj, name, filetype, space, H5P_DEFAULT, H5P_DEFAULT));
  PffCallHDF5(H5Awrite(attr, memtype, buf));
  PffCallHDF5(H5Aclose(attr));
  PffCallHDF5(H5Sclose(space));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffH5WriteAttributeString_Private(hid_t obj, const char name[], const char value[])
{
  hid_t type;

  PetscFunctionBeginUser;
  PffCallHDF5(type = H5Tcopy(H5T_C_S1));
  PffCallHDF5(H5Tset_size(type, strlen(value) + 1));
  PffCallHDF5(H5Tset_strpad(type, H5T_STR_NULLTERM));
  PetscCall(PffH5WriteAttribute_Private(obj, name, type, type, 0, value));
  PffCallHDF5(H5Tclose(type));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffH5ReadAttribute_Private(hid_t obj, const char name[], hid_t memtype, hsize_t n, void *buf,
                                          PetscBool *found)
{
  hid_t    attr, space;
  htri_t   exists;
  hssize_t npoints;
  int      ndims;

  PetscFunctionBeginUser;
  *found = PETSC_FALSE;
  PffCallHDF5(exists = H5Aexists(obj, name));
  if (!exists) PetscFunctionReturn(PETSC_SUCCESS);
  PffCallHDF5(attr = H5Aopen(obj, name, H5P_DEFAULT));
  PffCallHDF5(space = H5Aget_space(attr));
  PffCallHDF5(npoints = H5Sget_simple_extent_npoints(space));
  PffCallHDF5(ndims = H5Sget_simple_extent_ndims(space));
  if ((n == 0 && ndims == 0) || (n > 0 && ndims == 1 && (hsize_t)npoints == n)) {
    PffCallHDF5(H5Aread(attr, memtype, buf));
    *found = PETSC_TRUE;
  }
  PffCallHDF5(H5Sclose(space));
  PffCallHDF5(H5Aclose(attr));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffH5ReadAttributeString_Private(hid_t obj, const char name[], char **value)
{
  hid_t  attr, type, memtype;
  htri_t exists, isvlen;

  PetscFunctionBeginUser;
  *value = NULL;
  PffCallHDF5(exists = H5Aexists(obj, name));
  if (!exists) PetscFunctionReturn(PETSC_SUCCESS);
  PffCallHDF5(attr = H5Aopen(obj, name, H5P_DEFAULT));
  PffCallHDF5(type = H5Aget_type(attr));
  if (H5Tget_class(type) == H5T_STRING) {
    PffCallHDF5(isvlen = H5Tis_variable_str(type));
    PffCallHDF5(memtype = H5Tcopy(H5T_C_S1));
    if (isvlen) {
      /* Files written by h5py hold variable-length strings. */
      char *s = NULL;
      PffCallHDF5(H5Tset_size(memtype, H5T_VARIABLE));
      PffCallHDF5(H5Aread(attr, memtype, &s));
      PetscCall(PetscStrallocpy(s ? s : "", value));
      if (s) PffCallHDF5(H5free_memory(s));
    } else {
      const size_t size = H5Tget_size(type);
      PffCallHDF5(H5Tset_size(memtype, size + 1));
      PffCallHDF5(H5Tset_strpad(memtype, H5T_STR_NULLTERM));
      PetscCall(PetscCalloc1(size + 1, value));
      PffCallHDF5(H5Aread(attr, memtype, *value));
    }
    PffCallHDF5(H5Tclose(memtype));
  }
  PffCallHDF5(H5Tclose(type));
  PffCallHDF5(H5Aclose(attr));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffH5CreateDataset_Private(hid_t loc, const char name[], hid_t filetype, int rank, const hsize_t dims[],
                                          hid_t *dset)
{
  hid_t  space, dcpl;
  htri_t exists;

  PetscFunctionBeginUser;
  PffCallHDF5(exists = H5Lexists(loc, name, H5P_DEFAULT));
  PetscCheck(!exists, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG,
             "two grid channels map to the frame dataset %s; rename one of them", name);
  PffCallHDF5(space = H5Screate_simple(rank, dims, NULL));
  PffCallHDF5(dcpl = H5Pcreate(H5P_DATASET_CREATE));
  PffCallHDF5(H5Pset_fill_time(dcpl, H5D_FILL_TIME_NEVER));
  PffCallHDF5(*dset = H5Dcreate2(loc, name, filetype, space, H5P_DEFAULT, dcpl, H5P_DEFAULT));
  PffCallHDF5(H5Pclose(dcpl));
  PffCallHDF5(H5Sclose(space));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffIOFieldName_Private(const char name[], PffChannelKind kind, PetscInt comp, char buf[], size_t len)
{
  PetscFunctionBeginUser;
  PetscCheck(name[0] && !strchr(name, '/') && strcmp(name, ".") && strcmp(name, ".."), PETSC_COMM_SELF,
             PETSC_ERR_ARG_WRONG, "channel name \"%s\" cannot name an HDF5 dataset (empty, \".\" or contains '/')",
             name);
  if (kind == PFF_CHANNEL_FACE)
    PetscCall(PetscSNPrintf(buf, len, "%s_%c", name, (char)('x' + comp)));
  else
    PetscCall(PetscSNPrintf(buf, len, "%s", name));
  PetscFunctionReturn(PETSC_SUCCESS);
}
