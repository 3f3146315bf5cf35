#!/usr/bin/env bash
# A/B of the hot paths against an earlier commit, measured in one run: sampling 1M segments
# on the city (with bare Embree's rate beside it) and a build of 20k cells from 300k segments
# (subdivision, then merging with the neighbour graph), alternating the two binaries RUNS
# times; prints the medians and the ratio new / old. The old commit is built (Release) in a
# git worktree under out/ab/. Usage: scripts/bench-ab.sh OLD_COMMIT [RUNS] [CITY_SIZE]
set -euo pipefail
cd "$(dirname "$0")/.."
old="${1:?usage: scripts/bench-ab.sh OLD_COMMIT [RUNS] [CITY_SIZE]}"
runs="${2:-3}"
size="${3:-23}"
source scripts/bench-setup.sh  # builds the current tree (Release), sets $vc and $dir
city=$(bench_scene city "$size")
sha=$(git rev-parse --short "$old")
tree="out/ab/$sha"
if [ ! -x "$tree/b/cli/viewcells" ]; then
  rm -rf "$tree"
  git worktree prune
  git worktree add -f "$tree" "$sha" >/dev/null
  cmake -S "$tree" -B "$tree/b" -G Ninja -DCMAKE_BUILD_TYPE=Release -DVIEWCELLS_BUILD_TESTS=OFF >/dev/null
  cmake --build "$tree/b" -j "$(nproc)" --target viewcells >/dev/null
fi
declare -A bin=([old]="$tree/b/cli/viewcells" [new]="$vc")
results="$dir/ab.tsv"
: >"$results"
for r in $(seq "$runs"); do
  for side in old new; do
    "${bin[$side]}" -q sample "$city" --segments 1000000 --measure-raw -o "$dir/ab.vseg" --report "$dir/ab-s.json"
    "${bin[$side]}" -q build "$city" --segments 300000 --max-cells 20000 --min-reduction 0 -o "$dir/ab.vcells" \
      --report "$dir/ab-b.json"
    python3 -c "
import json
s = json.load(open('$dir/ab-s.json'))['timings']
b = json.load(open('$dir/ab-b.json'))['timings']
print('$side', s['segments_per_second'] / 1e6, s['raw_rays_per_second'] / 1e6, b['subdivision_seconds'], b['merge_seconds'], sep='\t')
" >>"$results"
  done
done
python3 - "$results" "$sha" "$runs" "$size" <<'EOF'
import statistics, sys
rows = [l.split('\t') for l in open(sys.argv[1]).read().split('\n') if l]
med = {side: [statistics.median(float(r[k]) for r in rows if r[0] == side) for k in range(1, 5)] for side in ('old', 'new')}
names = ['sampling Msegments/s', 'raw Embree Mrays/s', 'subdivision s (20k cells)', 'merge s (20k cells)']
print(f"Command: `scripts/bench-ab.sh {sys.argv[2]} {sys.argv[3]} {sys.argv[4]}`; city size {sys.argv[4]}, medians of {sys.argv[3]} alternating runs\n")
print('| quantity | old (' + sys.argv[2] + ') | new | new / old |')
print('| --- | ---: | ---: | ---: |')
for n, o, w in zip(names, med['old'], med['new']):
    print(f'| {n} | {o:.2f} | {w:.2f} | {w / o:.3f} |')
EOF
