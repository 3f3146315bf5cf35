#!/usr/bin/env bash
# Global visibility sampling benchmark (issue: AGVS): AGVS, SGVS and REF computing the PVSs of
# the same view cells for the same time, their convergence curves (mean PVS size and
# estimated pixel error against time), and how much sooner AGVS reaches the mean PVS size
# the others reach at the end. Writes docs/agvs/*.png and the agvs section of BENCHMARKS.md.
# Usage: scripts/bench-agvs.sh [KIND] [SIZE] [CELLS] [SECONDS]   (defaults: office 4 500 60)
set -euo pipefail
kind="${1:-office}"
size="${2:-4}"
cells="${3:-500}"
seconds="${4:-60}"
source "$(dirname "$0")/bench-setup.sh"
scene=$(bench_scene "$kind" "$size")
out="$dir/agvs-$kind$size"
mkdir -p docs/agvs
bench_level "$scene" "$cells" "$out"
# SGVS and REF first: AGVS's curve then also counts how much of their final PVSs it has found.
for m in sgvs ref agvs; do
  refs=()
  [ "$m" = agvs ] && refs=(--reference "$out/sgvs.pvs" --reference "$out/ref.pvs")
  "$vc" pvs "$out/level.vcells" --scene "$scene" --cells "$cells" --time "$seconds" --method "$m" --seed 1 -q \
    "${refs[@]}" -o "$out/$m.pvs" --report "$out/$m.json" --measure-cameras 20000 --measure-size 32
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
def first_time(m, ok):
    for p in r[m]["curve"]:
        if ok(p):
            return p["seconds"]
    return None
def fmt_t(t):
    return "not reached" if t is None else f"{t:.2f} s"
print(f"The {kind} of size {size} (seed 1): {cells} view cells cut from a merge history of AV-S cells, each method "
      f"given {seconds} s; threads = 2.\n")
print("By mean PVS size (the acceptance test): the time AGVS needs to reach the mean PVS size each method reaches "
      "at the end; the speed-up is that method's time over AGVS's.\n")
print("| method | samples | rays | mean PVS at the end | estimated pixel error | measured pixel error | "
      "AGVS reaches this mean PVS after | speed-up of AGVS |")
print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
for m in ("agvs", "sgvs", "ref"):
    final = r[m]["mean_pvs_size"]
    t = first_time("agvs", lambda p: p["mean_pvs_size"] >= final)
    est = r[m]["estimated_pixel_error"]
    bound = r[m].get("pixel_error_bound")
    meas = r[m]["measured_pixel_error"]["pixels"] if r[m]["measured_pixel_error"] else None
    speed = r[m]["seconds"] / t if t and m != "agvs" else None
    print(f"| {m.upper()} | {r[m]['samples']:,} | {r[m]['rays']:,} | {final:.2f} | "
          f"{(f'< {bound:.2f}' if bound is not None else 'n/a') if est is None else f'{est:.2f}'} | "
          f"{'n/a' if meas is None else f'{meas:.2f}'} | {fmt_t(t)} | {'' if speed is None else f'{speed:.1f} x'} |")
print("\nBy the entries themselves (robust to entries only AGVS finds): the time each method needs to find 95% of its "
      "own final PVS entries, and the time AGVS needs to find 95% of that method's final entries.\n")
print("| method | final entries | AGVS has of them at the end | method finds 95% of them after | "
      "AGVS finds 95% of them after | speed-up of AGVS |")
print("| --- | ---: | ---: | ---: | ---: | ---: |")
for k, m in enumerate(("sgvs", "ref")):
    entries = r[m]["pvs_entries"]
    own = first_time(m, lambda p: p["mean_pvs_size"] * int(cells) >= 0.95 * entries - 1e-9)
    agvs = first_time("agvs", lambda p: p["covered"][k] >= 0.95 * entries)
    have = r["agvs"]["curve"][-1]["covered"][k] / entries
    speed = own / agvs if own and agvs else None
    print(f"| {m.upper()} | {entries:,} | {100 * have:.1f}% | {fmt_t(own)} | {fmt_t(agvs)} | "
          f"{'' if speed is None else f'{speed:.1f} x'} |")
print(f"\nMeasured pixel error: 20,000 random cameras of 32x32 (90 degrees; wrong pixels come in clusters, so many "
      f"small cameras measure better than few large ones), wrong pixels scaled to 1024x1024. '< x': too few wrong "
      f"camera rays in the newer half of the run for equation 5's window; the error is below x with probability "
      f"0.9. Dashed in the plot.\n")
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
python3 scripts/replace-section.py BENCHMARKS.md "agvs-$kind$size" "scripts/bench-agvs.sh $kind $size $cells $seconds" "$out/table.md"
cat "$out/table.md"
