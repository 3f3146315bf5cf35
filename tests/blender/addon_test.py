"""The Blender add-on (tools/blender/viewcells_blender), headless in Debian's Blender 3.4: builds a
small level, bakes it through the add-on's operator, and checks that the cells and PVSs equal the
command line's bake of the same level exported to glTF by Blender's own exporter; then the cells
as meshes, "select its PVS", "show from here", one object per collection, and one rendered
image of the cells (Cycles on the CPU). Run by ctest (tests/CMakeLists.txt):
  blender -b --factory-startup --python-exit-code 1 --python addon_test.py -- PYDIR VIEWCELLS ADDON_DIR WORK
"""
import json
import os
import subprocess
import sys

argv = sys.argv[sys.argv.index("--") + 1:]
pydir, cli, addon_dir, work = argv
os.makedirs(work, exist_ok=True)
os.environ["VIEWCELLS_PYTHONPATH"] = pydir  # the add-on finds the module there, as a user sets it
sys.path.insert(0, addon_dir)

import bpy  # noqa: E402
import numpy as np  # noqa: E402

np.bool = bool  # Blender 3.4's glTF exporter uses numpy.bool, which numpy 1.24 removed

import viewcells_blender as addon  # noqa: E402


def fail(message):
    raise SystemExit("FAIL: " + message)


bpy.ops.wm.read_factory_settings(use_empty=True)
addon.register()
vc = addon.import_viewcells()


def box(name, location, half, rotation=0.0):
    bpy.ops.mesh.primitive_cube_add(location=location, rotation=(0, 0, rotation))
    o = bpy.context.active_object
    o.name = name
    o.scale = half
    return o


def material(name, see_through):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    bsdf = m.node_tree.nodes["Principled BSDF"]
    if see_through:
        m.blend_method = "BLEND"
        bsdf.inputs["Alpha"].default_value = 0.3
    else:
        bsdf.inputs["Base Color"].default_value = (0.7, 0.7, 0.68, 1)
    return m


# A room of 10 x 10, a dividing wall with a doorway, a rotated pillar, and a window in the west
# half: a frame (opaque) whose two large faces are glass (see-through), so one Blender object
# is two objects of the PVSs, as the glTF reader makes it.
wall = material("wall", False)
glass = material("glass", True)
parts = [box("floor", (0, 0, -0.1), (5, 5, 0.1)), box("wall_south", (0, -5, 1.5), (5, 0.1, 1.5)),
         box("wall_north", (0, 5, 1.5), (5, 0.1, 1.5)), box("wall_west", (-5, 0, 1.5), (0.1, 5, 1.5)),
         box("wall_east", (5, 0, 1.5), (0.1, 5, 1.5)), box("divider_a", (-3, 0, 1.5), (2, 0.1, 1.5)),
         box("divider_b", (3, 0, 1.5), (2, 0.1, 1.5)), box("pillar", (2, 2.5, 1.5), (0.3, 0.3, 1.5), 0.5),
         box("window", (-2.5, -2.5, 1.5), (0.05, 1, 1))]
# Furniture on both sides of the divider: what a cell sees, and so its cost, then differs.
for k, (x, y) in enumerate([(-4, -4), (-1, -4.2), (3.5, -3.5), (4, -1), (-4, 4), (-1.5, 3.5), (4, 4), (0.5, 1.2)]):
    parts.append(box(f"crate_{k}", (x, y, 0.4), (0.4, 0.4, 0.4), 0.3 * k))
for o in parts:
    o.data.materials.append(wall)
window = parts[8]
window.data.materials.append(glass)
for p in window.data.polygons:  # the faces across x are glass
    if abs(p.normal.x) > 0.5:
        p.material_index = 1
# Where players start: an empty the glTF export carries as a node, and the add-on as --start.
bpy.ops.object.empty_add(location=(-2.0, -3.5, 0.1))
bpy.context.active_object.name = "PlayerStart"
# Transforms applied, so that the add-on (which applies them in double) and the glTF file
# (which stores them in float) hold the very same coordinates.
bpy.ops.object.select_all(action="SELECT")
bpy.ops.object.transform_apply(location=True, rotation=True, scale=True)
bpy.context.view_layer.update()

# The level as glTF by Blender's exporter (y up, which the reader turns back to z up).
bpy.ops.export_scene.gltf(filepath=os.path.join(work, "level.glb"))

# The add-on's arrays hold the glTF reader's triangles in its order (objects in the view layer's
# order, an object's triangles grouped by material as the exporter writes its primitives): the
# two bakes below can then only differ if the add-on maps the level differently.
v, t, objects, object_names, see_through, _members = addon.scene_arrays(bpy.context)
gltf = vc.Scene.load(os.path.join(work, "level.glb"))
if object_names != gltf.names:
    fail(f"objects {object_names} against the glTF reader's {gltf.names}")
if not (np.array_equal(v[t], gltf.vertices[gltf.triangles]) and np.array_equal(objects, gltf.triangle_objects)):
    fail("the add-on's triangles differ from the glTF reader's")

# The play space, drawn: green floors 3 cm over the room's floor (z = 0; the crates, 0.8 m high,
# are neither stepped on nor 4 m^2), reached from the PlayerStart through the doorway, so both
# halves of the room. Drawn before the bake: the bake must leave the drawing out of the level
# (else its objects differ from the export's, below).
if bpy.ops.viewcells.show_play_space() != {"FINISHED"}:
    fail("Show play space failed")
play_obj = bpy.data.objects.get("viewcells play space")
if play_obj is None or addon.PLAY_COLLECTION not in [c.name for c in play_obj.users_collection]:
    fail("no play space object in its collection")
zs = np.array([p.co.z for p in play_obj.data.vertices])
xs = np.array([p.co.x for p in play_obj.data.vertices])
area = play_obj["floor_area_m2"]
print(f"play space: {len(play_obj.data.polygons)} faces, z {zs.min():.3f}-{zs.max():.3f}, {area:.1f} m^2 of floor, "
      f"x {xs.min():.2f} to {xs.max():.2f}")
if not (len(zs) and np.all(np.abs(zs - 0.03) < 1e-3)):
    fail("the play space's floors are not the room's floor")
if not (60 < area < 100 and xs.min() < -4 and xs.max() > 4):
    fail(f"the play space does not cover the room ({area:.1f} m^2, x {xs.min():.2f}..{xs.max():.2f})")
if "reachable from 1 of 1 start points" not in play_obj["rule"]:
    fail("the play space did not start from the PlayerStart: " + play_obj["rule"])

options = ["--samples", "30000", "--max-cells", "24", "--agvs-samples=30000", "--no-prove-hidden"]
s = bpy.context.scene.viewcells
s.cells = 6
s.time = 0
s.extra = " ".join(options)
s.output = os.path.join(work, "addon.pvs")
s.gltf = os.path.join(work, "addon-cells.glb")
if bpy.ops.viewcells.bake() != {"FINISHED"}:
    fail("the add-on's bake failed: " + s.status)
if open(s.gltf, "rb").read(4) != b"glTF":
    fail("no .glb written")
subprocess.run([cli, "-q", "bake", "level.glb", "--cells", "6", *options, "-o", "cli.pvs"], cwd=work, check=True)
ours, theirs = vc.read(s.output), vc.read(os.path.join(work, "cli.pvs"))
print(f"add-on: {ours.cell_count} cells, objects {list(ours.object_names)}")
if sorted(ours.object_names) != sorted(theirs.object_names) or "window (see-through)" not in ours.object_names:
    fail(f"objects differ: {ours.object_names} against the glTF's {theirs.object_names}")
if ours.cell_count != theirs.cell_count or not np.array_equal(ours.cell_bounds, theirs.cell_bounds):
    fail("the cells differ from the command line's bake of the glTF export")
for c in range(ours.cell_count):
    a = sorted(ours.object_names[i] for i in ours.pvs(c))
    b = sorted(theirs.object_names[i] for i in theirs.pvs(c))
    if a != b:
        fail(f"cell {c}: PVS {a} against the command line's {b}")
    for (va, fa), (vb, fb) in zip(ours.polyhedra(c), theirs.polyhedra(c)):
        if not np.array_equal(va, vb) or fa != fb:
            fail(f"cell {c}: its pieces differ")
print("the add-on's cells and PVSs equal the command line's bake of the glTF export")
# The add-on hands the empty to the bake as a start point, as the glTF reader reads the node.
_vc, scene_for_report, _out, start_options, _m = addon.VIEWCELLS_OT_bake.prepare(None, bpy.context)
if len(start_options.get("start", [])) != 1:
    fail(f"the add-on's bake options have no start point: {start_options}")
start_options.update(cells=2, samples=2000, agvs_samples=2000, max_cells=8)
view_space = vc.bake(scene_for_report, os.path.join(work, "start.pvs"), **start_options).report["settings"]["view_space"]
if "reachable from 1 of 1 start points" not in view_space:
    fail(f"the bake did not take the add-on's start point: {view_space}")
# "Add start point" puts a PlayerStart at the 3D cursor, which bakes then start from.
bpy.context.scene.cursor.location = (3.0, 3.0, 0.5)
if bpy.ops.viewcells.add_start() != {"FINISHED"}:
    fail("Add start point failed")
if sorted(addon.start_positions(bpy.context))[-1] != (3.0, 3.0, 0.5) or len(addon.start_positions(bpy.context)) != 2:
    fail(f"the new start point is not where the cursor was: {addon.start_positions(bpy.context)}")
for o in [o for o in bpy.data.objects if o.type == "EMPTY" and o.name != "PlayerStart"]:
    bpy.data.objects.remove(o)

# The cells: one translucent mesh each, coloured by render cost, holding id, cost and PVS.
cells = bpy.data.collections.get(addon.CELLS_COLLECTION)
if cells is None or len(cells.objects) != ours.cell_count:
    fail("the cells' collection is missing or incomplete")
read_back = vc.read(s.output, vc.Scene(v, t, objects=objects, names=object_names, see_through=see_through))
costs = read_back.cell_costs
for o in cells.objects:
    c = o["viewcells_cell"]
    if abs(o["render_cost"] - costs[c]) > 1e-9 * costs[c] or json.loads(o["pvs"]) != [ours.object_names[i] for i in ours.pvs(c)]:
        fail(f"{o.name}: its properties disagree with the file")
colours = {tuple(round(x, 3) for x in o.color[:3]) for o in cells.objects}
top = max(cells.objects, key=lambda o: o["render_cost"])
if tuple(top.color[:3]) != (1.0, 0.0, 0.0) or len(colours) < 3:
    fail(f"colours by render cost expected (the costliest red, at least 3 colours): {colours}")

# Select its PVS: a cell that does not see everything; its PVS's Blender objects are selected.
level = {o.name for o in addon.level_meshes(bpy.context)}
small = min(cells.objects, key=lambda o: o["pvs_size"])
names = json.loads(small["pvs"])
if len(names) >= len(ours.object_names):
    fail("every cell sees every object: the test level hides nothing")
expected = {n.replace(addon.SEE_THROUGH, "") for n in names}
bpy.context.view_layer.objects.active = small
if bpy.ops.viewcells.select_pvs() != {"FINISHED"}:
    fail("select_pvs did not run")
selected = {o.name for o in bpy.context.selected_objects if o.name in level}
if selected != expected:
    fail(f"selected {sorted(selected)}, the PVS is {sorted(expected)}")

# Show from here: the 3D cursor in that cell hides what its PVS does not list.
c = small["viewcells_cell"]
vertices, _faces = ours.polyhedra(c)[0]
bpy.context.scene.cursor.location = vertices.mean(axis=0)
if bpy.ops.viewcells.show_from_here() != {"FINISHED"}:
    fail("show_from_here did not run")
shown = {o.name for o in bpy.context.view_layer.objects if o.name in level and o.visible_get()}
if shown != expected:
    fail(f"show from here shows {sorted(shown)}, the PVS is {sorted(expected)}")
if [o.name for o in cells.objects if o.visible_get()] != [small.name]:
    fail("show from here should leave only the cursor's cell visible")
bpy.ops.viewcells.show_all()
if any(not o.visible_get() for o in bpy.context.view_layer.objects):
    fail("show all left something hidden")
print(f"cell {c}: select and show from here give its PVS ({len(expected)} of {len(level)} Blender objects)")

# One object per collection: the four outer walls in a collection are one object of the PVSs.
walls = bpy.data.collections.new("walls")
bpy.context.scene.collection.children.link(walls)
for n in ("wall_south", "wall_north", "wall_west", "wall_east"):
    o = bpy.data.objects[n]
    for coll in list(o.users_collection):
        coll.objects.unlink(o)
    walls.objects.link(o)
s.per = "COLLECTION"
s.output = os.path.join(work, "addon-collections.pvs")
s.gltf = ""
if bpy.ops.viewcells.bake() != {"FINISHED"}:
    fail("the add-on's bake per collection failed: " + s.status)
grouped = vc.read(s.output)
if "walls" not in grouped.object_names or "wall_north" in grouped.object_names:
    fail(f"per collection: objects {grouped.object_names}")
seen_walls = [o for o in addon.blender_objects_of(bpy.context, ["walls"])]
if sorted(o.name for o in seen_walls) != ["wall_east", "wall_north", "wall_south", "wall_west"]:
    fail("per collection: the PVS object 'walls' should stand for the four walls")
print(f"per collection: {grouped.object_count} objects {list(grouped.object_names)}")

# The panel draws (with a stand-in layout: headless Blender has no window to draw in), while
# idle and while a bake runs.


class Layout:
    def __init__(self):
        self.calls = []

    def __getattr__(self, name):
        def call(*args, **kwargs):
            self.calls.append((name, args, kwargs))
            return self
        return call


class Panel:
    layout = Layout()


addon.VIEWCELLS_PT_panel.draw(Panel, bpy.context)
drawn = [c[1][1] for c in Panel.layout.calls if c[0] == "prop"]
missing = [p for p in drawn if not hasattr(bpy.context.scene.viewcells, p)]
buttons = [c[1][0] for c in Panel.layout.calls if c[0] == "operator"]
if missing or len(drawn) < 10 or "viewcells.bake" not in buttons or "viewcells.show_from_here" not in buttons:
    fail(f"the panel draws unknown settings {missing} or no bake button")

# A picture of the cells over the level, rendered by Cycles on the CPU.
s.per = "OBJECT"
s.output = os.path.join(work, "addon.pvs")
s.gltf = os.path.join(work, "addon-cells.glb")
s.cells = 16
bpy.ops.viewcells.bake()
scene = bpy.context.scene
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 8
scene.cycles.use_denoising = False
scene.render.resolution_x, scene.render.resolution_y = 480, 300
scene.render.film_transparent = False
world = bpy.data.worlds.new("world")
world.color = (0.9, 0.9, 0.9)
scene.world = world
bpy.ops.object.light_add(type="SUN", rotation=(0.6, 0.2, 0.8))
bpy.context.active_object.data.energy = 3
bpy.ops.object.camera_add(location=(0, -14.5, 14), rotation=(0.8, 0, 0))
scene.camera = bpy.context.active_object
scene.render.filepath = os.path.join(work, "blender-cells.png")
bpy.ops.render.render(write_still=True)
image = bpy.data.images.load(scene.render.filepath)
pixels = np.array(image.pixels[:]).reshape(-1, 4)[:, :3]
hues = {tuple(np.round(p * 4).astype(int)) for p in pixels[::97]}
if pixels.std() < 0.05 or len(hues) < 8:
    fail(f"the picture looks empty ({len(hues)} colours)")
print(f"rendered {scene.render.filepath}: {image.size[0]}x{image.size[1]}, {len(hues)} coarse colours")
print("PASS")
