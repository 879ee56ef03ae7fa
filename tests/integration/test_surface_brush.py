"""Surface-aware brushes (issue 14 item 7) through the real daemon: two close, disconnected
sheets (0.05 apart, brush radius 0.25 on one of them). With `surface` the untouched sheet stays
exactly at rest (its float32 positions are the loaded ones, bit for bit) while the grabbed one
moves; without it the other sheet moves too. `deformctl brush --surface` gives the same bits as
the Python client; a bad surface byte is refused and changes nothing; a stroke repeated at the
same place after an undo (its distances over the rest mesh then come from the session's cache)
gives the bits of the first."""
import struct

import pytest

from conftest import DEFORMCTL  # noqa: F401  (the fixtures build it)
from deformd_client import Brush, DeformdError
from deformd_client import messages as m
from helpers import obj_bytes_positions
from test_brush_state import run_ctl

N = 9                       # vertices per sheet side
GAP = 0.05
CENTER = (0.5, 0.5, 0.0)
MOVE = (0.0, 0.0, 0.1)


def two_sheets_obj() -> bytes:
    """Two N x N sheets over [0, 1]^2 at z = 0 and z = GAP, sharing no element."""
    lines = ["# two disconnected sheets"]
    for s in range(2):
        for j in range(N):
            for i in range(N):
                lines.append("v %.6f %.6f %.6f" % (i / (N - 1), j / (N - 1), s * GAP))
    for s in range(2):
        o = s * N * N
        for j in range(N - 1):
            for i in range(N - 1):
                a = o + j * N + i + 1
                lines.append("f %d %d %d" % (a, a + 1, a + N + 1))
                lines.append("f %d %d %d" % (a, a + N + 1, a + N))
    return ("\n".join(lines) + "\n").encode()


def after(daemon, stroke) -> tuple:
    """(loaded positions, positions after stroke(client, sid)) of a fresh two-sheet session,
    as float32 bytes per sheet: ((rest0, rest1), (now0, now1))."""
    data = two_sheets_obj()
    rest = obj_bytes_positions(data).tobytes()
    with daemon.unix_client() as c:
        sid = c.load_mesh(data, fmt=".obj", name="").session_id
        try:
            stroke(c, sid)
            now = c.get_mesh(sid).positions.tobytes()
        finally:
            c.close_session(sid)
    half = len(rest) // 2
    return (rest[:half], rest[half:]), (now[:half], now[half:])


def brush(surface):
    return Brush(center=CENTER, move=MOVE, radius=0.25, nu=0.45, falloff=2, surface=surface)


def test_disconnected_sheet_stays_at_rest_only_with_the_mask(daemon):
    (r0, r1), (a0, a1) = after(daemon, lambda c, sid: c.stroke(sid, brush(1)))
    assert a1 == r1                     # the other sheet: exactly at rest
    assert a0 != r0                     # the grabbed one moved
    (r0, r1), (b0, b1) = after(daemon, lambda c, sid: c.stroke(sid, brush(None)))
    assert b1 != r1                     # without the mask the other sheet moves
    assert b0 == a0                     # on the grabbed (flat) sheet the mask is 1: same bits


def test_deformctl_surface_equals_the_python_client(daemon):
    def ctl(c, sid):
        run_ctl(daemon, "brush", sid, "--type", "grab", "--center", "0.5,0.5,0",
                "--move", "0,0,0.1", "--radius", "0.25", "--nu", "0.45", "--falloff", "2",
                "--surface")

    def py(c, sid):
        c.stroke(sid, brush(1))

    assert after(daemon, ctl) == after(daemon, py)


def test_cached_distances_give_the_same_stroke(daemon):
    def twice(c, sid):
        c.stroke(sid, brush(1))
        c.undo(sid)                     # back to the loaded positions
        c.stroke(sid, brush(1))

    def once(c, sid):
        c.stroke(sid, brush(1))

    assert after(daemon, twice)[1] == after(daemon, once)[1]


def test_bad_surface_byte_is_refused(daemon):
    with daemon.unix_client() as c:
        sid = c.load_mesh(two_sheets_obj(), fmt=".obj", name="").session_id
        body = m.encode_brush(sid, brush(1))
        assert len(body) == 253 + 2 + 4 + 1 and body[-1] == 1
        for bad, name in ((body[:-1] + b"\x02", "EINVAL"), (body + b"\x00", "EPROTO_TRAILING")):
            with pytest.raises(DeformdError) as e:
                c._one(m.BRUSH_BEGIN, bad)
            assert e.value.name == name, bad[-3:]
        assert c.open_session(sid).version == 0
        assert struct.unpack("<H", body[253:255]) == (0,)     # use_session sent as 0
        c.close_session(sid)
