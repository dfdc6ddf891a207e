#!/usr/bin/env bash
# rt3d at several viscosities (issue 10: does the lag behind De Rosis & Enan's Table IX come from the definition
# of Re?). rt3d.yaml's Re is W sqrt(g W) / nu; a reference that used another length or velocity scale would have
# run at a smaller viscosity: sqrt(A g W) gives our Re 362 for its 256, the half width W/2 gives 724, both 1024.
# Runs every W in PFF_RT_SIZES at every Re in PFF_RT_RE ("nu0": no viscosity), 2 ranks x 1 thread, no frames, into
# output/rt_reynolds/W<W>_<Re>/, then writes the comparison table (rt_spike.py --csv: the tip at every reference
# time, max and rms deviation, steps, wall seconds) and a plot of every run.
#   bash jobs/bench/rt_reynolds.sh                                   W = 16, 32, 64 at 256 ... 2048 and nu = 0
#   PFF_RT_SIZES="16 32" PFF_RT_RE="256 1024" bash jobs/bench/rt_reynolds.sh      a subset
# W = 64 takes 2-4 min per run on 2 cores, W = 32 about 10 s.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../setup.sh"
out=${PFF_BENCH_DIR:-$PFF_ROOT/output/rt_reynolds}
mkdir -p "$out"
export OMP_NUM_THREADS=1
files=()
labels=()
for W in ${PFF_RT_SIZES:-16 32 64}; do
  for re in ${PFF_RT_RE:-256 362 512 724 1024 1448 2048 nu0}; do
    dir=$out/W${W}_$re
    mkdir -p "$dir"
    if [ "$re" = nu0 ]; then
      visc=(-nu_liquid 0 -nu_gas 0)
      label="W = $W, nu = 0"
    else
      visc=(-rt_reynolds "$re")
      label="W = $W, Re = $re"
    fi
    "${PFF_MPIEXEC[@]}" -n 2 "$PFF_BUILD_DIR/bin/pfflip" -options_file_yaml "$PFF_ROOT/config/rt3d.yaml" \
      -rt_resolution "$W" "${visc[@]}" -sim_frames false -output_dir "$dir" >"$dir/log.txt" 2>&1 || {
      tail -n 20 "$dir/log.txt"
      exit 1
    }
    echo "rt_reynolds: $label done, load $(cut -d' ' -f1-3 /proc/loadavg)"
    files+=("$dir/rt3d_diag.csv")
    labels+=(--label "$label")
  done
done
/usr/bin/python3 "$PFF_ROOT/postproc/rt_spike.py" "${files[@]}" "${labels[@]}" -o "$out/rt_reynolds.png" \
  --csv "$out/rt_reynolds.csv"
