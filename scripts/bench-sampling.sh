#!/usr/bin/env bash
# Sampling benchmark (issue: foundation): a generated city of >= 1M triangles, 1M segments,
# segments per second against half the raw Embree rays per second measured in the same run.
# Five runs per configuration by default; the table shows medians. Rewrites the sampling section of
# BENCHMARKS.md. Usage: scripts/bench-sampling.sh [CITY_SIZE] [RUNS]
set -euo pipefail
size="${1:-23}"
runs="${2:-5}"
bench_cmake_args="-DVIEWCELLS_BUILD_BENCH=ON"
source "$(dirname "$0")/bench-setup.sh"
scene=$(bench_scene city "$size")
# The street band: the whole footprint, from the ground to 30 m (where people and cars are).
bounds=$("$vc" info "$scene" --json "$dir/info.json" >/dev/null && python3 -c "
import json; b=json.load(open('$dir/info.json'))['bounds']; print(','.join(str(v) for v in b['min'][:2]+[0.0]+b['max'][:2]+[30.0]))")

declare -A box=([scene-bounds]="" [street-band]="--view-box $bounds")
for name in scene-bounds street-band; do
  for r in $(seq 1 "$runs"); do
    # shellcheck disable=SC2086
    "$vc" sample "$scene" --segments 1000000 --seed "$r" --measure-raw -q ${box[$name]} \
      --report "$dir/sample-$name-$r.json"
  done
done

python3 - "$dir" "$runs" "$size" <<'PY' > "$dir/sampling-table.md"
import json, statistics, sys
d, runs, size = sys.argv[1], int(sys.argv[2]), sys.argv[3]
rows = []
for name in ["scene-bounds", "street-band"]:
    reps = [json.load(open(f"{d}/sample-{name}-{r}.json")) for r in range(1, runs + 1)]
    med = lambda f: statistics.median(f(x) for x in reps)
    t = lambda x: x["timings"]
    c = lambda x: x["counts"]
    half_raw = lambda x: t(x)["raw_rays_per_second"] / 2
    rows.append((name,
                 reps[0]["scene"]["triangles"],
                 med(lambda x: c(x)["valid_segments"]),
                 med(lambda x: c(x)["samples"]),
                 med(lambda x: c(x)["valid_segments"] / c(x)["samples"]),
                 med(lambda x: t(x)["raw_rays_per_second"]) / 1e6,
                 med(lambda x: t(x)["samples_per_second"]) / 1e6,
                 med(lambda x: t(x)["segments_per_second"]) / 1e6,
                 med(lambda x: t(x)["samples_per_second"] / half_raw(x)),
                 med(lambda x: t(x)["segments_per_second"] / half_raw(x)),
                 reps[0]["settings"]["threads"]))
print(f"City size {size}, seed 1; {runs} runs per row (seeds 1..{runs}), medians; threads = {rows[0][10]}.\n")
print("| view space | triangles | segments | samples | valid share | raw Embree Mrays/s | Msamples/s | Msegments/s | samples/s ÷ ½ raw | segments/s ÷ ½ raw |")
print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
for r in rows:
    print(f"| {r[0]} | {r[1]:,} | {r[2]:,.0f} | {r[3]:,.0f} | {r[4]:.3f} | {r[5]:.2f} | {r[6]:.2f} | {r[7]:.2f} | {r[8]:.3f} | {r[9]:.3f} |")
PY

python3 scripts/replace-section.py BENCHMARKS.md sampling "scripts/bench-sampling.sh $size $runs" "$dir/sampling-table.md"
cat "$dir/sampling-table.md"
