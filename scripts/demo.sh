#!/usr/bin/env bash
# Installs dependencies, builds, and runs the pipeline on the built-in default scene (a
# generated two-storey office): visibility sampling and view space subdivision into 2000 cells,
# with a coloured cell mesh and a slice image. Outputs go to out/demo/. Later stages extend it.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh build-release Release -DVIEWCELLS_BUILD_TESTS=OFF
vc=build-release/cli/viewcells
out=out/demo
mkdir -p "$out"
"$vc" generate office --size 4 --seed 1 -o "$out/office.obj"
"$vc" info "$out/office.obj" --json "$out/office-info.json"
"$vc" build "$out/office.obj" --samples 1000000 --seed 1 --max-cells 2000 -o "$out/office.vcells" \
  --report "$out/build-report.json" --mesh "$out/cells.ply" --slice-png "$out/slice.png" --slice-z 1.5
echo
echo "demo: scene $out/office.obj; cells $out/office.vcells (look at $out/slice.png and $out/cells.ply);"
echo "      what was enabled and why, costs and timings: $out/build-report.json"
