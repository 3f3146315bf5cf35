#!/usr/bin/env bash
# Installs dependencies, builds, fetches the OpenArena maps, and runs the whole test suite
# (unit, oracle, invariant, real-map and command-line tests) through ctest. This is the
# command CI runs.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh build RelWithDebInfo -DVIEWCELLS_BUILD_TESTS=ON
# Real Quake 3 levels from Debian's archive (oa_dm2 is tested); the tests fail without them.
bash scripts/fetch-maps.sh
export VIEWCELLS_REQUIRE_MAPS=1
cd build
ctest --output-on-failure -j "$(nproc)" --timeout 600
