#!/usr/bin/env bash
# Rays aimed at the pairs the proof leaves undecided (bake --aimed-rays, issue 65), in the
# default (not conservative) mode: a bake of 300 view cells with --prove-hidden and 0 or N aimed
# rays per undecided pair, each measured by CAMERAS (default 300) play cameras of 1024x768
# (seed 7). Prints a Markdown table: pairs, rays, pairs found visible, holes, cost.
# Usage: scripts/aimed-rays.sh MAP [RAYS...]   (e.g. q3dm6ish 0 256 4096)
set -euo pipefail
cd "$(dirname "$0")/.."
vc="${VIEWCELLS:-build/cli/viewcells}"
cameras="${CAMERAS:-300}"
m="$1"
shift
rays=("$@")
[ ${#rays[@]} -gt 0 ] || rays=(0 256)
out=out/bench/aimed
mkdir -p "$out"
for n in "${rays[@]}"; do
  [ -f "$out/$m-$n-m$cameras.json" ] && continue
  start=$(date +%s.%N)
  "$vc" -q bake "data/maps/bsp/$m.bsp" --cells 300 --memory-of lists --prove-hidden --aimed-rays "$n" --seed 1 \
    -o "$out/$m-$n.pvs" --report "$out/$m-$n.json"
  python3 -c "import time; print(round(time.time() - $start, 1))" >"$out/$m-$n.secs"
  "$vc" -q measure "data/maps/bsp/$m.bsp" "$out/$m-$n.pvs" --count "$cameras" --seed 7 --report "$out/$m-$n-m$cameras.json"
done
python3 - "$out" "$m" "$cameras" "${rays[@]}" <<'PY'
import json, sys
out, m, cams = sys.argv[1:4]
print("| map | aimed rays per pair | undecided pairs aimed at | rays | found visible | s | frames with a wrong pixel | mean wrong px per 1024^2 | worst frame | cost per frame | bake s |")
print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
for n in sys.argv[4:]:
    b = json.load(open(f"{out}/{m}-{n}.json")); a = b["hidden"]["aimed_rays"]
    e = json.load(open(f"{out}/{m}-{n}-m{cams}.json"))
    pe = e["pixel_error"]
    secs = open(f"{out}/{m}-{n}.secs").read().strip()
    print(f'| {m} | {n} | {a["pairs"]} | {a["rays"]} | {a["found_visible"]} | {a["seconds"]:.1f} | '
          f'{pe["cameras_with_wrong_pixels"]} of {e["cameras"]["count"]} | {pe["pixels"]:.3f} | {pe["worst_pixels"]:.0f} | '
          f'{e["frame"]["cost"]:.0f} | {secs} |')
PY
