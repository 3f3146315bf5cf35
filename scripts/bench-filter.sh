#!/usr/bin/env bash
# The visibility filter (issue: AGVS, deliverable 5): after a few sample counts, the mean PVS
# size and the measured pixel error with and without the filter (object space, k = 1; and
# with the view space filter over one neighbour). Writes the filter section of BENCHMARKS.md.
# Usage: scripts/bench-filter.sh [KIND] [SIZE] [CELLS]   (defaults: office 4 500)
set -euo pipefail
kind="${1:-office}"
size="${2:-4}"
cells="${3:-500}"
source "$(dirname "$0")/bench-setup.sh"
scene=$(bench_scene "$kind" "$size")
out="$dir/filter-$kind$size"
bench_level "$scene" "$cells" "$out"
for n in 100000 1000000 10000000; do
  for f in object both; do
    opts=(--filter)
    [ "$f" = both ] && opts+=(--filter-neighbours 1)
    "$vc" pvs "$out/level.vcells" --scene "$scene" --cells "$cells" --samples "$n" --seed 1 -q "${opts[@]}" \
      -o "$out/$f-$n.pvs" --report "$out/$f-$n.json" --measure-cameras 20000 --measure-size 32
  done
done
python3 - "$out" "$kind" "$size" "$cells" <<'PY' > "$out/table.md"
import json, sys
out, kind, size, cells = sys.argv[1:5]
print(f"AGVS on the {kind} of size {size} (seed 1), {cells} view cells. Measured pixel error: 20,000 random cameras "
      f"of 32x32, in pixels of a 1024x1024 image. Object space filter with k = 1; 'and view space': also merged "
      f"with the most similar neighbouring cell.\n")
print("| samples | filter | mean PVS unfiltered | filtered | growth | measured error unfiltered | filtered |")
print("| ---: | --- | ---: | ---: | ---: | ---: | ---: |")
for n in (100000, 1000000, 10000000):
    for f, name in (("object", "object space"), ("both", "and view space")):
        r = json.load(open(f"{out}/{f}-{n}.json"))
        fl = r["filter"]
        print(f"| {r['samples']:,} | {name} | {fl['mean_pvs_size_unfiltered']:.2f} | {fl['mean_pvs_size_filtered']:.2f} | "
              f"{fl['mean_pvs_size_filtered'] / fl['mean_pvs_size_unfiltered']:.2f} x | "
              f"{fl['measured_pixel_error_unfiltered']['pixels']:.2f} | {r['measured_pixel_error']['pixels']:.2f} |")
print()
PY
python3 scripts/replace-section.py BENCHMARKS.md "filter-$kind$size" "scripts/bench-filter.sh $kind $size $cells" \
  "$out/table.md"
cat "$out/table.md"
