#!/usr/bin/env bash
# Grid bandwidth benchmark (paper Table 3): the MSBG Laplacian against a streaming copy, with both
# cores busy (1 rank x 2 threads, 2 ranks x 1 thread) and on one thread. Appends the RESULT lines
# to output/bench/grid.txt. Usage: bash jobs/bench/grid.sh [extra pff-bench-grid options]
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../setup.sh"
out=$PFF_ROOT/output/bench
mkdir -p "$out"
bench=$PFF_BUILD_DIR/bin/pff-bench-grid
{
  echo "# $(date -u +%FT%TZ) $(git -C "$PFF_ROOT" describe --always --dirty) $(nproc) cores"
  OMP_NUM_THREADS=1 "${PFF_MPIEXEC[@]}" -n 1 "$bench" "$@"
  OMP_NUM_THREADS=2 "${PFF_MPIEXEC[@]}" -n 1 "$bench" "$@"
  OMP_NUM_THREADS=1 "${PFF_MPIEXEC[@]}" -n 2 "$bench" "$@"
} | tee -a "$out/grid.txt" | grep RESULT
