#!/usr/bin/env bash
# Plots what `viewcells compare ... -o DIR` wrote, with gnuplot (Debian's gnuplot-nox, which
# scripts/install-deps.sh installs): DIR/cost.png (evaluated render cost against the number of
# cells), DIR/ratio.png (each method's cost over AV-M's at equal cell counts) and
# DIR/histogram.png (share of the view space volume by render cost, at the histogram's cell
# count, as the paper's figure 9). Usage: scripts/plot-compare.sh DIR [TITLE]
set -euo pipefail
dir="$1"
title="${2:-$(basename "$dir")}"
[ -f "$dir/curves.csv" ] || { echo "plot-compare: $dir/curves.csv not found (run viewcells compare first)" >&2; exit 1; }
command -v gnuplot >/dev/null || { echo "plot-compare: gnuplot is missing (bash scripts/install-deps.sh)" >&2; exit 1; }
methods=$(python3 "$(dirname "$0")/vctables.py" compare-methods "$dir/curves.csv")
# Volume-weighted histograms of the cells' render cost, 24 common bins.
python3 "$(dirname "$0")/vctables.py" compare-histogram "$dir"
gnuplot <<GP
set datafile separator ","
set terminal pngcairo size 900,600 font ",11"
set key outside right
set grid
set logscale x
set xlabel "view cells"
set output "$dir/cost.png"
set title "$title: evaluated render cost"
set ylabel "expected render cost c(S)"
plot for [m in "$methods"] "$dir/curves.csv" using 2:(strcol(1) eq m ? \$3 : NaN) every ::1 with linespoints pt 7 ps 0.5 title m
set output "$dir/ratio.png"
set title "$title: render cost / AV-M's at equal cell counts"
set ylabel "cost ratio to AV-M"
plot for [m in "$methods"] "$dir/curves.csv" using 2:(strcol(1) eq m && strlen(strcol(4)) > 0 ? \$4 : NaN) every ::1 with linespoints pt 7 ps 0.5 title m
GP
if [ -s "$dir/histogram.dat" ]; then
  gnuplot <<GP
set terminal pngcairo size 900,600 font ",11"
set output "$dir/histogram.png"
set title "$title: share of the view space by render cost"
set xlabel "render cost of the cell r(PVS)"
set ylabel "share of the view space volume"
set key outside right
set grid
set style data histogram
set style histogram clustered gap 1
set style fill solid 0.8 border -1
set xtics rotate by -45
plot for [i=2:$(($(echo $methods | wc -w) + 1))] "$dir/histogram.dat" using i:xtic(sprintf("%.0f", column(1))) title columnheader(i)
GP
fi
echo "plot-compare: $dir/cost.png $dir/ratio.png $dir/histogram.png"
