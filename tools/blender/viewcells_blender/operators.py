"""The panel's operators: bake (blocking for scripts, in the background from the panel), select
a cell's PVS, show the level from the 3D cursor's cell, show all."""
import json
import threading

import bpy

from . import state
from .level import level_meshes, scene_arrays, start_points
from .module import import_viewcells
from .options import bake_options, progress_of
from .results import blender_objects_of, finish_bake, pvs_of_point
from .state import CELLS_COLLECTION


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
        options = bake_options(settings, vc.bake_options())
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
        if state.job is not None:
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
        state.job = job
        job["thread"].start()
        context.window_manager.progress_begin(0, 1)
        self._timer = context.window_manager.event_timer_add(0.25, window=context.window)
        context.window_manager.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        job = state.job
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
        state.job = None
        state.last_stages[:] = job["stages"]
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
