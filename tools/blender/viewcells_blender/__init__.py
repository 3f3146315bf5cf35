"""viewcells for Blender 3.4: bake view cells and their potentially visible sets (PVS) from the
meshes of the open scene, look at the cells as translucent meshes coloured by render cost,
select what a cell sees, and hide everything the 3D cursor's cell does not see.

The bake is the Python module `viewcells` (built by the project's CMake into build/python,
for the system Python 3.11 that Debian's Blender runs). The add-on finds it on sys.path, in
$VIEWCELLS_PYTHONPATH, in the directory its preferences name, or in the build directory of the
checkout it lives in (tools/blender/ -> build/python). Install the add-on by linking or copying
this directory into Blender's add-on directory, or Preferences > Add-ons > Install from a zip
of it; docs/blender.md says how objects and materials map to what a PVS lists.

Everything Blender-independent (mesh arrays to a scene, option words, colours, the PVS of a
point) is in plain functions below, so the headless test (tests/blender/addon_test.py) calls
the same code a click does.
"""

bl_info = {
    "name": "viewcells",
    "author": "viewcells",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "3D View > Sidebar > viewcells",
    "description": "Bake view cells and PVSs of the visible meshes; show and query them",
    "category": "3D View",
}

import json
import os
import shlex
import sys
import threading

import bpy
import numpy as np
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, PointerProperty, StringProperty

CELLS_COLLECTION = "viewcells cells"
PLAY_COLLECTION = "viewcells play space"
CELL_MATERIAL = "viewcells cell"
_baked = {}  # .pvs path (absolute) -> viewcells.Baked of this session
_job = None  # the bake running in the background (a modal run from the panel)
last_stages = []  # the progress values the last background bake went through, in order


# ---------------------------------------------------------------------------------------------
# The module


def import_viewcells():
    """The module `viewcells`, from sys.path, $VIEWCELLS_PYTHONPATH, the add-on's preferences or
    the checkout's build/python. Raises ImportError saying where it looked."""
    try:
        import viewcells  # noqa: F401
        return sys.modules["viewcells"]
    except ImportError:
        pass
    here = os.path.dirname(os.path.realpath(__file__))  # through the link install-blender-addon.sh makes
    places = [os.environ.get("VIEWCELLS_PYTHONPATH", "")]
    addon = bpy.context.preferences.addons.get(__name__)
    if addon is not None:
        places.append(bpy.path.abspath(addon.preferences.module_dir))
    places.append(os.path.normpath(os.path.join(here, "..", "..", "..", "build", "python")))
    for place in places:
        if place and os.path.isdir(place) and place not in sys.path:
            sys.path.append(place)
            try:
                import viewcells  # noqa: F401
                return sys.modules["viewcells"]
            except ImportError:
                sys.path.remove(place)
    raise ImportError("the Python module viewcells was not found (looked on sys.path and in "
                      + ", ".join(p for p in places if p)
                      + "); build it (scripts/test.sh or -DVIEWCELLS_PYTHON=ON) and set its directory in "
                      "the add-on's preferences or $VIEWCELLS_PYTHONPATH")


# ---------------------------------------------------------------------------------------------
# Blender's meshes as a scene


def material_is_see_through(m):
    """A material one sees through (glass, water: in PVSs, hiding nothing): alpha blended,
    hashed or clipped, or with a Principled BSDF's transmission above zero. This is what the
    glTF exporter writes as alphaMode BLEND or MASK or as KHR_materials_transmission, which
    `viewcells bake` reads as see-through, so a level baked here and its glTF export agree."""
    if m is None:
        return False
    if m.blend_method != "OPAQUE":
        return True
    if m.use_nodes and m.node_tree is not None:
        for node in m.node_tree.nodes:
            if node.type == "BSDF_PRINCIPLED":
                t = node.inputs["Transmission"]
                if t.is_linked or t.default_value > 0:
                    return True
    return False


def level_meshes(context, exclude=(CELLS_COLLECTION, PLAY_COLLECTION)):
    """The visible mesh objects of the view layer, outside the add-on's own collections (the
    cells, the play space), in its order."""
    own = [c for c in (bpy.data.collections.get(name) for name in exclude) if c is not None]
    out = []
    for o in context.view_layer.objects:
        if o.type != "MESH" or not o.visible_get():
            continue
        if any(c in o.users_collection for c in own):
            continue
        out.append(o)
    return out


def start_positions(context):
    """Where players start, as the glTF reader takes them from an export: the world positions of
    the empties whose names hold "spawn", "player start" or "info_player" (any case; spaces,
    underscores, dashes and dots ignored), as (x, y, z) tuples."""
    out = []
    for o in context.view_layer.objects:
        if o.type != "EMPTY":
            continue
        name = "".join(ch for ch in o.name.lower() if ch not in " _-.")
        if "spawn" in name or "playerstart" in name or "infoplayer" in name:
            p = o.matrix_world.translation
            out.append((p.x, p.y, p.z))
    return out


def start_points(context):
    """start_positions() as `--start` words."""
    return [f"{x!r},{y!r},{z!r}" for x, y, z in start_positions(context)]


def owner_name(obj, per):
    """The name of the PVS object a Blender object belongs to: itself, or (per collection) its
    first collection other than the scene's own."""
    if per == "COLLECTION":
        for c in obj.users_collection:
            if c != bpy.context.scene.collection:
                return c.name
    return obj.name


SEE_THROUGH = " (see-through)"


def scene_arrays(context, per="OBJECT"):
    """The level as arrays: world-space vertices (float64, the object's matrix applied in double),
    triangles, each triangle's object, object names, see-through flags, and for every PVS object
    the Blender objects it stands for. The triangles of an object (or collection) with a
    see-through material form an object of their own, named with " (see-through)" as the glTF
    reader names them: a window's frame hides what its glass does not."""
    depsgraph = context.evaluated_depsgraph_get()
    names, members, see_through = [], [], []
    index = {}
    chunks_v, chunks_t, chunks_o = [], [], []
    base = 0
    for o in level_meshes(context):
        owner = owner_name(o, per)
        flags = np.array([material_is_see_through(slot.material) for slot in o.material_slots] or [False])
        evaluated = o.evaluated_get(depsgraph)
        mesh = evaluated.to_mesh()
        try:
            mesh.calc_loop_triangles()
            co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
            mesh.vertices.foreach_get("co", co)
            tris = np.empty(len(mesh.loop_triangles) * 3, dtype=np.int64)
            mesh.loop_triangles.foreach_get("vertices", tris)
            material = np.empty(len(mesh.loop_triangles), dtype=np.int64)
            mesh.loop_triangles.foreach_get("material_index", material)
        finally:
            evaluated.to_mesh_clear()
        if len(tris) == 0:
            continue
        # Triangles grouped by material, in slot order, as the glTF exporter writes an object's
        # primitives: the same level then holds its triangles in the same order either way.
        order = np.argsort(material, kind="stable")
        tris = tris.reshape(-1, 3)[order].reshape(-1)
        material = material[order]
        tri_see_through = flags[np.minimum(material, len(flags) - 1)]
        object_of_tri = np.empty(len(material), dtype=np.int64)
        for st in (False, True):
            chosen = tri_see_through == st
            if not chosen.any():
                continue
            key = owner + (SEE_THROUGH if st else "")
            if key not in index:
                index[key] = len(names)
                names.append(key)
                members.append([])
                see_through.append(st)
            if o.name not in members[index[key]]:
                members[index[key]].append(o.name)
            object_of_tri[chosen] = index[key]
        m = np.array(o.matrix_world, dtype=np.float64)
        v = co.astype(np.float64).reshape(-1, 3) @ m[:3, :3].T + m[:3, 3]
        tris = tris.reshape(-1, 3)
        if np.linalg.det(m[:3, :3]) < 0:  # a mirroring matrix turns faces inside out: keep them outward
            tris = tris[:, [0, 2, 1]]
        chunks_v.append(v)
        chunks_t.append(tris + base)
        chunks_o.append(object_of_tri)
        base += len(v)
    if not names:
        raise ValueError("no visible mesh with triangles to bake")
    return (np.vstack(chunks_v), np.vstack(chunks_t), np.concatenate(chunks_o), names, see_through, members)


def option_words(text):
    """Extra `viewcells bake` options written as on the command line ("--samples 30000 --no-ga")
    as keywords for viewcells.bake."""
    words = shlex.split(text)
    out = {}
    i = 0
    while i < len(words):
        w = words[i]
        if not w.startswith("--") or len(w) < 3:
            raise ValueError(f"extra options: '{w}' is not an option (write them as --name value)")
        key = w[2:].replace("-", "_")
        if i + 1 < len(words) and not words[i + 1].startswith("--"):
            out[key] = words[i + 1]
            i += 2
        else:
            out[key] = True
            i += 1
    return out


def bake_options(settings):
    """The bake's keywords from the panel's settings, as `viewcells bake` takes them."""
    o = {}
    if settings.budget == "CELLS":
        o["cells"] = settings.cells
    else:
        o["memory"] = settings.memory
    if settings.holes > 0:
        o["holes"] = f"{settings.holes:g}%"
    if settings.pixel_error > 0:
        o["pixel_error"] = settings.pixel_error
    if settings.time > 0:
        o["time"] = settings.time
    o.update(option_words(settings.extra))
    return o


def cost_colour(t):
    """The project's colour scale: blue -> cyan -> green -> yellow -> red for t in [0, 1]."""
    stops = [(0, 0, 1), (0, 1, 1), (0, 1, 0), (1, 1, 0), (1, 0, 0)]
    t = min(max(t, 0.0), 1.0) * 4
    i = min(int(t), 3)
    f = t - i
    a, b = stops[i], stops[i + 1]
    return tuple(a[k] + (b[k] - a[k]) * f for k in range(3))


# Where a bake's log lines put the progress bar (the stages of `viewcells bake`, in order).
STAGES = [("loaded", 0.03), ("sampling", 0.05), ("valid segments", 0.15), ("subdividing", 0.2),
          ("cells in", 0.35), ("merging", 0.4), ("leaf PVSs", 0.5), ("by AGVS", 0.55), ("view cells, mean", 0.95)]


def progress_of(line, previous):
    for key, value in STAGES:
        if key in line:
            return max(previous, value)
    return previous


# ---------------------------------------------------------------------------------------------
# Results in the scene


def cell_material():
    m = bpy.data.materials.get(CELL_MATERIAL)
    if m is not None:
        return m
    m = bpy.data.materials.new(CELL_MATERIAL)
    m.use_nodes = True
    m.blend_method = "BLEND"
    m.shadow_method = "NONE"
    m.use_backface_culling = False
    nodes, links = m.node_tree.nodes, m.node_tree.links
    bsdf = nodes.get("Principled BSDF")
    info = nodes.new("ShaderNodeObjectInfo")
    links.new(info.outputs["Color"], bsdf.inputs["Base Color"])
    links.new(info.outputs["Color"], bsdf.inputs["Emission"])
    bsdf.inputs["Emission Strength"].default_value = 0.4
    bsdf.inputs["Alpha"].default_value = 0.35
    m.diffuse_color = (1, 1, 1, 0.35)
    return m


def make_cells(context, baked, members):
    """The cells as a collection of translucent meshes, one object per view cell, coloured from
    blue (the cheapest) to red (the costliest) by render cost r(PVS); each holds its id, cost and
    PVS (object names)."""
    old = bpy.data.collections.get(CELLS_COLLECTION)
    if old is not None:
        for o in list(old.objects):
            mesh = o.data
            bpy.data.objects.remove(o)
            if mesh is not None and mesh.users == 0:
                bpy.data.meshes.remove(mesh)
        bpy.data.collections.remove(old)
    collection = bpy.data.collections.new(CELLS_COLLECTION)
    context.scene.collection.children.link(collection)
    material = cell_material()
    costs = baked.cell_costs
    low, span = float(costs.min()), max(float(costs.max() - costs.min()), 1e-300)
    names = baked.object_names
    for c, (v, t) in enumerate(baked.cell_meshes):
        mesh = bpy.data.meshes.new(f"cell {c}")
        mesh.from_pydata(v.astype(np.float64).tolist(), [], t.tolist())
        mesh.materials.append(material)
        mesh.update()
        o = bpy.data.objects.new(f"cell {c:04d}", mesh)
        o.color = (*cost_colour((float(costs[c]) - low) / span), 0.35)  # the cheapest blue, the costliest red
        o["viewcells_cell"] = c
        o["render_cost"] = float(costs[c])
        pvs = [names[i] for i in baked.pvs(c)]
        o["pvs_size"] = len(pvs)
        o["pvs"] = json.dumps(pvs)
        o.display_type = "SOLID"
        o.show_transparent = True
        collection.objects.link(o)
    context.scene["viewcells_members"] = json.dumps(members)
    return collection


def baked_for(context):
    """The last bake of this scene (this session's, or its .pvs read again)."""
    vc = import_viewcells()
    path = bpy.path.abspath(context.scene.viewcells.output)
    if path not in _baked:
        if not os.path.exists(path):
            raise FileNotFoundError(f"{path}: no .pvs yet: bake first")
        _baked[path] = vc.read(path)
    return _baked[path]


def blender_objects_of(context, pvs_names):
    """The Blender objects the PVS objects `pvs_names` stand for."""
    members = json.loads(context.scene.get("viewcells_members", "{}") or "{}")
    out = []
    for n in pvs_names:
        for m in members.get(n, [n]):
            o = bpy.data.objects.get(m)
            if o is not None:
                out.append(o)
    return out


def pvs_of_point(context, point):
    """The cell of `point` and the Blender objects of its PVS ((-1, []) outside the view space)."""
    baked = baked_for(context)
    cell = baked.query(tuple(point))
    if cell < 0:
        return -1, []
    names = baked.object_names
    return cell, blender_objects_of(context, [names[i] for i in baked.pvs(cell)])


def finish_bake(context, baked, members):
    settings = context.scene.viewcells
    _baked[bpy.path.abspath(settings.output)] = baked
    if settings.gltf:
        baked.write_gltf(bpy.path.abspath(settings.gltf))
    make_cells(context, baked, members)
    r = baked.report
    summary = f"{baked.cell_count} cells, {baked.object_count} objects"
    pvs = r.get("pvs", {}) if isinstance(r.get("pvs"), dict) else {}
    if "mean_pvs" in r:
        summary += f", mean PVS {r['mean_pvs']:.1f}"
    elif "mean" in pvs:
        summary += f", mean PVS {pvs['mean']:.1f}"
    settings.status = summary
    return summary


# ---------------------------------------------------------------------------------------------
# Operators


class VIEWCELLS_OT_bake(bpy.types.Operator):
    """Bake view cells and PVSs of the visible meshes (writes the .pvs and, when set, a .glb)"""
    bl_idname = "viewcells.bake"
    bl_label = "Bake view cells"

    _timer = None

    def prepare(self, context):
        vc = import_viewcells()
        settings = context.scene.viewcells
        v, t, o, names, see_through, members = scene_arrays(context, settings.per)
        scene = vc.Scene(v, t, objects=o, names=names, see_through=see_through,
                         name=bpy.path.basename(bpy.data.filepath) or "blender scene")
        output = bpy.path.abspath(settings.output)
        options = bake_options(settings)
        starts = start_points(context)
        if starts and "start" not in options:
            options["start"] = starts  # the play space's start points, as a glTF export carries them
        return vc, scene, output, options, dict(zip(names, members))

    def execute(self, context):  # blocking: scripts and the headless test
        try:
            vc, scene, output, options, members = self.prepare(context)
            wm = context.window_manager
            wm.progress_begin(0, 1)
            state = {"p": 0.0}

            def progress(line):
                state["p"] = progress_of(line, state["p"])
                wm.progress_update(state["p"])
                print(line)

            try:
                baked = vc.bake(scene, output, progress=progress, **options)
            finally:
                wm.progress_end()
            self.report({"INFO"}, finish_bake(context, baked, members))
            return {"FINISHED"}
        except Exception as e:  # the library's message, in Blender's status bar
            context.scene.viewcells.status = f"failed: {e}"
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}

    def invoke(self, context, event):  # from the panel: in the background, with a progress bar
        global _job
        if _job is not None:
            self.report({"WARNING"}, "a bake is running")
            return {"CANCELLED"}
        try:
            vc, scene, output, options, members = self.prepare(context)
        except Exception as e:
            context.scene.viewcells.status = f"failed: {e}"
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        job = {"line": "starting", "p": 0.0, "baked": None, "error": None, "members": members, "stages": []}

        def progress(line):
            job["line"] = line.replace("viewcells: ", "")
            p = progress_of(line, job["p"])
            if p != job["p"]:
                job["stages"].append(p)
            job["p"] = p

        def run():
            try:
                job["baked"] = vc.bake(scene, output, progress=progress, **options)
            except Exception as e:
                job["error"] = str(e)

        job["thread"] = threading.Thread(target=run, daemon=True)
        _job = job
        job["thread"].start()
        context.window_manager.progress_begin(0, 1)
        self._timer = context.window_manager.event_timer_add(0.25, window=context.window)
        context.window_manager.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        global _job
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        job = _job
        settings = context.scene.viewcells
        settings.progress = job["p"]
        settings.status = job["line"][:120]
        context.window_manager.progress_update(job["p"])
        for area in context.screen.areas:
            if area.type == "VIEW_3D":
                area.tag_redraw()
        if job["thread"].is_alive():
            return {"RUNNING_MODAL"}
        context.window_manager.event_timer_remove(self._timer)
        context.window_manager.progress_end()
        _job = None
        last_stages[:] = job["stages"]
        settings.progress = 0
        if job["error"]:
            settings.status = f"failed: {job['error']}"
            self.report({"ERROR"}, job["error"])
            return {"CANCELLED"}
        self.report({"INFO"}, finish_bake(context, job["baked"], job["members"]))
        return {"FINISHED"}


class VIEWCELLS_OT_select_pvs(bpy.types.Operator):
    """Select the objects in the PVS of the active cell (keeps the cell active)"""
    bl_idname = "viewcells.select_pvs"
    bl_label = "Select its PVS"

    @classmethod
    def poll(cls, context):
        o = context.view_layer.objects.active
        return o is not None and "viewcells_cell" in o

    def execute(self, context):
        cell = context.view_layer.objects.active
        objects = blender_objects_of(context, json.loads(cell["pvs"]))
        for o in context.view_layer.objects:
            o.select_set(False)
        for o in objects:
            if o.visible_get():
                o.select_set(True)
        cell.select_set(True)
        self.report({"INFO"}, f"cell {cell['viewcells_cell']}: {len(objects)} objects in its PVS")
        return {"FINISHED"}


class VIEWCELLS_OT_show_from_here(bpy.types.Operator):
    """Hide every object outside the PVS of the 3D cursor's cell: what an engine would draw there"""
    bl_idname = "viewcells.show_from_here"
    bl_label = "Show from here"

    def execute(self, context):
        try:
            cell, objects = pvs_of_point(context, context.scene.cursor.location)
        except Exception as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        if cell < 0:
            self.report({"WARNING"}, "the 3D cursor is outside the view space")
            return {"CANCELLED"}
        keep = {o.name for o in objects}
        cells = bpy.data.collections.get(CELLS_COLLECTION)
        hidden = 0
        for o in level_meshes(context) + [o for o in context.view_layer.objects if o.hide_get()]:
            show = o.name in keep
            o.hide_set(not show)
            hidden += not show
        if cells is not None:
            for o in cells.objects:
                o.hide_set(o.get("viewcells_cell") != cell)
        context.scene.viewcells.status = f"from cell {cell}: {len(keep)} objects drawn, {hidden} hidden"
        self.report({"INFO"}, context.scene.viewcells.status)
        return {"FINISHED"}


class VIEWCELLS_OT_show_all(bpy.types.Operator):
    """Show every object again (after Show from here)"""
    bl_idname = "viewcells.show_all"
    bl_label = "Show all"

    def execute(self, context):
        for o in context.view_layer.objects:
            if o.hide_get():
                o.hide_set(False)
        return {"FINISHED"}


def on_active_change(*_args):
    """With "follow the selection" on, clicking a cell selects its PVS."""
    context = bpy.context
    o = context.view_layer.objects.active if context.view_layer else None
    if o is not None and "viewcells_cell" in o and context.scene.viewcells.follow_selection:
        bpy.ops.viewcells.select_pvs()


# ---------------------------------------------------------------------------------------------
# Settings and the panel


class ViewcellsSettings(bpy.types.PropertyGroup):
    per: EnumProperty(name="Objects", description="What one entry of a PVS is",
                      items=[("OBJECT", "Per object", "Every Blender mesh object is an object of the PVSs"),
                             ("COLLECTION", "Per collection",
                              "The mesh objects of a collection form one object of the PVSs")])
    budget: EnumProperty(name="Budget", items=[("CELLS", "Cells", "This many view cells"),
                                                ("MEMORY", "Memory", "The most cells whose .pvs fits")])
    cells: IntProperty(name="Cells", default=100, min=1, max=1 << 20)
    memory: StringProperty(name="Memory", default="256K", description="File size, as 256K or 4M")
    holes: FloatProperty(name="Holes %", default=0.0, min=0.0, max=100.0,
                         description="Stop once at most this share of measured frames shows a wrong pixel "
                                     "(0: the command line's default stop)")
    pixel_error: FloatProperty(name="Pixel error", default=0.0, min=0.0,
                               description="Stop once AGVS estimates at most this many wrong pixels (0: default)")
    time: FloatProperty(name="Time limit (s)", default=600.0, min=0.0, description="The whole bake's limit (0: none)")
    extra: StringProperty(name="Options", default="",
                          description="More `viewcells bake` options, as on the command line: --samples 30000 --no-ga")
    output: StringProperty(name="PVS file", default="//level.pvs", subtype="FILE_PATH")
    gltf: StringProperty(name="glTF file", default="//level-cells.glb", subtype="FILE_PATH",
                         description="The level and its cells as binary glTF (empty: none)")
    follow_selection: BoolProperty(name="Clicking a cell selects its PVS", default=True)
    status: StringProperty(name="Status", default="")
    play_status: StringProperty(name="Play space", default="")
    progress: FloatProperty(name="Progress", default=0.0, min=0.0, max=1.0, subtype="FACTOR")


class VIEWCELLS_PT_panel(bpy.types.Panel):
    bl_label = "viewcells"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "viewcells"

    def draw(self, context):
        s = context.scene.viewcells
        layout = self.layout
        col = layout.column()
        col.prop(s, "per")
        row = col.row()
        row.prop(s, "budget", expand=True)
        col.prop(s, "cells" if s.budget == "CELLS" else "memory")
        col.prop(s, "holes")
        col.prop(s, "pixel_error")
        col.prop(s, "time")
        col.prop(s, "extra")
        col.prop(s, "output")
        col.prop(s, "gltf")
        if _job is not None:
            col.prop(s, "progress", slider=True, text="Baking")
        else:
            col.operator("viewcells.bake", icon="RENDER_STILL")
        if s.status:
            col.label(text=s.status)
        col.separator()
        col.prop(s, "follow_selection")
        col.operator("viewcells.select_pvs")
        row = col.row()
        row.operator("viewcells.show_from_here", icon="HIDE_OFF")
        row.operator("viewcells.show_all")
        col.separator()
        row = col.row()
        row.operator("viewcells.show_play_space", icon="MOD_FLUIDSIM")
        row.operator("viewcells.add_start", icon="EMPTY_SINGLE_ARROW")
        if s.play_status:
            col.label(text=s.play_status)


class ViewcellsPreferences(bpy.types.AddonPreferences):
    bl_idname = __name__
    module_dir: StringProperty(name="Module directory", subtype="DIR_PATH", default="",
                               description="The directory of viewcells*.so (a build's build/python)")

    def draw(self, context):
        self.layout.prop(self, "module_dir")


from .play_space import VIEWCELLS_OT_add_start, VIEWCELLS_OT_show_play_space  # noqa: E402 (needs the helpers above)

CLASSES = (ViewcellsSettings, ViewcellsPreferences, VIEWCELLS_OT_bake, VIEWCELLS_OT_select_pvs,
           VIEWCELLS_OT_show_from_here, VIEWCELLS_OT_show_all, VIEWCELLS_OT_show_play_space,
           VIEWCELLS_OT_add_start, VIEWCELLS_PT_panel)
_owner = object()


def register():
    for c in CLASSES:
        bpy.utils.register_class(c)
    bpy.types.Scene.viewcells = PointerProperty(type=ViewcellsSettings)
    bpy.msgbus.subscribe_rna(key=(bpy.types.LayerObjects, "active"), owner=_owner, args=(),
                             notify=on_active_change)


def unregister():
    bpy.msgbus.clear_by_owner(_owner)
    del bpy.types.Scene.viewcells
    for c in reversed(CLASSES):
        bpy.utils.unregister_class(c)
