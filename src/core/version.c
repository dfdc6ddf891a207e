/* The build and library versions recorded in every output file. */
#include <pff.h>
#include <hdf5.h>
#include <metis.h>
#include <omp.h>

#ifndef PFF_GIT_REVISION
#define PFF_GIT_REVISION "unknown"
#endif

PetscErrorCode PffGetVersionString(char buf[], size_t len)
{
  char     petsc[128], mpi[MPI_MAX_LIBRARY_VERSION_STRING];
  int      mpilen = 0;
  unsigned maj = 0, min = 0, rel = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscGetVersion(petsc, sizeof(petsc)));
  PetscCallMPI(MPI_Get_library_version(mpi, &mpilen));
  for (int i = 0; i < mpilen; i++) {
    if (mpi[i] == ',' || mpi[i] == '\n') {
      mpi[i] = '\0';
      break;
    }
  }
  PetscCheck(H5get_libversion(&maj, &min, &rel) >= 0, PETSC_COMM_SELF, PETSC_ERR_LIB, "H5get_libversion failed");
  PetscCall(PetscSNPrintf(buf, len, "pfflip %s; %s; %s; HDF5 %u.%u.%u; METIS %d.%d.%d; OpenMP %d", PFF_GIT_REVISION,
                          petsc, mpi, maj, min, rel, METIS_VER_MAJOR, METIS_VER_MINOR, METIS_VER_SUBMINOR, _OPENMP));
  PetscFunctionReturn(PETSC_SUCCESS);
}
