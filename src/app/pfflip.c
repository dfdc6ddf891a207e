/* pfflip: the driver. Options -> scene set-up (every option read and checked) -> run -> finalize.

   mpiexec -n 2 build/bin/pfflip -options_file_yaml config/grid_demo.yaml [-key value ...]

   Input errors (bad or unknown options, missing files) print one line naming the key and exit
   with status 1; internal errors keep PETSc's full traceback. */
#include <pff.h>
#include <ctype.h>
#include <sys/stat.h>

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
  case PETSC_ERR_USER:          /* PETSc's own option parsing, e.g. an unknown enum value */
  case PETSC_ERR_NOT_CONVERGED: /* a run that failed (a solve, a non-finite field, a scene's check): its reason is one
                                   line */
    return PETSC_TRUE;
  default:
    return PETSC_FALSE;
  }
}

/* An option key such as -grid_h, as PETSc's PetscOptionsValidKey() decides: a value otherwise, also a
   negative number such as -0.5, -.5 or -inf. */
static int PffIsOptionKey(const char *arg)
{
  char *end;
  if (arg[0] != '-') return 0;
  if (arg[1] == '-') arg++;
  if (!isalpha((unsigned char)arg[1])) return 0;
  (void)strtod(arg, &end);
  return end == arg || *end == '_' || isalnum((unsigned char)*end);
}

/* PETSc's option parser reports a value it cannot read ("Input string abc has no numeric value") on
   PETSC_COMM_SELF and without the key. Options are the same on every rank, so every rank meets it;
   this finds the key that holds the value, so the line names it like our own checks do. */
static PetscBool PffNameBadOption(const char *mess, char *out, size_t len)
{
  static const char *const pat[][2] = {
      {"Input string ", " has no numeric value"},  {"Input string ", " has no integer value"},
      {"Unknown logical value: ", NULL},           {"Unable to find requested KSP type ", NULL},
      {"Unable to find requested PC type ", NULL}, {"Unsupported viewer ", NULL},
  };
  char value[256] = "", *all = NULL;
  int  found = 0;

  for (size_t k = 0; k < sizeof(pat) / sizeof(pat[0]) && !value[0]; k++) {
    size_t      n0 = strlen(pat[k][0]);
    const char *end;
    if (strncmp(mess, pat[k][0], n0)) continue;
    end = pat[k][1] ? strstr(mess + n0, pat[k][1]) : mess + strlen(mess);
    if (!end || end == mess + n0 || (size_t)(end - mess - n0) >= sizeof(value)) continue;
    memcpy(value, mess + n0, (size_t)(end - mess - n0));
    value[end - mess - n0] = 0;
  }
  {
    /* PETSc's enum parser names the key already, in its own shape: rewrite it in ours */
    const char *u = "Unknown option ", *f = strstr(mess, " for "), *a = strstr(mess, ". Available options: ");
    if (!strncmp(mess, u, strlen(u)) && f && a && a > f) {
      snprintf(out, len, "%.*s %.*s is invalid: must be one of %s", (int)(a - f - 5), f + 5,
               (int)(f - mess - strlen(u)), mess + strlen(u), a + strlen(". Available options: "));
      return PETSC_TRUE;
    }
  }
  if (!value[0] || PetscOptionsGetAll(NULL, &all) || !all) return PETSC_FALSE;
  /* "-key value -key value ...", keys told from values as on the command line */
  const char *prev = NULL;
  for (char *save = NULL, *tok = strtok_r(all, " ", &save); tok && !found; tok = strtok_r(NULL, " ", &save)) {
    const int key = PffIsOptionKey(tok);
    if (!key && prev && !strcmp(tok, value)) {
      snprintf(out, len, "%s %s is invalid: %s", prev, value,
               strstr(mess, "logical")   ? "must be true or false"
               : strstr(mess, "integer") ? "not an integer"
               : strstr(mess, " type ")  ? "unknown type (-help lists the types)"
               : strstr(mess, "viewer")  ? "unknown viewer"
                                         : "not a number");
      found = 1;
    }
    prev = key ? tok : NULL;
  }
  (void)PetscFree(all);
  return (PetscBool)found;
}

typedef struct {
  PetscBool collective; /* every rank met the error, so finalizing cleanly cannot hang */
  PetscBool input;      /* the error being handled is one line for the user, not a traceback */
} PffErrorState;

/* Prints an input error as one line. An error raised on a communicator that spans every rank, or by
   PETSc's own option parsing (options are the same on every rank), is met by all ranks, and world
   rank 0 speaks for them. Any other input error is printed by the rank that met it, and main then
   aborts, since the other ranks may be waiting in a collective. Other errors get PETSc's traceback. */
static PetscErrorCode PffErrorHandler(MPI_Comm comm, int line, const char *fun, const char *file, PetscErrorCode n,
                                      PetscErrorType p, const char *mess, void *ctx)
{
  PffErrorState *st = (PffErrorState *)ctx;
  char           named[512];

  if (p == PETSC_ERROR_INITIAL) {
    st->input = PETSC_FALSE;
    if (mess && PffNameBadOption(mess, named, sizeof(named))) {
      st->input = PETSC_TRUE;
      mess      = named;
    } else
      st->input = PffIsInputError(n);
    if (!st->input) return PetscTraceBackErrorHandler(comm, line, fun, file, n, p, mess, ctx);
    PetscMPIInt rank = 0, size = 1, wsize = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &wsize);
    if (comm != MPI_COMM_NULL) MPI_Comm_size(comm, &size);
    /* a value PETSc could not read is in every rank's options */
    st->collective = (PetscBool)(size == wsize || n == PETSC_ERR_USER || mess == named);
    if (!st->collective)
      fprintf(stderr, "pfflip: error on rank %d: %s\n", rank, mess ? mess : "input error");
    else if (rank == 0)
      fprintf(stderr, "pfflip: error: %s\n", mess ? mess : "input error");
  } else if (!st->input)
    return PetscTraceBackErrorHandler(comm, line, fun, file, n, p, mess, ctx);
  return n;
}

/* -options_file: PETSc only needs a readable regular file (its format errors name the line). */
static int PffCheckOptionFile(const char *path, char msg[], size_t len)
{
  struct stat st;
  const char *problem = PffFileProblem(path);
  if (problem || stat(path, &st))
    snprintf(msg, len, "%s: %s", path, problem ? problem : "cannot be read");
  else if (st.st_size > (1 << 24))
    snprintf(msg, len, "%s: larger than 16 MiB, not an option file", path);
  else {
    /* PETSc's format: "-key value" lines, comments after '#', and "alias" lines; its parser stops on
       anything else with a traceback, and a NUL byte silently ends the file */
    FILE  *fp   = fopen(path, "rb");
    size_t line = 1, col = 0;
    int    c, start = 1, bad = 0;
    if (!fp) {
      snprintf(msg, len, "%s: no such file or not readable", path);
      return 1;
    }
    while (!bad && (c = fgetc(fp)) != EOF) {
      col++;
      if (c == 0) {
        snprintf(msg, len, "%s:%zu:%zu: a NUL byte; an option file is text", path, line, col);
        bad = 1;
      } else if (c == '\n') {
        line++;
        col   = 0;
        start = 1;
      } else if (start && !isspace(c)) {
        char word[6] = {(char)c, 0};
        start        = 0;
        if (c == '-' || c == '#') continue;
        if (c == 'a' && fgets(word + 1, 5, fp) && !strncmp(word, "alias", 5)) {
          col += strlen(word) - 1;
          continue;
        }
        snprintf(msg, len, "%s:%zu:%zu: expected -key value, a comment (#) or alias on each line", path, line, col);
        bad = 1;
      }
    }
    fclose(fp);
    return bad;
  }
  return 1;
}

/* Prints the first problem of the command line and returns 1, or returns 0: a stray argument (a value
   that follows no key), an option file without a name, or a bad option file. */
static int PffCheckArgumentsLocal(int argc, char **argv)
{
  char msg[PETSC_MAX_PATH_LEN + 640];
  int  afterKey = 0;

  for (int i = 1; i < argc; i++) {
    const char *arg = argv[i];
    int         yaml;

    if (!PffIsOptionKey(arg)) {
      if (!afterKey) {
        fprintf(stderr, "pfflip: error: stray argument \"%s\" (options are -key value pairs)\n", arg);
        return 1;
      }
      afterKey = 0;
      continue;
    }
    afterKey = 1;
    yaml     = !strcmp(arg, "-options_file_yaml");
    if (!yaml && strcmp(arg, "-options_file")) continue;
    if (i + 1 == argc || PffIsOptionKey(argv[i + 1])) {
      fprintf(stderr, "pfflip: error: %s needs a file name\n", arg);
      return 1;
    }
    afterKey = 0;
    i++;
    if (yaml ? PffYAMLCheckFile(argv[i], msg, sizeof(msg)) : PffCheckOptionFile(argv[i], msg, sizeof(msg))) {
      fprintf(stderr, "pfflip: error: %s %s\n", arg, msg);
      return 1;
    }
  }
  return 0;
}

/* PETSc reads option files inside PetscInitialize, where a missing file or malformed YAML ends in a
   traceback without a line number (and a NUL byte or binary garbage may pass silently). This checks the
   command line and the option files first, so the user gets one line naming the problem. World rank 0
   checks and prints (it is also the rank on which PETSc reads the files), every rank gets the verdict. */
static int PffCheckArguments(int argc, char **argv)
{
  int rank = 0, bad = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank == 0) bad = PffCheckArgumentsLocal(argc, argv);
  MPI_Bcast(&bad, 1, MPI_INT, 0, MPI_COMM_WORLD);
  return bad;
}

int main(int argc, char **argv)
{
  PffScene       scene = NULL;
  PetscBool      help  = PETSC_FALSE;
  PetscErrorCode ierr;
  PffErrorState  errstate = {PETSC_TRUE, PETSC_FALSE};

  if (MPI_Init(&argc, &argv) != MPI_SUCCESS) return 1;
  if (PffCheckArguments(argc, argv)) {
    MPI_Finalize();
    return 1;
  }
  PetscCall(PetscInitialize(&argc, &argv, NULL, usage));
  PetscCall(PetscPushErrorHandler(PffErrorHandler, &errstate));
  PetscCall(PetscOptionsHasName(NULL, NULL, "-help", &help));
  ierr = PffHugePagesSetFromOptions(PETSC_COMM_WORLD);
  if (!ierr) ierr = PffSceneCreate(PETSC_COMM_WORLD, &scene);
  if (!ierr) ierr = PffSceneSetFromOptions(scene);
  if (!ierr) ierr = PffOptionsCheckUnused(PETSC_COMM_WORLD);
  if (!ierr && !help) ierr = PffSceneRun(scene);
  if (ierr) {
    /* an input error found on every rank ends cleanly; anything else may have left ranks behind */
    if (!errstate.input || !errstate.collective) MPI_Abort(MPI_COMM_WORLD, 1);
    (void)PffSceneDestroy(&scene);
    (void)PetscFinalize();
    MPI_Finalize();
    return 1;
  }
  PetscCall(PffSceneDestroy(&scene));
  PetscCall(PetscFinalize());
  return MPI_Finalize() == MPI_SUCCESS ? 0 : 1;
}
