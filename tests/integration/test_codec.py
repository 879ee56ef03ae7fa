"""The Python client's codec on its own (no daemon): frame header round trips, incremental
decoding, malformed headers, and body codecs against hand-packed bytes from proto/msg_*.c."""
import math
import struct
from array import array

import pytest

from deformd_client import frame as fr
from deformd_client import messages as m
from deformd_client import MeshState, OutOfSync


def test_header_layout_is_24_bytes_little_endian():
    h = fr.encode_header(0x0021, fr.FLAG_REPLY | fr.FLAG_MORE, 0x0102030405060708, 77)
    assert len(h) == 24
    assert h[:4] == b"DFMD"
    assert struct.unpack_from("<H", h, 4)[0] == 1
    assert struct.unpack_from("<H", h, 6)[0] == 0x21
    assert struct.unpack_from("<H", h, 8)[0] == 9
    assert h[12:20] == bytes([8, 7, 6, 5, 4, 3, 2, 1])
    assert struct.unpack_from("<I", h, 20)[0] == 77
    assert fr.decode_header(h) == (0x21, 9, 0x0102030405060708, 77, 1)


def test_decoder_reassembles_frames_split_at_every_byte():
    frames = [fr.encode_frame(3, b"x" * k, k + 1, fr.FLAG_REPLY) for k in range(5)]
    stream = b"".join(frames)
    d = fr.FrameDecoder()
    got = []
    for i in range(len(stream)):
        got += d.feed(stream[i:i + 1])
    assert [(f.request_id, f.payload) for f in got] == [(k + 1, b"x" * k) for k in range(5)]
    assert d.pending == 0


@pytest.mark.parametrize("mutate,needle", [
    (lambda h: b"XFMD" + h[4:], "magic"),
    (lambda h: h[:4] + struct.pack("<H", 2) + h[6:], "version"),
    (lambda h: h[:10] + struct.pack("<H", 1) + h[12:], "reserved"),
    (lambda h: h[:20] + struct.pack("<I", 0xFFFFFFFF), "limit"),
])
def test_decoder_rejects_bad_headers_and_stays_poisoned(mutate, needle):
    d = fr.FrameDecoder()
    with pytest.raises(fr.FrameError, match=needle):
        d.feed(mutate(fr.encode_header(3, 0, 1, 0)))
    with pytest.raises(fr.FrameError):
        d.feed(fr.encode_frame(3, b"", 2))


def test_oversized_payload_is_refused_by_the_encoder():
    with pytest.raises(fr.FrameError):
        fr.encode_frame(3, bytes(fr.MAX_FRAME_PAYLOAD + 1))


def test_brush_body_matches_the_c_layout():
    b = m.Brush(type="twist", center=(1, 2, 3), twist=(0, 0, 0.5), radius=0.25, nu=math.inf,
                falloff=2, ratio=3.0, dim=2, integrator="rk4", steps=7, moving=True,
                mirror=(0, 0, 0, 1, 0, 0), pinned=[(4, 5, 6), (7, 8, 9)])
    p = m.encode_brush(42, b)
    assert len(p) == 252 + 2 * 24
    v = struct.unpack_from("<QBBBBHBB", p, 0)
    assert v == (42, 2, 2, 2, 2, 7, 1, 1)
    radius, ratio, nu, strength = struct.unpack_from("<4d", p, 16)
    assert (radius, ratio, nu, strength) == (0.25, 3.0, math.inf, 1.0)
    assert struct.unpack_from("<3d", p, 48) == (1.0, 2.0, 3.0)       # center
    assert struct.unpack_from("<3d", p, 96) == (0.0, 0.0, 0.5)       # twist
    assert struct.unpack_from("<3d", p, 200) == (0.0, 0.0, 0.0)      # mirror point
    assert struct.unpack_from("<3d", p, 224) == (1.0, 0.0, 0.0)      # mirror normal
    assert struct.unpack_from("<I", p, 248)[0] == 2
    assert struct.unpack_from("<6d", p, 252) == (4.0, 5.0, 6.0, 7.0, 8.0, 9.0)
    with pytest.raises(ValueError):
        m.encode_brush(1, m.Brush(type="smudge"))
    with pytest.raises(ValueError):
        m.encode_brush(1, m.Brush(center=(1, 2)))


def test_handles_body_with_affine_sets():
    p = m.encode_handles(9, "neohookean", [3, 1, 4], 1e4, 0.01, 5e5, 1e-11, 500,
                         [m.AffineSet(A=[(0, 0, 1)], b=[2.5], indices=[7, 8])])
    sid, energy, w, s, rho, tol, iters, n = struct.unpack_from("<QB4dII", p, 0)
    assert (sid, energy, w, s, rho, tol, iters, n) == (9, 3, 1e4, 0.01, 5e5, 1e-11, 500, 3)
    off = 49
    assert struct.unpack_from("<3I", p, off) == (3, 1, 4)
    off += 12
    assert struct.unpack_from("<IB", p, off) == (1, 1)
    off += 5
    assert struct.unpack_from("<4d", p, off) == (0.0, 0.0, 1.0, 2.5)
    off += 32
    assert struct.unpack_from("<3I", p, off) == (2, 7, 8)
    assert len(p) == off + 12


def test_disp_round_trip_dense_and_sparse_and_chunk_join():
    xyz = array("f", [0.5 * k for k in range(12)])
    dense = m.Disp(5, 3, 2, m.CHANGE_BRUSH, m.DISP_DENSE, 4, 4, 0, 4, None, xyz)
    assert m.decode_disp(m.encode_disp(dense)) == dense
    sp = m.Disp(5, 4, 3, m.CHANGE_UNDO, m.DISP_SPARSE, 4, 2, 0, 2, array("I", [1, 3]),
                array("f", [1, 2, 3, -4, -5, -6]))
    enc = m.encode_disp(sp)
    assert len(enc) == 44 + 32
    assert m.decode_disp(enc) == sp
    halves = [m.Disp(5, 3, 2, 1, 1, 4, 4, 0, 2, None, xyz[:6]),
              m.Disp(5, 3, 2, 1, 1, 4, 4, 2, 2, None, xyz[6:])]
    assert m.join_disp(halves).xyz == xyz
    with pytest.raises(m.ProtocolError):
        m.join_disp(halves[::-1])
    with pytest.raises(m.ProtocolError):
        m.decode_disp(enc[:-1])
    with pytest.raises(m.ProtocolError):
        m.decode_disp(enc + b"\0")


def test_mesh_state_applies_dense_sparse_and_detects_gaps():
    base = array("f", [0, 0, 0, 1, 0, 0, 0, 1, 0])
    st = MeshState(base)
    d1 = m.Disp(1, 1, 0, 1, m.DISP_DENSE, 3, 3, 0, 3, None,
                array("f", [0.1, 0, 0, 0.2, 0, 0, 0.3, 0, 0]))
    assert st.apply(d1) and st.version == 1
    assert list(st.positions) == list(array("f", [0.1, 0, 0, 1.2, 0, 0, 0.3, 1, 0]))
    d2 = m.Disp(1, 2, 1, 4, m.DISP_SPARSE, 3, 1, 0, 1, array("I", [2]), array("f", [0, 0, 0]))
    assert st.apply(d2)
    assert st.positions[6:9] == array("f", [0, 1, 0])
    assert not st.apply(d2)                      # already applied
    d4 = m.Disp(1, 4, 3, 1, m.DISP_SPARSE, 3, 1, 0, 1, array("I", [0]), array("f", [1, 1, 1]))
    with pytest.raises(OutOfSync):
        st.apply(d4)
    assert st.version == 2


def test_error_session_info_and_stats_bodies():
    body = struct.pack("<iH", -7, 5) + b"gone!"
    assert m.decode_error(body) == (-7, "gone!")
    info = struct.pack("<QQBBHIIII", 3, 9, 2, 0, 1, 100, 196, 2, 0) + struct.pack("<H", 4) + b"spot"
    s = m.decode_session_info(info)
    assert (s.session_id, s.version, s.nv, s.ne, s.undo_depth, s.name) == (3, 9, 100, 196, 2, "spot")
    assert m.decode_session_list(struct.pack("<I", 2) + info + info)[1].name == "spot"
    st = struct.pack("<I", 1) + struct.pack("<H", 5) + b"a.b_c" + struct.pack("<d", 2.5)
    assert m.decode_stats(st) == {"a.b_c": 2.5}
    with pytest.raises(m.ProtocolError):
        m.decode_session_info(info[:-1])
