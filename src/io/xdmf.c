/* XDMF sidecar of a frame (Output stage), so that ParaView and VisIt open the HDF5 file directly.

   A spatial collection holds one uniform grid per active block, in Morton order: a 3DCoRectMesh of
   (n+1)^3 nodes with ORIGIN_DXDYDZ geometry (XDMF lists these z, y, x), and one cell-centred scalar
   per field dataset, read through a HyperSlab of the 1-D dataset (start = block offset, stride 1,
   count n^3) reshaped to n x n x n (z slowest, which matches our x-fastest storage). Face components
   appear as cell data too; docs/file-format.md says where they really sit. Rank 0 writes it alone:
   the replicated raster tells it every block. Only the channels flagged for output appear.

   Beside the block collection, a frame with particles gets a second uniform grid "particles": a
   Polyvertex topology (NumberOfElements = N, NodesPerElement = 1, no connectivity array: vertex i is
   point i) on XYZ geometry from /particles/x, with the node attributes type (scalar) and velocity
   (vector, /particles/v). */
#include <errno.h>
#include <stdio.h>
#include "h5util.h"

/* Writes s with the five XML special characters escaped (names come from users and file systems). */
static void PffXmlPuts(FILE *fp, const char s[])
{
  for (const char *c = s; *c; c++) {
    switch (*c) {
    case '&':
      fputs("&amp;", fp);
      break;
    case '<':
      fputs("&lt;", fp);
      break;
    case '>':
      fputs("&gt;", fp);
      break;
    case '"':
      fputs("&quot;", fp);
      break;
    case '\'':
      fputs("&apos;", fp);
      break;
    default:
      fputc(*c, fp);
    }
  }
}

PetscErrorCode PffIOWriteXdmf_Private(PffGrid grid, const PffFrameLayout *L, const char xmfpath[], const char h5name[],
                                      PetscReal time, PetscInt64 nparticles, int *err)
{
  const PetscInt *level;
  PetscInt        nb[3], n0, nch;
  PetscReal       origin[3], h0;
  FILE           *fp;

  PetscFunctionBeginUser;
  *err = 0;
  PetscCall(PffGridGetRaster(grid, nb, &level, NULL));
  PetscCall(PffGridGetSizes(grid, &n0, NULL, origin, &h0, NULL));
  PetscCall(PffGridGetNumChannels(grid, &nch));
  const PetscInt64 total = L->offset[L->nactive];

  fp = fopen(xmfpath, "w");
  if (!fp) {
    *err = errno;
    PetscFunctionReturn(PETSC_SUCCESS);
  }
  errno = 0;
  fprintf(fp, "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n<Xdmf Version=\"2.0\">\n <Domain>\n");
  fprintf(fp, "  <Grid Name=\"frame\" GridType=\"Collection\" CollectionType=\"Spatial\">\n");
  fprintf(fp, "   <Time Value=\"%.17g\"/>\n", (double)time);
  for (PetscInt p = 0; p < L->nactive; p++) {
    const PetscInt gid = L->order[p], l = level[gid], n = n0 >> l;
    PetscInt       ijk[3];
    PffRasterCoordinates(nb, gid, ijk);
    PetscReal lo[3];
    /* The same arithmetic as PffGridGetBlockInfo, so sidecar and /blocks/origin agree to the bit. */
    for (int d = 0; d < 3; d++) lo[d] = origin[d] + (PetscReal)(ijk[d] * n0) * h0;
    const double h = (double)(h0 * (PetscReal)((PetscInt)1 << l));

    fprintf(fp, "   <Grid Name=\"block%" PetscInt_FMT "\" GridType=\"Uniform\">\n", gid);
    fprintf(fp,
            "    <Topology TopologyType=\"3DCoRectMesh\" Dimensions=\"%" PetscInt_FMT " %" PetscInt_FMT
            " %" PetscInt_FMT "\"/>\n",
            n + 1, n + 1, n + 1);
    fprintf(fp, "    <Geometry GeometryType=\"ORIGIN_DXDYDZ\">\n");
    fprintf(fp,
            "     <DataItem Name=\"Origin\" Dimensions=\"3\" NumberType=\"Float\" Precision=\"8\" Format=\"XML\">%.17g "
            "%.17g %.17g</DataItem>\n",
            (double)lo[2], (double)lo[1], (double)lo[0]);
    fprintf(fp,
            "     <DataItem Name=\"Spacing\" Dimensions=\"3\" NumberType=\"Float\" Precision=\"8\" "
            "Format=\"XML\">%.17g %.17g %.17g</DataItem>\n",
            h, h, h);
    fprintf(fp, "    </Geometry>\n");
    for (PetscInt c = 0; c < nch; c++) {
      const char    *name;
      PffChannelKind kind;
      PetscInt       ncomp;
      PetscBool      write;

      PetscCall(PffGridGetChannelOutput(grid, c, &write));
      if (!write) continue;
      PetscCall(PffGridGetChannelInfo(grid, c, &name, &kind, &ncomp, NULL));
      for (PetscInt comp = 0; comp < ncomp; comp++) {
        char dname[256];

        PetscCall(PffIOFieldName_Private(name, kind, comp, dname, sizeof(dname)));
        fprintf(fp, "    <Attribute Name=\"");
        PffXmlPuts(fp, dname);
        fprintf(fp, "\" AttributeType=\"Scalar\" Center=\"Cell\">\n");
        fprintf(fp,
                "     <DataItem ItemType=\"HyperSlab\" Dimensions=\"%" PetscInt_FMT " %" PetscInt_FMT " %" PetscInt_FMT
                "\" Type=\"HyperSlab\">\n",
                n, n, n);
        fprintf(fp,
                "      <DataItem Dimensions=\"3 1\" NumberType=\"Int\" Precision=\"8\" Format=\"XML\">%" PetscInt64_FMT
                " 1 %" PetscInt64_FMT "</DataItem>\n",
                L->offset[p], (PetscInt64)n * n * n);
        fprintf(fp,
                "      <DataItem Dimensions=\"%" PetscInt64_FMT
                "\" NumberType=\"Float\" Precision=\"4\" Format=\"HDF\">",
                total);
        PffXmlPuts(fp, h5name);
        fprintf(fp, ":/fields/");
        PffXmlPuts(fp, dname);
        fprintf(fp, "</DataItem>\n     </DataItem>\n    </Attribute>\n");
      }
    }
    fprintf(fp, "   </Grid>\n");
  }
  fprintf(fp, "  </Grid>\n");
  if (nparticles > 0) {
    /* The particles: a Polyvertex topology (one vertex per element, implicit connectivity 0..N-1) over
       the float32 positions of /particles/x, with type and velocity as node data. */
    fprintf(fp, "  <Grid Name=\"particles\" GridType=\"Uniform\">\n");
    fprintf(fp, "   <Time Value=\"%.17g\"/>\n", (double)time);
    fprintf(fp,
            "   <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"%" PetscInt64_FMT
            "\" NodesPerElement=\"1\"/>\n",
            nparticles);
    fprintf(fp, "   <Geometry GeometryType=\"XYZ\">\n");
    fprintf(fp,
            "    <DataItem Dimensions=\"%" PetscInt64_FMT " 3\" NumberType=\"Float\" Precision=\"4\" Format=\"HDF\">",
            nparticles);
    PffXmlPuts(fp, h5name);
    fprintf(fp, ":/particles/x</DataItem>\n   </Geometry>\n");
    fprintf(fp, "   <Attribute Name=\"type\" AttributeType=\"Scalar\" Center=\"Node\">\n");
    fprintf(fp, "    <DataItem Dimensions=\"%" PetscInt64_FMT "\" NumberType=\"UChar\" Precision=\"1\" Format=\"HDF\">",
            nparticles);
    PffXmlPuts(fp, h5name);
    fprintf(fp, ":/particles/type</DataItem>\n   </Attribute>\n");
    fprintf(fp, "   <Attribute Name=\"velocity\" AttributeType=\"Vector\" Center=\"Node\">\n");
    fprintf(fp,
            "    <DataItem Dimensions=\"%" PetscInt64_FMT " 3\" NumberType=\"Float\" Precision=\"4\" Format=\"HDF\">",
            nparticles);
    PffXmlPuts(fp, h5name);
    fprintf(fp, ":/particles/v</DataItem>\n   </Attribute>\n  </Grid>\n");
  }
  fprintf(fp, " </Domain>\n</Xdmf>\n");
  if (ferror(fp)) *err = errno ? errno : EIO;
  if (fclose(fp) != 0 && !*err) *err = errno ? errno : EIO;
  PetscFunctionReturn(PETSC_SUCCESS);
}
