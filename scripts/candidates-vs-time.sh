#!/usr/bin/env bash
# What the subdivision's fast candidate positions cost in accuracy against the paper's exact
# choice (--exact-candidates), and what the number of positions per axis (--axis-candidates,
# the knob) buys: on the office, the rotated office, the city and oa_dm2, each compare run builds
# AV-S both ways from the same construction samples and scores both on the same independent
# evaluation samples. Per run: each way's subdivision seconds and evaluated cost. Writes
# docs/accuracy/candidates.md, docs/accuracy/candidates.png and the section "candidates" of
# docs/accuracy-vs-time.md.
# Usage: scripts/candidates-vs-time.sh [SAMPLES] [CELLS] [CITY_SIZE]   (defaults 1000000, 2000, 23)
# CANDIDATES_REUSE=1 keeps runs already in out/bench/candidates (to redo only the table).
set -euo pipefail
samples="${1:-1000000}"
cells="${2:-2000}"
size="${3:-23}"
source "$(dirname "$0")/bench-setup.sh"
out="$dir/candidates"
mkdir -p "$out" docs/accuracy
scenes=("office:$(bench_scene office 4)" "rotated-office:$(bench_scene rotated-office 4)" "city:$(bench_scene city "$size")")
map=data/maps/bsp/oa_dm2.bsp
if [ -f "$map" ]; then scenes+=("oa_dm2:$map"); else echo "candidates-vs-time: $map missing (scripts/fetch-maps.sh); skipped" >&2; fi
for entry in "${scenes[@]}"; do
  name="${entry%%:*}"
  path="${entry#*:}"
  for k in 25 50 100 200 400; do
    run="$name-$k"
    if [ "${CANDIDATES_REUSE:-0}" = 1 ] && [ -f "$out/$run/summary.json" ]; then continue; fi
    "$vc" compare "$path" --methods av-s,av-s-exact --samples "$samples" --seed 1 --eval-seed 99 --max-cells "$cells" \
      --axis-candidates "$k" -o "$out/$run" -q
  done
done
python3 scripts/vctables.py candidates "$out" "$samples" "$cells" > docs/accuracy/candidates.md
python3 scripts/vctables.py candidates-dat "$out" > "$out/candidates.dat"
gnuplot <<GP
set terminal pngcairo size 1000,640 font ",11" noenhanced
set output "docs/accuracy/candidates.png"
set title "AV-S to $cells cells: subdivision seconds (lines) and evaluated cost, fast / exact at k = 200 (points)"
set logscale x; set grid; set key below maxcols 4
set xlabel "axis-aligned positions per axis and cell (--axis-candidates)"
set ylabel "subdivision seconds"; set y2label "evaluated cost, fast / exact (k = 200)"
set ytics nomirror; set y2tics
plot for [s in "office rotated-office city oa_dm2"] "$out/candidates.dat" using 2:(strcol(1) eq s ? \$3 : NaN) with linespoints lw 2 title s." fast, s", \
     for [s in "office rotated-office city oa_dm2"] "$out/candidates.dat" using 2:(strcol(1) eq s ? \$4 : NaN) with linespoints dt 2 title s." exact, s", \
     for [s in "office rotated-office city oa_dm2"] "$out/candidates.dat" using 2:(strcol(1) eq s ? \$5 : NaN) axes x1y2 with points pt 7 title s." fast cost / exact (200)"
GP
echo "scripts/candidates-vs-time.sh $samples $cells $size" > docs/accuracy/candidates.command
python3 scripts/vctables.py replace-section docs/accuracy-vs-time.md candidates "$(cat docs/accuracy/candidates.command)" \
  docs/accuracy/candidates.md
echo "candidates-vs-time: docs/accuracy-vs-time.md (section candidates)"
