#!/usr/bin/env bash
# AGVS, SGVS and REF judged by the pixels they get right: each computes the PVSs of the same
# view cells for SECONDS, and is measured part-way (`pvs --measure-at`, log-spaced sample
# counts) by the same cameras: 5,000 of 32x32 pixels, 90 degrees; on a map, player eyes above
# floors reachable from the spawn points (`measure`'s play cameras), elsewhere random points of
# the view box looking anywhere. From the curves of measured error against the solver's time,
# the time each method needs to reach a given error, and AGVS's speed-ups. Scenes: the office
# of size 4 and the city of size 5 (500 cells, as scripts/bench.sh agvs), and three OpenArena
# maps at their q3map2 cluster counts. Writes docs/agvs/measured-*.png and the section
# "agvs-measured" of BENCHMARKS.md.
# Usage: scripts/agvs-measured.sh [SECONDS]   (default 60)
set -euo pipefail
seconds="${1:-60}"
source "$(dirname "$0")/bench-setup.sh"
bash scripts/fetch-maps.sh >/dev/null
out="$dir/agvs-measured"
mkdir -p "$out" docs/agvs
at=""
for k in $(seq 0 24); do at="$at $((10000 << k))"; done
run_scene() {  # NAME SCENE CELLS
  local name="$1" scene="$2" cells="$3" d="$out/$1"
  mkdir -p "$d"
  "$vc" build "$scene" --samples 500000 --max-cells $((4 * cells)) --seed 1 -q -o "$d/level.vcells"
  for m in agvs sgvs ref; do
    # shellcheck disable=SC2086
    "$vc" pvs "$d/level.vcells" --scene "$scene" --cells "$cells" --time "$seconds" --method "$m" --seed 1 -q \
      --measure-cameras 5000 --measure-size 32 --measure-at $at -o "$d/$m.pvs" --report "$d/$m.json"
  done
  echo "agvs-measured: $name done"
}
run_scene office4 "$(bench_scene office 4)" 500
run_scene city5 "$(bench_scene city 5)" 500
for map in oa_dm2 oa_shouse aggressor; do
  "$vc" info "data/maps/bsp/$map.bsp" --json "$out/$map.info.json" >/dev/null
  run_scene "$map" "data/maps/bsp/$map.bsp" "$(python3 scripts/vctables.py get "$out/$map.info.json" quake3 clusters)"
done
python3 scripts/vctables.py agvs-measured "$out" "$seconds" office4 city5 oa_dm2 oa_shouse aggressor > "$out/table.md"
for s in office4 city5 oa_dm2 oa_shouse aggressor; do
  gnuplot <<GP
set terminal pngcairo size 800,500
set output "docs/agvs/measured-$s.png"
set title "Measured pixel error (of 1024x1024) against time: $s"
set xlabel "seconds (the solver's own)"; set ylabel "wrong pixels per frame"; set logscale xy; set key top right
plot "$out/$s/agvs.dat" using 1:2 with linespoints lw 2 title "AGVS", "$out/$s/sgvs.dat" using 1:2 with linespoints lw 2 title "SGVS", "$out/$s/ref.dat" using 1:2 with linespoints lw 2 title "REF"
GP
done
python3 scripts/vctables.py replace-section BENCHMARKS.md agvs-measured "scripts/agvs-measured.sh $seconds" "$out/table.md"
cat "$out/table.md"
