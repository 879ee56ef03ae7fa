"""Issue 14 item 5: HANDLES_MOVE with the option bit KELVINLET_GUESS starts the solver from the
Kelvinlet field of the handles' move: on a tet cube (bottom fixed, top shifted) the move converges
with the handles on their targets, to the objective of the same move without the option on a
second session (within the solver tolerance); the bit is refused in HANDLES_SET."""
import pytest

from deformd_client import DeformdError, messages as m
from test_compute import cube_session


def test_move_with_the_kelvinlet_guess_reaches_the_plain_objective(daemon):
    with daemon.unix_client() as c:
        a, handles, targets = cube_session(c, n=4, name="plain")
        b, _, _ = cube_session(c, n=4, name="guess")
        for s in (a, b):
            c.set_handles(s, handles, max_iters=20000)
        plain = c.move_handles(a, targets)
        guess = c.move_handles(b, targets, kelvinlet_guess=True)
        print("plain %d iterations E %.12g; guess %d iterations E %.12g"
              % (plain.iterations, plain.objective, guess.iterations, guess.objective))
        assert plain.status_name == "converged" and guess.status_name == "converged"
        assert abs(guess.objective - plain.objective) / (plain.objective + 1) < 1e-8
        P = c.get_mesh(b).positions
        for h, t in zip(handles, targets):
            assert max(abs(P[3 * h + k] - t[k]) for k in range(3)) < 1e-5   # float32 positions
        c.close_session(a)
        c.close_session(b)


def test_the_guess_bit_is_refused_in_handles_set(daemon):
    with daemon.unix_client() as c:
        sid, handles, _ = cube_session(c, n=3)
        p = m.HandleParams.for_energy("arap")
        with pytest.raises(DeformdError):
            c._one(m.HANDLES_SET, m.encode_handles(sid, "arap", handles, p, [],
                                                   int(m.WorkOpt.KELVINLET_GUESS)))
        with pytest.raises(DeformdError):
            c.get_handles(sid)   # nothing changed: still no handle set
        c.close_session(sid)
