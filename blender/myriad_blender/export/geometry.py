"""Meshes of the evaluated scene → glTF meshes and nodes.

Every object instance the depsgraph lists (modifiers applied, instances expanded) becomes a
node; objects that share one evaluated mesh (linked duplicates, instances of one object)
share one glTF mesh, which myriad stores once and instances (unless it emits). Triangles are
written per face corner (unindexed), with the corner normals (smooth, flat or custom, as
Cycles shades them) and the active render UV map, one primitive per material slot. Axes go
from Blender's Z-up to glTF's Y-up: (x, y, z) → (x, z, −y).
"""

import numpy as np

# Blender (Z-up) to glTF (Y-up), as a matrix on column vectors.
TO_Y_UP = np.array([[1, 0, 0, 0], [0, 0, 1, 0], [0, -1, 0, 0], [0, 0, 0, 1]], dtype=np.float64)

# Object kinds whose evaluated geometry is a mesh Cycles renders.
GEOMETRY = {"MESH", "CURVE", "SURFACE", "META", "FONT", "CURVES"}


def y_up_points(p):
    """(n, 3) Blender coordinates to glTF's."""
    return np.stack([p[:, 0], p[:, 2], -p[:, 1]], axis=1)


def y_up_matrix(m):
    """A Blender object matrix (4 × 4) as a glTF node matrix, column-major."""
    m = np.array(m, dtype=np.float64)
    return (TO_Y_UP @ m @ TO_Y_UP.T).T.reshape(16)


def _corner_normals(mesh):
    n = len(mesh.loops)
    normals = np.empty(n * 3, dtype=np.float32)
    if hasattr(mesh, "corner_normals"):
        mesh.corner_normals.foreach_get("vector", normals)
    else:  # Blender before 4.1
        mesh.calc_normals_split()
        mesh.loops.foreach_get("normal", normals)
    return normals.reshape(n, 3)


def _render_uvs(mesh):
    layer = next((layer for layer in mesh.uv_layers if layer.active_render), None)
    if layer is None:
        return None
    n = len(mesh.loops)
    uv = np.empty(n * 2, dtype=np.float32)
    if hasattr(layer, "uv"):
        layer.uv.foreach_get("vector", uv)
    else:
        layer.data.foreach_get("uv", uv)
    uv = uv.reshape(n, 2)
    # glTF's UV origin is the image's top-left, Blender's its bottom-left.
    return np.stack([uv[:, 0], 1.0 - uv[:, 1]], axis=1)


def mesh_primitives(writer, mesh, slots, materials):
    """The glTF primitives of an evaluated `mesh`, one per used material slot; the number of
    triangles."""
    mesh.calc_loop_triangles()
    count = len(mesh.loop_triangles)
    if count == 0:
        return [], 0
    loops = np.empty(count * 3, dtype=np.int32)
    mesh.loop_triangles.foreach_get("loops", loops)
    material_index = np.empty(count, dtype=np.int32)
    mesh.loop_triangles.foreach_get("material_index", material_index)
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    corner_vertex = np.empty(len(mesh.loops), dtype=np.int32)
    mesh.loops.foreach_get("vertex_index", corner_vertex)
    positions = y_up_points(co.reshape(-1, 3)[corner_vertex[loops]])
    normals = y_up_points(_corner_normals(mesh)[loops])
    uvs = _render_uvs(mesh)
    uvs = None if uvs is None else uvs[loops]
    primitives = []
    for slot in np.unique(material_index):
        corners = np.repeat(material_index == slot, 3)
        attributes = {"POSITION": writer.accessor(positions[corners]), "NORMAL": writer.accessor(normals[corners])}
        if uvs is not None:
            attributes["TEXCOORD_0"] = writer.accessor(uvs[corners])
        material = slots[slot].material if slot < len(slots) else None
        primitives.append({"attributes": attributes, "material": materials.index(material)})
    return primitives, count


def mesh_key(obj):
    """What identifies an evaluated object's mesh among instances: its data where nothing
    changes it (linked duplicates share it), else the object itself."""
    if obj.type == "MESH" and not obj.modifiers and obj.data is not None:
        return ("data", obj.data.name_full)
    return ("object", obj.name_full)


def export_meshes(depsgraph, writer, materials, warn):
    """Every renderable mesh instance of `depsgraph` into `writer`; (triangles, instances)."""
    meshes = {}
    triangles = instances = 0
    for inst in depsgraph.object_instances:
        obj = inst.object
        if obj.type not in GEOMETRY:
            continue
        if not getattr(obj, "visible_camera", True) or getattr(obj, "is_holdout", False):
            warn(f"object '{obj.name}': its camera visibility and holdout settings are not rendered; it renders as seen")
        key = mesh_key(obj)
        if key not in meshes:
            mesh = obj.to_mesh()
            try:
                primitives, count = (mesh_primitives(writer, mesh, obj.material_slots, materials) if mesh else ([], 0))
            finally:
                obj.to_mesh_clear()
            meshes[key] = (writer.mesh(obj.name, primitives), count) if primitives else (None, 0)
        index, count = meshes[key]
        if index is None:
            continue
        writer.node(obj.name, index, y_up_matrix(inst.matrix_world))
        triangles += count
        instances += 1
    return triangles, instances
