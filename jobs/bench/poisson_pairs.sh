#!/usr/bin/env bash
# Two pff-bench-poisson binaries side by side (docs/benchmarks.md, issue 13's sets): each round runs, per density
# ratio, the other binary with pffmg alone and then this build's binary with pffmg and GAMG, on the 128^3 uniform
# bubbly problem, 2 ranks x 1 thread, best of 2 set-ups + solves. The VM's speed drifts by tens of per cent within
# minutes, so only the runs next to each other compare. Appends the output to output/bench/poisson_pairs.txt and
# prints one line per run and the summary of postproc/poisson_pairs.py (speed-up over GAMG, time against the run
# before).
# Usage: bash jobs/bench/poisson_pairs.sh <label>:<other pff-bench-poisson> [rounds (2)] [ratios ("1e3 1e4 1e5")]
#   e.g. bash jobs/bench/poisson_pairs.sh 48e345f:/tmp/bench-48e345f 4 1e3
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../setup.sh"
[ $# -ge 1 ] && [[ $1 == *:* ]] || { echo "usage: $0 <label>:<other pff-bench-poisson> [rounds] [ratios]" >&2; exit 2; }
label=${1%%:*} other=${1#*:} rounds=${2:-2} ratios=${3:-1e3 1e4 1e5}
[ -x "$other" ] || { echo "poisson_pairs: $other is not an executable" >&2; exit 2; }
out=$PFF_ROOT/output/bench
mkdir -p "$out"
log=$out/poisson_pairs.txt
new=$(git -C "$PFF_ROOT" describe --always --dirty)
bench=$PFF_BUILD_DIR/bin/pff-bench-poisson
: > "$log.run"
for round in $(seq "$rounds"); do
  for r in $ratios; do
    for side in other new; do
      if [ $side = other ]; then b=$other c=$label pcs=pffmg; else b=$bench c=$new pcs=pffmg,gamg; fi
      opts="-bench_grid uniform -bench_n 128 -bench_ratio $r -bench_pcs $pcs -bench_repeat 2"
      {
        echo "# $(date -u +%FT%TZ) $c $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
        echo "# ${PFF_MPIEXEC[*]} -n 2 <$c>/pff-bench-poisson $opts"
        OMP_NUM_THREADS=1 "${PFF_MPIEXEC[@]}" -n 2 "$b" $opts < /dev/null 2>&1
      } >> "$log.run"
    done
  done
done
cat "$log.run" >> "$log"
/usr/bin/python3 "$PFF_ROOT/postproc/poisson_pairs.py" "$log.run" -o "$out/poisson_pairs.csv"
rm -f "$log.run"
