"""The durable store (server/store/): sessions survive kill -9 with their ids, names, versions,
positions (bit for bit, as the clients last saw them acknowledged), rest shape, brush and handle
set; a store write error (the store full: store_max_mb) fails the request and loses nothing
acknowledged; a store file that is not a deformd store refuses start-up, naming it, untouched.

Each daemon here runs in a tmp dir of its own; the store file lives beside them and outlives
each daemon. Restarts wait on the daemon's readiness (conftest.Daemon), never on time."""
import os
import sqlite3
import subprocess

import pytest

from conftest import DEFORMD, MESHES, Daemon, check_stopped
from deformd_client import Brush, DeformdError
from deformd_client import errors as E
from helpers import downgrade_store, grid_obj


def start(tmp_path, store, run, extra=""):
    d = tmp_path / ("run%d" % run)
    d.mkdir()
    return Daemon(str(d), "store = %s\n%s" % (store, extra), tcp=False)


def kill9(d):
    d.proc.kill()           # SIGKILL: no shutdown code runs
    d.proc.wait()
    d._log.close()


def state(c, sid):
    """What a client can read of a session: positions and rest shape (float32 bytes), version."""
    m = c.get_mesh(sid, rest=True)
    return m.version, m.positions.tobytes(), m.rest.tobytes()


BUNNY_STROKES = 60  # each a bunny-wide version: 84 kB raw, ~4x less packed (codec.h)


def edit_two_sessions(d):
    """Two clients edit two sessions: strokes, a handle set and move, undo, redo, a brush
    change. Returns {sid: (name, version, positions, rest)} as of the last acknowledgement."""
    with d.unix_client() as a, d.unix_client() as b:
        s1 = a.load_file(os.path.join(MESHES, "bunny.off"), name="bunny").session_id
        s2 = b.load_mesh(data=grid_obj(12, 12), fmt=".obj", name="grid").session_id
        X1 = a.get_mesh(s1).positions
        X2 = b.get_mesh(s2).positions
        for k in range(BUNNY_STROKES):  # recipe records (journal.h), not deltas
            a.stroke(s1, Brush(type="grab", center=X1[3 * k:3 * k + 3], move=(0, 0, 0.01 * (k + 1)),
                               radius=0.05))
            if k < 3:
                b.stroke(s2, Brush(type="grab", center=X2[3 * k:3 * k + 3], move=(0.02, 0, 0.1),
                                   radius=0.3))
        b.set_handles(s1, [0, 10, 20], max_iters=20)
        b.move_handles(s1, [X1[0:3], X1[30:33], (X1[60], X1[61] + 0.01, X1[62])], max_iters=20)
        a.undo(s1)
        a.redo(s1)
        a.undo(s2)
        b.brush_state_set(s2, radius=0.375)
        a.reset_rest(s2)
        b.stroke(s2, Brush(type="grab", center=X2[0:3], move=(0, 0.05, 0), radius=0.2))
        b.stroke(s2, Brush(type="grab", center=X2[3:6], move=(0, 0.05, 0), radius=0.2))
        a.undo(s2)                          # what one more undo shows (then redone)
        out = {"undo_pos": a.get_mesh(s2).positions.tobytes()}
        a.redo(s2)
        for info in a.list_sessions():
            out[info.session_id] = (info.name,) + state(a, info.session_id)
            out["depth", info.session_id] = (info.undo_depth, info.redo_depth)
        out["handles"] = b.get_handles(s1).handles
        return out, s1, s2


def test_kill9_restart_restores_every_session(tmp_path):
    store = str(tmp_path / "deformd.db")
    d = start(tmp_path, store, 1)
    before, s1, s2 = edit_two_sessions(d)
    kill9(d)
    d = start(tmp_path, store, 2)
    try:
        log = d.log()
        assert "2 session(s) restored" in log
        # the bunny's strokes are logged as recipes (journal.h): each one recomputed at the
        # restart and verified against its checksum (replay.h), every row of its log replayed
        assert "session %d 'bunny' restored at version %d (" % (s1, before[s1][1]) in log
        line = log.split("session %d 'bunny' restored" % s1)[1].split("\n")[0]
        replayed = int(line.split("(")[1].split()[0])
        recipes = int(line.split("; ")[1].split()[0])
        assert recipes == BUNNY_STROKES and replayed > BUNNY_STROKES, line
        with d.unix_client() as c:
            infos = {i.session_id: i for i in c.list_sessions()}
            assert sorted(infos) == sorted([s1, s2])
            for sid in (s1, s2):
                name, version, pos, rest = before[sid]
                assert infos[sid].name == name
                assert infos[sid].version == version
                assert state(c, sid) == (version, pos, rest), "session %d differs" % sid
            assert c.get_handles(s1).handles == before["handles"]
            # the undo history is rebuilt from the log (since the last snapshot: the grid has
            # none, the bunny's log was folded into one)
            assert (infos[s2].undo_depth, infos[s2].redo_depth) == before["depth", s2]
            assert infos[s1].undo_depth <= before["depth", s1][0]
            c.undo(s2)
            assert c.get_mesh(s2).positions.tobytes() == before["undo_pos"]
            c.redo(s2)
            assert state(c, s2)[1:] == before[s2][2:]
            assert c.brush_state_get(s2).radius == 0.375
            # edits continue from the restored state; new sessions get new ids
            X = c.get_mesh(s2).positions
            ack = c.stroke(s2, Brush(type="grab", center=X[0:3], move=(0, 0, 0.1), radius=0.3))
            assert ack.version == before[s2][1] + 3      # after the undo and redo above
            s3 = c.load_mesh(data=grid_obj(3, 3), fmt=".obj").session_id
            assert s3 > max(s1, s2)
            c.close_session(s1)
    finally:
        check_stopped(d, d.stop())
    d = start(tmp_path, store, 3)            # a clean stop, then the close, are kept too
    try:
        with d.unix_client() as c:
            assert sorted(i.session_id for i in c.list_sessions()) == sorted([s2, s3])
    finally:
        check_stopped(d, d.stop())


def test_a_full_store_fails_the_edit_and_loses_nothing_acknowledged(tmp_path):
    """store_max_mb = 1: a bunny (3485 vertices, 170 kB of mesh) fits, a stroke too (two recipe
    records: journal.h), the undo of one (a delta of 84 kB raw, about a third of that packed:
    codec.h) soon does not. The edit that does not fit is refused with the store's message,
    not applied, not broadcast; after kill -9 the last acknowledged state is back."""
    store = str(tmp_path / "small.db")
    d = start(tmp_path, store, 1, "store_max_mb = 1\n")
    bunny = os.path.join(MESHES, "bunny.off")
    with d.unix_client() as c:
        sid = c.load_file(bunny, name="b").session_id
        X = c.get_mesh(sid).positions
        nv = len(X) // 3
        c.set_handles(sid, [0, 10, 20], max_iters=20)   # while there is room
        s0 = c.stats()
        c.stroke(sid, Brush(type="grab", center=X[0:3], move=(0, 0, 0.001), radius=0.05))
        s1 = c.stats()
        rows = s1["store_changes"] - s0["store_changes"]
        size = s1["store_log_bytes"] - s0["store_log_bytes"]
        assert rows == 2                       # begin's version; end's undo step (no delta)
        assert s1["store_recipe_records"] - s0["store_recipe_records"] == 2
        # both rows are recipe records (record.h: a 32-byte header and the stroke's request,
        # a version 3 recipe blob: 280 bytes)
        assert size == 2 * (32 + 280), size
        print("store: a Kelvinlet stroke on %d vertices logs %d bytes (%.2f per vertex)"
              % (nv, size, size / nv))
        acked = state(c, sid)
        err = None
        for k in range(100):    # begin (a version), end (an undo step) and the undo (a packed
            try:                # delta: codec.h) may each fail
                c.brush_begin(sid, Brush(type="grab", center=X[0:3],
                                         move=(0, 0, 0.001 * (k + 1)), radius=0.05))
                acked = state(c, sid)
                c.brush_end(sid)
                c.undo(sid)
                acked = state(c, sid)
            except DeformdError as e:
                err = e
                break
        assert err is not None, "100 strokes and undos fit in 1 MiB"
        assert err.code == E.ELIMIT and "full" in str(err) and store in str(err), err
        assert state(c, sid) == acked          # nothing of the refused edit applied
        # a handle move: its first iterate does not fit either; the move fails, nothing moves
        with pytest.raises(DeformdError) as ei:
            c.move_handles(sid, [X[0:3], X[30:33], (X[60], X[61] + 0.01, X[62])], max_iters=5,
                           progress_every=1)
        assert ei.value.code == E.ELIMIT and store in str(ei.value), ei.value
        assert state(c, sid) == acked
        assert c.stats()["store_errors"] >= 2
    kill9(d)
    d = start(tmp_path, store, 2)
    try:
        with d.unix_client() as c:
            assert state(c, sid) == acked
    finally:
        check_stopped(d, d.stop())


def test_crash_loop_loses_no_acknowledged_edit(tmp_path):
    """5 kill -9s at deterministic points: right after an ack, and with an edit sent but not yet
    answered (it may or may not have become durable: both are fine, an acked one must be)."""
    store = str(tmp_path / "loop.db")
    lost = 0
    restart_ms = []
    d = start(tmp_path, store, 0)
    with d.unix_client() as c:
        sid = c.load_mesh(data=grid_obj(10, 10), fmt=".obj", name="loop").session_id
        X = c.get_mesh(sid).positions
        acked = state(c, sid)
    for run in range(1, 6):
        with d.unix_client() as c:
            for k in range(run):
                c.stroke(sid, Brush(type="grab", center=X[3 * k:3 * k + 3],
                                    move=(0, 0.01 * run, 0.02), radius=0.4))
            if run % 2:
                c.undo(sid)
            acked = state(c, sid)
            in_flight = run >= 3
            if in_flight:   # a stroke begin sent, its answer not awaited
                c.send(*_brush_begin(sid, X, run))
            kill9(d)
        d = start(tmp_path, store, run, "durability = %s\n" % ("normal" if run % 2 else "full"))
        restart_ms.append(float(d.log().split("restored in ")[1].split()[0]))
        with d.unix_client() as c:
            now = state(c, sid)
            if now[0] < acked[0] or (now[0] == acked[0] and now != acked):
                lost += 1
            elif now[0] > acked[0]:
                assert in_flight and now[0] == acked[0] + 1
            acked = now
    check_stopped(d, d.stop())
    print("crash loop: 5 kill -9, acked edits lost: %d, store restore %.1f ms at most"
          % (lost, max(restart_ms)))
    assert lost == 0


def _brush_begin(sid, X, run):
    from deformd_client import messages as m
    return m.BRUSH_BEGIN, m.encode_brush(sid, Brush(type="grab", center=X[0:3],
                                                    move=(0.01 * run, 0, 0), radius=0.4))


@pytest.mark.parametrize("kind", ["empty", "text", "foreign"])
def test_a_file_that_is_not_a_store_refuses_start(tmp_path, kind):
    path = str(tmp_path / ("%s.db" % kind))
    if kind == "empty":
        open(path, "wb").close()
    elif kind == "text":
        with open(path, "w") as f:
            f.write("socket = /tmp/x\n" * 300)
    else:
        db = sqlite3.connect(path)
        db.execute("CREATE TABLE photos(id INTEGER PRIMARY KEY, title TEXT)")
        db.execute("INSERT INTO photos(title) VALUES('cat')")
        db.commit()
        db.close()
    with open(path, "rb") as f:
        before = f.read()
    sock = str(tmp_path / "d.sock")
    r = subprocess.run([DEFORMD, "--foreground", "--socket", sock, "--store", path],
                       stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=30)
    assert r.returncode == 1, r.stderr
    assert path in r.stderr and "not a deformd store" in r.stderr, r.stderr
    assert not os.path.exists(sock)
    with open(path, "rb") as f:
        assert f.read() == before


def test_a_store_in_use_refuses_a_second_daemon(tmp_path):
    store = str(tmp_path / "shared.db")
    d = start(tmp_path, store, 1)
    try:
        sock = str(tmp_path / "d2.sock")
        r = subprocess.run([DEFORMD, "--foreground", "--socket", sock, "--store", store],
                           stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=30)
        assert r.returncode == 1 and "in use" in r.stderr and store in r.stderr, r.stderr
    finally:
        check_stopped(d, d.stop())


def test_a_stroke_open_at_the_kill_ends_at_restart_as_one_undo_step(tmp_path):
    store = str(tmp_path / "open.db")
    d = start(tmp_path, store, 1)
    with d.unix_client() as c:
        sid = c.load_mesh(data=grid_obj(8, 8), fmt=".obj", name="open").session_id
        X = c.get_mesh(sid).positions
        c.stroke(sid, Brush(type="grab", center=X[0:3], move=(0, 0, 0.1), radius=0.5))
        before_stroke = state(c, sid)
        depth = c.list_sessions()[0].undo_depth
        c.brush_begin(sid, Brush(type="grab", center=X[6:9], move=(0.1, 0, 0), radius=0.5))
        c.brush_update(sid, move=(0.2, 0, 0))
        in_stroke = state(c, sid)            # acknowledged, the stroke still open
    kill9(d)
    for run in (2, 3):                       # the same history after a second restart
        d = start(tmp_path, store, run)
        try:
            with d.unix_client() as c:
                assert state(c, sid) == in_stroke
                assert c.list_sessions()[0].undo_depth == depth + 1
        finally:
            check_stopped(d, d.stop())
    d = start(tmp_path, store, 4)
    try:
        with d.unix_client() as c:
            c.undo(sid)                      # back to before the stroke
            assert state(c, sid)[1:] == before_stroke[1:]
    finally:
        check_stopped(d, d.stop())


def test_a_stroke_ended_by_a_disconnect_is_its_own_undo_step_after_restart(tmp_path):
    """A client that disconnects mid-stroke has the stroke ended as an undo step (as BRUSH_END);
    that step is journaled, so after kill -9 the history keeps it apart from the next stroke:
    two undos give back, bit for bit, the state between the strokes and the one before both."""
    store = str(tmp_path / "gone.db")
    d = start(tmp_path, store, 1)
    with d.unix_client() as c:
        sid = c.load_mesh(data=grid_obj(8, 8), fmt=".obj", name="gone").session_id
        X = c.get_mesh(sid).positions
        before = state(c, sid)
        with d.unix_client() as gone:
            gone.brush_begin(sid, Brush(type="grab", center=X[0:3], move=(0, 0, 0.1),
                                        radius=0.5))
            gone.brush_update(sid, move=(0, 0, 0.15))
        c.get_mesh(sid)                      # a session job: the disconnect's end has run
        between = state(c, sid)
        assert between[1] != before[1]
        c.stroke(sid, Brush(type="grab", center=X[9:12], move=(0.1, 0, 0), radius=0.5))
        after = state(c, sid)
        live_depth = c.list_sessions()[0].undo_depth
    kill9(d)
    d = start(tmp_path, store, 2)
    try:
        with d.unix_client() as c:
            assert state(c, sid) == after
            assert c.list_sessions()[0].undo_depth == live_depth == 2
            c.undo(sid)
            assert state(c, sid)[1:] == between[1:]
            c.undo(sid)
            assert state(c, sid)[1:] == before[1:]
    finally:
        check_stopped(d, d.stop())


def _packed_rows(store):
    """The change rows whose delta has the packed layout (codec.h: u32 0xFFFFFFFF, i32 nv,
    u32 count, a zstd frame), as (row id, blob)."""
    db = sqlite3.connect(store)
    try:
        rows = db.execute("SELECT id, delta FROM changes WHERE delta IS NOT NULL").fetchall()
    finally:
        db.close()
    return [(i, bytes(b)) for i, b in rows if bytes(b[:4]) == b"\xff\xff\xff\xff"]


def test_undo_redo_are_logged_packed_and_a_corrupt_packed_delta_refuses_start(tmp_path):
    store = str(tmp_path / "packed.db")
    d = start(tmp_path, store, 1)
    try:
        with d.unix_client() as c:
            sid = c.load_mesh(data=grid_obj(40, 40), fmt=".obj", name="packed").session_id
            X = c.get_mesh(sid).positions
            for k in range(3):  # a stroke is a recipe record; its undo and redo are deltas
                c.stroke(sid, Brush(type="grab", center=X[123 * k:123 * k + 3],
                                    move=(0, 0, 0.02), radius=0.1))
                c.undo(sid)
                c.redo(sid)
            acked = state(c, sid)
    finally:
        check_stopped(d, d.stop())
    packed = _packed_rows(store)
    assert len(packed) == 6, "undo and redo of 3 strokes: %d packed rows" % len(packed)
    for _, blob in packed:              # smaller than the raw layout of the same change
        nv = int.from_bytes(blob[4:8], "little", signed=True)
        count = int.from_bytes(blob[8:12], "little")
        assert nv == 1600 and 1 <= count <= nv
        raw = 8 + (0 if count == nv else 4 * count) + 24 * count
        assert len(blob) < raw, (len(blob), raw)
    d = start(tmp_path, store, 2)       # restored bit for bit from the packed log
    try:
        with d.unix_client() as c:
            assert state(c, sid) == acked
    finally:
        check_stopped(d, d.stop())
    row, blob = packed[-1]
    bad = bytearray(blob)
    bad[len(bad) // 2 + 6] ^= 0xFF      # inside the zstd frame
    db = sqlite3.connect(store)
    db.execute("UPDATE changes SET delta = ? WHERE id = ?", (bytes(bad), row))
    db.commit()
    db.close()
    sock = str(tmp_path / "d.sock")
    r = subprocess.run([DEFORMD, "--foreground", "--socket", sock, "--store", store],
                       stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=30)
    assert r.returncode == 1, r.stderr
    assert store in r.stderr and "compressed change delta is corrupt" in r.stderr, r.stderr
    assert not os.path.exists(sock)


def test_a_version_1_store_is_migrated_and_a_newer_one_refused(tmp_path):
    """A store of schema version 1 (no recipe records) opens: migrated to 3 at start, every
    session restored as it was, then strokes are logged as recipes. A store of a version this
    deformd does not know (a newer one) refuses start-up with a message naming it, untouched."""
    store = str(tmp_path / "old.db")
    d = start(tmp_path, store, 1)
    with d.unix_client() as c:
        sid = c.load_mesh(data=grid_obj(10, 10), fmt=".obj", name="old").session_id
        X = c.get_mesh(sid).positions
        c.set_handles(sid, [0, 5, 55], max_iters=10)     # deltas only: no stroke
        c.move_handles(sid, [X[0:3], X[15:18], (X[165], X[166] + 0.05, X[167])], max_iters=10)
        c.undo(sid)
        c.redo(sid)
        before = state(c, sid)
    check_stopped(d, d.stop())
    downgrade_store(store, 1)
    d = start(tmp_path, store, 2)
    try:
        assert "schema 1 migrated to 3" in d.log()
        with d.unix_client() as c:
            assert state(c, sid) == before
            assert list(c.get_handles(sid).handles) == [0, 5, 55]
            c.stroke(sid, Brush(type="grab", center=X[30:33], move=(0, 0, 0.05), radius=0.3))
            after = state(c, sid)
            assert c.stats()["store_recipe_records"] == 2     # the begin's version and the end
    finally:
        check_stopped(d, d.stop())
    db = sqlite3.connect(store)
    assert db.execute("PRAGMA user_version").fetchone() == (3,)
    assert db.execute("SELECT count(*) FROM changes WHERE recipe IS NOT NULL").fetchone() == (2,)
    db.execute("PRAGMA user_version = 4")                    # as a newer deformd would write
    db.commit()
    db.close()
    with open(store, "rb") as f:
        newer = f.read()
    sock = str(tmp_path / "d.sock")
    r = subprocess.run([DEFORMD, "--foreground", "--socket", sock, "--store", store],
                       stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=30)
    assert r.returncode == 1, r.stderr
    assert store in r.stderr and "schema version 4" in r.stderr and "newer deformd" in r.stderr, \
        r.stderr
    assert not os.path.exists(sock)
    with open(store, "rb") as f:
        assert f.read() == newer
    db = sqlite3.connect(store)                              # back to 3: restored after all
    db.execute("PRAGMA user_version = 3")
    db.commit()
    db.close()
    d = start(tmp_path, store, 3)
    try:
        with d.unix_client() as c:
            assert state(c, sid) == after
    finally:
        check_stopped(d, d.stop())


def test_a_recipe_that_does_not_replay_stops_at_the_last_verified_version(tmp_path):
    """Strokes are journaled as recipe records with the checksum of the positions they made
    (server/store/journal.h). A record whose recomputation does not reproduce its checksum (here
    the checksum is damaged in the file) stops that session's restore at the last verified
    version: its positions come back as a new version, the error is logged and counted
    (STATS store_replay_mismatches), never a different mesh under the old version number."""
    store = str(tmp_path / "mismatch.db")
    d = start(tmp_path, store, 1)
    with d.unix_client() as c:
        sid = c.load_mesh(data=grid_obj(12, 12), fmt=".obj", name="m").session_id
        X = c.get_mesh(sid).positions
        c.stroke(sid, Brush(type="grab", center=X[0:3], move=(0, 0, 0.1), radius=0.3))
        verified = state(c, sid)
        c.stroke(sid, Brush(type="grab", center=X[60:63], move=(0.05, 0, 0), radius=0.3))
        last = state(c, sid)
    check_stopped(d, d.stop())
    db = sqlite3.connect(store)
    rows = db.execute("SELECT id, recipe FROM changes WHERE flags & 8 AND version = ?",
                      (last[0],)).fetchall()
    assert len(rows) == 1
    row, rec = rows[0][0], bytearray(rows[0][1])
    rec[16] ^= 1                        # record.h: the checksum is bytes 16..23
    db.execute("UPDATE changes SET recipe = ? WHERE id = ?", (bytes(rec), row))
    db.commit()
    db.close()
    d = start(tmp_path, store, 2)
    try:
        log = d.log()
        assert "does not replay to what was recorded" in log and "session %d" % sid in log, log
        with d.unix_client() as c:
            assert c.stats()["store_replay_mismatches"] == 1
            now = state(c, sid)
            assert now[0] == last[0] + 1 and now[1:] == verified[1:]
    finally:
        check_stopped(d, d.stop())
    d = start(tmp_path, store, 3)       # folded into a snapshot: the same, nothing to report
    try:
        with d.unix_client() as c:
            assert c.stats()["store_replay_mismatches"] == 0
            assert state(c, sid) == now
    finally:
        check_stopped(d, d.stop())
