#!/usr/bin/python3
"""One fluid run against a reference run of the same scene (an adaptive grid against a uniform one, say).

Both diagnostics CSVs (<output_dir>/fluid_diag.csv; '#' lines are comments) need the columns t,
liquid_volume, liquid_x_max and liquid_cy (the fluid scene writes them). The run is interpolated
linearly to the reference's step times; printed on one line:

    compare_runs: <run> vs <reference> front_max_diff=<m> (t <= <until>) cy_max_diff=<m>
        drift_end=<run> ref_drift_end=<ref> drift_max=<run> ref_drift_max=<ref>

front_max_diff is the largest |liquid_x_max - reference| up to --until (the time the front reaches a
wall, after which both read the wall), cy_max_diff the same for the liquid centroid height, drift the
liquid volume change V/V0 - 1. With --curves FILE both runs' front, centroid height and drift go to FILE
every --every seconds (docs/data/adaptive_dam_break_128_curves.csv).

    compare_runs.py adaptive/fluid_diag.csv uniform/fluid_diag.csv --until 0.5 --curves curves.csv

Needs numpy. Exit status 0, or 1 when a file cannot be read or lacks a column.
"""
import argparse
import sys

import numpy as np

COLUMNS = ["t", "liquid_volume", "liquid_x_max", "liquid_cy"]


def read(path):
    try:
        d = np.genfromtxt(path, delimiter=",", names=True, comments="#")
    except OSError as e:
        raise ValueError(f"{path}: {e}")
    missing = [c for c in COLUMNS if d.dtype.names is None or c not in d.dtype.names]
    if missing:
        raise ValueError(f"{path}: no column {', '.join(missing)}")
    return np.atleast_1d(d)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("run")
    ap.add_argument("reference")
    ap.add_argument("--until", type=float, default=np.inf, help="compare the fronts up to this time")
    ap.add_argument("--curves", help="write both runs' curves to this CSV")
    ap.add_argument("--every", type=float, default=0.01, help="time between rows of --curves")
    a = ap.parse_args()
    try:
        run, ref = read(a.run), read(a.reference)
    except ValueError as e:
        print(f"compare_runs: {e}", file=sys.stderr)
        return 1
    t = ref["t"]
    at = lambda col: np.interp(t, run["t"], run[col])  # noqa: E731
    front = np.abs(at("liquid_x_max") - ref["liquid_x_max"])[t <= a.until]
    cy = np.abs(at("liquid_cy") - ref["liquid_cy"])
    drift = lambda d: d["liquid_volume"] / d["liquid_volume"][0] - 1  # noqa: E731
    dr, df = drift(run), drift(ref)
    print(f"compare_runs: {a.run} vs {a.reference} front_max_diff={front.max():.4f} (t <= {a.until:g}) "
          f"cy_max_diff={cy.max():.4f} drift_end={dr[-1]:.4f} ref_drift_end={df[-1]:.4f} "
          f"drift_max={np.abs(dr).max():.4f} ref_drift_max={np.abs(df).max():.4f}")
    if a.curves:
        ts = np.round(np.arange(0, t[-1] + 1e-9, a.every), 6)
        cols = [np.interp(ts, ref["t"], ref["liquid_x_max"]), np.interp(ts, run["t"], run["liquid_x_max"]),
                np.interp(ts, ref["t"], ref["liquid_cy"]), np.interp(ts, run["t"], run["liquid_cy"]),
                np.interp(ts, ref["t"], df), np.interp(ts, run["t"], dr)]
        with open(a.curves, "w") as f:
            f.write("t,front_uniform,front_adaptive,cy_uniform,cy_adaptive,liquid_drift_uniform,"
                    "liquid_drift_adaptive\n")
            for i, x in enumerate(ts):
                f.write(",".join(f"{v:.6g}" for v in [x] + [c[i] for c in cols]) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
