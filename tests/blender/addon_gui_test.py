"""The add-on's background bake, in Blender with a window (under Xvfb): the panel's button
starts the bake in a thread, a timer moves the progress bar through the bake's stages, and the
cells appear when it ends, while Blender keeps handling events. Headless Blender (-b) runs no
event loop, so addon_test.py cannot reach this path. Run by ctest (tests/CMakeLists.txt):
  xvfb-run -a blender --factory-startup --python-exit-code 1 --python addon_gui_test.py -- PYDIR ADDON_DIR WORK
"""
import os
import sys
import time

argv = sys.argv[sys.argv.index("--") + 1:]
pydir, addon_dir, work = argv
os.makedirs(work, exist_ok=True)
os.environ["VIEWCELLS_PYTHONPATH"] = pydir
sys.path.insert(0, addon_dir)

import bpy  # noqa: E402

import viewcells_blender as addon  # noqa: E402

addon.register()
state = {"started": None, "progress": [], "ticks": 0, "result": None}


def finish(message, code):
    print(message)
    sys.stdout.flush()
    os._exit(code)  # quit at once: the test's answer is its exit code


def level():
    """A room with a dividing wall and a crate on either side."""
    parts = [((0, 0, -0.1), (5, 5, 0.1)), ((0, -5, 1.5), (5, 0.1, 1.5)), ((0, 5, 1.5), (5, 0.1, 1.5)),
             ((-5, 0, 1.5), (0.1, 5, 1.5)), ((5, 0, 1.5), (0.1, 5, 1.5)), ((-3, 0, 1.5), (2, 0.1, 1.5)),
             ((3, 0, 1.5), (2, 0.1, 1.5)), ((-3, -3, 0.4), (0.4, 0.4, 0.4)), ((3, 3, 0.4), (0.4, 0.4, 0.4))]
    for k, (location, half) in enumerate(parts):
        bpy.ops.mesh.primitive_cube_add(location=location)
        bpy.context.active_object.scale = half
        bpy.context.active_object.name = f"part_{k}"


def start():
    for o in list(bpy.data.objects):
        bpy.data.objects.remove(o)
    level()
    s = bpy.context.scene.viewcells
    s.cells = 8
    s.time = 0
    s.extra = "--samples 200000 --max-cells 64 --agvs-samples 1000000"  # a second or two: several timer ticks
    s.output = os.path.join(work, "gui.pvs")
    s.gltf = os.path.join(work, "gui-cells.glb")
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    with bpy.context.temp_override(window=window, area=area):
        result = bpy.ops.viewcells.bake("INVOKE_DEFAULT")
    if result != {"RUNNING_MODAL"}:
        finish(f"FAIL: the bake did not start in the background: {result}, {s.status}", 1)
    state["started"] = time.time()
    bpy.app.timers.register(watch, first_interval=0.05)
    return None


def watch():
    state["ticks"] += 1  # Blender's event loop ran while the bake was baking
    s = bpy.context.scene.viewcells
    if addon.state.job is not None:
        state["progress"].append(s.progress)
        if time.time() - state["started"] > 240:
            finish("FAIL: the bake did not end in 240 s", 1)
        return 0.05
    cells = bpy.data.collections.get(addon.CELLS_COLLECTION)
    steps = sorted(set(state["progress"]))
    print(f"ticks {state['ticks']}, progress seen {steps}, status '{s.status}'")
    if cells is None or len(cells.objects) != 8:
        finish(f"FAIL: no cells after the background bake ({s.status})", 1)
    # Blender's event loop ran while the bake ran (a timer saw the bake's job at least once), and
    # the bar as the timers saw it never fell. That it rises through the stages is checked on
    # the stages the add-on set, not on what the timers sampled: how many distinct values a
    # timer sees depends on the machine's speed (two of five runs on a quiet machine saw one).
    print(f"stages set: {addon.state.last_stages}")
    if not state["progress"] or state["progress"] != sorted(state["progress"]):
        finish(f"FAIL: the progress bar should show and never fall while the bake runs: {state['progress']}", 1)
    if len(addon.state.last_stages) < 5 or addon.state.last_stages != sorted(addon.state.last_stages):
        finish(f"FAIL: the bake should go through its stages in order: {addon.state.last_stages}", 1)
    if not os.path.exists(s.output) or not os.path.exists(s.gltf):
        finish("FAIL: the .pvs or the .glb is missing", 1)
    # A click on a cell (here: making it the active object) selects its PVS, through the
    # message bus the add-on subscribes to.
    cell = min(cells.objects, key=lambda o: o["pvs_size"])
    for o in bpy.context.view_layer.objects:
        o.select_set(False)
    bpy.context.view_layer.objects.active = cell
    state["cell"] = cell
    bpy.app.timers.register(check_click, first_interval=0.3)
    return None


def check_click():
    import json
    cell = state["cell"]
    expected = set(json.loads(cell["pvs"]))
    level = {o.name for o in addon.level_meshes(bpy.context)}
    selected = {o.name for o in bpy.context.selected_objects if o.name in level}
    if selected != expected:
        finish(f"FAIL: activating {cell.name} selected {sorted(selected)}, its PVS is {sorted(expected)}", 1)
    print(f"activating {cell.name} selected its PVS: {len(selected)} of {len(level)} objects")
    finish("PASS", 0)
    return None


bpy.app.timers.register(start, first_interval=0.5)
