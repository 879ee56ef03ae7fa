"""Long handle moves never lock anyone out (issue 9 items 7, 8, 18): four long moves leave a
compute worker for other clients' strokes and reads; while a move runs, reads of its session are
answered from the last published version, UNDO is refused at once, HANDLES_GET is answered (so a
newer move can supersede), a brush begin supersedes the move; a move ends when its requester
disconnects. Only generous receive timeouts, no timing assertions: without the fixes the replies
below never come and the waits time out."""
import time

import pytest

from deformd_client import Brush, DeformdError, MeshState, Progress, messages as m
from helpers import grid_obj, obj_bytes_positions, tet_grid, tet_grid_medit

LONG_ITERS = 1_000_000
REPLY_S = 30.0         # generous upper bound on a reply that must come
END_S = 60.0           # generous upper bound on a superseded move's final iterate


def long_move_session(c, n=8):
    """A tet cube whose handles (bottom and top faces) are set for a move that never converges
    (tol 0, a million iterations); returns (session id, targets)."""
    pts, _ = tet_grid(n)
    sid = c.load_mesh(tet_grid_medit(n), fmt=".mesh").session_id
    bottom = [i for i, p in enumerate(pts) if p[2] == 0.0]
    top = [i for i, p in enumerate(pts) if p[2] == 1.0]
    c.set_handles(sid, bottom + top, tol=0.0, max_iters=LONG_ITERS)
    targets = [pts[i] for i in bottom] + [(p[0] + 0.3, p[1], p[2]) for p in (pts[i] for i in top)]
    return sid, targets


def wait_finals(c, sids, timeout=END_S):
    """The final PROGRESS events of the moves of sessions `sids`, by session (other events are
    skipped); fails when one does not come within `timeout` s of the previous event."""
    finals = {}
    for ev in c.events(timeout=timeout):
        if isinstance(ev, Progress) and ev.final and ev.disp.session_id in sids:
            finals[ev.disp.session_id] = ev
            if len(finals) == len(sids):
                return finals
    raise AssertionError("final iterates of sessions %s only within %.0f s"
                         % (sorted(finals), timeout))


def wait_final(c, sid, timeout=END_S):
    return wait_finals(c, {sid}, timeout)[sid]


def poll_stat(c, sid, key, ok, bound_s=REPLY_S):
    """The session's stats value `key` once ok(value) holds, polled every 10 ms; the last value
    when bound_s passes first (the caller's assertion then fails)."""
    deadline = time.monotonic() + bound_s
    while True:
        v = c.stats(sid)[key]
        if ok(v) or time.monotonic() > deadline:
            return v
        time.sleep(0.01)


def test_four_long_moves_leave_a_worker_for_other_clients(daemon):
    """Item 7: one client runs four never-ending moves on four sessions (the daemon has 4 compute
    workers); another client's strokes and reads on a fifth session, a read of a moving session,
    a handle set and a short move on a sixth are still answered. Closing the mover's connection
    then ends all four moves."""
    with daemon.unix_client() as mover, daemon.unix_client() as artist:
        moving = [long_move_session(mover) for _ in range(4)]
        data = grid_obj(30, 30)
        X = obj_bytes_positions(data)
        other = artist.load_mesh(data, fmt=".obj").session_id
        for sid, _ in moving:
            artist.subscribe(sid)
        for sid, targets in moving:
            mover.send(m.HANDLES_MOVE, m.encode_handle_move(sid, targets, progress_every=0))
        mover.ping(b"moves dispatched")          # the four moves have reached the pool
        for k in range(3):
            artist.brush_begin(other, Brush(type="grab", center=X[0:3], move=(0, 0, 0.01),
                                            radius=0.3))
            artist.brush_update(other, move=(0, 0, 0.02 * (k + 1)))
            artist.brush_end(other)
        mesh = artist.get_mesh(other)
        assert mesh.positions[2] != X[2]         # the strokes were applied
        busy = artist.get_mesh(moving[0][0])     # a moving session answers reads too
        assert busy.nv == mover.stats(moving[0][0])["nv"]
        st = artist.stats()
        assert st["pool.long_lane"] == 3 and st["pool.long_waits"] >= 1, st
        # another client's move gets its turn in the long lane (moves take time slices), and
        # a handle-set factorization is not stuck behind the never-ending moves
        own, own_targets = long_move_session(artist)
        res = artist.move_handles(own, own_targets, max_iters=5, timeout=END_S)
        assert res.status == m.MOVE_BUDGET and res.iterations == 5, res
        mover.close()                            # requester gone: every move ends
        ended = wait_finals(artist, {sid for sid, _ in moving})
        assert all(ev.status == m.MOVE_SUPERSEDED for ev in ended.values()), ended
        assert artist.stats()["moves_orphaned"] >= 4
        for sid, _ in moving:
            artist.close_session(sid)
        artist.close_session(other)
        artist.close_session(own)


def test_reads_undo_and_handles_get_during_a_move_then_the_orphan_ends(daemon):
    """Item 8: while a long move runs, GET_MESH and SNAPSHOT of its session are answered from the
    last published version (equal to what a subscriber reconstructed from the stream), UNDO fails
    with ESTATE at once; when the requester disconnects the move ends, its last iterate stays and
    is one undo step."""
    with daemon.unix_client() as mover, daemon.unix_client() as viewer:
        sid, targets = long_move_session(mover)
        replica = MeshState.sync(viewer, sid)
        viewer.subscribe(sid)
        mover.send(m.HANDLES_MOVE, m.encode_handle_move(sid, targets, progress_every=5))
        first = None
        for ev in viewer.events(timeout=REPLY_S):
            if isinstance(ev, Progress):
                first = ev
                break
        assert first is not None and not first.final      # the move is running
        mesh = viewer.get_mesh(sid)                  # client timeout: 30 s
        snap = viewer.snapshot(sid)
        assert snap.version == mesh.version or snap.version > mesh.version
        # every iterate up to the reply's version reached the viewer before the reply
        replica.apply(first)
        for ev in viewer.events(timeout=0.0):
            if isinstance(ev, Progress) and ev.disp.version <= mesh.version:
                replica.apply(ev)
        assert replica.version == mesh.version
        assert replica.positions.tobytes() == mesh.positions.tobytes()
        with pytest.raises(DeformdError) as e:
            viewer.undo(sid)
        assert e.value.name == "ESTATE" and "move" in e.value.message
        assert viewer.get_handles(sid).handles       # HANDLES_GET does not wait for the move
        mover.close()
        last = wait_final(viewer, sid)
        assert last.status == m.MOVE_SUPERSEDED
        after = viewer.get_mesh(sid)
        assert after.version == last.disp.version    # the last iterate stays
        # ... as one undo step: the daemon records it when the move's job completes on the loop
        # thread, after the final frames went out, and GET_MESH / STATS do not wait for the job
        # (reads run beside a move), so the step is polled for, up to a bound
        assert poll_stat(viewer, sid, "undo_depth", lambda v: v >= 1) >= 1
        viewer.undo(sid)
        pts, _ = tet_grid(8)
        back = viewer.get_mesh(sid).positions
        assert max(abs(back[3 * i + k] - pts[i][k]) for i in range(len(pts)) for k in range(3)) < 1e-6
        viewer.close_session(sid)


def test_brush_begin_supersedes_a_running_move(daemon):
    """Item 8: BRUSH_BEGIN during a move is answered promptly: the move ends (status superseded,
    its last iterate stays) and the stroke applies on top of it."""
    with daemon.unix_client() as mover, daemon.unix_client() as artist:
        sid, targets = long_move_session(mover)
        rid = mover.send(m.HANDLES_MOVE, m.encode_handle_move(sid, targets, progress_every=0))
        mover.ping(b"move dispatched")
        pts, _ = tet_grid(8)
        artist.brush_begin(sid, Brush(type="grab", center=pts[0], move=(0, 0, 0.05), radius=0.3))
        artist.brush_end(sid)
        res = m.decode_move_result(mover.wait_reply(rid, END_S)[0].payload)
        assert res.status == m.MOVE_SUPERSEDED, res
        assert artist.stats()["moves_preempted"] >= 1
        artist.close_session(sid)


def test_handles_get_lets_a_new_move_supersede_a_running_one(daemon):
    """Item 18: HANDLES_GET (what `deformctl move --targets X.node` sends first) is answered while
    a move runs, so the new move can be sent and supersedes the running one."""
    with daemon.unix_client() as first, daemon.unix_client() as second:
        sid, targets = long_move_session(first)
        rid = first.send(m.HANDLES_MOVE, m.encode_handle_move(sid, targets, progress_every=0))
        first.ping(b"move dispatched")
        hs = second.get_handles(sid)
        assert len(hs.handles) == len(targets)
        res2 = second.move_handles(sid, targets, max_iters=5, timeout=END_S)
        res1 = m.decode_move_result(first.wait_reply(rid, END_S)[0].payload)
        assert res1.status == m.MOVE_SUPERSEDED, res1
        assert res2.status == m.MOVE_BUDGET and res2.iterations == 5, res2
        second.close_session(sid)


def test_one_worker_is_shared_by_a_long_move_and_strokes(make_daemon):
    """Item 7 with `threads = 1`: the single worker is the long lane too; a never-ending move
    yields it between turns, so another client's strokes (through the pool: inline_us 0) and a
    handle set on another session are still answered while it runs."""
    d = make_daemon("threads = 1\ninline_us = 0\n")
    with d.unix_client() as mover, d.unix_client() as artist:
        sid, targets = long_move_session(mover)
        rid = mover.send(m.HANDLES_MOVE, m.encode_handle_move(sid, targets, progress_every=0))
        mover.ping(b"move dispatched")
        data = grid_obj(20, 20)
        X = obj_bytes_positions(data)
        other = artist.load_mesh(data, fmt=".obj").session_id
        for k in range(3):
            artist.stroke(other, Brush(type="grab", center=X[0:3], move=(0, 0, 0.01 * (k + 1)),
                                       radius=0.3))
        own, own_targets = long_move_session(artist)
        assert artist.move_handles(own, own_targets, max_iters=3, timeout=END_S).iterations == 3
        assert artist.stats()["pool.long_lane"] == 1
        artist.close_session(sid)                # ends the move (a request queued behind it)
        res = m.decode_move_result(mover.wait_reply(rid, END_S)[0].payload)
        assert res.status == m.MOVE_SUPERSEDED, res
