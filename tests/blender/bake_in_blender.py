"""Bakes a small level built in Blender through the Python module viewcells, inside Blender
3.4 (Debian's, headless, its Python 3.11), and checks that the .pvs equals what the command
line bakes from the same level written as OBJ. Run by ctest (tests/CMakeLists.txt):
  blender -b --factory-startup --python-exit-code 1 --python bake_in_blender.py -- PYDIR VIEWCELLS WORK
"""
import os
import subprocess
import sys

argv = sys.argv[sys.argv.index("--") + 1:]
pydir, cli, work = argv
sys.path.insert(0, pydir)
os.makedirs(work, exist_ok=True)

import bpy  # noqa: E402
import numpy as np  # noqa: E402
import viewcells  # noqa: E402

# A room of 10 x 10 with a dividing wall and a doorway, a pillar, and a glass pane (its
# material's alpha below one: seen through).
bpy.ops.wm.read_factory_settings(use_empty=True)


def box(name, location, half):
    bpy.ops.mesh.primitive_cube_add(location=location)
    o = bpy.context.active_object
    o.name = name
    o.scale = half
    return o


box("floor", (0, 0, -0.1), (5, 5, 0.1))
box("wall_south", (0, -5, 1.5), (5, 0.1, 1.5))
box("wall_north", (0, 5, 1.5), (5, 0.1, 1.5))
box("wall_west", (-5, 0, 1.5), (0.1, 5, 1.5))
box("wall_east", (5, 0, 1.5), (0.1, 5, 1.5))
box("divider_a", (-3, 0, 1.5), (2, 0.1, 1.5))
box("divider_b", (3, 0, 1.5), (2, 0.1, 1.5))
box("pillar", (2, 2.5, 1.5), (0.3, 0.3, 1.5))
glass = box("glass", (-2.5, -2.5, 1.5), (0.05, 1, 1))
material = bpy.data.materials.new("glass")
material.diffuse_color = (0.6, 0.8, 1.0, 0.3)
glass.data.materials.append(material)
bpy.context.view_layer.update()

# One object per Blender object (sorted by name), in world space, triangulated; see-through
# where the material's alpha is below one.
depsgraph = bpy.context.evaluated_depsgraph_get()
vertices, triangles, objects, names, see_through = [], [], [], [], []
for o in sorted((o for o in bpy.data.objects if o.type == "MESH"), key=lambda o: o.name):
    mesh = o.evaluated_get(depsgraph).to_mesh()
    mesh.calc_loop_triangles()
    base = len(vertices)
    vertices += [tuple(o.matrix_world @ v.co) for v in mesh.vertices]
    for t in mesh.loop_triangles:
        triangles.append([base + i for i in t.vertices])
        objects.append(len(names))
    names.append(o.name)
    see_through.append(any(m is not None and m.diffuse_color[3] < 1 for m in o.data.materials))
    o.evaluated_get(depsgraph).to_mesh_clear()

settings = dict(cells=6, samples=30000, max_cells=24, agvs_samples=30000)
scene = viewcells.Scene(np.array(vertices), np.array(triangles), objects=np.array(objects), names=names,
                        see_through=see_through, name="blender-level")
baked = viewcells.bake(scene, os.path.join(work, "blender.pvs"), **settings)
print(f"viewcells in Blender {bpy.app.version_string}: {baked.cell_count} cells, "
      f"{scene.object_count} objects, PVS sizes {[len(baked.pvs(c)) for c in range(baked.cell_count)]}")

# The same level as OBJ (exact coordinates; the glass in a see-through material), baked by the
# command line: the same file, byte for byte.
with open(os.path.join(work, "level.mtl"), "w") as f:
    f.write("newmtl opaque\nd 1\nnewmtl glass\nd 0.3\n")
with open(os.path.join(work, "level.obj"), "w") as f:
    f.write("mtllib level.mtl\n")
    for v in vertices:
        f.write("v %r %r %r\n" % tuple(float(x) for x in v))
    for g, name in enumerate(names):
        f.write(f"o {name}\nusemtl {'glass' if see_through[g] else 'opaque'}\n")
        for t, o in zip(triangles, objects):
            if o == g:
                f.write("f %d %d %d\n" % tuple(i + 1 for i in t))
subprocess.run([cli, "-q", "bake", "level.obj", "--cells", "6", "--samples", "30000", "--max-cells", "24",
                "--agvs-samples", "30000", "-o", "cli.pvs"], cwd=work, check=True)
same = open(os.path.join(work, "blender.pvs"), "rb").read() == open(os.path.join(work, "cli.pvs"), "rb").read()
if not same:
    raise SystemExit("FAIL: the bake in Blender differs from the command line's bake of the same level")
glass_id = names.index("glass")
if not any(glass_id in baked.pvs(c) for c in range(baked.cell_count)):
    raise SystemExit("FAIL: the glass is in no PVS")
print("PASS")
