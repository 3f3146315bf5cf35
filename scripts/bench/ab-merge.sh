# A/B of the default (validated) merge at the merging table's size, against an earlier commit,
# measured in one run: the city, SEGMENTS segments to CELLS cells (no stagnation stop, two
# threads), built and merged as `build` does by default (two AGVS runs over the leaves, held-out
# random samples, the candidates scored), alternating the old and the new build RUNS times.
# Prints each run's leaf PVSs, neighbour graph and merge seconds, the medians of their sum and
# the ratio new / old; the last line says whether the two builds' .vcells are byte-identical.
# The old commit is built (Release) in a git worktree under out/ab/ (as scripts/bench.sh ab does).
# Usage: scripts/bench.sh ab-merge OLD_COMMIT [RUNS] [CITY_SIZE] [SEGMENTS] [CELLS]
runs="${2:-3}"
size="${3:-23}"
segments="${4:-1500000}"
cells="${5:-50000}"
source scripts/bench-setup.sh  # builds the current tree (Release), sets $vc and $dir
scene=$(bench_scene city "$size")
bench_ab_binaries "$old"
results="$dir/ab-merge.tsv"
: >"$results"
step() {  # SIDE ROUND
  "${bin[$1]}" -q --threads 2 build "$scene" --segments "$segments" --min-reduction 0 --max-cells "$cells" \
    --seed 1 -o "$dir/ab-merge-$1.vcells" --report "$dir/ab-merge.json"
  local t
  for t in leaf_pvs_seconds neighbour_graph_seconds merge_seconds; do
    ab_record "$results" "$1" "$t" "$(python3 scripts/vctables.py get "$dir/ab-merge.json" timings "$t")"
  done
  ab_record "$results" "$1" "all three, s" "$(python3 -c 'import json, sys; t = json.load(open(sys.argv[1]))["timings"]
print(t["leaf_pvs_seconds"] + t["neighbour_graph_seconds"] + t["merge_seconds"])' "$dir/ab-merge.json")"
}
ab_alternate "$runs" step
ab_table "$results" - "" "City size $size, $segments segments to $cells cells, the default merge, alternating runs \
of the old ($sha) and the new build, two threads; \
$(same_files "$dir/ab-merge-old.vcells" "$dir/ab-merge-new.vcells" "the two builds' .vcells")."
