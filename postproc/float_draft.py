#!/usr/bin/env python3
"""Mean height of a floating body against Archimedes (config/tall_float_small.yaml, docs/tallcell.md).

Reads <run>/bodies.csv (pfflip's rigid-body log), averages the body's centre height over t >= --from (trapezoid
rule, so that uneven steps weigh by their length), and compares it with the equilibrium of a box of the given
size and density floating on a pool in a tank of the given floor area: draft d = (rho_body / rho_liquid) height,
the level = (liquid volume + displaced volume) / area, the centre at level - d + height / 2. The liquid volume is
the pool's (--pool times the area), or with --measured the run's own at each time (liquid_volume of
<run>/fluid_diag.csv), which separates the body's balance from a drift of the liquid's volume. Prints one line
with both heights and the error as a fraction of the draft; exits 1 when it exceeds --tol. With --periods the
mean is over whole periods of the body's oscillation (from the first to the last upward crossing of the window's
mean height), so that a part period at either end of the window does not bias it.
"""
import argparse
import csv
import sys


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", help="output directory holding bodies.csv")
    ap.add_argument("--body", type=int, default=0)
    ap.add_argument("--size", default="0.3,0.1,0.3", help="box extents x,y,z (m)")
    ap.add_argument("--density", type=float, default=500.0)
    ap.add_argument("--rho", type=float, default=1000.0, help="liquid density")
    ap.add_argument("--pool", type=float, default=0.4, help="still pool depth without the body (m)")
    ap.add_argument("--area", type=float, default=1.0, help="tank floor area (m^2)")
    ap.add_argument("--from", dest="t0", type=float, default=1.5, help="average over t >= this (s)")
    ap.add_argument("--tol", type=float, default=0.02, help="largest error as a fraction of the draft")
    ap.add_argument("--measured", action="store_true", help="the level from the run's liquid volume at each time")
    ap.add_argument("--periods", action="store_true", help="average over whole periods of the oscillation")
    a = ap.parse_args()
    sx, sy, sz = (float(v) for v in a.size.split(","))
    draft = a.density / a.rho * sy
    disp = sx * sz * draft
    volume = {}
    if a.measured:
        with open(f"{a.run}/fluid_diag.csv") as f:
            for row in csv.DictReader(f):
                volume[int(row["step"])] = float(row["liquid_volume"])
    t, y, yeq = [], [], []
    with open(f"{a.run}/bodies.csv") as f:
        for row in csv.DictReader(f):
            if int(row["body"]) != a.body or float(row["t"]) < a.t0:
                continue
            vl = volume.get(int(row["step"]), a.pool * a.area) if a.measured else a.pool * a.area
            t.append(float(row["t"]))
            y.append(float(row["y"]))
            yeq.append((vl + disp) / a.area - draft + 0.5 * sy)
    if len(t) < 2:
        print(f"float_draft: fewer than two samples after t = {a.t0} in {a.run}/bodies.csv", file=sys.stderr)
        return 2

    def mean(v):
        return sum(0.5 * (v[i] + v[i + 1]) * (t[i + 1] - t[i]) for i in range(len(t) - 1)) / (t[-1] - t[0])

    nper = 0
    if a.periods:
        ym = mean(y)
        up = [i for i in range(len(t) - 1) if y[i] < ym <= y[i + 1]]
        if len(up) < 2:
            print(f"float_draft: fewer than two upward crossings of the mean height after t = {a.t0}", file=sys.stderr)
            return 2
        nper = len(up) - 1
        lo, hi = up[0], up[-1] + 1
        t, y, yeq = t[lo:hi], y[lo:hi], yeq[lo:hi]

    y_mean, y_eq = mean(y), mean(yeq)
    err = (y_mean - y_eq) / draft
    print(f"float_draft: mean centre height {y_mean:.5f} m over t in [{t[0]:.3f}, {t[-1]:.3f}] s, Archimedes {y_eq:.5f} m "
          f"({'the run' + chr(39) + 's liquid volume' if a.measured else 'the pool'}, draft {draft:.4f} m): "
          f"error {100 * err:+.2f} % of the draft (bound {100 * a.tol:.1f} %), range {min(y):.5f}..{max(y):.5f} m"
          + (f", {nper} whole periods" if a.periods else ""))
    return 0 if abs(err) <= a.tol else 1


if __name__ == "__main__":
    sys.exit(main())
