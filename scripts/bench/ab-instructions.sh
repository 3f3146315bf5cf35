# Instructions the subdivision executes, an earlier commit against the current tree, counted by
# callgrind (valgrind): a count does not drift with the machine's speed as wall-clock time does
# here (up to 1.6x over an hour), so it tells a change of work from noise. Runs the city,
# SEGMENTS segments to CELLS cells (no stagnation stop, no merge, one thread, fast candidate
# positions), once per build under callgrind (about 50 times slower than without), and prints the
# instructions of the whole run, of the subdivision (Builder::run) and of the candidate
# evaluations, each new / old, and the final construction costs (which must match for the same
# work). The old commit is built (Release) in a git worktree under out/ab/, as bench.sh ab does.
# Usage: scripts/bench.sh ab-instructions OLD_COMMIT [CITY_SIZE] [SEGMENTS] [CELLS]
size="${2:-23}"
segments="${3:-200000}"
cells="${4:-5000}"
source scripts/bench-setup.sh  # builds the current tree (Release), sets $vc and $dir
city=$(bench_scene city "$size")
bench_ab_binaries "$old"
for side in old new; do
  valgrind --tool=callgrind --callgrind-out-file="$dir/ab-ir-$side.out" "${bin[$side]}" -q --threads 1 build "$city" \
    --segments "$segments" --max-cells "$cells" --min-reduction 0 --seed 1 --no-merge \
    --report "$dir/ab-ir-$side.json" 2>"$dir/ab-ir-$side.log"
  callgrind_annotate --inclusive=yes "$dir/ab-ir-$side.out" >"$dir/ab-ir-$side.txt" 2>/dev/null
done
python3 - "$dir" "$sha" "$size" "$segments" "$cells" <<'PY'
import json, re, sys
d, sha, size, segments, cells = sys.argv[1:]
def counts(side):
    text = open(f"{d}/ab-ir-{side}.txt").read()
    total = int(re.search(r"^([\d,]+) \(100\.0+%\)\s+PROGRAM TOTALS", text, re.M).group(1).replace(",", ""))
    def fn(pattern):
        m = re.search(r"^\s*([\d,]+) \([\d.]+%\)\s+\S*" + pattern, text, re.M)
        return int(m.group(1).replace(",", "")) if m else 0
    run = fn(r"viewcells::\(anonymous namespace\)::Builder::run\(\) ")
    # The parallel loops of Builder::run: the one that evaluates a round's children is the larger.
    loops = sorted((int(m.group(1).replace(",", "")) for m in re.finditer(
        r"^\s*([\d,]+) \([\d.]+%\)\s+\S*tbb::.*Builder::run\(\)::\{lambda", text, re.M)), reverse=True)
    cost = json.load(open(f"{d}/ab-ir-{side}.json"))["subdivision"]["final_cost"]
    return total, run, loops[:2], cost
o, n = counts("old"), counts("new")
print(f"City size {size}, {int(segments):,} segments to {int(cells):,} cells, one thread, under callgrind; "
      f"old = {sha}, new = the current tree.")
print(f"| instructions | old | new | new / old |\n| --- | ---: | ---: | ---: |")
print(f"| whole run | {o[0]:,} | {n[0]:,} | {n[0] / o[0]:.4f} |")
print(f"| subdivision (Builder::run) | {o[1]:,} | {n[1]:,} | {n[1] / o[1]:.4f} |")
for i, name in enumerate(("largest parallel loop of the subdivision", "second largest")):
    if i < len(o[2]) and i < len(n[2]):
        print(f"| {name} | {o[2][i]:,} | {n[2][i]:,} | {n[2][i] / o[2][i]:.4f} |")
print(f"Final construction cost: old {o[3]:,.0f}, new {n[3]:,.0f}" + (" (the same)" if o[3] == n[3] else " (DIFFERENT)"))
PY
