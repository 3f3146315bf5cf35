#!/usr/bin/env bash
# Installs dependencies, builds, and runs the pipeline on the built-in default scene (a
# generated two-storey office). Outputs go to out/demo/. Later stages extend this same command.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh build-release Release -DVIEWCELLS_BUILD_TESTS=OFF
vc=build-release/cli/viewcells
out=out/demo
mkdir -p "$out"
"$vc" generate office --size 4 --seed 1 -o "$out/office.obj"
"$vc" info "$out/office.obj" --json "$out/office-info.json"
"$vc" sample "$out/office.obj" --samples 1000000 --seed 1 -o "$out/office.vseg" --report "$out/sample-report.json"
echo
echo "demo: scene $out/office.obj, segments $out/office.vseg, report $out/sample-report.json"
