"""Every message type through the Python client against the real daemon (Unix socket and TCP),
with results checked against a reference Kelvinlet grab and the daemon's own snapshots."""
import math
import os
import re

import pytest

from deformd_client import (Brush, DeformdError, MeshState, SessionClosed, errors as E,
                            messages as m, stream as st)
from conftest import MESHES
from helpers import (grab_displacement, grid_session, grid_obj, obj_bytes_positions, tet_grid,
                     tet_grid_medit)

GRID_N = 20   # 400 vertices


@pytest.fixture(params=["unix", "tcp"])
def conn(daemon, request):
    c = daemon.unix_client() if request.param == "unix" else daemon.tcp_client()
    yield c
    c.close()


@pytest.fixture
def grid(daemon):
    """A fresh 20x20 grid session; closed afterwards."""
    with grid_session(daemon, GRID_N) as g:
        yield g


@pytest.fixture
def sym_grid(daemon):
    """A 20x20 grid symmetric about the plane x = 0.5."""
    data = grid_obj(GRID_N, GRID_N, symmetric=True)
    with daemon.unix_client() as c:
        info = c.load_mesh(data, fmt=".obj")
    yield info, obj_bytes_positions(data)
    with daemon.unix_client() as c:
        c.close_session(info.session_id)


def test_hello_reports_versions_limits_and_features(conn):
    h = conn.hello("pytest")
    assert h.version == 1 and h.server_max_version >= 1
    assert 1024 <= h.max_frame_payload <= 64 << 20
    assert 1 <= h.max_pending_requests <= m.MAX_PENDING_REQUESTS
    assert 1 <= h.max_mesh_vertices <= m.MAX_MESH_VERTICES
    assert 1 <= h.max_sessions <= 1024
    assert h.max_client_queue_bytes > 0
    assert h.features & m.FEAT_KELVINLET and h.features & m.FEAT_ADMM
    assert h.features & m.FEAT_TCP          # the fixture enables TCP
    if os.path.isdir(MESHES):
        assert h.features & m.FEAT_PATH_LOAD    # the fixture allows the meshes folder
    assert h.auth_required == 0
    assert h.server_name.startswith("deformd")


def test_ping_echoes_bytes_up_to_the_limit(conn):
    assert conn.ping(b"") == b""
    blob = os.urandom(m.MAX_PING_BYTES)
    assert conn.ping(blob) == blob
    with pytest.raises(DeformdError) as ei:
        conn.ping(blob + b"!")
    assert ei.value.code == E.ELIMIT
    assert conn.ping(b"after") == b"after"


def test_auth_is_answered_unsupported(conn):
    with pytest.raises(DeformdError) as ei:
        conn.auth(1, b"token")
    assert ei.value.code == E.EUNSUPPORTED and ei.value.name == "EUNSUPPORTED"


def test_load_list_open_close_and_session_closed_event(daemon, conn):
    data = grid_obj(7, 5)
    info = conn.load_mesh(data, fmt=".obj", name="msg-load")
    assert (info.nv, info.ne, info.kind, info.version) == (35, 2 * 6 * 4, 2, 0)
    assert info.name == "msg-load" and info.session_id != 0
    assert info.undo_depth == 0 and info.redo_depth == 0
    ids = {s.session_id: s for s in conn.list_sessions()}
    assert ids[info.session_id].nv == 35
    assert conn.open_session(info.session_id).name == "msg-load"
    assert conn.open_session(0, "msg-load").session_id == info.session_id
    watcher = daemon.unix_client()
    assert watcher.subscribe(info.session_id).subscribers == 1
    conn.close_session(info.session_id)
    ev = watcher.next_event(5.0)
    assert isinstance(ev, SessionClosed) and ev.session_id == info.session_id
    watcher.close()
    with pytest.raises(DeformdError) as ei:
        conn.open_session(info.session_id)
    assert ei.value.code == E.ENOTFOUND
    assert info.session_id not in {s.session_id for s in conn.list_sessions()}


def test_load_in_many_chunks_equals_one_chunk(daemon, monkeypatch):
    data = grid_obj(30, 30)
    with daemon.unix_client() as c:
        one = c.load_mesh(data, fmt=".obj")
        monkeypatch.setattr(m, "LOAD_CHUNK_BYTES", 997)
        many = c.load_mesh(data, fmt=m.FMT_AUTO)
        a = c.get_mesh(one.session_id)
        b = c.get_mesh(many.session_id)
        assert a.nv == b.nv == 900
        assert a.positions.tobytes() == b.positions.tobytes()
        assert a.elements.tobytes() == b.elements.tobytes()
        assert a.positions == obj_bytes_positions(data)
        c.close_session(one.session_id)
        c.close_session(many.session_id)


def test_load_by_server_path_only_inside_allowed_folders(daemon, meshes, tmp_path):
    with daemon.unix_client() as c:
        info = c.load_mesh(path=os.path.realpath(os.path.join(meshes, "bunny.off")))
        assert (info.nv, info.ne, info.kind) == (3485, 6966, 2)
        c.close_session(info.session_id)
        outside = tmp_path / "x.obj"
        outside.write_bytes(grid_obj(3, 3))
        with pytest.raises(DeformdError) as ei:
            c.load_mesh(path=str(outside))
        assert ei.value.code in (E.EINVAL, E.EIO, E.EUNSUPPORTED)
        with pytest.raises(DeformdError):
            c.load_mesh(path=os.path.join(os.path.realpath(meshes), "..", "..", "etc", "passwd"))


@pytest.mark.parametrize("name,nv,ne,kind", [
    ("teaser_apple_rest.node", 1088, 4072, 3), ("octopus-low.mesh", 452, 1140, 3),
    ("decimated-knight.off", 502, 1000, 2), ("suzanne.obj", 507, None, 2),
    ("woody.obj", 694, 1267, 2),
])
def test_load_shared_meshes_inline(daemon, meshes, name, nv, ne, kind):
    with daemon.unix_client() as c:
        info = c.load_file(os.path.join(meshes, name))
        assert (info.nv, info.kind) == (nv, kind)
        if ne is not None:
            assert info.ne == ne
        if name == "suzanne.obj":
            assert info.ne == 968  # 500 faces, quads split into two triangles
        if name == "woody.obj":      # `v x y 0.000000` lines: a flat 3D mesh, not a 2D one
            assert info.planar == 0
        mesh = c.get_mesh(info.session_id)
        assert len(mesh.positions) == 3 * nv and len(mesh.elements) == m.ELEM_SIZE[kind] * info.ne
        assert max(mesh.elements) < nv
        c.close_session(info.session_id)


def test_grab_stroke_matches_the_reference_formula(daemon, conn, grid):
    info, X = grid
    sid = info.session_id
    conn.subscribe(sid)
    ci = 7 * GRID_N + 9
    center = tuple(X[3 * ci:3 * ci + 3])
    tip = (0.02, -0.01, 0.1)
    b = Brush(type="grab", center=center, move=tip, radius=0.3, nu=0.45)
    a1 = conn.brush_begin(sid, b)
    a2 = conn.brush_update(sid, move=tip)
    a3 = conn.brush_end(sid)
    assert a1.version == 1 and a2.version == 2 and a3.version == 2   # end adds no version
    mesh = conn.get_mesh(sid)
    assert mesh.version == 2
    worst = 0.0
    for i in range(info.nv):
        u = grab_displacement(X[3 * i:3 * i + 3], center, tip, 0.3, 0.45)
        for k in range(3):
            worst = max(worst, abs(mesh.positions[3 * i + k] - (X[3 * i + k] + u[k])))
    assert worst < 1e-5, worst
    # the brush tip moved by exactly the requested displacement
    for k in range(3):
        assert abs(mesh.positions[3 * ci + k] - (center[k] + tip[k])) < 1e-6
    evs = list(conn.events(timeout=0.5))
    assert [e.version for e in evs] == [1, 2]
    assert all(e.kind == m.CHANGE_BRUSH for e in evs)


def test_grab_with_nu_inf_and_strength_and_knobs(daemon, grid):
    """nu = inf is the plain radial-falloff grab; knobs (set brush parameter) change the open
    stroke from its next update on, and without an open stroke are ESTATE and change nothing."""
    info, X = grid
    sid = info.session_id
    ci = 10 * GRID_N + 10
    center = tuple(X[3 * ci:3 * ci + 3])

    def worst(P, radius, tip):
        w = 0.0
        for i in range(0, info.nv, 7):
            u = grab_displacement(X[3 * i:3 * i + 3], center, tip, radius, math.inf)
            w = max(w, max(abs(P[3 * i + k] - (X[3 * i + k] + u[k])) for k in range(3)))
        return w

    with daemon.unix_client() as c:
        with pytest.raises(DeformdError) as ei:
            c.set_brush_param(sid, "radius", 0.2)
        assert ei.value.code == E.ESTATE
        c.brush_begin(sid, Brush(type="grab", center=center, radius=0.3, nu=math.inf))
        c.brush_update(sid, move=(0, 0, 0.2))
        assert worst(c.get_mesh(sid).positions, 0.3, (0, 0, 0.2)) < 1e-5   # knob had no effect
        c.set_brush_param(sid, "radius", 0.2)
        c.set_brush_param(sid, "strength", 0.5)
        c.brush_update(sid, move=(0, 0, 0.2))
        c.brush_end(sid)
        assert worst(c.get_mesh(sid).positions, 0.2, (0, 0, 0.1)) < 1e-5
        for bad in (("radius", -1.0), ("falloff", 0), ("falloff", 9), ("ratio", 1.0)):
            c.brush_begin(sid, Brush(type="grab", center=center, radius=0.3))
            with pytest.raises(DeformdError) as ei:
                c.set_brush_param(sid, *bad)
            assert ei.value.code == E.EINVAL, bad
            c.brush_cancel(sid)


def test_cancel_undo_redo_and_their_stream_kinds(daemon, grid):
    info, X = grid
    sid = info.session_id
    with daemon.unix_client() as c:
        c.subscribe(sid)
        b = Brush(type="grab", center=X[0:3], move=(0.1, 0, 0), radius=0.25, nu=0.3)
        c.brush_begin(sid, b)
        c.brush_update(sid, move=(0.2, 0, 0))
        ack = c.brush_cancel(sid)
        assert ack.version == 3
        assert c.get_mesh(sid).positions == X
        with pytest.raises(DeformdError) as ei:
            c.brush_end(sid)
        assert ei.value.code == E.ESTATE
        with pytest.raises(DeformdError) as ei:
            c.undo(sid)                        # nothing committed yet
        assert ei.value.code == E.ESTATE
        c.stroke(sid, b)
        after = c.get_mesh(sid).positions
        assert after != X
        info2 = c.open_session(sid)
        assert (info2.undo_depth, info2.redo_depth) == (1, 0)
        c.undo(sid)
        assert c.get_mesh(sid).positions == X
        assert c.open_session(sid).redo_depth == 1
        c.redo(sid)
        assert c.get_mesh(sid).positions.tobytes() == after.tobytes()
        with pytest.raises(DeformdError) as ei:
            c.redo(sid)
        assert ei.value.code == E.ESTATE
        kinds = [e.kind for e in c.events(timeout=0.5)]
        assert kinds == [m.CHANGE_BRUSH, m.CHANGE_BRUSH, m.CHANGE_BRUSH_CANCEL, m.CHANGE_BRUSH,
                         m.CHANGE_UNDO, m.CHANGE_REDO]


@pytest.mark.parametrize("brush", [
    Brush(type="twist", twist=(0, 0, 0.5), radius=0.3, nu=0.45),
    Brush(type="scale", scale=0.2, radius=0.3, nu=0.3),
    Brush(type="pinch", matrix=(0.2, 0, 0, 0, -0.2, 0, 0, 0, 0), radius=0.3, nu=0.3),
    Brush(type="affine", matrix=(0.1, 0.2, 0, 0, 0.1, 0, 0, 0, 0.3), radius=0.3, nu=0.3),
    Brush(type="grab", move=(0, 0, 0.1), radius=0.2, nu=0.4, falloff=2, ratio=1.5),
    Brush(type="grab", move=(0, 0, 0.1), radius=0.2, nu=0.4, falloff=3, ratio=1.3),
    Brush(type="grab", move=(0.05, 0.05, 0), radius=0.3, nu=0.45, dim=2),
    Brush(type="grab", move=(0, 0.2, 0), radius=0.3, nu=0.45, integrator="rk4", steps=8),
    Brush(type="grab", move=(0, 0.2, 0), radius=0.3, nu=0.45, moving=True, steps=8),
    Brush(type="grab", move=(0.1, 0, 0.05), radius=0.2, nu=0.45,
          mirror=(0.5, 0.5, 0, 1, 0, 0)),
], ids=["twist", "scale", "pinch", "affine", "bi-scale", "tri-scale", "2d", "rk4", "moving",
        "mirror"])
def test_every_brush_feature_deforms_finitely(daemon, grid, sym_grid, brush):
    info, X = sym_grid if brush.mirror is not None else grid
    sid = info.session_id
    ci = 10 * GRID_N + 6
    brush.center = tuple(X[3 * ci:3 * ci + 3])
    with daemon.unix_client() as c:
        c.stroke(sid, brush)
        P = c.get_mesh(sid).positions
    assert all(math.isfinite(v) for v in P)
    moved = [i for i in range(info.nv)
             if max(abs(P[3 * i + k] - X[3 * i + k]) for k in range(3)) > 1e-6]
    assert len(moved) > 10
    if brush.dim == 2:
        assert all(P[3 * i + 2] == X[3 * i + 2] for i in range(info.nv))   # z untouched
    if brush.mirror is not None:   # mirrored across x = 0.5: vertex (i, j) <-> (N-1-i, j)
        j = 10
        for i in range(GRID_N // 2):
            a, b = j * GRID_N + i, j * GRID_N + GRID_N - 1 - i
            ua = [P[3 * a + k] - X[3 * a + k] for k in range(3)]
            ub = [P[3 * b + k] - X[3 * b + k] for k in range(3)]
            assert abs(ua[0] + ub[0]) < 1e-5
            assert abs(ua[1] - ub[1]) < 1e-5 and abs(ua[2] - ub[2]) < 1e-5


def test_pinned_points_stay_and_the_lu_cache_hits(daemon, grid):
    info, X = grid
    sid = info.session_id
    ci, pi = 10 * GRID_N + 10, 10 * GRID_N + 14
    pin = tuple(X[3 * pi:3 * pi + 3])
    b = Brush(type="grab", center=tuple(X[3 * ci:3 * ci + 3]), move=(0, 0, 0.1), radius=0.3,
              nu=0.45, pinned=[pin])
    with daemon.unix_client() as c:
        s0 = c.stats()
        c.brush_begin(sid, b)
        for k in range(1, 5):
            c.brush_update(sid, move=(0, 0, 0.05 * k))
        c.brush_end(sid)
        P = c.get_mesh(sid).positions
        assert max(abs(P[3 * pi + k] - pin[k]) for k in range(3)) < 1e-5
        assert abs(P[3 * ci + 2] - (X[3 * ci + 2] + 0.2)) < 1e-5
        s1 = c.stats()
        assert c.stats(sid)["cache.kelvinlet_lu.cached"] == 1
        c.stroke(sid, b)                 # same pins and kernel: the cached LU is reused
        s2 = c.stats()
    miss = "cache.kelvinlet_lu.misses"
    hit = "cache.kelvinlet_lu.hits"
    assert s1[miss] - s0[miss] == 1
    assert s2[miss] == s1[miss]
    assert s2[hit] > s1[hit]


def test_handles_move_streams_progress_and_reaches_targets(daemon):
    pts, tets = tet_grid(5)
    with daemon.unix_client() as c:
        info = c.load_mesh(tet_grid_medit(5), fmt=".mesh", name="msg-handles")
        sid = info.session_id
        c.subscribe(sid)
        bottom = [i for i, p in enumerate(pts) if p[2] == 0.0]
        top = [i for i, p in enumerate(pts) if p[2] == 1.0]
        handles = bottom + top
        c.set_handles(sid, handles, energy="arap", w=1e-4, s=0.01, rho=0.1, tol=0.0,
                      max_iters=60)
        targets = [pts[i] for i in bottom] + [(p[0] + 0.2, p[1], p[2] + 0.1)
                                              for p in (pts[i] for i in top)]
        res = c.move_handles(sid, targets, progress_every=10)
        assert res.status in (m.MOVE_CONVERGED, m.MOVE_BUDGET), res
        assert 1 <= res.iterations <= 60
        assert math.isfinite(res.objective) and res.residual >= 0
        progress = [e for e in c.events(timeout=0.5) if isinstance(e, st.Progress)]
        assert len(progress) >= 2
        assert progress[-1].final == 1 and all(p.final == 0 for p in progress[:-1])
        assert [p.iteration for p in progress] == sorted(p.iteration for p in progress)
        assert progress[-1].disp.version == res.version
        mesh = c.get_mesh(sid)
        for h, t in zip(handles, targets):
            for k in range(3):
                assert abs(mesh.positions[3 * h + k] - t[k]) < 1e-4
        mid = [i for i, p in enumerate(pts) if p[2] == 0.5]
        assert sum(mesh.positions[3 * i] - pts[i][0] for i in mid) / len(mid) > 0.02
        with pytest.raises(DeformdError) as ei:
            c.move_handles(sid, targets[:-1])
        assert ei.value.code == E.EINVAL
        c.close_session(sid)


def test_get_handles_returns_the_set_and_follows_replacements(daemon):
    """HANDLES_GET: ENOTFOUND before any set; then every parameter, the handle order and the
    affine sets exactly as sent; a pipelined get after a set sees that set; moves still work."""
    pts, _ = tet_grid(4)
    with daemon.unix_client() as c:
        sid = c.load_mesh(tet_grid_medit(4), fmt=".mesh", name="msg-get-handles").session_id
        with pytest.raises(DeformdError) as ei:
            c.get_handles(sid)
        assert ei.value.code == E.ENOTFOUND and "handle set" in ei.value.message
        with pytest.raises(DeformdError) as ei:
            c.get_handles(987654321)
        assert ei.value.code == E.ENOTFOUND
        bottom = [i for i, p in enumerate(pts) if p[2] == 0.0]
        top = [i for i, p in enumerate(pts) if p[2] == 1.0]
        mid = [i for i, p in enumerate(pts) if 0 < p[2] < 1 and p[0] == 0.0]
        handles = top[::-1] + bottom          # not sorted: the order must survive
        aff = [m.AffineSet(A=[(1.0, 0.0, 0.0)], b=[0.0], indices=mid),
               m.AffineSet(A=[(0.0, 1.0, 0.0), (0.0, 0.0, 1.0)], b=[1.0 / 3, 2.0 / 3],
                           indices=[i for i in range(len(pts)) if i not in handles][:1])]
        sent = dict(w=2.5e-4, s=0.02, rho=0.75, tol=1e-9, max_iters=77, accelerate=True,
                    anderson_m=7, area_weighting=True, youngs=2e6, poisson=0.3,
                    strain_min=0.8, strain_max=1.25, bending=0.125)
        c.set_handles(sid, handles, energy="arap", affine=aff, **sent)
        hs = c.get_handles(sid)
        assert hs.session_id == sid and hs.energy == "arap"
        assert hs.handles == handles
        assert hs.params == m.HandleParams(**sent)
        assert len(hs.affine) == 2
        for got, want in zip(hs.affine, aff):
            assert got.A == [list(r) for r in want.A] and got.b == list(want.b)
            assert got.indices == list(want.indices)
        # a replacement set, sent without waiting, then a get: the get sees the new set
        rid_set = c.send(m.HANDLES_SET, m.encode_handles(
            sid, "neohookean", bottom, m.HandleParams.for_energy("neohookean", rho=1e3, w=1.0)))
        rid_get = c.send(m.HANDLES_GET, m.encode_session_ref(sid))
        c.wait_reply(rid_set)
        hs2 = m.decode_handles(b"".join(f.payload for f in c.wait_reply(rid_get)))
        assert hs2.energy == "neohookean" and hs2.handles == bottom and hs2.affine == []
        assert (hs2.params.w, hs2.params.rho, hs2.params.s) == (1.0, 1e3, 0.01)
        assert hs2.params.youngs == 1e7 and hs2.params.accelerate is False
        # the fetched handle order is the move's target order
        res = c.move_handles(sid, [pts[i] for i in hs2.handles], max_iters=5)
        assert res.status in (m.MOVE_CONVERGED, m.MOVE_BUDGET)
        P = c.get_mesh(sid).positions
        assert max(abs(P[3 * h + k] - pts[h][k]) for h in bottom for k in range(3)) < 1e-5
        c.close_session(sid)
        with pytest.raises(DeformdError) as ei:
            c.get_handles(sid)
        assert ei.value.code == E.ENOTFOUND


def test_reset_rest_makes_current_the_rest_shape(daemon, grid):
    info, X = grid
    sid = info.session_id
    with daemon.unix_client() as c:
        c.stroke(sid, Brush(type="grab", center=X[30:33], move=(0, 0, 0.1), radius=0.3))
        before = c.get_mesh(sid, rest=True, base=True)
        assert before.rest == X and before.base == X
        v = c.reset_rest(sid).version
        after = c.get_mesh(sid, rest=True, base=True)
        assert after.version == v
        assert after.rest.tobytes() == after.positions.tobytes() == before.positions.tobytes()
        assert after.base == X


def test_snapshot_and_replica_follow_the_stream(daemon, grid):
    info, X = grid
    sid = info.session_id
    with daemon.unix_client() as c, daemon.tcp_client() as w:
        w.subscribe(sid, snapshot=True)
        first = w.next_event(5.0)
        assert first.kind == m.CHANGE_SNAPSHOT and first.encoding == m.DISP_DENSE
        replica = MeshState(X)
        replica.apply(first)
        for k in range(4):
            c.stroke(sid, Brush(type="grab", center=X[3 * 40 * k:3 * 40 * k + 3],
                                move=(0, 0.01 * k, 0.05), radius=0.05 + 0.1 * k))
        c.undo(sid)
        c.undo(sid)
        c.redo(sid)
        c.brush_begin(sid, Brush(type="twist", center=X[600:603], twist=(0, 0, 0.3),
                                 radius=0.15))
        c.brush_cancel(sid)
        final = c.get_mesh(sid)
        for ev in w.events(timeout=0.5):
            replica.apply(ev)
        assert replica.version == final.version
        assert replica.tobytes() == final.positions.tobytes()
        snap = c.snapshot(sid)
        assert snap.version == final.version and snap.encoding == m.DISP_DENSE
        assert snap.xyz == replica.disp
        assert c.snapshot(sid, final.version).xyz == snap.xyz
        with pytest.raises(DeformdError) as ei:   # only the current version is retained
            c.snapshot(sid, 2)
        assert ei.value.code == E.ENOTFOUND
        sync = MeshState.sync(c, sid)
        assert sync.tobytes() == final.positions.tobytes()


def test_sparse_frames_list_only_moved_vertices(daemon):
    """A unit grid and a copy scaled by 1e6 and moved 1e7 away: a brush on the unit grid moves
    the far one by less than half a double ulp (its displacements stay exactly 0), so frames
    are sparse and list only the near vertices."""
    near = grid_obj(GRID_N, GRID_N).decode().splitlines()
    far = []
    for line in near:
        t = line.split()
        if t and t[0] == "v":
            far.append("v %r %r %r" % tuple(1e7 + 1e6 * float(x) for x in t[1:4]))
        elif t and t[0] == "f":
            far.append("f " + " ".join(str(int(x) + GRID_N * GRID_N) for x in t[1:]))
    data = ("\n".join(near + far) + "\n").encode()
    X = obj_bytes_positions(data)
    with daemon.unix_client() as c:
        info = c.load_mesh(data, fmt=".obj")
        sid = info.session_id
        assert info.nv == 2 * GRID_N * GRID_N
        c.subscribe(sid)
        replica = MeshState(X)
        c.brush_begin(sid, Brush(type="grab", center=X[0:3], move=(0, 0, 0.05), radius=0.2))
        c.brush_update(sid, move=(0, 0, 0.1))
        c.brush_update(sid, move=(0, 0, 0.1))     # same load: nothing changes
        c.brush_end(sid)
        evs = list(c.events(timeout=0.5))
        assert [e.encoding for e in evs] == [m.DISP_SPARSE] * 3
        assert [e.count for e in evs] == [GRID_N * GRID_N, GRID_N * GRID_N, 0]
        assert list(evs[0].idx) == list(range(GRID_N * GRID_N))
        for e in evs:
            replica.apply(e)
        assert replica.tobytes() == c.get_mesh(sid).positions.tobytes()
        c.close_session(sid)


def test_stats_daemon_wide_and_per_session(daemon, grid):
    info, _ = grid
    with daemon.unix_client() as c:
        s = c.stats()
        assert s and all(math.isfinite(v) for v in s.values())
        assert any(k.startswith("sessions") or k.startswith("clients") for k in s), sorted(s)
        ss = c.stats(info.session_id)
        assert ss and all(math.isfinite(v) for v in ss.values())
    # Every key the daemon reports is documented (PROTOCOL.md 4.23), with its own name.
    with open(os.path.join(os.path.dirname(__file__), "..", "..", "proto", "PROTOCOL.md")) as f:
        spec = f.read()
    prefixes = {"cache.kelvinlet_lu", "cache.admm_chol"}  # written "`x.hits` / `.misses`"
    # per-connection keys are written `client.<id>.NAME`
    per_client = {re.sub(r"^client\.\d+\.", "client.<id>.", k) for k in s}
    assert "client.<id>.bytes_per_s" in per_client, sorted(s)
    for key in sorted(per_client | set(ss)):
        head = key.rsplit(".", 1)[0]
        assert "`%s`" % key in spec or (head in prefixes and "`." + key.rsplit(".", 1)[1] + "`"
                                         in spec), "stats key %r is not in PROTOCOL.md" % key


def test_unsubscribe_stops_the_stream(daemon, grid):
    info, X = grid
    sid = info.session_id
    with daemon.unix_client() as c, daemon.unix_client() as w:
        w.subscribe(sid)
        c.stroke(sid, Brush(type="grab", center=X[0:3], move=(0, 0, 0.1), radius=0.3))
        assert len(list(w.events(timeout=0.5))) == 1
        w.unsubscribe(sid)
        c.stroke(sid, Brush(type="grab", center=X[0:3], move=(0, 0, 0.1), radius=0.3))
        assert list(w.events(timeout=0.5)) == []
