# The web viewer's frame time in headless Chromium (Debian's chromium, software WebGL on
# SwiftShader: these machines have no GPU), on the 1M-triangle city (size 23) and the office
# (size 4): each is baked (500 view cells; 500,000 construction samples, 2,000 cells merged on
# them, PVSs by 2M AGVS samples), written by `viewcells view`, opened at 1280x720 and turned about
# its centre for SECONDS; on the city also from a street-level camera turning on the spot and
# following its own cell, drawing everything and drawing only the cell's PVS; some at half
# resolution (the panel's choice). Also the time from a click to the lit PVS.
# Prints one JSON line per run and a Markdown table for BENCHMARKS.md.
# Usage: scripts/bench.sh viewer [SECONDS]
source scripts/bench-setup.sh
seconds="${1:-20}"
out="$dir/viewer"
mkdir -p "$out"
rows=()
for spec in city:23 office:4; do
  kind=${spec%%:*} size=${spec##*:}
  scene=$(bench_scene "$kind" "$size")
  pvs="$out/$kind$size.pvs"
  [ -f "$pvs" ] || "$vc" -q bake "$scene" --cells 500 --samples 500000 --max-cells 2000 --merge-pvs samples \
    --agvs-samples 2000000 --seed 1 -o "$pvs"
  "$vc" -q view "$pvs" --scene "$scene" -o "$out/$kind$size-site"
  tris=$("$vc" info "$scene" | awk '/^triangles:/ {print $2}')
  # Street level (city only): 1.7 m above a street between blocks (the generator's blocks are
  # 60 m with 16 m streets), looking along it.
  street="camera=388,420,1.7&target=388,440,1.7&spin=eye"
  views=("cells=all")
  [ "$kind" = city ] && views+=("cells=all&scale=0.5" "$street&cells=none&follow=1&draw=all"
                                "$street&cells=none&follow=1&draw=pvs" "$street&cells=none&follow=1&draw=pvs&scale=0.5")
  for settings in "${views[@]}"; do
    line=$(node web/test/bench_viewer.mjs "$out/$kind$size-site/index.html" "$seconds" 1280x720 "$settings")
    echo "$line"
    rows+=("$kind $size|$tris|$settings|$line")
  done
done
echo
echo "| scene | triangles | view | frame time, median (p95) | click to lit PVS |"
echo "| --- | --- | --- | --- | --- |"
for r in "${rows[@]}"; do
  IFS='|' read -r name tris settings line <<<"$r"
  view="from above, all cells shown"
  [[ $settings == *draw=all* ]] && view="street level, following its cell, drawing everything"
  [[ $settings == *draw=pvs* ]] && view="street level, following its cell, drawing only its PVS"
  [[ $settings == *scale=0.5* ]] && view="$view, half resolution"
  med=$(jq -r .frame_ms_median <<<"$line") p95=$(jq -r .frame_ms_p95 <<<"$line") click=$(jq -r .click_ms_median <<<"$line")
  printf '| %s | %s | %s | %s ms (%s ms) | %s ms |\n' "$name" "$tris" "$view" "$med" "$p95" "$click"
done
