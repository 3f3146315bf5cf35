#!/usr/bin/env bash
# The conservative mode on OpenArena maps (issue 65): a bake of 300 view cells (300,000
# construction samples, 1M AGVS samples, no near-object samples: the conservative sets hardly
# depend on sampling) with --conservative, measured by CAMERAS (default 1000, the issue's goal)
# play cameras of 1024x768 (seed 7), and the map's own PVS (q3map2's) measured by the same
# cameras. Prints a Markdown table.
# Usage: scripts/conservative-maps.sh MAP:HALF ...   (e.g. oa_dm2:tuning aggressor:held-out)
# The halves are those of scripts/near-samples.sh (alphabetical position 4k+2, 4k+3: tuning).
set -euo pipefail
cd "$(dirname "$0")/.."
vc="${VIEWCELLS:-build/cli/viewcells}"
out=out/bench/conservative
cameras="${CAMERAS:-1000}"
# --proof-steps: 200,000 for the first table of docs/conservative.md (bake's default is now 2M);
# another value bakes files of its own (NAME-sSTEPS).
steps="${PROOF_STEPS:-200000}"
mkdir -p "$out"
for arg in "$@"; do
  name="${arg%%:*}"
  map="data/maps/bsp/$name.bsp"
  m="$name"
  [ "$steps" = 200000 ] || m="$name-s$steps"
  if [ ! -f "$out/$m-cons.pvs" ]; then
    start=$(date +%s.%N)
    "$vc" -q bake "$map" --cells 300 --samples 300000 --agvs-samples 1000000 --near-samples 0 --seed 1 \
      --proof-steps "$steps" --conservative -o "$out/$m-cons.pvs" --report "$out/$m-cons-bake.json"
    python3 -c "import time; print(round(time.time() - $start, 1))" > "$out/$m-cons.secs"
  fi
  [ -f "$out/$m-cons-m$cameras.json" ] ||
    "$vc" -q measure "$map" "$out/$m-cons.pvs" --count "$cameras" --seed 7 --report "$out/$m-cons-m$cameras.json"
  [ -f "$out/$name-q3-m$cameras.json" ] ||
    "$vc" -q measure "$map" --count "$cameras" --seed 7 --report "$out/$name-q3-m$cameras.json"
done
python3 - "$out" "$cameras" "$steps" "$@" <<'PY'
import json, sys
out, cams, steps = sys.argv[1], sys.argv[2], sys.argv[3]
print("| map | half | conservative / q3map2 cost per frame | frames with a wrong pixel, conservative | q3map2 | worst frame (px per 1024^2) | pairs proven visible / hidden / undecided | seen by rays, proven hidden | cost bounds (visible, with undecided; by volume) | floods over budget | proof s | bake s |")
print("|---|---|---:|---:|---:|---:|---|---:|---|---:|---:|---:|")
for name, half in [a.split(":") for a in sys.argv[4:]]:
    m = name if steps == "200000" else f"{name}-s{steps}"
    b = json.load(open(f"{out}/{m}-cons-bake.json")); h = b["hidden"]
    c = json.load(open(f"{out}/{m}-cons-m{cams}.json")); q = json.load(open(f"{out}/{name}-q3-m{cams}.json"))
    pe, qe, n = c["pixel_error"], q["pixel_error"], c["cameras"]["count"]
    p, cb = h["pairs"], h["cost_per_frame"]
    secs = open(f"{out}/{m}-cons.secs").read().strip()
    print(f'| {name} | {half} | {c["frame"]["cost"] / q["frame"]["cost"]:.3f} | {pe["cameras_with_wrong_pixels"]} of {n} | '
          f'{qe["cameras_with_wrong_pixels"]} of {n} | {pe["worst_pixels"]:.0f} | {p["proven_visible"]} / {p["proven_hidden"]} / '
          f'{p["undecided"]} | {h["seen_but_proven_hidden"]} | {cb["proven_visible"]:.0f}, {cb["with_undecided"]:.0f} | '
          f'{h["floods_over_budget"]} of {h["floods"]} | {h["seconds"]:.0f} | {secs} |')
PY
