#!/usr/bin/python3
"""Where the liquid volume sum(phi V) of two-phase frames sits (docs/validation.md, "What the dam break's largest
drift is made of"): the cells of phi < 1/2 (air cells holding a little liquid: spray and the air side of the
interface), of 1/2 <= phi < 1 (the liquid side of the interface) and of phi = 1 (bulk), against the volume of the
liquid particles (their count times the volume a particle stands for at seeding, h0^3 8^level / ppc) and the number
of liquid particles flagged as droplet candidates (Sec. 3.4). One CSV row per frame on standard output (or -o) and a
last line
    PHISPLIT frames=<n> low_share_max=<largest share of sum(phi V) in phi < 1/2 cells, %> droplets_max=<count>
Fails (exit 1) when a frame has no phi field or no particles, or when low_share_max exceeds --max-low-share.
Usage: /usr/bin/python3 postproc/phi_split.py frame_0000.h5 [frame_0001.h5 ...] [--ppc 8] [-o split.csv]
       [--max-low-share 100]
"""
import argparse
import csv
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pff_frame import Frame  # noqa: E402

DROPLET = 0x1  # PFF_PARTICLE_FLAG_DROPLET (include/pff/particles.h)
LIQUID = 0


def split(path, ppc):
    with Frame(path) as f:
        if "phi" not in f.h5["fields"] or "particles" not in f.h5:
            raise ValueError("%s: no phi field or no particles" % path)
        phi = f.h5["fields/phi"][...].astype(np.float64)
        vol = np.repeat((f.h0 * 2.0 ** f.block_level) ** 3, f.block_n ** 3)
        kind = f.h5["particles/type"][...]
        level = f.h5["particles/level"][...].astype(np.int64)
        flags = f.h5["particles/flags"][...]
        liquid = kind == LIQUID
        low, mid, full = phi < 0.5, (phi >= 0.5) & (phi < 1), phi >= 1
        total = float(np.sum(phi * vol))
        return {
            "frame": os.path.basename(path),
            "t": f.time,
            "step": f.step,
            "phi_volume": total,
            "low": float(np.sum((phi * vol)[low])),
            "interface": float(np.sum((phi * vol)[mid])),
            "bulk": float(np.sum((phi * vol)[full])),
            "low_share_pct": 100.0 * float(np.sum((phi * vol)[low])) / total if total > 0 else 0.0,
            "particle_volume": float(np.sum(f.h0 ** 3 * 8.0 ** level[liquid])) / ppc,
            "liquid_particles": int(np.count_nonzero(liquid)),
            "droplets": int(np.count_nonzero(liquid & ((flags & DROPLET) != 0))),
        }


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("frames", nargs="+")
    ap.add_argument("--ppc", type=float, default=8.0, help="particles per cell at seeding (default 8)")
    ap.add_argument("-o", "--output", help="CSV file (default: standard output)")
    ap.add_argument("--max-low-share", type=float, default=100.0, help="largest share of phi < 1/2 cells accepted, %%")
    a = ap.parse_args()
    try:
        rows = [split(p, a.ppc) for p in a.frames]
    except (ValueError, KeyError, OSError) as e:
        print("PHISPLIT %s" % e)
        return 1
    out = open(a.output, "w", newline="") if a.output else sys.stdout
    w = csv.DictWriter(out, fieldnames=list(rows[0].keys()))
    w.writeheader()
    w.writerows(rows)
    if a.output:
        out.close()
    share = max(r["low_share_pct"] for r in rows)
    print("PHISPLIT frames=%d low_share_max=%.3f droplets_max=%d" % (len(rows), share, max(r["droplets"] for r in rows)))
    return 0 if share <= a.max_low_share else 1


if __name__ == "__main__":
    sys.exit(main())
