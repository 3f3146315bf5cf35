#!/usr/bin/env bash
# What accuracy costs in time, with the proof (issue 65): on each MAP, bakes of 300 view cells
# (300,000 construction samples, seed 1) bounded by `--time T` for every T of TIMES (default
# "30 120 600" seconds), in the default mode (`--prove-hidden`: the sampled PVSs are written,
# the proof only reports its classes) and in the conservative mode (`--conservative`), every
# file measured by the same 300 play cameras of 1024x768 (seed 7). Everything else is bake's
# default (AGVS to the time left, near-object samples). Prints a Markdown table: both cost
# bounds from the bake's own report, the measured cost per frame and frames with a wrong pixel
# of the file it wrote, and its seconds. Resumable: files already in out/bench/hidden-time
# are kept.
# Usage: [TIMES="30 120 600"] [VIEWCELLS=path] scripts/hidden-vs-time.sh MAP:HALF ...
set -euo pipefail
cd "$(dirname "$0")/.."
vc="${VIEWCELLS:-build/cli/viewcells}"
out=out/bench/hidden-time
times="${TIMES:-30 120 600}"
mkdir -p "$out"
for arg in "$@"; do
  name="${arg%%:*}"
  map="data/maps/bsp/$name.bsp"
  [ -f "$out/$name-q3-m300.json" ] ||
    "$vc" -q measure "$map" --count 300 --seed 7 --report "$out/$name-q3-m300.json"
  for t in $times; do
    for mode in default conservative; do
      f="$out/$name-$mode-$t"
      flag=--prove-hidden
      [ "$mode" = conservative ] && flag=--conservative
      if [ ! -f "$f.secs" ]; then
        echo "hidden-vs-time: $name $mode --time $t" >&2
        start=$(date +%s.%N)
        "$vc" -q bake "$map" --cells 300 --samples 300000 --seed 1 --time "$t" "$flag" \
          -o "$f.pvs" --report "$f-bake.json"
        python3 -c "import time; print(round(time.time() - $start, 1))" > "$f.secs"
      fi
      [ -f "$f-m300.json" ] || "$vc" -q measure "$map" "$f.pvs" --count 300 --seed 7 --report "$f-m300.json"
    done
  done
done
python3 - "$out" "$times" "$@" <<'PY'
import json, sys
out, times = sys.argv[1], sys.argv[2].split()
print("| map | half | --time s | mode | bake s | cost bounds per frame (proven visible, with undecided; by volume) | undecided pairs | floods over budget | measured cost / q3map2's | frames with a wrong pixel | 99th pct / worst wrong px per 1024^2 |")
print("|---|---|---:|---|---:|---|---:|---:|---:|---:|---|")
for name, half in [a.split(":") for a in sys.argv[3:]]:
    q = json.load(open(f"{out}/{name}-q3-m300.json"))
    for t in times:
        for mode in ("default", "conservative"):
            f = f"{out}/{name}-{mode}-{t}"
            b = json.load(open(f + "-bake.json")); h = b["hidden"]; m = json.load(open(f + "-m300.json"))
            pe, n = m["pixel_error"], m["cameras"]["count"]
            cb = h["cost_per_frame"]
            p99 = pe.get("p99_pixels", float("nan"))
            print(f'| {name} | {half} | {t} | {mode} | {open(f + ".secs").read().strip()} | '
                  f'{cb["proven_visible"]:.0f}, {cb["with_undecided"]:.0f} | {h["pairs"]["undecided"]} | '
                  f'{h["floods_over_budget"]} of {h["floods"]} | {m["frame"]["cost"] / q["frame"]["cost"]:.3f} | '
                  f'{pe["cameras_with_wrong_pixels"]} of {n} | {p99:.0f} / {pe["worst_pixels"]:.0f} |')
PY
