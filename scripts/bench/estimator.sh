# The pixel error estimator against the measured pixel error (issue: AGVS, deliverable 6):
# one computation per method, stopped at doubling sample counts (saved and resumed, which
# continues exactly), and at each stop the estimate (equation 5's window) next to the error
# measured by rendering random cameras. Writes docs/agvs/estimator-*.png and the estimator
# section of BENCHMARKS.md.
# Usage: scripts/bench.sh estimator [KIND] [SIZE] [CELLS] [MAX_SAMPLES] [CAMERAS] [CAMERA_SIZE]
#        (defaults: office 4 500 64000000 20000 32)
kind="${1:-office}"
size="${2:-4}"
cells="${3:-500}"
max_samples="${4:-64000000}"
cameras="${5:-20000}"
camera_size="${6:-32}"
source scripts/bench-setup.sh
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
python3 scripts/vctables.py estimator "$out" "$kind" "$size" "$cells" "$max_samples" "$cameras" "$camera_size" > "$out/table.md"
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
python3 scripts/vctables.py replace-section BENCHMARKS.md "estimator-$kind$size" \
  "scripts/bench.sh estimator $kind $size $cells $max_samples $cameras $camera_size" "$out/table.md"
cat "$out/table.md"
