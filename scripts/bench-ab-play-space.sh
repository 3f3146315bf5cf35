#!/usr/bin/env bash
# A/B of a bake's hierarchy stage on OpenArena maps, where `bake` finds the play space by
# default, against an earlier commit, measured in one run: for each map, the old and the new
# build alternate RUNS times (so that the machine's drift falls on both alike), each baking
# 40 cells from 50,000 construction samples (100 cells built, merged on the samples' PVSs) and
# 100,000 AGVS samples, two threads. Prints each side's hierarchy seconds (play space, sampling,
# subdivision, merging), the medians and their ratio new / old, the same stage without the
# play space (`--no-play-space`, new build) for scale, and whether the two builds' .pvs files
# are byte-identical. The old commit is built (Release) in a git worktree under out/ab/.
# Usage: scripts/bench-ab-play-space.sh OLD_COMMIT [RUNS] [MAP ...]   (default: oa_dm2)
set -euo pipefail
cd "$(dirname "$0")/.."
old="${1:?usage: scripts/bench-ab-play-space.sh OLD_COMMIT [RUNS] [MAP ...]}"
runs="${2:-5}"
shift $(($# >= 2 ? 2 : 1))
maps=("$@")
[ ${#maps[@]} -gt 0 ] || maps=(oa_dm2)
source scripts/bench-setup.sh  # builds the current tree (Release), sets $vc and $dir
bash scripts/fetch-maps.sh >/dev/null
bench_ab_binaries "$old"
results="$dir/ab-play-space.tsv"
: >"$results"
bake() {  # SIDE MAP [EXTRA...]
  local side=$1 map=$2
  shift 2
  "${bin[$side]}" -q --threads 2 bake "data/maps/bsp/$map.bsp" --cells 40 --samples 50000 --max-cells 100 \
    --merge-pvs samples --agvs-samples 100000 --seed 1 "$@" -o "$dir/ab-play-$side.pvs" --report "$dir/ab-play.json"
  python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["timings"]["hierarchy_seconds"])' "$dir/ab-play.json"
}
for map in "${maps[@]}"; do
  for r in $(seq "$runs"); do
    for side in old new; do printf '%s\t%s\t%s\n' "$map" "$side" "$(bake "$side" "$map")" >>"$results"; done
  done
  cmp -s "$dir/ab-play-old.pvs" "$dir/ab-play-new.pvs" && same=yes || same=no
  for r in $(seq "$runs"); do printf '%s\tnone\t%s\n' "$map" "$(bake new "$map" --no-play-space)" >>"$results"; done
  printf '%s\tsame\t%s\n' "$map" "$same" >>"$results"
done
python3 - "$results" "$sha" "$runs" <<'PY'
import statistics, sys
path, sha, runs = sys.argv[1:]
rows = [line.split("\t") for line in open(path).read().split("\n") if line]
print(f"bake hierarchy seconds (play space, sampling, subdivision, merging), {runs} alternating runs "
      f"of the old ({sha}) and the new build, two threads; medians")
print("| map | old s | new s | new / old | without the play space s | .pvs byte-identical |")
print("| --- | ---: | ---: | ---: | ---: | --- |")
for m in dict.fromkeys(r[0] for r in rows):
    t = {s: statistics.median(float(r[2]) for r in rows if r[0] == m and r[1] == s) for s in ("old", "new", "none")}
    same = next(r[2] for r in rows if r[0] == m and r[1] == "same")
    print(f"| {m} | {t['old']:.3f} | {t['new']:.3f} | {t['new'] / t['old']:.3f} | {t['none']:.3f} | {same} |")
PY
