#!/bin/bash
# The still pools on one, two and three grid levels over many steps, for one or more binaries (issue 10's goal
# "still water, 1000 steps, on 2- and 3-level static grids"). One CSV row per binary and pool:
#   bash jobs/bench/long_pools.sh <label>:<pfflip> [<label>:<pfflip> ...]
# Environment: PFF_BENCH_DIR (default output/long_pools), PFF_POOL_STEPS (default 1000), PFF_POOL_CONFIGS (default
# "still_water still_water_2lev still_water_3lev"), PFF_BENCH_EXTRA (options added to every run).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
DIR=${PFF_BENCH_DIR:-$ROOT/output/long_pools}
STEPS=${PFF_POOL_STEPS:-1000}
CONFIGS=${PFF_POOL_CONFIGS:-"still_water still_water_2lev still_water_3lev"}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_NUM_THREADS=${OMP_NUM_THREADS:-1}
[ $# -ge 1 ] || { echo "usage: $0 <label>:<pfflip> ..." >&2; exit 1; }
mkdir -p "$DIR"
CSV=$DIR/long_pools.csv
[ -f "$CSV" ] || echo "label,config,options,steps,wall_s,peak_umax,last_umax,liquid_drift,liquid_max_drift,target_fraction_end,bubbles_deleted,load_before" >"$CSV"
for spec in "$@"; do
  label=${spec%%:*} exe=${spec#*:}
  for cfg in $CONFIGS; do
    out=$DIR/${label}_$cfg
    rm -rf "$out" && mkdir -p "$out"
    load=$(cut -d' ' -f1 /proc/loadavg)
    t0=$(date +%s.%N)
    mpiexec --oversubscribe --bind-to none -n 2 "$exe" -options_file_yaml "$ROOT/config/$cfg.yaml" -sim_max_steps "$STEPS" \
      -sim_t_end 1000 -sim_frames false -output_dir "$out" ${PFF_BENCH_EXTRA:-} </dev/null >"$out/log.txt" 2>&1
    wall=$(echo "$(date +%s.%N) - $t0" | bc)
    /usr/bin/python3 - "$out" "$label" "$cfg" "${PFF_BENCH_EXTRA:-}" "$wall" "$load" >>"$CSV" <<'EOF'
import csv, glob, sys
out, label, cfg, extra, wall, load = sys.argv[1:]
rows = list(csv.DictReader(open(glob.glob(out + '/*_diag.csv')[0])))
v0 = float(rows[0]['liquid_volume'])
drift = [float(r['liquid_volume']) / v0 - 1 for r in rows]
u = [float(r['umax_grid']) for r in rows]
bub = sum(int(r['bubbles_deleted']) for r in rows[1:])
print(f"{label},{cfg},\"{extra}\",{rows[-1]['step']},{float(wall):.2f},{max(u):.4e},{u[-1]:.4e},{drift[-1]:.3e},"
      f"{max(abs(d) for d in drift):.3e},{rows[-1]['liquid_target_fraction']},{bub},{load}")
EOF
    tail -1 "$CSV"
  done
done
