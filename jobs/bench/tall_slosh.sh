#!/usr/bin/env bash
# The small free-surface wave of issue 15 against linear theory on the three discretisations: the sloshing tank of
# config/tall_slosh_small.yaml (first-mode period T1 = 1.1817 s) on uniform cubic cells (-grid_levels 1
# -tall_merge false), uniform tall cells (-grid_levels 1) and the quadtree (3 levels), 2 ranks x 1 thread, to
# t = 3 s. postproc/slosh_period.py measures the period from the liquid centroid; one CSV row per method goes to
# docs/data/tall_slosh_issue15.csv (commit, UTC time, load, period, error, run time, liquid volume drift).
# Usage: bash jobs/bench/tall_slosh.sh [options...] (extra pfflip options for every run, e.g. -tall_theta_min 0.1;
# they are appended to the CSV's method column).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../setup.sh"
out=$PFF_ROOT/output/bench
csv=$PFF_ROOT/docs/data/tall_slosh_issue15.csv
mkdir -p "$out"
extra=("$@")
commit=$(git -C "$PFF_ROOT" describe --always --dirty)
[ -f "$csv" ] || echo "commit,utc,load1,method,steps,wall_s,s_per_step,period_s,analytic_s,period_error,liquid_volume_drift" > "$csv"
for m in "uniform:-grid_levels 1 -tall_merge false" "tall:-grid_levels 1" "quadtree:"; do
  name=${m%%:*}${extra[*]+ ${extra[*]}}
  read -r -a opts <<< "${m#*:}"
  opts+=(${extra[@]+"${extra[@]}"})
  load=$(cut -d' ' -f1 /proc/loadavg)
  utc=$(date -u +%FT%TZ)
  dir=$out/tall_slosh_${m%%:*}
  OMP_NUM_THREADS=1 "${PFF_MPIEXEC[@]}" -n 2 "$PFF_BUILD_DIR/bin/pfflip" -options_file_yaml "$PFF_ROOT/config/tall_slosh_small.yaml" \
    -sim_frames false -output_dir "$dir" ${opts[@]+"${opts[@]}"} > "$dir.log" 2>&1
  res=$(/usr/bin/python3 "$PFF_ROOT/postproc/slosh_period.py" "$dir/fluid_diag.csv")
  { echo "# $utc $commit load $(cut -d' ' -f1-3 /proc/loadavg) method=$name ${opts[*]+${opts[*]}}"; grep -E "^(summary|conservation|tall cells)" "$dir.log"; echo "$res"; } | tee -a "$out/tall_slosh.txt"
  steps=$(grep -oP "summary: \K[0-9]+(?= steps)" "$dir.log")
  wall=$(grep -oP "summary: .* wall \K[0-9.]+" "$dir.log")
  drift=$(grep -oP "conservation: .*liquid volume drift \K[-+0-9.e]+" "$dir.log")
  per=$(grep -oP "period_s=\K[0-9.]+" <<< "$res"); ana=$(grep -oP "analytic_s=\K[0-9.]+" <<< "$res"); err=$(grep -oP "error=\K[-0-9.]+" <<< "$res")
  awk -v c="$commit" -v u="$utc" -v l="$load" -v m="$name" -v s="$steps" -v w="$wall" -v p="$per" -v a="$ana" -v e="$err" -v d="$drift" \
      'BEGIN{printf "%s,%s,%s,%s,%s,%s,%.4f,%s,%s,%s,%s\n", c,u,l,m,s,w,w/s,p,a,e,d}' >> "$csv"
done
