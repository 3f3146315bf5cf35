#!/usr/bin/env bash
# Installs the build into a temporary prefix, configures examples/consumer against it with
# find_package(viewcells), builds it and checks that its answers are the CLI's:
#   install_test.sh BUILD_DIR VIEWCELLS WORK [FLAGS]
# FLAGS: what the consumer compiles and links with too (a sanitized build's installed
# libraries need the sanitizers' runtimes).
set -euo pipefail
build="$1"; vc="$2"; work="$3"; flags="${4:-}"
# The interpreter itself, not a launcher in front of it (a pyenv shim takes 0.3 s a start).
PYTHON3=$(python3 -c 'import sys; print(sys.executable)')
python3() { "$PYTHON3" "$@"; }
src="$(cd "$(dirname "$0")/../.." && pwd)"
rm -rf "$work"; mkdir -p "$work"
cmake --install "$build" --prefix "$work/prefix" >/dev/null
test -f "$work/prefix/lib/cmake/viewcells/viewcellsConfig.cmake"
test -f "$work/prefix/include/viewcells/runtime.h"
# The stable headers are installed, the internals no stable header needs are not.
test -f "$work/prefix/include/viewcells/pipeline/bake.h"
for internal in core/parallel.h core/progress.h core/ranks.h vis/level_view.h q3/play.h q3/level.h; do
  if [ -e "$work/prefix/include/viewcells/$internal" ]; then echo "FAIL: installed an internal header, $internal"; exit 1; fi
done
# Bindings bind the library's fields: the command line's parser is no part of the install.
test -f "$work/prefix/include/viewcells/pipeline/options.h"
for front in viewcells_cli viewcells_studies; do
  if ls "$work/prefix/lib"/*"$front"* >/dev/null 2>&1; then echo "FAIL: installed $front (the command line's)"; exit 1; fi
done
cmake -S "$src/examples/consumer" -B "$work/consumer" -G Ninja -DCMAKE_PREFIX_PATH="$work/prefix" \
  -DCMAKE_C_FLAGS="$flags" -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_EXE_LINKER_FLAGS="$flags" >/dev/null
cmake --build "$work/consumer" >/dev/null

# A small level, made and queried by the CLI.
"$vc" -q generate office --size 1 -o "$work/office.obj"
"$vc" -q build "$work/office.obj" --samples 20000 --max-cells 60 -o "$work/office.vcells"
"$vc" -q compress "$work/office.vcells" --count 20 -o "$work/office.pvs"
for point in "2 2 1.5" "7.5 3.1 1.2" "1 9 2.5"; do
  # shellcheck disable=SC2086
  cli=$("$vc" query "$work/office.pvs" $point --json | python3 -c 'import json,sys; j=json.load(sys.stdin); print(j["cell"], " ".join(str(o["id"]) for o in j["pvs"]))')
  # shellcheck disable=SC2086
  ours=$("$work/consumer/pvs_lookup" "$work/office.pvs" $point | python3 -c 'import sys; l=sys.stdin.read().splitlines(); print(l[0].split()[1], " ".join(x.split()[0] for x in l[1:]))')
  if [ "$cli" != "$ours" ]; then
    echo "FAIL at $point: viewcells query says '$cli', the installed runtime '$ours'"; exit 1
  fi
done
# The consumer refuses what is not a .pvs file, with a message.
if "$work/consumer/pvs_lookup" "$work/office.obj" 0 0 0 2>"$work/err"; then echo "FAIL: accepted an OBJ"; exit 1; fi
grep -q "office.obj" "$work/err"
# The toolkit component links and runs too.
"$work/consumer/scene_stats" "$work/office.obj" | grep -q "triangles"
# ... and reads a Quake 3 map, whose reader it registers as a front end does.
map="$src/data/maps/bsp/oa_dm2.bsp"
if [ -f "$map" ]; then "$work/consumer/scene_stats" "$map" | grep -q "triangles"; fi
# A procedural level baked in memory, from C++ (bake_in_memory) and from C (bake_c: vc_bake, then
# vc_pvs_open_memory): 9 cells for 3 x 3 rooms, a cell for every room's middle (the corner rooms
# see fewer than all the objects), and nothing written where it ran.
mkdir -p "$work/empty"
for consumer in bake_in_memory bake_c; do
  (cd "$work/empty" && "$work/consumer/$consumer" 3) > "$work/$consumer.txt"
  python3 - "$work/$consumer.txt" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
objects = int(re.search(r"level: (\d+) objects", text).group(1))
assert re.search(r"^cells: 9,", text, re.M), text
rooms = [(int(c), int(n)) for c, n in re.findall(r"cell (-?\d+) sees (\d+) objects", text)]
assert len(rooms) == 3 and all(c >= 0 and 0 < n <= objects for c, n in rooms), text
assert rooms[0][1] < objects and rooms[2][1] < objects, text
PY
  [ -z "$(ls -A "$work/empty")" ] || { echo "FAIL: $consumer wrote $(ls "$work/empty")"; exit 1; }
done
if "$work/consumer/bake_c" 0 2>/dev/null; then echo "FAIL: bake_c accepted 0 rooms"; exit 1; fi
# The runtime library links nothing of the toolkit's dependencies.
if ldd "$work/consumer/pvs_lookup" | grep -Ei "embree|tbb|cgal|gmp|boost|png"; then
  echo "FAIL: the runtime consumer links toolkit dependencies"; exit 1
fi
echo "install test passed: find_package(viewcells) consumers agree with viewcells query"
