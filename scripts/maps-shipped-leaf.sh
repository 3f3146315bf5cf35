#!/usr/bin/env bash
# The maps of docs/results/q3-shipped.csv that miss the shipped goal against q3map2's rows and
# leaf surface lists (what q3map2 stores to go from a cluster to the surfaces it draws), baked
# again as maps-shipped.sh now does itself: the most cells whose compressed PVS lists fit those
# bytes (`viewcells bake MAP --memory ROWS+LEAF_LISTS --memory-of lists`), measured by the same
# play cameras. For a table made before maps-shipped.sh made that bake: the table's other bakes
# stay as they are. Writes docs/results/q3-shipped-leaf.md and .csv and the section
# "q3shippedleaf" of docs/results.md.
# With --play-space: the maps that still miss after that bake, baked the same way with
# `--play-space` (cells weighed, and AGVS's points drawn, where a player's eye can be), to
# docs/results/q3-shipped-play.md and .csv and the section "q3shippedplay".
# With --play-space and map names: those maps instead (maps that met the goal without it, to
# see what it does to them), to docs/results/q3-shipped-play-check.md and .csv and the section
# "q3shippedplaycheck". With --play-space all: every map of the table, in one run, to
# docs/results/q3-shipped-play-all.md and .csv and the section "q3shippedplayall" (one bake
# setting on every map: what BENCHMARKS.md leads with; --play-space is bake's default on a map
# now, and is passed anyway). Without --play-space, the bakes pass --no-play-space (all of the
# map's non-solid space, as the table it extends).
# Usage: scripts/maps-shipped-leaf.sh [PIXEL_ERROR] [SECONDS] [--play-space [all | MAP_NAME...]]   (defaults 1, 45: the table's)
set -euo pipefail
err="${1:-1}"
secs="${2:-45}"
play="${3:-}"
shift $(($# < 3 ? $# : 3))
source "$(dirname "$0")/shipped-setup.sh"
table=docs/results/q3-shipped.csv
if [ "$play" = --play-space ] && [ "${1:-}" = all ]; then
  kind=play-all out=out/shipped-play-all bake=fit-play flags=(--play-space)
  mapfile -t names < <(python3 -c 'import csv, sys; [print(r["map"]) for r in csv.DictReader(open(sys.argv[1]))]' "$table")
elif [ "$play" = --play-space ] && [ $# -gt 0 ]; then
  kind=play-check out=out/shipped-play bake=fit-play flags=(--play-space)
  names=("$@")
elif [ "$play" = --play-space ]; then
  kind=play out=out/shipped-play bake=fit-play flags=(--play-space)
  mapfile -t names < <(python3 scripts/vctables.py shipped-misses "$table" docs/results/q3-shipped-leaf.csv)
elif [ -z "$play" ]; then
  kind=leaf out=out/shipped-leaf bake=fit-leaf flags=(--no-play-space)
  mapfile -t names < <(python3 scripts/vctables.py shipped-misses "$table")
else
  echo "maps-shipped-leaf.sh: the third argument is --play-space or nothing (got $play)" >&2
  exit 2
fi
mkdir -p "$out"
i=0
for name in "${names[@]}"; do
  i=$((i + 1))
  map="data/maps/bsp/$name.bsp"
  d="$out/$name"
  mkdir -p "$d"
  [ -f "$d/q3map2.json" ] || "$vc" measure "$map" --count 5000 --width 64 --height 48 --report "$d/q3map2.json" -q 2> "$d/err"
  budget=$(python3 scripts/vctables.py shipped-budget "$d")
  echo "shipped-leaf: [$i/${#names[@]}] $name: within $budget bytes"
  shipped_fit "$map" "$d" "$budget" "$bake" "q3map2's rows and leaf surface lists" "${flags[@]}"
done
python3 scripts/vctables.py shipped-leaf "$out" "$table" "$err" "$secs" $play "$@"
echo "scripts/maps-shipped-leaf.sh $err $secs $play $*" | sed 's/ *$//' > "docs/results/q3-shipped-$kind.command"
python3 scripts/vctables.py replace-section docs/results.md "q3shipped${kind//-/}" "$(cat "docs/results/q3-shipped-$kind.command")" \
  "docs/results/q3-shipped-$kind.md"
echo "shipped-leaf: docs/results.md (section q3shipped${kind//-/}), docs/results/q3-shipped-$kind.csv"
