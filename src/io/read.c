/* Reading frames and checkpoints (restart and post-processing tools): PffIOReadFrame fills a set-up grid
   from a frame, PffIOReadCheckpoint also the particle store and the extra values (particles.c reads
   the particle rows), PffIOReadLevels returns the frame's level map so that a tool can first build a
   matching grid.

   A frame may be read on any number of ranks and with any partition: each rank selects its owned
   blocks at their Morton positions (layout.c), exactly as the writer did. Before touching data the
   reader compares the file with the grid (block size, raster, level map, channel names and kinds) and
   stops with one message naming the first difference; every rank reads the same metadata, so they all
   stop together, after closing the file. */
#include <string.h>
#include "h5util.h"

/* Opens path collectively and checks that it is a pfflip frame of a version we read. */
static PetscErrorCode PffIOOpenFrame(MPI_Comm comm, const char path[], hid_t *file)
{
  hid_t     fapl;
  char     *format = NULL, msg[PETSC_MAX_PATH_LEN + 256] = "";
  int       version = 0;
  PetscBool found;

  PetscFunctionBeginUser;
  PetscCall(PffIOCheckReadable_Private(comm, path));
  PetscCall(PffIOCreateAccessList_Private(comm, &fapl));
  *file = H5Fopen(path, H5F_ACC_RDONLY, fapl);
  if (*file < 0) {
    char h5msg[256];
    /* Before any other HDF5 call, which would clear the error stack. */
    PffHDF5ErrorMessage_Private(h5msg, sizeof(h5msg));
    SETERRQ(comm, PETSC_ERR_FILE_OPEN, "cannot open frame %s: not a readable HDF5 file (%s)", path, h5msg);
  }
  PffCallHDF5(H5Pclose(fapl));
  PetscCall(PffH5ReadAttributeString_Private(*file, "format", &format));
  PetscCall(PffH5ReadAttribute_Private(*file, "format_version", H5T_NATIVE_INT, 0, &version, &found));
  if (!format || strcmp(format, PFF_FRAME_FORMAT))
    PetscCall(PetscSNPrintf(msg, sizeof(msg),
                            "frame %s: not a pfflip frame (root attribute format is \"%s\", expected \"%s\")", path,
                            format ? format : "(missing)", PFF_FRAME_FORMAT));
  else if (!found || version < 1 || version > PFF_FRAME_FORMAT_VERSION)
    PetscCall(PetscSNPrintf(msg, sizeof(msg), "frame %s: format_version %d is not one this build reads (1 to %d)", path,
                            version, PFF_FRAME_FORMAT_VERSION));
  PetscCall(PetscFree(format));
  if (msg[0]) {
    PffCallHDF5(H5Fclose(*file));
    SETERRQ(comm, PETSC_ERR_FILE_UNEXPECTED, "%s", msg);
  }
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Reads /grid/raster and the full /grid/level map (every rank reads all of it). */
static PetscErrorCode PffIOReadRaster(hid_t file, const char path[], hid_t dxpl, PetscInt nb[3], PetscInt **level)
{
  PetscInt64 raster[3];
  PetscBool  found;
  htri_t     exists;
  hid_t      group, dset, space;
  hssize_t   npoints;

  PetscFunctionBeginUser;
  PffCallHDF5(exists = H5Lexists(file, "grid", H5P_DEFAULT));
  PetscCheck(exists, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "frame %s: no /grid group", path);
  PffCallHDF5(group = H5Gopen2(file, "grid", H5P_DEFAULT));
  PetscCall(PffH5ReadAttribute_Private(group, "raster", H5T_NATIVE_INT64, 3, raster, &found));
  PetscCheck(found, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "frame %s: /grid has no raster attribute of 3 values",
             path);
  for (int d = 0; d < 3; d++) {
    PetscCheck(raster[d] > 0 && raster[d] <= PETSC_MAX_INT, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED,
               "frame %s: /grid raster %" PetscInt64_FMT " is not a block count", path, raster[d]);
    nb[d] = (PetscInt)raster[d];
  }
  const PetscInt64 nblocks = raster[0] * raster[1] * raster[2];
  PffCallHDF5(exists = H5Lexists(group, "level", H5P_DEFAULT));
  PetscCheck(exists, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "frame %s: no /grid/level dataset", path);
  PffCallHDF5(dset = H5Dopen2(group, "level", H5P_DEFAULT));
  PffCallHDF5(space = H5Dget_space(dset));
  PffCallHDF5(npoints = H5Sget_simple_extent_npoints(space));
  PetscCheck(npoints == nblocks, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED,
             "frame %s: /grid/level has %" PetscInt64_FMT " entries but the raster has %" PetscInt64_FMT " blocks",
             path, (PetscInt64)npoints, nblocks);
  PetscCall(PetscMalloc1(nblocks, level));
  PffCallHDF5(H5Dread(dset, PFF_H5T_NATIVE_PETSCINT, H5S_ALL, H5S_ALL, dxpl, *level));
  PffCallHDF5(H5Sclose(space));
  PffCallHDF5(H5Dclose(dset));
  PffCallHDF5(H5Gclose(group));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffIOReadLevels(MPI_Comm comm, const char path[], PetscInt nb[3], PetscInt **level)
{
  hid_t file, dxpl;

  PetscFunctionBeginUser;
  PetscCall(PffIOInitialize_Private());
  PetscCall(PffIOOpenFrame(comm, path, &file));
  PetscCall(PffIOCreateTransferList_Private(&dxpl));
  PetscCall(PffIOReadRaster(file, path, dxpl, nb, level));
  PffCallHDF5(H5Pclose(dxpl));
  PffCallHDF5(H5Fclose(file));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Compares the frame's raster with the grid's; msg stays empty when they agree. */
static PetscErrorCode PffIOCompareRaster(PffGrid grid, hid_t file, const char path[], hid_t dxpl, char msg[],
                                         size_t len)
{
  const PetscInt *glevel;
  PetscInt       *flevel, fnb[3], nb[3], n0, nl;
  PetscReal       org[3], h0;
  PetscBool       per[3];
  int             fn0 = 0, fnl = 0, fper[3] = {0, 0, 0};
  double          fh0 = 0, forg[3] = {0, 0, 0};
  PetscBool       found, gfound[4];
  hid_t           group;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetRaster(grid, nb, &glevel, NULL));
  PetscCall(PffGridGetSizes(grid, &n0, &nl, org, &h0, per));
  PetscCall(PffIOReadRaster(file, path, dxpl, fnb, &flevel));
  PffCallHDF5(group = H5Gopen2(file, "grid", H5P_DEFAULT));
  PetscCall(PffH5ReadAttribute_Private(group, "block_size", H5T_NATIVE_INT, 0, &fn0, &found));
  /* the geometry a frame's fields live on: every difference is listed, so that one run shows them all */
  PetscCall(PffH5ReadAttribute_Private(group, "levels", H5T_NATIVE_INT, 0, &fnl, &gfound[0]));
  PetscCall(PffH5ReadAttribute_Private(group, "h0", H5T_NATIVE_DOUBLE, 0, &fh0, &gfound[1]));
  PetscCall(PffH5ReadAttribute_Private(group, "origin", H5T_NATIVE_DOUBLE, 3, forg, &gfound[2]));
  PetscCall(PffH5ReadAttribute_Private(group, "periodic", H5T_NATIVE_INT, 3, fper, &gfound[3]));
  PffCallHDF5(H5Gclose(group));
  {
    char diff[512] = "";
    if (gfound[0] && fnl != nl)
      PetscCall(PetscSNPrintf(diff + strlen(diff), sizeof(diff) - strlen(diff),
                              "; -grid_levels %d in the file, %" PetscInt_FMT " now", fnl, nl));
    if (gfound[1] && PetscAbsReal((PetscReal)fh0 - h0) > 1e-12 * PetscAbsReal(h0))
      PetscCall(PetscSNPrintf(diff + strlen(diff), sizeof(diff) - strlen(diff),
                              "; -grid_h %.15g in the file, %.15g now", fh0, (double)h0));
    if (gfound[2])
      for (int d = 0; d < 3; d++)
        if (PetscAbsReal((PetscReal)forg[d] - org[d]) > 1e-12 * PetscMax(1, h0 * nb[d] * n0)) {
          PetscCall(PetscSNPrintf(diff + strlen(diff), sizeof(diff) - strlen(diff),
                                  "; -grid_origin %g,%g,%g in the file, %g,%g,%g now", forg[0], forg[1], forg[2],
                                  (double)org[0], (double)org[1], (double)org[2]));
          break;
        }
    if (gfound[3] &&
        ((fper[0] != 0) != (per[0] != 0) || (fper[1] != 0) != (per[1] != 0) || (fper[2] != 0) != (per[2] != 0)))
      PetscCall(PetscSNPrintf(
          diff + strlen(diff), sizeof(diff) - strlen(diff), "; -grid_periodic %s%s%s%s in the file, %s%s%s%s now",
          fper[0] ? "x" : "", fper[1] ? "y" : "", fper[2] ? "z" : "", fper[0] || fper[1] || fper[2] ? "" : "none",
          per[0] ? "x" : "", per[1] ? "y" : "", per[2] ? "z" : "", per[0] || per[1] || per[2] ? "" : "none"));
    if (found && fn0 != n0)
      PetscCall(PetscSNPrintf(diff + strlen(diff), sizeof(diff) - strlen(diff),
                              "; -grid_block_size %d in the file, %" PetscInt_FMT " now", fn0, n0));
    if (fnb[0] * fn0 != nb[0] * n0 || fnb[1] * fn0 != nb[1] * n0 || fnb[2] * fn0 != nb[2] * n0)
      PetscCall(PetscSNPrintf(diff + strlen(diff), sizeof(diff) - strlen(diff),
                              "; -grid_cells %" PetscInt_FMT ",%" PetscInt_FMT ",%" PetscInt_FMT
                              " in the file, %" PetscInt_FMT ",%" PetscInt_FMT ",%" PetscInt_FMT " now",
                              fnb[0] * fn0, fnb[1] * fn0, fnb[2] * fn0, nb[0] * n0, nb[1] * n0, nb[2] * n0));
    if (diff[0]) {
      PetscCall(PetscSNPrintf(msg, len, "%s was written on another grid: %s", path, diff + 2));
      PetscCall(PetscFree(flevel));
      PetscFunctionReturn(PETSC_SUCCESS);
    }
  }
  /* equal block sizes and cell counts give equal rasters (the differences were listed above) */
  if (!found)
    PetscCall(PetscSNPrintf(msg, len, "frame %s: /grid has no block_size attribute", path));
  else {
    for (PetscInt b = 0; b < nb[0] * nb[1] * nb[2]; b++) {
      if (flevel[b] == glevel[b]) continue;
      PetscCall(PetscSNPrintf(msg, len,
                              "frame %s: block %" PetscInt_FMT " (%" PetscInt_FMT ",%" PetscInt_FMT ",%" PetscInt_FMT
                              ") has level %" PetscInt_FMT " in the file but %" PetscInt_FMT
                              " in the grid (-1 = inactive); build the grid from PffIOReadLevels()",
                              path, b, b % nb[0], (b / nb[0]) % nb[1], b / (nb[0] * nb[1]), flevel[b], glevel[b]));
      break;
    }
  }
  PetscCall(PetscFree(flevel));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* Checks that every component of every required grid channel has a dataset of the right kind and
   length: all channels when all is true (checkpoints), else those flagged for output. A channel not
   required is read when the file has any of its datasets (then all must be right) and skipped when it
   has none. present[c] says whether channel c is read. */
static PetscErrorCode PffIOCompareChannels(PffGrid grid, const PffFrameLayout *L, hid_t file, const char path[],
                                           PetscBool all, PetscBool present[], char msg[], size_t len)
{
  PetscInt  nch;
  htri_t    exists;
  hid_t     group;
  PetscBool need = PETSC_FALSE;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetNumChannels(grid, &nch));
  for (PetscInt c = 0; c < nch; c++) {
    PetscBool write;
    PetscCall(PffGridGetChannelOutput(grid, c, &write));
    present[c] = PETSC_FALSE;
    if (write || all) need = PETSC_TRUE;
  }
  PffCallHDF5(exists = H5Lexists(file, "fields", H5P_DEFAULT));
  if (!exists) {
    if (need) PetscCall(PetscSNPrintf(msg, len, "frame %s: no /fields group", path));
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  PffCallHDF5(group = H5Gopen2(file, "fields", H5P_DEFAULT));
  for (PetscInt c = 0; c < nch && !msg[0]; c++) {
    const char    *name;
    PffChannelKind kind;
    PetscInt       ncomp;
    PetscBool      write, any = PETSC_FALSE;

    PetscCall(PffGridGetChannelOutput(grid, c, &write));
    PetscCall(PffGridGetChannelInfo(grid, c, &name, &kind, &ncomp, NULL));
    /* a hidden (working) channel is rebuilt by the step, so a checkpoint without it still restarts:
       one written with -flow_extrapolate_layers 0 lacks velocity_liquid */
    if (!write) {
      for (PetscInt comp = 0; comp < ncomp && !any; comp++) {
        char dname[256];
        PetscCall(PffIOFieldName_Private(name, kind, comp, dname, sizeof(dname)));
        PffCallHDF5(exists = H5Lexists(group, dname, H5P_DEFAULT));
        if (exists) any = PETSC_TRUE;
      }
      if (!any) continue; /* a hidden channel the file does not hold: left as set up */
    }
    present[c] = PETSC_TRUE;
    for (PetscInt comp = 0; comp < ncomp && !msg[0]; comp++) {
      char     dname[256], *fkind = NULL;
      hid_t    dset, space;
      hssize_t npoints;

      PetscCall(PffIOFieldName_Private(name, kind, comp, dname, sizeof(dname)));
      PffCallHDF5(exists = H5Lexists(group, dname, H5P_DEFAULT));
      if (!exists) {
        PetscCall(PetscSNPrintf(msg, len, "frame %s: channel %s (%s) is missing: no dataset /fields/%s", path, name,
                                PffChannelKinds[kind], dname));
        break;
      }
      PffCallHDF5(dset = H5Dopen2(group, dname, H5P_DEFAULT));
      PetscCall(PffH5ReadAttributeString_Private(dset, "kind", &fkind));
      PffCallHDF5(space = H5Dget_space(dset));
      PffCallHDF5(npoints = H5Sget_simple_extent_npoints(space));
      if (!fkind || strcmp(fkind, PffChannelKinds[kind]))
        PetscCall(PetscSNPrintf(msg, len, "frame %s: channel %s is a %s channel in the grid but /fields/%s has kind %s",
                                path, name, PffChannelKinds[kind], dname, fkind ? fkind : "(missing)"));
      else if ((PetscInt64)npoints != L->offset[L->nactive])
        PetscCall(PetscSNPrintf(msg, len,
                                "frame %s: /fields/%s has %" PetscInt64_FMT " values but the grid has %" PetscInt64_FMT
                                " active cells",
                                path, dname, (PetscInt64)npoints, L->offset[L->nactive]));
      PetscCall(PetscFree(fkind));
      PffCallHDF5(H5Sclose(space));
      PffCallHDF5(H5Dclose(dset));
    }
  }
  PffCallHDF5(H5Gclose(group));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The file's own record of its order: /blocks/gid and /blocks/offset of the owned rows must be the
   grid's Morton order and prefix sum (a guard against a file that followed another convention). */
static PetscErrorCode PffIOCompareBlocks(MPI_Comm comm, const PffFrameLayout *L, hid_t file, const char path[],
                                         hid_t dxpl, char msg[], size_t len)
{
  const char *names[2] = {"/blocks/gid", "/blocks/offset"};
  PetscInt64 *buf;
  int         bad = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(L->nlocal > 0 ? L->nlocal : 1, &buf));
  for (int i = 0; i < 2; i++) {
    htri_t   exists;
    hid_t    dset, fspace, mspace;
    hssize_t npoints;

    PffCallHDF5(exists = H5Lexists(file, "blocks", H5P_DEFAULT));
    if (exists) PffCallHDF5(exists = H5Lexists(file, names[i], H5P_DEFAULT));
    if (!exists) {
      PetscCall(PetscSNPrintf(msg, len, "frame %s: no dataset %s", path, names[i]));
      break;
    }
    PffCallHDF5(dset = H5Dopen2(file, names[i], H5P_DEFAULT));
    PffCallHDF5(fspace = H5Dget_space(dset));
    PffCallHDF5(npoints = H5Sget_simple_extent_npoints(fspace));
    if (npoints != (hssize_t)L->nactive) {
      PetscCall(PetscSNPrintf(
          msg, len, "frame %s: %s has %" PetscInt64_FMT " rows but the grid has %" PetscInt_FMT " active blocks", path,
          names[i], (PetscInt64)npoints, L->nactive));
    } else {
      PetscCall(PffIOSelectBlocks_Private(L, fspace));
      PetscCall(PffIOCreateMemSpace_Private((hsize_t)L->nlocal, 0, &mspace));
      PffCallHDF5(H5Dread(dset, H5T_NATIVE_INT64, mspace, fspace, dxpl, buf));
      PffCallHDF5(H5Sclose(mspace));
      for (PetscInt k = 0; k < L->nlocal; k++) {
        const PetscInt64 expect = i == 0 ? (PetscInt64)L->order[L->lpos[k]] : L->offset[L->lpos[k]];
        if (buf[k] != expect) bad = 1;
      }
    }
    PffCallHDF5(H5Sclose(fspace));
    PffCallHDF5(H5Dclose(dset));
    if (msg[0]) break;
  }
  PetscCall(PetscFree(buf));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &bad, 1, MPI_INT, MPI_LOR, comm));
  if (!msg[0] && bad)
    PetscCall(
        PetscSNPrintf(msg, len, "frame %s: /blocks/gid or /blocks/offset is not in the grid's Morton order", path));
  PetscFunctionReturn(PETSC_SUCCESS);
}

static PetscErrorCode PffIOReadFields(PffGrid grid, const PffFrameLayout *L, hid_t file, hid_t dxpl,
                                      const PetscBool present[])
{
  const hsize_t total = (hsize_t)L->offset[L->nactive];
  PetscInt      nch;
  float        *buf;
  hid_t         group, fspace, mspace;

  PetscFunctionBeginUser;
  PetscCall(PffGridGetNumChannels(grid, &nch));
  if (nch == 0) PetscFunctionReturn(PETSC_SUCCESS);
  PetscCall(PetscMalloc1(L->ncells > 0 ? L->ncells : 1, &buf));
  PffCallHDF5(group = H5Gopen2(file, "fields", H5P_DEFAULT));
  PffCallHDF5(fspace = H5Screate_simple(1, &total, NULL));
  PetscCall(PffIOSelectCells_Private(L, fspace));
  PetscCall(PffIOCreateMemSpace_Private((hsize_t)L->ncells, 0, &mspace));
  for (PetscInt c = 0; c < nch; c++) {
    const char    *name;
    PffChannelKind kind;
    PetscInt       ncomp;

    if (!present[c]) continue;
    PetscCall(PffGridGetChannelInfo(grid, c, &name, &kind, &ncomp, NULL));
    for (PetscInt comp = 0; comp < ncomp; comp++) {
      char       dname[256];
      PetscInt64 pos = 0;
      hid_t      dset;

      PetscCall(PffIOFieldName_Private(name, kind, comp, dname, sizeof(dname)));
      PffCallHDF5(dset = H5Dopen2(group, dname, H5P_DEFAULT));
      PffCallHDF5(H5Dread(dset, H5T_NATIVE_FLOAT, mspace, fspace, dxpl, buf));
      PffCallHDF5(H5Dclose(dset));
      for (PetscInt k = 0; k < L->nlocal; k++) {
        const PetscInt64 nc = (PetscInt64)L->ln[k] * L->ln[k] * L->ln[k];
        float           *data;
        PetscCall(PffGridGetBlockData(grid, c, L->lb[k], comp, &data));
        PetscCall(PetscArraycpy(data, buf + pos, nc));
        pos += nc;
      }
    }
  }
  PffCallHDF5(H5Sclose(mspace));
  PffCallHDF5(H5Sclose(fspace));
  PffCallHDF5(H5Gclose(group));
  PetscCall(PetscFree(buf));
  PetscFunctionReturn(PETSC_SUCCESS);
}

/* The shared reader. checkpoint: the file must be a checkpoint, every channel must be in it, the extra
   values (nextra of them) are returned, and the particles are read into particles (when not NULL). */
static PetscErrorCode PffIOReadFile(PffGrid grid, PffParticles particles, const char path[], PetscBool checkpoint,
                                    PetscReal *time, PetscInt *step, PetscInt nextra, PetscReal extra[])
{
  char           msg[PETSC_MAX_PATH_LEN + 512] = "";
  MPI_Comm       comm;
  PffFrameLayout L;
  hid_t          file, dxpl;
  PetscReal      t  = 0;
  PetscInt64     st = 0, npart = 0;
  PetscBool      tfound, sfound, present[PFF_GRID_MAX_CHANNELS];
  double        *xbuf = NULL;

  PetscFunctionBeginUser;
  PetscCall(PffIOInitialize_Private());
  PetscCall(PffIOGetComm_Private(grid, &comm));
  if (checkpoint && particles) {
    PetscInt64 count[PFF_PARTICLE_NTYPES];
    PetscCall(PffParticlesGetTotals(particles, NULL, count, NULL));
    PetscCheck(count[0] + count[1] == 0, comm, PETSC_ERR_ARG_WRONGSTATE,
               "cannot read checkpoint %s: the particle store must be empty but holds %" PetscInt64_FMT " particles",
               path, count[0] + count[1]);
  }
  PetscCheck(nextra >= 0 && (nextra == 0 || extra != NULL), comm, PETSC_ERR_ARG_WRONG,
             "checkpoint %s: %" PetscInt_FMT " extra values requested but the array is NULL or the count negative",
             path, nextra);
  PetscCall(PffIOOpenFrame(comm, path, &file));
  PetscCall(PetscLogEventBegin(PFF_IORead, 0, 0, 0, 0));
  PetscCall(PffIOCreateTransferList_Private(&dxpl));
  PetscCall(PffIOLayoutCreate_Private(grid, &L));
  if (checkpoint) {
    int       mark = 0, fextra = 0;
    PetscBool found;

    PetscCall(PffH5ReadAttribute_Private(file, "checkpoint", H5T_NATIVE_INT, 0, &mark, &found));
    if (!found || mark != 1)
      PetscCall(PetscSNPrintf(msg, sizeof(msg),
                              "file %s is a frame, not a checkpoint (no root attribute checkpoint = 1); write it with "
                              "PffIOWriteCheckpoint",
                              path));
    if (!msg[0]) {
      PetscCall(PffH5ReadAttribute_Private(file, "nextra", H5T_NATIVE_INT, 0, &fextra, &found));
      if (!found || fextra != nextra)
        PetscCall(PetscSNPrintf(msg, sizeof(msg),
                                "checkpoint %s holds %d extra values but the caller expects %" PetscInt_FMT, path,
                                found ? fextra : 0, nextra));
    }
    if (!msg[0] && nextra > 0) {
      PetscCall(PetscMalloc1(nextra, &xbuf));
      PetscCall(PffH5ReadAttribute_Private(file, "extra", H5T_NATIVE_DOUBLE, (hsize_t)nextra, xbuf, &found));
      if (!found)
        PetscCall(PetscSNPrintf(msg, sizeof(msg), "checkpoint %s: no root attribute extra of %" PetscInt_FMT " values",
                                path, nextra));
    }
  }
  if (!msg[0]) PetscCall(PffIOCompareRaster(grid, file, path, dxpl, msg, sizeof(msg)));
  if (!msg[0]) PetscCall(PffIOCompareChannels(grid, &L, file, path, checkpoint, present, msg, sizeof(msg)));
  if (!msg[0]) PetscCall(PffIOCompareBlocks(comm, &L, file, path, dxpl, msg, sizeof(msg)));
  if (!msg[0]) {
    PetscCall(PffH5ReadAttribute_Private(file, "time", PFF_H5T_NATIVE_PETSCREAL, 0, &t, &tfound));
    PetscCall(PffH5ReadAttribute_Private(file, "step", H5T_NATIVE_INT64, 0, &st, &sfound));
    if (!tfound || !sfound) PetscCall(PetscSNPrintf(msg, sizeof(msg), "frame %s: no time or step attribute", path));
  }
  if (!msg[0] && checkpoint && particles) PetscCall(PffIOCheckParticles_Private(file, path, &npart, msg, sizeof(msg)));
  if (msg[0]) {
    PetscCall(PetscFree(xbuf));
    PetscCall(PffIOLayoutDestroy_Private(&L));
    PffCallHDF5(H5Pclose(dxpl));
    PffCallHDF5(H5Fclose(file));
    PetscCall(PetscLogEventEnd(PFF_IORead, 0, 0, 0, 0));
    SETERRQ(comm, PETSC_ERR_FILE_UNEXPECTED, "%s", msg);
  }
  PetscCall(PffIOReadFields(grid, &L, file, dxpl, present));
  if (checkpoint && particles) PetscCall(PffIOReadParticles_Private(particles, grid, comm, file, path, dxpl, npart));
  PetscCall(PffIOLayoutDestroy_Private(&L));
  PffCallHDF5(H5Pclose(dxpl));
  PffCallHDF5(H5Fclose(file));
  for (PetscInt i = 0; i < nextra; i++) extra[i] = (PetscReal)xbuf[i];
  PetscCall(PetscFree(xbuf));
  if (time) *time = t;
  if (step) PetscCall(PetscIntCast(st, step));
  PetscCall(PetscLogEventEnd(PFF_IORead, 0, 0, 0, 0));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffIOReadFrame(PffGrid grid, const char path[], PetscReal *time, PetscInt *step)
{
  PetscFunctionBeginUser;
  PetscCall(PffIOReadFile(grid, NULL, path, PETSC_FALSE, time, step, 0, NULL));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffIOReadCheckpoint(PffGrid grid, PffParticles particles, const char path[], PetscReal *time,
                                   PetscInt *step, PetscInt nextra, PetscReal extra[])
{
  PetscFunctionBeginUser;
  PetscCall(PffIOReadFile(grid, particles, path, PETSC_TRUE, time, step, nextra, extra));
  PetscFunctionReturn(PETSC_SUCCESS);
}

PetscErrorCode PffIOGetCheckpointExtraCount(PffGrid grid, const char path[], PetscInt *nextra)
{
  MPI_Comm  comm;
  hid_t     file;
  int       mark = 0, fextra = 0;
  PetscBool found;

  PetscFunctionBeginUser;
  PetscCall(PffIOInitialize_Private());
  PetscCall(PffIOGetComm_Private(grid, &comm));
  PetscCall(PffIOOpenFrame(comm, path, &file));
  PetscCall(PffH5ReadAttribute_Private(file, "checkpoint", H5T_NATIVE_INT, 0, &mark, &found));
  if (found && mark == 1) PetscCall(PffH5ReadAttribute_Private(file, "nextra", H5T_NATIVE_INT, 0, &fextra, &found));
  PffCallHDF5(H5Fclose(file));
  PetscCheck(mark == 1, comm, PETSC_ERR_FILE_UNEXPECTED,
             "file %s is a frame, not a checkpoint (no root attribute checkpoint = 1); write it with "
             "PffIOWriteCheckpoint",
             path);
  *nextra = found ? fextra : 0;
  PetscFunctionReturn(PETSC_SUCCESS);
}
