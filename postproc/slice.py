#!/usr/bin/python3
"""Slice of one or more fields of a pfflip frame through one plane, as a PNG.

The multiresolution blocks are assembled onto the finest lattice (a level-l cell is repeated 2^l
times along each axis), so the picture shows the resolution the solver actually had; inactive blocks
are left blank. By default the slice is the finest-lattice cell layer k = nz/2 (z = middle). Several
fields are drawn side by side, each with its own colour bar, on the same plane.

    slice.py frame.h5 phi                      # writes frame_phi_z.png
    slice.py frame.h5 vel_x --axis y -o v.png  # any /fields dataset, any axis
    slice.py frame.h5 phi --blocks             # outline the blocks, shaded by level
    slice.py frame.h5 phi vorticity -o out.png --axis z --pos 0.5   # two panels, plane z = 0.5

--pos is a world coordinate along --axis (the layer of the finest lattice that contains it);
--index names the layer directly. A field that the frame lacks ends the run with one line naming it
and the available datasets, and exit status 1.

Needs h5py, numpy and matplotlib (Debian python3-matplotlib); uses the Agg backend, no display.
"""
import argparse
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (the backend must be chosen first)
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pff_frame import Frame, FrameError  # noqa: E402


def layer_index(f, axis, index, pos):
    """Finest-lattice layer from --index or --pos (default: the middle one)."""
    ncells = int(f.raster[axis] * f.block_size)
    if pos is not None:
        lo = f.origin[axis]
        hi = lo + ncells * f.h0
        if not lo <= pos <= hi:
            raise FrameError(f"--pos {pos:g} is outside the domain along {'xyz'[axis]}: [{lo:g}, {hi:g}]")
        return min(int((pos - lo) / f.h0), ncells - 1)
    return index if index is not None else ncells // 2


def main(argv=None):
    ap = argparse.ArgumentParser(description="Render a slice of one or more fields of a frame to PNG.")
    ap.add_argument("frame", help="frame file (.h5)")
    ap.add_argument("fields", nargs="+", metavar="field",
                    help="dataset under /fields (a cell channel, or a face component such as vel_x); several are "
                         "drawn side by side")
    ap.add_argument("-o", "--output", help="PNG to write (default <frame>_<field>[-<field>...]_<axis>.png)")
    ap.add_argument("--axis", choices="xyz", default="z", help="normal of the slice plane (default z)")
    where = ap.add_mutually_exclusive_group()
    where.add_argument("--index", type=int, help="finest-lattice layer (default the middle one)")
    where.add_argument("--pos", type=float, help="world coordinate of the plane along --axis")
    ap.add_argument("--blocks", action="store_true", help="outline the blocks the plane cuts")
    ap.add_argument("--cmap", default="viridis")
    ap.add_argument("--dpi", type=int, default=150)
    args = ap.parse_args(argv)

    if not os.path.exists(args.frame):
        print(f"cannot open frame {args.frame}: no such file", file=sys.stderr)
        return 1
    axis = "xyz".index(args.axis)
    try:
        with Frame(args.frame) as f:
            channels = f.channels()
            available = [name for name, _, _, _ in f.datasets()]
            for field in args.fields:
                if field in channels and channels[field][0] == "face":
                    raise FrameError(f"{field} is a face channel: name one component, "
                                     f"{', '.join(channels[field][1])}")
                if field not in available:
                    raise FrameError(f"no field {field} in this frame; it has {', '.join(available)}")
            index = layer_index(f, axis, args.index, args.pos)
            pos = f.origin[axis] + (index + 0.5) * f.h0
            images = [f.finest_slice(field, axis, index) for field in args.fields]
            img0, (a, b), _ = images[0]
            npanel = len(images)
            fig, axes = plt.subplots(1, npanel, squeeze=False,
                                     figsize=(7 * npanel, 7 * img0.shape[0] / max(img0.shape[1], 1) + 0.8))
            for ax, field, (img, _, extent) in zip(axes[0], args.fields, images):
                im = ax.imshow(np.ma.masked_invalid(img), origin="lower", extent=extent, cmap=args.cmap,
                               interpolation="nearest")
                fig.colorbar(im, ax=ax, shrink=0.8, label=field)
                if args.blocks:
                    side = f.block_size * f.h0
                    ib = index // f.block_size
                    for p in np.nonzero(f.block_ijk[:, axis] == ib)[0]:
                        lo = f.block_origin[p]
                        ax.add_patch(plt.Rectangle((lo[a], lo[b]), side, side, fill=False, lw=0.5,
                                                   ec=str(0.2 + 0.25 * f.block_level[p])))
                ax.set_xlabel("xyz"[a])
                ax.set_ylabel("xyz"[b])
                ax.set_title(f"{field} at {args.axis} = {pos:.4g}, step {f.step}, t = {f.time:.4g}")
            out = args.output or f"{os.path.splitext(args.frame)[0]}_{'-'.join(args.fields)}_{args.axis}.png"
            fig.savefig(out, dpi=args.dpi, bbox_inches="tight")
            plt.close(fig)
    except (FrameError, KeyError, OSError) as e:
        print(f"{args.frame}: {e}", file=sys.stderr)
        return 1
    print(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
