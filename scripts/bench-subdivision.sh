#!/usr/bin/env bash
# Subdivision benchmark (issue: AV-S): the generated city (>= 1M triangles), segments to 50k
# cells, time per phase; and how the subdivision time grows with 0.5M, 1M, 1.5M, 2M segments.
# The stagnation stop is switched off (--min-reduction 0) so that every run reaches CELLS.
# Rewrites the subdivision section of BENCHMARKS.md. Usage: scripts/bench-subdivision.sh [SIZE] [CELLS]
set -euo pipefail
size="${1:-23}"
cells="${2:-50000}"
source "$(dirname "$0")/bench-setup.sh"
scene=$(bench_scene city "$size")
for n in 500000 1000000 1500000 2000000; do
  "$vc" build "$scene" --segments "$n" --max-cells "$cells" --min-reduction 0 --seed 1 -q --report "$dir/build-$n.json"
done
python3 - "$dir" "$size" "$cells" <<'PY' > "$dir/subdivision-table.md"
import json, sys
d, size, cells = sys.argv[1], sys.argv[2], sys.argv[3]
print(f"City size {size} (seed 1), {int(cells):,} cells, default view box, no stagnation stop, threads = 2.\n")
print("| segments | load s | BVH s | sampling s | subdivision s | write s | cells | initial cost | final cost | axis candidates | GA candidates |")
print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
base = None
for n in [500000, 1000000, 1500000, 2000000]:
    r = json.load(open(f"{d}/build-{n}.json")); t = r["timings"]; s = r["subdivision"]
    print(f"| {n:,} | {t['load_seconds']:.2f} | {t['bvh_build_seconds']:.2f} | {t['sampling_seconds']:.2f} | "
          f"{t['subdivision_seconds']:.1f} | {t['write_seconds']:.2f} | {s['cells']:,} | {s['initial_cost']:,.0f} | "
          f"{s['final_cost']:,.0f} | {s['axis_candidates_evaluated']:,} | {s['geometry_candidates_evaluated']:,} |")
ts = {n: json.load(open(f"{d}/build-{n}.json"))["timings"]["subdivision_seconds"] for n in [500000, 1000000, 2000000]}
print(f"\nSubdivision time ratios: 1M / 0.5M = {ts[1000000] / ts[500000]:.2f}, 2M / 1M = {ts[2000000] / ts[1000000]:.2f} "
      "(2.0 would be linear in the number of segments).")
PY
python3 scripts/replace-section.py BENCHMARKS.md subdivision "scripts/bench-subdivision.sh $size $cells" "$dir/subdivision-table.md"
cat "$dir/subdivision-table.md"
