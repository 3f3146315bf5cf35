# A/B of the hot paths against an earlier commit, measured in one run: sampling 1M segments
# on the city (with bare Embree's rate beside it), a build of 20k cells from 300k segments
# (subdivision, then merging with the neighbour graph), and AGVS on 500 view cells of the
# office (2M samples; the office's hierarchy is built once), alternating the two binaries RUNS
# times; the medians and the ratio new / old go into the ab section of BENCHMARKS.md. The old commit is built (Release) in a
# git worktree under out/ab/. Usage: scripts/bench.sh ab OLD_COMMIT [RUNS] [CITY_SIZE]
runs="${2:-3}"
size="${3:-23}"
source scripts/bench-setup.sh  # builds the current tree (Release), sets $vc and $dir
city=$(bench_scene city "$size")
bench_ab_binaries "$old"
results="$dir/ab.tsv"
: >"$results"
office=$(bench_scene office 4)
"$vc" -q build "$office" --samples 500000 --max-cells 2000 --seed 1 -o "$dir/ab-office.vcells"
step() {  # SIDE ROUND
  local b="${bin[$1]}"
  "$b" -q sample "$city" --segments 1000000 --measure-raw -o "$dir/ab.vseg" --report "$dir/ab-s.json"
  "$b" -q build "$city" --segments 300000 --max-cells 20000 --min-reduction 0 -o "$dir/ab.vcells" \
    --report "$dir/ab-b.json"
  "$b" -q pvs "$dir/ab-office.vcells" --scene "$office" --cells 500 --samples 2000000 --seed 1 \
    -o "$dir/ab.pvs" --report "$dir/ab-p.json"
  python3 scripts/vctables.py ab-row "$1" "$dir/ab-s.json" "$dir/ab-b.json" "$dir/ab-p.json" >>"$results"
}
ab_alternate "$runs" step
python3 scripts/vctables.py ab "$results" "$sha" "$runs" "$size" > "$dir/ab-table.md"
python3 scripts/vctables.py replace-section BENCHMARKS.md ab "scripts/bench.sh ab $sha $runs $size" "$dir/ab-table.md"
cat "$dir/ab-table.md"
