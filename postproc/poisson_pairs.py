#!/usr/bin/python3
"""Side-by-side pff-bench-poisson runs of two binaries (jobs/bench/poisson_pairs.sh) -> one line per run and a
summary per density ratio: pffmg's set-up + solve against the other binary's run just before it at the same ratio,
and the speed-up over GAMG measured in the same run as the newer pffmg.

Usage: /usr/bin/python3 postproc/poisson_pairs.py output/bench/poisson_pairs.txt [-o pairs.csv]
The newer binary is the one whose runs also hold GAMG (the script runs -bench_pcs pffmg,gamg with it); the CSV has
the rows of postproc/poisson_csv.py.
"""
import argparse
import csv
import os
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import poisson_csv  # noqa: E402


def total(r):
    return float(r["setup_s"]) + float(r["solve_s"])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("log")
    ap.add_argument("-o", "--csv", help="also write the rows as CSV")
    a = ap.parse_args()
    try:
        rows = poisson_csv.rows_of(a.log)
    except OSError as e:
        sys.exit(f"poisson_pairs: cannot read {a.log}: {e.strerror}")
    new = {r["commit"] for r in rows if r["pc"] == "gamg"}
    if len(new) != 1:
        sys.exit(f"poisson_pairs: {a.log}: expected the GAMG runs of one binary, found {len(new)}")
    new = new.pop()
    last_old, runs = {}, {}
    for i, r in enumerate(rows):
        if r["pc"] != "pffmg":
            continue
        if r["commit"] != new:
            last_old[r["ratio"]] = total(r)
            continue
        gamg = next((g for g in rows[i + 1:i + 3] if g["pc"] == "gamg" and g["ratio"] == r["ratio"]), None)
        if gamg is None:
            continue
        t, old = total(r), last_old.pop(r["ratio"], None)
        runs.setdefault(r["ratio"], []).append((t, old, total(gamg) / t))
        before = f"before {old:.3f} s, {t / old:.2f}x" if old else "no run before"
        print(f"ratio {r['ratio']}: pffmg {t:.3f} s ({before}), GAMG {total(gamg):.2f} s, "
              f"speed-up {total(gamg) / t:.1f}x (load {r['load1']})")
    if not runs:
        sys.exit(f"poisson_pairs: {a.log}: no run of {new} with GAMG")
    for ratio, rs in runs.items():
        sp = [s for _, _, s in rs]
        rel = [t / o for t, o, _ in rs if o]
        line = (f"ratio {ratio}: {new} over GAMG {min(sp):.1f}-{max(sp):.1f}x, median {statistics.median(sp):.1f}x "
                f"over {len(sp)} runs ({sum(s >= 10 for s in sp)} at 10x or more)")
        if rel:
            line += f"; pffmg against the run before: median {statistics.median(rel):.2f}x ({sum(x < 1 for x in rel)} of {len(rel)} faster)"
        print(line)
    if a.csv:
        with open(a.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=poisson_csv.FIELDS)
            w.writeheader()
            w.writerows(rows)


if __name__ == "__main__":
    main()
