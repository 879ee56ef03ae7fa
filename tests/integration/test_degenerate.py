"""Degenerate elements (issue 14 item 3): a mesh with two zero-area triangles (a duplicated vertex)
loads and deforms; the load report, the session stats and `deformctl load` / `deformctl stats`
say how many elements were excluded and what became of the duplicated vertex, and the shape
matches the same mesh loaded without those triangles."""
import json
import subprocess

from conftest import DEFORMCTL
from deformd_client import messages as m
from helpers import grid_obj

N = 8
C = 4 * N + 4             # an interior vertex (0-based), duplicated as vertex N * N


def meshes():
    """(with the degenerate triangles, without them): same vertices, the grid's faces in order."""
    base = grid_obj(N, N).decode().splitlines()
    verts = [ln for ln in base if ln.startswith("v ")]
    faces = [ln for ln in base if ln.startswith("f ")]
    dup = verts[C]                                   # the very same coordinates
    d = N * N + 1                                    # 1-based index of the duplicate
    extra = ["f %d %d %d" % (C + 1, C + 2, d), "f %d %d %d" % (C + 1, d, C + 1 + N)]
    with_deg = verts + [dup] + faces[:20] + extra + faces[20:]
    without = verts + [dup] + faces
    return [("\n".join(x) + "\n").encode() for x in (with_deg, without)]


def deform(c, data, name):
    info = c.load_mesh(data, fmt=".obj", name=name)
    mesh = c.get_mesh(info.session_id, rest=True)
    rest = [tuple(mesh.rest[3 * i:3 * i + 3]) for i in range(mesh.nv)]
    handles = [i for i in range(N * N) if i % N == 0] + [N * N - 1]
    targets = [rest[i] for i in handles[:-1]] + [(rest[-2][0] + 0.3, rest[-2][1] - 0.2,
                                                   rest[-2][2] + 0.1)]
    c.set_handles(info.session_id, handles, tol=1e-12, max_iters=5000)
    res = c.move_handles(info.session_id, targets, timeout=120)
    pos = c.get_mesh(info.session_id).positions
    return info, rest, res, [tuple(pos[3 * i:3 * i + 3]) for i in range(mesh.nv)]


def test_zero_area_triangles_are_excluded_and_reported(daemon):
    deg, ref = meshes()
    with daemon.unix_client() as c:
        info, rest, res, pos = deform(c, deg, "deg")
        rinfo, rrest, rres, rpos = deform(c, ref, "ref")
        assert info.report.degenerate_elements == 2, info.report
        assert rinfo.report.degenerate_elements == 0, rinfo.report
        s = c.stats(info.session_id)
        assert (s["degenerate_elements"], s["degenerate_action"], s["degenerate_followers"],
                s["degenerate_at_rest"]) == (2, 1, 1, 0), s
        r = c.stats(rinfo.session_id)
        assert (r["degenerate_elements"], r["degenerate_action"]) == (0, 0), r
        assert res.status == rres.status == m.MOVE_CONVERGED, (res, rres)
        # the grid deforms as without the two triangles (float32 positions on the wire)
        worst = max(abs(a - b) for i in range(N * N) for a, b in zip(pos[i], rpos[i]))
        assert worst < 1e-6, worst
        moved = max(abs(a - b) for a, b in zip(pos[C], rest[C]))
        assert moved > 1e-3, moved
        # the duplicate (a vertex of the two triangles only) follows its twin
        dup = N * N
        assert rest[dup] == rest[C]
        assert max(abs(a - b) for a, b in zip(pos[dup], pos[C])) < 1e-6, (pos[dup], pos[C])


def test_deformctl_load_and_stats_report_them(daemon, tmp_path):
    deg, _ = meshes()
    f = tmp_path / "dup.obj"
    f.write_bytes(deg)
    run = [DEFORMCTL, "--socket", daemon.socket_path]
    p = subprocess.run(run + ["load", str(f)], capture_output=True, text=True, timeout=60,
                       stdin=subprocess.DEVNULL)
    assert p.returncode == 0, p.stderr
    assert "2 degenerate elements" in p.stderr and "excluded from the solver" in p.stderr, p.stderr
    sid = p.stdout.split()[0]
    q = subprocess.run(run + ["--json", "stats", "--session", sid], capture_output=True, text=True,
                       timeout=60, stdin=subprocess.DEVNULL)
    assert q.returncode == 0, q.stderr
    st = json.loads(q.stdout)
    st = st.get("stats", st)
    assert st["degenerate_elements"] == 2 and st["degenerate_action"] == 1, st
    assert st["degenerate_followers"] == 1 and st["degenerate_at_rest"] == 0, st
