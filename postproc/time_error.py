#!/usr/bin/python3
"""Error against wall time of benchmark runs, one log-log panel per scene, as a PNG.

The benchmark CSV has the header

    scene,cells,ranks,threads,steps,wall_s,error,inside_band

(inside_band is yes, no or -). Each panel plots error against wall seconds, one series per
(ranks, threads) joined in order of increasing cells, every point labelled by its cell count; a
filled marker is a run inside the published band, a hollow one a run outside it, a dot a run
without a band. The shear_sphere panel also shows the published relative errors of
data/reference/shear_sphere.csv as horizontal lines. Rows whose error or wall time is not a positive
number cannot be drawn on log axes; they are counted on stdout.

    time_error.py bench.csv -o time_error.png

Needs numpy and matplotlib (Debian python3-matplotlib); uses the Agg backend, no display.
Exit status 0, or 1 when the file cannot be read or lacks a column.
"""
import argparse
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (the backend must be chosen first)

HERE = os.path.dirname(os.path.abspath(__file__))
SHEAR_REFERENCE = os.path.join(HERE, "..", "data", "reference", "shear_sphere.csv")
COLUMNS = ["scene", "cells", "ranks", "threads", "steps", "wall_s", "error", "inside_band"]


class InputError(Exception):
    pass


def read_rows(path):
    """Rows of a CSV with a header line ('#' comment lines skipped) as dicts."""
    try:
        with open(path, newline="") as fh:
            return list(csv.DictReader(line for line in fh if line.strip() and not line.lstrip().startswith("#")))
    except OSError as e:
        raise InputError(f"cannot read {path}: {e.strerror}")


def read_bench(path):
    try:
        with open(path, newline="") as fh:
            reader = csv.DictReader(line for line in fh if line.strip() and not line.lstrip().startswith("#"))
            header = [h.strip() for h in (reader.fieldnames or [])]
            rows = [{k.strip(): (v or "").strip() for k, v in r.items() if k is not None} for r in reader]
    except OSError as e:
        raise InputError(f"cannot read {path}: {e.strerror}")
    missing = [c for c in COLUMNS if c not in header]
    if missing:
        raise InputError(f"{path}: missing column{'s' if len(missing) > 1 else ''} {', '.join(missing)} "
                         f"(expected header {','.join(COLUMNS)})")
    return rows


def number(s):
    try:
        v = float(s)
    except ValueError:
        return None
    return v if math.isfinite(v) and v > 0 else None


def cell_count(s):
    """Number of cells of a label such as 2097152, 128^3 or 64x128x64 (0 when unreadable), for ordering."""
    try:
        if "^" in s:
            base, exp = s.split("^", 1)
            return float(base) ** float(exp)
        return math.prod(float(p) for p in s.lower().split("x"))
    except ValueError:
        return 0.0


def main(argv=None):
    ap = argparse.ArgumentParser(description="Plot error against wall time per scene (log-log).")
    ap.add_argument("bench", help="benchmark CSV: scene,cells,ranks,threads,steps,wall_s,error,inside_band")
    ap.add_argument("-o", "--output", required=True, help="PNG to write")
    ap.add_argument("--shear-reference", default=SHEAR_REFERENCE,
                    help="published shear_sphere errors (default data/reference/shear_sphere.csv)")
    ap.add_argument("--dpi", type=int, default=150)
    args = ap.parse_args(argv)

    try:
        rows = read_bench(args.bench)
        scenes = list(dict.fromkeys(r["scene"] for r in rows))
        published = []
        if "shear_sphere" in scenes:
            for r in read_rows(args.shear_reference):
                err = number(r.get("relative_error", ""))
                if err is None:
                    raise InputError(f"{args.shear_reference}: bad relative_error {r.get('relative_error')!r}")
                published.append((r.get("source", "?"), err))
    except InputError as e:
        print(f"time_error: {e}", file=sys.stderr)
        return 1
    if not scenes:
        print(f"time_error: {args.bench}: no data rows", file=sys.stderr)
        return 1

    ncol = min(3, len(scenes))
    nrow = (len(scenes) + ncol - 1) // ncol
    fig, axes = plt.subplots(nrow, ncol, figsize=(5 * ncol, 4 * nrow), squeeze=False)
    skipped = 0
    for ax, scene in zip(axes.flat, scenes):
        series = {}
        for r in rows:
            if r["scene"] != scene:
                continue
            wall, err = number(r["wall_s"]), number(r["error"])
            if wall is None or err is None:
                skipped += 1
                continue
            cells = r["cells"]
            ncells = cell_count(cells)
            series.setdefault((r["ranks"], r["threads"]), []).append((ncells, cells, wall, err, r["inside_band"]))
        for (ranks, threads), pts in sorted(series.items()):
            pts.sort(key=lambda p: p[0])
            line, = ax.plot([p[2] for p in pts], [p[3] for p in pts], "-", lw=1,
                            label=f"{ranks} ranks x {threads} threads")
            for _, cells, wall, err, band in pts:
                face = line.get_color() if band == "yes" else "none"
                ax.plot([wall], [err], "o" if band in ("yes", "no") else ".", color=line.get_color(), mfc=face, ms=6)
                ax.annotate(cells, (wall, err), textcoords="offset points", xytext=(4, 4), fontsize=7)
        if not series:
            ax.text(0.5, 0.5, "no run with a positive error and wall time", transform=ax.transAxes, ha="center",
                    fontsize=8)
        if scene == "shear_sphere":
            for (source, err), style in zip(published, ["--", ":", "-."] * len(published)):
                ax.axhline(err, color="0.4", ls=style, lw=1, label=f"{source}: {err:g}")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(scene)
        ax.set_xlabel("wall time [s]")
        ax.set_ylabel("error")
        ax.grid(alpha=0.3, which="both")
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7)
    for ax in list(axes.flat)[len(scenes):]:
        ax.set_visible(False)
    fig.tight_layout()
    try:
        fig.savefig(args.output, dpi=args.dpi)
    except OSError as e:
        print(f"time_error: cannot write {args.output}: {e.strerror}", file=sys.stderr)
        return 1
    plt.close(fig)
    print(f"time_error: {args.output}: {len(scenes)} scene{'s' if len(scenes) != 1 else ''}, "
          f"{len(rows) - skipped} points, {skipped} rows without a positive error or wall time")
    return 0


if __name__ == "__main__":
    sys.exit(main())
