"""deformctl end to end against the real daemon: every command, --json, --help, Unix and TCP,
on the shared meshes. Brush results are checked against the reference grab formula (eqs. 6-7)
and against the same stroke sent through the Python client; `get` output is re-read."""
import json
import math
import os
import subprocess
import time

import pytest

from conftest import DEFORMCTL
from deformd_client import Brush, DeformdError
from helpers import (grab_displacement, grid_obj, read_indices, read_node_positions,
                     read_obj_positions, read_off_positions, tet_grid_medit)

COMMANDS = ["ping", "load", "list", "close", "brush", "handles", "move", "get", "undo", "redo",
            "reset-rest", "watch", "stats", "brush-state"]


@pytest.fixture(scope="module")
def ctl(daemon):
    if not os.access(DEFORMCTL, os.X_OK):
        pytest.fail("%s is missing: build it first (make -j2)" % DEFORMCTL, pytrace=False)

    def run(*args, tcp=False, check=True, timeout=120):
        where = ["--tcp", "127.0.0.1:%d" % daemon.tcp_port] if tcp else \
            ["--socket", daemon.socket_path]
        p = subprocess.run([DEFORMCTL] + where + [str(a) for a in args], capture_output=True,
                           text=True, timeout=timeout, stdin=subprocess.DEVNULL)
        if check:
            assert p.returncode == 0, "deformctl %s -> %d\nstdout: %s\nstderr: %s" % (
                " ".join(map(str, args)), p.returncode, p.stdout, p.stderr)
        return p
    return run


def vec(v):
    return ",".join("%.9g" % x for x in v)


def test_help_everywhere(ctl):
    top = subprocess.run([DEFORMCTL, "--help"], capture_output=True, text=True, timeout=10)
    assert top.returncode == 0
    for cmd in COMMANDS:
        assert cmd in top.stdout
        p = subprocess.run([DEFORMCTL, cmd, "--help"], capture_output=True, text=True, timeout=10)
        assert p.returncode == 0 and "usage:" in p.stdout and cmd in p.stdout, (cmd, p.stderr)
    bad = subprocess.run([DEFORMCTL, "frobnicate"], capture_output=True, text=True, timeout=10)
    assert bad.returncode == 2 and bad.stderr


@pytest.mark.parametrize("tcp", [False, True])
def test_ping_and_json(ctl, tcp):
    assert "pong" in ctl("ping", tcp=tcp).stdout
    j = json.loads(ctl("--json", "ping", tcp=tcp).stdout)
    assert j["ok"] is True and j["protocol"] == 1 and j["rtt_us"] > 0


def test_load_prints_the_session_id_alone_and_list_shows_it(ctl, tmp_path):
    f = tmp_path / "g.obj"
    f.write_bytes(grid_obj(6, 6))
    out = ctl("load", f, "--name", "cli-load").stdout
    assert out.strip().isdigit() and out.endswith("\n") and out.count("\n") == 1
    sid = int(out)
    sessions = json.loads(ctl("--json", "list").stdout)["sessions"]
    mine = [s for s in sessions if s["session"] == sid]
    assert mine and mine[0]["name"] == "cli-load" and mine[0]["nv"] == 36
    assert "cli-load" in ctl("list").stdout
    other = int(ctl("load", f, tcp=True).stdout)
    assert other != sid


@pytest.fixture
def spot(ctl, meshes, daemon):
    path = os.path.join(meshes, "spot.obj")
    sid = int(ctl("load", path).stdout)
    yield sid, path
    with daemon.unix_client() as c:
        try:
            c.close_session(sid)
        except DeformdError:
            pass


def test_brush_grab_on_spot_matches_the_reference(ctl, spot, tmp_path):
    sid, path = spot
    ctl("get", sid, "--out", tmp_path / "before.obj")
    X, nf = read_obj_positions(str(tmp_path / "before.obj"))
    assert len(X) == 2930 and nf == 5856
    center = X[1234]
    tip = (0.05, 0.02, -0.03)
    out = ctl("--json", "brush", sid, "--type", "grab", "--center", vec(center), "--move",
              vec(tip), "--radius", 0.25, "--nu", 0.4).stdout
    assert json.loads(out)["version"] >= 1
    ctl("get", sid, "--out", tmp_path / "after.obj")
    P, _ = read_obj_positions(str(tmp_path / "after.obj"))
    worst = 0.0
    for i in range(0, len(X), 3):
        u = grab_displacement(X[i], center, tip, 0.25, 0.4)
        worst = max(worst, max(abs(P[i][k] - X[i][k] - u[k]) for k in range(3)))
    assert worst < 1e-5, worst
    assert max(abs(P[1234][k] - center[k] - tip[k]) for k in range(3)) < 1e-5


def test_brush_nu_inf_is_the_plain_falloff_brush(ctl, spot, tmp_path):
    sid, _ = spot
    ctl("get", sid, "--out", tmp_path / "b.off")
    X, _ = read_off_positions(str(tmp_path / "b.off"))
    center, tip = X[77], (0.0, 0.1, 0.0)
    ctl("brush", sid, "--type", "grab", "--center", vec(center), "--move", vec(tip),
        "--radius", 0.3, "--nu", "inf")
    ctl("get", sid, "--out", tmp_path / "a.off")
    P, _ = read_off_positions(str(tmp_path / "a.off"))
    worst = max(max(abs(P[i][k] - X[i][k] - u[k]) for k in range(3))
                for i in range(0, len(X), 5)
                for u in [grab_displacement(X[i], center, tip, 0.3, math.inf)])
    assert worst < 1e-5, worst


CLI_BRUSHES = [
    (["--type", "twist", "--twist", "0,0.4,0", "--radius", "0.3", "--nu", "0.45"],
     Brush(type="twist", twist=(0, 0.4, 0), radius=0.3, nu=0.45)),
    (["--type", "scale", "--scale", "0.2", "--radius", "0.3", "--nu", "0.3"],
     Brush(type="scale", scale=0.2, radius=0.3, nu=0.3)),
    (["--type", "pinch", "--matrix", "0.2,0,0,0,-0.2,0,0,0,0", "--radius", "0.3"],
     Brush(type="pinch", matrix=(0.2, 0, 0, 0, -0.2, 0, 0, 0, 0), radius=0.3, nu=0.45)),  # CLI default
    (["--type", "affine", "--matrix", "0.1,0.2,0,0,0.1,0,0,0,0.3", "--radius", "0.3",
      "--nu", "0.3"],
     Brush(type="affine", matrix=(0.1, 0.2, 0, 0, 0.1, 0, 0, 0, 0.3), radius=0.3, nu=0.3)),
    (["--type", "grab", "--move", "0,0,0.1", "--radius", "0.2", "--falloff", "2", "--ratio",
      "1.5", "--nu", "0.4"],
     Brush(type="grab", move=(0, 0, 0.1), radius=0.2, falloff=2, ratio=1.5, nu=0.4)),
    (["--type", "grab", "--move", "0,0.2,0", "--radius", "0.3", "--integrator", "rk4",
      "--steps", "6", "--nu", "0.45"],
     Brush(type="grab", move=(0, 0.2, 0), radius=0.3, integrator="rk4", steps=6, nu=0.45)),
    (["--type", "grab", "--move", "0.1,0,0.05", "--radius", "0.2", "--mirror",
      "0,0,0,1,0,0", "--nu", "0.45"],
     Brush(type="grab", move=(0.1, 0, 0.05), radius=0.2, mirror=(0, 0, 0, 1, 0, 0), nu=0.45)),
]


@pytest.mark.parametrize("args,brush", CLI_BRUSHES,
                         ids=["twist", "scale", "pinch", "affine", "bi-scale", "rk4", "mirror"])
def test_cli_brush_equals_the_python_client_stroke(ctl, daemon, meshes, args, brush, tmp_path):
    path = os.path.join(meshes, "decimated-knight.off")
    a = int(ctl("load", path).stdout)
    with daemon.unix_client() as c:
        b = c.load_file(path).session_id
        X = c.get_mesh(a).positions
        brush.center = tuple(X[3 * 100:3 * 100 + 3])
        ctl("brush", a, "--center", vec(brush.center), *args)
        c.stroke(b, brush)
        pa, pb = c.get_mesh(a).positions, c.get_mesh(b).positions
        assert pa != X
        assert max(abs(x - y) for x, y in zip(pa, pb)) < 1e-6
        c.close_session(a)
        c.close_session(b)


def test_cli_brush_2d_and_pins(ctl, daemon, meshes, tmp_path):
    path = os.path.join(meshes, "woody.obj")
    sid = int(ctl("load", path).stdout)
    with daemon.unix_client() as c:
        X = c.get_mesh(sid).positions
        size = max(X[0::3]) - min(X[0::3])          # woody is ~hundreds of units wide
        center, pin_i = X[3 * 10:3 * 10 + 3], 20
        ctl("brush", sid, "--type", "grab", "--center", vec(center), "--move",
            vec((0.05 * size, 0.02 * size, 0)), "--radius", 0.2 * size, "--dim", 2, "--nu", 0.45)
        P = c.get_mesh(sid).positions
        assert all(P[3 * i + 2] == X[3 * i + 2] for i in range(len(X) // 3))
        assert abs(P[30] - X[30] - 0.05 * size) < 1e-4 * size
        pins = tmp_path / "pins.txt"
        pins.write_text("%.9g %.9g %.9g\n" % tuple(P[3 * pin_i:3 * pin_i + 3]))
        ctl("brush", sid, "--type", "grab", "--center", vec(P[3 * 10:3 * 10 + 3]),
            "--move", vec((0, 0, 0.1 * size)), "--radius", 0.5 * size, "--pin", pins,
            "--nu", 0.45)
        Q = c.get_mesh(sid).positions
        assert max(abs(Q[3 * pin_i + k] - P[3 * pin_i + k]) for k in range(3)) < 1e-5 * size
        assert abs(Q[3 * 10 + 2] - P[3 * 10 + 2] - 0.1 * size) < 1e-5 * size
        c.close_session(sid)


def test_handles_and_move_on_the_apple(ctl, daemon, meshes, tmp_path):
    rest = os.path.join(meshes, "teaser_apple_rest.node")
    hfile = os.path.join(meshes, "teaser_apple_handles.txt")
    tfile = os.path.join(meshes, "teaser_apple_init1.node")
    sid = int(ctl("load", rest).stdout)
    # the paper's apple setting rho 1e3, s 0.01 with the loss weight w = rho s / 10 = 1
    out = ctl("handles", sid, "--energy", "neohookean", "--handles", hfile, "--rho", 1e3,
              "--s", 0.01, "--w", 1, "--iters", 40).stdout
    handles = read_indices(hfile)
    assert str(len(handles)) in out
    out = ctl("move", sid, "--targets", tfile, "--handles", hfile).stdout
    words = out.split()
    assert words[0] == "iterations" and words[2] == "residual" and words[4] == "objective", out
    assert 1 <= int(words[1]) <= 40
    assert float(words[3]) >= 0 and math.isfinite(float(words[5]))
    ctl("get", sid, "--out", tmp_path / "moved.node")
    P = read_node_positions(str(tmp_path / "moved.node"))
    T = read_node_positions(tfile)
    R = read_node_positions(rest)
    assert len(P) == len(T) == 1088
    assert max(abs(P[h][k] - T[h][k]) for h in handles for k in range(3)) < 1e-4
    free = [i for i in range(len(P)) if i not in set(handles)]
    assert max(abs(P[i][k] - R[i][k]) for i in free for k in range(3)) > 1e-3
    j = json.loads(ctl("--json", "move", sid, "--targets", tfile, "--handles", hfile,
                       "--max-iters", 5).stdout)
    assert j["iterations"] <= 5 and j["status"] in ("converged", "budget")
    # targets as plain 'x y z' rows in handle order give the same solve
    pts = tmp_path / "targets.txt"
    pts.write_text("".join("%.17g %.17g %.17g\n" % T[h] for h in handles))
    j2 = json.loads(ctl("--json", "move", sid, "--targets", pts, "--max-iters", 5).stdout)
    assert j2["iterations"] <= 5


def test_move_node_targets_without_handles_uses_the_session_set(ctl, daemon, meshes, tmp_path):
    """`move --targets X.node` alone: the rows at the session's own handle indices (HANDLES_GET);
    --handles FILE still overrides them."""
    rest = os.path.join(meshes, "teaser_apple_rest.node")
    hfile = os.path.join(meshes, "teaser_apple_handles.txt")
    tfile = os.path.join(meshes, "teaser_apple_init1.node")
    sid = int(ctl("load", rest).stdout)
    p = ctl("move", sid, "--targets", tfile, check=False)      # no handle set yet
    assert p.returncode == 1 and "ENOTFOUND" in p.stderr and "handle set" in p.stderr, p.stderr
    ctl("handles", sid, "--energy", "neohookean", "--handles", hfile, "--rho", 1e3,
        "--s", 0.01, "--w", 1, "--iters", 40)
    handles = read_indices(hfile)
    out = ctl("move", sid, "--targets", tfile).stdout
    words = out.split()
    assert words[0] == "iterations" and words[2] == "residual" and words[4] == "objective", out
    assert 1 <= int(words[1]) <= 40
    assert float(words[3]) >= 0 and math.isfinite(float(words[5]))
    ctl("get", sid, "--out", tmp_path / "moved.node")
    P = read_node_positions(str(tmp_path / "moved.node"))
    T = read_node_positions(tfile)
    R = read_node_positions(rest)
    assert len(P) == len(T) == 1088
    assert max(abs(P[h][k] - T[h][k]) for h in handles for k in range(3)) < 1e-4
    hset = set(handles)
    assert max(abs(P[i][k] - R[i][k]) for i in range(len(P)) if i not in hset
               for k in range(3)) > 1e-3
    j = json.loads(ctl("--json", "move", sid, "--targets", tfile, "--max-iters", 5).stdout)
    assert j["iterations"] <= 5 and j["status"] in ("converged", "budget")
    # the override is really used: a shorter handle file gives the wrong target count
    short = tmp_path / "short.txt"
    short.write_text("".join("%d\n" % h for h in handles[:3]))
    p = ctl("move", sid, "--targets", tfile, "--handles", short, check=False)
    assert p.returncode == 1 and "EINVAL" in p.stderr and "3 targets" in p.stderr, p.stderr
    # a .node file without rows at the handle indices is a usage error
    tiny = tmp_path / "tiny.node"
    tiny.write_text("3 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n")
    p = ctl("move", sid, "--targets", tiny, check=False)
    assert p.returncode == 2 and "tiny.node" in p.stderr, p.stderr
    p = ctl("move", sid, "--targets", tmp_path / "missing.node", check=False)
    assert p.returncode == 2 and p.stderr
    with daemon.unix_client() as c:
        assert c.get_mesh(sid).version == j["version"]   # failed moves changed nothing
        c.close_session(sid)


def test_move_node_targets_supersedes_a_running_move(ctl, daemon, meshes):
    """Issue 9 item 18: `move --targets X.node` without --handles fetches the handle set
    (HANDLES_GET) while another client's never-ending move runs, and its move supersedes it."""
    from deformd_client import messages as m
    rest = os.path.join(meshes, "teaser_apple_rest.node")
    hfile = os.path.join(meshes, "teaser_apple_handles.txt")
    tfile = os.path.join(meshes, "teaser_apple_init1.node")
    sid = int(ctl("load", rest).stdout)
    ctl("handles", sid, "--energy", "neohookean", "--handles", hfile, "--rho", 1e3,
        "--s", 0.01, "--w", 1, "--tol", 0, "--iters", 1000000)
    handles = read_indices(hfile)
    T = read_node_positions(tfile)
    with daemon.unix_client() as c:
        rid = c.send(m.HANDLES_MOVE, m.encode_handle_move(sid, [T[h] for h in handles]))
        c.ping(b"move dispatched")
        j = json.loads(ctl("--json", "move", sid, "--targets", tfile, "--max-iters", 3,
                           timeout=60).stdout)
        assert j["iterations"] <= 3 and j["status"] in ("converged", "budget"), j
        first = m.decode_move_result(c.wait_reply(rid, 60)[0].payload)
        assert first.status == m.MOVE_SUPERSEDED, first
        c.close_session(sid)


@pytest.mark.parametrize("ext", [".obj", ".off", ".ply", ".node", ".mesh"])
def test_get_writes_every_format_readably(ctl, daemon, ext, tmp_path):
    """get --out in each format, after a brush; the file loads back into the same mesh."""
    src = tmp_path / ("src.mesh" if ext in (".node", ".mesh") else "src.obj")
    src.write_bytes(tet_grid_medit(5) if ext in (".node", ".mesh") else grid_obj(12, 9))
    sid = int(ctl("load", src).stdout)
    ctl("brush", sid, "--type", "twist", "--center", "0.5,0.5,0.5", "--twist", "0,0,0.5",
        "--radius", 0.4)
    out = tmp_path / ("out" + ext)
    j = json.loads(ctl("--json", "get", sid, "--out", out).stdout)
    with daemon.unix_client() as c:
        mesh = c.get_mesh(sid)
        c.close_session(sid)
        assert j["nv"] == mesh.nv and j["version"] == mesh.version == 1   # one stroke, one version
        back = c.load_file(str(out))
        assert (back.nv, back.ne, back.kind) == (mesh.nv, mesh.ne, mesh.kind)
        again = c.get_mesh(back.session_id)
        assert max(abs(a - b) for a, b in zip(again.positions, mesh.positions)) < 1e-6
        assert again.elements == mesh.elements
        c.close_session(back.session_id)


def test_undo_redo_reset_rest(ctl, daemon, tmp_path):
    f = tmp_path / "g.obj"
    f.write_bytes(grid_obj(10, 10))
    sid = int(ctl("load", f).stdout)
    with daemon.unix_client() as c:
        X = c.get_mesh(sid).positions
        ctl("brush", sid, "--type", "grab", "--center", vec(X[0:3]), "--move", "0,0,0.1",
            "--radius", 0.5)
        moved = c.get_mesh(sid).positions
        ctl("undo", sid)
        assert c.get_mesh(sid).positions == X
        ctl("redo", sid)
        assert c.get_mesh(sid).positions == moved
        p = ctl("redo", sid, check=False)
        assert p.returncode == 1 and "ESTATE" in p.stderr
        ctl("reset-rest", sid)
        rest = c.get_mesh(sid, rest=True).rest
        assert max(abs(a - b) for a, b in zip(rest, moved)) < 1e-6
        c.close_session(sid)


@pytest.mark.parametrize("shm", [False, True])
def test_watch_prints_one_line_per_version(ctl, daemon, tmp_path, shm):
    f = tmp_path / "g.obj"
    f.write_bytes(grid_obj(10, 10))
    name = "cli-watch-shm" if shm else "cli-watch"
    sid = int(ctl("load", f, "--name", name).stdout)
    with daemon.unix_client() as c:
        refs0 = c.stats()["shm_refs"]
    w = subprocess.Popen([DEFORMCTL, "--socket", daemon.socket_path, "watch", name,
                          "--count", "3"] + (["--shm"] if shm else []), stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL)
    try:
        with daemon.unix_client() as c:
            for _ in range(1200):          # wait until the watcher subscribed (60 s guard)
                if c.open_session(sid).subscribers == 1 and (
                        not shm or c.stats(sid)["shm_subscribers"] == 1):
                    break
                time.sleep(0.05)
            X = c.get_mesh(sid).positions
            c.stroke(sid, Brush(type="grab", center=X[0:3], move=(0, 0, 0.1), radius=0.5))
            c.undo(sid)
            c.redo(sid)
        out, err = w.communicate(timeout=15)
    finally:
        if w.poll() is None:
            w.kill()
    assert w.returncode == 0, err
    lines = [ln for ln in out.splitlines() if ln.startswith("version")]
    assert [ln.split()[1] for ln in lines] == ["1", "2", "3"], out
    assert [ln.split()[2] for ln in lines] == ["brush", "undo", "redo"], out
    assert [int(ln.split()[3]) for ln in lines] == [100, 100, 100], out
    # With --shm all three versions (1.3 KB dense frames, above the 1 KiB threshold) came
    # through the ring.
    with daemon.unix_client() as c:
        refs = c.stats()["shm_refs"] - refs0
    assert refs == (3 if shm else 0), out


def test_stats_and_errors(ctl, daemon):
    st = json.loads(ctl("--json", "stats").stdout)
    assert st and all(isinstance(v, (int, float)) for v in st.values())
    assert ctl("stats").stdout.strip()
    p = ctl("undo", "987654321", check=False)
    assert p.returncode == 1 and "ENOTFOUND" in p.stderr
    p = ctl("brush", "1", "--type", "smudge", "--center", "0,0,0", check=False)
    assert p.returncode == 2
    p = ctl("brush", "1", "--type", "grab", "--center", "0,0", check=False)
    assert p.returncode == 2
    p = subprocess.run([DEFORMCTL, "--socket", "/nonexistent/sock", "ping"],
                       capture_output=True, text=True, timeout=10)
    assert p.returncode == 1 and p.stderr


def boundary_triangles(ele_path):
    """Sorted corner triples (0-based) of the triangles used by exactly one tet of a TetGen .ele
    file (1-based like the shared meshes)."""
    with open(ele_path) as f:
        rows = [ln.split("#")[0].split() for ln in f]
    rows = [r for r in rows if r]
    count = {}
    for r in rows[1:1 + int(rows[0][0])]:
        t = [int(v) - 1 for v in r[1:5]]
        for skip in range(4):
            key = tuple(sorted(t[:skip] + t[skip + 1:]))
            count[key] = count.get(key, 0) + 1
    return {k for k, n in count.items() if n == 1}


@pytest.mark.parametrize("name,ext", [("pig_rest", ".obj"), ("teaser_apple_rest", ".off"),
                                      ("teaser_apple_rest", ".obj")])
def test_get_tet_mesh_as_surface_writes_the_boundary(ctl, daemon, meshes, name, ext, tmp_path):
    """get --out X.obj|.off of a tet mesh: the boundary triangles over ALL vertices (vertex i of
    the file is vertex i of the mesh), a note on stderr, positions equal to the daemon's."""
    node = os.path.join(meshes, name + ".node")
    sid = int(ctl("load", node).stdout)
    ctl("brush", sid, "--type", "twist", "--center", "0,0,0", "--twist", "0,0.3,0",
        "--radius", 0.5)
    out = tmp_path / ("surf" + ext)
    p = ctl("--json", "get", sid, "--out", out)
    assert "boundary surface" in p.stderr and str(out) in p.stderr, p.stderr
    j = json.loads(p.stdout)
    expect = boundary_triangles(os.path.join(meshes, name + ".ele"))
    assert j["boundary_faces"] == len(expect) and j["version"] == 1
    if ext == ".obj":
        P, nf = read_obj_positions(str(out))
        with open(out) as f:
            faces = [tuple(int(w.split("/")[0]) - 1 for w in ln.split()[1:4])
                     for ln in f if ln.startswith("f ")]
    else:
        P, nf = read_off_positions(str(out))
        with open(out) as f:
            rows = [ln.split() for ln in f if ln.strip() and not ln.startswith("#")]
        faces = [tuple(int(v) for v in r[1:4]) for r in rows[2 + len(P):] if r[0] == "3"]
    assert nf == len(faces) == len(expect)
    assert {tuple(sorted(t)) for t in faces} == expect
    with daemon.unix_client() as c:
        mesh = c.get_mesh(sid)
        assert len(P) == mesh.nv == len(read_node_positions(node))
        assert max(abs(P[i][k] - mesh.positions[3 * i + k])
                   for i in range(mesh.nv) for k in range(3)) < 1e-6
        c.close_session(sid)


@pytest.mark.parametrize("nu", ["-inf", "+inf", "inf", "-Infinity"])
def test_brush_accepts_every_spelling_of_infinite_nu(ctl, spot, nu, tmp_path):
    """nu = +-inf is the plain radial-falloff brush (b = 0): both signs give the same field."""
    sid, _ = spot
    ctl("get", sid, "--out", tmp_path / "b.off")
    X, _ = read_off_positions(str(tmp_path / "b.off"))
    center, tip = X[200], (0.05, 0.0, -0.05)
    ctl("brush", sid, "--type", "grab", "--center", vec(center), "--move", vec(tip),
        "--radius", 0.3, "--nu", nu)
    ctl("get", sid, "--out", tmp_path / "a.off")
    P, _ = read_off_positions(str(tmp_path / "a.off"))
    sign = -math.inf if nu.startswith("-") else math.inf
    worst = max(max(abs(P[i][k] - X[i][k] - u[k]) for k in range(3))
                for i in range(0, len(X), 5)
                for u in [grab_displacement(X[i], center, tip, 0.3, sign)])
    assert worst < 1e-5, worst
    assert max(abs(P[200][k] - X[200][k] - tip[k]) for k in range(3)) < 1e-5


def _state(daemon, sid):
    with daemon.unix_client() as c:
        m = c.get_mesh(sid)
        return m.version, list(m.positions)


@pytest.mark.parametrize("args,msg", [
    (["--type", "pinch", "--matrix", "0.1,0.2,0,0,-0.1,0,0,0,0"], "symmetric and traceless"),
    (["--type", "grab", "--move", "0,0,0.1", "--nu", "0.7"], "Poisson ratio nu 0.7"),
    (["--type", "scale", "--scale", "0.1", "--nu", "0.5"], "ESINGULAR"),
    (["--type", "grab", "--move", "0,0,0.1", "--pin", "DUP2"], "coincide"),
    (["--type", "grab", "--move", "0,0,0.1", "--pin", "ONE", "--mirror", "0,0,0,1,0,0"],
     "EUNSUPPORTED"),
], ids=["pinch-asymmetric", "nu-range", "scale-nu-half", "pins-coincide", "pins-mirror"])
def test_brush_rejected_by_the_engine_fails_locally_with_exit_1(ctl, daemon, spot, args, msg,
                                                                tmp_path):
    """Strokes the Kelvinlet engine refuses are refused before connecting ('rejected:', exit 1:
    a semantic error, not a usage error) and the session is untouched."""
    sid, _ = spot
    (tmp_path / "dup2.txt").write_text("0.1 0.2 0.3\n0.1 0.2 0.3\n")
    (tmp_path / "one.txt").write_text("0.1 0.2 0.3\n")
    args = [str(tmp_path / "dup2.txt") if a == "DUP2" else
            str(tmp_path / "one.txt") if a == "ONE" else a for a in args]
    before = _state(daemon, sid)
    p = ctl("brush", sid, "--center", "0,0.1,0", "--radius", 0.3, *args, check=False)
    assert p.returncode == 1, (p.returncode, p.stderr)
    assert p.stderr.startswith("deformctl brush: rejected: ") and msg in p.stderr, p.stderr
    assert "server:" not in p.stderr and p.stdout == ""
    assert _state(daemon, sid) == before


def test_brush_rejected_by_the_daemon_says_server_and_exits_1(ctl, daemon, spot, tmp_path):
    """A stroke only the daemon can refuse (more pins than the local check factorizes, two of
    them identical): 'server: ESINGULAR', exit 1, the stroke is cancelled, positions unchanged."""
    sid, _ = spot
    pins = tmp_path / "pins.txt"
    rows = ["%.3f 0.3 0.2" % (0.5 + 0.01 * i) for i in range(64)] + ["0.500 0.3 0.2"]
    pins.write_text("\n".join(rows) + "\n")
    v0, X0 = _state(daemon, sid)
    p = ctl("brush", sid, "--type", "grab", "--center", "0,0.1,0", "--move", "0,0,0.1",
            "--radius", 0.3, "--pin", pins, check=False)
    assert p.returncode == 1, (p.returncode, p.stderr)
    assert p.stderr.startswith("deformctl brush: server: ESINGULAR: "), p.stderr
    assert "coincide" in p.stderr and p.stdout == ""
    v1, X1 = _state(daemon, sid)
    assert X1 == X0
    # the cancel of a stroke that never changed the mesh publishes no version
    assert v1 == v0, (v0, v1)
    # the session still takes strokes afterwards (the rejected one left no open stroke)
    ctl("brush", sid, "--type", "grab", "--center", "0,0.1,0", "--move", "0,0,0.01",
        "--radius", 0.3)
    assert _state(daemon, sid)[0] == v1 + 1


def test_move_with_the_kelvinlet_guess(ctl, daemon, meshes, tmp_path):
    """`move --kelvinlet-guess` (issue 14 item 5): the solver starts from the Kelvinlet field of
    the handles' move, handles on their targets, so one iteration already has them there."""
    rest = os.path.join(meshes, "teaser_apple_rest.node")
    hfile = os.path.join(meshes, "teaser_apple_handles.txt")
    tfile = os.path.join(meshes, "teaser_apple_init1.node")
    sid = int(ctl("load", rest).stdout)
    ctl("handles", sid, "--energy", "arap", "--handles", hfile, "--iters", 40)
    j = json.loads(ctl("--json", "move", sid, "--targets", tfile, "--kelvinlet-guess",
                       "--max-iters", 1).stdout)
    assert j["iterations"] == 1
    ctl("get", sid, "--out", tmp_path / "moved.node")
    P = read_node_positions(str(tmp_path / "moved.node"))
    T = read_node_positions(tfile)
    R = read_node_positions(rest)
    handles = read_indices(hfile)
    assert max(abs(P[h][k] - T[h][k]) for h in handles for k in range(3)) < 1e-4
    free = [i for i in range(len(P)) if i not in set(handles)]
    assert max(abs(P[i][k] - R[i][k]) for i in free for k in range(3)) > 1e-3


def test_move_with_polish(ctl, daemon, meshes):
    """`move --polish` (issue 14 item 2): after the ADMM budget a projected-Newton polish; the
    result counts its Newton steps, reports its KKT residual (< 1e-9: converged) and an objective
    no higher than the same budget without it."""
    rest = os.path.join(meshes, "teaser_apple_rest.node")
    hfile = os.path.join(meshes, "teaser_apple_handles.txt")
    tfile = os.path.join(meshes, "teaser_apple_init1.node")
    plain_sid = int(ctl("load", rest).stdout)
    sid = int(ctl("load", rest).stdout)
    for s in (plain_sid, sid):
        ctl("handles", s, "--energy", "neohookean", "--handles", hfile, "--iters", 40)
    plain = json.loads(ctl("--json", "move", plain_sid, "--targets", tfile, "--max-iters", 40).stdout)
    j = json.loads(ctl("--json", "move", sid, "--targets", tfile, "--polish", "--max-iters", 40).stdout)
    assert plain["iterations"] == 40 and j["iterations"] > 40
    assert j["status"] == "converged" and j["residual"] < 1e-9
    assert j["objective"] <= plain["objective"]
