/* core: package registration, log events, option checks, progress line, Morton codes. */
#pragma once

#include <stdint.h>
#include <petscsys.h>
#include <petscviewer.h>

#if PETSC_VERSION_LT(3, 19, 0) && !defined(PETSC_SUCCESS)
#define PETSC_SUCCESS ((PetscErrorCode)0)
#endif

/* Class id and log events, registered once by PffInitializePackage(). */
PETSC_EXTERN PetscClassId  PFF_CLASSID;
PETSC_EXTERN PetscLogEvent PFF_GridSetUp, PFF_GridAdapt, PFF_GridRefine, PFF_GridPartition, PFF_HaloSetUp,
    PFF_HaloBegin, PFF_HaloEnd, PFF_HaloRevBegin, PFF_HaloRevEnd, PFF_GridInterp, PFF_GridLaplacian, PFF_IOWrite,
    PFF_IORead, PFF_PartSeed, PFF_PartAdapt, PFF_FlowAdaptDist, PFF_FlowAdaptMap, PFF_PartBin, PFF_PartMigrate, PFF_P2G,
    PFF_G2P, PFF_Advect, PFF_PressSetUp, PFF_PressAssemble, PFF_PressSolve, PFF_PhaseField, PFF_Forces, PFF_FlowExtrap,
    PFF_CkptWrite, PFF_CkptRead, PFF_MGSetUp, PFF_MGApply, PFF_MGSmooth, PFF_MGCoarse, PFF_FlowRefBodies, PFF_TallBuild,
    PFF_TallSizing, PFF_FlowBandAdvect, PFF_FlowBandSeed, PFF_FlowBandDist;
/* pffmg's work on each multigrid level (smoothing and the transfers to and from the next level, not the levels
   below): MGLevel0 .. MGLevel6, and MGLevel7+ for all deeper levels together. */
#define PFF_MG_LOG_LEVELS 8
PETSC_EXTERN PetscLogEvent PFF_MGLevel[PFF_MG_LOG_LEVELS];

/* Registers the class id and every log event. Not collective; idempotent. */
PETSC_EXTERN PetscErrorCode PffInitializePackage(void);

/* Large arrays on transparent huge pages (src/core/memory.c): PffAdviseHugePages(p, bytes) advises the whole 2 MiB
   pages inside an array of at least 4 MiB, if -sim_huge_pages (default true, read by
   PffHugePagesSetFromOptions(), collective) is on. Call it before the array is first written. */
PETSC_EXTERN void           PffAdviseHugePages(void *p, size_t bytes);
PETSC_EXTERN PetscErrorCode PffHugePagesSetFromOptions(MPI_Comm comm);
PETSC_EXTERN PetscBool      PffHugePagesEnabled(void);

/* Fails with one message naming the first option that no object read (a misspelt or
   unknown key). Collective. Call once all SetFromOptions() have run. */
PETSC_EXTERN PetscErrorCode PffOptionsCheckUnused(MPI_Comm comm);

/* Why an input file cannot be read ("no such file or not readable", "is a directory", "is not a regular
   file"), or NULL. Plain C: also before PetscInitialize. */
PETSC_EXTERN const char *PffFileProblem(const char path[]);

/* Strict option readers, used inside PetscOptionsBegin/End like PetscOptionsReal() and friends. They
   read the raw text first and fail with "-KEY VALUE is invalid: WHY" on a value that is not a number,
   not finite, beyond +-1e12, not an integer, not a boolean, or a list longer than *n; then they call
   PETSc's reader, so -help and the used-option accounting stay PETSc's. Collective on the
   PetscOptionsBegin communicator. */
PETSC_EXTERN PetscErrorCode PffOptionsReal_Private(PetscOptionItems *, const char[], const char[], const char[],
                                                   PetscReal, PetscReal *, PetscBool *);
PETSC_EXTERN PetscErrorCode PffOptionsInt_Private(PetscOptionItems *, const char[], const char[], const char[],
                                                  PetscInt, PetscInt *, PetscBool *, PetscInt);
PETSC_EXTERN PetscErrorCode PffOptionsBool_Private(PetscOptionItems *, const char[], const char[], const char[],
                                                   PetscBool, PetscBool *, PetscBool *);
PETSC_EXTERN PetscErrorCode PffOptionsRealArray_Private(PetscOptionItems *, const char[], const char[], const char[],
                                                        PetscReal[], PetscInt *, PetscBool *);
PETSC_EXTERN PetscErrorCode PffOptionsIntArray_Private(PetscOptionItems *, const char[], const char[], const char[],
                                                       PetscInt[], PetscInt *, PetscBool *);
PETSC_EXTERN PetscErrorCode PffOptionsEnum_Private(PetscOptionItems *, const char[], const char[], const char[],
                                                   const char *const *, PetscEnum, PetscEnum *, PetscBool *);
#define PffOptionsEnum(a, b, c, d, e, f, g) PffOptionsEnum_Private(PetscOptionsObject, a, b, c, d, e, f, g)
#define PffOptionsReal(a, b, c, d, e, f) PffOptionsReal_Private(PetscOptionsObject, a, b, c, d, e, f)
#define PffOptionsInt(a, b, c, d, e, f) PffOptionsInt_Private(PetscOptionsObject, a, b, c, d, e, f, PETSC_MIN_INT)
#define PffOptionsBoundedInt(a, b, c, d, e, f, g) PffOptionsInt_Private(PetscOptionsObject, a, b, c, d, e, f, g)
#define PffOptionsBool(a, b, c, d, e, f) PffOptionsBool_Private(PetscOptionsObject, a, b, c, d, e, f)
#define PffOptionsRealArray(a, b, c, d, e, f) PffOptionsRealArray_Private(PetscOptionsObject, a, b, c, d, e, f)
#define PffOptionsIntArray(a, b, c, d, e, f) PffOptionsIntArray_Private(PetscOptionsObject, a, b, c, d, e, f)

/* Checks a YAML scene file (-options_file_yaml) before PETSc reads it: a readable regular file holding one
   UTF-8 document whose top level is a mapping of known sections and options (PETSc's YAML subset, no
   aliases, at most 8 mappings deep). Returns 0 if it is fine, else 1 with msg (at most len characters)
   holding one line "path:line:column: problem" (1-based) or "path: problem". Plain C: callable before
   PetscInitialize. Not collective. */
PETSC_EXTERN int PffYAMLCheckFile(const char path[], char msg[], size_t len);

/* The same checks for an option that another object reads (e.g. a PETSc KSP option), before it does:
   if key is set, its value must parse and lie in (lo, hi) if open, else in [lo, hi], described by range
   ("in (0, 1)"); an integer must lie in [lo, hi]. Collective. */
PETSC_EXTERN PetscErrorCode PffOptionsCheckReal(MPI_Comm comm, const char key[], PetscReal lo, PetscReal hi,
                                                PetscBool open, const char range[]);
PETSC_EXTERN PetscErrorCode PffOptionsCheckInt(MPI_Comm comm, const char key[], PetscInt lo, PetscInt hi);

/* Library versions and build revision as one line, e.g. for HDF5 attributes. Not collective.
   buf receives at most len characters. */
PETSC_EXTERN PetscErrorCode PffGetVersionString(char buf[], size_t len);

/* One line per step on rank 0: step, simulated time, wall time per step, ETA. */
typedef struct {
  PetscLogDouble start, last;
  PetscReal      t0, tend;
  PetscInt       step0, nsteps;
} PffProgress;
/* Starts the clock at simulated time t0 and step step0 (non-zero after a restart, so that the ETA
   uses the rate of this run only). tend (simulated end time) or nsteps (step count) gives the ETA;
   pass 0 for unknown. */
PETSC_EXTERN PetscErrorCode PffProgressStart(PffProgress *p, PetscReal t0, PetscReal tend, PetscInt step0,
                                             PetscInt nsteps);
/* Estimated wall time left after `elapsed` seconds since the start, at step `step` and time t: the
   rate since the start extrapolated to tend and to nsteps, the sooner of the two when both are
   known; -1 when neither is known yet. Not collective. */
PETSC_EXTERN double PffProgressETA(const PffProgress *p, PetscInt step, PetscReal t, double elapsed);
/* Prints "step <s> t <t> wall/step <w> s ETA <e> s <extra>". Collective (reduces nothing; rank 0 prints). */
PETSC_EXTERN PetscErrorCode PffProgressPrint(MPI_Comm comm, PffProgress *p, PetscInt step, PetscReal t,
                                             const char extra[]);

/* Morton (Z-order) key of block coordinates, 21 bits per axis, x in the lowest bit. */
static inline uint64_t PffMortonSpread_Private(uint64_t v)
{
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffULL;
  v = (v | v << 16) & 0x1f0000ff0000ffULL;
  v = (v | v << 8) & 0x100f00f00f00f00fULL;
  v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
  v = (v | v << 2) & 0x1249249249249249ULL;
  return v;
}
static inline uint64_t PffMortonCompact_Private(uint64_t v)
{
  v &= 0x1249249249249249ULL;
  v = (v ^ (v >> 2)) & 0x10c30c30c30c30c3ULL;
  v = (v ^ (v >> 4)) & 0x100f00f00f00f00fULL;
  v = (v ^ (v >> 8)) & 0x1f0000ff0000ffULL;
  v = (v ^ (v >> 16)) & 0x1f00000000ffffULL;
  v = (v ^ (v >> 32)) & 0x1fffff;
  return v;
}
static inline uint64_t PffMortonEncode(uint32_t x, uint32_t y, uint32_t z)
{
  return PffMortonSpread_Private(x) | PffMortonSpread_Private(y) << 1 | PffMortonSpread_Private(z) << 2;
}
static inline void PffMortonDecode(uint64_t key, uint32_t *x, uint32_t *y, uint32_t *z)
{
  *x = (uint32_t)PffMortonCompact_Private(key);
  *y = (uint32_t)PffMortonCompact_Private(key >> 1);
  *z = (uint32_t)PffMortonCompact_Private(key >> 2);
}
