# Merging and PVS compression benchmark (issue: merge history, extraction, compression).
# The generated city (>= 1M triangles): 1.5M segments, 50k AV-S cells, merged to one; and the
# compression ratios of the sampled PVSs on the office and the city at several view cell
# counts. The city is merged twice: validated by two AGVS runs over the leaves (the default)
# and greedy on the construction samples' PVSs (--merge-pvs samples). Times include the leaf
# PVSs and the neighbour graph. The neighbour graph and the greedy merge are also timed alone on
# the greedy run's file (bench/merge_bench.cpp, fastest of 3), which the machine's drift
# disturbs less than one run of the whole build. Rewrites the merging section of BENCHMARKS.md.
# Usage: scripts/bench.sh merge [CITY_SIZE] [CELLS]
size="${1:-23}"
cells="${2:-50000}"
bench_cmake_args="-DVIEWCELLS_BUILD_BENCH=ON"
source scripts/bench-setup.sh
city=$(bench_scene city "$size")
office=$(bench_scene office 4)
"$vc" build "$city" --segments 1500000 --max-cells "$cells" --min-reduction 0 --seed 1 -q \
  -o "$dir/city-merge.vcells" --report "$dir/merge-city.json"
"$vc" build "$city" --segments 1500000 --max-cells "$cells" --min-reduction 0 --seed 1 -q --merge-pvs samples \
  -o "$dir/city-merge-samples.vcells" --report "$dir/merge-city-samples.json"
build-release/bench/viewcells_merge_bench "$city" "$dir/city-merge-samples.vcells" 3 > "$dir/merge-stage.txt"
"$vc" build "$office" --samples 1000000 --max-cells 2000 --seed 1 -q \
  -o "$dir/office-merge.vcells" --report "$dir/merge-office.json"
for n in "$cells" 5000 500 50; do
  "$vc" compress "$dir/city-merge.vcells" --count "$n" -o "$dir/city-$n.pvs" --flat "$dir/city-$n.vflt" \
    --report "$dir/compress-city-$n.json" -q
done
for n in 2000 200 20; do
  "$vc" compress "$dir/office-merge.vcells" --count "$n" -o "$dir/office-$n.pvs" --flat "$dir/office-$n.vflt" \
    --report "$dir/compress-office-$n.json" -q
done
python3 scripts/vctables.py merging "$dir" "$size" "$cells" > "$dir/merge-table.md"
python3 scripts/vctables.py replace-section BENCHMARKS.md merging "scripts/bench.sh merge $size $cells" "$dir/merge-table.md"
cat "$dir/merge-table.md"
