# Measuring frames (issue: measure at the resolution players play at): primary rays a second at
# 1024x768 cast as coherent 4x4-pixel packets (rtcIntersect16) against the same frames' rays
# cast as incoherent single rays (rtcIntersect1M), both timed by `viewcells measure` in one run
# (its report's cameras.primary_rays_per_second), and the whole measurement's time, on the
# office, the city and two maps (oa_dm2, and oa_thor, the most detailed). Each scene gets a
# small bake to measure. Rewrites the "frames" section of BENCHMARKS.md.
# Usage: scripts/bench.sh frames [FRAMES]   (default 200)
frames="${1:-200}"
source scripts/bench-setup.sh
out="$dir/frames"
mkdir -p "$out"
office=$(bench_scene office 2)
city=$(bench_scene city 8)
rows=()
for scene in "$office" "$city" data/maps/bsp/oa_dm2.bsp data/maps/bsp/oa_thor.bsp; do
  name=$(basename "${scene%.*}")
  [ -f "$out/$name.pvs" ] || "$vc" bake "$scene" --cells 100 --samples 200000 --agvs-samples 1000000 --seed 1 -q \
    -o "$out/$name.pvs"
  "$vc" measure "$scene" "$out/$name.pvs" --count "$frames" --report "$out/$name.json" -q
  rows+=("$name" "$out/$name.json")
done
python3 - "$frames" "$(git rev-parse --short HEAD)" "${rows[@]}" > "$out/table.md" <<'PY'
import json, sys, datetime
frames, commit, rest = sys.argv[1], sys.argv[2], sys.argv[3:]
print(f"{datetime.date.today()}, commit {commit}, 2 threads. Each scene baked with 100 view cells (200,000 construction samples, "
      f"1M AGVS samples), then `viewcells measure SCENE PVS --count {frames}` (1024x768, 90 degrees; on a map player eyes, "
      "elsewhere random points of the view box). Rays a second: the first frames' rays (about 4.7M) cast both ways, "
      "frame by frame, twice each way alternating, the second round timed.\n")
print("| scene | coherent packets (M rays/s) | incoherent (M rays/s) | ratio | whole measurement (s) | frames with a wrong pixel | mean wrong pixels | 99th percentile | worst |")
print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
for name, path in zip(rest[::2], rest[1::2]):
    r = json.load(open(path))
    p = r["cameras"]["primary_rays_per_second"]
    e = r["pixel_error"]
    print(f"| {name} | {p['coherent'] / 1e6:.1f} | {p['incoherent'] / 1e6:.1f} | {p['coherent'] / p['incoherent']:.2f}x | "
          f"{r['seconds']:.1f} | {e['frames_with_wrong_pixels_share'] * 100:.1f}% | {e['pixels']:.1f} | {e['p99_pixels']:.0f} | {e['worst_pixels']:.0f} |")
PY
python3 scripts/vctables.py replace-section BENCHMARKS.md frames "scripts/bench.sh frames $frames" "$out/table.md"
cat "$out/table.md"
