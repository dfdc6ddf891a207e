#!/usr/bin/env bash
# Run time against error (issue 3): rt3d at W = 16, 32, 64 cells and shear_sphere at 48^3, 100^3,
# 200^3 (50^3 is not possible with power-of-two blocks; 48^3 stands in), on 2 ranks x 1 thread by
# default. One CSV row per run in output/bench/time_error.csv:
#   scene,cells,ranks,threads,steps,wall_s,error,inside_band
# rt3d error = max |y/W - reference| over t/t0 <= 3 (De Rosis & Enan 2021, Table IX) and whether
# the curve stays inside the band of the eight published models; shear error = the relative phi
# error after 2 periods. Plots: time_error.png and rt3d_spike.png in the same directory.
#   bash jobs/bench/time_error.sh                 all runs (200^3 alone takes about 18 h on 2 cores)
#   PFF_RT_SIZES="16 32" PFF_SHEAR_SIZES="48" bash jobs/bench/time_error.sh    a subset
#   PFF_RESUME=1 PFF_RT_SIZES=64 PFF_SHEAR_SIZES=" " bash jobs/bench/time_error.sh  continue a killed run
#   (an empty size list means the default sizes; a blank " " means none)
#   PFF_BENCH_ARGS="-pressure_pc_type gamg" ...                                  extra pfflip options
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../setup.sh"
out=${PFF_BENCH_DIR:-$PFF_ROOT/output/bench}
mkdir -p "$out"
csv=$out/time_error.csv
ranks=${PFF_RANKS:-2}
threads=${OMP_NUM_THREADS:-1}
export OMP_NUM_THREADS=$threads
[ -f "$csv" ] || echo "scene,cells,ranks,threads,steps,wall_s,error,inside_band" >"$csv"
py=/usr/bin/python3
pfflip=$PFF_BUILD_DIR/bin/pfflip
rev=$(git -C "$PFF_ROOT" describe --always --dirty)

# run <dir> <pfflip args...>: runs into <dir> with a checkpoint every 50 steps and prints
# "steps wall". With PFF_RESUME=1 a run that left <dir>/checkpoint.h5 continues from it: the
# diagnostics rows after the checkpoint are dropped (the restarted run appends its own) and the wall
# time is the sum over the segments (<dir>/segments.txt).
run() {
  local dir=$1
  shift
  local log=$dir/log.txt restart=()
  if [ "${PFF_RESUME:-0}" = 1 ] && [ -f "$dir/checkpoint.h5" ]; then
    local at
    at=$(sed -n 's/^checkpoint .* at step \([0-9]*\)$/\1/p' "$dir"/log*.txt | sort -n | tail -n 1)
    for d in "$dir"/*_diag.csv; do
      awk -F, -v at="$at" 'NR == 1 || /^#/ || $1 + 0 <= at' "$d" >"$d.tmp" && mv "$d.tmp" "$d"
    done
    log=$dir/log.$at.txt
    restart=(-sim_restart "$dir/checkpoint.h5")
    echo "pfflip: $dir continues from step $at" >&2
  else
    : >"$dir/segments.txt"
  fi
  # shellcheck disable=SC2086
  "${PFF_MPIEXEC[@]}" -n "$ranks" "$pfflip" "$@" -output_dir "$dir" -sim_frames false -sim_checkpoint_every 50 \
    "${restart[@]}" ${PFF_BENCH_ARGS:-} >"$log" 2>&1 || {
    tail -n 20 "$log"
    return 1
  }
  sed -n 's/^summary: \([0-9]*\) steps .* wall \([0-9.]*\) s.*/\1 \2/p' "$log" >>"$dir/segments.txt"
  awk '{w += $2} END {print last, w} {last = $1}' "$dir/segments.txt"
}

spikes=()
for W in ${PFF_RT_SIZES:-16 32 64}; do
  dir=$out/rt3d_W$W
  mkdir -p "$dir"
  read -r steps wall < <(run "$dir" -options_file_yaml "$PFF_ROOT/config/rt3d.yaml" -rt_resolution "$W")
  line=$($py "$PFF_ROOT/postproc/rt_spike.py" "$dir/rt3d_diag.csv" -o "$dir/spike.png")
  err=$(sed -n 's/.*max_dev=\([^ ]*\).*/\1/p' <<<"$line")
  band=$(sed -n 's/.*inside_band=\([^ ]*\).*/\1/p' <<<"$line")
  echo "rt3d,${W}x$((4 * W))x$W,$ranks,$threads,$steps,$wall,$err,$band" | tee -a "$csv"
  echo "# rt3d W=$W $rev: $line" >>"$out/time_error.log"
  spikes+=("$dir/rt3d_diag.csv")
done
for N in ${PFF_SHEAR_SIZES:-48 100 200}; do
  dir=$out/shear_$N
  mkdir -p "$dir"
  read -r steps wall < <(run "$dir" -options_file_yaml "$PFF_ROOT/config/shear_sphere.yaml" -shear_resolution "$N")
  err=$(sed -n 's/^shear_sphere: relative phi error \([0-9.eE+-]*\).*/\1/p' "$dir"/log*.txt | tail -n 1)
  echo "shear_sphere,${N}^3,$ranks,$threads,$steps,$wall,$err,-" | tee -a "$csv"
done
$py "$PFF_ROOT/postproc/time_error.py" "$csv" -o "$out/time_error.png"
[ ${#spikes[@]} -gt 0 ] && $py "$PFF_ROOT/postproc/rt_spike.py" "${spikes[@]}" -o "$out/rt3d_spike.png" >/dev/null
echo "pfflip: $csv, $out/time_error.png"
