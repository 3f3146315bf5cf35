# The visibility filter (issue: AGVS, deliverable 5): after a few sample counts, the mean PVS
# size and the measured pixel error with and without the filter (object space, k = 1; and
# with the view space filter over one neighbour). Writes the filter section of BENCHMARKS.md.
# Usage: scripts/bench.sh filter [KIND] [SIZE] [CELLS]   (defaults: office 4 500)
kind="${1:-office}"
size="${2:-4}"
cells="${3:-500}"
source scripts/bench-setup.sh
scene=$(bench_scene "$kind" "$size")
out="$dir/filter-$kind$size"
bench_level "$scene" "$cells" "$out"
for n in 100000 1000000 10000000; do
  for f in object both; do
    opts=(--filter)
    [ "$f" = both ] && opts+=(--filter-neighbours 1)
    "$vc" pvs "$out/level.vcells" --scene "$scene" --cells "$cells" --samples "$n" --seed 1 -q "${opts[@]}" \
      -o "$out/$f-$n.pvs" --report "$out/$f-$n.json" --measure-cameras 20000 --measure-size 32
  done
done
python3 scripts/vctables.py filter "$out" "$kind" "$size" "$cells" > "$out/table.md"
python3 scripts/vctables.py replace-section BENCHMARKS.md "filter-$kind$size" "scripts/bench.sh filter $kind $size $cells" \
  "$out/table.md"
cat "$out/table.md"
