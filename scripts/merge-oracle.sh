#!/usr/bin/env bash
# How low can a merge of AV-S's leaves go at a few cells, at best? bench/merge_oracle.cpp on the
# office (size 4) and the town at street level (size 23, eye heights 0.5-4 m), each from 1M
# construction samples to 5,000 cells as docs/results.md builds them: the leaves are merged and
# refined on the PVSs of evaluation set 1 itself (FIT samples), and every cell set is scored on
# set 1 and on an independent set 2 (SCORE samples). Run once with FIT = SCORE (the cells fitted
# to the evaluator's own samples) and once with FIT = 2M (about what a build draws besides its
# construction samples). Writes out/bench/merge-oracle.md (the tables in
# docs/accuracy-vs-time.md, "How far merging can go at a few cells").
# Usage: scripts/merge-oracle.sh [SCORE_SAMPLES] [FIT_SAMPLES_SMALL]
set -euo pipefail
score="${1:-16000000}"
small="${2:-2000000}"
bench_cmake_args="-DVIEWCELLS_BUILD_BENCH=ON"
source "$(dirname "$0")/bench-setup.sh"
office=$(bench_scene office 4)
town=$(bench_scene town 23)
oracle=build-release/bench/viewcells_merge_oracle
out="$dir/merge-oracle.md"
{
  echo "Command: \`scripts/merge-oracle.sh $score $small\`"
  for fit in "$score" "$small"; do
    echo
    echo "Office, fitted on $fit samples, scored on $score:"
    echo
    "$oracle" "$office" 1000000 5000 "$fit" 11,16,23,31,64 - "$score" | tail -n +2
    echo
    echo "Town at street level, fitted on $fit samples, scored on $score:"
    echo
    "$oracle" "$town" 1000000 5000 "$fit" 16,28,31,34,38 "0,0,0.5,1764,1764,4" "$score" | tail -n +2
  done
} | tee "$out"
