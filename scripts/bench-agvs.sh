#!/usr/bin/env bash
# Global visibility sampling benchmark (issue: AGVS): AGVS, SGVS and REF computing the PVSs of
# the same view cells for the same time, their convergence curves (mean PVS size and
# estimated pixel error against time), and how much sooner AGVS reaches the mean PVS size
# the others reach at the end. Writes docs/agvs/*.png and the agvs section of BENCHMARKS.md.
# Usage: scripts/bench-agvs.sh [KIND] [SIZE] [CELLS] [SECONDS]   (defaults: office-sealed 4 500 60; KIND office-sealed is the office generated with --sealed)
set -euo pipefail
kind="${1:-office-sealed}"
size="${2:-4}"
cells="${3:-500}"
seconds="${4:-60}"
source "$(dirname "$0")/bench-setup.sh"
scene=$(bench_scene "$kind" "$size")
out="$dir/agvs-$kind$size"
mkdir -p "$out" docs/agvs
"$vc" build "$scene" --samples 500000 --max-cells $((4 * cells)) --seed 1 -q -o "$out/level.vcells"
for m in agvs sgvs ref; do
  "$vc" pvs "$out/level.vcells" --scene "$scene" --cells "$cells" --time "$seconds" --method "$m" --seed 1 -q \
    -o "$out/$m.pvs" --report "$out/$m.json" --measure-cameras 100 --measure-size 512
done
python3 - "$out" "$kind" "$size" "$cells" "$seconds" <<'PY' > "$out/table.md"
import json, sys
out, kind, size, cells, seconds = sys.argv[1:6]
r = {m: json.load(open(f"{out}/{m}.json")) for m in ("agvs", "sgvs", "ref")}
for m in r:
    with open(f"{out}/{m}.dat", "w") as f:
        for p in r[m]["curve"]:
            err = p["pixel_error"] if p["pixel_error"] is not None else float("nan")
            bound = p["pixel_error_bound"] if p.get("pixel_error_bound") is not None else float("nan")
            f.write(f"{p['seconds']} {p['mean_pvs_size']} {err} {bound}\n")
def time_to(m, target):
    for p in r[m]["curve"]:
        if p["mean_pvs_size"] >= target:
            return p["seconds"]
    return None
print(f"The {kind} of size {size} (seed 1): {cells} view cells cut from a merge history of AV-S cells, each method "
      f"given {seconds} s; threads = 2. Mean PVS size reached, and the time AGVS needs to reach what the others "
      f"reach at the end (the speed-up is their time over AGVS's).\n")
print("| method | samples | rays | mean PVS at the end | estimated pixel error | measured pixel error | "
      "AGVS reaches this mean PVS after | speed-up of AGVS |")
print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
for m in ("agvs", "sgvs", "ref"):
    final = r[m]["mean_pvs_size"]
    t = time_to("agvs", final)
    est = r[m]["estimated_pixel_error"]
    bound = r[m].get("pixel_error_bound")
    meas = r[m]["measured_pixel_error"]["pixels"] if r[m]["measured_pixel_error"] else None
    speed = r[m]["seconds"] / t if t and m != "agvs" else None
    print(f"| {m.upper()} | {r[m]['samples']:,} | {r[m]['rays']:,} | {final:.2f} | "
          f"{(f'< {bound:.2f}' if bound is not None else 'n/a') if est is None else f'{est:.2f}'} | {'n/a' if meas is None else f'{meas:.2f}'} | "
          f"{'not reached' if t is None else f'{t:.2f} s'} | {'' if speed is None else f'{speed:.1f} x'} |")
print(f"\nMeasured pixel error: 100 random cameras of 512x512 (90 degrees), wrong pixels scaled to 1024x1024. "
      f"'< x': no wrong camera ray in the estimator's history, so no window is full; the error is below x with "
      f"probability 0.9. Dashed in the plot.\n")
print(f"\n![mean PVS](docs/agvs/{kind}{size}-pvs.png) ![pixel error](docs/agvs/{kind}{size}-error.png)\n")
PY
gnuplot <<GP
set terminal pngcairo size 800,500
set output "docs/agvs/$kind$size-pvs.png"
set title "Mean PVS size against time: $kind $size, $cells cells"
set xlabel "seconds"; set ylabel "mean PVS size (objects)"; set logscale x; set key bottom right
plot "$out/agvs.dat" using 1:2 with lines lw 2 title "AGVS", "$out/sgvs.dat" using 1:2 with lines lw 2 title "SGVS", "$out/ref.dat" using 1:2 with lines lw 2 title "REF"
set output "docs/agvs/$kind$size-error.png"
set title "Estimated pixel error (of 1024x1024) against time"
set ylabel "pixels"; set logscale y
plot "$out/agvs.dat" using 1:3 with lines lw 2 lc 1 title "AGVS", "$out/sgvs.dat" using 1:3 with lines lw 2 lc 2 title "SGVS", "$out/ref.dat" using 1:3 with lines lw 2 lc 3 title "REF", \
     "$out/agvs.dat" using 1:4 with lines lw 1 lc 1 dt 2 title "AGVS bound", "$out/sgvs.dat" using 1:4 with lines lw 1 lc 2 dt 2 notitle, "$out/ref.dat" using 1:4 with lines lw 1 lc 3 dt 2 notitle
GP
python3 scripts/replace-section.py BENCHMARKS.md agvs "scripts/bench-agvs.sh $kind $size $cells $seconds" "$out/table.md"
cat "$out/table.md"
