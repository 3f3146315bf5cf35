# Sampling benchmark (issue: foundation): a generated city of >= 1M triangles, 1M segments,
# segments per second against half the raw Embree rays per second measured in the same run.
# Five runs per configuration by default; the table shows medians. Rewrites the sampling section of
# BENCHMARKS.md. Usage: scripts/bench.sh sampling [CITY_SIZE] [RUNS]
size="${1:-23}"
runs="${2:-5}"
bench_cmake_args="-DVIEWCELLS_BUILD_BENCH=ON"
source scripts/bench-setup.sh
scene=$(bench_scene city "$size")
# The street band: the whole footprint, from the ground to 30 m (where people and cars are).
bounds=$("$vc" info "$scene" --json "$dir/info.json" >/dev/null && python3 scripts/vctables.py street-band "$dir/info.json")

declare -A box=([scene-bounds]="" [street-band]="--view-box $bounds")
for name in scene-bounds street-band; do
  for r in $(seq 1 "$runs"); do
    # shellcheck disable=SC2086
    "$vc" sample "$scene" --segments 1000000 --seed "$r" --measure-raw -q ${box[$name]} \
      --report "$dir/sample-$name-$r.json"
  done
done

python3 scripts/vctables.py sampling "$dir" "$runs" "$size" > "$dir/sampling-table.md"

python3 scripts/vctables.py replace-section BENCHMARKS.md sampling "scripts/bench.sh sampling $size $runs" "$dir/sampling-table.md"
cat "$dir/sampling-table.md"
