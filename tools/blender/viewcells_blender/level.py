"""The level as the bake takes it: the visible meshes as arrays (world space, objects per
Blender object or collection, see-through from the materials) and the start points."""
import bpy
import numpy as np

from .state import CELLS_COLLECTION, PLAY_COLLECTION


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
