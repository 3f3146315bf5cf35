#!/usr/bin/env bash
# A glTF level bakes like its map (issue 68): for each map, the map (.bsp, its own play space) and
# its glTF conversion (viewcells convert --start-points: meshes and spawn nodes, nothing else of
# the BSP; the play space found from the floors) are baked with the same command and budget, and
# both files are measured by the same cameras: the map's play cameras (player eyes above its
# reachable floors), written by the first measure (--cameras-out) and read by the second
# (--cameras-from, turned from metres into the level's units).
# Usage: scripts/play-space-bakes.sh MAP...   Env: VC, OUT (out/play/bakes), CELLS (300),
# CAMERAS (300), SIZE (1024x768), BAKE_ARGS (extra bake options, e.g. "--time 120").
set -euo pipefail
cd "$(dirname "$0")/.."
VC="${VC:-build/cli/viewcells}"
OUT="${OUT:-out/play/bakes}"
CELLS="${CELLS:-300}"
CAMERAS="${CAMERAS:-300}"
SIZE="${SIZE:-1024x768}"
W="${SIZE%x*}"; H="${SIZE#*x}"
mkdir -p "$OUT"
echo "| map | cost per frame, .glb / .bsp | frames with a wrong pixel, .bsp | .glb | bake s, .bsp | .glb |"
echo "| --- | ---: | ---: | ---: | ---: | ---: |"
for m in "$@"; do
  map="data/maps/bsp/$m.bsp"
  "$VC" convert "$map" -o "$OUT/$m.glb" --start-points -q
  s0=$(date +%s.%N)
  "$VC" bake "$map" --cells "$CELLS" -o "$OUT/$m-bsp.pvs" --report "$OUT/$m-bsp.json" -q ${BAKE_ARGS:-}
  s1=$(date +%s.%N)
  "$VC" bake "$OUT/$m.glb" --cells "$CELLS" -o "$OUT/$m-glb.pvs" --report "$OUT/$m-glb.json" -q ${BAKE_ARGS:-}
  s2=$(date +%s.%N)
  "$VC" measure "$map" "$OUT/$m-bsp.pvs" --count "$CAMERAS" --width "$W" --height "$H" --cameras-out "$OUT/$m-cams.json" \
    --report "$OUT/$m-bsp-m.json" -q
  "$VC" measure "$OUT/$m.glb" "$OUT/$m-glb.pvs" --cameras-from "$OUT/$m-cams.json" --width "$W" --height "$H" \
    --report "$OUT/$m-glb-m.json" -q
  python3 - "$OUT/$m" "$m" "$s0" "$s1" "$s2" <<'PY'
import json, sys
base, m, s0, s1, s2 = sys.argv[1], sys.argv[2], *map(float, sys.argv[3:])
b = json.load(open(base + "-bsp-m.json")); g = json.load(open(base + "-glb-m.json"))
share = lambda r: 100 * r["pixel_error"]["frames_with_wrong_pixels_share"]
print(f"| {m} | {g['frame']['cost'] / b['frame']['cost']:.3f} | {share(b):.1f}% | {share(g):.1f}% | {s1 - s0:.0f} | {s2 - s1:.0f} |")
PY
done
