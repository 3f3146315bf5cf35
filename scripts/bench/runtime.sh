# The runtime reader for engines (runtime/): point location plus PVS lookup per query on a
# .pvs of the city with CELLS view cells, one core, Google Benchmark (bench/runtime_bench.cpp).
# The hierarchy is the merging benchmark's (1.5M segments, 50k AV-S cells; built here when
# missing). Rewrites the runtime section of BENCHMARKS.md.
# Usage: scripts/bench.sh runtime [CITY_SIZE] [CELLS]
size="${1:-23}"
cells="${2:-50000}"
bench_cmake_args="-DVIEWCELLS_BUILD_BENCH=ON"
source scripts/bench-setup.sh
city=$(bench_scene city "$size")
if [ ! -f "$dir/city-merge.vcells" ]; then
  "$vc" build "$city" --segments 1500000 --max-cells "$cells" --min-reduction 0 --seed 1 -q \
    -o "$dir/city-merge.vcells" --report "$dir/merge-city.json"
fi
"$vc" compress "$dir/city-merge.vcells" --count "$cells" -o "$dir/city-$cells.pvs" -q
"$vc" recode "$dir/city-$cells.pvs" --format 1 -o "$dir/city-$cells-format1.pvs" -q
objects=$(python3 scripts/vctables.py get "$dir/merge-city.json" scene objects)
VIEWCELLS_BENCH_PVS="$dir/city-$cells.pvs" VIEWCELLS_BENCH_PVS_FORMAT1="$dir/city-$cells-format1.pvs" taskset -c 0 build-release/bench/viewcells_runtime_bench \
  --benchmark_min_time=1 --benchmark_repetitions=7 --benchmark_report_aggregates_only=true \
  --benchmark_format=json --benchmark_out="$dir/runtime.json" >/dev/null
python3 scripts/vctables.py runtime "$dir/runtime.json" "$cells" "$objects" \
  "$(stat -c %s "$dir/city-$cells.pvs")" "$(stat -c %s "$dir/city-$cells-format1.pvs")" > "$dir/runtime-table.md"
python3 scripts/vctables.py replace-section BENCHMARKS.md runtime "scripts/bench.sh runtime $size $cells" \
  "$dir/runtime-table.md"
cat "$dir/runtime-table.md"
