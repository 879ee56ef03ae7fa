"""The Python client's codec on its own (no daemon): frame header round trips, incremental
decoding, malformed headers, and body codecs against hand-packed bytes from proto/msg_*.c."""
import math
import struct
from array import array

import pytest

from deformd_client import frame as fr
from deformd_client import messages as m, stream as st
from deformd_client import MeshState, OutOfSync, ProtocolError


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
    assert len(p) == 253 + 2 * 24
    v = struct.unpack_from("<QBBBBHBB", p, 0)
    assert v == (42, 2, 2, 2, 2, 7, 1, 1)
    radius, ratio, nu, strength = struct.unpack_from("<4d", p, 16)
    assert (radius, ratio, nu, strength) == (0.25, 3.0, math.inf, 1.0)
    assert struct.unpack_from("<3d", p, 48) == (1.0, 2.0, 3.0)       # center
    assert struct.unpack_from("<3d", p, 96) == (0.0, 0.0, 0.5)       # twist
    assert struct.unpack_from("<3d", p, 200) == (0.0, 0.0, 0.0)      # mirror point
    assert struct.unpack_from("<3d", p, 224) == (1.0, 0.0, 0.0)      # mirror normal
    assert struct.unpack_from("<IB", p, 248) == (2, m.PIN_DISPLACEMENT)
    assert struct.unpack_from("<6d", p, 253) == (4.0, 5.0, 6.0, 7.0, 8.0, 9.0)
    assert m.encode_brush(1, m.Brush())[252] == 0                    # no pins: flags 0
    both = m.Brush(pinned=[(0, 0, 0)], pin_flags=m.PIN_DISPLACEMENT | m.PIN_GRADIENT)
    assert m.encode_brush(1, both)[252] == 3
    with pytest.raises(ValueError):
        m.encode_brush(1, m.Brush(type="smudge"))
    with pytest.raises(ValueError):
        m.encode_brush(1, m.Brush(center=(1, 2)))


def test_handles_body_with_affine_sets():
    hp = m.HandleParams.for_energy("neohookean", w=1.0, rho=1e3, max_iters=40, accelerate=True)
    p = m.encode_handles(9, "neohookean", [3, 1, 4], hp,
                         [m.AffineSet(A=[(0, 0, 1)], b=[2.5], indices=[7, 8])])
    head = struct.unpack_from("<QBBBB9dII", p, 0)
    assert head == (9, 3, 0, 1, 5, 1.0, 0.01, 1e3, 1e-11, 1e7, 0.45, 0.9, 1.1, 1e-3, 40, 3)
    off = 92
    assert struct.unpack_from("<3I", p, off) == (3, 1, 4)
    off += 12
    assert struct.unpack_from("<IB", p, off) == (1, 1)
    off += 5
    assert struct.unpack_from("<4d", p, off) == (0.0, 0.0, 1.0, 2.5)
    off += 32
    assert struct.unpack_from("<3I", p, off) == (2, 7, 8)
    assert len(p) == off + 12
    assert m.HandleParams.for_energy("arap").w == 1e-4
    with pytest.raises(TypeError):
        m.HandleParams.for_energy("arap", omega=1)


def test_handles_body_decodes_back_and_rejects_bad_bytes():
    """decode_handles (the HANDLES_GET reply) inverts encode_handles field by field."""
    hp = m.HandleParams.for_energy("cloth", strain_min=0.85, bending=0.5, area_weighting=True,
                                   anderson_m=3, max_iters=12)
    aff = [m.AffineSet(A=[(0, 0, 1), (1, 0, 0), (0, 1, 0)], b=[2.5, -1, 0.25], indices=[7, 8, 2])]
    p = m.encode_handles(11, "cloth", [30, 2, 17], hp, aff)
    hs = m.decode_handles(p)
    assert (hs.session_id, hs.energy, hs.handles) == (11, "cloth", [30, 2, 17])
    assert hs.params == hp
    assert hs.affine[0].A == [[0, 0, 1], [1, 0, 0], [0, 1, 0]]
    assert hs.affine[0].b == [2.5, -1, 0.25] and hs.affine[0].indices == [7, 8, 2]
    assert m.encode_handles(11, hs.energy, hs.handles, hs.params, hs.affine) == p
    for cut in (0, 91, 92, len(p) - 1):
        with pytest.raises(ProtocolError):
            m.decode_handles(p[:cut])
    with pytest.raises(ProtocolError):
        m.decode_handles(p + b"\0")
    with pytest.raises(ProtocolError):
        m.decode_handles(p[:8] + b"\x09" + p[9:])          # energy 9
    assert m.TYPE_NAMES[m.HANDLES_GET] == "handles_get" and m.HANDLES_GET == 0x0035


def test_disp_round_trip_dense_and_sparse_and_chunk_join():
    xyz = array("f", [0.5 * k for k in range(12)])
    dense = st.Disp(5, 3, 2, m.CHANGE_BRUSH, m.DISP_DENSE, 4, 4, 0, 4, None, xyz)
    assert st.decode_disp(st.encode_disp(dense)) == dense
    sp = st.Disp(5, 4, 3, m.CHANGE_UNDO, m.DISP_SPARSE, 4, 2, 0, 2, array("I", [1, 3]),
                array("f", [1, 2, 3, -4, -5, -6]))
    enc = st.encode_disp(sp)
    assert len(enc) == 44 + 32
    assert st.decode_disp(enc) == sp
    halves = [st.Disp(5, 3, 2, 1, 1, 4, 4, 0, 2, None, xyz[:6]),
              st.Disp(5, 3, 2, 1, 1, 4, 4, 2, 2, None, xyz[6:])]
    assert st.join_disp(halves).xyz == xyz
    with pytest.raises(st.ProtocolError):
        st.join_disp(halves[::-1])
    with pytest.raises(st.ProtocolError):
        st.decode_disp(enc[:-1])
    with pytest.raises(st.ProtocolError):
        st.decode_disp(enc + b"\0")


def test_mesh_state_applies_dense_sparse_and_detects_gaps():
    base = array("f", [0, 0, 0, 1, 0, 0, 0, 1, 0])
    rep = MeshState(base)
    d1 = st.Disp(1, 1, 0, 1, m.DISP_DENSE, 3, 3, 0, 3, None,
                array("f", [0.1, 0, 0, 0.2, 0, 0, 0.3, 0, 0]))
    assert rep.apply(d1) and rep.version == 1
    assert list(rep.positions) == list(array("f", [0.1, 0, 0, 1.2, 0, 0, 0.3, 1, 0]))
    d2 = st.Disp(1, 2, 1, 4, m.DISP_SPARSE, 3, 1, 0, 1, array("I", [2]), array("f", [0, 0, 0]))
    assert rep.apply(d2)
    assert rep.positions[6:9] == array("f", [0, 1, 0])
    assert not rep.apply(d2)                      # already applied
    d4 = st.Disp(1, 4, 3, 1, m.DISP_SPARSE, 3, 1, 0, 1, array("I", [0]), array("f", [1, 1, 1]))
    with pytest.raises(OutOfSync):
        rep.apply(d4)
    assert rep.version == 2


def test_error_session_info_and_stats_bodies():
    body = struct.pack("<iH", -7, 5) + b"gone!"
    assert m.decode_error(body) == (-7, "gone!")
    info = struct.pack("<QQBBHIIII", 3, 9, 2, 0, 1, 100, 196, 2, 0) + struct.pack("<H", 4) + b"spot"
    s = m.decode_session_info(info)
    assert (s.session_id, s.version, s.nv, s.ne, s.undo_depth, s.name) == (3, 9, 100, 196, 2, "spot")
    assert m.decode_session_list(struct.pack("<I", 2) + info + info)[1].name == "spot"
    stats = struct.pack("<I", 1) + struct.pack("<H", 5) + b"a.b_c" + struct.pack("<d", 2.5)
    assert m.decode_stats(stats) == {"a.b_c": 2.5}
    with pytest.raises(st.ProtocolError):
        m.decode_session_info(info[:-1])


def test_load_mesh_ext_and_load_reply_bodies():
    plain = m.encode_load_mesh(m.LOAD_INLINE, m.FMT_OBJ, "s", "", 3, 0, 0, b"abc")
    assert struct.unpack_from("<H", plain, 2)[0] == 0
    ext = m.encode_load_mesh(m.LOAD_INLINE, m.FMT_OBJ, "s", "", 3, 0, 0, b"abc", m.LOAD_OPT_EXT,
                             "spot.obj")
    assert struct.unpack_from("<H", ext, 2)[0] == m.LOAD_OPT_EXT
    assert ext == plain[:2] + b"\x01\x00" + plain[4:] + struct.pack("<H", 8) + b"spot.obj"
    # one options field: bit 0 EXT, bit 1 2D, bit 2 PROGRESS (2D and PROGRESS keep the layout)
    assert (m.LOAD_OPT_EXT, m.LOAD_OPT_2D, m.LOAD_OPT_PROGRESS, m.LOAD_OPTS_ALL) == (1, 2, 4, 7)
    two_d = m.encode_load_mesh(m.LOAD_INLINE, m.FMT_OBJ, "s", "", 3, 0, 0, b"abc", m.LOAD_OPT_2D)
    assert two_d == plain[:2] + b"\x02\x00" + plain[4:]
    prog = m.encode_load_mesh(m.LOAD_INLINE, m.FMT_OBJ, "s", "", 3, 0, 0, b"abc",
                              m.LOAD_OPT_PROGRESS)
    assert prog == plain[:2] + b"\x04\x00" + plain[4:]
    both = m.encode_load_mesh(m.LOAD_INLINE, m.FMT_OBJ, "s", "", 3, 0, 0, b"abc",
                              m.LOAD_OPT_EXT | m.LOAD_OPT_2D, "spot.obj")
    assert both == ext[:2] + b"\x03\x00" + ext[4:]
    info = struct.pack("<QQBBHIIII", 3, 0, 2, 0, 0, 100, 196, 0, 0) + struct.pack("<H", 4) + b"spot"
    bare = m.decode_load_reply(info)
    assert bare.name == "spot" and bare.report is None
    report = struct.pack("<BBH11I", 1, 1, 0, 98, 0, 2, 1, 0, 0, 3, 0, 4, 0, 5)
    s = m.decode_load_reply(info + report)
    assert (s.report.format, s.report.dropped_elements, s.report.duplicate_elements,
            s.report.nonmanifold_edges, s.report.boundary_edges, s.report.unused_vertices) == \
        (1, 2, 1, 3, 4, 5)
    for bad in (info + report[:-1], info + report + b"\0",
                info + report[:2] + b"\x01\x00" + report[4:]):
        with pytest.raises(ProtocolError):
            m.decode_load_reply(bad)


def _mesh_chunk(section, offset, rows, data, nv=4, ne=2):
    head = struct.pack("<QQBBBBIIIII", 7, 3, 2, 0, section, 0, nv, ne, 0, offset, rows)
    return head + data.tobytes()


def test_get_mesh_chunks_assemble_and_bad_order_is_refused():
    from deformd_client import MeshData
    pos = array("f", range(12))
    tri = array("I", [0, 1, 2, 0, 2, 3])
    chunks = [st.decode_mesh_chunk(_mesh_chunk(1, 0, 3, pos[:9])),
              st.decode_mesh_chunk(_mesh_chunk(1, 3, 1, pos[9:])),
              st.decode_mesh_chunk(_mesh_chunk(4, 0, 2, tri))]
    mesh = st.assemble_mesh(chunks, MeshData)
    assert mesh.positions == pos and mesh.elements == tri and mesh.elem_size == 3
    with pytest.raises(st.ProtocolError):
        st.assemble_mesh(chunks[1:], MeshData)
    with pytest.raises(st.ProtocolError):
        st.decode_mesh_chunk(_mesh_chunk(1, 3, 2, pos[:6]))      # rows beyond nv


def test_client_queues_events_met_while_waiting_and_raises_errors():
    """A fake daemon on a socketpair: the reply to a get-mesh comes in two chunks with a
    displacement event in between; then an error reply; then the peer hangs up. Replies are
    collected by id in any order."""
    import socket
    import threading
    from deformd_client import Client, ConnectionClosed, DeformdError, MeshData
    a, b = socket.socketpair()
    ev = st.Disp(7, 4, 3, m.CHANGE_UNDO, m.DISP_SPARSE, 4, 1, 0, 1, array("I", [2]),
                array("f", [1, 2, 3]))

    def fake_daemon():
        dec = fr.FrameDecoder()
        got = []
        while len(got) < 2:
            got += dec.feed(b.recv(65536))
        rid1, rid2 = got[0].request_id, got[1].request_id
        b.sendall(fr.encode_frame(m.GET_MESH, _mesh_chunk(1, 0, 4, array("f", range(12))), rid1,
                                  fr.FLAG_REPLY | fr.FLAG_MORE)
                  + fr.encode_frame(m.DISPLACEMENT, st.encode_disp(ev), 0, fr.FLAG_EVENT)
                  + fr.encode_frame(m.GET_MESH, _mesh_chunk(4, 0, 2, array("I", [0, 1, 2, 0, 2, 3])),
                                    rid1, fr.FLAG_REPLY)
                  + fr.encode_frame(m.UNDO, struct.pack("<iH", -8, 7) + b"nothing", rid2,
                                    fr.FLAG_REPLY | fr.FLAG_ERROR))
        b.close()

    t = threading.Thread(target=fake_daemon)
    t.start()
    c = Client(a, timeout=5, hello=False)
    r1 = c.send(m.GET_MESH, m.encode_get_mesh(7))
    r2 = c.send(m.UNDO, m.encode_session_ref(7))
    with pytest.raises(DeformdError) as ei:      # collected before the earlier request's reply
        c.wait_reply(r2)
    assert (ei.value.code, ei.value.name, ei.value.message) == (-8, "ESTATE", "nothing")
    mesh = st.assemble_mesh([st.decode_mesh_chunk(f.payload) for f in c.wait_reply(r1)], MeshData)
    assert mesh.nv == 4 and mesh.positions == array("f", range(12))
    assert c.pending_events() == 1
    assert c.next_event(1.0) == ev
    with pytest.raises(ConnectionClosed):
        c.next_event(1.0)
    t.join()
    c.close()
