#!/usr/bin/env bash
# Near-object samples (issue: no holes that players see): on OpenArena maps, a bake of 300 view
# cells (300,000 construction samples, 5M AGVS samples, the play space: bake's default on a
# map) without and with --near-samples, and q3map2's own PVS, all measured by the same 300 play
# cameras of 1024x768 (seed 7; the bakes' cameras and viewpoints draw from seeds of their own).
# The maps are split in two fixed halves by alphabetical position: the tuning half (positions
# 4k+2 and 4k+3, which holds oa_dm2 and oa_thor, where the sampler's settings were chosen) and
# the held-out half (the others). Resumable: what a map already has in out/bench/near-samples
# is kept, with the commit its executable was built from (out/bench/near-samples/commit-HALF; the
# table names it). NEAR_TABLE_ONLY=1 bakes nothing more and writes the table of the maps done
# so far. Writes the section "nearsamples-HALF" of docs/accuracy-vs-time.md.
# Usage: scripts/near-samples.sh tuning|held-out [K EYES ROUNDS]   (defaults 2048 512 4, bake's own)
set -euo pipefail
half="${1:?tuning or held-out}"
k="${2:-2048}"
eyes="${3:-512}"
rounds="${4:-4}"
source "$(dirname "$0")/bench-setup.sh"
vc="${NEAR_VIEWCELLS:-$vc}"  # a copy of the executable, so that a rebuild during the run changes nothing
out="$dir/near-samples"
mkdir -p "$out"
all=(data/maps/bsp/*.bsp)
maps=()
for i in "${!all[@]}"; do
  m=$(basename "${all[$i]}" .bsp)
  case "$half" in
    tuning) ((i % 4 >= 2)) && maps+=("$m") ;;
    held-out) ((i % 4 < 2)) && maps+=("$m") ;;
    *) echo "near-samples: the half is tuning or held-out, not '$half'" >&2; exit 2 ;;
  esac
done
common=(--cells 300 --samples 300000 --agvs-samples 5000000 --seed 1)
[ -f "$out/commit-$half" ] || git rev-parse --short HEAD > "$out/commit-$half"
timed_bake() {  # OUT.pvs JSON SECONDS_FILE ARGS...
  local pvs=$1 json=$2 secs=$3
  shift 3
  [ -f "$pvs" ] && [ -f "$secs" ] && return 0
  local start
  start=$(date +%s.%N)
  "$vc" -q bake "$@" -o "$pvs" --report "$json"
  python3 -c "import time; print(round(time.time() - $start, 1))" > "$secs"
}
rows=()
for m in "${maps[@]}"; do
  map="data/maps/bsp/$m.bsp"
  if [ -n "${NEAR_TABLE_ONLY:-}" ]; then
    [ -f "$out/$m-q3map2-m.json" ] && [ -f "$out/$m-near$k-$eyes-$rounds-m.json" ] && rows+=("$m")
    continue
  fi
  echo "near-samples: $m" >&2
  timed_bake "$out/$m-base.pvs" "$out/$m-base-bake.json" "$out/$m-base.secs" "$map" "${common[@]}" --near-samples 0
  timed_bake "$out/$m-near$k-$eyes-$rounds.pvs" "$out/$m-near$k-$eyes-$rounds-bake.json" \
    "$out/$m-near$k-$eyes-$rounds.secs" "$map" "${common[@]}" --near-samples "$k" --near-eyes "$eyes" --near-rounds "$rounds"
  for side in base "near$k-$eyes-$rounds"; do
    [ -f "$out/$m-$side-m.json" ] || "$vc" -q measure "$map" "$out/$m-$side.pvs" --count 300 --seed 7 --report "$out/$m-$side-m.json"
  done
  [ -f "$out/$m-q3map2-m.json" ] || "$vc" -q measure "$map" --count 300 --seed 7 --report "$out/$m-q3map2-m.json"
  rows+=("$m")
done
python3 - "$out" "$half" "$k-$eyes-$rounds" "$(cat "$out/commit-$half")" "${#maps[@]}" "${rows[@]}" > "$out/table-$half.md" <<'PY'
import datetime, json, statistics, sys
out, half, setting, commit, planned, maps = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4], int(sys.argv[5]), sys.argv[6:]
k, eyes, rounds = setting.split("-")
load = lambda m, side: json.load(open(f"{out}/{m}-{side}-m.json"))
secs = lambda m, side: float(open(f"{out}/{m}-{side}.secs").read())
done = f"{len(maps)} maps" if len(maps) == planned else f"{len(maps)} of its {planned} maps: the run was stopped there"
print(f"{datetime.date.today()}, commit {commit}, 2 threads; the {half} half ({done}). Each map baked with "
      f"`viewcells bake MAP --cells 300 --samples 300000 --agvs-samples 5000000 --seed 1 --near-samples 0` (base) and the same with "
      f"`--near-samples {k} --near-eyes {eyes} --near-rounds {rounds}` (near), measured with q3map2's own PVS by "
      "`viewcells measure MAP [PVS] --count 300 --seed 7` (player eyes, 1024x768, 90 degrees). Holes: the share of "
      "frames with any wrong pixel (q3map2's is 0 on every map); wrong pixels per 1024x1024 frame; cost: r(PVS) per "
      "frame over q3map2's.\n")
print("| map | cost base | cost near | holes base | holes near | mean base | mean near | p99 near | worst near | bake base (s) | bake near (s) |")
print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
rows = []
for m in maps:
    q3 = load(m, "q3map2")["frame"]["cost"]
    b, n = load(m, "base"), load(m, f"near{setting}")
    r = dict(cost_b=b["frame"]["cost"] / q3, cost_n=n["frame"]["cost"] / q3,
             holes_b=b["pixel_error"]["frames_with_wrong_pixels_share"], holes_n=n["pixel_error"]["frames_with_wrong_pixels_share"],
             mean_b=b["pixel_error"]["pixels"], mean_n=n["pixel_error"]["pixels"], p99_n=n["pixel_error"]["p99_pixels"],
             worst_n=n["pixel_error"]["worst_pixels"], t_b=secs(m, "base"), t_n=secs(m, f"near{setting}"))
    rows.append(r)
    print(f"| {m} | {r['cost_b']:.3f} | {r['cost_n']:.3f} | {100 * r['holes_b']:.1f}% | {100 * r['holes_n']:.1f}% | "
          f"{r['mean_b']:.2f} | {r['mean_n']:.2f} | {r['p99_n']:.0f} | {r['worst_n']:.0f} | {r['t_b']:.0f} | {r['t_n']:.0f} |")
med = lambda key: statistics.median(r[key] for r in rows)
count = lambda f: sum(1 for r in rows if f(r))
print(f"| **median** | {med('cost_b'):.3f} | {med('cost_n'):.3f} | {100 * med('holes_b'):.1f}% | {100 * med('holes_n'):.1f}% | "
      f"{med('mean_b'):.2f} | {med('mean_n'):.2f} | {med('p99_n'):.0f} | {med('worst_n'):.0f} | {med('t_b'):.0f} | {med('t_n'):.0f} |")
n = len(rows)
print(f"\nOf {n} maps, base / near: holes at most 1% on {count(lambda r: r['holes_b'] <= 0.01)} / "
      f"{count(lambda r: r['holes_n'] <= 0.01)}, at most 5% on {count(lambda r: r['holes_b'] <= 0.05)} / "
      f"{count(lambda r: r['holes_n'] <= 0.05)}; mean at most 1 wrong pixel on {count(lambda r: r['mean_b'] <= 1)} / "
      f"{count(lambda r: r['mean_n'] <= 1)}; cost at most 0.5 of q3map2's on {count(lambda r: r['cost_b'] <= 0.5)} / "
      f"{count(lambda r: r['cost_n'] <= 0.5)}; all three (holes at most 1%, mean at most 1, cost at most 0.5) on "
      f"{count(lambda r: r['holes_b'] <= 0.01 and r['mean_b'] <= 1 and r['cost_b'] <= 0.5)} / "
      f"{count(lambda r: r['holes_n'] <= 0.01 and r['mean_n'] <= 1 and r['cost_n'] <= 0.5)}. With 300 cameras a share "
      "of 1% is 3 frames; its standard error there is about 0.6 points.")
PY
python3 scripts/vctables.py replace-section docs/accuracy-vs-time.md "nearsamples-$half" \
  "scripts/near-samples.sh $half $k $eyes $rounds" "$out/table-$half.md"
cat "$out/table-$half.md"
