/* pfflip: the driver. Options -> scene set-up (every option read and checked) -> run -> finalize.

   mpiexec -n 2 build/bin/pfflip -options_file_yaml config/grid_demo.yaml [-key value ...]

   Input errors (bad or unknown options, missing files) print one line naming the key and exit
   with status 1; internal errors keep PETSc's full traceback. */
#include <pff.h>
#include <unistd.h>

static const char usage[] =
    "pfflip: Adaptive Phase-Field-FLIP on Multiresolution Sparse Block Grids.\n"
    "Usage: mpiexec -n <ranks> pfflip -options_file_yaml config/<scene>.yaml [-key value ...]\n";

static PetscBool PffIsInputError(PetscErrorCode n)
{
  switch (n) {
  case PETSC_ERR_ARG_OUTOFRANGE:
  case PETSC_ERR_ARG_WRONG:
  case PETSC_ERR_ARG_SIZ:
  case PETSC_ERR_ARG_INCOMP:
  case PETSC_ERR_ARG_UNKNOWN_TYPE:
  case PETSC_ERR_ARG_WRONGSTATE:
  case PETSC_ERR_FILE_OPEN:
  case PETSC_ERR_FILE_READ:
  case PETSC_ERR_FILE_UNEXPECTED:
  case PETSC_ERR_USER_INPUT:
  case PETSC_ERR_USER: /* PETSc's own option parsing, e.g. an unknown enum value */
    return PETSC_TRUE;
  default:
    return PETSC_FALSE;
  }
}

typedef struct {
  PetscBool collective; /* every rank met the error, so finalizing cleanly cannot hang */
} PffErrorState;

/* Prints an input error as one line. An error raised on a communicator that spans every rank, or by
   PETSc's own option parsing (options are the same on every rank), is met by all ranks, and world
   rank 0 speaks for them. Any other input error is printed by the rank that met it, and main then
   aborts, since the other ranks may be waiting in a collective. Other errors get PETSc's traceback. */
static PetscErrorCode PffErrorHandler(MPI_Comm comm, int line, const char *fun, const char *file, PetscErrorCode n,
                                      PetscErrorType p, const char *mess, void *ctx)
{
  PffErrorState *st = (PffErrorState *)ctx;
  if (!PffIsInputError(n)) return PetscTraceBackErrorHandler(comm, line, fun, file, n, p, mess, ctx);
  if (p == PETSC_ERROR_INITIAL) {
    PetscMPIInt rank = 0, size = 1, wsize = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &wsize);
    if (comm != MPI_COMM_NULL) MPI_Comm_size(comm, &size);
    st->collective = (PetscBool)(size == wsize || n == PETSC_ERR_USER);
    if (!st->collective)
      fprintf(stderr, "pfflip: error on rank %d: %s\n", rank, mess ? mess : "input error");
    else if (rank == 0)
      fprintf(stderr, "pfflip: error: %s\n", mess ? mess : "input error");
  }
  return n;
}

/* PETSc reads option files inside PetscInitialize, where a missing file ends in a traceback; this
   only checks that the named files exist, so the user gets one line naming the key instead. */
static int PffCheckOptionFiles(int argc, char **argv)
{
  int rank = 0, bad = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  for (int i = 1; i + 1 < argc; i++) {
    if (strcmp(argv[i], "-options_file_yaml") && strcmp(argv[i], "-options_file")) continue;
    if (access(argv[i + 1], R_OK)) {
      if (rank == 0 && !bad)
        fprintf(stderr, "pfflip: error: %s %s: no such file or not readable\n", argv[i], argv[i + 1]);
      bad = 1;
    }
  }
  return bad;
}

int main(int argc, char **argv)
{
  PffScene       scene = NULL;
  PetscBool      help  = PETSC_FALSE;
  PetscErrorCode ierr;
  PffErrorState  errstate = {PETSC_TRUE};

  if (MPI_Init(&argc, &argv) != MPI_SUCCESS) return 1;
  if (PffCheckOptionFiles(argc, argv)) {
    MPI_Finalize();
    return 1;
  }
  PetscCall(PetscInitialize(&argc, &argv, NULL, usage));
  PetscCall(PetscPushErrorHandler(PffErrorHandler, &errstate));
  PetscCall(PetscOptionsHasName(NULL, NULL, "-help", &help));
  ierr = PffSceneCreate(PETSC_COMM_WORLD, &scene);
  if (!ierr) ierr = PffSceneSetFromOptions(scene);
  if (!ierr) ierr = PffOptionsCheckUnused(PETSC_COMM_WORLD);
  if (!ierr && !help) ierr = PffSceneRun(scene);
  if (ierr) {
    /* an input error found on every rank ends cleanly; anything else may have left ranks behind */
    if (!PffIsInputError(ierr) || !errstate.collective) MPI_Abort(MPI_COMM_WORLD, 1);
    (void)PffSceneDestroy(&scene);
    (void)PetscFinalize();
    MPI_Finalize();
    return 1;
  }
  PetscCall(PffSceneDestroy(&scene));
  PetscCall(PetscFinalize());
  return MPI_Finalize() == MPI_SUCCESS ? 0 : 1;
}
