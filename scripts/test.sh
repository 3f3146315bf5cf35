#!/usr/bin/env bash
# Installs dependencies, builds, and runs the whole test suite (unit, oracle, invariant and
# command-line tests) through ctest. This is the command CI runs.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh build RelWithDebInfo -DVIEWCELLS_BUILD_TESTS=ON
cd build
ctest --output-on-failure -j "$(nproc)" --timeout 600
