"""Malformed input over raw sockets: every broken frame gets an error reply (connection kept) or
an error frame and a closed connection (framing broken), and the daemon keeps serving."""
import math
import random
import struct

import pytest

from deformd_client import DeformdError, errors as E, frame as fr, messages as m
from helpers import grid_obj, tet_grid_medit
from rawwire import read_frames, wait_closed


@pytest.fixture(scope="module")
def grid_session(daemon):
    with daemon.unix_client() as c:
        info = c.load_mesh(tet_grid_medit(4), fmt=".mesh", name="malformed-cube")
        assert info.nv == 64 and info.kind == 3
    yield info
    with daemon.unix_client() as c:
        c.close_session(info.session_id)


def assert_serving(daemon):
    assert daemon.alive(), "deformd died:\n" + daemon.log()[-3000:]
    with daemon.unix_client(timeout=5) as c:
        assert c.ping(b"still here") == b"still here"


def error_of(f: fr.Frame):
    assert f.is_error, "expected an error frame, got type 0x%x flags 0x%x" % (f.type, f.flags)
    return m.decode_error(f.payload)


def one_reply(sock, data: bytes, rid: int):
    sock.sendall(data)
    frames, closed = read_frames(sock, 5.0)
    assert frames, "no reply (closed=%s)" % closed
    f = frames[0]
    assert f.request_id == rid
    assert f.is_reply
    return f, closed


def ping_on(sock, rid: int = 999) -> bool:
    sock.sendall(fr.encode_frame(m.PING, b"ok?", rid))
    frames, _ = read_frames(sock, 5.0)
    return bool(frames) and frames[0].payload == b"ok?" and frames[0].request_id == rid


@pytest.mark.parametrize("what,header,code", [
    ("bad magic", fr.encode_header(m.PING, 0, 1, 0, magic=0x58585858), E.EPROTO_BADMAGIC),
    ("bad version", fr.encode_header(m.PING, 0, 1, 0, version=2), E.EPROTO_BADVERSION),
    ("version 0", fr.encode_header(m.PING, 0, 1, 0, version=0), E.EPROTO_BADVERSION),
    ("length 4 GiB", fr.encode_header(m.PING, 0, 1, 0xFFFFFFFF), E.EPROTO_TOOLARGE),
    ("length 64 MiB + 1", fr.encode_header(m.LOAD_MESH, 0, 1, fr.MAX_FRAME_PAYLOAD + 1),
     E.EPROTO_TOOLARGE),
])
def test_fatal_header_errors_close_only_that_connection(daemon, what, header, code):
    bystander = daemon.unix_client()
    s = daemon.raw_unix()
    s.sendall(header)
    frames, closed = read_frames(s, 5.0)
    # PROTOCOL.md 7: one ERROR event (type ERROR, flags ERROR only, request id 0), then close
    assert frames, "%s: no error frame before the close" % what
    c, msg = error_of(frames[0])
    assert c == code, "%s: code %d (%s)" % (what, c, msg)
    assert frames[0].type == m.ERROR and frames[0].flags == fr.FLAG_ERROR, \
        "%s: type 0x%x flags 0x%x" % (what, frames[0].type, frames[0].flags)
    assert frames[0].request_id == 0
    closed = closed or wait_closed(s)
    assert closed, "%s: connection not closed" % what
    s.close()
    assert bystander.ping(b"x") == b"x"
    bystander.close()
    assert_serving(daemon)


def test_requests_before_hello_are_refused_estate(daemon, grid_session):
    """PROTOCOL.md 1.4: requests other than HELLO and PING before a successful HELLO get
    ESTATE."""
    s = daemon.raw_unix()
    assert ping_on(s)
    f, _ = one_reply(s, fr.encode_frame(m.LIST_SESSIONS, b"", 5), 5)
    assert f.is_error and error_of(f)[0] == E.ESTATE, "LIST_SESSIONS before HELLO was served"
    s.close()


def test_unknown_type_gets_badtype_and_connection_survives(daemon):
    s = daemon.raw_unix(hello=True)
    f, closed = one_reply(s, fr.encode_frame(0x7777, b"hello", 41), 41)
    assert error_of(f)[0] == E.EPROTO_BADTYPE
    assert f.type == 0x7777, "answered with type 0x%x, not the request's" % f.type
    assert ping_on(s)
    # server-only types sent as requests are refused too
    f, _ = one_reply(s, fr.encode_frame(m.DISPLACEMENT, b"", 42), 42)
    assert error_of(f)[0] == E.EPROTO_BADTYPE
    assert f.type == m.DISPLACEMENT
    s.close()
    assert_serving(daemon)


@pytest.mark.parametrize("flags,code", [
    (fr.FLAG_REPLY, E.EPROTO_BADFLAGS),  # a reply sent to the server
    (fr.FLAG_EVENT, E.EPROTO_BADFLAGS),
    (fr.FLAG_REPLY | fr.FLAG_ERROR, E.EPROTO_BADFLAGS),
    (fr.FLAG_MORE, E.EPROTO_BADFLAGS),  # only load_mesh may be chunked
    (0x0100, E.EPROTO_BADFLAGS),    # unknown bit
])
def test_bad_flags_are_answered(daemon, flags, code):
    s = daemon.raw_unix(hello=True)
    s.sendall(fr.encode_frame(m.PING, b"abc", 7, flags))
    frames, closed = read_frames(s, 5.0)
    assert frames, "no reply to flags 0x%x (closed=%s)" % (flags, closed)
    c, msg = error_of(frames[0])
    assert c == code, "flags 0x%x: %s %s" % (flags, E.error_name(c), msg)
    assert frames[0].type == m.PING and frames[0].request_id == 7
    s.close()
    assert_serving(daemon)


def test_request_id_zero_is_refused_with_an_error_event(daemon):
    """PROTOCOL.md 1.3: id 0 is reserved for events; a request with it is not executed and is
    answered by an ERROR event (type ERROR, flags ERROR, id 0, EINVAL); the connection stays."""
    s = daemon.raw_unix(hello=True)
    s.sendall(fr.encode_frame(m.PING, b"zero", 0))
    frames, closed = read_frames(s, 5.0)
    assert frames and not closed
    f = frames[0]
    assert f.type == m.ERROR and f.flags == fr.FLAG_ERROR and f.request_id == 0
    c, msg = error_of(f)
    assert c == E.EINVAL and "request id 0" in msg
    assert ping_on(s)
    s.close()


def test_hello_version_mismatch_is_answered_then_closed(daemon):
    """PROTOCOL.md 4.2b: no common version -> EPROTO_BADVERSION reply, then the server closes."""
    s = daemon.raw_unix()
    s.sendall(fr.encode_frame(m.HELLO, m.encode_hello(5, 9, 0, "future"), 3))
    frames, closed = read_frames(s, 5.0)
    assert frames, "no reply to the HELLO"
    assert frames[0].is_reply and frames[0].request_id == 3
    assert error_of(frames[0])[0] == E.EPROTO_BADVERSION
    assert closed or wait_closed(s), "connection left open after a version mismatch"
    s.close()
    assert_serving(daemon)


def test_nonzero_reserved_header_field_is_answered(daemon):
    s = daemon.raw_unix(hello=True)
    s.sendall(fr.encode_header(m.PING, 0, 5, 2, reserved=1) + b"hi")
    frames, closed = read_frames(s, 5.0)
    assert frames and error_of(frames[0])[0] == E.EPROTO_RESERVED
    assert ping_on(s)
    s.close()


@pytest.mark.parametrize("cut", [3, 23, 24 + 10])
def test_truncated_frame_then_eof(daemon, cut):
    """A peer that sends part of a frame and hangs up: daemon drops it, serves others."""
    frame = fr.encode_frame(m.BRUSH_UPDATE, m.encode_brush_update(1, (0, 0, 1)), 3)
    s = daemon.raw_unix()
    s.sendall(frame[:cut])
    s.shutdown(1)
    frames, closed = read_frames(s, 3.0)
    assert not frames or frames[0].is_error
    s.close()
    assert_serving(daemon)


def test_truncated_frame_then_silence_does_not_block_others(daemon):
    s = daemon.raw_unix()
    s.sendall(fr.encode_header(m.PING, 0, 1, 1000) + b"only a little")
    assert_serving(daemon)
    s.close()


@pytest.mark.parametrize("msg_type", [m.BRUSH_BEGIN, m.BRUSH_UPDATE, m.HELLO, m.LOAD_MESH,
                                      m.HANDLES_SET, m.HANDLES_MOVE, m.GET_MESH, m.UNDO,
                                      m.SNAPSHOT, m.SUBSCRIBE, m.OPEN_SESSION,
                                      m.HANDLES_GET])
def test_length_zero_body_is_truncated(daemon, msg_type):
    s = daemon.raw_unix(hello=True)
    f, _ = one_reply(s, fr.encode_frame(msg_type, b"", 11), 11)
    c, msg = error_of(f)
    assert c == E.EPROTO_TRUNCATED, "%s: %d %s" % (m.TYPE_NAMES[msg_type], c, msg)
    assert f.type == msg_type
    assert ping_on(s)
    s.close()


def test_trailing_bytes_are_refused(daemon, grid_session):
    s = daemon.raw_unix(hello=True)
    f, _ = one_reply(s, fr.encode_frame(m.UNDO, m.encode_session_ref(grid_session.session_id)
                                        + b"\0", 12), 12)
    assert error_of(f)[0] == E.EPROTO_TRAILING
    f, _ = one_reply(s, fr.encode_frame(m.LIST_SESSIONS, b"x", 13), 13)
    assert error_of(f)[0] == E.EPROTO_TRAILING
    for rid, body in ((14, m.encode_session_ref(grid_session.session_id) + b"\0"),
                      (15, m.encode_session_ref(grid_session.session_id)[:7])):
        f, _ = one_reply(s, fr.encode_frame(m.HANDLES_GET, body, rid), rid)
        assert f.type == m.HANDLES_GET
        assert error_of(f)[0] == (E.EPROTO_TRAILING if rid == 14 else E.EPROTO_TRUNCATED)
    f, _ = one_reply(s, fr.encode_frame(m.HANDLES_GET, m.encode_session_ref(0), 16), 16)
    assert error_of(f)[0] in (E.EINVAL, E.ENOTFOUND)
    assert ping_on(s)
    s.close()


def _brush_payload(sid, **kw):
    b = m.Brush(type="grab", center=(0.5, 0.5, 0), move=(0, 0, 0.1), radius=0.3, nu=0.45)
    for k, v in kw.items():
        setattr(b, k, v)
    return m.encode_brush(sid, b)


NAN = float("nan")


def _handles(sid, handles, affine=(), **kw):
    return m.encode_handles(sid, "arap", handles, m.HandleParams.for_energy("arap", **kw),
                            affine)


@pytest.mark.parametrize("what,payload_fn", [
    ("radius NaN", lambda sid: _brush_payload(sid, radius=NAN)),
    ("nu NaN", lambda sid: _brush_payload(sid, nu=NAN)),
    ("center NaN", lambda sid: _brush_payload(sid, center=(NAN, 0, 0))),
    ("move inf", lambda sid: _brush_payload(sid, move=(0, math.inf, 0))),
    ("strength NaN", lambda sid: _brush_payload(sid, strength=NAN)),
    ("pinned NaN", lambda sid: _brush_payload(sid, pinned=[(NAN, 0, 0)])),
    ("mirror normal 0", lambda sid: _brush_payload(sid, mirror=(0, 0, 0, 0, 0, 0))),
    ("radius 0", lambda sid: _brush_payload(sid, radius=0.0)),
    ("falloff 9", lambda sid: _brush_payload(sid, falloff=9)),
    ("steps 0", lambda sid: _brush_payload(sid, steps=0)),
    ("dim 4", lambda sid: _brush_payload(sid, dim=4)),
])
def test_bad_brush_parameters_change_nothing(daemon, grid_session, what, payload_fn):
    sid = grid_session.session_id
    with daemon.unix_client() as c:
        before = c.get_mesh(sid)
        rid = c.send(m.BRUSH_BEGIN, payload_fn(sid))
        with pytest.raises(DeformdError) as ei:
            c.wait_reply(rid)
        assert ei.value.code == E.EINVAL, "%s: %s" % (what, ei.value)
        after = c.get_mesh(sid)
        assert after.version == before.version
        assert after.positions.tobytes() == before.positions.tobytes()


@pytest.mark.parametrize("what,payload_fn", [
    ("update NaN", lambda sid: (m.BRUSH_UPDATE, m.encode_brush_update(sid, (NAN, 0, 0)))),
    ("param radius NaN", lambda sid: (m.SET_BRUSH_PARAM, m.encode_brush_param(sid, "radius", NAN))),
    ("param falloff 0", lambda sid: (m.SET_BRUSH_PARAM, m.encode_brush_param(sid, "falloff", 0))),
    ("param id 77", lambda sid: (m.SET_BRUSH_PARAM, struct.pack("<QBd", sid, 77, 1.0))),
    ("move target NaN", lambda sid: (m.HANDLES_MOVE, m.encode_handle_move(sid, [(NAN, 0, 0)]))),
    ("handles w NaN", lambda sid: (m.HANDLES_SET, _handles(sid, [0], w=NAN))),
    ("handles rho inf", lambda sid: (m.HANDLES_SET, _handles(sid, [0], rho=math.inf))),
    ("handles poisson 0.5", lambda sid: (m.HANDLES_SET, _handles(sid, [0], poisson=0.5))),
    ("handle index out of range", lambda sid: (m.HANDLES_SET, _handles(sid, [0, 64]))),
    ("handle index 2^31", lambda sid: (m.HANDLES_SET, _handles(sid, [0, 1 << 31]))),
    ("handle repeated", lambda sid: (m.HANDLES_SET, _handles(sid, [3, 3]))),
    ("affine index out of range", lambda sid: (m.HANDLES_SET, _handles(
        sid, [0], affine=[m.AffineSet(A=[(0, 0, 1)], b=[0], indices=[1000])]))),
    ("energy 9", lambda sid: (m.HANDLES_SET, _handles(sid, [0])[:8] + b"\x09"
                              + _handles(sid, [0])[9:])),
    ("anderson_m 0", lambda sid: (m.HANDLES_SET, _handles(sid, [0], anderson_m=0))),
])
def test_bad_numbers_and_indices_are_refused(daemon, grid_session, what, payload_fn):
    sid = grid_session.session_id
    mtype, payload = payload_fn(sid)
    with daemon.unix_client() as c:
        v0 = c.open_session(sid).version
        rid = c.send(mtype, payload)
        with pytest.raises(DeformdError) as ei:
            c.wait_reply(rid)
        assert ei.value.code in (E.EINVAL, E.ELIMIT, E.ESTATE), "%s: %s" % (what, ei.value)
        assert c.open_session(sid).version == v0
    assert_serving(daemon)


def test_unknown_session_and_future_version(daemon, grid_session):
    with daemon.unix_client() as c:
        for call in (lambda: c.undo(987654321), lambda: c.get_mesh(987654321),
                     lambda: c.subscribe(987654321), lambda: c.stats(987654321),
                     lambda: c.open_session(0, "no-such-session")):
            with pytest.raises(DeformdError) as ei:
                call()
            assert ei.value.code == E.ENOTFOUND
            assert ei.value.name == "ENOTFOUND" and ei.value.message
        with pytest.raises(DeformdError) as ei:
            c.snapshot(grid_session.session_id, 10 ** 12)
        assert ei.value.code == E.ENOTFOUND
        rid = c.send(m.UNDO, m.encode_session_ref(0))
        with pytest.raises(DeformdError) as ei:
            c.wait_reply(rid)
        assert ei.value.code in (E.EINVAL, E.ENOTFOUND)


def test_load_chunks_out_of_order_and_inconsistent(daemon):
    data = grid_obj(6, 6)
    s = daemon.raw_unix(hello=True)
    # first chunk claims offset 100
    p = m.encode_load_mesh(m.LOAD_INLINE, m.FMT_OBJ, "bad", "", len(data), 0, 100, data[100:200])
    f, _ = one_reply(s, fr.encode_frame(m.LOAD_MESH, p, 21, fr.FLAG_MORE), 21)
    assert error_of(f)[0] in (E.EPROTO_CHUNK, E.EINVAL)
    # a chunk past total_size
    p = m.encode_load_mesh(m.LOAD_INLINE, m.FMT_OBJ, "bad", "", 10, 0, 0, data[:50])
    f, _ = one_reply(s, fr.encode_frame(m.LOAD_MESH, p, 22), 22)
    assert error_of(f)[0] in (E.EINVAL, E.EPROTO_CHUNK)
    # last chunk (no MORE flag) that leaves the upload incomplete
    p = m.encode_load_mesh(m.LOAD_INLINE, m.FMT_OBJ, "bad", "", len(data), 0, 0, data[:50])
    f, _ = one_reply(s, fr.encode_frame(m.LOAD_MESH, p, 23), 23)
    assert error_of(f)[0] in (E.EPROTO_CHUNK, E.EINVAL)
    assert ping_on(s)
    s.close()
    with daemon.unix_client() as c:
        assert not [i for i in c.list_sessions() if i.name == "bad"]


def test_garbage_mesh_bytes_are_a_format_error(daemon):
    with daemon.unix_client() as c:
        n0 = len(c.list_sessions())
        for fmt, data in ((".obj", b"v 1 2\nf 1 2 3\n"), (".off", b"OFF\n3 1 0\n0 0 0\n"),
                          (".obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"),
                          (".obj", b"v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")):
            with pytest.raises(DeformdError) as ei:
                c.load_mesh(data, fmt=fmt, name="garbage")
            assert ei.value.code in (E.EFORMAT, E.EINVAL), ei.value
        assert len(c.list_sessions()) == n0


def test_random_payloads_never_kill_the_daemon(daemon, grid_session):
    rng = random.Random(1234)
    types = sorted(set(m.TYPE_NAMES) - {m.CLOSE_SESSION})
    sid = grid_session.session_id
    for round_ in range(4):
        s = daemon.raw_unix(hello=True)
        sent = 0
        for k in range(60):
            t = rng.choice(types)
            n = rng.choice([1, 7, 8, 9, 16, 17, 44, 136, 252, 300])
            payload = bytearray(rng.getrandbits(8) for _ in range(n))
            if n >= 8 and rng.random() < 0.5:
                payload[:8] = struct.pack("<Q", sid)
            try:
                s.sendall(fr.encode_frame(t, bytes(payload), 1000 + k))
                sent += 1
            except (BrokenPipeError, ConnectionResetError):
                break
        frames, closed = read_frames(s, 5.0, want=sent)
        for f in frames:
            assert f.is_reply or f.is_event or f.is_error
        s.close()
        assert_serving(daemon)
