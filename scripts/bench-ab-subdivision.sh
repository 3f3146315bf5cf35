#!/usr/bin/env bash
# A/B of the subdivision at the subdivision issue's size, against an earlier commit, measured
# in one run: the city, SEGMENTS segments to CELLS cells (no stagnation stop, no merge, two
# threads, fast candidate positions), alternating the old and the new build RUNS times, so that
# the machine's drift over an hour (up to 1.6x here) falls on both alike. Prints each run's
# subdivision seconds and final construction cost, the medians and their ratio new / old; the
# old commit is built (Release) in a git worktree under out/ab/ (as scripts/bench-ab.sh does).
# With map:NAME for CITY_SIZE, the OpenArena map data/maps/bsp/NAME.bsp instead (as the
# subdivision table's map row: SEGMENTS construction samples, default 300,000, to CELLS cells,
# default 1,500, the default stagnation stop, geometry-aligned candidates as auto decides).
# Each side writes its cells; the last line says whether the two builds' .vcells are
# byte-identical (the same tree). Commits before f2ea46e (such as 6f655e9, the build the
# subdivision issue's 149 s came from) need libopenmesh-dev to build, which install-deps.sh no
# longer installs: `apt-get install libopenmesh-dev` first.
# Usage: scripts/bench-ab-subdivision.sh OLD_COMMIT [RUNS] [CITY_SIZE | map:NAME] [SEGMENTS] [CELLS]
set -euo pipefail
cd "$(dirname "$0")/.."
old="${1:?usage: scripts/bench-ab-subdivision.sh OLD_COMMIT [RUNS] [CITY_SIZE] [SEGMENTS] [CELLS]}"
runs="${2:-3}"
size="${3:-23}"
source scripts/bench-setup.sh  # builds the current tree (Release), sets $vc and $dir
if [[ "$size" == map:* ]]; then
  segments="${4:-300000}"
  cells="${5:-1500}"
  scene="data/maps/bsp/${size#map:}.bsp"
  bash scripts/fetch-maps.sh >/dev/null
  what=(--samples "$segments")
else
  segments="${4:-1500000}"
  cells="${5:-50000}"
  scene=$(bench_scene city "$size")
  what=(--segments "$segments" --min-reduction 0)
fi
bench_ab_binaries "$old"
results="$dir/ab-subdivision.tsv"
: >"$results"
for r in $(seq "$runs"); do
  for side in old new; do
    "${bin[$side]}" -q --threads 2 build "$scene" "${what[@]}" --max-cells "$cells" --seed 1 \
      --no-merge -o "$dir/ab-sub-$side.vcells" --report "$dir/ab-sub.json"
    python3 - "$side" "$dir/ab-sub.json" >>"$results" <<'PY'
import json, sys
r = json.load(open(sys.argv[2]))
print(sys.argv[1], r["timings"]["subdivision_seconds"], r["subdivision"]["final_cost"], sep="\t")
PY
  done
done
python3 - "$results" "$sha" "$runs" "$size" "$segments" "$cells" <<'PY'
import statistics, sys
path, sha, runs, size, segments, cells = sys.argv[1:]
rows = [line.split("\t") for line in open(path).read().split("\n") if line]
t = {s: [float(x[1]) for x in rows if x[0] == s] for s in ("old", "new")}
c = {s: [float(x[2]) for x in rows if x[0] == s] for s in ("old", "new")}
scene = f"{size[4:]}, {int(segments):,} construction samples" if size.startswith("map:") else f"City size {size}, {int(segments):,} segments"
print(f"{scene} to {int(cells):,} cells, {runs} alternating runs of the old "
      f"({sha}) and the new build, two threads.")
for s in ("old", "new"):
    print(f"{s}: subdivision s " + ", ".join(f"{x:.2f}" for x in t[s]) + f"; median {statistics.median(t[s]):.2f}; "
          f"final construction cost {statistics.median(c[s]):,.0f}")
print(f"new / old (medians): {statistics.median(t['new']) / statistics.median(t['old']):.3f}")
PY
if cmp -s "$dir/ab-sub-old.vcells" "$dir/ab-sub-new.vcells"; then
  echo "cells: byte-identical .vcells"
else
  echo "cells: the .vcells differ"
fi
