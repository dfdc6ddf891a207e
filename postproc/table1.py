#!/usr/bin/python3
"""Seconds per step in the columns of Narita et al. 2025, Table 1, from a pfflip run's `-log_view :file` (ASCII).

Usage: table1.py LOGVIEW [STEPS] [--csv]    (STEPS: by default the number of tall-cell builds, one per step)

Columns (seconds per step, each the slowest rank's time of its events or stages, over STEPS steps):
  sizing       TallSizing outside the Main stage (the sizing function during the run; 0 with the quadtree of t = 0)
  quadtree     GridAdapt outside the Main stage (the quadtree rebuilt from it)
  advection    the Advect stage, less FlowRefBodies (the bodies' reference lattice, timed there)
  tall_cells   TallBuild (columns, rows, the bodies' J and the assembly of A)
  projection   KSPSolve in the Pressure stage
  extrapolate  FlowExtrapolate
  particles    the P2G, PhaseField and G2P stages, less FlowExtrapolate
  other        the rest of the step (forces, the Pressure stage's level set and velocity update, escaped
               particles, volume correction, FlowRefBodies)
  total        the step stages' sum
The one-time set-up (the Main stage: the grid, the sizing and quadtree of t = 0, seeding) is printed apart.
Stage totals in the summary are averages over ranks, so `other` absorbs the difference to the maxima."""
import re
import sys

STEP_STAGES = ("P2G", "PhaseField", "Forces", "Pressure", "G2P", "Advect", "Escaped", "Correction", "Adapt")


def parse(path):
    stages, events, counts, stage = {}, {}, {}, None
    with open(path) as fh:
        for line in fh:
            m = re.match(r"\s*\d+:\s+(\S[^:]*):\s+([0-9.eE+-]+)\s", line)
            if m and stage is None:
                stages[m.group(1).strip()] = float(m.group(2))
                continue
            m = re.match(r"--- Event Stage \d+: (.+?)\s*$", line)
            if m:
                stage = m.group(1)
                continue
            if stage is not None:
                f = line.split()
                if len(f) > 4 and re.match(r"^[0-9]+$", f[1]) and re.match(r"^[0-9.eE+-]+$", f[3]):
                    events.setdefault(stage, {})[f[0]] = float(f[3])
                    counts.setdefault(stage, {})[f[0]] = int(f[1])
    return stages, events, counts


def ev(events, name, stage=None, outside_main=False):
    total = 0.0
    for s, table in events.items():
        if stage is not None and s != stage:
            continue
        if outside_main and s == "Main Stage":
            continue
        total += table.get(name, 0.0)
    return total


def table1(path, steps=None):
    stages, events, counts = parse(path)
    if steps is None:
        steps = counts.get("Pressure", {}).get("TallBuild", 0)
    if not steps:
        raise SystemExit("table1: no step count (no TallBuild event in the Pressure stage): give STEPS")
    total = sum(stages.get(s, 0.0) for s in STEP_STAGES)
    refb = ev(events, "FlowRefBodies")
    extr = ev(events, "FlowExtrapolate")
    row = {
        "sizing": ev(events, "TallSizing", outside_main=True),
        "quadtree": ev(events, "GridAdapt", outside_main=True),
        "advection": stages.get("Advect", 0.0) - refb,
        "tall_cells": ev(events, "TallBuild"),
        "projection": ev(events, "KSPSolve", stage="Pressure"),
        "extrapolate": extr,
        "particles": stages.get("P2G", 0.0) + stages.get("PhaseField", 0.0) + stages.get("G2P", 0.0) - extr,
    }
    row["other"] = total - sum(row.values())
    row["total"] = total
    per = {k: v / steps for k, v in row.items()}
    setup = {"setup_s": stages.get("Main Stage", 0.0), "setup_sizing_s": ev(events, "TallSizing", stage="Main Stage"),
             "setup_quadtree_s": ev(events, "GridAdapt", stage="Main Stage")}
    return per, setup, steps


def main(argv):
    args = [a for a in argv[1:] if not a.startswith("--")]
    if not args:
        sys.stderr.write(__doc__)
        return 2
    per, setup, steps = table1(args[0], int(args[1]) if len(args) > 1 else None)
    keys = list(per)
    if "--csv" in argv:
        print(",".join(f"{per[k]:.5f}" for k in keys) + "," + ",".join(f"{v:.3f}" for v in setup.values()))
    else:
        print(f"table1: {steps} steps  " + "  ".join(f"{k} {per[k]:.4f}" for k in keys) + "  (s / step);  " +
              "  ".join(f"{k} {v:.2f}" for k, v in setup.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
