#!/usr/bin/env bash
# A/B of the default (validated) merge at the merging table's size, against an earlier commit,
# measured in one run: the city, SEGMENTS segments to CELLS cells (no stagnation stop, two
# threads), built and merged as `build` does by default (two AGVS runs over the leaves, held-out
# random samples, the candidates scored), alternating the old and the new build RUNS times.
# Prints each run's leaf PVSs, neighbour graph and merge seconds, the medians of their sum and
# the ratio new / old; the last line says whether the two builds' .vcells are byte-identical.
# The old commit is built (Release) in a git worktree under out/ab/ (as scripts/bench-ab.sh does).
# Usage: scripts/bench-ab-merge.sh OLD_COMMIT [RUNS] [CITY_SIZE] [SEGMENTS] [CELLS]
set -euo pipefail
cd "$(dirname "$0")/.."
old="${1:?usage: scripts/bench-ab-merge.sh OLD_COMMIT [RUNS] [CITY_SIZE] [SEGMENTS] [CELLS]}"
runs="${2:-3}"
size="${3:-23}"
segments="${4:-1500000}"
cells="${5:-50000}"
source scripts/bench-setup.sh  # builds the current tree (Release), sets $vc and $dir
scene=$(bench_scene city "$size")
bench_ab_binaries "$old"
results="$dir/ab-merge.tsv"
: >"$results"
for r in $(seq "$runs"); do
  for side in old new; do
    "${bin[$side]}" -q --threads 2 build "$scene" --segments "$segments" --min-reduction 0 --max-cells "$cells" \
      --seed 1 -o "$dir/ab-merge-$side.vcells" --report "$dir/ab-merge.json"
    python3 - "$side" "$dir/ab-merge.json" >>"$results" <<'PY'
import json, sys
t = json.load(open(sys.argv[2]))["timings"]
print(sys.argv[1], t["leaf_pvs_seconds"], t["neighbour_graph_seconds"], t["merge_seconds"], sep="\t")
PY
  done
done
python3 - "$results" "$sha" "$runs" "$size" "$segments" "$cells" <<'PY'
import statistics, sys
path, sha, runs, size, segments, cells = sys.argv[1:]
rows = [line.split("\t") for line in open(path).read().split("\n") if line]
print(f"City size {size}, {int(segments):,} segments to {int(cells):,} cells, the default merge, "
      f"{runs} alternating runs of the old ({sha}) and the new build, two threads.")
total = {}
for s in ("old", "new"):
    mine = [[float(v) for v in x[1:]] for x in rows if x[0] == s]
    total[s] = [sum(x) for x in mine]
    print(f"{s}: leaf PVSs + graph + merge s " + ", ".join(f"{x[0]:.1f} + {x[1]:.1f} + {x[2]:.1f}" for x in mine)
          + f"; median of the sums {statistics.median(total[s]):.1f}")
print(f"new / old (medians): {statistics.median(total['new']) / statistics.median(total['old']):.3f}")
PY
if cmp -s "$dir/ab-merge-old.vcells" "$dir/ab-merge-new.vcells"; then
  echo "the two builds' .vcells are byte-identical"
else
  echo "the two builds' .vcells differ"
fi
