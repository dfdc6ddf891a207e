#!/usr/bin/python3
"""One CSV row per step from the progress lines of a pfflip log (stdout): particles, the largest rank's resident
set now and its peak so far (MB), and, on adapting steps, the particles split, removed, and the blocks refined and
coarsened.  Usage: progress_rss.py run.log -o timeline.csv"""
import argparse
import re

ap = argparse.ArgumentParser(description=__doc__)
ap.add_argument("log")
ap.add_argument("-o", "--output", required=True)
args = ap.parse_args()
step = re.compile(r"^step\s+(\d+)\s.*?particles (\d+)")
adapt = re.compile(r"adapt: split (\d+) removed (\d+)/\d+ blocks \+(\d+) -(\d+)")
rss = re.compile(r"rss (\d+) MB \(peak (\d+)\)")
rows, top = 0, (-1, None)
with open(args.log) as f, open(args.output, "w") as out:
    out.write("step,particles,rss_mb,peak_mb,split,removed,blocks_refined,blocks_coarsened\n")
    for line in f:
        m = step.match(line)
        r = rss.search(line)
        if not m or not r:
            continue
        a = adapt.search(line)
        s, rm, bp, bm = a.groups() if a else ("0", "0", "0", "0")
        out.write(",".join([m.group(1), m.group(2), r.group(1), r.group(2), s, rm, bp, bm]) + "\n")
        rows += 1
        if int(r.group(2)) > top[0]:
            top = (int(r.group(2)), m.group(1))
if rows == 0:
    raise SystemExit(f"progress_rss: no progress lines with a resident set in {args.log}")
print(f"progress_rss: {rows} steps, peak {top[0]} MB first at step {top[1]} -> {args.output}")
