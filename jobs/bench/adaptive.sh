#!/usr/bin/env bash
# Dynamic adaptivity against a uniform grid (issue 14): rt3d at effective W cells across (default 64),
# uniform against 3 adaptive levels (-adapt_levels 3, bands beta_bw in PFF_BANDS, default "1 2"), on
# 2 ranks x 1 thread. One CSV row per run in output/bench/adaptive/adaptive.csv:
#   run,W,levels,band,ranks,threads,steps,wall_s,s_per_step,rss_max_mb,rss_sum_mb,particles_end,
#   spike_t3,max_dev,inside_band,adapt_share,start_utc,load1,commit
# wall_s is the run's time-stepping wall time (the summary line), rss_* the peak resident set of the
# ranks (/usr/bin/time around each rank), max_dev the largest |spike - reference| over t/t0 <= 3
# (postproc/rt_spike.py, De Rosis & Enan 2021), adapt_share the Adapt stage's share of the step time.
# Runs alone (one heavy process at a time); record the load with the figures.
#   bash jobs/bench/adaptive.sh                     W = 64: uniform about 6 min, each adaptive run 2-4 min
#   PFF_W=32 PFF_BANDS="1" bash jobs/bench/adaptive.sh   a smaller check
#   PFF_RUNS="adaptive" ...                          skip the uniform run (its row stays in the CSV)
#   PFF_EXTRA="-flow_volume_control 0" ...           options appended to every run; the run's name and output
#                                                    directory carry them (spaces as _), e.g. the volume control's
#                                                    rows of docs/validation.md, "The volume control on adaptive grids"
# adaptive.log also gets the number of steps that changed the grid (blocks refined or coarsened) and the liquid
# volume's swings (postproc/volume_swings.py --threshold 0.2: largest step change, alternating steps, drift range).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../setup.sh"
W=${PFF_W:-64}
out=${PFF_BENCH_DIR:-$PFF_ROOT/output/bench}/adaptive
mkdir -p "$out"
csv=$out/adaptive.csv
ranks=${PFF_RANKS:-2}
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-1}
py=/usr/bin/python3
pfflip=$PFF_BUILD_DIR/bin/pfflip
rev=$(git -C "$PFF_ROOT" describe --always --dirty)
[ -f "$csv" ] || echo "run,W,levels,band,ranks,threads,steps,wall_s,s_per_step,rss_max_mb,rss_sum_mb,particles_end,spike_t3,max_dev,inside_band,adapt_share,start_utc,load1,commit" >"$csv"

# bench <name> <levels> <band> <pfflip args...>
bench() {
  local name=$1 levels=$2 band=$3
  shift 3
  if [ -n "${PFF_EXTRA:-}" ]; then
    name="${name}_$(tr ' ,' '__' <<<"$PFF_EXTRA")"
    set -- "$@" $PFF_EXTRA
  fi
  local dir=$out/${name}_W$W
  mkdir -p "$dir"
  local start load
  start=$(date -u +%H:%M)
  load=$(cut -d' ' -f1 /proc/loadavg)
  "${PFF_MPIEXEC[@]}" -n "$ranks" -x OMP_NUM_THREADS /usr/bin/time -f "RSS_KB %M" "$pfflip" \
    -options_file_yaml "$PFF_ROOT/config/rt3d.yaml" -rt_resolution "$W" -output_dir "$dir" -sim_frames false "$@" \
    >"$dir/log.txt" 2>&1 || {
    tail -n 20 "$dir/log.txt"
    return 1
  }
  local steps wall sps rss particles spike line dev inside share
  read -r steps wall sps < <(sed -n 's/^summary: \([0-9]*\) steps .* wall \([0-9.]*\) s  (\([0-9.]*\) s\/step).*/\1 \2 \3/p' "$dir/log.txt")
  rss=$(awk '/^RSS_KB/ {s += $2; if ($2 > m) m = $2} END {printf "%.0f,%.0f", m / 1024, s / 1024}' "$dir/log.txt")
  particles=$(grep '^step ' "$dir/log.txt" | tail -n 1 | sed -n 's/.* particles \([0-9]*\) .*/\1/p')
  spike=$(sed -n 's/^rt3d: spike tip y\/W \([0-9.]*\) .*/\1/p' "$dir/log.txt")
  line=$($py "$PFF_ROOT/postproc/rt_spike.py" "$dir/rt3d_diag.csv" -o "$dir/spike.png")
  dev=$(sed -n 's/.*max_dev=\([^ ]*\).*/\1/p' <<<"$line")
  inside=$(sed -n 's/.*inside_band=\([^ ]*\).*/\1/p' <<<"$line")
  share=$(sed -n 's/.*Adapt \([0-9.]*\)%.*/\1/p' "$dir/log.txt")
  echo "$name,$W,$levels,$band,$ranks,$OMP_NUM_THREADS,$steps,$wall,$sps,$rss,$particles,$spike,$dev,$inside,${share:-0},$start,$load,$rev" | tee -a "$csv"
  local changes
  changes=$(grep -E '^step ' "$dir/log.txt" | grep -cE 'blocks \+[1-9]|blocks \+[0-9]+ -[1-9]' || true)
  # the liquid volume's step-to-step swings (docs/validation.md, "Holes after a grid change"); never fails the run
  local swings
  swings=$($py "$PFF_ROOT/postproc/volume_swings.py" "$dir/rt3d_diag.csv" --threshold 0.2 --max-alternating 1000000 | head -n 1)
  echo "# $name W=$W $rev: $line grid_changes=$changes $swings" >>"$out/adaptive.log"
}

for run in ${PFF_RUNS:-uniform adaptive}; do
  case $run in
  uniform) bench uniform 1 - ;;
  adaptive)
    for b in ${PFF_BANDS:-1 2}; do
      bench "adaptive_b$b" 3 "$b" -grid_levels 3 -adapt_levels 3 -adapt_band "$b"
    done
    ;;
  *) echo "unknown run $run" >&2 && exit 1 ;;
  esac
done
$py "$PFF_ROOT/postproc/rt_spike.py" "$out"/*_W"$W"/rt3d_diag.csv -o "$out/spike_W$W.png" >/dev/null
echo "pfflip: $csv, $out/spike_W$W.png"
