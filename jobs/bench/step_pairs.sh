#!/usr/bin/env bash
# Two pfflip binaries side by side on the first steps of a scene (docs/benchmarks.md, issue 12's step time): each
# round runs the other binary, then this build's, 2 ranks x 1 thread. The VM's speed drifts by tens of per cent within
# minutes, so only the runs next to each other compare. One CSV row per run on standard output (and appended to
# output/bench/step_pairs.csv): the binary, round, UTC, load, the steps' wall time and s per step from the `summary:`
# line, the P2G, Pressure, Correction and Advect shares, and the md5 prefix of the diagnostics without the columns that
# differ between equal runs (wall_s) or between versions (active_cells, since 96267f8), so that equal prefixes mean the
# same results (for rt3d the same as `cut -d, -f1-12,14-16 rt3d_diag.csv | md5sum`).
# Usage: bash jobs/bench/step_pairs.sh <label>:<other pfflip> [rounds (2)] [steps (5)] [-- options]
#   e.g. bash jobs/bench/step_pairs.sh 2d3cb04:/tmp/oldbuild/bin/pfflip 3 5
#   default options: -options_file_yaml config/rt3d.yaml -rt_resolution 64 (scene rt3d: diagnostics rt3d_diag.csv)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../setup.sh"
[ $# -ge 1 ] && [[ $1 == *:* ]] || { echo "usage: $0 <label>:<other pfflip> [rounds] [steps] [-- options]" >&2; exit 2; }
label=${1%%:*} other=${1#*:} rounds=2 steps=5
shift
if [ $# -gt 0 ] && [ "$1" != -- ]; then rounds=$1; shift; fi
if [ $# -gt 0 ] && [ "$1" != -- ]; then steps=$1; shift; fi
if [ $# -gt 0 ] && [ "$1" = -- ]; then shift; fi
opts=("$@")
[ ${#opts[@]} -gt 0 ] || opts=(-options_file_yaml "$PFF_ROOT/config/rt3d.yaml" -rt_resolution 64)
[ -x "$other" ] || { echo "step_pairs: $other is not an executable" >&2; exit 2; }
out=$PFF_ROOT/output/bench
mkdir -p "$out"
new=$(git -C "$PFF_ROOT" describe --always --dirty)
[ -s "$out/step_pairs.csv" ] ||
  echo "binary,commit,round,utc,load1,wall_steps_s,s_per_step,P2G_pct,Pressure_pct,Correction_pct,Advect_pct,diag_md5" \
    > "$out/step_pairs.csv"
for round in $(seq "$rounds"); do
  for side in other new; do
    if [ $side = other ]; then b=$other c=$label; else b=$PFF_BUILD_DIR/bin/pfflip c=$new; fi
    dir=$out/step_pairs_$side
    rm -rf "$dir"
    load=$(cut -d' ' -f1 /proc/loadavg) utc=$(date -u +%H:%M:%S)
    OMP_NUM_THREADS=1 "${PFF_MPIEXEC[@]}" -n 2 "$b" "${opts[@]}" -sim_max_steps "$steps" -sim_frames false \
      -output_dir "$dir" > "$dir.log" 2>&1 < /dev/null
    wall=$(sed -n "s/^summary: $steps steps .*wall \([0-9.]*\) s *(\([0-9.]*\) s\/step).*/\1,\2/p" "$dir.log")
    share() { sed -n "s/^summary: stage shares.* $1 \([0-9.]*\)%.*/\1/p" "$dir.log"; }
    diag=$(ls "$dir"/*_diag.csv)
    md5=$(awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) keep[i] = $i != "wall_s" && $i != "active_cells" }
                   { s = ""; for (i = 1; i <= NF; i++) if (keep[i]) s = s (s == "" ? "" : ",") $i; print s }' "$diag" |
          md5sum | cut -c1-8)
    echo "$side,$c,$round,$utc,$load,$wall,$(share P2G),$(share Pressure),$(share Correction),$(share Advect),$md5" |
      tee -a "$out/step_pairs.csv"
  done
done
