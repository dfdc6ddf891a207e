#!/usr/bin/python3
"""Step-to-step swings of the liquid volume in a scene's diagnostics (the liquid_volume column, sum phi V after each
step; --column gas_volume for the gas's). A volume that the correction and its control hold moves smoothly; a loop that lags or overshoots makes it swing
with a period of two steps (docs/validation.md, "Holes after a grid change"). Prints one line:
    VOLSWING steps=<n> largest=<largest |change| in % of the first volume> alternating=<k> threshold=<%>
             end=<drift of the last row, %> low=<lowest drift, %> high=<highest drift, %>
where k counts the steps whose change and the previous step's are both above the threshold and of opposite sign.
Fails (exit 1) when k exceeds --max-alternating or the largest change exceeds --max-step, or without the column.
Usage: /usr/bin/python3 postproc/volume_swings.py <diag.csv> [--threshold 0.1] [--max-alternating 0] [--max-step 100]
       [--column liquid_volume]
"""
import argparse
import sys

import numpy as np


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("csv")
    ap.add_argument("--threshold", type=float, default=0.1, help="change (in %% of the first volume) that counts")
    ap.add_argument("--max-alternating", type=int, default=0, help="alternating steps accepted")
    ap.add_argument("--max-step", type=float, default=100.0, help="largest change accepted, in %% of the first volume")
    ap.add_argument("--column", default="liquid_volume", help="the volume column (liquid_volume or gas_volume)")
    a = ap.parse_args()
    data = np.genfromtxt(a.csv, delimiter=",", names=True)
    if data.dtype.names is None or a.column not in data.dtype.names:
        print("VOLSWING %s: no column %s" % (a.csv, a.column))
        return 1
    v = np.atleast_1d(data[a.column]).astype(float)
    if v.size < 3 or v[0] <= 0:
        print("VOLSWING %s: fewer than 3 rows or no liquid at the start" % a.csv)
        return 1
    d = 100.0 * np.diff(v) / v[0]
    big = np.abs(d) > a.threshold
    alternating = int(np.sum(big[1:] & big[:-1] & (d[1:] * d[:-1] < 0)))
    largest = float(np.max(np.abs(d)))
    drift = 100.0 * (v / v[0] - 1)
    print("VOLSWING steps=%d largest=%.4f alternating=%d threshold=%g end=%+.4f low=%+.4f high=%+.4f" %
          (d.size, largest, alternating, a.threshold, drift[-1], drift.min(), drift.max()))
    if alternating > a.max_alternating or largest > a.max_step:
        print("VOLSWING: beyond the bounds (alternating %d > %d or largest %.4f > %g)" %
              (alternating, a.max_alternating, largest, a.max_step))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
