#!/usr/bin/env bash
# Our view cells against q3map2's on every OpenArena map that carries visibility data: for
# each map, `viewcells compare MAP --methods av-m,av-s,q3-clusters` (AV-S to 3x the map's clusters,
# merged; q3map2's clusters scored on the same evaluation samples over the map's non-solid
# space). Writes docs/results/q3-maps.md, docs/results/q3-maps.csv and the section "Quake 3
# maps" of docs/results.md.
# Usage: scripts/maps-table.sh [SAMPLES] [EVAL_SAMPLES]   (defaults 500000 and 4 x SAMPLES)
# MAPS_REUSE=1 keeps comparisons already in out/maps (to redo only the tables).
set -euo pipefail
samples="${1:-500000}"
eval_samples="${2:-$((4 * samples))}"
source "$(dirname "$0")/bench-setup.sh"
bash scripts/fetch-maps.sh >/dev/null
out=out/maps
mkdir -p "$out" docs/results
maps=(data/maps/bsp/*.bsp)
i=0
for map in "${maps[@]}"; do
  i=$((i + 1))
  name=$(basename "$map" .bsp)
  if [ "${MAPS_REUSE:-0}" = 1 ] && { [ -f "$out/$name/summary.json" ] || [ -f "$out/$name.skipped" ]; }; then continue; fi
  rm -f "$out/$name.skipped" "$out/$name.failed"
  "$vc" info "$map" --json "$out/$name.info.json" >/dev/null
  clusters=$(python3 scripts/vctables.py get "$out/$name.info.json" quake3 clusters)
  if [ "$clusters" = 0 ]; then
    echo "no visibility data" > "$out/$name.skipped"
    echo "maps: [$i/${#maps[@]}] $name: no visibility data, skipped"
    continue
  fi
  start=$(date +%s.%N)
  if "$vc" compare "$map" --samples "$samples" --eval-samples "$eval_samples" --eval-sets 2 --seed 1 \
      --methods av-m,av-s,q3-clusters -o "$out/$name" -q 2> "$out/$name.err"; then
    python3 scripts/vctables.py elapsed "$start" > "$out/$name/wall_seconds"
    echo "maps: [$i/${#maps[@]}] $name: $clusters clusters, $(cat "$out/$name/wall_seconds") s"
  else
    cp "$out/$name.err" "$out/$name.failed"
    echo "maps: [$i/${#maps[@]}] $name: FAILED ($(tail -1 "$out/$name.err"))"
  fi
done

python3 scripts/vctables.py maps "$out" "$samples" "$eval_samples"
echo "scripts/maps-table.sh $samples $eval_samples" > docs/results/q3-maps.command
python3 scripts/vctables.py replace-section docs/results.md q3maps "$(cat docs/results/q3-maps.command)" docs/results/q3-maps.md
echo "maps: docs/results.md (section q3maps), docs/results/q3-maps.csv"
