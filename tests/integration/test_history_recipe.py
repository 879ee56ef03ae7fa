"""Undo history kept as stroke recipes (server/session/history.h): a stroke that began from the
last committed state is one RECIPE step (its request, replayed on undo from a checkpoint and
checked against a checksum); anything else (a pair of interleaved strokes, a handle move) an XOR
step. Undo and redo must give back exactly the positions GET_MESH returned at each committed
state, whichever kind of step lies between, across checkpoints, and the stats count the steps,
checkpoints and replays."""
import pytest

from deformd_client import Brush, DeformdError, errors as E
from helpers import grid_obj


def positions(c, sid) -> bytes:
    return c.get_mesh(sid).positions.tobytes()


def stroke_brush(k: int, **kw) -> Brush:
    return Brush(center=(0.2 + 0.07 * k, 0.3 + 0.05 * k, 0.0), move=(0.01, -0.005, 0.02 * k),
                 radius=0.15, nu=0.4, **kw)


@pytest.mark.parametrize("replay_ms", [0, 250])
def test_undo_redo_over_recipe_and_xor_steps_is_exact(make_daemon, replay_ms):
    """replay_ms 0: a checkpoint at every stroke (undo crosses checkpoints); 250: one checkpoint
    for this small mesh (undo replays from it)."""
    d = make_daemon("history_replay_ms = %d\n" % replay_ms)
    with d.unix_client() as a, d.unix_client() as b:
        sid = a.load_mesh(grid_obj(30, 30), fmt=".obj", name="recipes").session_id
        shots = [positions(a, sid)]
        kinds = []
        for k in range(3):                       # three plain strokes: recipes
            a.stroke(sid, stroke_brush(k))
            shots.append(positions(a, sid))
            kinds.append("recipe")
        # a pinned stroke (pins are part of the recipe)
        a.stroke(sid, stroke_brush(3, pinned=[(0.9, 0.9, 0.0), (0.1, 0.9, 0.0)]))
        shots.append(positions(a, sid))
        kinds.append("recipe")
        s = a.stats(sid)
        assert (s["history_recipe_steps"], s["history_xor_steps"]) == (4, 0), s
        assert s["history_checkpoints"] >= 1
        # an interleaved pair: each stroke's base includes the other's uncommitted motion
        a.brush_begin(sid, stroke_brush(4))
        b.brush_begin(sid, stroke_brush(5))
        a.brush_update(sid, move=(0.0, 0.01, 0.03))
        b.brush_update(sid, move=(0.01, 0.0, -0.02))
        a.brush_end(sid)                         # commits both strokes' motion so far
        shots.append(positions(a, sid))
        kinds.append("xor")
        b.brush_update(sid, move=(0.02, 0.0, -0.03))
        b.brush_end(sid)
        shots.append(positions(a, sid))
        kinds.append("xor")
        # a handle move between strokes: an XOR step, and the next stroke a recipe again
        X = a.get_mesh(sid).positions
        a.set_handles(sid, [0, 29, 870])
        a.move_handles(sid, [(X[0], X[1], X[2] + 0.05), (X[87], X[88], X[89]),
                             (X[2610], X[2611], X[2612])], max_iters=20)
        shots.append(positions(a, sid))
        kinds.append("xor")
        a.stroke(sid, stroke_brush(6))
        shots.append(positions(a, sid))
        kinds.append("recipe")
        assert len(set(shots)) == len(shots)     # every change changed something
        s = a.stats(sid)
        assert s["history_recipe_steps"] == kinds.count("recipe") == 5, s
        assert s["history_xor_steps"] == kinds.count("xor") == 3, s
        assert s["undo_depth"] == len(kinds)
        assert 0 < s["history_undo_bytes"] < s["history_bytes"]
        checkpoints = s["history_checkpoints"]
        if replay_ms == 0:
            assert checkpoints >= 4              # one per recipe step after the first
        replays0 = s["history_replays"]
        for k in range(len(kinds) - 1, -1, -1):  # undo everything
            a.undo(sid)
            assert positions(b, sid) == shots[k], "undo to state %d" % k
        with pytest.raises(DeformdError) as ei:
            a.undo(sid)
        assert ei.value.code == E.ESTATE
        s = a.stats(sid)
        assert s["history_replays"] > replays0   # undoing below a recipe replays it
        for k in range(1, len(kinds) + 1):       # redo everything
            a.redo(sid)
            assert positions(b, sid) == shots[k], "redo to state %d" % k
        s = a.stats(sid)
        assert s["history_replay_mismatches"] == 0
        assert s["history_recipe_steps"] == 5 and s["history_xor_steps"] == 3
        # undo twice then a new stroke: the redo tail goes, the undo below still exact
        a.undo(sid)
        a.undo(sid)
        a.stroke(sid, stroke_brush(7))
        s = a.stats(sid)
        assert s["redo_depth"] == 0 and s["undo_depth"] == len(kinds) - 1
        a.undo(sid)
        assert positions(a, sid) == shots[len(kinds) - 2]
        a.undo(sid)
        assert positions(a, sid) == shots[len(kinds) - 3]


def test_a_cancelled_then_new_stroke_and_an_undo_during_a_stroke(make_daemon):
    """A cancelled stroke commits nothing; the next stroke from the same state is a recipe.
    Undo while a stroke is open is refused (ESTATE) and changes nothing."""
    d = make_daemon("")
    with d.unix_client() as c:
        sid = c.load_mesh(grid_obj(20, 20), fmt=".obj", name="cancel").session_id
        s0 = positions(c, sid)
        c.brush_begin(sid, stroke_brush(1))
        c.brush_cancel(sid)
        assert positions(c, sid) == s0
        c.stroke(sid, stroke_brush(2))
        s1 = positions(c, sid)
        c.brush_begin(sid, stroke_brush(3))
        with pytest.raises(DeformdError) as ei:
            c.undo(sid)
        assert ei.value.code == E.ESTATE
        c.brush_end(sid)
        s = c.stats(sid)
        assert (s["history_recipe_steps"], s["history_xor_steps"]) == (2, 0), s
        c.undo(sid)
        assert positions(c, sid) == s1
        c.undo(sid)
        assert positions(c, sid) == s0


def test_checkpoints_packed_against_the_rest_shape_across_a_reset_rest(make_daemon):
    """The undo checkpoints are packed against the session's rest shape (history.h): with a
    checkpoint at every stroke, undo/redo give back exactly the states GET_MESH returned, before
    and after a reset-rest (which makes the current positions the rest shape and clears the
    history), and the undo history holds less than full copies of its checkpoints would."""
    d = make_daemon("history_replay_ms = 0\n")
    with d.unix_client() as c:
        nv = 30 * 30
        sid = c.load_mesh(grid_obj(30, 30), fmt=".obj", name="packed").session_id
        for phase in range(2):
            shots = [positions(c, sid)]
            for k in range(4):
                c.stroke(sid, stroke_brush(k + 4 * phase))
                shots.append(positions(c, sid))
            assert len(set(shots)) == len(shots)
            s = c.stats(sid)
            assert s["history_recipe_steps"] == 4 and s["history_checkpoints"] >= 4, s
            # the newest checkpoint packed: less than its full copy (24 bytes per vertex)
            assert 0 < s["history_anchor_bytes"] < 24 * nv, s
            assert s["history_anchor_bytes"] < s["history_undo_bytes"], s
            for k in range(3, -1, -1):
                c.undo(sid)
                assert positions(c, sid) == shots[k], "phase %d undo to %d" % (phase, k)
            for k in range(1, 5):
                c.redo(sid)
                assert positions(c, sid) == shots[k], "phase %d redo to %d" % (phase, k)
            assert c.stats(sid)["history_replay_mismatches"] == 0
            c.reset_rest(sid)                    # rest = current; undo/redo cleared
            s = c.stats(sid)
            assert s["undo_depth"] == 0 and s["redo_depth"] == 0, s
            assert positions(c, sid) == shots[4]
