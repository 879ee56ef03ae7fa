"""Issue 14 item 2: HANDLES_MOVE with the option bit POLISH polishes the ADMM result by projected
Newton (core/admm/admm.h df_admm_polish): on a tet cube (bottom fixed, top shifted) the polished
move converges to a KKT residual below 1e-9 with an objective no higher than the same ADMM budget
without the option on a second session (and than a 40x longer plain move), the Newton steps
counted in its iterations, the handles on their targets; a triangle session refuses the bit
(EUNSUPPORTED, nothing changed), HANDLES_SET refuses it (EPROTO_RESERVED)."""
import pytest

from deformd_client import DeformdError, messages as m
from helpers import grid_obj
from test_compute import cube_session


# the ADMM budget: short enough that the plain move has not converged (the adaptive penalty
# brings ARAP here to round-off within 50 iterations, where a polish has nothing left to gain)
@pytest.mark.parametrize("energy,budget", [("neohookean", 50), ("arap", 10)])
def test_polished_move_reaches_the_kkt_target(daemon, energy, budget):
    with daemon.unix_client() as c:
        a, handles, targets = cube_session(c, n=4, name="plain")
        b, _, _ = cube_session(c, n=4, name="polish")
        for s in (a, b):
            c.set_handles(s, handles, energy=energy, tol=0.0, max_iters=budget)
        plain = c.move_handles(a, targets)
        pol = c.move_handles(b, targets, polish=True)
        print("%s: plain %d iterations E %.12g res %.3g; polished %d iterations E %.12g KKT %.3g"
              % (energy, plain.iterations, plain.objective, plain.residual, pol.iterations,
                 pol.objective, pol.residual))
        assert plain.status_name == "budget" and plain.iterations == budget
        assert plain.residual > 1e-9             # the plain move is not at the KKT target
        assert pol.status_name == "converged"
        assert pol.residual < 1e-9
        assert pol.iterations > budget           # the ADMM budget plus its Newton steps
        assert pol.objective < plain.objective
        longer = c.move_handles(a, targets, max_iters=2000)   # continues from the plain result
        assert pol.objective <= longer.objective * (1 + 1e-12)
        P = c.get_mesh(b).positions
        for h, t in zip(handles, targets):
            assert max(abs(P[3 * h + k] - t[k]) for k in range(3)) < 1e-5   # float32 positions
        c.close_session(a)
        c.close_session(b)


def test_polish_on_a_triangle_mesh_is_refused(daemon):
    with daemon.unix_client() as c:
        sid = c.load_mesh(grid_obj(6, 6), fmt=".obj").session_id
        c.set_handles(sid, [0, 35])
        v0 = c.get_mesh(sid).version
        with pytest.raises(DeformdError) as e:
            c.move_handles(sid, [(0, 0, 0), (1.2, 1.0, 0.1)], polish=True)
        assert e.value.name == "EUNSUPPORTED" and "POLISH" in e.value.message
        assert c.get_mesh(sid).version == v0    # nothing changed
        c.close_session(sid)


def test_the_polish_bit_is_refused_in_handles_set(daemon):
    with daemon.unix_client() as c:
        sid, handles, _ = cube_session(c, n=3)
        p = m.HandleParams.for_energy("arap")
        with pytest.raises(DeformdError) as e:
            c._one(m.HANDLES_SET, m.encode_handles(sid, "arap", handles, p, [],
                                                   int(m.WorkOpt.POLISH)))
        assert e.value.name == "EPROTO_RESERVED"
        with pytest.raises(DeformdError):
            c.get_handles(sid)   # nothing changed: still no handle set
        c.close_session(sid)
