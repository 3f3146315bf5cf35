"""The play space in Blender: where a bake assumes players stand (walkable floors reachable from
the start points, found from the visible meshes as `viewcells bake` finds its default view
space), drawn as green floors, and start points to mark where players begin."""

import bpy
import numpy as np

from .level import scene_arrays, start_positions
from .module import import_viewcells
from .state import PLAY_COLLECTION

PLAY_OBJECT = "viewcells play space"
PLAY_MATERIAL = "viewcells play space"
START_NAME = "PlayerStart"


def play_material():
    m = bpy.data.materials.get(PLAY_MATERIAL)
    if m is not None:
        return m
    m = bpy.data.materials.new(PLAY_MATERIAL)
    m.use_nodes = True
    m.blend_method = "BLEND"
    m.shadow_method = "NONE"
    bsdf = m.node_tree.nodes.get("Principled BSDF")
    bsdf.inputs["Base Color"].default_value = (0.2, 0.85, 0.3, 1)
    bsdf.inputs["Alpha"].default_value = 0.5
    m.diffuse_color = (0.2, 0.85, 0.3, 0.5)
    return m


def find_play_space(context):
    """The play space of the visible meshes (viewcells.PlaySpace) with the scene's start points."""
    vc = import_viewcells()
    v, t, o, names, see_through, _members = scene_arrays(context, context.scene.viewcells.per)
    scene = vc.Scene(v, t, objects=o, names=names, see_through=see_through,
                     name=bpy.path.basename(bpy.data.filepath) or "blender scene")
    return vc.play_space(scene, start=start_positions(context))


def show_play_space(context):
    """Replaces the play space's collection with the floors found now; returns the PlaySpace
    (its object is in PLAY_COLLECTION, named PLAY_OBJECT, unless none was found)."""
    old = bpy.data.collections.get(PLAY_COLLECTION)
    if old is not None:
        for ob in list(old.objects):
            mesh = ob.data
            bpy.data.objects.remove(ob)
            if mesh is not None and mesh.users == 0:
                bpy.data.meshes.remove(mesh)
        bpy.data.collections.remove(old)
    play = find_play_space(context)
    if not play.found:
        return play
    collection = bpy.data.collections.new(PLAY_COLLECTION)
    context.scene.collection.children.link(collection)
    v, t = play.floors
    mesh = bpy.data.meshes.new(PLAY_OBJECT)
    mesh.from_pydata(v.astype(np.float64).tolist(), [], t.tolist())
    mesh.materials.append(play_material())
    mesh.update()
    ob = bpy.data.objects.new(PLAY_OBJECT, mesh)
    ob["rule"] = play.rule
    ob["floor_area_m2"] = play.floor_area_m2
    ob["volume_m3"] = play.volume_m3
    ob.show_transparent = True
    ob.hide_select = True  # clicks go to the level and the cells under it
    collection.objects.link(ob)
    return play


class VIEWCELLS_OT_show_play_space(bpy.types.Operator):
    """Draw where a bake assumes players stand: the walkable floors reachable from the start
    points (empties named PlayerStart or spawn; none: every floor region), in green"""
    bl_idname = "viewcells.show_play_space"
    bl_label = "Show play space"

    def execute(self, context):
        settings = context.scene.viewcells
        try:
            play = show_play_space(context)
        except Exception as e:  # the module's errors and a level without meshes
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        if play.found:
            settings.play_status = f"play space: {play.floor_area_m2:.0f} m^2 of floor"
            self.report({"INFO"}, play.rule)
        else:
            settings.play_status = "no play space: bakes use the whole box"
            self.report({"WARNING"}, play.rule)
        return {"FINISHED"}


class VIEWCELLS_OT_add_start(bpy.types.Operator):
    """Mark where players start: an empty named PlayerStart at the 3D cursor (bakes and the play
    space start from every such empty; the glTF exporter keeps it)"""
    bl_idname = "viewcells.add_start"
    bl_label = "Add start point"

    def execute(self, context):
        ob = bpy.data.objects.new(START_NAME, None)
        ob.empty_display_type = "SINGLE_ARROW"
        ob.location = context.scene.cursor.location
        context.scene.collection.objects.link(ob)
        return {"FINISHED"}
