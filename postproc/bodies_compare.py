#!/usr/bin/env python3
"""Compares the rigid bodies of two runs (bodies.csv of pfflip's liquid model) at their common final time.

Prints the largest distance between the bodies' centres and the largest difference of their velocities, and
exits 1 when the distance exceeds --tol (m) or the runs did not end at the same time. For checking that a scene
gives the same bodies on any number of ranks.
"""
import argparse
import csv
import math
import sys


def last_rows(path):
    rows = list(csv.DictReader(open(path)))
    t = max(float(r["t"]) for r in rows)
    return t, {int(r["body"]): r for r in rows if float(r["t"]) == t}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run_a")
    ap.add_argument("run_b")
    ap.add_argument("--tol", type=float, default=1e-4, help="largest distance of the centres (m)")
    a = ap.parse_args()
    ta, ra = last_rows(f"{a.run_a}/bodies.csv")
    tb, rb = last_rows(f"{a.run_b}/bodies.csv")
    if abs(ta - tb) > 1e-12 * max(1.0, ta) or sorted(ra) != sorted(rb):
        print(f"bodies_compare: the runs end at t = {ta} and {tb} with {len(ra)} and {len(rb)} bodies")
        return 1
    dx = max(math.dist([float(ra[i][k]) for k in "xyz"], [float(rb[i][k]) for k in "xyz"]) for i in ra)
    dv = max(abs(float(ra[i][k]) - float(rb[i][k])) for i in ra for k in ("vx", "vy", "vz"))
    print(f"bodies_compare: {len(ra)} bodies at t = {ta:.6g} s: largest centre distance {dx:.3e} m (bound {a.tol:.1e}), "
          f"largest velocity difference {dv:.3e} m/s")
    return 0 if dx <= a.tol else 1


if __name__ == "__main__":
    sys.exit(main())
