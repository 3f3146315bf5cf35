#!/usr/bin/env bash
# The method comparison of the paper's section 6.3 on the generated office, rotated office,
# city (a street grid) and town (not a grid) at full size: every method built from the same construction samples and scored on
# independent evaluation samples (EVAL_SAMPLES a set, default 16x the construction samples, another
# seed; two such sets, to show the evaluator's own noise; the paper draws 4x, which flatters the
# sample-driven methods: docs/accuracy-vs-time.md). Writes docs/results.md and the
# plots in docs/results/. Usage: scripts/results.sh [CELLS] [SAMPLES] [CITY_SIZE] [EVAL_SAMPLES]
set -euo pipefail
cells="${1:-5000}"
samples="${2:-1000000}"
size="${3:-23}"
eval_samples="${4:-$((16 * samples))}"
source "$(dirname "$0")/bench-setup.sh"
office=$(bench_scene office 4)
rotated=$(bench_scene rotated-office 4)
city=$(bench_scene city "$size")
town=$(bench_scene town "$size")
mkdir -p docs/results
# RESULTS_REUSE=1 keeps comparisons already in out/bench (to redo only the tables).
# The town twice: its whole bounding box (mostly sky, where every cell sees much of the town) and
# its streets at eye level (z from 0.5 to 4 m; viewpoints inside buildings are empty space).
ext=$((size * 76 + 16))
for name in office rotated-office city town town-street; do
  if [ "${RESULTS_REUSE:-0}" = 1 ] && [ -f "$dir/compare-$name/summary.json" ]; then continue; fi
  case "$name" in
    office) scene="$office" ;;
    rotated-office) scene="$rotated" ;;
    city) scene="$city" ;;
    town | town-street) scene="$town" ;;
  esac
  box=()
  [ "$name" = town-street ] && box=(--view-box "0,0,0.5,$ext,$ext,4")
  "$vc" compare "$scene" --samples "$samples" --seed 1 --max-cells "$cells" --eval-sets 2 \
    --eval-samples "$eval_samples" "${box[@]}" \
    -o "$dir/compare-$name" -q
  bash scripts/plot-compare.sh "$dir/compare-$name" "$name" >/dev/null
  for plot in cost ratio histogram; do cp "$dir/compare-$name/$plot.png" "docs/results/$name-$plot.png"; done
  cp "$dir/compare-$name/curves.csv" "docs/results/$name-curves.csv"
  cp "$dir/compare-$name/summary.json" "docs/results/$name-summary.json"
done
python3 scripts/vctables.py results "$dir" "$cells" "$samples" "$size" "$eval_samples" > docs/results.md
# The Quake 3 sections are scripts/maps-shipped.sh's and scripts/maps-table.sh's; keep what they
# last wrote.
cat >> docs/results.md <<'EOF_SHIPPED'

## As shipped: q3map2's PVS against a bake

What a player's frames draw and get wrong with the PVS each side ships, measured by the same
cameras (`viewcells measure`; see [docs/quake3.md](quake3.md#as-shipped)). The section below
this one compares partitions (q3map2's clusters scored with our sampled PVSs); this one
compares the products.

<!-- q3shipped:begin -->
Not generated yet: run scripts/maps-shipped.sh.
<!-- q3shipped:end -->
EOF_SHIPPED
# The shipped tables' subsections (scripts/maps-shipped-leaf.sh), each where its table exists.
shipped_sections=(
  "|q3shipped"
  "leaf|q3shippedleaf|Within q3map2's rows and leaf surface lists"
  "play|q3shippedplay|With --play-space"
  "play-check|q3shippedplaycheck|--play-space where the default already met the goal"
  "play-all|q3shippedplayall|One bake setting on every map: --play-space within q3map2's rows and leaf surface lists"
)
for entry in "${shipped_sections[@]}"; do
  IFS='|' read -r kind section title <<<"$entry"
  base=docs/results/q3-shipped${kind:+-$kind}
  [ -f "$base.md" ] && [ -f "$base.command" ] || continue
  [ -n "$title" ] && printf '\n### %s\n\n<!-- %s:begin -->\n<!-- %s:end -->\n' "$title" "$section" "$section" >> docs/results.md
  python3 scripts/vctables.py replace-section docs/results.md "$section" "$(cat "$base.command")" "$base.md"
done
printf '\n## Real game levels: OpenArena maps against q3map2\n\n<!-- q3maps:begin -->\nNot generated yet: run scripts/maps-table.sh.\n<!-- q3maps:end -->\n' >> docs/results.md
if [ -f docs/results/q3-maps.md ] && [ -f docs/results/q3-maps.command ]; then
  python3 scripts/vctables.py replace-section docs/results.md q3maps "$(cat docs/results/q3-maps.command)" docs/results/q3-maps.md
fi
echo "results: docs/results.md"
