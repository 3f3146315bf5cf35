# Global visibility sampling benchmark (issue: AGVS): AGVS, SGVS and REF computing the PVSs of
# the same view cells for the same time, their convergence curves (mean PVS size and
# estimated pixel error against time), and how much sooner AGVS reaches the mean PVS size
# the others reach at the end. Writes docs/agvs/*.png and the agvs section of BENCHMARKS.md.
# Usage: scripts/bench.sh agvs [KIND] [SIZE] [CELLS] [SECONDS]   (defaults: office 4 500 60)
kind="${1:-office}"
size="${2:-4}"
cells="${3:-500}"
seconds="${4:-60}"
source scripts/bench-setup.sh
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
python3 scripts/vctables.py agvs "$out" "$kind" "$size" "$cells" "$seconds" > "$out/table.md"
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
python3 scripts/vctables.py replace-section BENCHMARKS.md "agvs-$kind$size" "scripts/bench.sh agvs $kind $size $cells $seconds" "$out/table.md"
cat "$out/table.md"
