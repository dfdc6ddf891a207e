#!/usr/bin/env bash
# Installs what is missing, builds, and runs the default scene on 2 MPI ranks.
#   bash jobs/run.sh [extra pfflip options]      e.g. bash jobs/run.sh -demo_steps 50 -log_view
#   PFF_RANKS=4 PFF_SCENE=config/other.yaml bash jobs/run.sh
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
scene=${PFF_SCENE:-$PFF_ROOT/config/grid_demo.yaml}
outdir=${PFF_OUTPUT_DIR:-$PFF_ROOT/output/$(basename "$scene" .yaml)}
"${PFF_MPIEXEC[@]}" -n "${PFF_RANKS:-2}" "$PFF_BUILD_DIR/bin/pfflip" -options_file_yaml "$scene" -output_dir "$outdir" "$@"
last=$(ls "$outdir"/frame_*.h5 2>/dev/null | sort | tail -n 1 || true)
if [ -n "$last" ] && [ -x /usr/bin/python3 ]; then
  /usr/bin/python3 "$PFF_ROOT/postproc/slice.py" "$last" u -o "${last%.h5}_u.png" && echo "pfflip: slice plot ${last%.h5}_u.png"
fi
echo "pfflip: output in $outdir (open the .xmf files in ParaView)"
