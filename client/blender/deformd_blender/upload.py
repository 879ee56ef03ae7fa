"""The object's evaluated mesh (object space) as a binary little-endian PLY, built with numpy:
vertex floats and triangle rows are written as whole arrays (no per-vertex Python loop)."""
import numpy as np

FACE_DTYPE = np.dtype([("n", "u1"), ("v", "<u4", (3,))])


def evaluated_arrays(obj, depsgraph):
    """(positions (nv, 3) float32, triangles (nt, 3) uint32) of obj's evaluated mesh in object
    space. ValueError when obj is not a mesh."""
    if obj is None or obj.type != "MESH":
        raise ValueError("the active object is not a mesh")
    # without modifiers or shape keys the evaluated mesh is the object's own: no copy
    plain = not obj.modifiers and obj.data.shape_keys is None
    ev = None if plain else obj.evaluated_get(depsgraph)
    mesh = obj.data if plain else ev.to_mesh()
    try:
        nv = len(mesh.vertices)
        pos = np.empty(nv * 3, dtype=np.float32)
        mesh.vertices.foreach_get("co", pos)
        # unsigned 32-bit buffers take foreach_get's raw-copy path (int32 is ~10x slower in
        # Blender 3.4: per-item conversion); triangle corners -> vertices by a numpy gather
        corner_vert = np.empty(len(mesh.loops), dtype=np.uint32)
        mesh.loops.foreach_get("vertex_index", corner_vert)
        mesh.calc_loop_triangles()
        tri_loops = np.empty(len(mesh.loop_triangles) * 3, dtype=np.uint32)
        mesh.loop_triangles.foreach_get("loops", tri_loops)
        tri = corner_vert[tri_loops]
    finally:
        if ev is not None:
            ev.to_mesh_clear()
    return pos.reshape(-1, 3), tri.reshape(-1, 3)


def ply_bytes(pos: np.ndarray, tri: np.ndarray) -> bytes:
    """Binary PLY: `vertex` x y z float, `face` list uchar uint vertex_indices."""
    pos = np.ascontiguousarray(pos, dtype="<f4").reshape(-1, 3)
    faces = np.empty(len(tri), dtype=FACE_DTYPE)
    faces["n"] = 3
    faces["v"] = tri
    head = ("ply\nformat binary_little_endian 1.0\ncomment deformd_blender\n"
            "element vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
            "element face %d\nproperty list uchar uint vertex_indices\nend_header\n"
            % (len(pos), len(faces))).encode("ascii")
    return b"".join((head, pos.tobytes(), faces.tobytes()))


def object_ply(obj, depsgraph):
    """(ply bytes, nv) of obj's evaluated mesh."""
    pos, tri = evaluated_arrays(obj, depsgraph)
    return ply_bytes(pos, tri), len(pos)
