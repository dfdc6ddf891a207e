#!/usr/bin/python3
"""The peak of umax_grid (the largest face speed after each step; t is the time at the step's start, t_end the
time reached) in fluid-scene diagnostics, and its value at a
few steps, one CSV row per run.  Usage: umax_peak.py LABEL=diag.csv [LABEL=diag.csv ...] -o peaks.csv
(LABEL names the run, e.g. its -flow_dt_max; it fills the first column, headed by --label-name)."""
import argparse

import numpy as np

ap = argparse.ArgumentParser(description=__doc__)
ap.add_argument("runs", nargs="+")
ap.add_argument("-o", "--output", required=True)
ap.add_argument("--label-name", default="dt_max")
ap.add_argument("--steps", default="1,5,20,50,150", help="steps whose umax is reported (the last one if beyond)")
args = ap.parse_args()
steps = [int(s) for s in args.steps.split(",")]
rows = [",".join([args.label_name, "steps", "t_end", "peak_umax", "peak_step", "peak_t"] + [f"u_step{s}" for s in steps])]
for run in args.runs:
    label, path = run.split("=", 1)
    d = np.genfromtxt(path, delimiter=",", names=True)
    step = d["dt"] > 0  # the rows of the initial and the final state (dt = 0) are not steps
    u, t = d["umax_grid"][step], d["t"][step]
    if len(u) == 0:
        raise SystemExit(f"umax_peak: no steps in {path}")
    i = int(np.argmax(u))
    at = [f"{u[min(s, len(u)) - 1]:.4f}" for s in steps]
    rows.append(",".join([label, str(len(u)), f"{d['t'][-1]:.4f}", f"{u[i]:.4f}", str(i + 1), f"{t[i]:.4f}"] + at))
with open(args.output, "w") as f:
    f.write("\n".join(rows) + "\n")
print("\n".join(rows))
