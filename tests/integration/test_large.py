"""Messages larger than one frame on the real daemon: a 17 MB mesh upload (3 load chunks), a
dense displacement version of 1.4M vertices (> DF_STREAM_CHUNK_BYTES, so 2 event chunks), a
chunked get-mesh reply; the replica built from the chunks equals the daemon's positions."""
import struct
from array import array

from deformd_client import Brush, MeshState, messages as m, stream as st

N = 1190                      # 1,416,100 vertices: 16.99 MB of float32 xyz, above 16 MiB


def big_plane_ply(n: int) -> bytes:
    """Binary PLY: an n x n vertex plane (z = 0) and one triangle."""
    v = array("f")
    row = [i / (n - 1) for i in range(n)]
    for j in range(n):
        y = j / (n - 1)
        xyz = array("f", bytes(12 * n))
        xyz[0::3] = array("f", row)
        xyz[1::3] = array("f", [y] * n)
        v += xyz
    head = ("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\n"
            "property float y\nproperty float z\nelement face 1\n"
            "property list uchar int vertex_indices\nend_header\n" % (n * n)).encode()
    return head + v.tobytes() + struct.pack("<Biii", 3, 0, 1, n)


def test_chunked_upload_stream_and_get_mesh(daemon):
    data = big_plane_ply(N)
    assert len(data) > 2 * m.LOAD_CHUNK_BYTES
    with daemon.unix_client(timeout=120) as c, daemon.unix_client(timeout=120) as w:
        info = c.load_mesh(data, fmt=".ply", name="large")
        sid = info.session_id
        assert info.nv == N * N
        w.subscribe(sid)
        c.stroke(sid, Brush(type="grab", center=(0.5, 0.5, 0.0), move=(0.0, 0.0, 0.1),
                            radius=0.3, nu=0.45))
        chunks = []
        while True:                                   # raw frames of the one version
            f = w.recv_frame(timeout=60)
            assert f is not None and f.type == m.DISPLACEMENT and f.is_event
            chunks.append(f)
            if not f.more:
                break
        assert len(chunks) >= 2
        assert all(len(f.payload) <= st.DISP_STRUCT.size + (16 << 20) for f in chunks)
        version = st.join_disp([st.decode_disp(f.payload) for f in chunks])
        assert version.encoding == m.DISP_DENSE and version.count == N * N
        parts = c.request(m.GET_MESH, m.encode_get_mesh(sid, m.GET_MESH_BASE))
        assert sum(1 for p in parts if p.more) >= 2 and not parts[-1].more
        mesh = c.get_mesh(sid, base=True)
        replica = MeshState(mesh.base)
        replica.apply(version)
        assert replica.tobytes() == mesh.positions.tobytes()
        centre = (N // 2) * N + N // 2
        assert abs(mesh.positions[3 * centre + 2] - 0.1) < 2e-3
        c.close_session(sid)
