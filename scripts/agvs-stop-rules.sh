#!/usr/bin/env bash
# AGVS stopped by its estimated pixel error (`pvs --pixel-error E`) against stopped by a
# measured one (`pvs --measured-error E`: the PVSs measured after one batch and at every
# doubling of the samples, by the same 5,000 cameras of 32x32 pixels), on the office and the
# city (500 cells, to 1 wrong pixel per 1024x1024 frame) and on the map aggressor (q3map2's
# cluster count, to 10 pixels). Every run ends measured by those cameras; both have a limit of
# LIMIT seconds of the solver's own clock. Writes the table into docs/agvs.md.
# Usage: scripts/agvs-stop-rules.sh [LIMIT]
set -euo pipefail
limit="${1:-120}"
source "$(dirname "$0")/bench-setup.sh"
bash scripts/fetch-maps.sh >/dev/null
out="$dir/agvs-stop-rules"
mkdir -p "$out"
table="$out/table.md"
{
  echo "Each run computes the PVSs of the same view cells (AGVS, seed 1, 2 threads) until its rule holds or"
  echo "$limit s of the solver's own clock pass; all are measured by the same 5,000 cameras of 32x32"
  echo "pixels (errors in wrong pixels per 1024x1024 frame, mean over the cameras): the estimated rule's"
  echo "once at the end, the measured rule's after one batch and at every doubling of the samples, its"
  echo "last measurement being the end's. Measuring is not in the solver's seconds; the wall column has"
  echo "it (and loading the scene)."
  echo
  echo "| scene | cells | rule | stopped by | samples | solver s | wall s | measurements | measured error at the end |"
  echo "| --- | ---: | --- | --- | ---: | ---: | ---: | ---: | ---: |"
} >"$table"
run_scene() {  # NAME SCENE CELLS ERROR
  local name="$1" scene="$2" cells="$3" err="$4" d="$out/$1"
  mkdir -p "$d"
  [ -f "$d/level.vcells" ] || bench_level "$scene" "$cells" "$d"
  local common=(pvs "$d/level.vcells" --scene "$scene" --cells "$cells" --time "$limit" --seed 1 -q
    --measure-cameras 5000 --measure-size 32)
  local start
  for rule in estimated measured; do
    start=$(date +%s.%N)
    if [ "$rule" = estimated ]; then
      "$vc" "${common[@]}" --pixel-error "$err" -o "$d/$rule.pvs" --report "$d/$rule.json"
    else
      "$vc" "${common[@]}" --measured-error "$err" -o "$d/$rule.pvs" --report "$d/$rule.json"
    fi
    python3 scripts/vctables.py elapsed "$start" >"$d/$rule.wall"
    jq -r --arg name "$name" --arg cells "$cells" --arg rule "$rule ($err px)" --arg wall "$(cat "$d/$rule.wall")" \
      '"| \($name) | \($cells) | \($rule) | \(.stop_reason) | \(.samples) | \(.seconds * 100 | round / 100) | \($wall) | \([(.measured_curve | length), 1] | max) | \(.measured_pixel_error.pixels * 100 | round / 100) |"' \
      "$d/$rule.json" >>"$table"
  done
  echo "agvs-stop-rules: $name done" >&2
}
run_scene office4 "$(bench_scene office 4)" 500 1
run_scene city5 "$(bench_scene city 5)" 500 1
"$vc" info data/maps/bsp/aggressor.bsp --json "$out/aggressor.info.json" >/dev/null
run_scene aggressor data/maps/bsp/aggressor.bsp "$(python3 scripts/vctables.py get "$out/aggressor.info.json" quake3 clusters)" 10
python3 scripts/vctables.py replace-section docs/agvs.md stop-rules "scripts/agvs-stop-rules.sh $limit" "$table"
cat "$table"
