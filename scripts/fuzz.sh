#!/usr/bin/env bash
# Fuzzes every reader with libFuzzer (clang-14, AddressSanitizer and UBSan): OBJ, PLY, OFF, STL,
# Quake 3 BSP, binary glTF and FBX (through Assimp), .vseg, .vcells, .pvs and .vagvs, and the engines'
# runtime reader (runtime/: a .pvs payload and two query points, through every C API call), and vc_bake
# on objects and option words from the bytes, its result opened from memory. Seed
# corpora are made by the project's own generators and commands (in build-fuzz/corpus, not in git); the toolkit's own formats are
# fuzzed as container payloads, so that inputs get past the checksum to the parsers.
# Each target runs SECONDS (default 60), two at a time; findings (crash-, leak-, oom-,
# timeout- files) go to build-fuzz/findings/, and the script fails when there is one.
# Usage: scripts/fuzz.sh [SECONDS] [TARGET...]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"
shift $(( $# > 0 ? 1 : 0 ))
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(obj ply off stl bsp glb fbx vseg vcells pvs runtime vagvs bake)

bash scripts/install-deps.sh --fuzz
CC=clang-14 CXX=clang++-14 bash scripts/build.sh build-fuzz RelWithDebInfo -DVIEWCELLS_FUZZ=ON -DVIEWCELLS_BUILD_TESTS=OFF
bin=build-fuzz/tests/fuzz
vc=build-fuzz/cli/viewcells
corpus=build-fuzz/corpus
findings=build-fuzz/findings
mkdir -p "$findings"
export ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=0
export LSAN_OPTIONS=suppressions=$PWD/tests/fuzz/lsan.supp:print_suppressions=0
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1

# The payload of one of our containers (32-byte header, zstd frame) with the byte that picks
# its format version in the fuzz target (version - 1) in front.
payload() {  # FILE OUT
  local version
  version=$(od -An -tu1 -j4 -N1 "$1" | tr -d ' ')
  { printf "\\$(printf '%03o' $((version - 1)))"; tail -c +33 "$1" | zstd -dq; } >"$2"
}

# OBJ -> OFF and ASCII STL (one facet per triangle), for seeds in those formats.
obj_to_off() {
  awk '/^v /{v[nv++]=$2" "$3" "$4} /^f /{f[nf++]="3 "($2-1)" "($3-1)" "($4-1)}
       END{print "OFF"; print nv, nf, 0; for(i=0;i<nv;i++) print v[i]; for(i=0;i<nf;i++) print f[i]}' "$1"
}
obj_to_stl() {
  awk '/^v /{v[++nv]=$2" "$3" "$4} /^f /{print " facet normal 0 0 0\n  outer loop";
       for(k=2;k<=4;k++) print "   vertex "v[$k]; print "  endloop\n endfacet"}
       BEGIN{print "solid seed"} END{print "endsolid seed"}' "$1"
}

if [ ! -f "$corpus/done" ]; then
  echo "fuzz: making seed corpora"
  rm -rf "$corpus"
  for t in obj ply off stl bsp glb fbx vseg vcells pvs runtime vagvs bake; do mkdir -p "$corpus/$t"; done
  work=$(mktemp -d)
  "$vc" -q generate office --size 1 -o "$corpus/obj/office.obj"
  "$vc" -q generate rotated-office --size 1 --seed 2 -o "$corpus/obj/rotated.obj"
  head -c 20000 "$corpus/obj/office.obj" | sed '$d' >"$corpus/obj/office-part.obj"
  # Real binary glTF and FBX files from Debian's assimp-testmodels.
  for f in /usr/share/assimp/models/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb \
           /usr/share/assimp/models/glTF2/BoxBadNormals-glTF-Binary/BoxBadNormals.glb; do
    cp "$f" "$corpus/glb/"
  done
  for f in box.fbx cubes_with_names.fbx boxWithCompressedCTypeArray.FBX; do cp "/usr/share/assimp/models/FBX/$f" "$corpus/fbx/"; done
  obj_to_off "$corpus/obj/office.obj" >"$corpus/off/office.off"
  obj_to_stl "$corpus/obj/rotated.obj" >"$corpus/stl/rotated.stl"
  "$vc" -q sample "$corpus/obj/office.obj" --samples 2000 -o "$work/s.vseg"
  "$vc" -q build "$corpus/obj/office.obj" --samples 5000 --max-cells 12 -o "$work/l.vcells" --mesh "$corpus/ply/cells.ply"
  "$vc" -q compress "$work/l.vcells" --count 4 -o "$work/l.pvs"
  payload "$work/s.vseg" "$corpus/vseg/office"
  payload "$work/l.vcells" "$corpus/vcells/office"
  payload "$work/l.pvs" "$corpus/pvs/office"
  # The runtime's input: the version byte, two query points (48 bytes: the origin and a point
  # at 1e308), then the payload; and the saved findings with extreme view boxes.
  { head -c 1 "$corpus/pvs/office"; head -c 24 /dev/zero; printf '\x00\x00\x00\x00\x00\x00\xe0\x7f%.0s' 1 2 3;
    tail -c +2 "$corpus/pvs/office"; } >"$corpus/runtime/office"
  cp data/fuzz/regressions/runtime/* "$corpus/runtime/"
  # vc_bake's input (tests/fuzz/entries.cpp, entry_bake): two closed cubes, with and without
  # option words, and bad vertices and indices.
  cp data/fuzz/regressions/bake/* "$corpus/bake/"
  VIEWCELLS_FUZZ_SEED="$work/state.vagvs" "$bin/fuzz_vagvs" >/dev/null 2>&1
  payload "$work/state.vagvs" "$corpus/vagvs/office"
  # The two smallest OpenArena maps, when scripts/fetch-maps.sh has fetched them.
  if ls data/maps/bsp/*.bsp >/dev/null 2>&1; then
    ls -S data/maps/bsp/*.bsp | tail -2 | xargs -I{} cp {} "$corpus/bsp/"
  fi
  printf 'IBSP\x2e\x00\x00\x00' >"$corpus/bsp/header-only"
  rm -rf "$work"
  touch "$corpus/done"
fi
if [ ! -d "$corpus/bake" ]; then  # corpora made before the bake target existed
  mkdir -p "$corpus/bake"
  cp data/fuzz/regressions/bake/* "$corpus/bake/"
fi

run_one() {
  local t=$1 seconds=$2 log=build-fuzz/fuzz_$1.log
  set +e
  build-fuzz/tests/fuzz/fuzz_"$t" "build-fuzz/corpus/$t" -max_total_time="$seconds" -rss_limit_mb=2048 \
    -timeout=20 -max_len=4000000 -print_final_stats=1 -artifact_prefix="build-fuzz/findings/$t-" >"$log" 2>&1
  local rc=$?
  set -e
  printf '%-7s exit %-3s %s, corpus %s\n' "$t" "$rc" \
    "$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | sed 's/$/ runs/')" \
    "$(ls "build-fuzz/corpus/$t" | wc -l)"
}
export -f run_one
echo "fuzz: ${#targets[@]} targets, $seconds s each, two at a time"
printf '%s\n' "${targets[@]}" | xargs -P 2 -I{} bash -c "run_one {} $seconds"
found=$(ls "$findings" 2>/dev/null | wc -l)
if [ "$found" -gt 0 ]; then
  echo "fuzz: $found findings in $findings (logs: build-fuzz/fuzz_TARGET.log):"
  ls "$findings"
  exit 1
fi
echo "fuzz: no findings"
