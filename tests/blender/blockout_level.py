"""A level blocked out in Blender the way designers do (a hall and a second room through a
doorway, stairs up to a balcony over the hall, a ramp up to a platform, a window, a closet nobody
can enter, a roof, a "PlayerStart" empty), exported by Blender's own glTF exporter, then read by
viewcells: the play space is found from its floors and the start point in the file, and bake
uses it by default. Run by ctest (tests/CMakeLists.txt):
  blender -b --factory-startup --python-exit-code 1 --python blockout_level.py -- VIEWCELLS WORK
"""
import json
import math
import os
import subprocess
import sys

argv = sys.argv[sys.argv.index("--") + 1:]
cli, work = argv
os.makedirs(work, exist_ok=True)

import numpy  # noqa: E402

numpy.bool = bool  # Blender 3.4's glTF exporter uses numpy.bool, removed in numpy 1.24
import bpy  # noqa: E402

bpy.ops.wm.read_factory_settings(use_empty=True)


def box(name, lo, hi):
    """An axis-aligned box from corner lo to corner hi (metres, z up)."""
    centre = [(a + b) / 2 for a, b in zip(lo, hi)]
    bpy.ops.mesh.primitive_cube_add(location=centre)
    o = bpy.context.active_object
    o.name = name
    o.scale = [(b - a) / 2 for a, b in zip(lo, hi)]
    return o


box("floor", (-10, -6, -0.2), (10, 6, 0))
box("wall_south", (-10, -6.2, 0), (10, -6, 6))
box("wall_west", (-10.2, -6, 0), (-10, 6, 6))
box("wall_east", (10, -6, 0), (10.2, 6, 6))
box("wall_north_a", (-10, 6, 0), (5, 6.2, 6))  # the window: x 5..7, z 1..2 in the north wall
box("wall_north_b", (7, 6, 0), (10, 6.2, 6))
box("wall_north_sill", (5, 6, 0), (7, 6.2, 1))
box("wall_north_lintel", (5, 6, 2), (7, 6.2, 6))
box("divider_a", (1.9, -6, 0), (2.1, -1, 6))  # hall (x < 2) | room (x > 2), a doorway y -1..1
box("divider_b", (1.9, 1, 0), (2.1, 6, 6))
box("lintel", (1.9, -1, 2.5), (2.1, 1, 6))
box("balcony", (-10, -6, 2.8), (-7, 6, 3.0))  # over the hall along its west wall
for k in range(15):  # stairs along the south wall, 0.2 m up each 0.25 m west, to the balcony
    box(f"step_{k:02d}", (-3.25 - 0.25 * (k + 1), -6, 0), (-3.25 - 0.25 * k, -4.5, 0.2 * (k + 1)))
box("platform", (7, 3, 0), (10, 6, 1))  # in the room, reached by a ramp
ramp = box("ramp", (4, 3, -0.1), (7.16, 6, 0.1))
ramp.rotation_euler = (0, -math.atan2(1, 3), 0)  # rises 1 m over 3 m towards the platform
ramp.location = (5.5, 4.5, 0.5 - 0.1)
box("closet_a", (7.9, -6, 0), (8.1, -4, 6))  # a closet in the room's corner, walled shut
box("closet_b", (8, -4.1, 0), (10, -3.9, 6))
box("roof", (-10.2, -6.2, 6), (10.2, 6.2, 6.2))
bpy.ops.object.empty_add(location=(-5, 0, 0.1))
bpy.context.active_object.name = "PlayerStart"
bpy.context.view_layer.update()

level = os.path.join(work, "blockout.glb")
bpy.ops.export_scene.gltf(filepath=level, export_format="GLB")

probes = {
    "hall": (-5, 2, 1.6),
    "room, through the doorway": (5, -2, 1.6),
    "balcony, by the stairs": (-8.5, 0, 3.0 + 1.6),
    "top of the stairs": (-6.8, -5.2, 3.0 + 1.6),
    "platform, by the ramp": (8.5, 4.5, 1.0 + 1.6),
    "under the balcony": (-8.5, 0, 1.6),
}
outside = {
    "closet": (9, -5, 1.6),
    "on the roof": (0, 0, 6.2 + 1.6),
    "between the roof and the floor, too high": (-5, 2, 4.5),
    "under the floor": (-5, 2, -1),
}
report = os.path.join(work, "play.json")
args = [cli, "-q", "play-space", level, "--report", report]
for p in list(probes.values()) + list(outside.values()):
    args += ["--at", ",".join(str(x) for x in p)]
subprocess.run(args, check=True)
r = json.load(open(report))
assert r["found"] and "reachable from 1 of 1 start points" in r["rule"] and "from the file" in r["rule"], r["rule"]
answers = [p["in"] for p in r["probes"]]
names = list(probes) + list(outside)
wrong = [n for n, a, want in zip(names, answers, [True] * len(probes) + [False] * len(outside)) if a != want]
assert not wrong, f"wrong answers for {wrong}: {r['probes']}"

bake_report = os.path.join(work, "bake.json")
subprocess.run([cli, "-q", "bake", level, "--cells", "16", "--samples", "50000", "--agvs-samples", "50000",
                "-o", os.path.join(work, "blockout.pvs"), "--report", bake_report], check=True)
b = json.load(open(bake_report))
assert b["settings"]["play_space"] and b["settings"]["view_space"].startswith("the play space"), b["settings"]
print("blockout level: play space found from Blender's glTF,", r["floor_area_m2"], "m^2 of floor; bake used it")
