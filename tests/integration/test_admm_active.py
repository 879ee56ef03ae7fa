"""Active-set handle moves (issue 14 item 4, config `admm_active`): with `admm_active = 1` the
daemon's handle moves iterate only over the region the edit moves (admm.h DF_ADMM_ACTIVE); a
converged move gives the same shape as the default full solve, the rest of the mesh stays exactly
at its rest position, and the session stats report the region."""
from deformd_client import messages as m
from helpers import grid_obj

N = 30
H = 1.0 / (N - 1)                                  # grid spacing
CENTRE = (N // 2) * N + N // 2


def converge(c, params):
    info = c.load_mesh(grid_obj(N, N), fmt=".obj", name="grid")
    mesh = c.get_mesh(info.session_id, rest=True)
    rest = [tuple(mesh.rest[3 * i:3 * i + 3]) for i in range(mesh.nv)]
    handles = [j * N for j in range(N)] + [CENTRE]          # left column pinned, centre dragged
    targets = [rest[i] for i in handles[:-1]]
    x, y, z = rest[CENTRE]
    targets.append((x + 0.2 * H, y - 0.1 * H, z + 0.5 * H))
    c.set_handles(info.session_id, handles, **params)
    res = c.move_handles(info.session_id, targets, timeout=120)
    pos = c.get_mesh(info.session_id).positions
    return info, rest, res, [tuple(pos[3 * i:3 * i + 3]) for i in range(mesh.nv)]


def test_active_moves_equal_the_full_solve_and_keep_the_far_field_at_rest(make_daemon):
    # spokes-and-rims ARAP, stiffness ~ 1 per vertex: w ~ H keeps the support a few rings wide
    params = dict(w=0.5 * H, s=0.25 * H, rho=6.0, tol=1e-11, max_iters=3000)
    act_d = make_daemon("admm_active = 1\n")
    full_d = make_daemon("")
    with act_d.unix_client() as c:
        info, rest, res, pos = converge(c, params)
        st = c.stats(info.session_id)
    with full_d.unix_client() as c:
        finfo, frest, fres, fpos = converge(c, params)
        fst = c.stats(finfo.session_id)
    assert res.status == fres.status == m.MOVE_CONVERGED, (res, fres)
    assert rest == frest
    nv = len(rest)
    assert st["admm.active"] == 1 and st["admm.active_runs"] >= 1, st
    assert st["admm.active_fallbacks"] == 0, st
    region = st["admm.active_region_vertices"]
    assert 0 < st["admm.active_support"] <= region < nv / 2, st
    assert fst["admm.active"] == 0 and fst["admm.active_runs"] == 0, fst
    # same shape (float32 positions on the wire)
    worst = max(abs(a - b) for i in range(nv) for a, b in zip(pos[i], fpos[i]))
    assert worst < 1e-6, worst
    moved = max(abs(a - b) for a, b in zip(pos[CENTRE], rest[CENTRE]))
    assert moved > 0.4 * H, moved
    # outside the region nothing moved at all; the full solve's far field is at rest only up to
    # round-off, so at least as many of its vertices differ from rest
    at_rest = sum(1 for i in range(nv) if pos[i] == rest[i])
    assert at_rest >= nv - region, (at_rest, nv, region)
    assert sum(1 for i in range(nv) if fpos[i] == frest[i]) <= at_rest
