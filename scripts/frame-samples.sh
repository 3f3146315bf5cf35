#!/usr/bin/env bash
# Frames as a sampler (issue: no holes that players see): on MAPS, bakes of 300 view cells
# (300,000 construction samples, 5M AGVS samples, play space) without and with --frame-samples
# at several counts and frame sizes, each measured by 300 play cameras of 1024x768 from seed 7
# (never the bake's: the sampling cameras draw from their own seed); the last setting spends
# the frames of 64 a cell in four rounds of 16, each after the first only in the cells whose
# frames still added an object (--frame-rounds). Writes the section
# "framesamples" of docs/accuracy-vs-time.md. Near-object samples (bake's default since) are
# left out: this measures frames as a sampler alone.
# Usage: scripts/frame-samples.sh [MAP...]   (default oa_dm2 oa_thor)
set -euo pipefail
source "$(dirname "$0")/bench-setup.sh"
maps=("$@")
[ ${#maps[@]} -gt 0 ] || maps=(oa_dm2 oa_thor)
out="$dir/frame-samples"
mkdir -p "$out"
rows=()
for map in "${maps[@]}"; do
  for spec in "0 256x192 1" "16 256x192 1" "64 256x192 1" "16 1024x768 1" "16 256x192 4"; do
    read -r fs size rounds <<<"$spec"
    tag="$map-$fs-$size-$rounds"
    start=$(date +%s.%N)
    "$vc" -q bake "data/maps/bsp/$map.bsp" --cells 300 --samples 300000 --agvs-samples 5000000 --seed 1 \
      --frame-samples "$fs" --frame-size "$size" --frame-rounds "$rounds" --near-samples 0 -o "$out/$tag.pvs" --report "$out/$tag-bake.json"
    seconds=$(python3 -c "import time; print(round(time.time() - $start, 1))")
    "$vc" -q measure "data/maps/bsp/$map.bsp" "$out/$tag.pvs" --count 300 --seed 7 --report "$out/$tag-m.json"
    rows+=("$map" "$fs" "$size" "$rounds" "$seconds" "$out/$tag-bake.json" "$out/$tag-m.json")
  done
done
python3 - "$(git rev-parse --short HEAD)" "${rows[@]}" > "$out/table.md" <<'PY'
import datetime, json, sys
commit, rest = sys.argv[1], sys.argv[2:]
print(f"{datetime.date.today()}, commit {commit}, 2 threads. Each map baked with `viewcells bake MAP --cells 300 --samples "
      "300000 --agvs-samples 5000000 --frame-samples K --frame-size WxH --frame-rounds R` (the play space, bake's default on a map), "
      "measured by `viewcells measure MAP PVS --count 300 --seed 7` (player eyes, 1024x768). K = 0 is AGVS alone. "
      "Holes: the share of frames with any wrong pixel; errors per 1024x1024 frame; cost: r(PVS) per frame.\n")
print("| map | frame samples per cell | frame size | rounds | bake (s) | frames with a hole | mean wrong pixels | 99th percentile | worst | cost per frame | PVS entries the frames added |")
print("| --- | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
for i in range(0, len(rest), 7):
    m, fs, size, rounds, seconds, bake, meas = rest[i:i + 7]
    b, r = json.load(open(bake)), json.load(open(meas))
    e = r["pixel_error"]
    added = b["effects"]["frame_samples"]["reason"].split(" added ")[1].split(" ")[0] if int(fs) else "-"
    print(f"| {m} | {fs} | {size} | {rounds} | {seconds} | {100 * e['frames_with_wrong_pixels_share']:.1f}% | {e['pixels']:.1f} | "
          f"{e['p99_pixels']:.0f} | {e['worst_pixels']:.0f} | {r['frame']['cost']:.0f} | {added} |")
PY
python3 scripts/vctables.py replace-section docs/accuracy-vs-time.md framesamples "scripts/frame-samples.sh ${maps[*]}" \
  "$out/table.md"
cat "$out/table.md"
