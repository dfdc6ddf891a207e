/* Set-up of the pressure projection (Eq. 8-10) on the multiresolution grid: the face list and the
   gradient matrix G, once per grid topology.

   Every owned cell owns its lower face along each axis d (the component d of a face channel), so
   the owned face rows are r = 3 c + d for the owned cells c, and every geometric face of the grid
   is owned exactly once. The upper side of the face is the cell itself; the lower side is found in
   the replicated block raster (PffRasterNeighbour, periodic wrap):
     inside the block or a same-level neighbour: one cell, d_f = h, A_f = h^2;
     a coarser neighbour (fine above coarse): the coarse cell, d_f = Delta_g 2h, A_f = h^2;
     a finer neighbour (coarse above fine): the 4 fine cells with weight 1/4, d_f = Delta_g h, A_f = h^2;
     a wall or an inactive block: closed, no row entries.
   With Delta_g = 3/4 (PF-FLIP Sec. 4.2, Losasso 2004 Fig. 9c) d_f is the distance between the cell
   centres on both sides. Global cell numbers come from PffGridGetCellNumbering, which needs no
   communication, so the rows of G are assembled locally; G^T (divergence) and products with G
   let PETSc carry all off-rank traffic. */
#include "pressureimpl.h"

const char *const PffFaceKinds[] = {"interior", "same",        "coarser",   "finer", "wall",
                                    "inactive", "PffFaceKind", "PFF_FACE_", NULL};

/* Global number of cell (i, j, k) of active block gid at its own level n. */
static inline PetscInt CellNumber(PetscInt64 first, PetscInt n, PetscInt i, PetscInt j, PetscInt k)
{
  return (PetscInt)(first + i + n * (j + (PetscInt64)n * k));
}

PetscErrorCode PffPressureBuildFaces_Private(PffPressure ps)
{
  PffGrid            grid = ps->grid;
  PetscInt           nb[3], n0, nlevels, nfiner = 0;
  const PetscInt    *level;
  const PetscMPIInt *owner;
  PetscReal          h0, origin[3];
  PetscBool          periodic[3];
  PetscInt64         rstart, nowned, ntotal, count[PFF_FACE_NKINDS] = {0};

  PetscFunctionBeginUser;
  PetscCall(PffGridGetRaster(grid, nb, &level, &owner));
  PetscCall(PffGridGetSizes(grid, &n0, &nlevels, origin, &h0, periodic));
  PetscCall(PffGridGetLocalBlocks(grid, &ps->nlocal));
  PetscCall(PffGridGetCellNumbering(grid, -1, NULL, &nowned, &rstart, &ntotal));
  /* the matrix-free path numbers cells globally and faces only locally (3 per owned cell), so it reaches
     PetscInt's range in cells; the assembled operator's 3 N face rows are checked where it is built */
  PetscCheck(ntotal < PETSC_MAX_INT && 3 * nowned < PETSC_MAX_INT, ps->comm, PETSC_ERR_SUP,
             "pressure: %" PetscInt64_FMT " cells exceed PetscInt; build with PETSc's 64-bit indices (cmake "
             "-DPFF_PETSC64=ON, docs/pressure.md)",
             ntotal);
  ps->ncells = (PetscInt)nowned;
  ps->rstart = (PetscInt)rstart;
  ps->ntotal = (PetscInt)ntotal;

  PetscCall(PetscMalloc1(ps->nlocal + 1, &ps->blockStart));
  /* first pass: block offsets and the number of coarse-above-fine faces */
  for (PetscInt lb = 0; lb < ps->nlocal; lb++) {
    PffBlockInfo info;
    PetscInt64   first;
    PetscCall(PffGridGetBlockInfo(grid, lb, &info));
    PetscCall(PffGridGetCellNumbering(grid, info.gid, &first, NULL, NULL, NULL));
    ps->blockStart[lb] = (PetscInt)(first - rstart);
    for (PetscInt d = 0; d < 3; d++) {
      PetscInt dir[3]     = {0, 0, 0};
      dir[d]              = -1;
      const PetscInt ngid = PffRasterNeighbour(nb, periodic, info.ijk, dir);
      if (ngid >= 0 && level[ngid] >= 0 && level[ngid] == info.level - 1) nfiner += info.n * info.n;
    }
  }
  ps->blockStart[ps->nlocal] = ps->ncells;
  for (PetscInt lb = 0; lb + 1 < ps->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(grid, lb, &info));
    PetscCheck(ps->blockStart[lb + 1] - ps->blockStart[lb] == info.n * info.n * info.n, PETSC_COMM_SELF, PETSC_ERR_PLIB,
               "pressure: owned blocks are not numbered contiguously in local order");
  }

  PetscCall(PetscMalloc1(3 * ps->ncells, &ps->kind));
  PetscCall(PetscMalloc1(3 * ps->ncells, &ps->lower));
  PetscCall(PetscMalloc1(ps->nlocal, &ps->hblock));
  PetscCall(PetscMalloc1(4 * nfiner, &ps->lower4));
  ps->nfiner = 0;

  for (PetscInt lb = 0; lb < ps->nlocal; lb++) {
    PffBlockInfo info;
    PetscCall(PffGridGetBlockInfo(grid, lb, &info));
    const PetscInt n = info.n, c0 = ps->blockStart[lb];
    ps->hblock[lb] = info.h;
    for (PetscInt d = 0; d < 3; d++) {
      PetscInt dir[3]     = {0, 0, 0};
      dir[d]              = -1;
      const PetscInt ngid = PffRasterNeighbour(nb, periodic, info.ijk, dir);
      PffFaceKind    bkind; /* class of the faces on the block's lower d-side */
      PetscInt64     nfirst = -1;
      if (ngid < 0)
        bkind = PFF_FACE_WALL;
      else if (level[ngid] < 0)
        bkind = PFF_FACE_INACTIVE;
      else {
        PetscCheck(PetscAbsInt(level[ngid] - info.level) <= 1, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                   "pressure: blocks %" PetscInt_FMT " and %" PetscInt_FMT " violate 2:1 grading", info.gid, ngid);
        bkind =
            level[ngid] == info.level ? PFF_FACE_SAME : (level[ngid] > info.level ? PFF_FACE_COARSER : PFF_FACE_FINER);
        PetscCall(PffGridGetCellNumbering(grid, ngid, &nfirst, NULL, NULL, NULL));
      }
      for (PetscInt k = 0; k < n; k++)
        for (PetscInt j = 0; j < n; j++)
          for (PetscInt i = 0; i < n; i++) {
            const PetscInt c[3] = {i, j, k}, r = 3 * (c0 + i + n * (j + n * k)) + d;
            if (c[d] > 0) {
              PetscInt lo[3] = {i, j, k};
              lo[d]--;
              ps->kind[r]  = PFF_FACE_INTERIOR;
              ps->lower[r] = (PetscInt)(rstart + c0) + lo[0] + n * (lo[1] + n * lo[2]);
              continue;
            }
            ps->kind[r] = (unsigned char)bkind;
            switch (bkind) {
            case PFF_FACE_WALL:
            case PFF_FACE_INACTIVE:
              ps->lower[r] = -1;
              break;
            case PFF_FACE_SAME: {
              PetscInt lo[3] = {i, j, k};
              lo[d]          = n - 1;
              ps->lower[r]   = CellNumber(nfirst, n, lo[0], lo[1], lo[2]);
            } break;
            case PFF_FACE_COARSER: {
              const PetscInt nc    = n / 2;
              PetscInt       lo[3] = {i / 2, j / 2, k / 2};
              lo[d]                = nc - 1;
              ps->lower[r]         = CellNumber(nfirst, nc, lo[0], lo[1], lo[2]);
            } break;
            case PFF_FACE_FINER: {
              const PetscInt nf = 2 * n;
              PetscInt       q  = 0;
              for (PetscInt b = 0; b < 2; b++)
                for (PetscInt a = 0; a < 2; a++) {
                  PetscInt lo[3] = {2 * i, 2 * j, 2 * k}, t[2], m = 0;
                  for (PetscInt e = 0; e < 3; e++)
                    if (e != d) t[m++] = e;
                  lo[t[0]] += a;
                  lo[t[1]] += b;
                  lo[d]                            = nf - 1;
                  ps->lower4[4 * ps->nfiner + q++] = CellNumber(nfirst, nf, lo[0], lo[1], lo[2]);
                }
              ps->lower[r] = ps->nfiner++;
            } break;
            default:
              break;
            }
          }
    }
  }
  PetscCheck(ps->nfiner == nfiner, PETSC_COMM_SELF, PETSC_ERR_PLIB, "pressure: coarse-fine face count mismatch");
  for (PetscInt r = 0; r < 3 * ps->ncells; r++) count[ps->kind[r]]++;
  PetscCall(MPIU_Allreduce(count, ps->nkind, PFF_FACE_NKINDS, MPIU_INT64, MPI_SUM, ps->comm));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffPressureBuildGradient_Private(PffPressure ps)
{
  const PetscInt nrows = 3 * ps->ncells, cend = ps->rstart + ps->ncells;
  PetscInt      *dnz, *onz;

  PetscFunctionBeginUser;
  PetscCheck(3 * (PetscInt64)ps->ntotal < PETSC_MAX_INT, ps->comm, PETSC_ERR_SUP,
             "pressure: the assembled operator needs 3 x %" PetscInt_FMT
             " face rows, more than PetscInt holds; use the matrix-free default (-pressure_pc_type pffmg "
             "-pressure_operator shell) or PETSc with 64-bit indices (cmake -DPFF_PETSC64=ON)",
             ps->ntotal);
  PetscCall(PetscCalloc1(nrows, &dnz));
  PetscCall(PetscCalloc1(nrows, &onz));
  for (PetscInt lb = 0; lb < ps->nlocal; lb++)
    for (PetscInt r = 3 * ps->blockStart[lb]; r < 3 * ps->blockStart[lb + 1]; r++) {
      const PetscReal h = ps->hblock[lb];
      PetscInt        cols[5], m;
      PetscScalar     vals[5];
      m = PffPressureGradientRow(ps, r, h, cols, vals);
      for (PetscInt q = 0; q < m; q++) {
        if (cols[q] >= ps->rstart && cols[q] < cend)
          dnz[r]++;
        else
          onz[r]++;
      }
    }
  PetscCall(MatCreateAIJ(ps->comm, nrows, ps->ncells, 3 * ps->ntotal, ps->ntotal, 0, dnz, 0, onz, &ps->G));
  PetscCall(MatSetOption(ps->G, MAT_NO_OFF_PROC_ENTRIES, PETSC_TRUE));
  for (PetscInt lb = 0; lb < ps->nlocal; lb++)
    for (PetscInt r = 3 * ps->blockStart[lb]; r < 3 * ps->blockStart[lb + 1]; r++) {
      const PetscReal h = ps->hblock[lb];
      PetscInt        cols[5], m, row = 3 * ps->rstart + r;
      PetscScalar     vals[5];
      m = PffPressureGradientRow(ps, r, h, cols, vals);
      if (m) PetscCall(MatSetValues(ps->G, 1, &row, m, cols, vals, INSERT_VALUES));
    }
  PetscCall(MatAssemblyBegin(ps->G, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(ps->G, MAT_FINAL_ASSEMBLY));
  PetscCall(PetscFree(dnz));
  PetscCall(PetscFree(onz));

  PetscFunctionReturn(PETSC_SUCCESS);
}
