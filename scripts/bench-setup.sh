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
# KIND may end in -sealed (e.g. office-sealed): the generator's --sealed variant.
bench_scene() {
  local path="$dir/$1$2.obj" kind="${1%-sealed}" sealed=()
  [ "$kind" != "$1" ] && sealed=(--sealed)
  [ -f "$path" ] || "$vc" generate "$kind" "${sealed[@]}" --size "$2" --seed 1 -o "$path" -q
  echo "$path"
}
