#!/usr/bin/env bash
# A whole liquid simulation on the three discretisations of Narita et al. 2025 (Table 1: time per step): the water
# drop of config/tall_drop_small.yaml or the breaking dam with pillars of config/tall_dam_small.yaml
# (-flow_model liquid) on uniform cubic cells (-grid_levels 1 -tall_merge false), uniform tall cells
# (-grid_levels 1) and quadtree tall cells (3 levels, the sizing function's quadtree), 2 ranks x 1 thread, no
# frames. Usage: bash jobs/bench/tall_scene.sh [N [t_end [drop|dam [options [methods]]]]] (default 64, 0.5 s, drop;
# N cells across the unit box, the dam's tank is 3N/4 high; options, one string, are added to every run and to the
# method's name in the CSVs, e.g. "-flow_liquid_band 4" gives quadtree+flow_liquid_band_4; methods a subset of
# "uniform tall quadtree"). Appends the summaries to output/bench/tall_scene.txt and one CSV row
# per method to docs/data/tall_scene_issue15.csv (drop) or docs/data/tall_dam_issue15.csv (dam): commit, UTC time,
# load average, steps, seconds per step, the Pressure stage's seconds per step, particles, liquid volume drift; and
# one row per method to docs/data/tall_table1_issue15.csv with the paper's Table 1 columns in seconds per step
# (postproc/table1.py on the run's -log_view: sizing, quadtree, advection, tall cells, projection, extrapolation,
# particles, other, total) and the one-time set-up.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../setup.sh"
n=${1:-64}
tend=${2:-0.5}
scene=${3:-drop}
extra=${4:-}
methods=${5:-uniform tall quadtree}
suffix=""
[ -n "$extra" ] && suffix="+$(echo "$extra" | sed 's/^-//; s/ -/+/g; s/ /_/g')"
h=$(awk -v n="$n" 'BEGIN{printf "%.10g", 1.0/n}')
out=$PFF_ROOT/output/bench
case $scene in
  drop) cfg=tall_drop_small.yaml; cells="$n,$n,$n"; csv=$PFF_ROOT/docs/data/tall_scene_issue15.csv; tag=tall_scene ;;
  dam) cfg=tall_dam_small.yaml; cells="$n,$((3 * n / 4)),$n"; csv=$PFF_ROOT/docs/data/tall_dam_issue15.csv; tag=tall_dam ;;
  *) echo "tall_scene.sh: unknown scene '$scene' (drop or dam)" >&2; exit 2 ;;
esac
mkdir -p "$out"
commit=$(git -C "$PFF_ROOT" describe --always --dirty)
t1csv=$PFF_ROOT/docs/data/tall_table1_issue15.csv
[ -f "$t1csv" ] || echo "commit,utc,load1,scene,n,method,t_end,steps,sizing,quadtree,advection,tall_cells,projection,extrapolate,particles,other,total,setup_s,setup_sizing_s,setup_quadtree_s" > "$t1csv"
[ -f "$csv" ] || echo "commit,utc,load1,n,method,t_end,steps,wall_s,s_per_step,pressure_s_per_step,pressure_share,particles,liquid_volume_drift,max_abs_drift" > "$csv"
for m in "uniform:-grid_levels 1 -tall_merge false" "tall:-grid_levels 1" "quadtree:"; do
  name=${m%%:*}
  [[ " $methods " == *" $name "* ]] || continue
  read -r -a opts <<< "${m#*:} $extra"
  name=$name$suffix
  load=$(cut -d' ' -f1 /proc/loadavg)
  utc=$(date -u +%FT%TZ)
  log=$out/${tag}_${n}_${name}.log
  OMP_NUM_THREADS=1 "${PFF_MPIEXEC[@]}" -n 2 "$PFF_BUILD_DIR/bin/pfflip" -options_file_yaml "$PFF_ROOT/config/$cfg" \
    -grid_cells "$cells" -grid_h "$h" -sim_t_end "$tend" -sim_frames false -output_dir "$out/${tag}_${n}_${name}" \
    -log_view ":$out/${tag}_${n}_${name}.lv" \
    ${opts[@]+"${opts[@]}"} > "$log" 2>&1
  { echo "# $utc $commit load $(cut -d' ' -f1-3 /proc/loadavg) scene=$scene n=$n method=$name ${opts[*]+${opts[*]}}"; grep -E "^(summary|conservation|tall cells)" "$log"; } | tee -a "$out/tall_scene.txt"
  steps=$(grep -oP "summary: \K[0-9]+(?= steps)" "$log")
  wall=$(grep -oP "summary: .* wall \K[0-9.]+" "$log")
  share=$(grep -oP "Pressure \K[0-9.]+(?=%)" "$log")
  parts=$(grep -oP "conservation: liquid particles \K[0-9]+" "$log")
  drift=$(grep -oP "liquid volume drift \K[-+0-9.e]+" "$log" | tail -1)
  maxd=$(grep -oP "conservation: .*liquid volume drift [-+0-9.e]+ \(max \|drift\| \K[-+0-9.e]+" "$log")
  awk -v c="$commit" -v u="$utc" -v l="$load" -v n="$n" -v m="$name" -v t="$tend" -v s="$steps" -v w="$wall" \
      -v sh="$share" -v p="$parts" -v d="$drift" -v md="$maxd" \
      'BEGIN{printf "%s,%s,%s,%s,%s,%s,%s,%s,%.4f,%.4f,%s,%s,%s,%s\n", c,u,l,n,m,t,s,w,w/s,w/s*sh/100,sh,p,d,md}' >> "$csv"
  t1=$(/usr/bin/python3 "$PFF_ROOT/postproc/table1.py" "$out/${tag}_${n}_${name}.lv" "$steps" --csv)
  echo "$commit,$utc,$load,$scene,$n,$name,$tend,$steps,$t1" >> "$t1csv"
  /usr/bin/python3 "$PFF_ROOT/postproc/table1.py" "$out/${tag}_${n}_${name}.lv" "$steps" | tee -a "$out/tall_scene.txt"
done
