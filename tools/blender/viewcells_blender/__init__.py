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
point) is in plain functions, so the headless test (tests/blender/addon_test.py) calls the same
code a click does. The modules: module.py finds `viewcells`; level.py turns the visible meshes
into arrays and finds the start points; options.py the bake's keywords and progress stages;
results.py puts the cells into the scene; operators.py, play_space.py and panel.py are what
the sidebar shows; state.py what they share.
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

import bpy
from bpy.props import PointerProperty

from . import state  # noqa: F401 (state.job, state.last_stages: what scripts and tests read)
from .level import SEE_THROUGH, level_meshes, scene_arrays, start_points, start_positions  # noqa: F401
from .module import import_viewcells  # noqa: F401
from .options import bake_options, option_words, progress_of  # noqa: F401
from .results import baked_for, blender_objects_of, make_cells, pvs_of_point  # noqa: F401
from .state import CELLS_COLLECTION, PLAY_COLLECTION  # noqa: F401
from .operators import (VIEWCELLS_OT_bake, VIEWCELLS_OT_select_pvs, VIEWCELLS_OT_show_all,  # noqa: F401
                        VIEWCELLS_OT_show_from_here, on_active_change)
from .panel import VIEWCELLS_PT_panel, ViewcellsPreferences, ViewcellsSettings  # noqa: F401
from .play_space import VIEWCELLS_OT_add_start, VIEWCELLS_OT_show_play_space

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
