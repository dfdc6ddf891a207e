#!/usr/bin/env bash
# Velocity spikes of the liquid model in violent flow (issue 15): the breaking dam with pillars
# (config/tall_dam_small.yaml) to t = 0.4 s, the floating cubes (config/tall_cubes_small.yaml) to t = 0.5 s and the
# floating box (config/tall_float_small.yaml) to t = 5 s, on their quadtrees, 2 ranks x 1 thread, no frames.
# Usage: bash jobs/bench/tall_spikes.sh [binary [label [options...]]] (default: the build's pfflip, git describe).
# Appends one CSV row per scene to docs/data/tall_spikes_issue15.csv: commit (or label), UTC time, load average,
# scene, options, steps, wall seconds, the largest grid speed (umax_grid of fluid_diag.csv) and the steps above 3 and
# 5 m/s, the median grid speed, the largest particle speed (the step's CFL number times h / dt, h = 1/64 in all three
# scenes) and the steps where it exceeds 5 m/s, the liquid volume drift, and for the floating box its mean
# height over whole periods against Archimedes' (postproc/float_draft.py --periods, % of the draft).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../setup.sh"
bin=${1:-$PFF_BUILD_DIR/bin/pfflip}
label=${2:-$(git -C "$PFF_ROOT" describe --always --dirty)}
shift $(( $# > 2 ? 2 : $# ))
extra=("$@")
out=$PFF_ROOT/output/bench
csv=$PFF_ROOT/docs/data/tall_spikes_issue15.csv
mkdir -p "$out"
[ -f "$csv" ] || echo "commit,utc,load1,scene,options,steps,wall_s,umax_grid_max,steps_above_3,steps_above_5,umax_grid_median,umax_particles_max,particle_steps_above_5,liquid_volume_drift,float_err_pct" > "$csv"
for sc in "dam:tall_dam_small.yaml:0.4" "cubes:tall_cubes_small.yaml:0.5" "float:tall_float_small.yaml:5"; do
  IFS=: read -r name cfg tend <<< "$sc"
  load=$(cut -d' ' -f1 /proc/loadavg)
  utc=$(date -u +%FT%TZ)
  dir=$out/tall_spikes_$name
  rm -rf "$dir"
  OMP_NUM_THREADS=1 "${PFF_MPIEXEC[@]}" -n 2 "$bin" -options_file_yaml "$PFF_ROOT/config/$cfg" -sim_t_end "$tend" \
    -sim_frames false -output_dir "$dir" ${extra[@]+"${extra[@]}"} > "$dir.log" 2>&1
  wall=$(grep -oP "summary: .* wall \K[0-9.]+" "$dir.log")
  fl=""
  [ "$name" = float ] && fl=$(/usr/bin/python3 "$PFF_ROOT/postproc/float_draft.py" "$dir" --from 0.5 --periods | grep -oP "error \K[-+0-9.]+" || true)
  row=$(/usr/bin/python3 -c "import csv,sys
r=list(csv.DictReader(open(sys.argv[1])))[1:]
u=[float(x['umax_grid']) for x in r]
v0,v1=float(r[0]['liquid_volume']),float(r[-1]['liquid_volume'])
vp=[float(x['cfl'])/64/float(x['dt']) for x in r if float(x['dt'])>0]
print(f\"{len(r)},{max(u):.3f},{sum(x>3 for x in u)},{sum(x>5 for x in u)},{sorted(u)[len(u)//2]:.3f},{max(vp):.3f},{sum(x>5 for x in vp)},{v1/v0-1:.3e}\")" "$dir/fluid_diag.csv")
  IFS=, read -r steps umax n3 n5 med vpmax vp5 drift <<< "$row"
  echo "# $utc $label load $(cut -d' ' -f1-3 /proc/loadavg) $name ${extra[*]+${extra[*]}}: $row $fl" | tee -a "$out/tall_spikes.txt"
  echo "$label,$utc,$load,$name,${extra[*]+${extra[*]}},$steps,$wall,$umax,$n3,$n5,$med,$vpmax,$vp5,$drift,$fl" >> "$csv"
done
