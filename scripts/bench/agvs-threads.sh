# AGVS on one and two threads (issue 58): the city of size 23 (seed 1) cut into 500, 5,000 and
# 50,000 view cells (one merge history of 50,000 AV-S cells from 4M construction samples), `pvs`
# with 1M samples in batches of 20,000, seed 1, the default single mutation lane and LANES
# lanes; one and two threads alternating, RUNS rounds. Prints the medians, the speed-up, and per
# phase (the report's phases) its speed-up and the serial share Amdahl's law gives from it,
# s = 2 t2 / t1 - 1, as a share of the whole run on one thread. Also checks that one and two
# threads wrote the same .pvs.
# Usage: scripts/bench.sh agvs-threads [RUNS] [LANES]   (default 3 rounds, 64 lanes)
runs="${1:-3}"
lanes="${2:-64}"
source scripts/bench-setup.sh
scene=$(bench_scene city 23)
out="$dir/agvs-threads"
mkdir -p "$out"
level=$(bench_city_cells 4000000 50000)
lines="$out/runs.jsonl"
: >"$lines"
for r in $(seq "$runs"); do
  for cells in 500 5000 50000; do
    for l in 1 "$lanes"; do
      for t in 1 2; do
        "$vc" --threads "$t" -q pvs "$level" --scene "$scene" --cells "$cells" --samples 1000000 \
          --batch 20000 --seed 1 --mutation-lanes "$l" -o "$out/$cells-$l-$t.pvs" --report "$out/run.json"
        jq -c --argjson c "$cells" --argjson l "$l" --argjson t "$t" \
          '{cells: $c, lanes: $l, threads: $t, seconds: .seconds, phases: .phases}' "$out/run.json" >>"$lines"
      done
      cmp -s "$out/$cells-$l-1.pvs" "$out/$cells-$l-2.pvs" || { echo "bench-agvs-threads: 1 and 2 threads differ" >&2; exit 1; }
    done
  done
  echo "bench-agvs-threads: round $r of $runs done" >&2
done
python3 - "$lines" "$runs" "$lanes" <<'PY'
import json, statistics, sys, subprocess
path, runs, lanes = sys.argv[1], sys.argv[2], sys.argv[3]
rows = [json.loads(l) for l in open(path)]
commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
date = subprocess.run(["date", "+%Y-%m-%d"], capture_output=True, text=True).stdout.strip()
cpu = subprocess.run(["sh", "-c", "grep -m1 'model name' /proc/cpuinfo | cut -d: -f2"], capture_output=True, text=True).stdout.strip()
print(f"Command: `scripts/bench.sh agvs-threads {runs} {lanes}`\n")
print(f"{date}, commit {commit}, {cpu}, 2 cores. City of size 23, 1M AGVS samples in batches of 20,000, seed 1; "
      f"medians of {runs} alternating runs. Phases: planning the batch (draw), the mutation lanes, drawing and casting "
      "the stationary samples (cast), applying; serial: Amdahl's s = 2 t2 / t1 - 1 of the phase, as a share of the "
      "whole one-thread run (negative: within noise of none).\n")
phases = [("mutation_seconds", "mutations"), ("cast_seconds", "draw and cast"), ("apply_seconds", "apply")]
print("| cells | lanes | 1 thread s | 2 threads s | speed-up | " + " | ".join(f"{n}: 1 / 2 threads s, serial" for _, n in phases) + " |")
print("| ---: | ---: | ---: | ---: | ---: | " + " | ".join("---:" for _ in phases) + " |")
for cells in (500, 5000, 50000):
    for l in (1, int(lanes)):
        sel = {t: [r for r in rows if r["cells"] == cells and r["lanes"] == l and r["threads"] == t] for t in (1, 2)}
        med = lambda t, f: statistics.median(f(r) for r in sel[t])
        t1, t2 = med(1, lambda r: r["seconds"]), med(2, lambda r: r["seconds"])
        cols = []
        for key, _ in phases:
            p1, p2 = med(1, lambda r: r["phases"][key]), med(2, lambda r: r["phases"][key])
            serial = (2 * p2 / p1 - 1) * p1 / t1 if p1 > 0 else 0
            cols.append(f"{p1:.2f} / {p2:.2f}, {100 * serial:.1f}%")
        print(f"| {cells:,} | {l} | {t1:.2f} | {t2:.2f} | {t1 / t2:.2f}x | " + " | ".join(cols) + " |")
PY
