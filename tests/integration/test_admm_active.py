"""Active-set handle moves (issue 14 item 4, config `admm_active`): with `admm_active = 1` (or 2,
with the tail test) the
daemon's handle moves iterate only over the region the edit moves (admm.h DF_ADMM_ACTIVE); a
converged move gives the same shape as the default full solve, the rest of the mesh stays exactly
at its rest position, and the session stats report the region."""
import pytest

from deformd_client import messages as m
from helpers import grid_obj

def converge(c, n, params):
    """Loads an n x n grid (spacing 1 / (n - 1)), pins its left column, drags its centre vertex
    by a fraction of a grid spacing and converges; returns the load info, rest and final
    positions and the move's reply."""
    h = 1.0 / (n - 1)
    centre = (n // 2) * n + n // 2
    info = c.load_mesh(grid_obj(n, n), fmt=".obj", name="grid")
    mesh = c.get_mesh(info.session_id, rest=True)
    rest = [tuple(mesh.rest[3 * i:3 * i + 3]) for i in range(mesh.nv)]
    handles = [j * n for j in range(n)] + [centre]          # left column pinned, centre dragged
    targets = [rest[i] for i in handles[:-1]]
    x, y, z = rest[centre]
    targets.append((x + 0.2 * h, y - 0.1 * h, z + 0.5 * h))
    c.set_handles(info.session_id, handles, **params)
    res = c.move_handles(info.session_id, targets, timeout=120)
    pos = c.get_mesh(info.session_id).positions
    return info, rest, res, [tuple(pos[3 * i:3 * i + 3]) for i in range(mesh.nv)]


# mode 2 adds the tail test (admm.h DF_ADMM_ACTIVE_TAIL), whose region is larger: a larger grid
# keeps it under half the mesh (above that the run falls back to the full solve)
@pytest.mark.parametrize("mode,n", [(1, 30), (2, 60)])
def test_active_moves_equal_the_full_solve_and_keep_the_far_field_at_rest(make_daemon, mode, n):
    # spokes-and-rims ARAP, stiffness ~ 1 per vertex: w ~ h keeps the support a few rings wide
    h = 1.0 / (n - 1)
    centre = (n // 2) * n + n // 2
    params = dict(w=0.5 * h, s=0.25 * h, rho=6.0, tol=1e-11, max_iters=3000)
    act_d = make_daemon("admm_active = %d\n" % mode)
    full_d = make_daemon("")
    with act_d.unix_client() as c:
        info, rest, res, pos = converge(c, n, params)
        st = c.stats(info.session_id)
    with full_d.unix_client() as c:
        finfo, frest, fres, fpos = converge(c, n, params)
        fst = c.stats(finfo.session_id)
    assert res.status == fres.status == m.MOVE_CONVERGED, (res, fres)
    assert rest == frest
    nv = len(rest)
    assert st["admm.active"] == mode and st["admm.active_runs"] >= 1, st
    assert (st["admm.active_tail_grows"] > 0) == (mode == 2), st
    assert st["admm.active_fallbacks"] == 0, st
    region = st["admm.active_region_vertices"]
    assert 0 < st["admm.active_support"] <= region < nv / 2, st
    assert fst["admm.active"] == 0 and fst["admm.active_runs"] == 0, fst
    # same shape (float32 positions on the wire)
    worst = max(abs(a - b) for i in range(nv) for a, b in zip(pos[i], fpos[i]))
    assert worst < 1e-6, worst
    moved = max(abs(a - b) for a, b in zip(pos[centre], rest[centre]))
    assert moved > 0.4 * h, moved
    # outside the region nothing moved at all; the full solve's far field is at rest only up to
    # round-off, so at least as many of its vertices differ from rest
    at_rest = sum(1 for i in range(nv) if pos[i] == rest[i])
    assert at_rest >= nv - region, (at_rest, nv, region)
    assert sum(1 for i in range(nv) if fpos[i] == frest[i]) <= at_rest
