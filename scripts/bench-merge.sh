#!/usr/bin/env bash
# Merging and PVS compression benchmark (issue: merge history, extraction, compression).
# The generated city (>= 1M triangles): 1.5M segments, 50k AV-S cells, merged to one; and the
# compression ratios of the sampled PVSs on the office and the city at several view cell
# counts. Rewrites the merging section of BENCHMARKS.md.
# Usage: scripts/bench-merge.sh [CITY_SIZE] [CELLS]
set -euo pipefail
size="${1:-23}"
cells="${2:-50000}"
source "$(dirname "$0")/bench-setup.sh"
city=$(bench_scene city "$size")
office=$(bench_scene office 4)
"$vc" build "$city" --segments 1500000 --max-cells "$cells" --min-reduction 0 --seed 1 -q \
  -o "$dir/city-merge.vcells" --report "$dir/merge-city.json"
"$vc" build "$office" --samples 1000000 --max-cells 2000 --seed 1 -q \
  -o "$dir/office-merge.vcells" --report "$dir/merge-office.json"
for n in "$cells" 5000 500 50; do
  "$vc" compress "$dir/city-merge.vcells" --count "$n" -o "$dir/city-$n.pvs" --flat "$dir/city-$n.vflt" \
    --report "$dir/compress-city-$n.json" -q
done
for n in 2000 200 20; do
  "$vc" compress "$dir/office-merge.vcells" --count "$n" -o "$dir/office-$n.pvs" --flat "$dir/office-$n.vflt" \
    --report "$dir/compress-office-$n.json" -q
done
python3 - "$dir" "$size" "$cells" <<'PY' > "$dir/merge-table.md"
import json, sys
d, size, cells = sys.argv[1], sys.argv[2], int(sys.argv[3])
print(f"Merging: the city of size {size} (seed 1), 1.5M segments, {cells:,} AV-S cells merged down to one; "
      "the office of size 4, 1M samples, 2,000 cells. Threads = 2.\n")
print("| scene | cells merged | subdivision s | merge s | pair costs evaluated | stale entries skipped | cost at all cells | at 1/10 | at 1/100 |")
print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
for name in ["city", "office"]:
    r = json.load(open(f"{d}/merge-{name}.json")); m = r["merge"]; t = r["timings"]
    curve = {p["cells"]: p["cost"] for p in m["cost_at_power_of_two_cells"]}
    n = m["cells_from"]
    def near(k):
        c = min(curve, key=lambda x: abs(x - k)); return f"{curve[c]:,.0f} ({c:,})"
    print(f"| {name} | {n:,} | {t['subdivision_seconds']:.1f} | {t['merge_seconds']:.2f} | {m['pair_costs_evaluated']:,} | "
          f"{m['stale_entries_skipped']:,} | {r['final_cost']:,.0f} | {near(n / 10)} | {near(n / 100)} |")
print("\nCompression of the sampled PVSs through the merge history (`viewcells compress`):\n")
print("| scene | view cells | objects | PVS entries | kept after | ratio | varint bytes before | after | .pvs file bytes | bit rows bytes | Quake RLE bytes |")
print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
for name, counts in [("city", [cells, 5000, 500, 50]), ("office", [2000, 200, 20])]:
    for n in counts:
        r = json.load(open(f"{d}/compress-{name}-{n}.json"))
        print(f"| {name} | {r['cells']:,} | {r['objects']:,} | {r['entries_before']:,} | {r['entries_after']:,} | "
              f"{r['entry_ratio']:.3f} | {r['varint_bytes_before']:,} | {r['varint_bytes_after']:,} | {r['file_bytes']:,} | "
              f"{r['flat']['bit_row_bytes']:,} | {r['flat']['run_length_bytes']:,} |")
PY
python3 scripts/replace-section.py BENCHMARKS.md merging "scripts/bench-merge.sh $size $cells" "$dir/merge-table.md"
cat "$dir/merge-table.md"
