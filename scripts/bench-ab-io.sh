#!/usr/bin/env bash
# A/B of reading files against an earlier commit, measured in one run: `info` on the city's
# OBJ (size CITY_SIZE, seed 1) and `extract --count 50` of a hierarchy of the city (1.5M
# segments, 50,000 cells, greedy merging on the construction samples, built once by the current
# build), alternating the old and the new binary RUNS times. Prints each run's wall-clock
# seconds, the medians and new / old, and writes them into the io section of BENCHMARKS.md;
# the last line says whether both sides printed the same. The old commit is built (Release) in
# a git worktree under out/ab/ (as scripts/bench-ab.sh does).
# Usage: scripts/bench-ab-io.sh OLD_COMMIT [RUNS] [CITY_SIZE]
set -euo pipefail
cd "$(dirname "$0")/.."
old="${1:?usage: scripts/bench-ab-io.sh OLD_COMMIT [RUNS] [CITY_SIZE]}"
runs="${2:-5}"
size="${3:-23}"
source scripts/bench-setup.sh  # builds the current tree (Release), sets $vc and $dir
city=$(bench_scene city "$size")
bench_ab_binaries "$old"
hier="$dir/io-city.vcells"
"$vc" -q build "$city" --segments 1500000 --max-cells 50000 --min-reduction 0 --seed 1 --merge-pvs samples -o "$hier"
results="$dir/ab-io.tsv"
: >"$results"
for r in $(seq "$runs"); do
  for side in old new; do
    for what in info extract; do
      if [ "$what" = info ]; then cmd=("${bin[$side]}" -q info "$city"); else
        cmd=("${bin[$side]}" -q extract "$hier" --count 50); fi
      start=$(date +%s.%N)
      "${cmd[@]}" > "$dir/ab-io-$what-$side.out"
      end=$(date +%s.%N)
      echo -e "$side\t$what\t$(python3 -c "print($end - $start)")" >>"$results"
    done
  done
done
same=identical
for what in info extract; do cmp -s "$dir/ab-io-$what-old.out" "$dir/ab-io-$what-new.out" || same=different; done
python3 - "$results" "$sha" "$runs" "$size" "$(stat -c %s "$city")" "$(stat -c %s "$hier")" "$same" > "$dir/ab-io.md" <<'PY'
import statistics, sys
path, sha, runs, size, obj_bytes, hier_bytes, same = sys.argv[1:]
rows = [line.split("\t") for line in open(path).read().split("\n") if line]
print(f"City size {size}: its OBJ ({int(obj_bytes) / 1e6:.0f} MB) and a hierarchy of it (1.5M segments, 50,000 cells, "
      f"greedy merge, {int(hier_bytes) / 1e6:.0f} MB), {runs} alternating runs of the old ({sha}) and the new build.\n")
print("| command | old s | new s | new / old (medians) |")
print("| --- | --- | --- | ---: |")
for what, label in (("info", "`info` on the OBJ"), ("extract", "`extract --count 50` of the hierarchy")):
    t = {s: [float(x[2]) for x in rows if x[0] == s and x[1] == what] for s in ("old", "new")}
    print(f"| {label} | " + ", ".join(f"{x:.2f}" for x in t["old"]) + " | " + ", ".join(f"{x:.2f}" for x in t["new"]) +
          f" | {statistics.median(t['new']) / statistics.median(t['old']):.3f} |")
print(f"\nBoth builds printed {'the same' if same == 'identical' else 'DIFFERENT output'} for each command.")
PY
python3 scripts/vctables.py replace-section BENCHMARKS.md io "scripts/bench-ab-io.sh $sha $runs $size" "$dir/ab-io.md"
cat "$dir/ab-io.md"
