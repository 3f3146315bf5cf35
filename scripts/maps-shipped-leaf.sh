#!/usr/bin/env bash
# The maps of docs/results/q3-shipped.csv that miss the shipped goal against q3map2's rows and
# leaf surface lists (what q3map2 stores to go from a cluster to the surfaces it draws), baked
# again as maps-shipped.sh now does itself: the most cells whose compressed PVS lists fit those
# bytes (`viewcells bake MAP --memory ROWS+LEAF_LISTS --memory-of lists`), measured by the same
# play cameras. For a table made before maps-shipped.sh made that bake: the table's other bakes
# stay as they are. Writes docs/results/q3-shipped-leaf.md and .csv and the section
# "q3shippedleaf" of docs/results.md.
# Usage: scripts/maps-shipped-leaf.sh [PIXEL_ERROR] [SECONDS]   (defaults 1, 45: the table's)
set -euo pipefail
err="${1:-1}"
secs="${2:-45}"
source "$(dirname "$0")/shipped-setup.sh"
out=out/shipped-leaf
table=docs/results/q3-shipped.csv
mkdir -p "$out"
mapfile -t names < <(python3 scripts/vctables.py shipped-misses "$table")
i=0
for name in "${names[@]}"; do
  i=$((i + 1))
  map="data/maps/bsp/$name.bsp"
  d="$out/$name"
  mkdir -p "$d"
  [ -f "$d/q3map2.json" ] || "$vc" measure "$map" --report "$d/q3map2.json" -q 2> "$d/err"
  budget=$(python3 scripts/vctables.py shipped-budget "$d")
  echo "shipped-leaf: [$i/${#names[@]}] $name: within $budget bytes"
  shipped_fit "$map" "$d" "$budget" fit-leaf "q3map2's rows and leaf surface lists"
done
python3 scripts/vctables.py shipped-leaf "$out" "$table" "$err" "$secs"
echo "scripts/maps-shipped-leaf.sh $err $secs" > docs/results/q3-shipped-leaf.command
python3 scripts/vctables.py replace-section docs/results.md q3shippedleaf "$(cat docs/results/q3-shipped-leaf.command)" \
  docs/results/q3-shipped-leaf.md
echo "shipped-leaf: docs/results.md (section q3shippedleaf), docs/results/q3-shipped-leaf.csv"
