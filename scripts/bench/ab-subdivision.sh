# A/B of the subdivision at the subdivision issue's size, against an earlier commit, measured
# in one run: the city, SEGMENTS segments to CELLS cells (no stagnation stop, no merge, two
# threads, fast candidate positions), alternating the old and the new build RUNS times, so that
# the machine's drift over an hour (up to 1.6x here) falls on both alike. Prints each run's
# subdivision seconds and final construction cost, the medians and their ratio new / old; the
# old commit is built (Release) in a git worktree under out/ab/ (as scripts/bench.sh ab does).
# With map:NAME for CITY_SIZE, the OpenArena map data/maps/bsp/NAME.bsp instead (as the
# subdivision table's map row: SEGMENTS construction samples, default 300,000, to CELLS cells,
# default 1,500, the default stagnation stop, geometry-aligned candidates as auto decides).
# Each side writes its cells; the last line says whether the two builds' .vcells are
# byte-identical (the same tree). Commits before f2ea46e (such as 6f655e9, the build the
# subdivision issue's 149 s came from) need libopenmesh-dev to build, which install-deps.sh no
# longer installs: `apt-get install libopenmesh-dev` first.
# Usage: scripts/bench.sh ab-subdivision OLD_COMMIT [RUNS] [CITY_SIZE | map:NAME] [SEGMENTS] [CELLS]
runs="${2:-3}"
size="${3:-23}"
source scripts/bench-setup.sh  # builds the current tree (Release), sets $vc and $dir
if [[ "$size" == map:* ]]; then
  segments="${4:-300000}"
  cells="${5:-1500}"
  scene="data/maps/bsp/${size#map:}.bsp"
  bash scripts/fetch-maps.sh >/dev/null
  what=(--samples "$segments")
else
  segments="${4:-1500000}"
  cells="${5:-50000}"
  scene=$(bench_scene city "$size")
  what=(--segments "$segments" --min-reduction 0)
fi
bench_ab_binaries "$old"
results="$dir/ab-subdivision.tsv"
: >"$results"
step() {  # SIDE ROUND
  "${bin[$1]}" -q --threads 2 build "$scene" "${what[@]}" --max-cells "$cells" --seed 1 \
    --no-merge -o "$dir/ab-sub-$1.vcells" --report "$dir/ab-sub.json"
  ab_record "$results" "$1" "subdivision s" "$(python3 scripts/vctables.py get "$dir/ab-sub.json" timings subdivision_seconds)"
  ab_record "$results" "$1" "final construction cost" \
    "$(python3 scripts/vctables.py get "$dir/ab-sub.json" subdivision final_cost)"
}
ab_alternate "$runs" step
ab_table "$results" - "" "$scene: $segments construction samples or segments to $cells cells, alternating runs of \
the old ($sha) and the new build, two threads; $(same_files "$dir/ab-sub-old.vcells" "$dir/ab-sub-new.vcells" "cells")."
