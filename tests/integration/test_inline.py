"""Inline brush updates (server/exec/job.h): a cheap update runs on the loop thread instead of the
compute pool. Checked here, with nothing that depends on how long an update takes: never inline
with inline_us = 0, never for pinned strokes, both paths give byte-identical streams and
positions, and a pipelined burst gives the same result whichever way its updates go. How many
updates run inline (small vs big meshes, the per-iteration cap of a burst) depends on measured
costs: tests/bench/bench_integration.py prints those; the cap itself is checked deterministically
by tests/unit/server/test_jobs.c."""
from deformd_client import Brush, MeshState, frame as fr, messages as m
from helpers import grid_obj, obj_bytes_positions
from rawwire import read_frames

UPDATES = 12


def _update(c, sid, brush, u):
    """Update number u of a test stroke (cumulative loads growing with u)."""
    c.brush_update(sid, move=(0.003 * u, -0.001 * u, 0.002 * u),
                   twist=(0.0, 0.0, 0.05 * u) if brush.type == "twist" else None)


def _stroke_session(d, data, brush, updates=UPDATES):
    """Loads `data` on daemon `d`, strokes it (begin, `updates` updates, end) while subscribed;
    returns (replica bytes from the stream, get-mesh bytes, versions seen, jobs_inline delta)."""
    X = obj_bytes_positions(data)
    with d.unix_client() as c:
        sid = c.load_mesh(data, fmt=".obj", name="inline").session_id
        c.subscribe(sid)
        before = c.stats()["jobs_inline"]
        c.brush_begin(sid, brush)
        for u in range(1, updates + 1):
            _update(c, sid, brush, u)
        c.brush_end(sid)
        inline = c.stats()["jobs_inline"] - before
        final = c.get_mesh(sid)
        replica = MeshState(X)
        versions = []
        for ev in c.events(timeout=60.0):   # ends at the final version
            assert replica.apply(ev), "version %d not applied" % ev.version
            versions.append(ev.version)
            if ev.version == final.version:
                break
        c.close_session(sid)  # session names are unique: the next call reuses "inline"
    return replica.tobytes(), final.positions.tobytes(), versions, inline


def budget_us(d, data, brush, factor):
    """An inline_us that is `factor` times what one update of `brush` on `data` measures on
    daemon `d` (session stat brush.last_ms), within the config's 1..1000: the tests then hold in
    optimized and sanitizer builds alike, whose update costs differ by 10x."""
    with d.unix_client() as c:
        sid = c.load_mesh(data, fmt=".obj", name="probe").session_id
        c.brush_begin(sid, brush)
        costs = []
        for u in range(1, 4):
            _update(c, sid, brush, u)
            costs.append(c.stats(sid)["brush.last_ms"])
        c.brush_end(sid)
        c.close_session(sid)
    return max(1, min(1000, int(factor * min(costs) * 1000.0) + 1))


def test_default_inline_budget(daemon):
    with daemon.unix_client() as c:
        assert c.stats()["inline_us"] == 50


def test_cheap_updates_run_inline_and_match_the_pool_path(daemon, make_daemon):
    data = grid_obj(24, 24)
    X = obj_bytes_positions(data)
    brushes = (Brush(type="grab", center=X[0:3], move=(0.01, 0.0, 0.02), radius=0.3, nu=0.4),
               Brush(type="twist", center=X[300:303], twist=(0, 0, 0.2), radius=0.25,
                     falloff=3, integrator="rk4", steps=2))
    fast = make_daemon("inline_us = 1000\n")   # the largest budget: small updates go inline
    pooled = make_daemon("inline_us = 0\n")
    with pooled.unix_client() as c:
        assert c.stats()["inline_us"] == 0
    for brush in brushes:
        a = _stroke_session(fast, data, brush)
        b = _stroke_session(pooled, data, brush)
        # how many of a's updates ran inline depends on their measured cost: not asserted
        print("%s: %d of %d updates inline" % (brush.type, a[3], UPDATES))
        assert 0 <= a[3] <= UPDATES
        assert b[3] == 0
        assert a[2] == b[2] == list(range(a[2][0], a[2][0] + UPDATES + 1))
        assert a[0] == a[1] == b[0] == b[1], brush.type + ": inline and pool paths differ"


def test_pinned_strokes_stay_on_the_pool(make_daemon):
    daemon = make_daemon("inline_us = 1000\n")
    small = grid_obj(12, 12)
    Xs = obj_bytes_positions(small)
    pinned = Brush(center=Xs[0:3], move=(0.01, 0, 0), radius=0.3, pinned=[Xs[30:33]])
    r = _stroke_session(daemon, small, pinned, updates=4)
    assert r[3] == 0, "a pinned stroke's update ran on the loop thread"
    assert r[0] == r[1]


PIPELINED = 60  # below max_pending_requests (64)


def _pipelined_stroke(d, data, brush):
    """Begins a stroke, then sends PIPELINED updates in one write on a raw socket; returns (final
    positions bytes, jobs_inline delta, jobs_inline_deferred delta)."""
    X = obj_bytes_positions(data)
    with d.unix_client() as c:
        sid = c.load_mesh(data, fmt=".obj", name="pipelined").session_id
        s0 = c.stats()
        sock = d.raw_unix(hello=True)
        begin = m.encode_brush(sid, brush)
        sock.sendall(fr.encode_frame(m.BRUSH_BEGIN, begin, request_id=1))
        frames, _ = read_frames(sock, timeout=60.0, want=1)
        assert frames and not frames[0].flags & fr.FLAG_ERROR
        burst = b"".join(fr.encode_frame(m.BRUSH_UPDATE,
                                         m.encode_brush_update(sid, move=(0.01 + 0.001 * u, 0, 0)),
                                         request_id=2 + u) for u in range(PIPELINED))
        sock.sendall(burst)
        frames, _ = read_frames(sock, timeout=60.0, want=PIPELINED)
        sock.close()
        assert [f.request_id for f in frames] == list(range(2, 2 + PIPELINED))
        assert not any(f.flags & fr.FLAG_ERROR for f in frames)
        s1 = c.stats()
        return (c.get_mesh(sid).positions.tobytes(), s1["jobs_inline"] - s0["jobs_inline"],
                s1["jobs_inline_deferred"] - s0["jobs_inline_deferred"])


def test_a_pipelined_burst_gives_the_same_result_either_way(make_daemon):
    """60 cheap updates arriving in one read: whichever of them run inline (at most
    DF_JOB_INLINE_ITER_FACTOR x inline_us of them per loop iteration; the rest go to the pool),
    every one is answered in order and the result equals the pool-only daemon's."""
    data = grid_obj(32, 32)
    X = obj_bytes_positions(data)
    grab = Brush(center=X[0:3], move=(0.01, 0, 0), radius=0.3)
    pooled, none, none_deferred = _pipelined_stroke(make_daemon("inline_us = 0\n"), data, grab)
    assert none == none_deferred == 0
    fast, inline, deferred = _pipelined_stroke(make_daemon("inline_us = 1000\n"), data, grab)
    print("pipelined burst, inline_us 1000: %d inline, %d deferred of %d" % (inline, deferred,
                                                                            PIPELINED))
    assert inline + deferred <= PIPELINED
    assert fast == pooled
