"""The bake's results in the scene: the cells as a collection of meshes coloured by render cost,
and the Blender objects of a PVS."""
import json
import os

import bpy
import numpy as np

from . import state
from .module import import_viewcells
from .state import CELLS_COLLECTION, CELL_MATERIAL


def cost_colour(t):
    """The project's colour scale: blue -> cyan -> green -> yellow -> red for t in [0, 1]."""
    stops = [(0, 0, 1), (0, 1, 1), (0, 1, 0), (1, 1, 0), (1, 0, 0)]
    t = min(max(t, 0.0), 1.0) * 4
    i = min(int(t), 3)
    f = t - i
    a, b = stops[i], stops[i + 1]
    return tuple(a[k] + (b[k] - a[k]) * f for k in range(3))


# Where a bake's log lines put the progress bar (the stages of `viewcells bake`, in order).


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
    if path not in state.baked:
        if not os.path.exists(path):
            raise FileNotFoundError(f"{path}: no .pvs yet: bake first")
        state.baked[path] = vc.read(path)
    return state.baked[path]


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
    state.baked[bpy.path.abspath(settings.output)] = baked
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
