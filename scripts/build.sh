#!/usr/bin/env bash
# Configures and builds viewcells. Usage: scripts/build.sh [BUILD_DIR] [BUILD_TYPE] [extra cmake args...]
# Defaults: build/ and Release. Uses Ninja when available.
set -euo pipefail
cd "$(dirname "$0")/.."
dir="${1:-build}"
type="${2:-Release}"
shift $(( $# > 2 ? 2 : $# ))
gen=()
if command -v ninja >/dev/null 2>&1; then gen=(-G Ninja); fi
# Reuse an existing build directory only if it was configured with the same generator.
if [ -f "$dir/CMakeCache.txt" ] && ! grep -q "CMAKE_GENERATOR:INTERNAL=${gen[1]:-Unix Makefiles}" "$dir/CMakeCache.txt"; then
  rm -rf "$dir"
fi
cmake -S . -B "$dir" "${gen[@]}" -DCMAKE_BUILD_TYPE="$type" "$@" >/dev/null
cmake --build "$dir" -j "$(nproc)"
