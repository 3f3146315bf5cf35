#!/usr/bin/env bash
# The play space found from meshes against each map's own (issue 68): every map is converted to a
# glTF level (viewcells convert: rendered surfaces only, y-up metres) twice, with its spawn
# points as nodes named "spawn N" and without, and `viewcells play-space LEVEL --map MAP` measures
# how much of the map's play space (its eye band, 1-3 m above walkable floors, in the leaves a
# player reaches) the one found covers and how much it adds outside it.
# Usage: scripts/play-space-maps.sh [MAP...]   (default: all maps in data/maps/bsp)
# Env: VC (viewcells binary), OUT (out/play), POINTS (1000000).
# Halves: maps in alphabetical order, index i; tuning when i % 4 >= 2 (as docs/conservative.md).
set -euo pipefail
cd "$(dirname "$0")/.."
VC="${VC:-build/cli/viewcells}"
OUT="${OUT:-out/play}"
POINTS="${POINTS:-1000000}"
mkdir -p "$OUT"
all=($(ls data/maps/bsp/*.bsp | xargs -n1 basename | sed 's/\.bsp$//' | sort))
maps=("$@")
[ ${#maps[@]} -gt 0 ] || maps=("${all[@]}")
echo "| map | half | coverage, spawn nodes | adds, spawn nodes | coverage, no start points | adds, no start points |"
echo "| --- | --- | ---: | ---: | ---: | ---: |"
for m in "${maps[@]}"; do
  half=held-out
  for i in "${!all[@]}"; do [ "${all[$i]}" = "$m" ] && [ $((i % 4)) -ge 2 ] && half=tuning; done
  "$VC" convert "data/maps/bsp/$m.bsp" -o "$OUT/$m.glb" --start-points -q
  "$VC" convert "data/maps/bsp/$m.bsp" -o "$OUT/$m-nostart.glb" -q
  row="| $m | $half"
  for level in "$m" "$m-nostart"; do
    "$VC" play-space "$OUT/$level.glb" --map "data/maps/bsp/$m.bsp" --points "$POINTS" --report "$OUT/$level.json" -q
    row="$row | $(python3 -c "
import json; a = json.load(open('$OUT/$level.json'))['against_map']
print(f\"{100 * a['coverage']:.1f}% | {100 * a['excess']:.1f}%\")")"
  done
  echo "$row |"
done
