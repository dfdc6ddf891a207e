#!/usr/bin/env bash
# Quadtree tall cells against uniform cubic and uniform tall cells (docs/benchmarks.md, "Quadtree tall cells",
# Narita et al. 2025 Tables 1-2, projection columns): pff-bench-tall on the water-drop snapshot at N = 64, 128
# and 256 (or the sizes given), 2 ranks x 1 thread, best of 2 runs per method. Appends the output to
# output/bench/tall.txt and the RESULT lines as CSV rows to docs/data/tall_issue15.csv (with the commit, the UTC
# time and the load average). Usage: bash jobs/bench/tall.sh [N ...]
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../setup.sh"
out=$PFF_ROOT/output/bench
csv=$PFF_ROOT/docs/data/tall_issue15.csv
mkdir -p "$out"
bench=$PFF_BUILD_DIR/bin/pff-bench-tall
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(64 128 256)
commit=$(git -C "$PFF_ROOT" describe --always --dirty)
[ -f "$csv" ] || echo "commit,utc,load1,scene,method,n,ranks,cells,tall_cells,samples,rows,liquid_cells,sizing_s,quadtree_s,assemble_s,solve_s,projection_s,res0,res,its,peak_rss_MB" > "$csv"
for n in "${sizes[@]}"; do
  load=$(cut -d' ' -f1 /proc/loadavg)
  utc=$(date -u +%FT%TZ)
  {
    echo "# $utc $commit $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
    echo "# ${PFF_MPIEXEC[*]} -n 2 $bench -bench_n $n -bench_repeat 2"
    OMP_NUM_THREADS=1 "${PFF_MPIEXEC[@]}" -n 2 "$bench" -bench_n "$n" -bench_repeat 2
  } | tee -a "$out/tall.txt" | grep -E "^(RESULT|RATIO|# quadtree)" | tee /dev/stderr |
    grep "^RESULT" | sed -e 's/^RESULT //' -e 's/[a-z_0-9A-Z]*=//g' -e 's/ /,/g' -e "s/^/$commit,$utc,$load,/" >> "$csv"
done
