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
python3 scripts/vctables.py subdivision "$dir" "$size" "$cells" > "$dir/subdivision-table.md"
python3 scripts/vctables.py replace-section BENCHMARKS.md subdivision "scripts/bench-subdivision.sh $size $cells" "$dir/subdivision-table.md"
cat "$dir/subdivision-table.md"
