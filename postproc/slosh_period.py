#!/usr/bin/python3
"""Period of the first sloshing mode from a fluid scene's diagnostics (liquid_cx of fluid_diag.csv), against linear
theory T1 = 2 pi / sqrt(g k tanh(k H)), k = pi / L. Prints one line:
    SLOSH period_s=<T> analytic_s=<T1> error=<relative> crossings=<n> wall_s=<run time>
and fails (exit 1) when fewer than 3 zero crossings are found or the error exceeds --max-error. With --max-umax the
line ends with umax_max=<v>, the largest grid speed of the run (umax_grid), and the run fails when it exceeds the
bound: a small wave moves at centimetres per second, and metres per second are the spikes of a void read as air.
Usage: /usr/bin/python3 postproc/slosh_period.py <fluid_diag.csv> [--length 1] [--depth 0.5] [--g 9.81] [--max-error 1]
       [--max-umax <m/s>]
"""
import argparse
import math
import sys

import numpy as np


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("csv")
    ap.add_argument("--length", type=float, default=1.0, help="tank length along x (m)")
    ap.add_argument("--depth", type=float, default=0.5, help="still water depth (m)")
    ap.add_argument("--g", type=float, default=9.81)
    ap.add_argument("--max-error", type=float, default=1.0, help="largest relative period error accepted")
    ap.add_argument("--max-umax", type=float, help="largest grid speed (umax_grid, m/s) accepted")
    a = ap.parse_args()
    data = np.genfromtxt(a.csv, delimiter=",", names=True)
    t, cx, wall = data["t"], data["liquid_cx"], data["wall_s"]
    umax = None
    if a.max_umax is not None:
        if "umax_grid" not in data.dtype.names:
            print("SLOSH %s: no column umax_grid for --max-umax" % a.csv)
            return 1
        umax = float(np.max(data["umax_grid"]))
    keep = t > 0
    t, cx = t[keep], cx[keep]
    x = cx - 0.5 * (cx.max() + cx.min())
    # samples exactly on the mean carry no sign: a crossing is found between their neighbours
    nz = x != 0
    t, x = t[nz], x[nz]
    crossings = []
    for i in range(len(x) - 1):
        if x[i] * x[i + 1] < 0:
            crossings.append(t[i] + (t[i + 1] - t[i]) * x[i] / (x[i] - x[i + 1]))
    k = math.pi / a.length
    t1 = 2 * math.pi / math.sqrt(a.g * k * math.tanh(k * a.depth))
    if len(crossings) < 3:
        print("SLOSH crossings=%d: too few zero crossings of liquid_cx" % len(crossings))
        return 1
    period = 2 * (crossings[-1] - crossings[0]) / (len(crossings) - 1)
    err = (period - t1) / t1
    line = "SLOSH period_s=%.4f analytic_s=%.4f error=%.4f crossings=%d wall_s=%.1f" % (
        period, t1, err, len(crossings), float(np.sum(wall)))
    if umax is not None:
        line += " umax_max=%.3f" % umax
    print(line)
    ok = abs(err) <= a.max_error and (umax is None or umax <= a.max_umax)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
