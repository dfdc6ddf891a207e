#!/usr/bin/env bash
# Bubbly Poisson benchmark (docs/benchmarks.md, "Bubbly Poisson problem"): FCG with each PC on the
# nine-bubble problem, uniform and 3-level adaptive grids, N = 64 and 128, density ratio 1e3, rtol 1e-8,
# on 2 ranks x 1 thread. Appends the full output to output/bench/poisson.txt and shows the RESULT and
# SKIP lines. Usage: bash jobs/bench/poisson.sh [extra pff-bench-poisson options, e.g. -bench_pcs gamg,hypre]
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../setup.sh"
out=$PFF_ROOT/output/bench
mkdir -p "$out"
bench=$PFF_BUILD_DIR/bin/pff-bench-poisson
{
  echo "# $(date -u +%FT%TZ) $(git -C "$PFF_ROOT" describe --always --dirty) $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
  echo "# ${PFF_MPIEXEC[*]} -n 2 $bench $*"
  OMP_NUM_THREADS=1 "${PFF_MPIEXEC[@]}" -n 2 "$bench" "$@"
} | tee -a "$out/poisson.txt" | grep -E "^(RESULT|SKIP|# grid|# FAILED)"
