#!/usr/bin/env bash
# A glTF level bakes like its map (issue 68): for each map, the map (.bsp, its own play space) and
# its glTF conversion (viewcells convert: surfaces and sky as meshes, nothing else of the BSP; the
# play space found from the floors), once with the spawn points as nodes (--start-points) and
# once without (every floor region of 4 m^2 is a start), are baked with the same command and
# budget, and every file is measured by the same cameras: the map's play cameras (player eyes
# above its reachable floors), written by the first measure (--cameras-out) and read by the
# others (--cameras-from, turned from metres into the level's units).
# Usage: scripts/play-space-bakes.sh MAP...   Env: VC, OUT (out/play/bakes), CELLS (300),
# CAMERAS (300), SIZE (1024x768), BAKE_ARGS (extra bake options).
set -euo pipefail
cd "$(dirname "$0")/.."
VC="${VC:-build/cli/viewcells}"
OUT="${OUT:-out/play/bakes}"
CELLS="${CELLS:-300}"
CAMERAS="${CAMERAS:-300}"
SIZE="${SIZE:-1024x768}"
W="${SIZE%x*}"; H="${SIZE#*x}"
mkdir -p "$OUT"
echo "| map | frames with a wrong pixel, .bsp | cost per frame, .glb with spawn nodes / .bsp | frames with a wrong pixel | cost, .glb with no start points / .bsp | frames with a wrong pixel |"
echo "| --- | ---: | ---: | ---: | ---: | ---: |"
for m in "$@"; do
  map="data/maps/bsp/$m.bsp"
  "$VC" convert "$map" -o "$OUT/$m-spawns.glb" --start-points -q
  "$VC" convert "$map" -o "$OUT/$m-regions.glb" -q
  "$VC" bake "$map" --cells "$CELLS" -o "$OUT/$m-bsp.pvs" --report "$OUT/$m-bsp.json" -q ${BAKE_ARGS:-}
  "$VC" measure "$map" "$OUT/$m-bsp.pvs" --count "$CAMERAS" --width "$W" --height "$H" --cameras-out "$OUT/$m-cams.json" \
    --report "$OUT/$m-bsp-m.json" -q
  for v in spawns regions; do
    "$VC" bake "$OUT/$m-$v.glb" --cells "$CELLS" -o "$OUT/$m-$v.pvs" --report "$OUT/$m-$v.json" -q ${BAKE_ARGS:-}
    "$VC" measure "$OUT/$m-$v.glb" "$OUT/$m-$v.pvs" --cameras-from "$OUT/$m-cams.json" --width "$W" --height "$H" \
      --report "$OUT/$m-$v-m.json" -q
  done
  python3 - "$OUT/$m" "$m" <<'PY'
import json, sys
base, m = sys.argv[1], sys.argv[2]
r = {k: json.load(open(f"{base}-{k}-m.json")) for k in ("bsp", "spawns", "regions")}
share = lambda k: f"{100 * r[k]['pixel_error']['frames_with_wrong_pixels_share']:.1f}%"
ratio = lambda k: f"{r[k]['frame']['cost'] / r['bsp']['frame']['cost']:.3f}"
print(f"| {m} | {share('bsp')} | {ratio('spawns')} | {share('spawns')} | {ratio('regions')} | {share('regions')} |")
PY
done
