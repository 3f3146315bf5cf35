#!/usr/bin/env bash
# The viewcells command line as a user meets it: subcommands, reports, exit codes, messages,
# and that a failing command leaves files already written alone.
# Usage: cli_test.sh PATH/TO/viewcells WORKDIR
set -u
VC="$1"
WORK="$2"
MAPS="$(cd "$(dirname "$0")/../../data/maps/bsp" 2>/dev/null && pwd)"
rm -rf "$WORK" && mkdir -p "$WORK" && cd "$WORK" || exit 1
# The interpreter itself, not a launcher in front of it (a pyenv shim takes 0.3 s to start it,
# 0.05 s without, and this test runs about 20 checks in Python).
PYTHON3=$(python3 -c 'import sys; print(sys.executable)') || exit 1
python3() { "$PYTHON3" "$@"; }
passed=0
failed=0
ok() { passed=$((passed + 1)); }
bad() { echo "FAIL: $*"; failed=$((failed + 1)); }
expect_ok() { if "$@" >out.txt 2>err.txt; then ok; else bad "expected success: $* ($(cat err.txt))"; fi; }
# expect_error FRAGMENT CMD...: non-zero exit and the fragment in stderr, never a crash.
expect_error() {
  local fragment="$1"
  shift
  "$@" >out.txt 2>err.txt
  local rc=$?
  if [ $rc -eq 0 ]; then bad "expected failure: $*"; return; fi
  if [ $rc -ge 128 ]; then bad "crashed (signal $((rc - 128))): $*"; return; fi
  if ! grep -q "viewcells: error:" err.txt && ! grep -qi "error" err.txt; then bad "no error message: $*"; return; fi
  if ! grep -qF -- "$fragment" err.txt; then bad "message lacks '$fragment': $(cat err.txt)"; return; fi
  ok
}
# json_get FILE "['a']['b'][0]": the value there, printed as Python would (True, False, None);
# non-zero when the path is not in the file. jq, since python3 takes 0.3 s to start here.
json_get() {
  local path
  path="[$(sed -e "s/^\[//; s/\]\$//; s/\]\[/,/g; s/'/\"/g" <<<"$2")]"
  jq -r --argjson p "$path" '
    reduce $p[] as $k (.; if (type == "object" and ($k | type) == "string" and has($k))
                             or (type == "array" and ($k | type) == "number" and $k < length)
                          then .[$k] else error("no \($k)") end)
    | if . == true then "True" elif . == false then "False" elif . == null then "None" else . end' "$1"
}

# --help explains every subcommand.
expect_ok "$VC" --help
for sub in generate info sample build export extract compress recode pvs query view compare bake measure; do grep -q "$sub" out.txt && ok || bad "--help lacks $sub"; done
expect_ok "$VC" sample --help
grep -q -- "--measure-raw" out.txt && ok || bad "sample --help lacks --measure-raw"

# generate -> info -> sample
expect_ok "$VC" generate office --size 2 --seed 3 -o office.obj
expect_ok "$VC" generate office --size 2 --seed 3 -o office2.obj
cmp -s office.obj office2.obj && ok || bad "generate is not deterministic"
expect_ok "$VC" generate rotated-office --size 1 -o rotated.obj
expect_ok "$VC" generate city --size 2 -o city.obj
expect_ok "$VC" info office.obj --json info.json --list
grep -q "empty space detect: *enabled" out.txt && ok || bad "info does not report empty space detection"
grep -q "f0_room_a0_doorwall" out.txt && ok || bad "info --list lacks object names"
[ "$(json_get info.json "['all_solid']")" = "True" ] && ok || bad "info.json all_solid"
expect_ok "$VC" info rotated.obj
grep -Eq "non-axis-aligned: +[1-9][0-9]\.[0-9]+%" out.txt && ok || bad "rotated office should be mostly non-axis-aligned: $(grep non-axis out.txt)"

expect_ok "$VC" sample office.obj --samples 20000 --seed 5 --threads 1 -o a.vseg --report a.json --measure-raw
expect_ok "$VC" sample office.obj --samples 20000 --seed 5 --threads 2 -o b.vseg --report b.json
cmp -s a.vseg b.vseg && ok || bad "segments differ between 1 and 2 threads"
for key in "['settings']['samples']" "['settings']['seed']" "['effects']['empty_space_detection']['enabled']" \
  "['effects']['empty_space_detection']['reason']" "['counts']['valid_segments']" "['counts']['rays']" \
  "['timings']['segments_per_second']" "['timings']['raw_rays_per_second']" "['counts']['segments_per_object']"; do
  json_get a.json "$key" >/dev/null 2>&1 && ok || bad "report lacks $key"
done
[ "$(json_get a.json "['effects']['empty_space_detection']['enabled']")" = "True" ] && ok || bad "ESD should be on for a solid scene"
expect_ok "$VC" sample office.obj --samples 2000 --empty-space off --report off.json -q
[ "$(json_get off.json "['effects']['empty_space_detection']['reason']")" = "disabled by the user" ] && ok || bad "ESD off reason"
expect_ok "$VC" sample city.obj --samples 5000 --view-box 0,0,0,100,100,20 --report box.json -q
[ "$(json_get box.json "['settings']['view_box_source']")" = "user (--view-box)" ] && ok || bad "view box source"

# An open scene: empty space detection stays off, and the report says why.
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\ng plane\nf 1 2 3\ng other\nf 1 2 4\n' > open.obj
expect_ok "$VC" sample open.obj --samples 1000 --report open.json -q
[ "$(json_get open.json "['effects']['empty_space_detection']['enabled']")" = "False" ] && ok || bad "ESD should be off for an open scene"
json_get open.json "['effects']['empty_space_detection']['reason']" | grep -q "open" && ok || bad "open-scene reason"

# Bad input: clear message with file and line, non-zero exit, no crash.
expect_error "no such file" "$VC" info missing.obj
printf 'v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n' > nan.obj
expect_error "nan.obj:2:" "$VC" info nan.obj
printf 'v 0 0 0\nv 1 0 0\nf 1 2 9\n' > badface.obj
expect_error "badface.obj:3:" "$VC" sample badface.obj --samples 10
: > empty.obj
expect_error "no triangles" "$VC" info empty.obj
printf 'OFF\n8 6 0\n0 0 0\n1 0' > truncated.off
expect_error "truncated.off" "$VC" info truncated.off
expect_error "unknown scene kind" "$VC" generate castle -o x.obj
expect_error "view-box" "$VC" sample office.obj --view-box 1,2,3
expect_error "min < max" "$VC" sample office.obj --view-box 0,0,0,1,1,0
# A scene with no floor a player fits on (boxes 1 m apart under a slab 1.2 m up) has no play space:
# --play-space is an error that says why, and bake's default keeps the view box and says so.
printf 'v 0 0 0\nv 9 0 0\nv 9 9 0\nv 0 9 0\nv 0 0 1.2\nv 9 0 1.2\nv 9 9 1.2\nv 0 9 1.2\nf 1 2 3 4\nf 8 7 6 5\n' > lowroom.obj
expect_error "lowroom.obj: --play-space needs a view space that knows where players stand: the scene has none: no walkable floor" \
  "$VC" build lowroom.obj --play-space -o play.vcells
expect_error "the scene has none: no walkable floor" "$VC" bake lowroom.obj --play-space --cells 4 -o play.pvs
expect_ok "$VC" bake lowroom.obj --cells 4 --samples 5000 --agvs-samples 5000 -o lowroom.pvs --report lowroom.json -q
json_get lowroom.json "['settings']['view_space']" | grep -q "the whole view box: no play space (no walkable floor" && ok ||
  bad "bake on a scene without floors: the report does not say the view box was kept and why"
# convert: a glTF level of a scene, read back with the same objects; bad outputs are errors.
expect_ok "$VC" convert office.obj -o office-level.glb -q
expect_ok "$VC" info office-level.glb --json office-level.json -q
python3 -c "
import json; a = json.load(open('office-level.json')); b = json.load(open('info.json'))
assert a['objects'] == b['objects'] and a['triangles'] == b['triangles'], (a['objects'], b['objects'])
" && ok || bad "convert: the level does not read back with the office's objects and triangles"
expect_error "give a .glb output" "$VC" convert office.obj -o office-level.obj
expect_error "no such file" "$VC" convert missing.obj -o x.glb
# The office has floors: bake finds its play space by default and says so; measure's play cameras stand there.
expect_ok "$VC" play-space office.obj --report office-play.json -q
python3 -c "
import json; r = json.load(open('office-play.json'))
assert r['found'] and r['floor_area_m2'] > 100 and 'no start points' in r['rule'], r
" && ok || bad "play-space on the office"
expect_error "empty-space" "$VC" sample office.obj --empty-space maybe
expect_error "samples" "$VC" sample office.obj --samples 0

# build -> export: cells, report, mesh, slice; the reloaded hierarchy gives the same slice.
expect_ok "$VC" build office.obj --samples 30000 --max-cells 64 -o office.vcells --report build.json \
  --mesh cells.ply --slice-png slice.png --slice-z 1.5 -q
for f in office.vcells cells.ply slice.png; do [ -s "$f" ] && ok || bad "build did not write $f"; done
head -c 8 slice.png | od -c | grep -q "P   N   G" && ok || bad "slice.png is not a PNG"
head -n 1 cells.ply | grep -q "^ply" && ok || bad "cells.ply is not a PLY"
[ "$(json_get build.json "['subdivision']['cells']")" = "64" ] && ok || bad "build should give 64 cells"
python3 -c "
import json; r=json.load(open('build.json')); s=r['subdivision']
assert r['final_cost'] < s['initial_cost'], 'the cost must drop'
c=[p['cost'] for p in s['cost_at_power_of_two_cells']]
assert all(b <= a for a, b in zip(c, c[1:])), 'cost must not increase with cells'
assert [p['cells'] for p in s['cost_at_power_of_two_cells']] == [1, 2, 4, 8, 16, 32, 64]
assert r['effects']['geometry_aligned_candidates']['enabled'] is False
assert s['axis_candidates_evaluated'] > 0 and s['geometry_candidates_evaluated'] == 0
for k in ['load_seconds', 'sampling_seconds', 'subdivision_seconds', 'write_seconds']: assert k in r['timings'], k
" && ok || bad "build report"
expect_ok "$VC" export office.vcells --slice-png slice2.png --slice-z 1.5 --scene office.obj -q
cmp -s slice.png slice2.png && ok || bad "the reloaded hierarchy gives another slice"
expect_ok "$VC" build rotated.obj --samples 20000 --max-cells 32 --report rot.json -q
[ "$(json_get rot.json "['effects']['geometry_aligned_candidates']['enabled']")" = "True" ] && ok || bad "GA should be on for the rotated office"
expect_ok "$VC" build rotated.obj --samples 20000 --max-cells 32 --no-ga --report rot_aa.json -q
[ "$(json_get rot_aa.json "['subdivision']['geometry_candidates_evaluated']")" = "0" ] && ok || bad "--no-ga"
[ "$(json_get build.json "['effects']['pixel_cost_term']['enabled']")" = "False" ] && ok || bad "pixel term must be off by default"
# The pixel term: on with --cost-c, said so in the report, the screen recorded.
expect_ok "$VC" build office.obj --samples 20000 --max-cells 32 --cost-c 0.01 --screen 640x480 --fov 70 \
  -o pixel.vcells --report pixel.json -q
python3 -c "
import json; r=json.load(open('pixel.json'))
e=r['effects']['pixel_cost_term']; assert e['enabled'] is True and '640x480' in e['reason'], e
assert r['settings']['cost_model']['screen'] == {'width': 640, 'height': 480, 'fov_degrees': 70.0}
assert r['final_cost'] < r['subdivision']['initial_cost']
" && ok || bad "pixel term report"
expect_ok "$VC" export pixel.vcells --mesh pixel.ply -q
expect_error "--screen" "$VC" build office.obj --samples 1000 --cost-c 1 --screen 640-480
expect_error "field of view" "$VC" build office.obj --samples 1000 --cost-c 1 --fov 200
expect_error "must be a number from 0 to 1e12" "$VC" build office.obj --samples 1000 --cost-c -1
# Merging (default), extraction, compression and queries.
python3 -c "
import json; r=json.load(open('build.json')); m=r['merge']
assert r['effects']['merging']['enabled'] is True
assert m['cells_from'] == 64 and m['cells_to'] == 1
c=[p['cost'] for p in m['cost_at_power_of_two_cells']]
assert all(b <= a for a, b in zip(c, c[1:])), 'merged cost must fall with more cells'
" && ok || bad "build report: merge"
expect_ok "$VC" extract office.vcells --count 10 -o ten.json --mesh ten.ply --slice-png ten.png --slice-z 1.5 -q
python3 -c "
import json; r=json.load(open('ten.json'))
assert r['cells'] == 10 and len(r['view_cells']) == 10
leaves = sorted(l for c in r['view_cells'] for l in c['bsp_leaves'])
assert len(leaves) == 64 and len(set(leaves)) == 64, 'the cells tile the 64 leaves'
" && ok || bad "extract --count"
[ -s ten.ply ] && [ -s ten.png ] && ok || bad "extract views"
# A 1K budget is for the written .pvs file (not the 4-bytes-an-entry estimate the report also
# gives): compress with the same budget writes as many cells in at most 1,024 bytes.
expect_ok "$VC" extract office.vcells --memory 1K -o mem.json -q
expect_ok "$VC" compress office.vcells --memory 1K -o mem.pvs --report memc.json -q
[ "$(json_get mem.json "['cells']")" = "$(json_get memc.json "['cells']")" ] && [ "$(stat -c %s mem.pvs)" -le 1024 ] &&
  grep -q "fits in 1024 bytes" mem.json && ok ||
  bad "extract --memory 1K: $(json_get mem.json "['cells']") cells, compress $(json_get memc.json "['cells']") in $(stat -c %s mem.pvs) bytes"
# --memory holds for the .pvs file compress writes, measured, and is the most cells that do.
expect_ok "$VC" extract office.vcells --memory 1800 -o mem3.json -q
expect_ok "$VC" compress office.vcells --memory 1800 -o mem3.pvs --report mem3c.json -q
n=$(json_get mem3.json "['cells']")
[ "$(json_get mem3c.json "['cells']")" = "$n" ] && [ "$(stat -c %s mem3.pvs)" -le 1800 ] && ok \
  || bad "compress --memory 1800: $(stat -c %s mem3.pvs) bytes for $(json_get mem3c.json "['cells']") cells (extract: $n)"
# A budget that holds one more cell's file (plus the longer rule text it records) gives at least as
# many cells, and its file fits too.
if [ "$n" -lt 64 ]; then
  expect_ok "$VC" compress office.vcells --count $((n + 1)) -o mem3more.pvs -q
  more=$(( $(stat -c %s mem3more.pvs) + 64 ))
  expect_ok "$VC" compress office.vcells --memory "$more" -o mem3b.pvs --report mem3b.json -q
  [ "$(json_get mem3b.json "['cells']")" -ge "$n" ] && [ "$(stat -c %s mem3b.pvs)" -le "$more" ] && ok \
    || bad "compress --memory $more: $(json_get mem3b.json "['cells']") cells, $(stat -c %s mem3b.pvs) bytes"
fi
expect_ok "$VC" extract office.vcells --cost-ratio 1.5 -o ratio.json -q
python3 -c "
import json; r=json.load(open('ratio.json')); assert r['cost_ratio'] <= 1.5
" && ok || bad "extract --cost-ratio"
expect_error "only one of" "$VC" extract office.vcells --count 3 --cost-ratio 2
expect_error "say which cells" "$VC" extract office.vcells
expect_error "cannot extract 65 cells" "$VC" extract office.vcells --count 65
expect_error "--memory needs a size" "$VC" extract office.vcells --memory lots
expect_error "too small" "$VC" extract office.vcells --memory 10
expect_ok "$VC" compress office.vcells --count 16 -o office.pvs --flat office.vflt --report compress.json -q
python3 -c "
import json; r=json.load(open('compress.json'))
assert r['cells'] == 16 and r['entries_after'] < r['entries_before'], r
assert r['flat']['run_length_bytes'] > 0
" && ok || bad "compress report"
expect_ok "$VC" query office.pvs 2 2 1.5
grep -q "^cell [0-9]* of 16" out.txt && grep -q "facade" out.txt && ok || bad "query output: $(head -3 out.txt)"
expect_ok "$VC" query office.pvs 2 2 1.5 --json
python3 -c "
import json; r=json.load(open('out.txt')); assert r['cells'] == 16 and len(r['pvs']) > 0
" && ok || bad "query --json"
expect_error "outside the view space" "$VC" query office.pvs 1e6 0 0
head -c 60 office.pvs > cut.pvs
expect_error "cut.pvs" "$VC" query cut.pvs 2 2 1.5
# recode: the same cells and PVSs in the current format; a failing recode leaves its output as
# it was.
expect_ok "$VC" recode office.pvs -o recoded.pvs
grep -q "(format 2)" err.txt && ok || bad "recode: $(cat err.txt)"
expect_ok "$VC" query recoded.pvs 2 2 1.5 --json
cp out.txt recoded-query.txt
expect_ok "$VC" query office.pvs 2 2 1.5 --json
cmp -s out.txt recoded-query.txt && ok || bad "recode changed a query's answer"
# Format 1 for engines with an older runtime reader, and back: the same bytes as before.
expect_ok "$VC" recode recoded.pvs --format 1 -o format1.pvs
expect_ok "$VC" recode format1.pvs -o format2.pvs
grep -q "format1.pvs (format 1)" err.txt && cmp -s format2.pvs recoded.pvs && ok || bad "recode through format 1: $(cat err.txt)"
expect_error "--format" "$VC" recode office.pvs --format 3 -o format3.pvs
cp recoded.pvs recoded-before.pvs
expect_error "cut.pvs" "$VC" recode cut.pvs -o recoded.pvs
cmp -s recoded.pvs recoded-before.pvs && ok || bad "a failed recode changed its output"
expect_error "required" "$VC" recode office.pvs
# view: the cells as a web page and as glTF (read back through Assimp: the scene's objects and
# one translucent object per view cell).
expect_ok "$VC" view office.pvs --scene office.obj -o site --gltf cells.glb -q
[ -s site/index.html ] && [ -s site/viewer.js ] && grep -q "^window.VIEWCELLS_DATA = " site/data.js && ok || bad "view: site"
expect_ok "$VC" info cells.glb --list
[ "$(grep -c '	cell [0-9]* (see-through)$' out.txt)" = 16 ] && ok || bad "view: glTF cells: $(grep -c cell out.txt)"
# ... and the play space (the office's floors) as one more object, which --no-play-space leaves out.
grep -q '	play space (see-through)$' out.txt && ok || bad "view: no play space in the glTF"
expect_ok "$VC" view office.pvs --scene office.obj --gltf noplay.glb --no-play-space -q
expect_ok "$VC" info noplay.glb --list
! grep -q 'play space' out.txt && ok || bad "view --no-play-space: the glTF has a play space"
cp cells.glb cells-before.glb
expect_error "fingerprints differ" "$VC" view office.pvs --scene rotated.obj --gltf cells.glb
cmp -s cells.glb cells-before.glb && ok || bad "a failed view changed the earlier glTF"
expect_error "give one" "$VC" view office.pvs --scene office.obj
expect_error "not a directory" "$VC" view office.pvs --scene office.obj -o office.obj
expect_error "cut.pvs" "$VC" view cut.pvs --scene office.obj -o site2
[ ! -e site2 ] && ok || bad "a failed view created its directory"
# pvs: the cells' PVSs by global visibility sampling, written like compress's.
expect_ok "$VC" pvs office.vcells --scene office.obj --cells 16 --samples 40000 -o agvs.pvs --report agvs.json -q
python3 -c "
import json; r=json.load(open('agvs.json'))
assert r['cells'] == 16 and 40000 <= r['samples'] < 80000 and r['mean_pvs_size'] > 0, r
assert 'estimated_pixel_error' in r and r['samples_per_second'] > 0 and len(r['curve']) > 0
assert sum(d['samples'] for d in r['distributions']) == r['samples']
assert r['effects']['silhouette_mutation']['enabled']
" && ok || bad "pvs report"
expect_ok "$VC" query agvs.pvs 2 2 1.5
grep -q "^cell [0-9]* of 16" out.txt && ok || bad "query on a pvs from AGVS"
# --reference: the curve counts the entries another solution has too (here AGVS's own final one).
expect_ok "$VC" pvs office.vcells --scene office.obj --cells 16 --samples 40000 --method sgvs --reference agvs.pvs \
  -o sgvs.pvs --report sgvs.json -q
python3 -c "
import json; a=json.load(open('agvs.json')); s=json.load(open('sgvs.json'))
cov = [p['covered'][0] for p in s['curve']]
assert cov == sorted(cov) and 0 < cov[-1] <= min(a['pvs_entries'], s['pvs_entries']), cov[-5:]
" && ok || bad "pvs --reference coverage"
expect_error "these view cells" "$VC" pvs office.vcells --scene office.obj --cells 8 --samples 10 --reference agvs.pvs \
  -o x.pvs
expect_ok "$VC" pvs office.vcells --scene office.obj --cells 16 --samples 20000 --save half.vagvs -o half.pvs -q
expect_ok "$VC" pvs office.vcells --scene office.obj --cells 16 --samples 40000 --resume half.vagvs -o resumed.pvs -q
# --save may be the --resume state (continue and keep it); -o onto it may not.
cp half.vagvs again.vagvs
expect_ok "$VC" pvs office.vcells --scene office.obj --cells 16 --samples 40000 --resume again.vagvs --save ./again.vagvs -o again.pvs -q
expect_error "is an input" "$VC" pvs office.vcells --scene office.obj --cells 16 --samples 40000 --resume half.vagvs -o half.vagvs -q
cmp -s resumed.pvs agvs.pvs && ok || bad "20000 samples resumed to 40000 differ from 40000 in one run"
expect_error "another scene or other view cells" "$VC" pvs office.vcells --scene office.obj --cells 8 --samples 10 \
  --resume half.vagvs -o x.pvs
# The visibility filter: the written PVSs are supersets of the sampled ones.
expect_ok "$VC" pvs office.vcells --scene office.obj --cells 16 --samples 2000 --batch 500 --filter --filter-neighbours 1 \
  -o filtered.pvs --report filtered.json -q
python3 -c "
import json; r=json.load(open('filtered.json'))
f = r['filter']
assert r['effects']['visibility_filter']['enabled'] and f['object_space'] and f['view_neighbours'] == 1, r['filter']
assert f['mean_pvs_size_filtered'] == r['mean_pvs_size_written'] > r['mean_pvs_size'] == f['mean_pvs_size_unfiltered'], f
" && ok || bad "pvs --filter report"
expect_ok "$VC" query filtered.pvs 2 2 1.5
expect_ok "$VC" pvs office.vcells --scene office.obj --cells 16 --samples 2000 --batch 500 --filter-neighbours 1 \
  -o neighbours.pvs --report neighbours.json -q
python3 -c "
import json; r=json.load(open('neighbours.json'))
assert r['mean_pvs_size_written'] > r['mean_pvs_size'] and not r['filter']['object_space'], r['filter']
" && ok || bad "pvs --filter-neighbours alone extends the PVSs"
expect_error "--filter" "$VC" pvs office.vcells --scene office.obj --samples 10 --filter-k 2 -o x.pvs
expect_error "without the filter" "$VC" pvs office.vcells --scene office.obj --cells 16 --samples 40000 \
  --resume half.vagvs --filter -o x.pvs
# Dynamic edits: a wall inserted into the scene (an OBJ group appended), then the wall deleted.
python3 - <<'PY'
xs, ys, zs = [], [], []
for line in open("office.obj"):
    if line.startswith("v "):
        x, y, z = map(float, line.split()[1:4]); xs.append(x); ys.append(y); zs.append(z)
mid = 0.5 * (min(xs) + max(xs))
lo = (mid - 0.05, min(ys) - 1, min(zs) - 1); hi = (mid + 0.05, max(ys) + 1, max(zs) + 1)
corners = [(hi[0] if k & 1 else lo[0], hi[1] if k & 2 else lo[1], hi[2] if k & 4 else lo[2]) for k in range(8)]
quads = [(0, 4, 6, 2), (1, 3, 7, 5), (0, 1, 5, 4), (2, 6, 7, 3), (0, 2, 3, 1), (4, 5, 7, 6)]
with open("walled.obj", "w") as f:
    f.write(open("office.obj").read())
    f.write("g inserted_wall\n")
    for c in corners: f.write("v %r %r %r\n" % c)
    for q in quads: f.write("f " + " ".join(str(i - 8) for i in q) + "\n")
PY
expect_ok "$VC" pvs office.vcells --scene walled.obj --edited-from office.obj --cells 16 --samples 40000 \
  --resume half.vagvs --save walled.vagvs -o walled.pvs --report walled.json -q
python3 -c "
import json; r=json.load(open('walled.json')); e=r['edit']
assert e['inserted_objects'] == 1 and e['deleted_objects'] == 0 and e['entries_in_penumbrae'] > 0, e
" && ok || bad "pvs --edited-from report"
# Resuming the edited state needs no second edit.
expect_ok "$VC" pvs office.vcells --scene walled.obj --edited-from office.obj --cells 16 --samples 50000 \
  --resume walled.vagvs -o walled2.pvs --report walled2.json -q
[ "$(json_get walled2.json "['edit']")" = "None" ] && ok || bad "a resumed edited state was edited again"
expect_error "needs --resume" "$VC" pvs office.vcells --scene walled.obj --edited-from office.obj --samples 10 -o x.pvs
expect_error "fingerprints differ" "$VC" pvs office.vcells --scene walled.obj --samples 10 -o x.pvs
python3 - <<'PY'
# office.obj without its first group's faces: a deleted object.
out, group, first = [], None, None
for line in open("office.obj"):
    if line.startswith(("g ", "o ")):
        group = line
        first = first or line
    if line.startswith("f ") and group == first:
        continue
    out.append(line)
open("fewer.obj", "w").write("".join(out))
PY
expect_ok "$VC" pvs office.vcells --scene fewer.obj --edited-from office.obj --cells 16 --samples 40000 \
  --resume half.vagvs -o fewer.pvs --report fewer.json -q
python3 -c "
import json; r=json.load(open('fewer.json')); e=r['edit']
assert e['deleted_objects'] == 1 and e['inserted_objects'] == 0 and e['entries_of_deleted_objects'] > 0, e
" && ok || bad "pvs --edited-from with a deleted object"
expect_error "give when to stop" "$VC" pvs office.vcells --scene office.obj -o x.pvs
expect_error "fingerprints differ" "$VC" pvs office.vcells --scene city.obj --samples 10 -o x.pvs
expect_error "unknown PVS method" "$VC" pvs office.vcells --scene office.obj --samples 10 --method fast -o x.pvs
[ ! -e x.pvs ] && ok || bad "a refused pvs wrote its output"
expect_ok "$VC" build office.obj --samples 5000 --max-cells 8 --no-merge -o nomerge.vcells -q
expect_error "need --merge-pvs agvs" "$VC" build office.obj --samples 5000 --max-cells 8 --merge-pvs samples \
  --merge-samples 100 -o x.vcells
expect_error "--merge-pvs" "$VC" build office.obj --samples 5000 --max-cells 8 --merge-pvs fast -o x.vcells
# The old greedy merge on request, and the validated one's report says what it chose.
expect_ok "$VC" build office.obj --samples 5000 --max-cells 16 --merge-pvs samples -o oldmerge.vcells \
  --report oldmerge.json -q
[ "$(json_get oldmerge.json "['merge']['pvs']")" = "construction samples" ] && ok || bad "build --merge-pvs samples"
expect_ok "$VC" build office.obj --samples 5000 --max-cells 16 -o newmerge.vcells --report newmerge.json -q
[ "$(json_get newmerge.json "['merge']['agvs_samples']['validation']")" -ge 5000 ] && ok || bad "build's merge report"
expect_error "no merge history" "$VC" extract nomerge.vcells --count 2
# compare: every method from the same samples, scored on independent ones.
expect_ok "$VC" compare office.obj --samples 20000 --max-cells 40 -o cmp -q
python3 -c "
import csv, json
rows = list(csv.DictReader(open('cmp/curves.csv')))
methods = {r['method'] for r in rows}
assert methods == {'av-m','av-m-samples','av-s','kd-casm','kd-lasm','kd-vt','kd-vt-star','bsp'}, methods
s = json.load(open('cmp/summary.json'))
assert s['settings']['merge_pvs'] == 'agvs' and s['settings']['merge_agvs_samples_per_run'] == 20000, s['settings']
m = {x['method']: x for x in s['methods']}
assert m['av-m']['merge']['leaf_agvs_samples'] >= 40000 and m['av-m-samples']['merge']['leaf_agvs_samples'] == 0
assert len(m['av-m']['merge']['starts_scored']) >= 2 and m['av-m-samples']['merge']['greedy_from_cells'] == 40
assert s['settings']['evaluation_samples'] == 80000 and s['settings']['evaluation_seed'] != s['settings']['construction_seed']
avm = {int(r['cells']): float(r['cost']) for r in rows if r['method'] == 'av-m'}
kd = {int(r['cells']): float(r['cost']) for r in rows if r['method'] == 'kd-casm'}
assert avm[40] < kd[40], (avm[40], kd[40])
assert all(float(r['ratio_to_av_m']) == 1.0 for r in rows if r['method'] == 'av-m')
" && ok || bad "compare outputs"
[ -s cmp/histogram.csv ] && ok || bad "compare histogram"
# -q on a terminal: no progress bars (each stage's bar is drawn only on a terminal, and a bar its
# stage switched off must not draw itself when it ends). `script` gives the run a terminal.
if command -v script >/dev/null; then
  script -qc "'$VC' compare office.obj --samples 5000 --max-cells 16 --methods av-m,kd-casm -o cmpq -q" /dev/null \
    >tty.txt 2>&1 </dev/null
  if grep -aq '\[' tty.txt; then bad "compare -q drew progress bars on a terminal: $(tr '\r' '\n' <tty.txt | head -3)"; else ok; fi
  script -qc "'$VC' compare office.obj --samples 5000 --max-cells 16 --methods av-m,kd-casm -o cmpq" /dev/null \
    >tty.txt 2>&1 </dev/null
  grep -aq 'evaluation set 1 of 1 \[' tty.txt && ok || bad "compare without -q drew no evaluation bar on a terminal"
fi
# A second evaluation set: every method scored on both; set 1 is the run above's.
expect_ok "$VC" compare office.obj --samples 20000 --max-cells 40 --methods av-s,kd-casm --eval-sets 2 -o cmp3 -q
python3 -c "
import csv, json
one = {(r['method'], r['cells']): r['cost'] for r in csv.DictReader(open('cmp/curves.csv'))}
rows = list(csv.DictReader(open('cmp3/curves.csv')))
assert rows and all(r['cost'] == one[(r['method'], r['cells'])] for r in rows)
assert all(float(r['cost_2']) > 0 for r in rows)
assert any(r['cost_2'] != r['cost'] for r in rows if int(r['cells']) > 1), 'the second set is not independent'
assert json.load(open('cmp3/summary.json'))['settings']['evaluation_sets'] == 2
# Set 1 scored on its first half too: sampled PVSs only grow, so no cost falls with the rest.
assert all(float(r['cost']) >= float(r['cost_half']) > 0 for r in rows)
assert any(float(r['cost']) > float(r['cost_half']) for r in rows), 'the second half added nothing anywhere'
rise = {m['method']: m['evaluator_second_half_rise'] for m in json.load(open('cmp3/summary.json'))['methods']}
assert set(rise) == {'av-s', 'kd-casm'} and all(r['first_half_samples'] == 40960 and r['largest'] >= 0 for r in rise.values()), rise
" && ok || bad "compare with two evaluation sets"
expect_error "--eval-sets" "$VC" compare office.obj --samples 1000 --eval-sets 0 -o cmp2
expect_error "unknown subdivision method 'kd-foo'" "$VC" compare office.obj --samples 1000 --methods av-m,kd-foo -o cmp2
[ ! -e cmp2 ] && ok || bad "a refused compare created its output directory"
head -c 100 office.vcells > cut.vcells
expect_error "cut.vcells" "$VC" export cut.vcells --mesh x.ply
expect_error "nothing to export" "$VC" export office.vcells
expect_error "outside the view space" "$VC" export office.vcells --slice-png x.png --slice-z 1000

# q3-clusters needs a Quake 3 map; and a real map, when fetched (CI fetches it).
expect_error "q3-clusters needs a Quake 3 map" "$VC" compare office.obj --samples 1000 --methods av-m,q3-clusters -o cmpq
if [ -n "$MAPS" ] && [ -f "$MAPS/oa_dm2.bsp" ]; then
  expect_ok "$VC" info "$MAPS/oa_dm2.bsp"
  grep -q "1041 clusters" out.txt && ok || bad "info lacks the map's clusters"
  expect_ok "$VC" compare "$MAPS/oa_dm2.bsp" --samples 100000 --methods av-m,q3-clusters -o q3cmp -q
  python3 -c "
import json, math
s = json.load(open('q3cmp/summary.json'))
q = s['q3map2']
assert q['clusters'] == 1041 and q['q3map2_cost'] > 0, q
assert q['av_m_cost_at_clusters'] is not None and q['pvs_size_ratio'] > 0, q
assert sum(q['excluded_by_cause'].values()) == q['excluded_but_seen'], q
assert 'non-solid' in s['view_space'], s['view_space']
" && ok || bad "compare on oa_dm2: summary"
  grep -q "^q3-clusters,1041," q3cmp/curves.csv && ok || bad "curves lack q3-clusters"
  [ "$(wc -l < q3cmp/excluded.csv)" -ge 1 ] && ok || bad "no excluded.csv"
  expect_error "needs av-m" "$VC" compare "$MAPS/oa_dm2.bsp" --samples 1000 --methods av-s,q3-clusters -o q3bad
  expect_error "not one surface" "$VC" compare "$MAPS/oa_dm2.bsp" --samples 1000 --objects components -o q3bad
  expect_ok "$VC" build "$MAPS/oa_dm2.bsp" --samples 50000 --max-cells 100 -o dm2.vcells --report dm2.json -q
  [ "$(json_get dm2.json "['settings']['view_box_source']")" = "the map's non-solid leaves" ] && ok || bad "build on a map: view box"
  # measure: the map's own PVS (q3map2's vis rows) and a baked one, by the same play cameras.
  expect_ok "$VC" measure "$MAPS/oa_dm2.bsp" --count 300 --width 64 --height 48 --report q3m.json -q
  [ "$(json_get q3m.json "['cells']")" = "1041" ] && ok || bad "measure on oa_dm2: $(json_get q3m.json "['cells']") clusters"
  # By default at 1024x768, what players see, cast as coherent packets; the report gives both rates.
  expect_ok "$VC" measure "$MAPS/oa_dm2.bsp" --count 8 --report q3big.json -q
  python3 -c "
import json; r = json.load(open('q3big.json')); c = r['cameras']
assert (c['width'], c['height'], c['count']) == (1024, 768, 8), c
p = c['primary_rays_per_second']; assert p['coherent'] > 0 and p['incoherent'] > 0 and p['rays_timed'] > 0, p
e = r['pixel_error']; assert 0 <= e['median_pixels'] <= e['p99_pixels'] <= e['worst_pixels'], e
assert e['frames_with_wrong_pixels_share'] == e['cameras_with_wrong_pixels'] / 8, e
" && ok || bad "measure at its default resolution: report"
  # (Fewer near-object samples than the default, which took 10 s of this test's 36 in these two
  # bakes; the office's bakes here run them at the default.)
  expect_ok "$VC" bake "$MAPS/oa_dm2.bsp" --cells 40 --samples 50000 --max-cells 100 --merge-pvs samples \
    --agvs-samples 100000 --near-samples 128 --near-eyes 32 -o dm2.pvs --report dm2bake.json -q
  [ "$(json_get dm2bake.json "['effects']['restricted_view_space']['enabled']")" = "True" ] && ok || bad "bake on a map: AGVS not in the view space"
  # On a map, bake weighs cells and draws AGVS's points in the play space unless told not to.
  [ "$(json_get dm2bake.json "['settings']['play_space']")" = "True" ] && ok || bad "bake on a map: the play space is not the default"
  json_get dm2bake.json "['effects']['restricted_view_space']['reason']" | grep -q "play space" && ok ||
    bad "bake on a map: the report does not say AGVS drew in the play space"
  expect_error "excludes" "$VC" bake "$MAPS/oa_dm2.bsp" --cells 40 --play-space --no-play-space -o dm2bad.pvs
  # view on a map draws no play space from floors (its own is the BSP's), and says so.
  "$VC" view dm2.pvs --scene "$MAPS/oa_dm2.bsp" --gltf dm2view.glb 2> view.err && ok || bad "view on a map failed"
  grep -q "play space not drawn: a Quake 3 map" view.err && ok || bad "view on a map: $(grep 'play space' view.err)"
  expect_ok "$VC" info dm2view.glb --list
  ! grep -q 'play space' out.txt && ok || bad "view on a map drew a play space from floors"
  expect_error "not expected" "$VC" build "$MAPS/oa_dm2.bsp" --no-play-space -o dm2bad.vcells
  # bake --measured-error: stops when the play cameras measure it, and measure agrees with its report.
  expect_ok "$VC" bake "$MAPS/oa_dm2.bsp" --cells 40 --samples 50000 --max-cells 100 --merge-pvs samples \
    --measured-error 300 --measure-cameras 300 --no-play-space --near-samples 128 --near-eyes 32 -o dm2m.pvs \
    --report dm2mbake.json -q
  [ "$(json_get dm2mbake.json "['settings']['play_space']")" = "False" ] &&
    json_get dm2mbake.json "['effects']['restricted_view_space']['reason']" | grep -q "non-solid space" && ok ||
    bad "bake --no-play-space on a map: still the play space"
  expect_ok "$VC" measure "$MAPS/oa_dm2.bsp" dm2m.pvs --count 300 --width 64 --height 48 --report dm2mm.json -q
  python3 -c "
import json
b, m = json.load(open('dm2mbake.json')), json.load(open('dm2mm.json'))
e = b['measured_pixel_error']
assert e['pixels'] <= 300 and e['cameras'] == 300 and 'spawn points' in e['placement'], e
assert b['agvs']['stop_reason'].startswith('measured pixel error'), b['agvs']['stop_reason']
# The near-object samples after AGVS (bake's default) only add entries: the file written shows
# at most what AGVS's last measurement did.
assert e['pixels'] <= b['measured_curve'][-1]['measured_pixels'], (b['measured_curve'][-1], e)
assert abs(m['pixel_error']['pixels'] - e['pixels']) <= 1e-9 * max(1, e['pixels']), (m['pixel_error'], e)
" && ok || bad "bake --measured-error on oa_dm2: the report and measure disagree"
  expect_ok "$VC" measure "$MAPS/oa_dm2.bsp" dm2.pvs --count 300 --width 64 --height 48 --report ourm.json -q
  [ "$(json_get ourm.json "['cells']")" = "40" ] && ok || bad "measure of a baked map: cells"
  [ "$(json_get ourm.json "['cameras']['placement']")" = "$(json_get q3m.json "['cameras']['placement']")" ] &&
    [ "$(json_get ourm.json "['cameras']['points_drawn']")" = "$(json_get q3m.json "['cameras']['points_drawn']")" ] &&
    ok || bad "measure: the two sides met different cameras"
  python3 -c "
import json, sys
for f in ('q3m.json', 'ourm.json'):
    r = json.load(open(f))
    assert r['frame']['cost'] > 0 and r['frame']['triangles'] > 0, f
    assert 0 <= r['pixel_error']['share'] <= 1, f
    assert sum(r['pixel_error']['by_cause'].values()) == round(r['pixel_error']['share'] * 300 * 64 * 48), f
    assert 'spawn points' in r['cameras']['placement'], f
" && ok || bad "measure on oa_dm2: report"
  expect_error "play cameras: the scene has no play space" "$VC" measure lowroom.obj lowroom.pvs --cameras play
  expect_error "was not made for the scene" "$VC" measure office.obj dm2.pvs
elif [ -n "${VIEWCELLS_REQUIRE_MAPS:-}" ]; then
  bad "oa_dm2.bsp is missing (scripts/fetch-maps.sh)"
fi

# A failing run leaves what was already written untouched.
cp a.vseg keep.vseg
cp a.json keep.json
expect_error "nan.obj" "$VC" sample nan.obj -o a.vseg --report a.json
cmp -s a.vseg keep.vseg && cmp -s a.json keep.json && ok || bad "a failed run changed existing outputs"
expect_error "cannot" "$VC" generate office -o no/such/dir/x.obj
# A run that fails at a later output (the report's directory does not exist) replaces none.
expect_error "no/such" "$VC" sample office.obj --samples 2000 -q -o a.vseg --report no/such/r.json
cmp -s a.vseg keep.vseg && ok || bad "a run failing at its report replaced -o"
expect_error "no/such" "$VC" build office.obj --samples 3000 --max-cells 8 -q -o keep.vcells --mesh no/such/m.ply
[ ! -e keep.vcells ] && ok || bad "a build failing at --mesh wrote -o"
ls ./*.tmp.* >/dev/null 2>&1 && bad "temporary files left behind" || ok
# Outputs onto inputs, onto each other, or onto what is not a regular file are refused up front.
cp office.obj victim.obj
expect_error "is an input" "$VC" sample victim.obj --samples 1000 -o victim.obj
cmp -s office.obj victim.obj && ok || bad "-o onto the input scene changed it"
expect_error "two outputs" "$VC" sample office.obj --samples 1000 -o same.json --report same.json
expect_error "not a regular file" "$VC" sample office.obj --samples 1000 -o /dev/null
[ -c /dev/null ] && ok || bad "/dev/null is no longer a device"
mkfifo fifo.vseg && expect_error "not a regular file" "$VC" sample office.obj --samples 1000 -o fifo.vseg
ln -sf keep.vseg link.vseg && expect_error "not a regular file" "$VC" sample office.obj --samples 1000 -o link.vseg
# Options are checked before any work, with what is allowed.
expect_error "whole number from 1" "$VC" sample office.obj --samples -1 -o x.vseg
expect_error "whole number from 1" "$VC" build office.obj --max-cells 0 -o x.vcells
expect_error "whole number from 16" "$VC" build office.obj --slice-png s.png --slice-width 0 -o x.vcells
expect_error "outside the view space" "$VC" build office.obj --samples 2000 --slice-png s.png --slice-z 1000 -o x.vcells -q
[ ! -e x.vcells ] && ok || bad "a build with a bad --slice-z wrote -o"
expect_error "above 0" "$VC" pvs keep.vcells --scene office.obj --pixel-error 0 -o x.pvs
expect_error "whole number from 1" "$VC" pvs keep.vcells --scene office.obj --samples 10 --measure-cameras 4294967295 -o x.pvs
expect_error "unknown Embree ISA" "$VC" --embree-isa avx9 sample office.obj -o x.vseg
# Rays Embree cannot take, and scenes single precision cannot resolve, are errors, not aborts.
expect_error "invalid ray" "$VC" sample office.obj --samples 1000 -q --view-box 1e19,0,0,1.0000001e19,1,1 -o x.vseg
{ cat office.obj; printf 'o stray\nv 1e7 0 0\nv 10000001 0 0\nv 1e7 1 0\nf -3 -2 -1\n'; } > stray.obj
expect_error "object 'stray'" "$VC" sample stray.obj --samples 1000 -q -o x.vseg
# The cells PLY that viewcells writes loads back as a scene; cut anywhere, it is an error.
expect_ok "$VC" info cells.ply
header=$(grep -abo end_header cells.ply | cut -d: -f1)
for n in 1 4 12 30 60 $((header / 2)) $((header + 5)) $((header + 200)) $(( $(stat -c %s cells.ply) - 3 )); do
  head -c "$n" cells.ply > cut.ply
  expect_error "cut.ply" timeout 20 "$VC" -q info cut.ply
  [ ! -s err.txt ] || [ "$(wc -l < err.txt)" -le 3 ] && ok || bad "a cut PLY floods stderr ($(wc -l < err.txt) lines)"
done
printf 'OFF\n3 1000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n' > invented.off
expect_error "1000 faces" "$VC" info invented.off
# Reports and file headers say which Embree ISA cast the rays.
expect_ok "$VC" --embree-isa sse4.2 sample office.obj --samples 2000 -q -o isa.vseg --report isa.json
[ "$(json_get isa.json "['embree_isa']")" = "sse4.2" ] && ok || bad "the report lacks the Embree ISA"
[ "$(od -An -tu1 -j6 -N1 isa.vseg | tr -d ' ')" = "2" ] && ok || bad "the .vseg header lacks the Embree ISA code"

# bake: the whole chain under a budget; the file written holds the budget, and a viewpoint is
# looked up in it. Threads do not change it; a rerun with a work directory reuses the hierarchy.
expect_ok "$VC" bake office.obj --cells 12 --samples 20000 --agvs-samples 100000 -o bake1.pvs --report bake.json \
  --threads 1 --work bakework -q
expect_ok "$VC" bake office.obj --cells 12 --samples 20000 --agvs-samples 100000 -o bake2.pvs --threads 2 -q
cmp -s bake1.pvs bake2.pvs && ok || bad "bake differs between 1 and 2 threads"
[ "$(json_get bake.json "['cells']")" = "12" ] && ok || bad "bake wrote $(json_get bake.json "['cells']") cells, not 12"
[ "$(json_get bake.json "['file_bytes']")" = "$(stat -c %s bake1.pvs)" ] && ok || bad "bake.json file_bytes is not the file's size"
expect_ok "$VC" query bake1.pvs 2 2 1.5
grep -q "of 12 (exactly 12 cells; PVS by agvs)" out.txt && ok || bad "query on a baked file: $(head -1 out.txt)"
expect_ok "$VC" bake office.obj --cells 12 --samples 20000 --agvs-samples 200000 -o bake3.pvs --report bake3.json \
  --work bakework -q
[ "$(json_get bake3.json "['effects']['hierarchy_reused']['enabled']")" = "True" ] && ok || bad "bake did not reuse the work directory's hierarchy"
[ "$(json_get bake3.json "['effects']['agvs_resumed']['enabled']")" = "True" ] && ok || bad "bake did not continue the saved AGVS state"
# A bake cut off during AGVS (kill -9) continues from its last checkpoint when run again, and
# writes what an uninterrupted bake writes.
expect_ok "$VC" bake office.obj --cells 12 --samples 20000 --agvs-samples 1000000 -o direct.pvs -q
"$VC" bake office.obj --cells 12 --samples 20000 --agvs-samples 1000000 -o killed.pvs --work killwork \
  --checkpoint 0.1 2>kill.txt &
pid=$!
for _ in $(seq 100); do grep -q "checkpoint after" kill.txt 2>/dev/null && break; sleep 0.1; done
kill -9 "$pid" 2>/dev/null
wait "$pid" 2>/dev/null
[ ! -e killed.pvs ] && ok || bad "a bake killed mid-way wrote its output"
expect_ok "$VC" bake office.obj --cells 12 --samples 20000 --agvs-samples 1000000 -o killed.pvs --work killwork \
  --checkpoint 0.1 --report killed.json -q
[ "$(json_get killed.json "['effects']['agvs_resumed']['enabled']")" = "True" ] && ok || bad "the killed bake did not continue from its checkpoint"
cmp -s direct.pvs killed.pvs && ok || bad "a bake resumed after kill -9 differs from an uninterrupted one"
for budget in 3000 6K 20000; do
  expect_ok "$VC" bake office.obj --memory "$budget" --samples 20000 --max-cells 300 --agvs-samples 50000 -o mem.pvs -q \
    --report mem.json
  bytes=$(stat -c %s mem.pvs)
  limit=$(python3 -c "print(int(float('$budget'.rstrip('K')) * (1024 if '$budget'.endswith('K') else 1)))")
  [ "$bytes" -le "$limit" ] && ok || bad "bake --memory $budget wrote $bytes bytes"
done
# --memory-of lists: the budget holds for the compressed lists alone, and buys more cells than
# the same budget for the whole file; measure reports the same list bytes.
expect_ok "$VC" bake office.obj --memory 3000 --memory-of lists --samples 20000 --max-cells 300 --agvs-samples 50000 \
  -o meml.pvs -q --report meml.json
[ "$(json_get meml.json "['budget']['counts']")" = lists ] && [ "$(json_get meml.json "['list_bytes']")" -le 3000 ] && ok ||
  bad "bake --memory-of lists: $(json_get meml.json "['list_bytes']") list bytes"
expect_ok "$VC" bake office.obj --memory 3000 --samples 20000 --max-cells 300 --agvs-samples 50000 -o memf.pvs -q \
  --report memf.json
[ "$(json_get meml.json "['cells']")" -ge "$(json_get memf.json "['cells']")" ] && ok ||
  bad "3000 bytes of lists hold fewer cells than a 3000-byte file"
expect_ok "$VC" measure office.obj meml.pvs --count 20 --width 8 --height 8 --report memlm.json -q
[ "$(json_get memlm.json "['pvs_bytes']")" = "$(json_get meml.json "['list_bytes']")" ] && ok || bad "measure's pvs_bytes differ from bake's list_bytes"
# The same cameras again from a file: the same frames, the same cost and wrong pixels; in another
# unit (the file is in metres), the eyes move with the scene.
expect_ok "$VC" measure office.obj meml.pvs --count 20 --width 8 --height 8 --cameras-out cams.json --report camo.json -q
expect_ok "$VC" measure office.obj meml.pvs --cameras-from cams.json --width 8 --height 8 --report cami.json -q
python3 -c "
import json; a = json.load(open('camo.json')); b = json.load(open('cami.json')); c = json.load(open('cams.json'))
assert a['frame'] == b['frame'] and a['pixel_error']['pixels'] == b['pixel_error']['pixels'], (a['frame'], b['frame'])
assert len(c['cameras']) == 20 and all(len(x) == 9 for x in c['cameras']), c
" && ok || bad "measure --cameras-from: not the same frames"
echo '{"format": "viewcells cameras 1", "cameras": [[0, 0, 1, 0, 0, 0, 0, 0, 1]]}' > badcams.json
expect_error "camera 0: forward and up must be unit vectors" "$VC" measure office.obj meml.pvs --cameras-from badcams.json
echo '{"cameras": []' > badcams.json
expect_error "badcams.json: not a cameras file" "$VC" measure office.obj meml.pvs --cameras-from badcams.json
expect_error "file or lists" "$VC" bake office.obj --memory 3000 --memory-of everything -o x.pvs
# Frames as a sampler: the report says how many frames added how many entries.
expect_ok "$VC" bake office.obj --cells 12 --samples 20000 --max-cells 60 --agvs-samples 20000 --frame-samples 8 \
  --frame-size 64x48 -o framed.pvs --report framed.json -q
python3 -c "
import json; r = json.load(open('framed.json')); e = r['effects']['frame_samples']
assert e['enabled'] and '96 frames of 64x48' in e['reason'], e
assert r['settings']['view_space'].startswith('the play space'), r['settings']['view_space']
" && ok || bad "bake --frame-samples: report"
expect_error "WIDTHxHEIGHT" "$VC" bake office.obj --cells 12 --frame-samples 8 --frame-size 64 -o x.pvs
# Rounds: after the first, frames only where the last ones still found something. Invariant (any
# CPU's samples): round k + 1 runs exactly when round k added an entry; with one AGVS batch of
# 1,000 samples the first round adds some.
"$VC" bake office.obj --cells 12 --samples 20000 --max-cells 60 --agvs-samples 1000 --batch 1000 --frame-samples 8 \
  --frame-size 64x48 --frame-rounds 3 -o framed3.pvs 2>err.txt
python3 -c "
import re
rounds = [(int(k), int(a)) for k, a in re.findall(r'frame round (\d+): \d+ frames in \d+ cells added (\d+) entries', open('err.txt').read())]
assert rounds and rounds[0][0] == 1 and rounds[0][1] > 0, rounds
for (k, added), nxt in zip(rounds, rounds[1:] + [None]):
    assert (nxt is not None) == (added > 0 and k < 3), rounds
" && ok || bad "bake --frame-rounds 3: $(grep 'frame round' err.txt)"
# Near-object samples: after one AGVS batch, neighbours of what the cells see are tested and the
# visible ones added (invariant on any CPU: the file holds at least the entries without them,
# and the report counts what was tested and added).
expect_ok "$VC" bake office.obj --cells 12 --samples 20000 --max-cells 60 --agvs-samples 1000 --batch 1000 \
  --near-samples 0 -o unnear.pvs --report unnear.json -q
expect_ok "$VC" bake office.obj --cells 12 --samples 20000 --max-cells 60 --agvs-samples 1000 --batch 1000 \
  --near-samples 32 --near-eyes 16 -o near.pvs --report near.json -q
python3 -c "
import json, re
a, b = json.load(open('unnear.json')), json.load(open('near.json'))
e = b['effects']['near_samples']
tested, added = map(int, re.match(r'(\d+) \(cell, neighbouring object\) pairs tested .* added (\d+) PVS entries', e['reason']).groups())
assert e['enabled'] and tested > 0 and b['pvs_entries'] == a['pvs_entries'] + added, (e, a['pvs_entries'], b['pvs_entries'])
assert not a['effects']['near_samples']['enabled']
" && ok || bad "bake --near-samples: report"
expect_error "near-samples" "$VC" bake office.obj --cells 12 --near-samples 5000 -o x.pvs
# Where no viewpoint can be placed (the view box inside a closed cube, sampled with empty space
# detection off), bake's default near-object samples are skipped, said so, and the bake succeeds.
printf 'v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nf 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n' > cube.obj
expect_ok "$VC" bake cube.obj --cells 2 --samples 20000 --agvs-samples 20000 --view-box 0.2,0.2,0.2,0.8,0.8,0.8 \
  --empty-space off -o cube.pvs --report cube.json -q
python3 -c "
import json; e = json.load(open('cube.json'))['effects']['near_samples']
assert not e['enabled'] and 'no viewpoints' in e['reason'], e
" && ok || bad "bake: near-object samples without viewpoints should be skipped"
cp bake1.pvs keep.pvs
expect_error "too small" "$VC" bake office.obj --memory 50 --samples 20000 --max-cells 300 --agvs-samples 50000 \
  -o keep.pvs -q
cmp -s bake1.pvs keep.pvs && ok || bad "a failing bake replaced its output"
expect_error "needs a budget" "$VC" bake office.obj -o x.pvs
expect_error "excludes" "$VC" bake office.obj --cells 4 --memory 1M -o x.pvs

# measure: frames at cameras for a .pvs of any scene; a map is needed for its own PVS.
expect_ok "$VC" measure office.obj bake1.pvs --count 200 --width 16 --height 16 --report om.json -q
[ "$(json_get om.json "['cells']")" = "12" ] && ok || bad "measure: cells"
grep -q "view box" <<<"$(json_get om.json "['cameras']['placement']")" && ok || bad "measure: cameras not in the view box"
expect_ok "$VC" measure office.obj bake1.pvs --count 200 --width 16 --height 16 --report om2.json -q --threads 1
[ "$(json_get om.json "['pixel_error']['share']")" = "$(json_get om2.json "['pixel_error']['share']")" ] && ok || bad "measure differs between thread counts"
expect_error "needs a .pvs file" "$VC" measure office.obj
expect_error "unknown camera placement" "$VC" measure office.obj bake1.pvs --cameras everywhere
expect_error "--width" "$VC" measure office.obj bake1.pvs --width 100000

# Hostile input (issue: the runtime never crashes an engine, every run is bounded): each case
# a clear error and a non-zero exit before any work, or a bounded run; earlier files untouched.
expect_error "above the ceiling of 4294967296" "$VC" measure office.obj bake1.pvs --count 10000000
expect_error "above the ceiling" "$VC" measure office.obj bake1.pvs --count 2000 --width 2048 --height 2048
expect_error "give a number from 1 to 179" "$VC" measure office.obj bake1.pvs --fov nan
expect_error "must be a number from 0 to 1e12" "$VC" bake office.obj --cells 5 --cost-b 1e308 -o x.pvs
expect_error "must be a number from 0 to 1e12" "$VC" measure office.obj bake1.pvs --cost-b 1e308
expect_error "elementary cells of --max-cells" "$VC" bake office.obj --cells 5 --max-cells 2 -o x.pvs
expect_error "above 0 bytes" "$VC" bake office.obj --memory 0 -o x.pvs
expect_error "its directory nodir does not exist" "$VC" bake office.obj --cells 5 -o nodir/x.pvs
expect_error "its directory nodir does not exist" "$VC" bake office.obj --cells 5 -o keep.pvs --report nodir/r.json
cmp -s bake1.pvs keep.pvs && ok || bad "a bake refused for its report path replaced its output"
expect_error "empty value" "$VC" bake office.obj --cells 5 -o ""
expect_error "also given as an output file" "$VC" bake office.obj --cells 5 -o samedir --work samedir
touch afile
expect_error "exists and is not a directory" "$VC" bake office.obj --cells 5 -o x.pvs --work afile
# A .pvs inside the work directory would break every later run with it (issue 67).
mkdir -p wdir
expect_error "is inside the work directory wdir" "$VC" bake office.obj --cells 5 -o wdir/hierarchy.vcells --work wdir
[ -z "$(ls wdir)" ] && ok || bad "a refused bake wrote into its work directory: $(ls wdir)"
# Seeds are whole numbers that fit 64 bits: -1 and 2^64 used to run as 2^64 - 1 (issue 67).
expect_error "--seed: '-1' is not allowed" "$VC" bake office.obj --cells 5 --seed -1 -o x.pvs
expect_error "--seed: '18446744073709551616' is not allowed" "$VC" bake office.obj --cells 5 --seed 18446744073709551616 -o x.pvs
expect_error "--seed: '99999999999999999999999' is not allowed" "$VC" measure office.obj bake1.pvs --seed 99999999999999999999999
# 309-digit numbers are printed as 1.000e+308.
"$VC" query bake1.pvs 1e308 0 0 >out.txt 2>err.txt
grep -q "1.000e+308" err.txt && [ "$(wc -c <err.txt)" -lt 200 ] && ok || bad "query 1e308: $(cat err.txt)"
# --time bounds the whole bake, also a merge that would never reach its pixel error (4 s: the hierarchy,
# play space included, takes about 2 s of it on 2 busy cores).
start=$(date +%s)
expect_ok "$VC" bake office.obj --cells 5 --samples 5000 --merge-pixel-error 1e-300 --time 4 -o timed.pvs -q
[ $(( $(date +%s) - start )) -lt 30 ] && ok || bad "bake --time 4 took $(( $(date +%s) - start )) s"
# ... and its measurements and frame samples (issue 67: 1,000 frames of 1024x768 ran 40-76 s
# past --time 5). A generous bound, twice the limit and five seconds: the overshoot is one
# frame, one batch of rays and the file's writing.
for extra in "--holes 1%" "--measure-cameras 1000 --measure-size 2048x2048 --pixel-error 1" \
             "--frame-samples 200 --frame-size 2048x2048"; do
  start=$(date +%s)
  # shellcheck disable=SC2086
  expect_ok "$VC" bake office.obj --cells 5 --samples 5000 --time 5 $extra -o timed.pvs --report timed.json -q
  [ $(( $(date +%s) - start )) -lt 15 ] && ok || bad "bake --time 5 $extra took $(( $(date +%s) - start )) s"
done
# Ctrl-C stops a long measurement cleanly: exit 130, no report written.
rm -f sigint.json
"$VC" measure office.obj bake1.pvs --count 1000000 --width 32 --height 32 --report sigint.json -q 2>err.txt &
pid=$!
sleep 1  # the measurement is under way by then
kill -INT $pid
wait $pid
rc=$?
[ $rc -eq 130 ] && grep -q "interrupted" err.txt && [ ! -e sigint.json ] && ok || bad "measure after SIGINT: exit $rc ($(cat err.txt))"
# Another scene under a slice: an error, not a drawing of the wrong geometry.
expect_error "is not the scene" "$VC" export office.vcells --slice-png other.png --scene rotated.obj
expect_error "is not the scene" "$VC" extract office.vcells --count 4 --slice-png other.png --scene rotated.obj
# glTF: a NaN vertex, lines only, the whole view space inside one closed solid.
python3 - <<'PY'
import base64, json, struct
def gltf(path, verts, idx, mode=4):
    vb = b''.join(struct.pack('<3f', *v) for v in verts)
    ib = b''.join(struct.pack('<I', i) for i in idx)
    fin = [v for v in verts if all(c == c and abs(c) != float('inf') for c in v)] or [(0, 0, 0)]
    doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"name": "box", "mesh": 0}],
           "meshes": [{"name": "box", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": mode}]}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": len(verts), "type": "VEC3",
                          "min": [min(v[k] for v in fin) for k in range(3)], "max": [max(v[k] for v in fin) for k in range(3)]},
                         {"bufferView": 1, "componentType": 5125, "count": len(idx), "type": "SCALAR"}],
           "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(vb)},
                           {"buffer": 0, "byteOffset": len(vb), "byteLength": len(ib)}],
           "buffers": [{"byteLength": len(vb) + len(ib),
                        "uri": "data:application/octet-stream;base64," + base64.b64encode(vb + ib).decode()}]}
    open(path, 'w').write(json.dumps(doc))
box = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
tris = [0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4, 1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7]
gltf('solid.gltf', box, tris)
gltf('nan.gltf', [(float('nan'), 0, 0)] + box[1:], tris)
gltf('lines.gltf', box, tris, mode=1)
PY
expect_error "whose coordinates are not finite" "$VC" info nan.gltf
expect_error "holds no triangles" "$VC" info lines.gltf
expect_error "0 valid segments" "$VC" bake solid.gltf --cells 2 --samples 5000 -o x.pvs

echo "cli: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
