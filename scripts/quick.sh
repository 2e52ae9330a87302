#!/usr/bin/env bash
# The quick loop while working: the release build and its whole suite, nothing else (no soak, no
# packages, no sanitizers). What CI runs is still scripts/test.sh.
#
#   scripts/quick.sh                    build/release: build, then every release suite
#   scripts/quick.sh -R hesai           ctest's own options narrow it (here: suites matching hesai)
# With SIM_CCACHE_DIR=~/.cache/sim-ccache a rebuild after a branch switch is mostly cache hits.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
SIM_TEST_STAGES=release SIM_SOAK_SECONDS=0 SIM_CTEST_ARGS="$*" exec "$root/scripts/test.sh"
