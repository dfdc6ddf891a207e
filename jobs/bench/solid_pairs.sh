#!/bin/bash
# Two pfflip binaries alternated on the scenes with a solid obstacle (docs/benchmarks.md, "Solids out of the coarse
# levels"): dam_break.yaml whole, dam_break_adaptive.yaml 60 steps, dam_break_2lev.yaml 200 steps, two rounds, 2 ranks x
# 1 thread. One CSV row per run (wall, pressure and correction iterations, stage shares, largest liquid drift) on
# standard output and in output/bench/solid_pairs.csv.
# Usage: bash jobs/bench/solid_pairs.sh <label>:<other pfflip>
set -euo pipefail
[ $# -ge 1 ] && [[ $1 == *:* ]] || { echo "usage: $0 <label>:<other pfflip>" >&2; exit 2; }
label=${1%%:*} other=${1#*:}
source "$(dirname "${BASH_SOURCE[0]}")/../setup.sh"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_NUM_THREADS=1
out=$PFF_ROOT/output/bench/solid_pairs.csv; mkdir -p "$(dirname "$out")"
echo "case,binary,round,utc,load1,steps,wall_s,pressure_its,correction_its,pressure_pct,correction_pct,liquid_max_drift" > $out
for round in 1 2; do
  for c in "dam_break:" "dam_break_adaptive:-sim_max_steps 60" "dam_break_2lev:-sim_max_steps 200"; do
    cfg=${c%%:*}; extra=${c#*:}
    for side in old new; do
      if [ $side = old ]; then b=$other; lab=$label; else b=$PFF_BUILD_DIR/bin/pfflip; lab=$(git -C "$PFF_ROOT" describe --always); fi
      d=$PFF_ROOT/output/bench/solid_pairs_$side; rm -rf $d
      load=$(cut -d' ' -f1 /proc/loadavg); utc=$(date -u +%H:%M:%S)
      "${PFF_MPIEXEC[@]}" -n 2 $b -options_file_yaml $PFF_ROOT/config/$cfg.yaml -sim_frames false -output_dir $d -info :sys $extra </dev/null > $d.log 2>&1
      steps=$(sed -n 's/^summary: \([0-9]*\) steps .*wall \([0-9.]*\) s.*/\1,\2/p' $d.log)
      pits=$(awk -F, 'NR>1{s+=$7} END{print s}' $d/fluid_diag.csv)
      cits=$(grep -o '^\[0\] <sys> [A-Za-z_]*(): volume correction: [0-9]* iterations' $d.log | awk '{s+=$6} END{print s}' || true)
      share() { sed -n "s/^summary: stage shares.* $1 \([0-9.]*\)%.*/\1/p" $d.log; }
      md=$(sed -n 's/.*liquid volume drift [-+0-9.e]* (max |drift| \([-+0-9.e]*\)).*/\1/p' $d.log)
      echo "$cfg,$lab,$round,$utc,$load,$steps,$pits,$cits,$(share Pressure),$(share Correction),$md" | tee -a $out
    done
  done
done
