#!/usr/bin/env bash
# The floating box of config/tall_float_small.yaml (issue 15: "a floating box comes to rest at its Archimedes
# draft, within 2 %"): the liquid model on the quadtree with Eq. 7's phi as the free surface (the default), with
# -flow_liquid_surface_volume, and on uniform cubic cells (-grid_levels 1 -tall_merge false), 2 ranks x 1 thread,
# no frames, to t_end. Its mean height over whole periods of the oscillation after t = 0.5 s against Archimedes'
# (postproc/float_draft.py --periods), for the pool's nominal volume and for the run's own liquid volume.
# Usage: bash jobs/bench/tall_float.sh [t_end [binary [label]]] (default 5 s, the build's pfflip, git describe).
# Appends one CSV row per variant to docs/data/tall_float_issue15.csv: commit (or label), UTC time, load average,
# variant, t_end, steps, wall seconds, liquid volume drift and its largest magnitude, the errors in % of the draft
# (nominal, the run's volume), whole periods averaged, the largest grid speed and the steps above 1 m/s.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../setup.sh"
tend=${1:-5}
bin=${2:-$PFF_BUILD_DIR/bin/pfflip}
commit=${3:-$(git -C "$PFF_ROOT" describe --always --dirty)}
out=$PFF_ROOT/output/bench
csv=$PFF_ROOT/docs/data/tall_float_issue15.csv
mkdir -p "$out"
[ -f "$csv" ] || echo "commit,utc,load1,variant,t_end,steps,wall_s,liquid_volume_drift,max_abs_drift,err_nominal_pct,err_run_volume_pct,periods,umax_grid_max,steps_above_1ms" > "$csv"
for m in "quadtree_phi:" "quadtree_volume:-flow_liquid_surface_volume" "cubic_phi:-grid_levels 1 -tall_merge false"; do
  name=${m%%:*}
  read -r -a opts <<< "${m#*:}"
  load=$(cut -d' ' -f1 /proc/loadavg)
  utc=$(date -u +%FT%TZ)
  dir=$out/tall_float_$name
  rm -rf "$dir"
  OMP_NUM_THREADS=1 "${PFF_MPIEXEC[@]}" -n 2 "$bin" -options_file_yaml "$PFF_ROOT/config/tall_float_small.yaml" \
    -sim_t_end "$tend" -sim_frames false -output_dir "$dir" ${opts[@]+"${opts[@]}"} > "$dir.log" 2>&1
  steps=$(grep -oP "summary: \K[0-9]+(?= steps)" "$dir.log")
  wall=$(grep -oP "summary: .* wall \K[0-9.]+" "$dir.log")
  drift=$(grep -oP "liquid volume drift \K[-+0-9.e]+" "$dir.log" | tail -1)
  maxd=$(grep -oP "conservation: .*liquid volume drift [-+0-9.e]+ \(max \|drift\| \K[-+0-9.e]+" "$dir.log")
  nom=$(/usr/bin/python3 "$PFF_ROOT/postproc/float_draft.py" "$dir" --from 0.5 --periods || true)
  run=$(/usr/bin/python3 "$PFF_ROOT/postproc/float_draft.py" "$dir" --from 0.5 --periods --measured || true)
  echo "# $utc $commit load $(cut -d' ' -f1-3 /proc/loadavg) $name: $nom" | tee -a "$out/tall_float.txt"
  en=$(grep -oP "error \K[-+0-9.]+" <<< "$nom")
  er=$(grep -oP "error \K[-+0-9.]+" <<< "$run")
  per=$(grep -oP "[0-9]+(?= whole periods)" <<< "$nom")
  spd=$(/usr/bin/python3 -c "import csv,sys
r=[float(x['umax_grid']) for x in list(csv.DictReader(open(sys.argv[1])))[1:]]
print(f'{max(r):.3f},{sum(1 for v in r if v > 1)}')" "$dir/fluid_diag.csv")
  echo "$commit,$utc,$load,$name,$tend,$steps,$wall,$drift,$maxd,$en,$er,$per,$spd" >> "$csv"
done
