#!/usr/bin/python3
"""pff-bench-poisson output (RESULT, MEMORY, SWEEP, ITERATION, TRAFFIC lines and the "# <date> <commit> load ..."
headers that jobs/bench/poisson.sh and the docs' commands write) -> one CSV row per PC run.

Usage: /usr/bin/python3 postproc/poisson_csv.py output/bench/poisson.txt > docs/data/poisson.csv
Each row carries the commit and load average of the header above it and the extra options of the
command line ("# ... pff-bench-poisson <options>"), so rows of different runs stay apart.
"""
import csv
import re
import sys

FIELDS = ["commit", "load1", "options", "pc", "grid", "n", "ratio", "ranks", "threads", "its", "setup_s", "solve_s",
          "relres", "peak_rss_MB_max_rank", "peak_rss_B_per_cell", "solver_B_per_cell", "iteration_s", "sweep_ns_per_cell",
          "sweep_bound_ns_per_cell", "sweep_ratio", "copy_GBs", "it_cell_updates", "it_updates_per_finest_cell",
          "it_bound_s", "it_ratio", "it_visits_per_finest_cell", "traffic_B_per_finest_cell", "traffic_smoothing",
          "traffic_transfers", "traffic_kcycle", "traffic_outer", "traffic_bound_s", "traffic_ratio"]


def pairs(line):
    return dict(kv.split("=", 1) for kv in line.split()[1:] if "=" in kv)


def rows_of(path):
    """The rows of the log at path, one dict of FIELDS (strings) per RESULT line."""
    rows, cur, commit, load, options = [], None, "", "", ""
    with open(path) as f:
        for line in f:
            line = line.strip()
            m = re.match(r"# \S+Z (\S+) .*?load (\S+)", line)
            if m:
                commit, load = m.group(1), m.group(2)
                continue
            m = re.match(r"#.*pff-bench-poisson(.*)$", line)
            if m:
                options = m.group(1).strip()
                continue
            if line.startswith("RESULT "):
                p = pairs(line)
                cur = {k: "" for k in FIELDS}
                cur.update(commit=commit, load1=load, options=options)
                for k in ("pc", "grid", "n", "ratio", "ranks", "threads", "its", "setup_s", "solve_s", "relres"):
                    cur[k] = p.get(k, "")
                rows.append(cur)
            elif cur is not None and line.startswith("MEMORY "):
                p = pairs(line)
                for k in ("peak_rss_MB_max_rank", "peak_rss_B_per_cell", "solver_B_per_cell", "iteration_s"):
                    cur[k] = p.get(k, "")
            elif cur is not None and line.startswith("SWEEP "):
                p = pairs(line)
                cur.update(sweep_ns_per_cell=p.get("ns_per_cell", ""), sweep_bound_ns_per_cell=p.get("bound_ns_per_cell", ""),
                           sweep_ratio=p.get("ratio", ""), copy_GBs=p.get("copy_GBs", ""))
            elif cur is not None and line.startswith("ITERATION "):
                p = pairs(line)
                cur.update(it_cell_updates=p.get("cell_updates", ""), it_updates_per_finest_cell=p.get("per_finest_cell", ""),
                           it_bound_s=p.get("bound_s", ""), it_ratio=p.get("ratio", ""),
                           it_visits_per_finest_cell=p.get("visits_per_finest_cell", ""))
            elif cur is not None and line.startswith("TRAFFIC "):
                p = pairs(line)
                cur.update(traffic_B_per_finest_cell=p.get("B_per_finest_cell", ""), traffic_smoothing=p.get("smoothing", ""),
                           traffic_transfers=p.get("transfers", ""), traffic_kcycle=p.get("kcycle", ""),
                           traffic_outer=p.get("outer", ""), traffic_bound_s=p.get("bound_s", ""),
                           traffic_ratio=p.get("ratio", ""))
    return rows


def main(path):
    w = csv.DictWriter(sys.stdout, fieldnames=FIELDS)
    w.writeheader()
    w.writerows(rows_of(path))


if __name__ == "__main__":
    main(sys.argv[1])
