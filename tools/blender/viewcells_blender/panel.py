"""The settings, the panel in the 3D view's sidebar, and the add-on's preferences."""
import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, StringProperty

from . import state


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
        if state.job is not None:
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
