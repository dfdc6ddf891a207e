#!/usr/bin/python3
"""Pressure-solver iterations per step of fluid runs, against time, as a PNG.

Each diagnostics CSV (<output_dir>/<scene>_diag.csv: a header line, then one row per step; '#' lines
are comments) needs the columns t, dt, ksp_its and ksp_rnorm; other columns are ignored. The rows of
the initial and the final state (dt = 0, no solve) are skipped. The upper panel shows the KSP
iterations of every step against the step's start time, the lower one the relative true residual
|V (D u + c_div)| / |b| that the solve reached. For each run one line goes to stdout:

    ksp_its: <file> steps=<n> max=<m> (step <s>) mean=<x>

and with --max-its N a verdict for each run and one for all of them:

    ksp_its: <file> PASS: every step at or below 30 iterations
    ksp_its: <file> FAIL: 3 of 111 steps above 30 iterations (max 45 at step 17)
    ksp_its: PASS (max-its 30, 2 runs)

    ksp_its.py output/fluid/fluid_diag.csv -o its.png
    ksp_its.py gamg/fluid_diag.csv pffmg/fluid_diag.csv -o its.png --label gamg --label pffmg --max-its 30

Needs numpy and matplotlib (Debian python3-matplotlib); uses the Agg backend, no display.
Exit status 0 whatever the verdict, or 1 when a file cannot be read, lacks a column or has no step.
"""
import argparse
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (the backend must be chosen first)
import numpy as np  # noqa: E402

COLUMNS = ["step", "t", "dt", "ksp_its", "ksp_rnorm"]


class InputError(Exception):
    pass


def read_steps(path):
    """Columns of the step rows (dt > 0) of a diagnostics CSV as float arrays."""
    try:
        with open(path, newline="") as fh:
            rows = [r for r in csv.reader(line for line in fh if line.strip() and not line.lstrip().startswith("#"))]
    except OSError as e:
        raise InputError(f"cannot read {path}: {e.strerror}")
    if not rows:
        raise InputError(f"{path}: no header line")
    header = [h.strip() for h in rows[0]]
    missing = [c for c in COLUMNS if c not in header]
    if missing:
        raise InputError(f"{path}: no column {', '.join(missing)} (columns: {', '.join(header)})")
    idx = [header.index(c) for c in COLUMNS]
    try:
        data = np.array([[float(r[i]) for i in idx] for r in rows[1:]], dtype=np.float64).reshape(-1, len(COLUMNS))
    except (ValueError, IndexError):
        raise InputError(f"{path}: a missing or non-numeric value in {', '.join(COLUMNS)}")
    data = data[data[:, 2] > 0]
    if data.shape[0] == 0:
        raise InputError(f"{path}: no step rows (every row has dt = 0)")
    return {c: data[:, k] for k, c in enumerate(COLUMNS)}


def main(argv=None):
    ap = argparse.ArgumentParser(description="Plot the pressure KSP iterations per step against time.")
    ap.add_argument("diag", nargs="+", help="diagnostics CSV with columns step, t, dt, ksp_its, ksp_rnorm")
    ap.add_argument("-o", "--output", required=True, help="PNG to write")
    ap.add_argument("--label", action="append", default=[], help="legend label, once per file in order")
    ap.add_argument("--max-its", type=int, default=None,
                    help="report PASS when every step of every run needs at most this many iterations, else FAIL")
    ap.add_argument("--dpi", type=int, default=150)
    args = ap.parse_args(argv)
    if len(args.label) > len(args.diag):
        print(f"ksp_its: {len(args.label)} labels for {len(args.diag)} files", file=sys.stderr)
        return 1
    if args.max_its is not None and args.max_its < 0:
        print(f"ksp_its: --max-its {args.max_its} is invalid: must be >= 0", file=sys.stderr)
        return 1
    labels = args.label + args.diag[len(args.label):]

    try:
        runs = [(path, read_steps(path)) for path in args.diag]
    except InputError as e:
        print(f"ksp_its: {e}", file=sys.stderr)
        return 1

    fig, (ax, axr) = plt.subplots(2, 1, figsize=(7, 6), sharex=True, gridspec_kw={"height_ratios": [2, 1]})
    passed = True
    for (path, d), label in zip(runs, labels):
        its, n = d["ksp_its"], d["ksp_its"].size
        k = int(np.argmax(its))
        print(f"ksp_its: {path} steps={n} max={int(its[k])} (step {int(d['step'][k])}) mean={its.mean():.1f}")
        if args.max_its is not None:
            over = int(np.count_nonzero(its > args.max_its))
            if over:
                passed = False
                print(f"ksp_its: {path} FAIL: {over} of {n} steps above {args.max_its} iterations "
                      f"(max {int(its[k])} at step {int(d['step'][k])})")
            else:
                print(f"ksp_its: {path} PASS: every step at or below {args.max_its} iterations")
        ax.plot(d["t"], its, ".-", lw=1, ms=3, label=label)
        axr.semilogy(d["t"], np.maximum(d["ksp_rnorm"], 1e-300), ".", ms=3, label=label)
    if args.max_its is not None:
        ax.axhline(args.max_its, color="0.3", ls="--", lw=1, label=f"max-its {args.max_its}")
        print(f"ksp_its: {'PASS' if passed else 'FAIL'} (max-its {args.max_its}, {len(runs)} "
              f"run{'s' if len(runs) != 1 else ''})")
    ax.set_ylabel("pressure KSP iterations")
    ax.set_ylim(bottom=0)
    ax.set_title("pressure solve per step")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    axr.set_xlabel("t (step start) [s]")
    axr.set_ylabel("relative residual")
    axr.grid(alpha=0.3, which="both")
    fig.tight_layout()
    try:
        fig.savefig(args.output, dpi=args.dpi)
    except OSError as e:
        print(f"ksp_its: cannot write {args.output}: {e.strerror}", file=sys.stderr)
        return 1
    plt.close(fig)
    return 0


if __name__ == "__main__":
    sys.exit(main())
