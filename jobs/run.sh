#!/usr/bin/env bash
# Installs what is missing, builds, and runs the default scene (a small 3D Rayleigh-Taylor
# instability, config/rt3d_small.yaml, about a minute on 2 ranks), then plots its spike tip against
# the published reference band and a mid-plane slice of phi and vorticity.
#   bash jobs/run.sh [extra pfflip options]          e.g. bash jobs/run.sh -rt_resolution 32 -log_view
#   PFF_RANKS=4 PFF_SCENE=config/still_water.yaml bash jobs/run.sh
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
scene=${PFF_SCENE:-$PFF_ROOT/config/rt3d_small.yaml}
name=$(basename "$scene" .yaml)
outdir=${PFF_OUTPUT_DIR:-$PFF_ROOT/output/$name}
"${PFF_MPIEXEC[@]}" -n "${PFF_RANKS:-2}" "$PFF_BUILD_DIR/bin/pfflip" -options_file_yaml "$scene" -output_dir "$outdir" "$@"
py=/usr/bin/python3
if [ -x $py ]; then
  for diag in "$outdir"/rt3d_diag.csv "$outdir"/rt_paper_diag.csv; do
    [ -f "$diag" ] && $py "$PFF_ROOT/postproc/rt_spike.py" "$diag" -o "${diag%_diag.csv}_spike.png" &&
      echo "pfflip: spike-tip plot ${diag%_diag.csv}_spike.png"
  done
  last=$(ls "$outdir"/frame_*.h5 2>/dev/null | sort | tail -n 1 || true)
  if [ -n "$last" ]; then
    for ch in phi vorticity u; do
      if $py "$PFF_ROOT/postproc/slice.py" "$last" "$ch" -o "${last%.h5}_$ch.png" >/dev/null 2>&1; then
        echo "pfflip: slice plot ${last%.h5}_$ch.png"
      fi
    done
  fi
fi
echo "pfflip: output in $outdir (open the .xmf files in ParaView)"
