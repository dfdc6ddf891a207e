/* Unused options are errors: a misspelt key must not silently fall back to a default. */
#include <pff.h>

PetscErrorCode PffOptionsCheckUnused(MPI_Comm comm)
{
  PetscInt  n     = 0;
  char    **names = NULL, **values = NULL;
  PetscBool help = PETSC_FALSE;

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsHasName(NULL, NULL, "-help", &help));
  if (help) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscOptionsLeftGet(NULL, &n, &names, &values));
  if (n > 0) {
    char key[256];
    PetscCall(PetscSNPrintf(key, sizeof(key), "-%s", names[0]));
    PetscCall(PetscOptionsLeftRestore(NULL, &n, &names, &values));
    SETERRQ(comm, PETSC_ERR_ARG_WRONG,
            "unknown option %s (misspelt, or not used by this scene; -help lists every option)", key);
  }
  PetscCall(PetscOptionsLeftRestore(NULL, &n, &names, &values));
  PetscFunctionReturn(PETSC_SUCCESS);
}
