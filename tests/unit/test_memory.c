/* Unit test of the huge-page advice (core.h, src/core/memory.c): PffAdviseHugePages and -sim_huge_pages.

   With huge pages on (the default), the whole 2 MiB pages inside a 16 MiB array carry the kernel's "hg" flag
   (MADV_HUGEPAGE, VmFlags in /proc/self/smaps) after the advice, the array keeps its values and is usable; with
   -sim_huge_pages false (or on a kernel without transparent huge pages) they do not. The particle store and the
   grid's channels take this advice.

   Sample run:  ./test_memory [-sim_huge_pages false]
   Prints:      memory ok: huge pages <on|off>, <n> checks */
#include "pfftest.h"
#include <stdint.h>
#include <unistd.h>

static const char help[] = "Huge-page advice for large arrays.\n";

/* Whether the mapping that holds address a is advised MADV_HUGEPAGE (VmFlags "hg"). */
static PetscErrorCode AdvisedHuge(const void *a, PetscBool *hg)
{
  FILE     *fp = fopen("/proc/self/smaps", "r");
  char      line[512];
  PetscBool inside = PETSC_FALSE, found = PETSC_FALSE;

  PetscFunctionBeginUser;
  *hg = PETSC_FALSE;
  PetscCheck(fp, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "cannot read /proc/self/smaps");
  while (fgets(line, sizeof(line), fp)) {
    unsigned long lo, hi;
    char          perms[8];
    if (sscanf(line, "%lx-%lx %7s", &lo, &hi, perms) == 3) { /* a mapping's first line */
      inside = (PetscBool)((uintptr_t)a >= lo && (uintptr_t)a < hi);
      found  = (PetscBool)(found || inside);
      continue;
    }
    if (inside && !strncmp(line, "VmFlags:", 8)) *hg = (PetscBool)(strstr(line, " hg") != NULL);
  }
  fclose(fp);
  PetscCheck(found, PETSC_COMM_SELF, PETSC_ERR_PLIB, "no mapping holds %p", a);
  PetscFunctionReturn(PETSC_SUCCESS);
}

int main(int argc, char **argv)
{
  PetscInt     n = 0;
  PetscBool    hg;
  float       *big;
  const size_t nbig = (size_t)4 << 20; /* 16 MiB of floats */

  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(PffInitializePackage());
  PetscCall(PffHugePagesSetFromOptions(PETSC_COMM_WORLD));
  /* a kernel without transparent huge pages refuses the advice: then no array may carry the flag */
  const PetscBool thp = (PetscBool)(access("/sys/kernel/mm/transparent_hugepage/enabled", F_OK) == 0);
  const PetscBool on  = (PetscBool)(PffHugePagesEnabled() && thp);

  PetscCall(PetscMalloc1(nbig, &big));
  PffAdviseHugePages(big, sizeof(float) * nbig);
  for (size_t i = 0; i < nbig; i++) big[i] = (float)i;
  /* the first whole huge page inside the array */
  const float *page = (const float *)(((uintptr_t)big + ((uintptr_t)2 << 20) - 1) & ~(((uintptr_t)2 << 20) - 1));
  PetscCall(AdvisedHuge(page, &hg));
  PetscCheck(hg == on, PETSC_COMM_SELF, PETSC_ERR_PLIB, "a 16 MiB array is %sadvised with huge pages %s",
             hg ? "" : "not ", on ? "on" : "off");
  n++;
  for (size_t i = 0; i < nbig; i++)
    PetscCheck(big[i] == (float)i, PETSC_COMM_SELF, PETSC_ERR_PLIB, "value %zu changed", i);
  n++;
  PetscCall(PetscFree(big));

  PetscCall(
      PetscPrintf(PETSC_COMM_WORLD, "memory ok: huge pages %s, %" PetscInt_FMT " checks\n", on ? "on" : "off", n));
  PetscCall(PetscFinalize());
  return 0;
}
