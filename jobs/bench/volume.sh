#!/usr/bin/env bash
# Issue 10's volume and still-water goals, one row per run, into $PFF_BENCH_DIR/volume.csv (default
# output/bench): liquid and gas volume drift (final and max |drift| over the run, from the conservation
# line), peak max|u| on the grid, steps and wall time, the load average before the run, and the shares of
# the step that the pressure and the correction's solve take (the summary line, max over ranks).
#   PFF_BENCH_RANKS  MPI ranks (default 2)     PFF_BENCH_EXE  the pfflip binary (default build/bin/pfflip)
#   PFF_BENCH_CASES  names of the cases to run (default all, see below)
#   PFF_BENCH_EXTRA  options appended to every case (e.g. -flow_volume_correction_interface closed), also in the
#                    CSV's options column
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
OUT=${PFF_BENCH_DIR:-$ROOT/output/bench}
EXE=${PFF_BENCH_EXE:-$ROOT/build/bin/pfflip}
NP=${PFF_BENCH_RANKS:-2}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_NUM_THREADS=${OMP_NUM_THREADS:-1}
mkdir -p "$OUT"
CSV=$OUT/volume.csv
declare -A CASES=(
  [dam_break]="dam_break.yaml"
  [drop_pool]="drop_pool.yaml"
  [still_1e3_1000]="still_water.yaml -sim_max_steps 1000 -sim_t_end 1000"
  [still_1e4_1000]="still_water.yaml -still_ratio 1e4 -sim_max_steps 1000 -sim_t_end 1000"
  [still_1e3_1000_band0]="still_water.yaml -particles_jitter_band 0 -sim_max_steps 1000 -sim_t_end 1000"
  [still_1e4_1000_band0]="still_water.yaml -still_ratio 1e4 -particles_jitter_band 0 -sim_max_steps 1000 -sim_t_end 1000"
  [still_lattice_1000]="still_water.yaml -particles_jitter 0 -pressure_ksp_rtol 1e-10 -sim_max_steps 1000 -sim_t_end 1000"
  [still_lattice_1e4_1000]="still_water.yaml -still_ratio 1e4 -particles_jitter 0 -pressure_ksp_rtol 1e-10 -sim_max_steps 1000 -sim_t_end 1000"
  [rt3d_w32]="rt3d.yaml"
  [bubbles_small_003]="bubbles_small.yaml -sim_t_end 0.03"
  [dam_break_small_cfl0.01]="dam_break_small.yaml -sim_t_end 1 -flow_cfl 0.01"
  [dam_break_small_cfl0.1]="dam_break_small.yaml -sim_t_end 1 -flow_cfl 0.1"
  [dam_break_small_cfl1]="dam_break_small.yaml -sim_t_end 1 -flow_cfl 1"
  [dam_break_small_cfl3]="dam_break_small.yaml -sim_t_end 1 -flow_cfl 3"
  [dam_break_small_dtmax1e-6]="dam_break_small.yaml -sim_t_end 0.002 -flow_dt_max 1e-6"
  [still_small_1e5]="still_water_small.yaml -still_ratio 1e5 -sim_t_end 1"
  [still_water_2lev]="still_water_2lev.yaml"
  [still_water_3lev]="still_water_3lev.yaml"
  [rt3d_small_2lev]="rt3d_small_2lev.yaml"
  [rt3d_small_3lev]="rt3d_small_3lev.yaml"
  [dam_break_2lev]="dam_break_2lev.yaml"
  [dam_break_3lev]="dam_break_3lev.yaml"
  [drop_pool_2lev]="drop_pool_2lev.yaml"
)
ORDER=${PFF_BENCH_CASES:-"still_small_1e5 dam_break_small_cfl3 dam_break_small_cfl1 dam_break_small_cfl0.1 dam_break_small_cfl0.01 dam_break_small_dtmax1e-6 bubbles_small_003 still_water_2lev still_water_3lev rt3d_small_2lev rt3d_small_3lev dam_break drop_pool rt3d_w32 dam_break_2lev dam_break_3lev drop_pool_2lev still_1e3_1000 still_1e4_1000 still_1e3_1000_band0 still_1e4_1000_band0 still_lattice_1000 still_lattice_1e4_1000"}
[ -f "$CSV" ] || echo "case,options,ranks,steps,wall_s,liquid_drift,liquid_max_drift,gas_drift,gas_max_drift,peak_umax_grid,load_before,status,pressure_share,correction_share" > "$CSV"
# the share of stage $1 in the summary line of $log
share() { sed -n "s/^summary: stage shares.* $1 \([0-9.]*\)%.*/\1/p" <<<"$log"; }
for c in $ORDER; do
  set -- ${CASES[$c]} ${PFF_BENCH_EXTRA:-}
  yaml=$1; shift
  dir=$OUT/volume_$c
  rm -rf "$dir"
  load=$(cut -d' ' -f1 /proc/loadavg)
  log=$(mpiexec --oversubscribe --bind-to none -n "$NP" "$EXE" -options_file_yaml "$ROOT/config/$yaml" -sim_frames false \
        -output_dir "$dir" "$@" 2>&1) && status=ok || status=failed
  cons=$(grep '^conservation:' <<<"$log" || true)
  num() { sed -n "s/.*$1 \([-+0-9.e]*\) (max |drift| \([-+0-9.e]*\)).*/\1,\2/p" <<<"$cons"; }
  liq=$(num "liquid volume drift"); gas=$(num "gas volume drift")
  steps=$(sed -n 's/^summary: \([0-9]*\) steps .*wall \([0-9.]*\) s.*/\1,\2/p' <<<"$log")
  diag=$(ls "$dir"/*_diag.csv 2>/dev/null | head -1)
  peak=$(awk -F, 'NR==1{for(i=1;i<=NF;i++) if($i=="umax_grid") k=i} NR>1 && k && $k+0>m{m=$k+0} END{printf "%.4e", m}' "$diag" 2>/dev/null || echo nan)
  echo "$c,\"$yaml $*\",$NP,${steps:-,},${liq:-,},${gas:-,},$peak,$load,$status,$(share Pressure),$(share Correction)" |
    tee -a "$CSV"
done
