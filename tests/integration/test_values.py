"""Bad values and flat meshes (issue 9 items 14, 15, 16): brush knobs validated when set,
results that would not be finite in float32 refused, flat 3D meshes deformed in 3D and 2D
sessions refusing z motion. Every refusal must leave the session unchanged."""
import math

import pytest

from deformd_client import Brush, DeformdError, errors as E
from helpers import grid_obj, obj_bytes_positions

GRID_N = 12


@pytest.fixture
def grid(daemon):
    data = grid_obj(GRID_N, GRID_N)
    with daemon.unix_client() as c:
        info = c.load_mesh(data, fmt=".obj", name="")
    yield info, obj_bytes_positions(data)
    with daemon.unix_client() as c:
        try:
            c.close_session(info.session_id)
        except DeformdError:
            pass


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
