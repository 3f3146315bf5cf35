#!/usr/bin/env bash
# A/B of AGVS on ONE thread against an earlier commit, measured in one run (issue 58: the
# one-machine path must not slow): the city of size 23 (seed 1) cut into 500 and 5,000 view
# cells (scripts/bench-mpi.sh's merge history of 5,000 cells), `pvs` with 1M samples in
# batches of 20,000, seed 1, one lane; the old and the new build alternate RUNS times. Prints
# each side's samples a second (medians and range), the ratio new / old, and whether the two
# wrote the same .pvs. The old commit is built (Release) in a git worktree under out/ab/.
# Usage: scripts/bench-ab-agvs-thread.sh OLD_COMMIT [RUNS]   (default 5)
set -euo pipefail
cd "$(dirname "$0")/.."
old="${1:?usage: scripts/bench-ab-agvs-thread.sh OLD_COMMIT [RUNS]}"
runs="${2:-5}"
source scripts/bench-setup.sh  # builds the current tree (Release), sets $vc and $dir
bench_ab_binaries "$old"
scene=$(bench_scene city 23)
out="$dir/ab-agvs-thread"
mkdir -p "$out"
level=$(bench_city_cells 1000000 5000)
results="$out/runs.tsv"
: >"$results"
for r in $(seq "$runs"); do
  for cells in 500 5000; do
    for side in old new; do
      "${bin[$side]}" --threads 1 -q pvs "$level" --scene "$scene" --cells "$cells" --samples 1000000 \
        --batch 20000 --seed 1 -o "$out/$cells-$side.pvs" --report "$out/run.json"
      printf '%s\t%s\t%s\n' "$cells" "$side" "$(jq .samples_per_second "$out/run.json")" >>"$results"
    done
  done
done
same=()
for cells in 500 5000; do
  cmp -s "$out/$cells-old.pvs" "$out/$cells-new.pvs" && same+=("$cells: yes") || same+=("$cells: no")
done
python3 - "$results" "$sha" "$runs" "${same[*]}" <<'PY'
import statistics, subprocess, sys
path, sha, runs, same = sys.argv[1:]
rows = [line.split("\t") for line in open(path).read().split("\n") if line]
commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
print(f"Command: `scripts/bench-ab-agvs-thread.sh {sha} {runs}`\n")
print(f"AGVS on one thread, old {sha} against new {commit}, {runs} alternating runs; samples a second, medians "
      f"(range). Same .pvs: {same}.\n")
print("| cells | old | new | new / old |")
print("| ---: | ---: | ---: | ---: |")
for cells in ("500", "5000"):
    v = {s: sorted(float(r[2]) for r in rows if r[0] == cells and r[1] == s) for s in ("old", "new")}
    m = {s: statistics.median(x) for s, x in v.items()}
    print(f"| {int(cells):,} | {m['old']:,.0f} ({v['old'][0]:,.0f}-{v['old'][-1]:,.0f}) | {m['new']:,.0f} "
          f"({v['new'][0]:,.0f}-{v['new'][-1]:,.0f}) | {m['new'] / m['old']:.3f} |")
PY
