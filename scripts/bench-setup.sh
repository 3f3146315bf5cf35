# Sourced by the benchmark scripts: dependencies, a Release build, where outputs go, and the
# generated scenes they share. Set bench_cmake_args before sourcing for extra CMake options.
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash scripts/install-deps.sh >/dev/null
# shellcheck disable=SC2086
bash scripts/build.sh build-release Release -DVIEWCELLS_BUILD_TESTS=OFF ${bench_cmake_args:-}
vc=build-release/cli/viewcells
dir=out/bench
mkdir -p "$dir"
# bench_scene KIND SIZE: generates out/bench/KINDSIZE.obj once (seed 1) and prints its path.
bench_scene() {
  local path="$dir/$1$2.obj"
  [ -f "$path" ] || "$vc" generate "$1" --size "$2" --seed 1 -o "$path" -q
  echo "$path"
}
