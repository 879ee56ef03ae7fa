"""The object's evaluated mesh (object space) as a binary little-endian PLY, built with numpy:
vertex floats and triangle rows are written as whole arrays (no per-vertex Python loop)."""
import numpy as np

FACE_DTYPE = np.dtype([("n", "u1"), ("v", "<i4", (3,))])


def evaluated_arrays(obj, depsgraph):
    """(positions (nv, 3) float32, triangles (nt, 3) int32) of obj's evaluated mesh in object
    space. ValueError when obj is not a mesh."""
    if obj is None or obj.type != "MESH":
        raise ValueError("the active object is not a mesh")
    ev = obj.evaluated_get(depsgraph)
    mesh = ev.to_mesh()
    try:
        nv = len(mesh.vertices)
        pos = np.empty(nv * 3, dtype=np.float32)
        mesh.vertices.foreach_get("co", pos)
        mesh.calc_loop_triangles()
        nt = len(mesh.loop_triangles)
        tri = np.empty(nt * 3, dtype=np.int32)
        mesh.loop_triangles.foreach_get("vertices", tri)
    finally:
        ev.to_mesh_clear()
    return pos.reshape(-1, 3), tri.reshape(-1, 3)


def ply_bytes(pos: np.ndarray, tri: np.ndarray) -> bytes:
    """Binary PLY: `vertex` x y z float, `face` list uchar int vertex_indices."""
    pos = np.ascontiguousarray(pos, dtype="<f4").reshape(-1, 3)
    faces = np.empty(len(tri), dtype=FACE_DTYPE)
    faces["n"] = 3
    faces["v"] = tri
    head = ("ply\nformat binary_little_endian 1.0\ncomment deformd_blender\n"
            "element vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
            "element face %d\nproperty list uchar int vertex_indices\nend_header\n"
            % (len(pos), len(faces))).encode("ascii")
    return b"".join((head, pos.tobytes(), faces.tobytes()))


def object_ply(obj, depsgraph):
    """(ply bytes, nv) of obj's evaluated mesh."""
    pos, tri = evaluated_arrays(obj, depsgraph)
    return ply_bytes(pos, tri), len(pos)
