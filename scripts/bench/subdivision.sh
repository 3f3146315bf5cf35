# Subdivision benchmark: the generated city (>= 1M triangles), segments to 50k cells, time per
# phase, with the default (fast) candidate positions and with --exact-candidates (the paper's
# choice), each size run with both in turn so that their ratio is measured in one run; how the
# subdivision time grows with 0.5M, 1M, 1.5M, 2M segments; and one compare at 1.5M segments
# that scores both subdivisions on independent evaluation samples at 1k, 10k and 50k cells; and
# the glass city (see-through surfaces) at 1.5M segments both ways; and, on oa_shouse (a Quake 3
# map with much water and glass), build both ways, time per candidate against the city's by
# medians of alternating runs (RATIO_RUNS, default 5), and compare with its defaults (peak memory).
# The stagnation stop is switched off (--min-reduction 0) so that every run reaches CELLS.
# Rewrites the subdivision section of BENCHMARKS.md. Usage: scripts/bench.sh subdivision [SIZE] [CELLS]
size="${1:-23}"
cells="${2:-50000}"
source scripts/bench-setup.sh
scene=$(bench_scene city "$size")
# peak KB FILE COMMAND...: runs COMMAND, writing its peak resident memory (KB) to FILE when
# GNU time is there.
peak() {
  local file="$1"; shift
  if [ -x /usr/bin/time ]; then /usr/bin/time -f %M -o "$file" "$@"; else rm -f "$file"; "$@"; fi
}
for n in 500000 1000000 1500000 2000000; do
  peak "$dir/build-$n.kb" "$vc" build "$scene" --segments "$n" --max-cells "$cells" --min-reduction 0 --seed 1 -q \
    --no-merge --report "$dir/build-$n.json"
  peak "$dir/build-exact-$n.kb" "$vc" build "$scene" --segments "$n" --max-cells "$cells" --min-reduction 0 --seed 1 \
    -q --no-merge --exact-candidates --report "$dir/build-exact-$n.json"
done
# The see-through path: the glass city (curtain walls, pools of water), whose crossings add a
# segment each, at 1.5M segments, both ways.
glass=$(bench_scene glass-city "$size")
peak "$dir/build-glass.kb" "$vc" build "$glass" --segments 1500000 --max-cells "$cells" --min-reduction 0 --seed 1 -q \
  --no-merge --report "$dir/build-glass.json"
peak "$dir/build-glass-exact.kb" "$vc" build "$glass" --segments 1500000 --max-cells "$cells" --min-reduction 0 \
  --seed 1 -q --no-merge --exact-candidates --report "$dir/build-glass-exact.json"
# A Quake 3 map with much water and glass whose walls are not axis-aligned (geometry-aligned
# candidates on): the path that was slowest per candidate, both ways.
map=data/maps/bsp/oa_shouse.bsp
rm -f "$dir"/ratio-city-*.json "$dir"/ratio-map-*.json  # an earlier run's, which the table would read
if [ -f "$map" ]; then
  peak "$dir/build-map.kb" "$vc" build "$map" --samples 300000 --max-cells 1500 --seed 1 -q --no-merge \
    --report "$dir/build-map.json"
  peak "$dir/build-map-exact.kb" "$vc" build "$map" --samples 300000 --max-cells 1500 --seed 1 -q --no-merge \
    --exact-candidates --report "$dir/build-map-exact.json"
  # Time per candidate, map against city, in one sitting: the map's subdivision is under a second,
  # so one run of it moves with this machine's speed from minute to minute; RATIO_RUNS alternating
  # runs of the city at 1.5M segments (fast), the map, and the map without geometry-aligned
  # planes, compared by medians.
  for r in $(seq "${RATIO_RUNS:-5}"); do
    "$vc" build "$scene" --segments 1500000 --max-cells "$cells" --min-reduction 0 --seed 1 -q --no-merge \
      --report "$dir/ratio-city-$r.json"
    "$vc" build "$map" --samples 300000 --max-cells 1500 --seed 1 -q --no-merge --report "$dir/ratio-map-$r.json"
    "$vc" build "$map" --samples 300000 --max-cells 1500 --seed 1 -q --no-merge --no-ga \
      --report "$dir/ratio-map-noga-$r.json"
  done
  # compare on it with every default (its methods, samples and cell count): time and peak memory.
  rm -rf "$dir/compare-map"
  peak "$dir/compare-map.kb" "$vc" compare "$map" --seed 1 -q -o "$dir/compare-map"
fi
"$vc" compare "$scene" --segments 1500000 --max-cells "$cells" --min-reduction 0 --methods av-s,av-s-exact --seed 1 -q \
  -o "$dir/compare-candidates"
python3 scripts/vctables.py subdivision "$dir" "$size" "$cells" > "$dir/subdivision-table.md"
python3 scripts/vctables.py replace-section BENCHMARKS.md subdivision "scripts/bench.sh subdivision $size $cells" "$dir/subdivision-table.md"
cat "$dir/subdivision-table.md"
