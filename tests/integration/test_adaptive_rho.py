"""Handle moves with no rho (rho 0 on the wire: the solver's adaptive penalty, core/admm/admm.h
DF_ADMM_RHO_RULE) converge through the daemon, to the objective of a long fixed-penalty run of the
same problem in another session; deformctl `handles` without --rho does the same."""
import math
import subprocess

from conftest import DEFORMCTL
from deformd_client import messages as m
from helpers import tet_grid, tet_grid_medit

N = 5
W, S = 1e-3, 0.02


def _setup(pts):
    bottom = [i for i, p in enumerate(pts) if p[2] == 0.0]
    top = [i for i, p in enumerate(pts) if p[2] == 1.0]
    targets = [pts[i] for i in bottom] + [(p[0] + 0.25, p[1], p[2] + 0.1)
                                          for p in (pts[i] for i in top)]
    return bottom + top, targets


def _move(c, name, handles, targets, iters, **params):
    sid = c.load_mesh(tet_grid_medit(N), fmt=".mesh", name=name).session_id
    c.set_handles(sid, handles, energy="arap", w=W, s=S, max_iters=iters, **params)
    res = c.move_handles(sid, targets, timeout=600)
    return sid, res


def _ctl_handles(daemon, sid, hfile, *extra):
    """deformctl `handles` on session sid: ARAP, the handles of hfile, W, S, then extra; it must
    succeed."""
    p = subprocess.run([DEFORMCTL, "--socket", daemon.socket_path, "handles", str(sid),
                        "--energy", "arap", "--handles", str(hfile), "--w", str(W),
                        "--s", str(S), *extra],
                       capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)
    assert p.returncode == 0, p.stderr


def test_move_without_rho_converges_to_the_fixed_penalty_objective(daemon):
    pts, _ = tet_grid(N)
    handles, targets = _setup(pts)
    with daemon.unix_client() as c:
        # the reference: a fixed penalty (10 w / s), no early stop, a long budget
        ref_sid, ref = _move(c, "rho-ref", handles, targets, 3000, rho=10 * W / S, tol=0.0)
        assert ref.status == m.MOVE_BUDGET and ref.iterations == 3000
        # the defaults: no rho (0 on the wire), the default tolerance
        sid, res = _move(c, "rho-adaptive", handles, targets, 3000)
        hs = c.get_handles(sid)
        assert hs.params.rho == 0.0          # the set keeps "adaptive", as sent
        assert res.status == m.MOVE_CONVERGED, res
        assert res.iterations < 3000
        assert math.isfinite(res.objective) and ref.objective > 0
        assert res.objective <= ref.objective * (1 + 1e-6)
        assert res.objective >= ref.objective * (1 - 1e-3)
        mesh = c.get_mesh(sid)
        for h, t in zip(handles, targets):
            for k in range(3):
                assert abs(mesh.positions[3 * h + k] - t[k]) < 1e-5  # float32 positions
        c.close_session(sid)
        c.close_session(ref_sid)


def test_deformctl_handles_without_rho_sends_zero(daemon, tmp_path):
    """deformctl `handles` with no --rho sends rho 0 (adaptive); a move then converges; an
    explicit --rho is kept as given."""
    pts, _ = tet_grid(N)
    handles, targets = _setup(pts)
    hfile = tmp_path / "h.txt"
    hfile.write_text("".join("%d\n" % h for h in handles))
    with daemon.unix_client() as c:
        sid = c.load_mesh(tet_grid_medit(N), fmt=".mesh", name="rho-ctl").session_id
        _ctl_handles(daemon, sid, hfile, "--iters", "3000")
        assert c.get_handles(sid).params.rho == 0.0
        res = c.move_handles(sid, targets, timeout=600)
        assert res.status == m.MOVE_CONVERGED and res.iterations < 3000, res
        _ctl_handles(daemon, sid, hfile, "--rho", "0.5")
        assert c.get_handles(sid).params.rho == 0.5
        c.close_session(sid)
