"""Shared-memory stream (PROTOCOL.md 6.1, STREAM_SHM / SHM_REF): a Unix-socket subscriber reads
the session's large event frames from a ring file the daemon writes once, and receives a 24-byte
SHM_REF per frame on its socket. Checked here: replicas built from the ring equal the daemon's
positions byte for byte, the socket carries references (small frames stay on it), shm_info
matches the config and the ring file's life cycle, every error reply, a slow reader losing
frames and resyncing instead of being dropped, and UNSUBSCRIBE ending the references. The first
tests drive the Python client against a fake daemon and a ring written by the test itself."""
import mmap
import os
import socket
import stat
import struct
import tempfile
from array import array
from typing import List

import pytest

from deformd_client import (Brush, Client, DeformdError, MeshState, OutOfSync, ProtocolError,
                            SessionClosed, errors as E, frame as fr, messages as m, stream as st)
from deformd_client.client import ShmLost
from helpers import grid_obj, obj_bytes_positions, tet_grid, tet_grid_medit
from rawwire import read_frames

GRID_N = 40                                    # 1,600 vertices
DENSE_FRAME = fr.HEADER_SIZE + st.DISP_STRUCT.size + 12 * GRID_N * GRID_N   # 19,268 bytes
UPDATES = 15
REPEAT_EVERY = 4     # _stroke(mixed=True) repeats every 4th load: an empty 68-byte sparse version
RING_HEADER = struct.Struct("<8sIIQQQQ")       # magic, header_bytes, reserved, capacity,
#                                                session, valid_from, head


def ring_size(nv: int, cap: int = 64 << 20) -> int:
    """deformd's ring for a session of nv vertices (server/net/shm.h df_shm_ring_size)."""
    want = -(-128 * (12 * nv + 128) // (64 << 10)) * (64 << 10)
    return min(max(want, 64 << 10), cap)


def _grid_session(c: Client, name: str = "shm"):
    """Loads a GRID_N x GRID_N grid; returns (session id, base positions)."""
    data = grid_obj(GRID_N, GRID_N)
    return c.load_mesh(data, fmt=".obj", name=name).session_id, obj_bytes_positions(data)


def _wide_brush(X) -> Brush:
    """A grab whose radius covers the whole grid: every vertex moves, so versions are dense."""
    return Brush(type="grab", center=X[0:3], move=(0.0, 0.0, 0.0), radius=5.0, nu=0.4)


def _stroke(w: Client, sid: int, X, updates: int, mixed: bool = False) -> List[bool]:
    """One stroke of `updates` dense versions; with `mixed`, every REPEAT_EVERY-th load is sent
    twice, adding a version in which nothing moved (sparse, no rows: a frame far below
    min_frame, which stays on the socket). Returns, per version, whether it is dense."""
    dense = []
    w.brush_begin(sid, _wide_brush(X))
    for u in range(1, updates + 1):
        for again in range(2 if mixed and u % REPEAT_EVERY == 0 else 1):
            w.brush_update(sid, move=(0.002 * u, -0.001 * u, 0.003 * u))
            dense.append(again == 0)
    w.brush_end(sid)
    return dense


def _raw_request(sock, msg_type: int, payload: bytes, rid: int) -> fr.Frame:
    """Sends one request on a raw socket and returns its reply (the first frame back)."""
    sock.sendall(fr.encode_frame(msg_type, payload, rid))
    frames, closed = read_frames(sock, 5.0)
    assert frames, "no reply to 0x%x (closed=%s)" % (msg_type, closed)
    f = frames[0]
    assert (f.type, f.request_id) == (msg_type, rid) and f.is_reply
    return f


def _error_code(fn) -> int:
    with pytest.raises(DeformdError) as ei:
        fn()
    return ei.value.code


# ------------------------------------------------------------------ client against a fake daemon
class FakeRing:
    """The writer half of PROTOCOL.md 6.1, in Python: a ring file the tests fill themselves."""

    def __init__(self, path: str, capacity: int, session_id: int, magic: bytes = m.SHM_MAGIC):
        self.capacity = capacity
        with open(path, "wb") as f:
            f.write(RING_HEADER.pack(magic, m.SHM_HEADER_BYTES, 0, capacity, session_id, 0, 0))
            f.truncate(m.SHM_HEADER_BYTES + capacity)
        self._file = open(path, "r+b")
        self.map = mmap.mmap(self._file.fileno(), 0)
        self.head = 0

    def set_valid_from(self, v: int) -> None:
        struct.pack_into("<Q", self.map, 32, v)

    def append(self, frame: bytes) -> int:
        """Writes one frame; returns its stream position."""
        n, p = len(frame), self.head
        if p % self.capacity + n > self.capacity:          # a frame never wraps
            p += self.capacity - p % self.capacity
        if p + n > self.capacity:
            self.set_valid_from(max(struct.unpack_from("<Q", self.map, 32)[0],
                                    p + n - self.capacity))
        off = m.SHM_HEADER_BYTES + p % self.capacity
        self.map[off:off + n] = frame
        self.head = p + n
        struct.pack_into("<Q", self.map, 40, self.head)
        return p

    def close(self) -> None:
        self.map.close()
        self._file.close()


def _disp_frame(sid, version, offset, count, nv=4, more=False) -> bytes:
    xyz = array("f", [0.25 * version + 0.01 * k for k in range(3 * count)])
    d = st.Disp(sid, version, version - 1, m.CHANGE_BRUSH, m.DISP_DENSE, nv, nv, offset, count,
                None, xyz)
    return fr.encode_frame(m.DISPLACEMENT, st.encode_disp(d), 0,
                           fr.FLAG_EVENT | (fr.FLAG_MORE if more else 0))


def _ref(sid, position, length) -> bytes:
    return fr.encode_frame(m.SHM_REF, m.encode_shm_ref(sid, position, length), 0, fr.FLAG_EVENT)


@pytest.fixture
def fake():
    """(client, daemon-side socket, ring file path) with nothing sent yet; the client's first
    request gets id 1."""
    a, b = socket.socketpair()
    tmp = tempfile.TemporaryDirectory(prefix="deformd-shm-")
    c = Client(a, timeout=5, hello=False)
    yield c, b, os.path.join(tmp.name, "ring")
    c.close()
    b.close()
    tmp.cleanup()


def _attach(c, b, path, sid=7, capacity=4096, magic=m.SHM_MAGIC):
    ring = FakeRing(path, capacity, sid, magic)
    info = m.ShmInfo(sid, capacity, 24, capacity, path)
    b.sendall(fr.encode_frame(m.STREAM_SHM, m.encode_shm_info(info), 1, fr.FLAG_REPLY))
    return ring, info


def test_shm_codecs_reject_malformed_bodies():
    info = m.ShmInfo(3, 1 << 20, 1024, 1 << 20, "/run/deformd.sock.shm-3")
    p = m.encode_shm_info(info)
    assert len(p) == 24 + 2 + len(info.path)
    assert m.decode_shm_info(p) == info
    for cut in (0, 7, 23, 24, 25, len(p) - 1):
        with pytest.raises(ProtocolError):
            m.decode_shm_info(p[:cut])
    with pytest.raises(ProtocolError):
        m.decode_shm_info(p + b"\0")
    for bad in (m.ShmInfo(0, 4096, 24, 4096, "/a"), m.ShmInfo(1, 4095, 24, 4095, "/a"),
                m.ShmInfo(1, 4096, 200, 100, "/a"), m.ShmInfo(1, 4096, 24, 4097, "/a"),
                m.ShmInfo(1, 4096, 24, 4096, ""), m.ShmInfo(1, 4096, 24, 4096, "rel/ring"),
                m.ShmInfo(1, 4096, 24, 4096, "/" + "x" * 4095)):
        with pytest.raises(ProtocolError):
            m.decode_shm_info(m.encode_shm_info(bad))
    r = m.encode_shm_ref(5, 1 << 40, 19268)
    assert len(r) == 24 and m.decode_shm_ref(r) == (5, 1 << 40, 19268)
    for bad in (r[:23], r + b"\0", r[:20] + b"\1\0\0\0", m.encode_shm_ref(0, 0, 24),
                m.encode_shm_ref(5, 0, 23)):
        with pytest.raises(ProtocolError):
            m.decode_shm_ref(bad)
    assert m.TYPE_NAMES[m.STREAM_SHM] == "stream_shm" and m.STREAM_SHM == 0x0016
    assert m.TYPE_NAMES[m.SHM_REF] == "shm_ref" and m.SHM_REF == 0x0083
    assert m.TYPE_NAMES[m.DISPLACEMENT] == "displacement" and m.FEAT_SHM_STREAM == 0x80


def test_client_resolves_refs_and_reports_lost_frames(fake):
    c, b, path = fake
    ring, info = _attach(c, b, path)
    assert c.stream_shm(7) == info
    assert c.shm_ring(7).info == info
    # version 1: two chunks through the ring, read at once
    f1a, f1b = _disp_frame(7, 1, 0, 2, more=True), _disp_frame(7, 1, 2, 2)
    b.sendall(b"".join(_ref(7, ring.append(f), len(f)) for f in (f1a, f1b)))
    evs = list(c.events(timeout=0.5))
    # version 2: its first chunk is overwritten before the client reads it, the second is not
    f2a, f2b = _disp_frame(7, 2, 0, 2, more=True), _disp_frame(7, 2, 2, 2)
    pa, pb = ring.append(f2a), ring.append(f2b)
    ring.set_valid_from(pa + 1)
    # version 3 on the socket, then the session closes
    b.sendall(_ref(7, pa, len(f2a)) + _ref(7, pb, len(f2b)) + _disp_frame(7, 3, 0, 4)
              + fr.encode_frame(m.SESSION_CLOSED, m.encode_session_ref(7), 0, fr.FLAG_EVENT))
    evs += list(c.events(timeout=0.5))
    assert [type(e).__name__ for e in evs] == ["Disp", "ShmLost", "Disp", "SessionClosed"]
    assert evs[0].version == 1 and evs[0].count == 4
    assert evs[0].xyz == st.decode_disp(f1a[24:]).xyz + st.decode_disp(f1b[24:]).xyz
    assert (evs[1].session_id, evs[1].position, evs[1].length) == (7, pa, len(f2a))
    assert evs[1].type == m.SHM_REF and evs[1].lost
    assert evs[2].version == 3 and evs[3] == SessionClosed(7)
    assert c.shm_ring(7) is None                      # SESSION_CLOSED drops the mapping
    replica = MeshState(array("f", bytes(48)))
    assert replica.apply(evs[0])
    assert replica.apply(evs[1]) is False and replica.version == 1
    with pytest.raises(OutOfSync):
        replica.apply(evs[2])
    # a reference for a session without a ring is a protocol error
    b.sendall(_ref(7, 0, len(f1a)))
    with pytest.raises(ProtocolError, match="no shared-memory stream"):
        c.next_event(0.5)
    ring.close()


def test_client_rejects_refs_outside_the_ring(fake):
    c, b, path = fake
    ring, info = _attach(c, b, path)
    c.stream_shm(7)
    f = _disp_frame(7, 1, 0, 4)
    p = ring.append(f)
    for bad in (_ref(7, 4096 - 10, len(f)),           # crosses the end of the lap
                _ref(7, ring.head, len(f)),           # not written yet (beyond head)
                _ref(7, p, len(f) - 4)):              # not one whole frame
        b.sendall(bad)
        with pytest.raises(ProtocolError):
            c.next_event(0.5)
    b.sendall(_ref(7, p, len(f)))
    assert c.next_event(0.5).version == 1
    assert c.shm_ring(7).frames == 1
    ring.close()


def test_client_unsubscribes_when_the_ring_cannot_be_mapped(fake):
    c, b, path = fake
    ring, _ = _attach(c, b, path, magic=b"NOTARING")
    b.sendall(fr.encode_frame(m.UNSUBSCRIBE, struct.pack("<QQ", 7, 0), 2, fr.FLAG_REPLY))
    with pytest.raises(ProtocolError, match="magic"):
        c.stream_shm(7)
    assert c.shm_ring(7) is None
    frames, _ = read_frames(b, 1.0, want=2)
    assert [(f.type, f.request_id) for f in frames] == [(m.STREAM_SHM, 1), (m.UNSUBSCRIBE, 2)]
    assert m.decode_session_ref(frames[1].payload) == 7
    ring.close()


# ------------------------------------------------------------------ against the daemon
def test_shm_subscriber_replica_matches_and_the_socket_carries_refs(daemon):
    """(a) A stroke of dense 19 KB versions mixed with empty 68-byte ones: the shm subscriber's
    replica equals get_mesh byte for byte with contiguous versions; a raw shm subscriber
    receives an SHM_REF (24-byte payload) in place of each dense DISPLACEMENT frame, which it
    resolves in the ring file itself, while the small frames (and SESSION_CLOSED) stay on its
    socket, all in version order. The ring is written once for both subscribers."""
    with daemon.unix_client() as w, daemon.unix_client() as r:
        assert w.server.features & m.FEAT_SHM_STREAM
        sid, X = _grid_session(w)
        v0 = w.get_mesh(sid).version
        r.subscribe(sid)
        info = r.stream_shm(sid)
        assert info.session_id == sid
        assert info.min_frame <= DENSE_FRAME <= info.max_frame, info
        raw = daemon.raw_unix(hello=True)
        assert not _raw_request(raw, m.SUBSCRIBE, m.encode_subscribe(sid), 1).is_error
        f = _raw_request(raw, m.STREAM_SHM, m.encode_session_ref(sid), 2)
        assert not f.is_error, m.decode_error(f.payload)
        assert m.decode_shm_info(f.payload) == info      # one ring per session
        s0 = w.stats()
        dense = _stroke(w, sid, X, UPDATES, mixed=True)
        n_dense, n = sum(dense), len(dense)
        assert (n_dense, n) == (UPDATES, UPDATES + UPDATES // REPEAT_EVERY)
        final = w.get_mesh(sid)
        assert final.version == v0 + n
        s1 = w.stats()

        replica = MeshState(X)
        versions = []
        for ev in r.events(timeout=5.0):
            assert isinstance(ev, st.Disp), ev
            assert replica.apply(ev), "version %d not applied" % ev.version
            assert (ev.encoding == m.DISP_DENSE) == dense[ev.version - v0 - 1]
            versions.append(ev.version)
            if ev.version == final.version:
                break
        assert versions == list(range(v0 + 1, final.version + 1))
        assert replica.tobytes() == final.positions.tobytes()
        ring = r.shm_ring(sid)
        assert (ring.frames, ring.lost) == (n_dense, 0)

        frames, closed = read_frames(raw, 2.0, want=n + 1)
        assert not closed
        assert [f.type for f in frames] == [m.SHM_REF if d else m.DISPLACEMENT for d in dense], \
            [(hex(f.type), len(f.payload)) for f in frames]
        refs = []
        for f in frames:
            assert (f.flags, f.request_id) == (fr.FLAG_EVENT, 0)
            if f.type == m.DISPLACEMENT:
                assert fr.HEADER_SIZE + len(f.payload) < info.min_frame
                continue
            assert len(f.payload) == 24
            ref_sid, pos, length = m.decode_shm_ref(f.payload)
            assert (ref_sid, length) == (sid, DENSE_FRAME)
            refs.append(pos)
        assert refs == sorted(refs) and len(set(refs)) == n_dense
        # resolve the references independently of the client library
        with open(info.path, "rb") as fh:
            ring_map = mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ)
        try:
            magic, hb, _, cap, ring_sid, valid_from, head = RING_HEADER.unpack_from(ring_map, 0)
            assert (magic, hb, cap, ring_sid) == (m.SHM_MAGIC, 4096, info.capacity, sid)
            assert valid_from <= refs[0] and head >= refs[-1] + DENSE_FRAME
            seen = []
            for f in frames:
                if f.type == m.SHM_REF:
                    off = hb + m.decode_shm_ref(f.payload)[1] % cap
                    got = fr.FrameDecoder().feed(ring_map[off:off + DENSE_FRAME])
                    assert len(got) == 1 and got[0].flags == fr.FLAG_EVENT
                    f = got[0]
                assert f.type == m.DISPLACEMENT
                seen.append(st.decode_disp(f.payload).version)
            assert seen == versions
        finally:
            ring_map.close()
        written = s1["shm_frames"] - s0["shm_frames"]
        assert n_dense <= written < 2 * n_dense, "ring frames written: %d" % written
        assert s1["shm_refs"] - s0["shm_refs"] >= 2 * n_dense

        w.close_session(sid)
        frames, _ = read_frames(raw, 5.0)
        assert [(f.type, f.flags, f.payload) for f in frames] == \
            [(m.SESSION_CLOSED, fr.FLAG_EVENT, m.encode_session_ref(sid))]
        assert r.next_event(5.0) == SessionClosed(sid)
        assert r.shm_ring(sid) is None
        raw.close()


def test_shm_info_follows_the_config_and_the_file_lives_with_the_session(daemon, make_daemon):
    """(b) capacity sized to the session (128 dense versions, rounded up to 64 KiB; PROTOCOL.md
    6.1), at most shm_ring_bytes (default 64m), frames of 1024 .. capacity / 2 bytes through
    the ring, an absolute 0600 file of the daemon's user with the documented header, one ring
    per session; attaching twice is a no-op; CLOSE_SESSION removes the file."""
    with daemon.unix_client() as c:
        sid, _ = _grid_session(c)
        c.subscribe(sid)
        assert c.stream_shm(sid).capacity == ring_size(GRID_N * GRID_N) < 64 << 20
        c.close_session(sid)
    d = make_daemon("shm_ring_bytes = 1m\n")
    with d.unix_client() as c:
        assert c.server.features & m.FEAT_SHM_STREAM
        sid, _ = _grid_session(c)
        c.subscribe(sid)
        info = c.stream_shm(sid)
        assert info.session_id == sid and info.capacity == 1 << 20
        assert (info.min_frame, info.max_frame) == (1024, info.capacity // 2)   # deformd's
        assert os.path.isabs(info.path) and os.path.exists(info.path)
        s = os.stat(info.path)
        assert stat.S_ISREG(s.st_mode) and stat.S_IMODE(s.st_mode) == 0o600, oct(s.st_mode)
        assert s.st_uid == os.getuid()
        assert s.st_size >= m.SHM_HEADER_BYTES + info.capacity
        with open(info.path, "rb") as fh:
            head = fh.read(RING_HEADER.size)
        assert RING_HEADER.unpack(head) == (m.SHM_MAGIC, 4096, 0, 1 << 20, sid, 0, 0)
        ring = c.shm_ring(sid)
        assert c.stream_shm(sid) == info and c.shm_ring(sid) is ring
        sid2, _ = _grid_session(c, "second")
        c.subscribe(sid2)
        assert c.stream_shm(sid2).path != info.path
        c.close_session(sid)
        assert not os.path.exists(info.path), "ring file left after CLOSE_SESSION"
        assert c.next_event(5.0) == SessionClosed(sid)
        assert c.ping(b"x") == b"x"


def test_stream_shm_errors_leave_the_daemon_serving(daemon, make_daemon):
    """(c) ESTATE before SUBSCRIBE, ENOTFOUND for an unknown session, EUNSUPPORTED on TCP and
    when shm_ring_bytes = 0 (hello then lacks SHM_STREAM), EPROTO_TRUNCATED / EPROTO_TRAILING
    for a malformed body; the connection and the daemon keep serving after each."""
    with daemon.unix_client() as c, daemon.tcp_client() as t:
        assert c.server.features & m.FEAT_SHM_STREAM
        sid, _ = _grid_session(c)
        assert _error_code(lambda: c.stream_shm(sid)) == E.ESTATE
        assert c.ping(b"1") == b"1"
        assert _error_code(lambda: c.stream_shm(sid + 100000)) == E.ENOTFOUND
        assert c.ping(b"2") == b"2"
        c.subscribe(sid)
        assert _error_code(lambda: c.stream_shm(sid + 100000)) == E.ENOTFOUND
        assert c.shm_ring(sid) is None and c.shm_ring(sid + 100000) is None
        t.subscribe(sid)
        assert _error_code(lambda: t.stream_shm(sid)) == E.EUNSUPPORTED
        assert t.ping(b"3") == b"3"
        raw = daemon.raw_unix(hello=True)
        for rid, body, code in ((5, m.encode_session_ref(sid)[:7], E.EPROTO_TRUNCATED),
                                (6, b"", E.EPROTO_TRUNCATED),
                                (7, m.encode_session_ref(sid) + b"\0", E.EPROTO_TRAILING)):
            f = _raw_request(raw, m.STREAM_SHM, body, rid)
            assert f.is_error and m.decode_error(f.payload)[0] == code, \
                (rid, m.decode_error(f.payload) if f.is_error else f.payload)
        assert _raw_request(raw, m.PING, b"raw", 8).payload == b"raw"
        raw.close()
        # the TCP subscriber still gets its socket stream
        c.stroke(sid, Brush(center=(0.5, 0.5, 0.0), move=(0, 0, 0.01), radius=5.0))
        ev = t.next_event(5.0)
        assert isinstance(ev, st.Disp) and ev.version == 1
        c.close_session(sid)
    off = make_daemon("shm_ring_bytes = 0\n")
    with off.unix_client() as c:
        assert not c.server.features & m.FEAT_SHM_STREAM
        sid, _ = _grid_session(c)
        c.subscribe(sid)
        assert _error_code(lambda: c.stream_shm(sid)) == E.EUNSUPPORTED
        assert c.ping(b"4") == b"4"
        assert c.stats()["clients_dropped"] == 0
    assert daemon.alive() and off.alive()


def test_slow_shm_reader_loses_frames_and_resyncs_without_being_dropped(make_daemon):
    """(d) A 64 KiB ring holds 3 dense 19 KB frames: a subscriber that reads nothing during 20
    versions finds the older ones overwritten (ShmLost events, MeshState.apply False, then
    OutOfSync), resyncs with a snapshot to the exact positions, stays connected and keeps
    receiving versions through the ring."""
    d = make_daemon("shm_ring_bytes = 64k\n")
    n = 20
    with d.unix_client() as w, d.unix_client() as r:
        sid, X = _grid_session(w)
        r.subscribe(sid)
        info = r.stream_shm(sid)
        assert info.capacity == 64 << 10 and info.min_frame <= DENSE_FRAME <= info.max_frame
        _stroke(w, sid, X, n)
        final = w.get_mesh(sid)
        assert final.version == n
        evs = []
        for ev in r.events(timeout=5.0):
            evs.append(ev)
            if isinstance(ev, st.Disp) and ev.version == final.version:
                break
        lost = [e for e in evs if isinstance(e, ShmLost)]
        got = [e.version for e in evs if isinstance(e, st.Disp)]
        assert lost, "no frame was lost from a 64 KiB ring"
        assert all(e.type == m.SHM_REF and e.lost and e.session_id == sid for e in lost)
        assert all(e.length == DENSE_FRAME for e in lost)
        assert len(lost) + len(got) == n, (len(lost), got)
        assert got and got == list(range(n - len(got) + 1, n + 1)), got  # the newest survive
        assert len(got) <= 4
        assert r.shm_ring(sid).lost == len(lost)
        replica = MeshState(X)
        assert replica.apply(lost[0]) is False and replica.version == 0
        with pytest.raises(OutOfSync):
            replica.apply(next(e for e in evs if isinstance(e, st.Disp)))
        assert replica.apply(r.snapshot(sid))
        assert replica.version == final.version
        assert replica.tobytes() == final.positions.tobytes()
        # not dropped: still connected, still subscribed, still reading through the ring
        assert r.ping(b"alive") == b"alive"
        assert w.stats()["clients_dropped"] == 0
        assert w.open_session(sid).subscribers == 1
        w.stroke(sid, Brush(center=X[0:3], move=(0, 0.01, 0), radius=5.0))
        ev = r.next_event(5.0)
        assert isinstance(ev, st.Disp) and ev.version == n + 1
        assert replica.apply(ev)
        assert replica.tobytes() == w.get_mesh(sid).positions.tobytes()
        assert r.shm_ring(sid).frames == len(got) + 1


def test_unsubscribe_ends_shm_refs(daemon):
    """(e) References queued before UNSUBSCRIBE's ack are still read; after it the mapping is
    gone, and a plain SUBSCRIBE again brings DISPLACEMENT frames on the socket."""
    with daemon.unix_client() as w, daemon.unix_client() as r:
        sid, X = _grid_session(w)
        r.subscribe(sid)
        r.stream_shm(sid)
        w.stroke(sid, Brush(center=X[0:3], move=(0, 0, 0.01), radius=5.0))
        f = r.recv_frame(timeout=5.0)
        assert f is not None and f.type == m.SHM_REF and len(f.payload) == 24
        inner = r.shm_frame(f)
        assert inner is not None and inner.type == m.DISPLACEMENT
        assert st.decode_disp(inner.payload).version == 1
        w.stroke(sid, Brush(center=X[0:3], move=(0, 0, 0.02), radius=5.0))   # unread
        r.unsubscribe(sid)
        assert r.shm_ring(sid) is None
        ev = r.next_event(0.5)
        assert isinstance(ev, st.Disp) and ev.version == 2   # read before the ack dropped the ring
        r.subscribe(sid)
        w.stroke(sid, Brush(center=X[0:3], move=(0, 0, 0.03), radius=5.0))
        f = r.recv_frame(timeout=5.0)
        assert f is not None and f.is_event
        assert (f.type, fr.HEADER_SIZE + len(f.payload)) == (m.DISPLACEMENT, DENSE_FRAME)
        assert st.decode_disp(f.payload).version == 3
        # the same on a raw socket: references, then UNSUBSCRIBE + SUBSCRIBE, then frames
        raw = daemon.raw_unix(hello=True)
        _raw_request(raw, m.SUBSCRIBE, m.encode_subscribe(sid), 1)
        assert not _raw_request(raw, m.STREAM_SHM, m.encode_session_ref(sid), 2).is_error
        w.stroke(sid, Brush(center=X[0:3], move=(0, 0, 0.04), radius=5.0))
        frames, _ = read_frames(raw, 5.0)
        assert [f.type for f in frames] == [m.SHM_REF]
        assert not _raw_request(raw, m.UNSUBSCRIBE, m.encode_session_ref(sid), 3).is_error
        assert not _raw_request(raw, m.SUBSCRIBE, m.encode_subscribe(sid), 4).is_error
        w.stroke(sid, Brush(center=X[0:3], move=(0, 0, 0.05), radius=5.0))
        frames, _ = read_frames(raw, 5.0)
        assert [(f.type, len(f.payload) + fr.HEADER_SIZE) for f in frames] == \
            [(m.DISPLACEMENT, DENSE_FRAME)]
        raw.close()
        w.close_session(sid)


def test_progress_iterates_come_through_the_ring(daemon):
    """PROGRESS chunks of a handle move (2.7 KB when dense on a 216-vertex tet grid) go through
    the ring like displacements, small ones stay on the socket: a replica fed by the shm
    subscriber's events ends at the move's positions."""
    pts, _ = tet_grid(6)
    X = array("f", [x for p in pts for x in p])
    with daemon.unix_client() as w, daemon.unix_client() as r:
        sid = w.load_mesh(tet_grid_medit(6), fmt=".mesh", name="shm-handles").session_id
        r.subscribe(sid)
        info = r.stream_shm(sid)
        frame = fr.HEADER_SIZE + 32 + st.DISP_STRUCT.size + 12 * len(pts)
        assert info.min_frame <= frame <= info.max_frame
        bottom = [i for i, p in enumerate(pts) if p[2] == 0.0]
        top = [i for i, p in enumerate(pts) if p[2] == 1.0]
        w.set_handles(sid, bottom + top, energy="arap", tol=0.0, max_iters=40)
        targets = [pts[i] for i in bottom] + [(pts[i][0] + 0.2, pts[i][1], pts[i][2] + 0.1)
                                              for i in top]
        res = w.move_handles(sid, targets, progress_every=10)
        mesh = w.get_mesh(sid, base=True)
        assert mesh.base == X
        replica = MeshState(mesh.base)
        progress = []
        for ev in r.events(timeout=5.0):
            assert isinstance(ev, (st.Progress, st.Disp)), ev
            assert replica.apply(ev)
            if isinstance(ev, st.Progress):
                progress.append(ev)
            if replica.version == res.version:
                break
        assert len(progress) >= 2 and progress[-1].final == 1
        assert replica.tobytes() == mesh.positions.tobytes()
        sizes = [fr.HEADER_SIZE + 32 + st.DISP_STRUCT.size
                 + (12 if p.disp.encoding == m.DISP_DENSE else 16) * p.disp.count
                 for p in progress]
        in_ring = sum(info.min_frame <= n <= info.max_frame for n in sizes)
        assert in_ring >= 2, sizes
        assert r.shm_ring(sid).frames == in_ring, sizes
        w.close_session(sid)
