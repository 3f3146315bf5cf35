#!/usr/bin/env bash
# As shipped, on OpenArena maps: what a player's frames draw and get wrong with q3map2's PVS
# (the map's own vis rows) and with ours (`viewcells bake`: AV-M view cells at q3map2's
# cluster count, PVSs by AGVS until its estimated pixel error is below PIXEL_ERROR per
# 1024x1024 frame or SECONDS have passed), both measured by `viewcells measure` with the same
# play cameras (5,000 player eyes above walkable floors reachable from the spawn points,
# 64x48 pixels, 90 degrees). Unless our compressed PVS lists at that count take more than 4 times
# the bytes of q3map2's rows, a second bake takes the most cells whose lists fit in the rows'
# bytes (`--memory ROWS --memory-of lists`: fewer cells than the clusters, or more where the
# lists leave room), measured the same way. Where neither bake meets the goal (cost at most half,
# median camera at most 1 wrong pixel, within the budget) counting q3map2's leaf surface lists
# with its rows, a third bake takes the most cells whose lists fit both. Every bake here weighs
# cells by all of the map's non-solid space (--no-play-space); bake's default on a map, the play
# space, is measured by scripts/maps-shipped-leaf.sh 1 45 --play-space all. Writes docs/results/q3-shipped.md
# and .csv and the section "q3shipped" of docs/results.md.
# Usage: scripts/maps-shipped.sh [PIXEL_ERROR] [SECONDS] [MAP_NAME...]   (defaults 1, 300, every map)
# SHIPPED_REUSE=1 keeps maps already measured in out/shipped (to redo only the tables).
# SHIPPED_RECODE=1 keeps the bakes at the cluster count in out/shipped, rewrites them in the
# current .pvs format (`viewcells recode`: the same cells and PVSs), measures them again and
# redoes the bakes that fit q3map2's rows (for a change of the list coding alone).
set -euo pipefail
err="${1:-1}"
secs="${2:-300}"
shift $(($# < 2 ? $# : 2))
source "$(dirname "$0")/shipped-setup.sh"
out=out/shipped
mkdir -p "$out" docs/results
if [ $# -gt 0 ]; then
  maps=()
  for n in "$@"; do maps+=("data/maps/bsp/$n.bsp"); done
else
  maps=(data/maps/bsp/*.bsp)
fi
# fit_rows MAP DIR: the most cells whose lists fit q3map2's rows. Nothing when done before, or
# when our lists at the cluster count take more than 4 times the rows' bytes (the few cells
# whose lists would fit are no comparison).
fit_rows() {
  local rows lists
  rows=$(python3 scripts/vctables.py get "$2/q3map2.json" pvs_bytes)
  lists=$(python3 scripts/vctables.py get "$2/ours.json" pvs_bytes)
  [ "$lists" -gt $((4 * rows)) ] || shipped_fit "$1" "$2" "$rows" fit "q3map2's rows" --no-play-space
}
# fit_leaf MAP DIR: where neither bake so far meets the goal within q3map2's rows and leaf
# surface lists (what it stores to go from a cluster to its surfaces), the most cells whose
# lists fit those bytes (within 4 times them, as above).
fit_leaf() {
  local budget lists
  budget=$(python3 scripts/vctables.py shipped-budget "$2")
  lists=$(python3 scripts/vctables.py get "$2/ours.json" pvs_bytes)
  [ "$(python3 scripts/vctables.py shipped-met "$2" "$budget")" = no ] && [ "$lists" -le $((4 * budget)) ] &&
    shipped_fit "$1" "$2" "$budget" fit-leaf "q3map2's rows and leaf surface lists" --no-play-space
  return 0
}
fits() { fit_rows "$1" "$2"; fit_leaf "$1" "$2"; }
i=0
for map in "${maps[@]}"; do
  i=$((i + 1))
  name=$(basename "$map" .bsp)
  d="$out/$name"
  if [ "${SHIPPED_RECODE:-0}" = 1 ] && [ -f "$d/ours.pvs" ]; then
    "$vc" recode "$d/ours.pvs" -o "$d/recoded.pvs" -q 2>> "$d/err" && mv "$d/recoded.pvs" "$d/ours.pvs"
    "$vc" measure "$map" "$d/ours.pvs" --count 5000 --width 64 --height 48 --report "$d/ours.json" -q 2>> "$d/err"
    rm -f "$d"/fit*.pvs "$d"/fit*.json
    echo "shipped: [$i/${#maps[@]}] $name: recoded, lists $(python3 scripts/vctables.py get "$d/ours.json" pvs_bytes) bytes"
    fits "$map" "$d"
    continue
  fi
  if [ "${SHIPPED_REUSE:-0}" = 1 ] && { [ -f "$d/ours.json" ] || [ -f "$d.skipped" ]; }; then
    [ -f "$d/ours.json" ] && fits "$map" "$d"
    continue
  fi
  rm -rf "$d" "$d.skipped" "$d.failed"
  mkdir -p "$d"
  "$vc" info "$map" --json "$d/info.json" >/dev/null
  clusters=$(python3 scripts/vctables.py get "$d/info.json" quake3 clusters)
  if [ "$clusters" = 0 ]; then
    echo "no visibility data" > "$d.skipped"
    echo "shipped: [$i/${#maps[@]}] $name: no visibility data, skipped"
    continue
  fi
  if "$vc" measure "$map" --count 5000 --width 64 --height 48 --report "$d/q3map2.json" -q 2> "$d/err" &&
     start=$(date +%s.%N) &&
     "$vc" bake "$map" --cells "$clusters" --pixel-error "$err" --agvs-time "$secs" --seed 1 --no-play-space -o "$d/ours.pvs" \
       --report "$d/bake.json" -q 2>> "$d/err" &&
     python3 scripts/vctables.py elapsed "$start" > "$d/bake_wall_seconds" &&
     "$vc" measure "$map" "$d/ours.pvs" --count 5000 --width 64 --height 48 --report "$d/ours.json" -q 2>> "$d/err"; then
    echo "shipped: [$i/${#maps[@]}] $name: $clusters clusters, bake $(cat "$d/bake_wall_seconds") s"
    fits "$map" "$d"
  else
    cp "$d/err" "$d.failed"
    echo "shipped: [$i/${#maps[@]}] $name: FAILED ($(tail -1 "$d/err"))"
  fi
done

python3 scripts/vctables.py shipped "$out" "$err" "$secs"
recode=""
[ "${SHIPPED_RECODE:-0}" = 1 ] && recode="SHIPPED_RECODE=1 "
echo "${recode}scripts/maps-shipped.sh $err $secs $*" | sed 's/ *$//' > docs/results/q3-shipped.command
python3 scripts/vctables.py replace-section docs/results.md q3shipped "$(cat docs/results/q3-shipped.command)" \
  docs/results/q3-shipped.md
echo "shipped: docs/results.md (section q3shipped), docs/results/q3-shipped.csv"
