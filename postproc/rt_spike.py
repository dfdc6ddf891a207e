#!/usr/bin/python3
"""Spike-tip position of the 3D Rayleigh-Taylor run against De Rosis & Enan (2021), as a PNG.

Each diagnostics CSV (a header line, then one row per output time; '#' lines are comments) needs the
columns t_over_t0 and spike_over_W; other columns are ignored. The plot shows every run, the reference
curve and the shaded min-max band of the eight models of the paper's Table IX
(data/reference/rt3d_derosis2021.csv). For each run one line goes to stdout:

    rt_spike: <file> max_dev=<x> inside_band=<yes|no> compared_points=<k> [until=<t>]

max_dev is the largest |simulated - reference| at the reference times t/t0 <= min(3, last simulated
time) that the run covers, the simulated curve interpolated linearly; inside_band says whether every
such point lies in the band; until=<t> appears when the run ended before t/t0 = 3.

With --csv FILE the comparison also goes to a table, one row per run: its label, the spike tip at each
reference time (empty after the run's end), max_dev, rms_dev (root mean square over the compared points),
inside_band, compared_points, and the run's steps and wall seconds (the rows and the sum of the wall_s column
of the diagnostics; empty when it has none); then one more line goes to stdout:

    rt_spike: wrote <file>: <n> rows, largest rms_dev=<x>

    rt_spike.py out/rt3d/diag.csv -o rt.png
    rt_spike.py a/diag.csv b/diag.csv -o rt.png --label "64^3" --label "128^3" --csv table.csv

Needs numpy and matplotlib (Debian python3-matplotlib); uses the Agg backend, no display.
Exit status 0, or 1 when a file cannot be read or lacks a column.
"""
import argparse
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (the backend must be chosen first)
import numpy as np  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
REFERENCE = os.path.join(HERE, "..", "data", "reference", "rt3d_derosis2021.csv")
T_END = 3.0  # last reference time
TOL = 1e-12  # band membership tolerance (the band touches the reference at t/t0 = 3)


class InputError(Exception):
    pass


def read_columns(path, names):
    """The named columns of a CSV file with a header line ('#' comment lines skipped) as float arrays."""
    try:
        with open(path, newline="") as fh:
            rows = [r for r in csv.reader(line for line in fh if line.strip() and not line.lstrip().startswith("#"))]
    except OSError as e:
        raise InputError(f"cannot read {path}: {e.strerror}")
    if not rows:
        raise InputError(f"{path}: no header line")
    header = [h.strip() for h in rows[0]]
    out = {}
    for name in names:
        if name not in header:
            raise InputError(f"{path}: no column {name} (columns: {', '.join(header)})")
        c = header.index(name)
        try:
            out[name] = np.array([float(r[c]) for r in rows[1:]], dtype=np.float64)
        except (ValueError, IndexError):
            raise InputError(f"{path}: column {name} has a missing or non-numeric value")
    return out


def compare(t, y, ref):
    """(max_dev, inside, compared points, last time) of a simulated curve against the reference."""
    order = np.argsort(t, kind="stable")
    t, y = t[order], y[order]
    tr = ref["t_over_t0"]
    sel = (tr <= min(T_END, t[-1]) + TOL) & (tr >= t[0] - TOL)
    ys = np.interp(tr[sel], t, y)
    dev = np.abs(ys - ref["y_over_W_reference"][sel])
    inside = bool(np.all((ys >= ref["band_min"][sel] - TOL) & (ys <= ref["band_max"][sel] + TOL)))
    max_dev = float(dev.max()) if dev.size else float("nan")
    return max_dev, inside and dev.size > 0, int(dev.size), float(t[-1])


def table_row(label, t, y, wall, result, ref):
    """The --csv row of one run: label, the tip at every reference time, max_dev, rms_dev, inside, points,
    steps and wall seconds (wall: the per-step wall_s column or None; result: compare()'s of the run)."""
    max_dev, inside, k, last = result
    order = np.argsort(t, kind="stable")
    tr = ref["t_over_t0"]
    ys = np.interp(tr, t[order], y[order])
    covered = (tr <= min(T_END, last) + TOL) & (tr >= t[order][0] - TOL)
    rms = float(np.sqrt(np.mean((ys[covered] - ref["y_over_W_reference"][covered]) ** 2))) if k else float("nan")
    return ([label] + [f"{v:.4f}" if c else "" for v, c in zip(ys, covered)]
            + [f"{max_dev:.4f}", f"{rms:.4f}", "yes" if inside else "no", str(k)]
            + ([str(int(np.count_nonzero(wall))), f"{wall.sum():.1f}"] if wall is not None else ["", ""])), rms


def main(argv=None):
    ap = argparse.ArgumentParser(description="Plot the RT spike tip against the De Rosis & Enan (2021) reference.")
    ap.add_argument("diag", nargs="+", help="diagnostics CSV with columns t_over_t0 and spike_over_W")
    ap.add_argument("-o", "--output", required=True, help="PNG to write")
    ap.add_argument("--label", action="append", default=[], help="legend label, once per file in order")
    ap.add_argument("--reference", default=REFERENCE, help="reference CSV (default data/reference/rt3d_derosis2021.csv)")
    ap.add_argument("--dpi", type=int, default=150)
    ap.add_argument("--csv", help="table of the comparison to write, one row per run")
    args = ap.parse_args(argv)
    if len(args.label) > len(args.diag):
        print(f"rt_spike: {len(args.label)} labels for {len(args.diag)} files", file=sys.stderr)
        return 1
    labels = args.label + args.diag[len(args.label):]

    try:
        ref = read_columns(args.reference, ["t_over_t0", "y_over_W_reference", "band_min", "band_max"])
        runs = []
        for path in args.diag:
            d = read_columns(path, ["t_over_t0", "spike_over_W"])
            if d["t_over_t0"].size == 0:
                raise InputError(f"{path}: no data rows")
            try:  # optional: the per-step wall time, for the table's run time beside the error
                wall = read_columns(path, ["wall_s"])["wall_s"]
            except InputError:
                wall = None
            runs.append((path, d["t_over_t0"], d["spike_over_W"], wall))
    except InputError as e:
        print(f"rt_spike: {e}", file=sys.stderr)
        return 1

    fig, ax = plt.subplots(figsize=(7, 5))
    ax.fill_between(ref["t_over_t0"], ref["band_min"], ref["band_max"], color="0.85",
                    label="range of 8 models (De Rosis & Enan 2021)")
    ax.plot(ref["t_over_t0"], ref["y_over_W_reference"], "ko--", ms=4, lw=1, label="reference")
    results = []
    for (path, t, y, _), label in zip(runs, labels):
        max_dev, inside, k, last = compare(t, y, ref)
        results.append((max_dev, inside, k, last))
        line = (f"rt_spike: {path} max_dev={max_dev:.4g} inside_band={'yes' if inside else 'no'} "
                f"compared_points={k}")
        if last < T_END - TOL:
            line += f" until={last:.4g}"
        print(line)
        order = np.argsort(t, kind="stable")
        ax.plot(t[order], y[order], lw=1.5, label=label)
    ax.set_xlabel("t / t0")
    ax.set_ylabel("spike tip y / W")
    ax.set_title("3D Rayleigh-Taylor instability: spike tip")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    try:
        fig.savefig(args.output, dpi=args.dpi, bbox_inches="tight")
    except OSError as e:
        print(f"rt_spike: cannot write {args.output}: {e.strerror}", file=sys.stderr)
        return 1
    plt.close(fig)
    if args.csv:
        header = (["run"] + [f"y_at_{t:g}" for t in ref["t_over_t0"]]
                  + ["max_dev", "rms_dev", "inside_band", "compared_points", "steps", "wall_s"])
        rows = [table_row(label, t, y, wall, res, ref)
                for (path, t, y, wall), label, res in zip(runs, labels, results)]
        try:
            with open(args.csv, "w", newline="") as fh:
                w = csv.writer(fh)
                w.writerow(header)
                w.writerows(r for r, _ in rows)
        except OSError as e:
            print(f"rt_spike: cannot write {args.csv}: {e.strerror}", file=sys.stderr)
            return 1
        print(f"rt_spike: wrote {args.csv}: {len(rows)} rows, largest rms_dev={max(r for _, r in rows):.4g}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
