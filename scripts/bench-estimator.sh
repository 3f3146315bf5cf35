#!/usr/bin/env bash
# The pixel error estimator against the measured pixel error (issue: AGVS, deliverable 6):
# one computation per method, stopped at doubling sample counts (saved and resumed, which
# continues exactly), and at each stop the estimate (equation 5's window) next to the error
# measured by rendering random cameras. Writes docs/agvs/estimator-*.png and the estimator
# section of BENCHMARKS.md.
# Usage: scripts/bench-estimator.sh [KIND] [SIZE] [CELLS] [MAX_SAMPLES] [CAMERAS] [CAMERA_SIZE]
#        (defaults: office 4 500 64000000 20000 32)
set -euo pipefail
kind="${1:-office}"
size="${2:-4}"
cells="${3:-500}"
max_samples="${4:-64000000}"
cameras="${5:-20000}"
camera_size="${6:-32}"
source "$(dirname "$0")/bench-setup.sh"
scene=$(bench_scene "$kind" "$size")
out="$dir/estimator-$kind$size"
mkdir -p docs/agvs
bench_level "$scene" "$cells" "$out"
for m in sgvs agvs; do
  state=()
  n=250000
  while [ "$n" -le "$max_samples" ]; do
    "$vc" pvs "$out/level.vcells" --scene "$scene" --cells "$cells" --samples "$n" --method "$m" --seed 1 -q \
      "${state[@]}" --save "$out/$m-$n.state" -o "$out/$m-$n.pvs" --report "$out/$m-$n.json" \
      --measure-cameras "$cameras" --measure-size "$camera_size"
    state=(--resume "$out/$m-$n.state")
    n=$((n * 2))
  done
done
python3 - "$out" "$kind" "$size" "$cells" "$max_samples" "$cameras" "$camera_size" <<'PY' > "$out/table.md"
import glob, json, math, sys
out, kind, size, cells, max_samples, cameras, camera_size = sys.argv[1:8]
rows = {}
for m in ("sgvs", "agvs"):
    runs = sorted((json.load(open(f)) for f in glob.glob(f"{out}/{m}-*.json")), key=lambda r: r["samples"])
    rows[m] = runs
    with open(f"{out}/{m}.dat", "w") as f:
        for r in runs:
            est = r["estimated_pixel_error"]; bound = r.get("pixel_error_bound")
            meas = r["measured_pixel_error"]["pixels"]
            f.write(f"{r['samples']} {est if est is not None else 'nan'} {bound if bound is not None else 'nan'} {meas}\n")
print(f"The {kind} of size {size} (seed 1), {cells} view cells; each method stopped at doubling sample counts "
      f"(saved and resumed). Estimated: equation 5's window (P = 0.9, k = 0.5) of the camera rays (view "
      f"space-direction rays from free space); measured: {cameras} random cameras of {camera_size}x{camera_size} "
      f"(90 degrees) against the PVSs at that point. Both in pixels of a 1024x1024 image. Ratio: estimated over "
      f"measured ('<': too few wrong camera rays in the newer half of the run for a window, the 90% upper bound "
      f"instead).\n")
print("| method | samples | mean PVS | estimated | window (camera rays) | measured | ratio |")
print("| --- | ---: | ---: | ---: | ---: | ---: | ---: |")
within = {}
for m, runs in rows.items():
    for r in runs:
        est = r["estimated_pixel_error"]; bound = r.get("pixel_error_bound")
        meas = r["measured_pixel_error"]["pixels"]
        shown = f"{est:.2f}" if est is not None else (f"< {bound:.2f}" if bound is not None else "n/a")
        ratio = est / meas if est is not None and meas > 0 else None
        if ratio is not None:
            within.setdefault(m, []).append(0.5 <= ratio <= 2)
        print(f"| {m.upper()} | {r['samples']:,} | {r['mean_pvs_size']:.2f} | {shown} | "
              f"{r['estimator_window_rays']:,} | {meas:.2f} | {'' if ratio is None else f'{ratio:.2f}'} |")
print()
for m, w in within.items():
    print(f"- {m.upper()}: the estimate is within a factor of 2 of the measurement at {sum(w)} of {len(w)} stops "
          f"with both known.")
print(f"\n![estimated and measured pixel error](docs/agvs/estimator-{kind}{size}.png)\n")
PY
gnuplot <<GP
set terminal pngcairo size 800,500
set output "docs/agvs/estimator-$kind$size.png"
set title "Pixel error (of 1024x1024): estimated (lines) and measured (points), $kind $size, $cells cells"
set xlabel "samples"; set ylabel "pixels"; set logscale xy; set key top right
plot "$out/sgvs.dat" using 1:2 with linespoints lw 2 lc 2 title "SGVS estimated", \
     "$out/sgvs.dat" using 1:4 with points pt 7 ps 1.5 lc 2 title "SGVS measured", \
     "$out/agvs.dat" using 1:2 with linespoints lw 2 lc 1 title "AGVS estimated", \
     "$out/agvs.dat" using 1:3 with lines lw 1 dt 2 lc 1 title "AGVS bound (no window)", \
     "$out/agvs.dat" using 1:4 with points pt 7 ps 1.5 lc 1 title "AGVS measured"
GP
python3 scripts/replace-section.py BENCHMARKS.md "estimator-$kind$size" \
  "scripts/bench-estimator.sh $kind $size $cells $max_samples $cameras $camera_size" "$out/table.md"
cat "$out/table.md"
