"""Opens a frame's XDMF sidecar with ParaView's XDMF reader and checks that it sees every block and
every cell of the HDF5 file, with each field present. Run with pvbatch:

    pvbatch postproc/pv_check_xdmf.py output/grid_demo/frame_0001.xmf

Prints "paraview: blocks <b> cells <c> fields <names> ok" and exits non-zero on a mismatch."""
import sys

import h5py
from paraview.simple import UpdatePipeline, XDMFReader, servermanager

xmf = sys.argv[1]
h5 = xmf[: -len(".xmf")] + ".h5"
with h5py.File(h5, "r") as f:
    nblocks = f["blocks/gid"].shape[0]
    fields = sorted(f["fields"].keys())
    ncells = f["fields"][fields[0]].shape[0]

reader = XDMFReader(FileNames=[xmf])
UpdatePipeline()
data = servermanager.Fetch(reader)
seen_blocks, seen_cells, missing = 0, 0, set()
it = data.NewIterator()
it.InitTraversal()
while not it.IsDoneWithTraversal():
    block = it.GetCurrentDataObject()
    seen_blocks += 1
    seen_cells += block.GetNumberOfCells()
    missing.update(name for name in fields if block.GetCellData().GetArray(name) is None)
    it.GoToNextItem()
if seen_blocks != nblocks or seen_cells != ncells or missing:
    sys.exit(f"paraview: read {seen_blocks} blocks / {seen_cells} cells (file: {nblocks} / {ncells}), missing fields {sorted(missing)}")
print(f"paraview: blocks {seen_blocks} cells {seen_cells} fields {','.join(fields)} ok")
