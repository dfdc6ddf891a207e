/* Scene registry: -scene picks a set-up by name; -output_dir says where its files go. */
#include "sceneimpl.h"
#include <errno.h>
#include <sys/stat.h>
#include <unistd.h>

typedef struct {
  const char *name;
  PetscErrorCode (*create)(PffScene);
} PffSceneEntry;

static const PffSceneEntry PffScenes[] = {
    {"grid_demo", PffSceneCreate_GridDemo},       {"rt3d", PffSceneCreate_RT3D},
    {"rt_paper", PffSceneCreate_RTPaper},         {"still_water", PffSceneCreate_StillWater},
    {"shear_sphere", PffSceneCreate_ShearSphere}, {"fluid", PffSceneCreate_Fluid},
};

PetscErrorCode PffSceneCreate(MPI_Comm comm, PffScene *scene)
{
  PffScene s;

  PetscFunctionBeginUser;
  PetscCall(PffInitializePackage());
  PetscCall(PetscNew(&s));
  s->comm = comm;
  PetscCall(PetscStrncpy(s->name, "grid_demo", sizeof(s->name)));
  *scene = s;
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Why path cannot hold the run's output (0 if it can): it must be a writable directory. */
static int PffSceneCheckDir(const char *path)
{
  struct stat sb;
  if (stat(path, &sb)) return errno;
  if (!S_ISDIR(sb.st_mode)) return ENOTDIR;
  return access(path, W_OK | X_OK) ? errno : 0;
}

/* Before any work: an -output_dir that exists must be a writable directory, on every rank. Creates
   nothing, so that a run stopped by a later input error leaves no trace. */
static PetscErrorCode PffSceneCheckOutputDir(PffScene s)
{
  struct stat sb;
  int         err = 0;

  PetscFunctionBeginUser;
  if (!stat(s->outdir, &sb)) err = PffSceneCheckDir(s->outdir);
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &err, 1, MPI_INT, MPI_MAX, s->comm));
  PetscCheck(!err, s->comm, PETSC_ERR_FILE_OPEN, "-output_dir %s is invalid: %s", s->outdir,
             err == ENOTDIR ? "exists and is not a directory" : strerror(err));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffSceneSetFromOptions(PffScene s)
{
  const size_t nscenes    = PETSC_STATIC_ARRAY_LENGTH(PffScenes);
  PetscInt     pick       = -1;
  char         known[256] = "";

  PetscFunctionBeginUser;
  for (size_t i = 0; i < nscenes; i++) {
    PetscCall(PetscStrlcat(known, i ? ", " : "", sizeof(known)));
    PetscCall(PetscStrlcat(known, PffScenes[i].name, sizeof(known)));
  }
  PetscOptionsBegin(s->comm, NULL, "Scene", "PffScene");
  char name[64];
  PetscCall(PetscStrncpy(name, s->name, sizeof(name)));
  PetscCall(PetscOptionsString("-scene", "Scene to run", "PffSceneCreate", name, name, sizeof(name), NULL));
  for (size_t i = 0; i < nscenes; i++)
    if (!strcmp(name, PffScenes[i].name)) pick = (PetscInt)i;
  PetscCheck(pick >= 0, s->comm, PETSC_ERR_ARG_UNKNOWN_TYPE, "-scene %s is unknown; known scenes: %s", name, known);
  PetscCall(PetscStrncpy(s->name, name, sizeof(s->name)));
  PetscCall(PetscSNPrintf(s->outdir, sizeof(s->outdir), "output/%s", s->name));
  PetscCall(PetscOptionsString("-output_dir", "Directory for frames and logs", NULL, s->outdir, s->outdir,
                               sizeof(s->outdir), NULL));
  PetscOptionsEnd();
  PetscCall(PffSceneCheckOutputDir(s));
  PetscCall(PffScenes[pick].create(s));
  if (s->ops.setfromoptions) PetscCall(s->ops.setfromoptions(s));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Creates the output directory (rank 0), then checks on every rank that it is a writable directory
   (ranks on other nodes see it through a shared file system or not at all); errors name -output_dir. */
PetscErrorCode PffSceneMakeOutputDir_Private(PffScene s)
{
  PetscMPIInt rank;
  int         err = 0;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  if (rank == 0) {
    char path[PETSC_MAX_PATH_LEN];
    PetscCall(PetscStrncpy(path, s->outdir, sizeof(path)));
    for (char *c = path + 1; *c && !err; c++) {
      if (*c != '/') continue;
      *c = '\0';
      if (mkdir(path, 0755) && errno != EEXIST) err = errno;
      *c = '/';
    }
    if (!err && mkdir(path, 0755) && errno != EEXIST) err = errno;
  }
  PetscCallMPI(MPI_Bcast(&err, 1, MPI_INT, 0, s->comm));
  if (!err) err = PffSceneCheckDir(s->outdir);
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &err, 1, MPI_INT, MPI_MAX, s->comm));
  PetscCheck(!err, s->comm, PETSC_ERR_FILE_OPEN, "-output_dir %s cannot be created or written: %s", s->outdir,
             err == ENOTDIR ? "a part of it exists and is not a directory" : strerror(err));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffSceneRun(PffScene s)
{
  PetscFunctionBeginUser;
  PetscCall(s->ops.run(s));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffSceneDestroy(PffScene *scene)
{
  PetscFunctionBeginUser;
  if (!scene || !*scene) PetscFunctionReturn(PETSC_SUCCESS);
  if ((*scene)->ops.destroy) PetscCall((*scene)->ops.destroy(*scene));
  PetscCall(PetscFree(*scene));
  PetscFunctionReturn(PETSC_SUCCESS);
}
