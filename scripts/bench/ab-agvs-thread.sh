# A/B of AGVS on ONE thread against an earlier commit, measured in one run (issue 58: the
# one-machine path must not slow): the city of size 23 (seed 1) cut into 500 and 5,000 view
# cells (scripts/bench.sh mpi's merge history of 5,000 cells), `pvs` with 1M samples in
# batches of 20,000, seed 1, one lane; the old and the new build alternate RUNS times. Prints
# each side's samples a second (medians and range), the ratio new / old, and whether the two
# wrote the same .pvs. The old commit is built (Release) in a git worktree under out/ab/.
# Usage: scripts/bench.sh ab-agvs-thread OLD_COMMIT [RUNS]   (default 5)
runs="${2:-5}"
source scripts/bench-setup.sh  # builds the current tree (Release), sets $vc and $dir
bench_ab_binaries "$old"
scene=$(bench_scene city 23)
out="$dir/ab-agvs-thread"
mkdir -p "$out"
level=$(bench_city_cells 1000000 5000)
results="$out/runs.tsv"
: >"$results"
step() {  # SIDE ROUND
  local cells
  for cells in 500 5000; do
    "${bin[$1]}" --threads 1 -q pvs "$level" --scene "$scene" --cells "$cells" --samples 1000000 \
      --batch 20000 --seed 1 -o "$out/$cells-$1.pvs" --report "$out/run.json"
    ab_record "$results" "$1" "$cells cells, samples a second" \
      "$(python3 scripts/vctables.py get "$out/run.json" samples_per_second)"
  done
}
ab_alternate "$runs" step
ab_table "$results" - "" "AGVS on one thread, old $sha against the current tree, alternating runs; \
$(same_files "$out/500-old.pvs" "$out/500-new.pvs" "500 cells"), $(same_files "$out/5000-old.pvs" "$out/5000-new.pvs" "5,000 cells")."
