# A/B of AGVS's sample stream against an earlier commit, measured in one run (issue 58: the
# stationary distributions' chunks became Halton index ranges, drawn by the rank that casts
# them). Without a view space (the office, the city) the stream must not change: their .pvs
# files are compared byte for byte. On a map's play space it changes, so quality is compared:
# for each map, 300 view cells cut from one merge history (300,000 construction samples, seed 1,
# built by the new build, used by both), and `pvs --time SECONDS` of each build with seeds 1
# and 2, alternating, measured part-way (`--measure-at`, doubling sample counts) by the same
# 1,000 play cameras of 64x64 pixels, 90 degrees (the measuring cameras' own seed). Prints, per
# map and sample count, each side's seconds and the spread of the measured error (share of
# frames with any wrong pixel, mean wrong pixels per 1024x1024 frame, 99th percentile, worst),
# medians over the seeds, and the seeds' range of the share, which is the noise.
# Usage: scripts/bench.sh ab-agvs-stream OLD_COMMIT [SECONDS] [MAP ...]
#   (default: 20 s; aggressor oa_dm4 kaos, from the held-out half of docs/accuracy-vs-time.md)
seconds="${2:-20}"
shift $(($# >= 2 ? 2 : 1))
maps=("$@")
[ ${#maps[@]} -gt 0 ] || maps=(aggressor oa_dm4 kaos)
source scripts/bench-setup.sh  # builds the current tree (Release), sets $vc and $dir
bash scripts/fetch-maps.sh >/dev/null
bench_ab_binaries "$old"
out="$dir/ab-agvs-stream"
mkdir -p "$out"
at=""
for k in $(seq 0 10); do at="$at $((100000 << k))"; done
# No view space: the same stream, byte for byte.
for kind in office city; do
  scene=$(bench_scene "$kind" 3)
  "$vc" -q build "$scene" --samples 100000 --max-cells 200 --seed 1 -o "$out/$kind.vcells"
  for side in old new; do
    "${bin[$side]}" -q --threads 2 pvs "$out/$kind.vcells" --scene "$scene" --cells 50 --samples 400000 --seed 1 \
      --mutation-lanes 7 -o "$out/$kind-$side.pvs"
  done
  cmp -s "$out/$kind-old.pvs" "$out/$kind-new.pvs" && echo "$kind: byte-identical" || echo "$kind: the .pvs files differ"
done | tee "$out/identity.txt"
for map in "${maps[@]}"; do
  bsp="data/maps/bsp/$map.bsp"
  "$vc" -q build "$bsp" --samples 300000 --max-cells 1200 --seed 1 -o "$out/$map.vcells"
  for seed in 1 2; do
    for side in old new; do
      # shellcheck disable=SC2086
      "${bin[$side]}" -q --threads 2 pvs "$out/$map.vcells" --scene "$bsp" --cells 300 --time "$seconds" --seed "$seed" \
        --measure-cameras 1000 --measure-size 64 --measure-at $at -o "$out/$map-$side-$seed.pvs" \
        --report "$out/$map-$side-$seed.json"
    done
  done
  echo "bench-ab-agvs-stream: $map done" >&2
done
python3 - "$out" "$sha" "$seconds" "${maps[@]}" <<'PY'
import json, statistics, sys, subprocess
out, sha, seconds, maps = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
date = subprocess.run(["date", "+%Y-%m-%d"], capture_output=True, text=True).stdout.strip()
print(f"Command: `scripts/bench.sh ab-agvs-stream {sha} {seconds} {' '.join(maps)}`\n")
print(f"{date}, old {sha} against new {commit} (with its uncommitted changes, if any), 2 threads, one run. "
      + open(f"{out}/identity.txt").read().replace("\n", "; ").rstrip("; ") + ". "
      f"On each map: 300 cells, `pvs --time {seconds}`, seeds 1 and 2, measured by 1,000 play cameras of 64x64 "
      "pixels; medians over the seeds; share range: the two seeds' shares of frames with a hole.\n")
print("| map | samples | old s | new s | old: frames with a hole (range) | new: frames with a hole (range) "
      "| old mean / p99 / worst | new mean / p99 / worst |")
print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
for m in maps:
    curves = {side: [json.load(open(f"{out}/{m}-{side}-{s}.json"))["measured_curve"] for s in (1, 2)]
              for side in ("old", "new")}
    n = min(len(c) for cs in curves.values() for c in cs)
    for i in range(n):
        row = {}
        for side, cs in curves.items():
            pts = [c[i] for c in cs]
            med = lambda k: statistics.median(p[k] for p in pts)
            shares = sorted(100 * p["frames_with_wrong_pixels_share"] for p in pts)
            row[side] = (med("seconds"), f"{med('frames_with_wrong_pixels_share') * 100:.1f}% ({shares[0]:.1f}-{shares[-1]:.1f})",
                         f"{med('measured_pixels'):.2f} / {med('measured_p99_pixels'):.0f} / {med('measured_worst_pixels'):.0f}")
        samples = statistics.median(c[i]["samples"] for c in curves["new"])
        print(f"| {m} | {samples:,.0f} | {row['old'][0]:.2f} | {row['new'][0]:.2f} | {row['old'][1]} | {row['new'][1]} "
              f"| {row['old'][2]} | {row['new'][2]} |")
PY
