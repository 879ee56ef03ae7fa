"""Bad values and flat meshes (issue 9 items 14, 15, 16): brush knobs validated when set,
results that would not be finite in float32 refused, flat 3D meshes deformed in 3D and 2D
sessions refusing z motion. Every refusal must leave the session unchanged."""
import math
import subprocess

import pytest

from conftest import DEFORMCTL
from deformd_client import Brush, DeformdError, errors as E
from helpers import grid_session, read_obj_positions

GRID_N = 12


@pytest.fixture
def grid(daemon):
    with grid_session(daemon, GRID_N) as g:
        yield g


# -- item 15: SET_BRUSH_PARAM is validated when set ------------------------------------------

@pytest.mark.parametrize("param, value, code, words", [
    ("nu", 0.7, E.EINVAL, "nu 0.7"),
    ("nu", -1.5, E.EINVAL, "nu -1.5"),
    ("radius", 1e7, E.EINVAL, "radius 1e+07"),
    ("radius", 1e-9, E.EINVAL, "radius 1e-09"),
    ("strength", 1e12, E.EINVAL, "strength 1e+12"),
    ("ratio", 1e4, E.EINVAL, "ratio 10000"),        # radius * ratio^(order-1) beyond 1e6
])
def test_set_brush_param_refuses_values_the_next_update_would_fail(daemon, grid, param, value,
                                                                   code, words):
    info, X = grid
    sid = info.session_id
    with daemon.unix_client() as c:
        c.brush_begin(sid, Brush(type="grab", center=X[0:3], radius=0.3, nu=0.45, falloff=3))
        c.brush_update(sid, move=(0, 0, 0.05))
        before = c.get_mesh(sid).positions
        v0 = c.open_session(sid).version
        with pytest.raises(DeformdError) as ei:
            c.set_brush_param(sid, param, value)
        assert ei.value.code == code
        assert words in ei.value.message and param in ei.value.message, ei.value.message
        # nothing changed: same version, and the stroke still updates with its old parameters
        assert c.open_session(sid).version == v0
        assert c.get_mesh(sid).positions == before
        c.brush_update(sid, move=(0, 0, 0.05))
        assert c.get_mesh(sid).positions == before
        c.brush_update(sid, move=(0, 0, 0.1))
        assert c.get_mesh(sid).positions != before
        c.brush_cancel(sid)


def test_set_brush_param_scale_at_nu_half_is_refused_when_set(daemon, grid):
    info, X = grid
    sid = info.session_id
    with daemon.unix_client() as c:
        c.brush_begin(sid, Brush(type="scale", center=X[0:3], radius=0.3, nu=0.3))
        with pytest.raises(DeformdError) as ei:
            c.set_brush_param(sid, "nu", 0.5)
        assert ei.value.code == E.ESINGULAR and "nu 0.5" in ei.value.message
        c.brush_update(sid, scale=0.1)   # still the nu 0.3 stroke
        c.brush_cancel(sid)


def test_begin_with_pins_on_a_2d_brush_is_refused_at_zero_load(daemon, grid):
    info, X = grid
    sid = info.session_id
    with daemon.unix_client() as c:
        for kw in ({"dim": 2}, {"moving": True}, {"mirror": (0.5, 0, 0, 1, 0, 0)}):
            b = Brush(type="grab", center=X[0:3], radius=0.3, nu=0.45,
                      pinned=[X[30:33]], **kw)
            with pytest.raises(DeformdError) as ei:
                c.brush_begin(sid, b)
            assert ei.value.code == E.EUNSUPPORTED, kw
            assert "pinned" in ei.value.message
            with pytest.raises(DeformdError) as ei:   # no stroke was opened
                c.brush_update(sid, move=(0, 0, 0.1))
            assert ei.value.code == E.ESTATE
        with pytest.raises(DeformdError) as ei:
            c.brush_begin(sid, Brush(type="grab", center=X[0:3], radius=0.3, strength=1e12))
        assert ei.value.code == E.EINVAL and "strength" in ei.value.message


# -- item 14: results not finite in float32 are refused -----------------------------------

def big_grid_obj(n: int, scale: float) -> bytes:
    """An n x n vertex grid over [0, 1]^2 x {0.5} (z varies a little) scaled by `scale`."""
    lines = []
    for j in range(n):
        for i in range(n):
            x, y = i / (n - 1), j / (n - 1)
            lines.append("v %.9e %.9e %.9e" % (scale * x, scale * y,
                                               scale * (0.5 + 0.1 * x * y)))
    for j in range(n - 1):
        for i in range(n - 1):
            a = j * n + i + 1
            lines.append("f %d %d %d" % (a, a + 1, a + n + 1))
            lines.append("f %d %d %d" % (a, a + n + 1, a + n))
    return ("\n".join(lines) + "\n").encode()


def test_move_that_would_leave_float32_range_is_refused_and_changes_nothing(daemon):
    """Coordinates near 3e38 load fine; a handle target of 6e38 is a finite double whose
    float32 displacement (3e38) is finite too, but the float32 position is +inf: before the
    fix that version was published and every later GET_MESH and brush failed."""
    data = big_grid_obj(6, 3.0e38)
    with daemon.unix_client() as c:
        info = c.load_mesh(data, fmt=".obj")
        sid = info.session_id
        try:
            before = c.get_mesh(sid).positions
            v0 = c.open_session(sid).version
            last = info.nv - 1
            c.set_handles(sid, [0, last], energy="arap")
            tgt = [[6.0e38, 0.0, before[2]], list(before[3 * last:3 * last + 3])]
            with pytest.raises(DeformdError) as ei:
                c.move_handles(sid, tgt, max_iters=5, timeout=60)
            assert ei.value.code == E.EINVAL
            assert "float32" in ei.value.message and "target 0" in ei.value.message
            assert c.open_session(sid).version == v0
            assert c.get_mesh(sid).positions == before      # the session still answers
            assert all(math.isfinite(x) for x in c.snapshot(sid).xyz)
        finally:
            c.close_session(sid)


def test_brush_on_a_mesh_near_float32_max_is_refused_and_changes_nothing(daemon):
    data = big_grid_obj(6, 3.0e38)
    with daemon.unix_client() as c:
        info = c.load_mesh(data, fmt=".obj")
        sid = info.session_id
        try:
            before = c.get_mesh(sid).positions
            with pytest.raises(DeformdError) as ei:
                c.brush_begin(sid, Brush(type="grab", center=before[0:3], move=(0, 0, 1e9),
                                         radius=1e6, nu=0.45))
            assert ei.value.code == E.EINVAL
            assert c.get_mesh(sid).positions == before
        finally:
            c.close_session(sid)


# -- item 16: flat meshes keep their third dimension; 2D sessions refuse z motion ---------

def flat_obj(n: int, two_coords: bool = False, z: float = 0.0) -> bytes:
    """An n x n grid over [0, 1]^2 as OBJ: `v x y 0.000000` lines (a flat 3D mesh, like
    woody.obj), or `v x y` (a 2D file) with two_coords."""
    lines = []
    for j in range(n):
        for i in range(n):
            x, y = i / (n - 1), j / (n - 1)
            lines.append("v %.6f %.6f" % (x, y) if two_coords else
                         "v %.6f %.6f %.6f" % (x, y, z if (i, j) == (1, 1) else 0.0))
    for j in range(n - 1):
        for i in range(n - 1):
            a = j * n + i + 1
            lines.append("f %d %d %d" % (a, a + 1, a + n + 1))
            lines.append("f %d %d %d" % (a, a + n + 1, a + n))
    return ("\n".join(lines) + "\n").encode()


def run_ctl(daemon, *args):
    p = subprocess.run([DEFORMCTL, "--socket", daemon.socket_path] + [str(a) for a in args],
                       capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)
    return p


def test_flat_grid_grab_moves_z_through_deformctl(daemon, tmp_path):
    """The issue's case: a 30x30 `v x y 0` grid, `brush --move 0,0,0.1`, `get`: z moved."""
    src = tmp_path / "flat.obj"
    src.write_bytes(flat_obj(30))
    p = run_ctl(daemon, "load", src, "--name", "flat30")
    assert p.returncode == 0, p.stderr
    sid = int(p.stdout.strip())
    try:
        with daemon.unix_client() as c:
            assert c.open_session(sid).planar == 0      # a flat 3D mesh, not a 2D one
        p = run_ctl(daemon, "brush", sid, "--type", "grab", "--center", "0.5,0.5,0",
                    "--move", "0,0,0.1", "--radius", "0.3", "--nu", "0.45")
        assert p.returncode == 0, p.stderr
        out = tmp_path / "out.obj"
        p = run_ctl(daemon, "get", sid, "--out", out)
        assert p.returncode == 0, p.stderr
        verts, _ = read_obj_positions(str(out))
        zs = [v[2] for v in verts]
        centre = verts[15 * 30 + 15]   # (15/29, 15/29): near the brush centre
        assert max(zs) > 0.05 and centre[2] > 0.05, max(zs)
    finally:
        with daemon.unix_client() as c:
            c.close_session(sid)


@pytest.mark.parametrize("energy", ["arap", "acap", "cloth"])
def test_flat_grid_handles_reach_targets_off_the_plane(daemon, energy):
    with daemon.unix_client() as c:
        info = c.load_mesh(flat_obj(30), fmt=".obj")
        sid = info.session_id
        try:
            assert info.planar == 0
            X = c.get_mesh(sid).positions
            h = [0, 29, 30 * 29, 30 * 29 + 29, 15 * 30 + 15]     # corners + centre
            tg = [list(X[3 * i:3 * i + 3]) for i in h]
            tg[-1][2] = 0.3
            c.set_handles(sid, h, energy=energy)
            r = c.move_handles(sid, tg, timeout=120)
            P = c.get_mesh(sid).positions
            for i, t in zip(h, tg):                  # every handle at its target
                assert all(abs(P[3 * i + k] - t[k]) < 1e-6 for k in range(3)), (i, t)
            nb = 15 * 30 + 16
            assert P[3 * nb + 2] > 0.05                  # the region around it followed
            test_flat_grid_handles_reach_targets_off_the_plane.objective[energy] = r.objective
            o = test_flat_grid_handles_reach_targets_off_the_plane.objective
            if "arap" in o and "acap" in o:
                assert abs(o["arap"] - o["acap"]) > 1e-6 * o["arap"]
        finally:
            c.close_session(sid)


test_flat_grid_handles_reach_targets_off_the_plane.objective = {}


def test_2d_session_refuses_z_motion_and_changes_nothing(daemon):
    with daemon.unix_client() as c:
        info = c.load_mesh(flat_obj(12, two_coords=True), fmt=".obj")   # `v x y`: 2D
        sid = info.session_id
        try:
            assert info.planar == 1
            X = c.get_mesh(sid).positions
            v0 = c.open_session(sid).version
            ctr = X[3 * 66:3 * 66 + 3]
            bad = [Brush(type="grab", center=ctr, move=(0, 0, 0.1), radius=0.3, nu=0.45),
                   Brush(type="grab", center=ctr, move=(0, 0, 0.1), radius=0.3, nu=0.45, dim=2),
                   Brush(type="twist", center=ctr, twist=(0.3, 0, 0), radius=0.3, nu=0.45),
                   Brush(type="affine", center=ctr, matrix=(0, 0, 0.1, 0, 0, 0, 0, 0, 0),
                         radius=0.3, nu=0.45),
                   Brush(type="grab", center=(ctr[0], ctr[1], 0.2), move=(0.1, 0, 0),
                         radius=0.3, nu=0.45)]
            for b in bad:
                with pytest.raises(DeformdError) as ei:
                    c.brush_begin(sid, b)
                assert ei.value.code == E.EINVAL and "2D" in ei.value.message, b
            # an in-plane stroke works, keeps z at 0; its update with z is refused
            c.brush_begin(sid, Brush(type="grab", center=ctr, move=(0.05, 0, 0), radius=0.3,
                                     nu=0.45))
            with pytest.raises(DeformdError) as ei:
                c.brush_update(sid, move=(0.05, 0, 0.1))
            assert ei.value.code == E.EINVAL and "move z" in ei.value.message
            c.brush_end(sid)
            P = c.get_mesh(sid).positions
            assert P != X and all(P[3 * i + 2] == 0.0 for i in range(info.nv))
            # handles: a target off the plane is refused, nothing changes; in the plane works
            v1 = c.open_session(sid).version
            assert v1 == v0 + 1
            h = [0, 11, 66]
            c.set_handles(sid, h, energy="arap")
            tg = [list(P[3 * i:3 * i + 3]) for i in h]
            tg[2][2] = 0.3
            with pytest.raises(DeformdError) as ei:
                c.move_handles(sid, tg, timeout=60)
            assert ei.value.code == E.EINVAL and "2D" in ei.value.message
            assert c.open_session(sid).version == v1 and c.get_mesh(sid).positions == P
            tg[2][2] = 0.0
            tg[2][0] += 0.05
            c.move_handles(sid, tg, timeout=60)
            Q = c.get_mesh(sid).positions
            assert abs(Q[3 * 66] - tg[2][0]) < 1e-6
        finally:
            c.close_session(sid)


def test_load_2d_on_request(daemon, tmp_path):
    with daemon.unix_client() as c:
        info = c.load_mesh(flat_obj(6), fmt=".obj", two_d=True)
        assert info.planar == 1
        c.close_session(info.session_id)
        with pytest.raises(DeformdError) as ei:       # z != 0 cannot be 2D
            c.load_mesh(flat_obj(6, z=0.25), fmt=".obj", two_d=True)
        assert ei.value.code == E.EFORMAT and "2D" in ei.value.message
        assert "z = 0.25" in ei.value.message
    src = tmp_path / "flat.obj"
    src.write_bytes(flat_obj(6))
    p = run_ctl(daemon, "load", src, "--2d")
    assert p.returncode == 0, p.stderr
    with daemon.unix_client() as c:
        sid = int(p.stdout.strip())
        assert c.open_session(sid).planar == 1
        c.close_session(sid)
