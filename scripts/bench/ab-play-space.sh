# A/B of a bake's hierarchy stage on OpenArena maps, where `bake` finds the play space by
# default, against an earlier commit, measured in one run: for each map, the old and the new
# build alternate RUNS times (so that the machine's drift falls on both alike), each baking
# 40 cells from 50,000 construction samples (100 cells built, merged on the samples' PVSs) and
# 100,000 AGVS samples, two threads. Prints each side's hierarchy seconds (play space, sampling,
# subdivision, merging), the medians and their ratio new / old, the same stage without the
# play space (`--no-play-space`, new build) for scale, and whether the two builds' .pvs files
# are byte-identical. The old commit is built (Release) in a git worktree under out/ab/.
# Usage: scripts/bench.sh ab-play-space OLD_COMMIT [RUNS] [MAP ...]   (default: oa_dm2)
runs="${2:-5}"
shift $(($# >= 2 ? 2 : 1))
maps=("$@")
[ ${#maps[@]} -gt 0 ] || maps=(oa_dm2)
source scripts/bench-setup.sh  # builds the current tree (Release), sets $vc and $dir
bash scripts/fetch-maps.sh >/dev/null
bench_ab_binaries "$old"
results="$dir/ab-play-space.tsv"
: >"$results"
bake() {  # SIDE MAP [EXTRA...]: the bake's hierarchy seconds
  local side=$1 map=$2
  shift 2
  "${bin[$side]}" -q --threads 2 bake "data/maps/bsp/$map.bsp" --cells 40 --samples 50000 --max-cells 100 \
    --merge-pvs samples --agvs-samples 100000 --seed 1 "$@" -o "$dir/ab-play-$side.pvs" --report "$dir/ab-play.json"
  python3 scripts/vctables.py get "$dir/ab-play.json" timings hierarchy_seconds
}
same=()
for map in "${maps[@]}"; do
  step() { ab_record "$results" "$1" "$map: hierarchy s" "$(bake "$1" "$map")"; }
  ab_alternate "$runs" step
  same+=("$(same_files "$dir/ab-play-old.pvs" "$dir/ab-play-new.pvs" "$map's .pvs")")
  for r in $(seq "$runs"); do ab_record "$results" new "$map: hierarchy s without the play space" "$(bake new "$map" --no-play-space)"; done
done
ab_table "$results" - "" "bake's hierarchy seconds (play space, sampling, subdivision, merging), alternating runs \
of the old ($sha) and the new build, two threads; ${same[*]}."
