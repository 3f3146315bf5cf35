#!/usr/bin/env bash
# What the validated merge costs in time against what it gains (issue 15): on the office and
# the rotated office, the same construction samples and AV-S leaves merged four ways: greedy on
# the construction samples' PVSs (--merge-pvs samples, the old AV-M), and validated with two
# AGVS runs of 0.25x, 1x and 4x the construction samples each. Per run: the merge's seconds
# (leaf PVSs with AGVS, neighbour graph, merging with the choice of its start) and AV-M's
# evaluated cost and worst ratio to AV-S from 16 cells up. Writes docs/accuracy/merge.md and
# the section "merge" of docs/accuracy-vs-time.md.
# Usage: scripts/merge-vs-time.sh [SAMPLES] [CELLS]   (defaults 500000 and 2000)
# MERGE_REUSE=1 keeps runs already in out/bench/merge (to redo only the table).
set -euo pipefail
samples="${1:-500000}"
cells="${2:-2000}"
source "$(dirname "$0")/bench-setup.sh"
office=$(bench_scene office 4)
rotated=$(bench_scene rotated-office 4)
out="$dir/merge"
mkdir -p "$out" docs/accuracy
for scene in office rotated-office; do
  path=$office
  [ "$scene" = rotated-office ] && path=$rotated
  for mode in samples 0.25 1 4; do
    name="$scene-$mode"
    if [ "${MERGE_REUSE:-0}" = 1 ] && [ -f "$out/$name/summary.json" ]; then continue; fi
    if [ "$mode" = samples ]; then merge=(--merge-pvs samples)
    else merge=(--merge-samples "$(python3 -c "print(int($mode * $samples))")"); fi
    "$vc" compare "$path" --methods av-m,av-s,kd-casm --samples "$samples" --seed 1 --eval-seed 99 \
      --eval-sets 2 --max-cells "$cells" "${merge[@]}" -o "$out/$name" -q
  done
done
python3 scripts/vctables.py merge-vs-time "$out" "$samples" "$cells" > docs/accuracy/merge.md
echo "scripts/merge-vs-time.sh $samples $cells" > docs/accuracy/merge.command
python3 scripts/vctables.py replace-section docs/accuracy-vs-time.md merge "$(cat docs/accuracy/merge.command)" \
  docs/accuracy/merge.md
echo "merge-vs-time: docs/accuracy-vs-time.md (section merge)"
