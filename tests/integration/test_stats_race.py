"""Session stats while compute runs: one client reads a session's stats over and over while
another runs handle moves and pinned brush strokes on it. The per-session keys that come from
the compute state (cache.admm_chol.cached, cache.kelvinlet_lu.cached, cache.bytes, brush.last_ms,
move.last_ms) must be read from loop-owned copies, never from fields a pool worker is writing:
under `make tsan` the daemon of this test halts with a ThreadSanitizer report otherwise (and the
make_daemon fixture fails the test on any report in its log). In the plain build it checks the
values stay consistent and end at the last job's figures."""
import threading

from deformd_client import Brush, messages as m
from helpers import tet_grid, tet_grid_medit

KEYS = ("handles", "cache.admm_chol.cached", "cache.kelvinlet_lu.cached", "cache.bytes",
        "brush.last_ms", "move.last_ms", "job_running")


def test_session_stats_read_while_a_move_and_strokes_run(make_daemon):
    d = make_daemon()
    n = 6
    pts, _ = tet_grid(n)
    with d.unix_client() as c, d.unix_client() as reader:
        sid = c.load_mesh(tet_grid_medit(n), fmt=".mesh", name="stats-race").session_id
        bottom = [i for i, p in enumerate(pts) if p[2] == 0.0]
        top = [i for i, p in enumerate(pts) if p[2] == 1.0]
        targets = [pts[i] for i in bottom] + [(p[0] + 0.2, p[1], p[2]) for p in (pts[i] for i in top)]
        c.set_handles(sid, bottom + top, tol=0.0, max_iters=200)

        stop = threading.Event()
        seen, errors = [], []

        def read_stats():
            try:
                while not stop.is_set():
                    st = reader.stats(sid)
                    missing = [k for k in KEYS if k not in st]
                    assert not missing, missing
                    assert st["cache.admm_chol.cached"] in (0, 1), st
                    assert st["cache.kelvinlet_lu.cached"] in (0, 1), st
                    assert st["cache.bytes"] >= 0 and st["move.last_ms"] >= 0, st
                    assert st["brush.last_ms"] >= 0, st
                    seen.append(st["job_running"])
            except Exception as e:  # reported by the main thread
                errors.append(repr(e))

        t = threading.Thread(target=read_stats)
        t.start()
        try:
            for k in range(3):
                # a move runs on a worker (solver built in the first one, then reused) ...
                rid = c.send(m.HANDLES_MOVE, m.encode_handle_move(sid, targets, max_iters=150,
                                                                  progress_every=25))
                # ... while strokes with pinned points queue behind it (K_pp LU on the worker)
                b = Brush(type="grab", center=pts[len(pts) // 2], move=(0.0, 0.0, 0.02),
                          radius=0.5, nu=0.4, pinned=[pts[0], pts[-1]])
                c.brush_begin(sid, b)
                for u in range(1, 4):
                    c.brush_update(sid, move=(0.0, 0.0, 0.02 * (u + 1)))
                c.brush_end(sid)
                res = m.decode_move_result(c.wait_reply(rid, 60)[-1].payload)
                assert res.iterations > 0, res
        finally:
            stop.set()
            t.join(60)
        assert not errors, errors
        assert seen, "no stats read completed"
        final = reader.stats(sid)
        assert final["job_running"] == 0
        assert final["handles"] == len(bottom) + len(top)
        assert final["cache.admm_chol.cached"] == 1 and final["cache.kelvinlet_lu.cached"] == 1
        assert final["cache.bytes"] > 0
        assert final["move.last_ms"] > 0 and final["brush.last_ms"] > 0
        c.close_session(sid)
