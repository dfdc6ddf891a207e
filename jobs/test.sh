#!/usr/bin/env bash
# Installs what is missing, builds, and runs the default test suite (ctest); exit status = result.
# Long cases (label "long") run only on request: PFF_TEST_ARGS="-L long" bash jobs/test.sh
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
cd "$PFF_BUILD_DIR"
# shellcheck disable=SC2086
ctest --output-on-failure -j "$(nproc)" ${PFF_TEST_ARGS:--LE long}
