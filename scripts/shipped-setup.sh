# Sourced by maps-shipped.sh and maps-shipped-leaf.sh: the Release build (bench-setup.sh), the
# maps, and the bake that fits a byte budget.
source "$(dirname "${BASH_SOURCE[0]}")/bench-setup.sh"
bash scripts/fetch-maps.sh >/dev/null
# shipped_fit MAP DIR BUDGET NAME WHAT: bakes the most cells of MAP whose compressed PVS lists fit
# BUDGET bytes (`bake --memory BUDGET --memory-of lists`, PIXEL_ERROR and SECONDS from $err and
# $secs, seed 1) to DIR/NAME.pvs and measures it with the play cameras (DIR/NAME.json), unless
# DIR/NAME.json exists. WHAT names the budget in the line it prints; more arguments go to bake.
shipped_fit() {
  local map="$1" d="$2" budget="$3" name="$4" what="$5"
  shift 5
  [ -f "$d/$name.json" ] && return 0
  if "$vc" bake "$map" --memory "$budget" --memory-of lists --pixel-error "$err" --agvs-time "$secs" --seed 1 "$@" \
       -o "$d/$name.pvs" --report "$d/$name-bake.json" -q 2>> "$d/err" &&
     "$vc" measure "$map" "$d/$name.pvs" --count 5000 --width 64 --height 48 --report "$d/$name.json" -q 2>> "$d/err"; then
    echo "shipped: $(basename "$d"): lists fit $what ($budget bytes) at $(python3 scripts/vctables.py get "$d/$name.json" cells) cells, ours / q3map2 $(python3 scripts/vctables.py shipped-ratio "$d" "$name")"
  else
    echo "shipped: $(basename "$d"): no cut fits $what ($budget bytes): $(tail -1 "$d/err")"
  fi
}
