#!/usr/bin/env bash
# Installs dependencies, builds, and runs the pipeline on the built-in default scene (a
# generated two-storey office): first in one command (bake: 100 view cells, PVSs by AGVS to a
# pixel error of 5), then stage by stage to show what each makes: visibility sampling, view
# space subdivision into 2000 cells and merging, 100 view cells cut from the merge history,
# their PVSs compressed into a .pvs file, then computed again by adaptive global visibility
# sampling (AGVS, 20 s, with the measured pixel error), and a viewpoint looked up in it.
# Coloured cell mesh and slice images; the baked cells as a web page (out/demo/site/index.html,
# open it in a browser) and as glTF (out/demo/office-cells.glb, for Blender or an engine).
# Outputs: out/demo/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh build-release Release -DVIEWCELLS_BUILD_TESTS=OFF
vc=build-release/cli/viewcells
out=out/demo
mkdir -p "$out"
"$vc" generate office --size 4 --seed 1 -o "$out/office.obj"
"$vc" info "$out/office.obj" --json "$out/office-info.json"
"$vc" bake "$out/office.obj" --cells 100 --pixel-error 5 --max-cells 400 --seed 1 -o "$out/office-baked.pvs" \
  --report "$out/bake.json"
"$vc" query "$out/office-baked.pvs" 3 12 1.5 | head -n 3
"$vc" build "$out/office.obj" --samples 1000000 --seed 1 --max-cells 2000 -o "$out/office.vcells" \
  --report "$out/build-report.json" --mesh "$out/cells.ply" --slice-png "$out/slice.png" --slice-z 1.5
"$vc" extract "$out/office.vcells" --count 100 -o "$out/view-cells.json" \
  --slice-png "$out/view-cells.png" --slice-z 1.5 --scene "$out/office.obj"
"$vc" compress "$out/office.vcells" --count 100 -o "$out/office.pvs" --flat "$out/office.vflt" \
  --report "$out/compress-report.json"
"$vc" pvs "$out/office.vcells" --scene "$out/office.obj" --cells 100 --time 20 --seed 1 -o "$out/office-agvs.pvs" \
  --report "$out/pvs-report.json" --measure-cameras 5000 --measure-size 32 --save "$out/office.vagvs"
"$vc" query "$out/office-agvs.pvs" 3 12 1.5 | head -n 8
"$vc" view "$out/office-baked.pvs" --scene "$out/office.obj" -o "$out/site" --gltf "$out/office-cells.glb"
echo
echo "demo: baked in one command: $out/office-baked.pvs ($out/bake.json)"
echo "      scene $out/office.obj; hierarchy $out/office.vcells (look at $out/slice.png, $out/cells.ply);"
echo "      100 view cells $out/view-cells.json ($out/view-cells.png); PVS from the construction samples"
echo "      $out/office.pvs, by AGVS $out/office-agvs.pvs (continue with --resume $out/office.vagvs);"
echo "      what was enabled and why, costs and timings: $out/build-report.json, $out/compress-report.json,"
echo "      $out/pvs-report.json"
echo "      look at the baked cells and what each sees: open $out/site/index.html in a browser (no server"
echo "      needed; click a surface), or $out/office-cells.glb in Blender"
