#!/usr/bin/env bash
# What accuracy costs in time (the users' question; the paper's figure 6, table 1, figure 11):
#  1. construction samples (50k, 200k, 1M, 2M) against build time and evaluated cost;
#  2. axis-aligned candidates only against geometry-aligned ones too (rotated office);
#  3. candidate limits (axis positions per axis, geometry-aligned planes per cell);
#  4. Embree robust against fast mode: speed, and rays leaking through edges and vertices
#     counted against the watertight brute-force caster.
# Sections 5 (merging) and 6 (subdivision candidates) come from scripts/merge-vs-time.sh and
# scripts/candidates-vs-time.sh and hold measurements written beside their tables; this script
# keeps them as they are.
# Writes docs/accuracy-vs-time.md and its plots in docs/accuracy/.
# Usage: scripts/accuracy-vs-time.sh [CELLS] [CITY_SIZE]
set -euo pipefail
cells="${1:-2000}"
size="${2:-23}"
bench_cmake_args="-DVIEWCELLS_BUILD_BENCH=ON"
source "$(dirname "$0")/bench-setup.sh"
office=$(bench_scene office 4)
rotated=$(bench_scene rotated-office 4)
city=$(bench_scene city "$size")
small_city=$(bench_scene city 3)
out="$dir/accuracy"
# ACCURACY_REUSE=1 keeps runs already in out/bench/accuracy (to redo only the tables and plots).
run() {  # run NAME ARGS...: viewcells compare ARGS -o $out/NAME, unless reused
  local name="$1"
  shift
  if [ "${ACCURACY_REUSE:-0}" = 1 ] && [ -f "$out/$name/summary.json" ]; then return; fi
  "$vc" compare "$@" -o "$out/$name" -q
}
mkdir -p "$out" docs/accuracy

# 1. Construction samples; the same 8M (office) / 4M (city) evaluation samples for all.
for scene in office city; do
  path=$office; eval_samples=8000000
  [ "$scene" = city ] && path=$city && eval_samples=4000000
  for n in 50000 200000 1000000 2000000; do
    run "samples-$scene-$n" "$path" --methods av-s --samples "$n" --seed 1 --eval-samples "$eval_samples" \
      --eval-seed 99 --max-cells "$cells"
  done
done
# 2. and 3. on the rotated office: geometry-aligned candidates, and the candidate limits.
run ga-off "$rotated" --methods av-s,av-m --samples 1000000 --seed 1 --eval-seed 99 --max-cells "$cells" --no-ga
for ga in 50 150 400; do
  run "ga-$ga" "$rotated" --methods av-s --samples 1000000 --seed 1 --eval-seed 99 --max-cells "$cells" \
    --ga-candidates "$ga"
done
run ga-150-avm "$rotated" --methods av-m --samples 1000000 --seed 1 --eval-seed 99 --max-cells "$cells"
for ax in 50 800; do
  run "axis-$ax" "$rotated" --methods av-s --samples 1000000 --seed 1 --eval-seed 99 --max-cells "$cells" \
    --axis-candidates "$ax"
done
# 4. Robust versus fast ray casting.
[ "${ACCURACY_REUSE:-0}" = 1 ] && [ -f "$out/leaks.json" ] ||
  build-release/bench/viewcells_leaks "$small_city" "$city" 50000 4000000 "$out/leaks.json" >/dev/null

# Sections 1-4 are this script's. Sections 5 and 6 are scripts/merge-vs-time.sh's and
# scripts/candidates-vs-time.sh's tables with the measurements written beside them: kept as they
# are (their tables refreshed from what those scripts last wrote). The new file replaces the old
# one only once it is whole.
doc=docs/accuracy-vs-time.md
new="$doc.new"
python3 scripts/vctables.py accuracy "$out" "$cells" "$size" > "$new"
if [ -f "$doc" ] && grep -q '^## 5\. ' "$doc"; then
  printf '\n' >> "$new"
  sed -n '/^## 5\. /,$p' "$doc" >> "$new"
else
  printf '\n## 5. Merging: what the validated merge costs and gains\n\n<!-- merge:begin -->\nNot generated yet: run scripts/merge-vs-time.sh.\n<!-- merge:end -->\n' >> "$new"
  printf '\n## 6. Subdivision candidates: fast against exact, and positions per axis\n\n<!-- candidates:begin -->\nNot generated yet: run scripts/candidates-vs-time.sh.\n<!-- candidates:end -->\n' >> "$new"
fi
if [ -f docs/accuracy/merge.md ] && [ -f docs/accuracy/merge.command ]; then
  python3 scripts/vctables.py replace-section "$new" merge "$(cat docs/accuracy/merge.command)" docs/accuracy/merge.md
fi
if [ -f docs/accuracy/candidates.md ] && [ -f docs/accuracy/candidates.command ]; then
  python3 scripts/vctables.py replace-section "$new" candidates "$(cat docs/accuracy/candidates.command)" \
    docs/accuracy/candidates.md
fi
mv "$new" "$doc"

# Plots: evaluated cost against cells per construction sample count; AA / AA+GA ratio.
for scene in office city; do
  python3 scripts/vctables.py accuracy-samples-dat "$out" "$scene" > "$out/samples-$scene.dat"
  gnuplot <<GP
set terminal pngcairo size 800,520 font ",11"
set output "docs/accuracy/samples-$scene.png"
set title "$scene: evaluated cost of AV-S built from N samples"
set logscale x; set grid; set key top right
set xlabel "view cells"; set ylabel "evaluated render cost"
plot for [i=2:5] "$out/samples-$scene.dat" using 1:i with lines lw 2 title columnheader(i)
GP
done
python3 scripts/vctables.py ga-ratio-dat "$out" > "$out/ga-ratio.dat"
gnuplot <<GP
set terminal pngcairo size 800,520 font ",11"
set output "docs/accuracy/ga-ratio.png"
set title "rotated office: cost with axis-aligned candidates only / with geometry-aligned too"
set logscale x; set grid; unset key
set xlabel "view cells"; set ylabel "cost ratio AA / AA+GA"
plot "$out/ga-ratio.dat" using 1:2 with linespoints pt 7 ps 0.5
GP
echo "accuracy-vs-time: docs/accuracy-vs-time.md"
