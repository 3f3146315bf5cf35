#!/usr/bin/env bash
# What the scene's solid space proves on mesh scenes (issue 65): the generated office, city and
# glass city (size 2), each baked to 50 view cells with --prove-hidden (200,000 construction
# samples, 1M AGVS samples). The proof uses the closed, convex, opaque objects as brushes; the
# report says how many objects qualified. Prints a Markdown table.
# Usage: scripts/hidden-meshes.sh [KIND...]   (default: office city glass-city)
set -euo pipefail
cd "$(dirname "$0")/.."
vc="${VIEWCELLS:-build/cli/viewcells}"
out=out/bench/hidden-meshes
mkdir -p "$out"
kinds=("$@")
[ ${#kinds[@]} -gt 0 ] || kinds=(office city glass-city)
for k in "${kinds[@]}"; do
  [ -f "$out/$k.obj" ] || "$vc" -q generate "$k" --size 2 -o "$out/$k.obj"
  [ -f "$out/$k.json" ] ||
    "$vc" -q bake "$out/$k.obj" --cells 50 --samples 200000 --agvs-samples 1000000 --prove-hidden --seed 1 \
      -o "$out/$k.pvs" --report "$out/$k.json"
done
python3 - "$out" "${kinds[@]}" <<'PY'
import json, sys
out = sys.argv[1]
print("| scene | objects | what proves | pairs proven visible / hidden / undecided | cost bounds (visible, with undecided) | proof s |")
print("|---|---:|---|---|---|---:|")
for k in sys.argv[2:]:
    b = json.load(open(f"{out}/{k}.json")); h = b["hidden"]
    if not h["proved"]:
        print(f'| {k} | {b["objects"]} | nothing: {h["reason"]} | | | |'); continue
    p, c = h["pairs"], h["cost_per_frame"]
    print(f'| {k} | {b["objects"]} | {h["method"]} | {p["proven_visible"]} / {p["proven_hidden"]} / {p["undecided"]} | '
          f'{c["proven_visible"]:.0f}, {c["with_undecided"]:.0f} | {h["seconds"]:.0f} |')
PY
