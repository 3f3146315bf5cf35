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
# bench_city_cells SAMPLES CELLS: the merge history the AGVS scaling benchmarks share, of at most
# CELLS AV-S cells of the city of size 23 (seed 1) from SAMPLES construction samples, merged on
# the samples' PVSs; built once into out/bench/city23-CELLS.vcells, whose path it prints.
bench_city_cells() {
  local path="$dir/city23-$2.vcells"
  [ -f "$path" ] || "$vc" -q build "$(bench_scene city 23)" --samples "$1" --max-cells "$2" --merge-pvs samples \
    --seed 1 -o "$path"
  echo "$path"
}
# bench_level SCENE CELLS OUT: the view cells the PVS benchmarks share, a merge history of AV-S
# cells (500,000 construction samples, 4 x CELLS cells, seed 1), written to OUT/level.vcells.
bench_level() {
  mkdir -p "$3"
  "$vc" build "$1" --samples 500000 --max-cells $((4 * $2)) --seed 1 -q -o "$3/level.vcells"
}
# bench_old_build COMMIT: builds COMMIT (Release, the viewcells executable) in a git worktree
# under out/ab/ once, and prints the executable's path.
bench_old_build() {
  local sha tree
  sha=$(git rev-parse --short "$1")
  tree="out/ab/$sha"
  if [ ! -x "$tree/b/cli/viewcells" ]; then
    rm -rf "$tree"
    git worktree prune
    git worktree add -f "$tree" "$sha" >/dev/null
    cmake -S "$tree" -B "$tree/b" -G Ninja -DCMAKE_BUILD_TYPE=Release -DVIEWCELLS_BUILD_TESTS=OFF >/dev/null
    cmake --build "$tree/b" -j "$(nproc)" --target viewcells >/dev/null
  fi
  echo "$tree/b/cli/viewcells"
}
# bench_ab_binaries COMMIT: sets sha (COMMIT, short) and bin[old] / bin[new] (that commit's
# executable, built by bench_old_build, and the current tree's), for the A/B scripts.
bench_ab_binaries() {
  sha=$(git rev-parse --short "$1")
  declare -gA bin=([old]="$(bench_old_build "$sha")" [new]="$vc")
}
