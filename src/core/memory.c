/* Large arrays on transparent huge pages (docs/decisions.md, "Huge pages").

   The kernel here backs anonymous memory with 2 MiB pages only where a program asks for them (madvise mode, Debian's
   default). The particle store and the grid's channels are large, fully used arrays that the particle kernels walk
   block by block; in an adaptive run they are also grown or made again at grid changes, and every fresh 4 KiB page
   costs a fault. Their owners advise them here (-sim_huge_pages, default true). Only whole 2 MiB pages inside an
   array are advised: a partly used one would be resident in full. Other allocations are left alone: advising every
   large PETSc block (tried through PetscMallocSet) made the uniform rt3d at W = 64 14 % larger in resident memory and
   no faster (docs/benchmarks.md, "Huge pages"). */
#define _GNU_SOURCE /* MADV_HUGEPAGE */
#include <pff.h>
#include <stdint.h>
#include <sys/mman.h>

#define PFF_HUGE_PAGE ((uintptr_t)2 << 20)
#define PFF_HUGE_MIN ((size_t)4 << 20)

static PetscBool pffHugePages = PETSC_TRUE;

void PffAdviseHugePages(void *p, size_t bytes)
{
  if (!pffHugePages || !p || bytes < PFF_HUGE_MIN) return;
  const uintptr_t lo = ((uintptr_t)p + PFF_HUGE_PAGE - 1) & ~(PFF_HUGE_PAGE - 1);
  const uintptr_t hi = ((uintptr_t)p + bytes) & ~(PFF_HUGE_PAGE - 1);
  /* advice only: a kernel without huge pages refuses it and the array works as any other */
  if (hi > lo) (void)madvise((void *)lo, (size_t)(hi - lo), MADV_HUGEPAGE);
}

PetscErrorCode PffHugePagesSetFromOptions(MPI_Comm comm)
{
  PetscBool on = pffHugePages;

  PetscFunctionBeginUser;
  PetscOptionsBegin(comm, NULL, "Memory", NULL);
  PetscCall(PffOptionsBool("-sim_huge_pages",
                           "Put the particle store and the grid channels on transparent huge pages (madvise)", NULL, on,
                           &on, NULL));
  PetscOptionsEnd();
  pffHugePages = on;
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscBool PffHugePagesEnabled(void)
{
  return pffHugePages;
}
