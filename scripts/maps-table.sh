#!/usr/bin/env bash
# Our view cells against q3map2's on every OpenArena map that carries visibility data: for
# each map, `viewcells compare MAP --methods av-m,q3-clusters` (AV-S to 3x the map's clusters,
# merged; q3map2's clusters scored on the same evaluation samples over the map's non-solid
# space). Writes docs/results/q3-maps.md, docs/results/q3-maps.csv and the section "Quake 3
# maps" of docs/results.md.
# Usage: scripts/maps-table.sh [SAMPLES] [EVAL_SAMPLES]   (defaults 500000 and 4 x SAMPLES)
# MAPS_REUSE=1 keeps comparisons already in out/maps (to redo only the tables).
set -euo pipefail
samples="${1:-500000}"
eval_samples="${2:-$((4 * samples))}"
source "$(dirname "$0")/bench-setup.sh"
bash scripts/fetch-maps.sh >/dev/null
out=out/maps
mkdir -p "$out" docs/results
maps=(data/maps/bsp/*.bsp)
i=0
for map in "${maps[@]}"; do
  i=$((i + 1))
  name=$(basename "$map" .bsp)
  if [ "${MAPS_REUSE:-0}" = 1 ] && { [ -f "$out/$name/summary.json" ] || [ -f "$out/$name.skipped" ]; }; then continue; fi
  rm -f "$out/$name.skipped" "$out/$name.failed"
  "$vc" info "$map" --json "$out/$name.info.json" >/dev/null
  clusters=$(python3 -c "import json; print(json.load(open('$out/$name.info.json'))['quake3']['clusters'])")
  if [ "$clusters" = 0 ]; then
    echo "no visibility data" > "$out/$name.skipped"
    echo "maps: [$i/${#maps[@]}] $name: no visibility data, skipped"
    continue
  fi
  start=$(date +%s.%N)
  if "$vc" compare "$map" --samples "$samples" --eval-samples "$eval_samples" --seed 1 \
      --methods av-m,q3-clusters -o "$out/$name" -q 2> "$out/$name.err"; then
    python3 -c "print('%.1f' % ($(date +%s.%N) - $start))" > "$out/$name/wall_seconds"
    echo "maps: [$i/${#maps[@]}] $name: $clusters clusters, $(cat "$out/$name/wall_seconds") s"
  else
    cp "$out/$name.err" "$out/$name.failed"
    echo "maps: [$i/${#maps[@]}] $name: FAILED ($(tail -1 "$out/$name.err"))"
  fi
done

python3 - "$out" "$samples" "$eval_samples" <<'PY'
import csv, glob, json, os, statistics, sys
out, samples, eval_samples = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
rows, skipped, failed = [], [], []
for info_path in sorted(glob.glob(f"{out}/*.info.json")):
    name = os.path.basename(info_path)[:-len(".info.json")]
    if os.path.exists(f"{out}/{name}.skipped"):
        skipped.append(name); continue
    if os.path.exists(f"{out}/{name}.failed"):
        failed.append((name, open(f"{out}/{name}.failed").read().strip().splitlines()[-1])); continue
    s = json.load(open(f"{out}/{name}/summary.json"))
    info = json.load(open(info_path))
    q = s["q3map2"]
    t = s["timings"]
    rows.append(dict(
        map=name, triangles=s["scene"]["triangles"], objects=s["scene"]["objects"], clusters=q["clusters"],
        non_occluding=info["quake3"]["surfaces"]["non_occluding"],
        q3_cost=q["q3map2_cost"], avm_cost=q["av_m_cost_at_clusters"], ratio=q["av_m_cost_ratio"],
        cells_to_match=q["av_m_cells_to_match"], pvs_ratio=q["pvs_size_ratio"],
        excluded=q["excluded_but_seen"], causes=q["excluded_by_cause"],
        q3_bytes=q["storage_bytes"]["q3map2_rows"], q3_leaf_bytes=q["storage_bytes"]["q3map2_leaf_surface_lists"],
        ours_bytes=q["storage_bytes"]["ours_compressed"], ours_rle=q["storage_bytes"]["ours_rle_rows"],
        build_s=q["build_seconds"],
        sampling_s=t["construction_sampling_seconds"] + t["evaluation_sampling_seconds"],
        wall_s=float(open(f"{out}/{name}/wall_seconds").read())))

CAUSES = ("crack", "invisible", "void", "unlisted", "far", "rejected")

def num(x, d=0):
    return "n/a" if x is None else f"{x:,.{d}f}"

with open("docs/results/q3-maps.csv", "w", newline="") as f:
    w = csv.writer(f)
    keys = [k for k in rows[0] if k != "causes"] if rows else []
    w.writerow(keys + list(CAUSES))
    for r in rows:
        w.writerow([r[k] for k in keys] + [r["causes"].get(c, 0) for c in CAUSES])

lines = []
lines.append(f"Every OpenArena map with vis data ({len(rows)} maps; {len(skipped)} without vis data skipped"
             + (f", {len(failed)} failed" if failed else "") + "). Per map: "
             f"{samples:,} construction samples, {eval_samples:,} evaluation samples (another seed), both with origins "
             "in the map's non-solid space; AV-S to 3x the map's cluster count, merged (AV-M); cell weights are "
             "volumes of non-solid space; r(o) = max(100, triangles); the sky closes the map but costs nothing; "
             "solid brushes stop rays as hulls half a unit inside their sides; water, fog, slime, lava and "
             "translucent surfaces are rendered and seen through; objects are the map's surfaces.\n")
lines.append("| map | triangles | clusters | q3map2 cost | AV-M cost at clusters | AV-M / q3map2 | AV-M cells to match q3map2 "
             "| PVS ours / q3map2 | seen but excluded (crack / invisible / void / unlisted / far / rejected) "
             "| q3map2 rows (B) | ours compressed (B) "
             "| build (s) |")
lines.append("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
for r in rows:
    c = r["causes"]
    lines.append(f"| {r['map']} | {r['triangles']:,} | {r['clusters']:,} | {num(r['q3_cost'])} | {num(r['avm_cost'])} | "
                 f"{num(r['ratio'], 3)} | {num(r['cells_to_match'])} | {r['pvs_ratio']:.3f} | "
                 f"{r['excluded']:,} ({' / '.join(f'{c.get(k, 0):,}' for k in CAUSES)}) | "
                 f"{r['q3_bytes']:,} | {r['ours_bytes']:,} | {r['build_s']:.1f} |")
lines.append("")
ratios = [r["ratio"] for r in rows if r["ratio"] is not None]
lower = [x for x in ratios if x < 1]
if ratios:
    lines.append(f"**AV-M's evaluated render cost at q3map2's cell count is lower than q3map2's on {len(lower)} of "
                 f"{len(rows)} maps**" + (f" ({len(rows) - len(ratios)} did not reach that count)" if len(ratios) < len(rows) else "")
                 + f": AV-M / q3map2 median {statistics.median(ratios):.3f}, range {min(ratios):.3f} to {max(ratios):.3f}. "
                 f"Fewest AV-M cells that match q3map2's cost, as a share of its clusters: median "
                 f"{statistics.median([r['cells_to_match'] / r['clusters'] for r in rows if r['cells_to_match']]):.3f}.\n")
tot = {k: sum(r["causes"].get(k, 0) for r in rows) for k in CAUSES}
worst = lambda k: ", ".join(f"{r['map']} {r['causes'][k]:,}" for r in sorted(rows, key=lambda r: -r["causes"].get(k, 0))[:3]
                            if r["causes"].get(k, 0))
lines.append(f"PVS agreement: our samples see a median {statistics.median([r['pvs_ratio'] for r in rows]):.3f} of what "
             f"q3map2's cluster PVS admits (q3map2's is conservative: portal flow through structural brushes, whole "
             f"clusters, every surface of every leaf; ours is sampled). Objects we see from a cluster that q3map2 "
             f"excludes, {sum(r['excluded'] for r in rows):,} (cluster, object) pairs over all maps, each with the "
             f"first evaluation segment that saw it and its cause (docs/quake3.md): {tot['crack']:,} crack (through "
             f"a drawn brush side: cracks between triangles; {worst('crack')}), {tot['invisible']:,} invisible "
             f"(through a brush side that is not drawn; {worst('invisible')}), {tot['void']:,} void (through solid "
             f"space no brush fills; {worst('void')}), {tot['unlisted']:,} unlisted (seen inside a cluster q3map2 "
             f"admits, but the surface is not listed in that cluster's leaves; {worst('unlisted')}), {tot['far']:,} "
             f"far (beyond the map's _farplanedist; {worst('far')}), {tot['rejected']:,} rejected (a line of sight "
             f"through non-solid space that q3map2's PVS rejects; {worst('rejected')}). The pairs are in "
             f"out/maps/MAP/excluded.csv.\n")
qb = sum(r["q3_bytes"] for r in rows)
ql = sum(r["q3_leaf_bytes"] for r in rows)
ob = sum(r["ours_bytes"] for r in rows)
orle = sum(r["ours_rle"] for r in rows)
lines.append(f"Storage over all maps at q3map2's cell counts: q3map2's uncompressed cluster rows {qb:,} B (plus "
             f"{ql:,} B of leaf surface lists a renderer needs to turn clusters into surfaces); our hierarchy-"
             f"compressed object lists {ob:,} B ({ob / qb:.2f} x the rows; as flat Quake-style RLE object rows "
             f"{orle:,} B).\n")
lines.append(f"Time: building (AV-S and merging) took {sum(r['build_s'] for r in rows):.0f} s over all maps "
             f"(median {statistics.median([r['build_s'] for r in rows]):.1f} s), sampling "
             f"{sum(r['sampling_s'] for r in rows):.0f} s, whole runs {sum(r['wall_s'] for r in rows):.0f} s.\n")
if failed:
    lines.append("Failed: " + "; ".join(f"{n} ({e})" for n, e in failed) + "\n")
lines.append("Per map in docs/results/q3-maps.csv.\n")
open("docs/results/q3-maps.md", "w").write("\n".join(lines))
PY
echo "scripts/maps-table.sh $samples $eval_samples" > docs/results/q3-maps.command
python3 scripts/replace-section.py docs/results.md q3maps "$(cat docs/results/q3-maps.command)" docs/results/q3-maps.md
echo "maps: docs/results.md (section q3maps), docs/results/q3-maps.csv"
