#!/usr/bin/env bash
# The whole test suite under AddressSanitizer and UBSan (VIEWCELLS_SANITIZE, gcc), in
# build-asan/: any report fails the run (-fno-sanitize-recover). Slower than the plain suite
# (several minutes to build, about three times the test time), so CI leaves it to this script.
# Usage: scripts/sanitize.sh [ctest arguments...]
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh build-asan RelWithDebInfo -DVIEWCELLS_SANITIZE=ON -DVIEWCELLS_BUILD_TESTS=ON
bash scripts/fetch-maps.sh
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
# Assimp leaks a little on some malformed files, inside the library (tests/fuzz/lsan.supp).
export LSAN_OPTIONS=suppressions=$PWD/tests/fuzz/lsan.supp:print_suppressions=0
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
cd build-asan
ctest --output-on-failure -j "$(nproc)" --timeout 1800 "$@"
