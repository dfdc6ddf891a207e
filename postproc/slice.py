#!/usr/bin/python3
"""Mid-plane slice of one field of a pfflip frame, as a PNG.

The multiresolution blocks are assembled onto the finest lattice (a level-l cell is repeated 2^l
times along each axis), so the picture shows the resolution the solver actually had; inactive blocks
are left blank. By default the slice is the finest-lattice cell layer k = nz/2 (z = middle).

    slice.py frame.h5 phi                      # writes frame_phi_z.png
    slice.py frame.h5 vel_x --axis y -o v.png  # any /fields dataset, any axis
    slice.py frame.h5 phi --blocks             # outline the blocks, shaded by level

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


def main(argv=None):
    ap = argparse.ArgumentParser(description="Render a mid-plane slice of a frame's field to PNG.")
    ap.add_argument("frame", help="frame file (.h5)")
    ap.add_argument("field", help="dataset under /fields (a cell channel, or a face component such as vel_x)")
    ap.add_argument("-o", "--output", help="PNG to write (default <frame>_<field>_<axis>.png)")
    ap.add_argument("--axis", choices="xyz", default="z", help="normal of the slice plane (default z)")
    ap.add_argument("--index", type=int, help="finest-lattice layer (default the middle one)")
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
            if args.field in channels and channels[args.field][0] == "face":
                raise FrameError(f"{args.field} is a face channel: name one component, "
                                 f"{', '.join(channels[args.field][1])}")
            img, (a, b), extent = f.finest_slice(args.field, axis, args.index)
            index = args.index if args.index is not None else int(f.raster[axis] * f.block_size // 2)
            pos = f.origin[axis] + (index + 0.5) * f.h0
            fig, ax = plt.subplots(figsize=(7, 7 * img.shape[0] / max(img.shape[1], 1) + 0.8))
            im = ax.imshow(np.ma.masked_invalid(img), origin="lower", extent=extent, cmap=args.cmap,
                           interpolation="nearest")
            fig.colorbar(im, ax=ax, shrink=0.8, label=args.field)
            if args.blocks:
                side = f.block_size * f.h0
                ib = index // f.block_size
                for p in np.nonzero(f.block_ijk[:, axis] == ib)[0]:
                    lo = f.block_origin[p]
                    ax.add_patch(plt.Rectangle((lo[a], lo[b]), side, side, fill=False, lw=0.5,
                                               ec=str(0.2 + 0.25 * f.block_level[p])))
            ax.set_xlabel("xyz"[a])
            ax.set_ylabel("xyz"[b])
            ax.set_title(f"{args.field} at {args.axis} = {pos:.4g}, step {f.step}, t = {f.time:.4g}")
            out = args.output or f"{os.path.splitext(args.frame)[0]}_{args.field}_{args.axis}.png"
            fig.savefig(out, dpi=args.dpi, bbox_inches="tight")
            plt.close(fig)
    except (FrameError, KeyError, OSError) as e:
        print(f"{args.frame}: {e}", file=sys.stderr)
        return 1
    print(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
