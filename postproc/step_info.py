#!/usr/bin/python3
"""Per-rank totals of the per-step lines that pfflip prints with -info :sys (PffFlowSceneInfoStep): steps, the wall
time of the steps, each stage's time, the time outside every stage (wall minus the stages) and the page faults.
With --changes, also what a step that changed the grid (a progress line with "blocks +r -c", r + c > 0) costs
beyond the nearest steps that did not (up to two of them, the step before and after first), per stage.
Usage: step_info.py run.log [-o totals.csv] [--first N] [--last N] [--changes]"""
import argparse
import re

ap = argparse.ArgumentParser(description=__doc__)
ap.add_argument("log")
ap.add_argument("-o", "--output", help="CSV, one row per rank")
ap.add_argument("--first", type=int, default=1, help="first step counted (default 1)")
ap.add_argument("--last", type=int, default=None, help="last step counted (default: all)")
ap.add_argument("--changes", action="store_true", help="the extra cost of the steps that changed the grid")
args = ap.parse_args()
line = re.compile(r"\[(\d+)\] <sys> PffFlowSceneInfoStep\(\): step (\d+) wall ([0-9.]+) s, minor page faults (\d+), "
                  r"stages \(s\):(.*)")
progress = re.compile(r"^step\s+(\d+)\s")
change = re.compile(r"blocks \+(\d+) -(\d+)")
ranks, stages, changed, per = {}, [], {}, {}
with open(args.log) as f:
    for text in f:
        p = progress.match(text)
        if p:
            c = change.search(text)
            changed[int(p.group(1))] = bool(c and int(c.group(1)) + int(c.group(2)) > 0)
            continue
        m = line.search(text)
        if not m:
            continue
        rank, step = int(m.group(1)), int(m.group(2))
        if step < args.first or (args.last is not None and step > args.last):
            continue
        one = {"wall": float(m.group(3))}
        one.update((name, float(sec)) for name, sec in re.findall(r"(\w+) ([0-9.]+)", m.group(5)))
        per.setdefault(rank, {})[step] = one
        t = ranks.setdefault(rank, {"steps": 0, "wall": 0.0, "faults": 0, "stages": {}})
        t["steps"] += 1
        t["wall"] += float(m.group(3))
        t["faults"] += int(m.group(4))
        for name, sec in re.findall(r"(\w+) ([0-9.]+)", m.group(5)):
            if name not in stages:
                stages.append(name)
            t["stages"][name] = t["stages"].get(name, 0.0) + float(sec)
if not ranks:
    raise SystemExit(f"step_info: no PffFlowSceneInfoStep lines in {args.log} (run with -info :sys)")
rows = []
for rank in sorted(ranks):
    t = ranks[rank]
    outside = t["wall"] - sum(t["stages"].values())
    rows.append([rank, t["steps"], t["wall"]] + [t["stages"].get(s, 0.0) for s in stages] + [outside, t["faults"]])
    print(f"step_info: rank {rank} steps {t['steps']} wall {t['wall']:.3f} s outside stages {outside:.3f} s"
          f" ({100 * outside / t['wall'] if t['wall'] > 0 else 0:.1f} %) "
          + " ".join(f"{s} {t['stages'].get(s, 0.0):.3f}" for s in stages) + f" page faults {t['faults']}")
if args.output:
    with open(args.output, "w") as out:
        out.write(",".join(["rank", "steps", "wall_s"] + [f"{s}_s" for s in stages] + ["outside_s", "page_faults"]) + "\n")
        for r in rows:
            out.write(",".join(f"{v:.4f}" if isinstance(v, float) else str(v) for v in r) + "\n")
if args.changes:
    for rank in sorted(per):
        steps, extra, n = per[rank], {}, 0
        for s in sorted(steps):
            if not changed.get(s):
                continue
            near = [q for q in (s - 1, s + 1, s - 2, s + 2) if q in steps and changed.get(q) is False][:2]
            if not near:
                continue
            n += 1
            for k in ["wall"] + stages:
                extra[k] = extra.get(k, 0.0) + steps[s].get(k, 0.0) - sum(steps[q].get(k, 0.0) for q in near) / len(near)
        if n == 0:
            raise SystemExit(f"step_info: no step that changed the grid next to one that did not in {args.log}")
        print(f"step_info: rank {rank} grid changes {n} extra per change: "
              + " ".join(f"{k} {extra[k] / n:.4f}" for k in ["wall"] + stages))
