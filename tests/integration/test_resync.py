"""Resync from a held version (issue 12; PROTOCOL.md 6.2): SUBSCRIBE with flag FROM_VERSION and
the version a client holds answers session_info and then, before any live frame, either the
frames of the versions it missed exactly as they were broadcast (compared byte for byte with what
a subscriber that never left recorded) or, when the daemon no longer keeps them (a ring too small
for them, a restart) or the version is ahead of the session, one dense snapshot of the current
version. The client that applies them ends byte-identical to a fresh GET_MESH / snapshot replica,
and the live stream continues in order. The old 12-byte SUBSCRIBE body works as before; bad
bodies are refused and change nothing. deformctl watch --from-version prints the same versions.

Nothing waits on time: every frame awaited is named by its version, and "nothing was sent"
is checked with a PING whose reply comes after anything queued before it on that connection."""
import json
import struct
import subprocess

import pytest

from conftest import DEFORMCTL
from deformd_client import Brush, DeformdError, MeshState
from deformd_client import errors as E
from deformd_client import messages as m
from deformd_client import stream as st
from helpers import grid_obj

TIMEOUT = 30.0


def disp_of(f):
    """The Disp (chunk) a stream frame carries, or None for another frame."""
    if f.type == m.DISPLACEMENT:
        return st.decode_disp(f.payload)
    if f.type == m.PROGRESS:
        return st.decode_progress(f.payload).disp
    return None


def read_until(c, version):
    """Raw frames of client `c` up to and including the last chunk of `version`."""
    out = []
    while True:
        f = c.recv_frame(TIMEOUT)
        assert f is not None, "no frame of version %d within %.0f s" % (version, TIMEOUT)
        out.append(f)
        d = disp_of(f)
        if d is not None and d.version == version and not f.more:
            return out


def versions(frames):
    """[(version, [frames of it])] in arrival order; a version's chunks stay together."""
    out = []
    for f in frames:
        d = disp_of(f)
        assert d is not None, "unexpected frame type 0x%x" % f.type
        if not out or out[-1][0] != d.version:
            out.append((d.version, []))
        out[-1][1].append(f)
    return out


def apply_frames(state, frames):
    """Applies whole versions (chunks joined) to a MeshState."""
    for _, fs in versions(frames):
        assert state.apply(st.join_disp([disp_of(f) for f in fs]))


def subscribe_from(c, sid, v):
    """Sends SUBSCRIBE FROM_VERSION v; returns (request id, session_info of the reply). No
    event can come before the reply on a connection that was not subscribed."""
    rid = c.send(m.SUBSCRIBE, m.encode_subscribe(sid, m.SUBSCRIBE_FROM_VERSION, v))
    f = c.recv_frame(TIMEOUT)
    assert f is not None and f.request_id == rid and f.is_reply, f
    if f.is_error:
        code, msg = m.decode_error(f.payload)
        raise DeformdError(code, E.error_name(code), msg)
    return rid, m.decode_session_info(f.payload)


def nothing_queued(c):
    """Asserts that nothing was queued to `c` before a PING's reply (same connection: in order)."""
    rid = c.send(m.PING, b"barrier")
    f = c.recv_frame(TIMEOUT)
    assert f is not None and f.type == m.PING and f.request_id == rid, \
        "frame 0x%x (id %d) queued before the barrier" % (f.type, f.request_id)


def fresh(c, sid):
    """The session as a client that just arrived sees it: base + snapshot, and GET_MESH."""
    s = MeshState.sync(c, sid)
    mesh = c.get_mesh(sid)
    assert s.version == mesh.version
    assert s.tobytes() == mesh.positions.tobytes()
    return s


def edits(c, sid, X):
    """Strokes, an undo, a cancelled stroke, a handle move with progress iterates, a reset of
    the rest shape: every kind of version. X: the session's load-time positions."""
    c.stroke(sid, Brush(type="grab", center=X[0:3], move=(0.02, 0, 0.1), radius=0.3))
    c.stroke(sid, Brush(type="twist", center=X[30:33], twist=(0, 0, 0.4), radius=0.25))
    c.undo(sid)
    c.brush_begin(sid, Brush(type="grab", center=X[60:63], move=(0, 0.05, 0), radius=0.2))
    c.brush_update(sid, move=(0, 0.08, 0.01))
    c.brush_cancel(sid)
    c.stroke(sid, Brush(type="grab", center=X[90:93], move=(0.01, 0.02, 0.03), radius=0.4))
    c.set_handles(sid, [0, 5, 11], max_iters=8)
    c.move_handles(sid, [X[0:3], X[15:18], (X[33], X[34] + 0.05, X[35])], max_iters=8,
                   progress_every=3)
    c.reset_rest(sid)
    c.stroke(sid, Brush(type="scale", center=X[12:15], scale=0.1, radius=0.3, nu=0.3))


def test_resync_replays_exactly_the_missed_versions_then_live(make_daemon):
    d = make_daemon()
    with d.unix_client() as rec:                       # the recorder never leaves
        with d.unix_client() as b, d.unix_client() as a:
            data = grid_obj(12, 12)
            sid = b.load_mesh(data, fmt=".obj", name="resync").session_id
            X = b.get_mesh(sid).positions
            rec.subscribe(sid)
            held = MeshState(a.get_mesh(sid, base=True).base, 0)
            a.subscribe(sid)
            b.stroke(sid, Brush(type="grab", center=X[3:6], move=(0, 0, 0.05), radius=0.3))
            b.stroke(sid, Brush(type="grab", center=X[6:9], move=(0.03, 0, 0), radius=0.3))
            v = int(b.stats(sid)["version"])
            apply_frames(held, read_until(a, v))
            assert held.version == v
        # A is gone; B edits on; the recorder keeps every frame as broadcast
        with d.unix_client() as b:
            resync_after_edits(d, b, rec, sid, X, held, v)


def resync_after_edits(d, b, rec, sid, X, held, v):
    edits(b, sid, X)
    cur = int(b.stats(sid)["version"])
    assert cur > v + 8
    recorded = versions(read_until(rec, cur))
    recorded = [(ver, fs) for ver, fs in recorded if ver > v]
    assert [ver for ver, _ in recorded] == list(range(v + 1, cur + 1))
    kinds = {disp_of(fs[0]).kind for _, fs in recorded}
    assert {m.CHANGE_BRUSH, m.CHANGE_UNDO, m.CHANGE_BRUSH_CANCEL, m.CHANGE_HANDLE_MOVE,
            m.CHANGE_RESET_REST} <= kinds, kinds
    with d.unix_client() as a2:
        rid, info = subscribe_from(a2, sid, v)
        assert info.version == cur
        replay = read_until(a2, cur)
        # exactly versions v+1 .. cur, each byte for byte as broadcast (type, flags, id, body)
        got = versions(replay)
        assert [ver for ver, _ in got] == list(range(v + 1, cur + 1))
        for (ver, fs), (_, want) in zip(got, recorded):
            assert [(f.type, f.flags, f.request_id, bytes(f.payload)) for f in fs] == \
                   [(f.type, f.flags, f.request_id, bytes(f.payload)) for f in want], ver
        assert all(disp_of(f).kind != m.CHANGE_SNAPSHOT for f in replay)
        apply_frames(held, replay)
        assert held.version == cur
        assert held.tobytes() == fresh(b, sid).tobytes()
        # the live stream continues with cur + 1, in order, nothing in between
        b.stroke(sid, Brush(type="grab", center=X[9:12], move=(0, 0.01, 0.02), radius=0.3))
        live = read_until(a2, cur + 1)
        assert [ver for ver, _ in versions(live)] == [cur + 1]
        assert disp_of(live[0]).base_version == cur
        apply_frames(held, live)
        assert held.tobytes() == fresh(b, sid).tobytes()
        # from the current version: nothing before the live stream
        with d.unix_client() as a3:
            _, info3 = subscribe_from(a3, sid, cur + 1)
            assert info3.version == cur + 1
            nothing_queued(a3)
        s, g = b.stats(sid), b.stats()
        assert g["resync_replays"] == 2 and g["resync_snapshots"] == 0, g
        assert s["resync_versions"] == cur + 1 and s["resync_from"] == 0, s
        assert s["resync_ring_bytes"] > sum(len(f.payload) for _, fs in recorded for f in fs)
        assert g["resync_ring_bytes"] == g["memory.resync_bytes"] == s["resync_ring_bytes"]
        assert g["resync.limit_bytes"] == 32 << 20


def test_too_old_or_ahead_gets_a_snapshot(make_daemon):
    """A ring of 1 MiB holds few versions of a 22,500-vertex grid (every vertex moves: dense
    270 kB frames); versions before it, and versions ahead of the session, get one snapshot."""
    d = make_daemon("resync_ring_mb = 1\n")
    with d.unix_client() as b:
        sid = b.load_mesh(grid_obj(150, 150), fmt=".obj", name="big").session_id
        X = b.get_mesh(sid).positions
        held = MeshState(b.get_mesh(sid, base=True).base, 0)
        for k in range(8):
            b.stroke(sid, Brush(type="grab", center=X[300 * k:300 * k + 3],
                                move=(0, 0, 0.01 * (k + 1)), radius=0.5))
        s = b.stats(sid)
        cur, oldest = int(s["version"]), int(s["resync_from"])
        assert s["resync_ring_bytes"] <= 1 << 20 and 0 < s["resync_versions"] < cur, s
        assert oldest == cur - s["resync_versions"] and oldest > 0
        for v, why in ((0, "older than the ring"), (oldest - 1, "just before the ring"),
                       (cur + 5, "ahead of the session")):
            with d.unix_client() as a:
                rid, info = subscribe_from(a, sid, v)
                assert info.version == cur
                frames = read_until(a, cur)
                assert all(f.request_id == rid and f.type == m.DISPLACEMENT for f in frames), why
                snap = st.join_disp([disp_of(f) for f in frames])
                assert snap.kind == m.CHANGE_SNAPSHOT and snap.encoding == m.DISP_DENSE, why
                assert snap.base_version == 0 and snap.count == snap.nv, why
                state = MeshState(held.base, v)
                assert state.apply(snap)
                assert state.tobytes() == fresh(b, sid).tobytes(), why
                nothing_queued(a)
        # the oldest version the ring serves still replays
        with d.unix_client() as a:
            _, info = subscribe_from(a, sid, oldest)
            got = versions(read_until(a, cur))
            assert [ver for ver, _ in got] == list(range(oldest + 1, cur + 1))
        g = b.stats()
        assert g["resync_snapshots"] == 3 and g["resync_replays"] == 1, g
        assert g["memory.resync_bytes"] <= 1 << 20


def test_restart_loses_the_ring_not_the_version(tmp_path, make_daemon):
    """The ring is not persisted: after a restart (store on) a resync from before gets a
    snapshot, from exactly the restored version nothing."""
    store = str(tmp_path / "resync.db")
    d = make_daemon("store = %s\n" % store)
    with d.unix_client() as b:
        sid = b.load_mesh(grid_obj(10, 10), fmt=".obj", name="kept").session_id
        X = b.get_mesh(sid).positions
        base = b.get_mesh(sid, base=True).base
        for k in range(3):
            b.stroke(sid, Brush(type="grab", center=X[3 * k:3 * k + 3], move=(0, 0, 0.02),
                                radius=0.3))
        cur = int(b.stats(sid)["version"])
    d.stop()
    d2 = make_daemon("store = %s\n" % store)
    with d2.unix_client() as b, d2.unix_client() as a, d2.unix_client() as a2:
        assert b.stats(sid)["version"] == cur and b.stats(sid)["resync_versions"] == 0
        # the client API: subscribe(from_version=), then whole events for MeshState.apply
        info = a.subscribe(sid, from_version=cur - 2)
        assert info.version == cur
        ev = a.next_event(TIMEOUT)
        assert ev.kind == m.CHANGE_SNAPSHOT and ev.version == cur and ev.count == ev.nv
        state = MeshState(base, cur - 2)
        assert state.apply(ev)
        assert state.tobytes() == fresh(b, sid).tobytes()
        assert a2.subscribe(sid, from_version=cur).version == cur
        nothing_queued(a2)
        b.stroke(sid, Brush(type="grab", center=X[0:3], move=(0, 0.02, 0), radius=0.3))
        assert [ver for ver, _ in versions(read_until(a2, cur + 1))] == [cur + 1]


def test_old_subscribe_body_and_bad_bodies(make_daemon):
    d = make_daemon()
    with d.unix_client() as b, d.unix_client() as a:
        sid = b.load_mesh(grid_obj(6, 6), fmt=".obj", name="old").session_id
        X = b.get_mesh(sid).positions
        b.stroke(sid, Brush(type="grab", center=X[0:3], move=(0, 0, 0.05), radius=0.3))
        bad = [(struct.pack("<QIQ", sid, m.SUBSCRIBE_SNAPSHOT | m.SUBSCRIBE_FROM_VERSION, 0),
                E.EINVAL, "exclusive"),
               (struct.pack("<QI", sid, m.SUBSCRIBE_FROM_VERSION), E.EPROTO_TRUNCATED,
                "from_version"),
               (struct.pack("<QIQ", sid, 0, 1), E.EPROTO_TRAILING, ""),
               (struct.pack("<QI", sid, 4), E.EINVAL, "flag")]
        for body, code, needle in bad:
            with pytest.raises(DeformdError) as ei:
                a.request(m.SUBSCRIBE, body)
            assert ei.value.code == code and needle in ei.value.message, ei.value
        assert b.stats(sid)["subscribers"] == 0          # nothing changed
        # the 12-byte body of before: session_info, then the snapshot when asked
        rid = a.send(m.SUBSCRIBE, struct.pack("<QI", sid, m.SUBSCRIBE_SNAPSHOT))
        info = m.decode_session_info(a.wait_reply(rid)[0].payload)
        snap = read_until(a, info.version)
        assert {(f.request_id, disp_of(f).kind) for f in snap} == {(rid, m.CHANGE_SNAPSHOT)}
        with d.unix_client() as a2:
            rid2 = a2.send(m.SUBSCRIBE, struct.pack("<QI", sid, 0))
            assert m.decode_session_info(a2.wait_reply(rid2)[0].payload).version == info.version
            nothing_queued(a2)
            assert b.stats(sid)["subscribers"] == 2


def test_deformctl_watch_from_version(make_daemon):
    d = make_daemon()
    with d.unix_client() as b:
        sid = b.load_mesh(grid_obj(8, 8), fmt=".obj", name="watched").session_id
        X = b.get_mesh(sid).positions
        for k in range(5):
            b.stroke(sid, Brush(type="grab", center=X[3 * k:3 * k + 3], move=(0, 0, 0.02),
                                radius=0.3))
        b.undo(sid)
        cur = int(b.stats(sid)["version"])
    v = cur - 4
    out = subprocess.run([DEFORMCTL, "--socket", d.socket_path, "--json", "watch", str(sid),
                          "--from-version", str(v), "--count", "4"],
                         capture_output=True, text=True, timeout=TIMEOUT)
    assert out.returncode == 0, out.stderr
    lines = [json.loads(x) for x in out.stdout.splitlines()]
    assert lines[0]["kind"] == "watching" and lines[0]["from_version"] == v
    assert lines[0]["version"] == cur
    assert [x["version"] for x in lines[1:]] == list(range(v + 1, cur + 1))
    assert lines[-1]["kind"] == "undo"
    bad = subprocess.run([DEFORMCTL, "--socket", d.socket_path, "watch", str(sid),
                          "--from-version", "-1"], capture_output=True, text=True, timeout=TIMEOUT)
    assert bad.returncode != 0 and "--from-version" in bad.stderr


def test_undo_history_comes_before_the_ring_under_memory_pressure(make_daemon):
    """With a small memory budget the undo history keeps as many steps as it would with no ring
    at all (resync_ring_mb = 0, computed by a second daemon); the ring gets what is left."""
    depth, strokes = {}, None
    for ring in (32, 0):
        # history_replay_ms = 0: a checkpoint link per stroke, so the history fills the budget
        d = make_daemon("memory_max_mb = 16\nresync_ring_mb = %d\nhistory_replay_ms = 0\n"
                        % ring)
        with d.unix_client() as b:
            sid = b.load_mesh(grid_obj(150, 150), fmt=".obj", name="tight").session_id
            X = b.get_mesh(sid).positions
            # strokes until the budget drops a step (the first daemon), the same count after
            k = 0
            while k < (strokes or 200):
                c = 3 * ((900 * k + 37 * (k // 25)) % (150 * 150))
                b.stroke(sid, Brush(type="grab", center=X[c:c + 3], move=(0, 0, 0.01),
                                    radius=0.5))
                k += 1
                if strokes is None and b.stats(sid)["history_steps_dropped"] > 0:
                    break
            strokes = k
            s, g = b.stats(sid), b.stats()
            depth[ring] = (s["undo_depth"], s["history_steps_dropped"])
            assert s["history_steps_dropped"] > 0, s        # the budget binds the history
            assert g["memory_used_bytes"] <= g["memory_max_bytes"], g
            if ring:  # what the history left (nothing once it fills the budget)
                assert s["resync_ring_bytes"] == g["memory.resync_bytes"], (s, g)
            else:
                assert s["resync_ring_bytes"] == 0 and s["resync_versions"] == 0, s
    assert depth[32] == depth[0], depth
