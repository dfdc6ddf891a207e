#!/usr/bin/python3
"""What an adaptive run can save at most against the uniform run of the same scene, from the grid and the particles it
kept (the columns active_cells and particles of the two diagnostics CSVs; docs/benchmarks.md, "What the adaptive grid
can save"). Each step of the adaptive run is weighed by the fraction of the uniform run's cells and particles it held;
a run whose cost per step followed its cells (the solves) or its particles (the particle stages) exactly, with an
adaptation that cost nothing, would take that fraction of a uniform step. Prints one line:
    ADAPTBOUND steps=<adaptive>/<uniform> cells=<mean fraction> particles=<mean fraction> end_cells=<last fraction>
               bound_cells=<x> bound_particles=<x> measured=<uniform wall / adaptive wall>
with bound_* = (uniform steps) / (sum over the adaptive steps of the fraction), and measured from the wall_s columns.
With -o, writes one row per adaptive step: step, t_over_t0, cells_fraction, particles_fraction, wall_s.
Fails (exit 1) when a column is missing or the uniform run has no cells or particles.
Usage: /usr/bin/python3 postproc/adaptive_bound.py <adaptive_diag.csv> <uniform_diag.csv> [-o steps.csv]
"""
import argparse
import sys

import numpy as np

NEED = ("step", "t_over_t0", "particles", "wall_s", "active_cells")


def load(path):
    d = np.genfromtxt(path, delimiter=",", names=True)
    if d.dtype.names is None:
        return None, "%s: no header" % path
    missing = [c for c in NEED if c not in d.dtype.names]
    if missing:
        return None, "%s: no column %s" % (path, ", ".join(missing))
    d = np.atleast_1d(d)
    return d[d["dt"] > 0] if "dt" in d.dtype.names else d, None  # the rows of steps (not the initial/final state)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("adaptive")
    ap.add_argument("uniform")
    ap.add_argument("-o", dest="out", help="CSV with one row per adaptive step")
    a = ap.parse_args()
    ad, err = load(a.adaptive)
    un, err2 = load(a.uniform)
    if err or err2:
        print("ADAPTBOUND " + (err or err2))
        return 1
    cu, pu = float(np.max(un["active_cells"])), float(np.max(un["particles"]))
    if cu <= 0 or pu <= 0 or ad.size == 0:
        print("ADAPTBOUND: the uniform run has no cells or particles, or the adaptive run no steps")
        return 1
    fc = ad["active_cells"].astype(float) / cu
    fp = ad["particles"].astype(float) / pu
    wa, wu = float(np.sum(ad["wall_s"])), float(np.sum(un["wall_s"]))
    print("ADAPTBOUND steps=%d/%d cells=%.3f particles=%.3f end_cells=%.3f bound_cells=%.2f bound_particles=%.2f "
          "measured=%.2f" % (ad.size, un.size, fc.mean(), fp.mean(), fc[-1], un.size / fc.sum(), un.size / fp.sum(),
                             wu / wa if wa > 0 else float("nan")))
    if a.out:
        with open(a.out, "w") as f:
            f.write("step,t_over_t0,cells_fraction,particles_fraction,wall_s\n")
            for r, c, p in zip(ad, fc, fp):
                f.write("%d,%.6f,%.5f,%.5f,%.4e\n" % (r["step"], r["t_over_t0"], c, p, r["wall_s"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
