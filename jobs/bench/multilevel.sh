#!/usr/bin/env bash
# Static multi-level fluid scenes (issue 10, docs/scenes.md): runs each 2- and 3-level config and its
# one-level reference (the same file with -grid_levels 1: every block at level 0) for PFF_STEPS steps
# (default 10) on PFF_RANKS ranks (default 2) x OMP_NUM_THREADS threads (default 1), without frames.
# Prints one markdown table row per run (also in output/bench/multilevel/table.md):
#   config | levels | blocks per level | particles | steps/s | liquid volume drift | max |u| | particles kept
# max |u| is the largest umax_grid of the diagnostics CSV; the drift and the particle check are those
# of the conservation line at the end of the run.
#   bash jobs/bench/multilevel.sh
#   PFF_CONFIGS="dam_break_small_3lev" PFF_RANKS=4 PFF_REFERENCE=0 bash jobs/bench/multilevel.sh
#   PFF_STEPS=0 PFF_BENCH_ARGS="-sim_t_end 0.5" ...     to an end time instead (extra pfflip options)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../setup.sh"
out=${PFF_BENCH_DIR:-$PFF_ROOT/output/bench}/multilevel
steps=${PFF_STEPS:-10}
ranks=${PFF_RANKS:-2}
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-1}
configs=${PFF_CONFIGS:-"still_water_2lev still_water_3lev rt3d_small_2lev rt3d_small_3lev dam_break_small_2lev
  dam_break_small_3lev dam_break_2lev dam_break_3lev drop_pool_2lev drop_pool_3lev"}
mkdir -p "$out"
table=$out/table.md

# run <label> <config> <extra pfflip args...>: one run, one table row
run() {
  local label=$1 config=$2 dir=$out/$1
  shift 2
  rm -rf "$dir" && mkdir -p "$dir"
  "${PFF_MPIEXEC[@]}" -n "$ranks" "$PFF_BUILD_DIR/bin/pfflip" -options_file_yaml "$PFF_ROOT/config/$config.yaml" \
    -output_dir "$dir" -sim_frames false -sim_max_steps "$steps" ${PFF_BENCH_ARGS:-} "$@" >"$dir/log.txt" 2>&1 || echo "run failed" >>"$dir/log.txt"
  /usr/bin/python3 - "$label" "$dir" <<'PY' | tee -a "$table"
import csv, glob, re, sys
label, d = sys.argv[1], sys.argv[2]
log = open(d + "/log.txt").read()
n0 = int(re.search(r"block size (\d+)", log).group(1))
levels = [(int(l), int(c)) for l, c in re.findall(r"^  level (\d+): (\d+) cells", log, re.M)]
blocks = " / ".join(str(c // (n0 >> l) ** 3) for l, c in levels)
cons = re.search(r"conservation: liquid particles (\d+) \(start (\d+)\)  gas particles (\d+) \(start (\d+), (\d+) deleted"
                 r"[^)]*\)  liquid volume drift (\S+)  (\w+)", log)
summ = re.search(r"summary: (\d+) steps .*\(([0-9.]+) s/step\)", log)
if not cons or not summ:
    print(f"| {label} | run failed, see {d}/log.txt | | | | | | |")
    sys.exit(0)
rows = list(csv.DictReader(open(glob.glob(d + "/*_diag.csv")[0])))
umax = max(float(r["umax_grid"]) for r in rows)
particles = int(cons.group(2)) + int(cons.group(4))
sps = 1 / float(summ.group(2)) if float(summ.group(2)) > 0 else 0
print(f"| {label} | {len(levels)} | {blocks} | {particles} | {sps:.2f} ({summ.group(1)} steps) | {float(cons.group(6)):.2e} "
      f"| {umax:.3f} | {cons.group(7)} |")
PY
}

echo "| config | levels | blocks per level | particles | steps/s | liquid volume drift | max \|u\| (m/s or W/t0) | particles kept |" | tee -a "$table"
echo "| --- | --- | --- | --- | --- | --- | --- | --- |" | tee -a "$table"
for c in $configs; do
  run "${c}_np${ranks}" "$c"
  if [ "${PFF_REFERENCE:-1}" = 1 ]; then run "${c}_1lev_np${ranks}" "$c" -grid_levels 1; fi
done
