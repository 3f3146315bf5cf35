# A/B of reading files against an earlier commit, measured in one run: `info` on the city's
# OBJ (size CITY_SIZE, seed 1) and `extract --count 50` of a hierarchy of the city (1.5M
# segments, 50,000 cells, greedy merging on the construction samples, built once by the current
# build), alternating the old and the new binary RUNS times. Prints each run's wall-clock
# seconds, the medians and new / old, and writes them into the io section of BENCHMARKS.md;
# the last line says whether both sides printed the same. The old commit is built (Release) in
# a git worktree under out/ab/ (as scripts/bench.sh ab does).
# Usage: scripts/bench.sh ab-io OLD_COMMIT [RUNS] [CITY_SIZE]
runs="${2:-5}"
size="${3:-23}"
source scripts/bench-setup.sh  # builds the current tree (Release), sets $vc and $dir
city=$(bench_scene city "$size")
bench_ab_binaries "$old"
hier="$dir/io-city.vcells"
"$vc" -q build "$city" --segments 1500000 --max-cells 50000 --min-reduction 0 --seed 1 --merge-pvs samples -o "$hier"
results="$dir/ab-io.tsv"
: >"$results"
step() {  # SIDE ROUND
  ab_time "$results" "$1" "info on the OBJ, s" "${bin[$1]}" -q info "$city"
  cp "$dir/ab-last.out" "$dir/ab-io-info-$1.out"
  ab_time "$results" "$1" "extract --count 50 of the hierarchy, s" "${bin[$1]}" -q extract "$hier" --count 50
  cp "$dir/ab-last.out" "$dir/ab-io-extract-$1.out"
}
ab_alternate "$runs" step
same="$(same_files "$dir/ab-io-info-old.out" "$dir/ab-io-info-new.out" "info's output"); \
$(same_files "$dir/ab-io-extract-old.out" "$dir/ab-io-extract-new.out" "extract's output")"
ab_table "$results" io "scripts/bench.sh ab-io $sha $runs $size" \
  "City size $size: its OBJ ($(($(stat -c %s "$city") / 1000000)) MB) and a hierarchy of it (1.5M segments, 50,000 \
cells, greedy merge, $(($(stat -c %s "$hier") / 1000000)) MB), alternating runs of the old ($sha) and the new build; \
$same."
