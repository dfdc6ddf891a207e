#!/usr/bin/python3
"""The liquid layer by layer in a frame or checkpoint with particles (docs/validation.md, "Long still pools on
multi-level grids"): per layer of finest cells along an axis, the liquid particles' volume as a fraction of the layer
(their volume is h0^3 8^level / ppc, the volume a particle stands for at seeding), their count per level, and the
sum(phi V) of the cells whose centres lie in the layer. With --boundary y it also counts the liquid particles of
--level within --width below the plane y (the sliver beside a coarse-fine boundary where the face measure let them
pack). One CSV row per layer on standard output (or -o) and a last line
    LEVELROWS layers=<n> liquid=<total liquid particle volume> sliver=<count> fill_min=<lowest fill> fill_max=<highest>
where fill_min / fill_max range over the layers that are full of liquid, between --from and --to (layer indices).
Fails (exit 1) without particles or a phi field, or when the sliver count exceeds --max-sliver.
Usage: /usr/bin/python3 postproc/level_rows.py checkpoint.h5 [--axis 1] [--ppc 8] [--boundary 0.4 --level 0
       --width 0.005] [--from 10 --to 19] [--max-sliver N] [-o rows.csv]
"""
import argparse
import csv
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pff_frame import Frame  # noqa: E402

LIQUID = 0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("file")
    ap.add_argument("--axis", type=int, default=1, choices=(0, 1, 2))
    ap.add_argument("--ppc", type=int, default=8, help="particles per cell at seeding")
    ap.add_argument("--boundary", type=float, help="world coordinate of a level boundary along the axis")
    ap.add_argument("--level", type=int, default=0, help="particle level counted in the sliver")
    ap.add_argument("--width", type=float, default=0.005, help="sliver width below the boundary (world units)")
    ap.add_argument("--from", dest="lo", type=int, default=0, help="first layer of the fill range")
    ap.add_argument("--to", dest="hi", type=int, default=-1, help="last layer of the fill range (-1: the last)")
    ap.add_argument("--max-sliver", type=int, default=-1, help="largest sliver count accepted (-1: no bound)")
    ap.add_argument("-o", "--output")
    a = ap.parse_args()
    with Frame(a.file) as f:
        if "particles" not in f.h5 or "phi" not in f.h5["fields"]:
            print("LEVELROWS %s: no particles or no phi field" % a.file)
            return 1
        ax = a.axis
        cells = f.raster * f.block_size
        nl = int(cells[ax])
        area = float(np.prod([cells[d] * f.h0 for d in range(3) if d != ax]))
        x = f.h5["particles/x"][...].astype(np.float64)
        kind = f.h5["particles/type"][...]
        level = f.h5["particles/level"][...].astype(np.int64)
        liq = kind == LIQUID
        vol = f.h0 ** 3 * 8.0 ** level / a.ppc
        layer = np.clip(np.floor((x[:, ax] - f.origin[ax]) / f.h0).astype(np.int64), 0, nl - 1)
        fill = np.bincount(layer[liq], weights=vol[liq], minlength=nl) / (f.h0 * area)
        nlev = max(int(level.max()) + 1 if level.size else 1, f.levels)
        counts = np.zeros((nl, nlev), dtype=np.int64)
        np.add.at(counts, (layer[liq], level[liq]), 1)
        phiv = np.zeros(nl)
        phi = f.field("phi").astype(np.float64)
        for p in range(f.nactive):
            h = f.h0 * 2.0 ** int(f.block_level[p])
            v = f.block_values("phi", p, phi)  # [k, j, i]
            n = v.shape[0]
            sums = v.sum(axis=tuple(d for d in range(3) if d != 2 - ax)) * h ** 3  # one value per cell layer
            centres = f.block_origin[p][ax] + (np.arange(n) + 0.5) * h
            idx = np.clip(np.floor((centres - f.origin[ax]) / f.h0).astype(np.int64), 0, nl - 1)
            np.add.at(phiv, idx, sums)
        sliver = 0
        if a.boundary is not None:
            c = x[:, ax]
            sliver = int(np.sum(liq & (level == a.level) & (c < a.boundary) & (c >= a.boundary - a.width)))
    hi = nl - 1 if a.hi < 0 else a.hi
    rng = [i for i in range(a.lo, hi + 1) if fill[i] > 0.5]
    fmin = min(fill[i] for i in rng) if rng else float("nan")
    fmax = max(fill[i] for i in rng) if rng else float("nan")
    out = open(a.output, "w", newline="") if a.output else sys.stdout
    w = csv.writer(out)
    w.writerow(["layer", "fill"] + ["liquid_level%d" % l for l in range(nlev)] + ["phi_volume"])
    for i in range(nl):
        w.writerow([i, "%.4f" % fill[i]] + [int(c) for c in counts[i]] + ["%.6f" % phiv[i]])
    if a.output:
        out.close()
    print("LEVELROWS layers=%d liquid=%.6f sliver=%d fill_min=%.4f fill_max=%.4f" %
          (nl, float(np.sum(vol[liq])), sliver, fmin, fmax))
    if 0 <= a.max_sliver < sliver:
        print("LEVELROWS: %d liquid particles of level %d within %g below %g (more than %d)" %
              (sliver, a.level, a.width, a.boundary, a.max_sliver))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
