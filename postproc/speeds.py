#!/usr/bin/env python3
"""Largest particle and grid speeds of a run (fluid_diag.csv), for velocity spikes (docs/tallcell.md).

The particles' largest speed per step is the step's CFL number times h / dt (the time step comes from it), h the
finest cell size (--h); the grid's is umax_grid, the largest |u| on any face of the projected velocity (it includes
faces that solids nearly close, whose u the particles do not read). Prints one line with both maxima, when they
occur and the steps above --above, and exits 1 when the particles' maximum exceeds --max-particle.
"""
import argparse
import csv
import sys


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv", help="fluid_diag.csv of a run")
    ap.add_argument("--h", type=float, required=True, help="finest cell size (m)")
    ap.add_argument("--max-particle", type=float, default=float("inf"), help="bound on the particles' speed (m/s)")
    ap.add_argument("--above", type=float, default=5.0, help="count the steps above this speed (m/s)")
    a = ap.parse_args()
    rows = [r for r in csv.DictReader(open(a.csv)) if float(r["dt"]) > 0]
    if not rows:
        print(f"speeds: no steps in {a.csv}", file=sys.stderr)
        return 2
    vp = [(float(r["cfl"]) * a.h / float(r["dt"]), float(r["t"])) for r in rows]
    vg = [(float(r["umax_grid"]), float(r["t"])) for r in rows]
    pmax, gmax = max(vp), max(vg)
    np_above = sum(v > a.above for v, _ in vp)
    ng_above = sum(v > a.above for v, _ in vg)
    print(f"SPEEDS steps={len(rows)} particle_max={pmax[0]:.3f} (t={pmax[1]:.4f}) grid_max={gmax[0]:.3f} "
          f"(t={gmax[1]:.4f}) steps_above_{a.above:g}: particles={np_above} grid={ng_above} "
          f"bound={a.max_particle:g}")
    return 0 if pmax[0] <= a.max_particle else 1


if __name__ == "__main__":
    sys.exit(main())
