"""The session brush (issue 11, PROTOCOL.md 4.14a-c) through the real daemon: BRUSH_STATE_GET /
BRUSH_STATE_SET, the BRUSH_STATE event with its origin, refusals that change nothing, strokes
that take fields from the session brush (bit-identical to the same values given explicitly),
old-format BRUSH_BEGIN bodies, and `deformctl brush-state` / `deformctl watch`."""
import json
import math
import struct
import subprocess

import pytest

from conftest import DEFORMCTL
from deformd_client import (Brush, BrushStateField, Client, DeformdError, Origin, brush_state,
                            schema)
from deformd_client import messages as m
from helpers import grid_session

BS = BrushStateField
EVENT_WAIT_S = 30.0          # a guard only: the event is awaited, never timed
CENTER = (0.5, 0.5, 0.0)     # the middle of grid_obj's unit square (z = 0)
MOVE = (0.0, 0.05, 0.08)


def brush_event(c: Client):
    """The next event of `c`, which must be a brush_state event."""
    ev = c.next_event(EVENT_WAIT_S)
    assert ev is not None and ev.kind_name == "brush_state", ev
    return ev


def raw_set(c: Client, sid: int, mask: int, **vals) -> bytes:
    """A BRUSH_STATE_SET body built by hand (the Python encoder would refuse bad values
    locally): the defaults with `vals` (type/integrator as wire numbers) replaced."""
    v = dict(type=1, falloff=1, integrator=1, has_mirror=0, steps=1, radius=1.0, nu=0.5,
             strength=1.0, ratio=1.1, point=(0.0, 0.0, 0.0), normal=(1.0, 0.0, 0.0))
    v.update(vals)
    body = struct.pack("<QHBBBBH4d3d3d", sid, mask, v["type"], v["falloff"], v["integrator"],
                       v["has_mirror"], v["steps"], v["radius"], v["nu"], v["strength"],
                       v["ratio"], *v["point"], *v["normal"])
    assert len(body) == 96
    return c._one(m.BRUSH_STATE_SET, body)


def test_get_returns_the_defaults(daemon):
    with grid_session(daemon, 3) as (info, _), daemon.unix_client() as c:
        s = c.brush_state_get(info.session_id)
    d = schema.BRUSH_DEFAULTS
    assert (s.session_id, s.seq, s.changed, s.origin, s.origin_id, s.origin_name) == (
        info.session_id, 0, 0, Origin.NONE, 0, "")
    assert s.type == d["type"].name.lower() and s.integrator == d["integrator"].name.lower()
    assert (s.radius, s.nu, s.strength, s.falloff, s.ratio, s.steps) == (
        d["radius"], d["nu"], d["strength"], d["falloff"], d["ratio"], d["steps"])
    assert s.mirror is None and s.values.mirror_normal == (1.0, 0.0, 0.0)


def test_set_is_broadcast_with_the_changer_as_origin(daemon):
    with grid_session(daemon, 3) as (info, _), \
            Client.connect_unix(daemon.socket_path, name="knob-panel") as a, \
            Client.connect_unix(daemon.socket_path, name="viewer") as b:
        sid = info.session_id
        b.subscribe(sid)
        before = a.open_session(sid)
        reply = a.brush_state_set(sid, radius=0.25, nu=0.45)
        ev = brush_event(b)
        assert ev.origin == Origin.CLIENT and ev.origin_name == "knob-panel"
        assert ev.origin_id == reply.origin_id and ev.seq == reply.seq == 1
        assert ev.changed == reply.changed == BS.RADIUS | BS.NU
        assert (ev.radius, ev.nu) == (0.25, 0.45) and ev.values == reply.values
        assert ev.strength == schema.BRUSH_DEFAULTS["strength"]      # the others untouched
        # from the other client: its own connection id and name
        b.brush_state_set(sid, falloff=3, ratio=1.5, mirror=(0, 0, 0, 1, 0, 0))
        ev2 = brush_event(b)
        assert ev2.origin_name == "viewer" and ev2.origin_id != ev.origin_id and ev2.seq == 2
        assert ev2.changed == BS.FALLOFF | BS.RATIO | BS.MIRROR and ev2.radius == 0.25
        assert ev2.mirror == (0, 0, 0, 1, 0, 0)
        # a brush change is no mesh change: same version, same undo depth, no displacement
        after = a.open_session(sid)
        assert (after.version, after.undo_depth) == (before.version, before.undo_depth)
        g = a.brush_state_get(sid)
        assert g.seq == 2 and g.changed == 0 and g.origin_name == "viewer"
        assert g.values == ev2.values
        assert a.stats(sid)["brush.seq"] == 2


BAD = [  # (mask, raw values, error name)
    (BS.RADIUS, dict(radius=0.0), "EINVAL"),
    (BS.RADIUS, dict(radius=math.nan), "EINVAL"),
    (BS.RADIUS, dict(radius=1e7), "EINVAL"),          # the engine's radius range
    (BS.NU, dict(nu=0.9), "EINVAL"),                  # outside [-1, 0.5]
    (BS.NU, dict(nu=math.nan), "EINVAL"),
    (BS.STRENGTH, dict(strength=2e6), "EINVAL"),      # |strength| <= 1e6
    (BS.STRENGTH, dict(strength=math.inf), "EINVAL"),
    (BS.FALLOFF, dict(falloff=9), "EINVAL"),
    (BS.FALLOFF, dict(falloff=0), "EINVAL"),
    (BS.RATIO, dict(ratio=1.0), "EINVAL"),
    (BS.TYPE, dict(type=6), "EINVAL"),
    (BS.INTEGRATOR, dict(integrator=3), "EINVAL"),
    (BS.INTEGRATOR, dict(steps=0), "EINVAL"),
    (BS.INTEGRATOR, dict(steps=1025), "EINVAL"),
    (BS.MIRROR, dict(has_mirror=1, normal=(0.0, 0.0, 0.0)), "EINVAL"),
    (BS.MIRROR, dict(has_mirror=2), "EINVAL"),
    (BS.RADIUS | BS.NU, dict(radius=0.3, nu=0.9), "EINVAL"),   # one good, one bad field
    (0, dict(), "EINVAL"),
    (0x100, dict(), "EPROTO_RESERVED"),
]


def test_invalid_values_are_refused_and_change_nothing(daemon):
    with grid_session(daemon, 3) as (info, _), daemon.unix_client() as a, \
            daemon.unix_client() as b:
        sid = info.session_id
        b.subscribe(sid)
        a.brush_state_set(sid, radius=0.5)
        assert brush_event(b).seq == 1
        before = a.brush_state_get(sid)
        for mask, vals, name in BAD:
            with pytest.raises(DeformdError) as e:
                raw_set(a, sid, mask, **vals)
            assert e.value.name == name, (mask, vals, e.value)
        with pytest.raises(DeformdError) as e:
            a._one(m.BRUSH_STATE_SET, struct.pack("<QH", sid, int(BS.RADIUS)))  # truncated
        assert e.value.name == "EPROTO_TRUNCATED"
        with pytest.raises(DeformdError) as e:
            a.brush_state_set(987654321, radius=0.5)
        assert e.value.name == "ENOTFOUND"
        after = a.brush_state_get(sid)
        assert after == before and after.seq == 1 and after.radius == 0.5
        # no event was sent for any refusal: the next one b receives is the next change
        a.brush_state_set(sid, nu=0.25)
        ev = brush_event(b)
        assert ev.seq == 2 and ev.nu == 0.25 and ev.radius == 0.5
        assert b.pending_events() == 0


SESSION_FIELDS = dict(type="grab", radius=0.3, nu=0.2, strength=0.5, falloff=2, ratio=1.5,
                      integrator="rk4", steps=3)


def positions_after(daemon, strokes) -> bytes:
    """Positions (float32 bytes) of a fresh 6 x 6 grid after `strokes(client, sid)`."""
    with grid_session(daemon, 6) as (info, _), daemon.unix_client() as c:
        strokes(c, info.session_id)
        return c.get_mesh(info.session_id).positions.tobytes()


def test_stroke_with_use_session_equals_the_explicit_values(daemon):
    def from_session(c, sid):
        c.brush_state_set(sid, **SESSION_FIELDS)
        # the message's own values are the defaults: every field comes from the session brush
        c.stroke(sid, Brush(center=CENTER, move=MOVE, moving=True, use_session=sum(BS)))
        assert c.open_session(sid).version == 1     # the brush state added no version

    def explicit(c, sid):
        c.stroke(sid, Brush(center=CENTER, move=MOVE, moving=True, **SESSION_FIELDS))

    def defaults(c, sid):
        c.stroke(sid, Brush(center=CENTER, move=MOVE, moving=True))

    a, b = positions_after(daemon, from_session), positions_after(daemon, explicit)
    assert a == b                                    # bit-identical
    assert a != positions_after(daemon, defaults)    # the session values made a difference


def test_use_session_takes_only_the_named_fields_as_of_the_begin(daemon):
    def partial(c, sid):
        c.brush_state_set(sid, radius=0.3, nu=0.2, falloff=3)
        c.brush_begin(sid, Brush(center=CENTER, radius=0.7, nu=0.4, falloff=2,
                                 use_session=BS.RADIUS | BS.NU))
        c.brush_state_set(sid, radius=0.9)           # an open stroke keeps what it took
        c.brush_update(sid, move=MOVE)
        c.brush_end(sid)

    def explicit(c, sid):
        c.brush_begin(sid, Brush(center=CENTER, radius=0.3, nu=0.2, falloff=2))
        c.brush_update(sid, move=MOVE)
        c.brush_end(sid)

    assert positions_after(daemon, partial) == positions_after(daemon, explicit)


def test_old_format_brush_begin_still_works(daemon):
    old = Brush(center=CENTER, move=MOVE, radius=0.4, nu=0.3)
    body_len = len(m.encode_brush(1, old))
    assert body_len == 253                           # no use_session trailer: the old layout

    def old_style(c, sid):
        c.brush_state_set(sid, radius=0.9, nu=-0.5)   # ignored: the body names no field
        c.stroke(sid, old)

    def fresh(c, sid):
        c.stroke(sid, old)

    assert positions_after(daemon, old_style) == positions_after(daemon, fresh)
    with grid_session(daemon, 3) as (info, _), daemon.unix_client() as c:
        bad = m.encode_brush(info.session_id, old) + b"\x00"     # one byte of a trailer
        with pytest.raises(DeformdError) as e:
            c._one(m.BRUSH_BEGIN, bad)
        assert e.value.name == "EPROTO_TRUNCATED"
        bad = m.encode_brush(info.session_id, Brush(center=CENTER, use_session=0x100))
        with pytest.raises(DeformdError) as e:
            c._one(m.BRUSH_BEGIN, bad)
        assert e.value.name == "EPROTO_RESERVED"
        assert c.open_session(info.session_id).version == 0


# ------------------------------------------------------------------ deformctl
def run_ctl(daemon, *args, check=True):
    p = subprocess.run([DEFORMCTL, "--socket", daemon.socket_path] + [str(a) for a in args],
                       capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)
    if check:
        assert p.returncode == 0, (args, p.stdout, p.stderr)
    return p


def kv(text: str) -> dict:
    return dict(line.split(" ", 1) for line in text.splitlines())


def test_deformctl_brush_state_prints_and_sets(daemon):
    with grid_session(daemon, 3) as (info, _), daemon.unix_client() as c:
        sid = info.session_id
        d = kv(run_ctl(daemon, "brush-state", sid).stdout)
        assert d["type"] == "grab" and d["integrator"] == "euler" and d["mirror"] == "off"
        for k in ("radius", "nu", "strength", "ratio"):
            assert float(d[k]) == schema.BRUSH_DEFAULTS[k], k
        assert (d["falloff"], d["steps"], d["seq"], d["origin"]) == ("1", "1", "0", "none")
        d = kv(run_ctl(daemon, "brush-state", sid, "--radius", "0.25", "--nu", "0.45",
                       "--integrator", "rk4").stdout)
        assert (d["radius"], d["nu"], d["integrator"], d["steps"], d["seq"]) == (
            "0.25", "0.45", "rk4", "1", "1")
        assert (d["origin"], d["origin_name"], d["changed"]) == (
            "client", "deformctl", "radius,nu,integrator")
        s = c.brush_state_get(sid)
        assert (s.radius, s.nu, s.integrator, s.seq) == (0.25, 0.45, "rk4", 1)
        j = json.loads(run_ctl(daemon, "--json", "brush-state", sid, "--steps", "4",
                               "--nu", "-inf", "--mirror", "0,0,0,0,1,0").stdout)
        assert (j["steps"], j["integrator"], j["nu"], j["seq"]) == (4, "rk4", "-inf", 2)
        assert j["mirror"] == [0, 0, 0, 0, 1, 0] and j["changed"] == ["nu", "integrator",
                                                                      "mirror"]
        assert c.brush_state_get(sid).nu == -math.inf
        p = run_ctl(daemon, "brush-state", sid, "--nu", "0.9", check=False)
        assert p.returncode == 1 and "EINVAL" in p.stderr and "nu 0.9" in p.stderr
        p = run_ctl(daemon, "brush-state", sid, "--falloff", "9", check=False)
        assert p.returncode == 2 and "--falloff" in p.stderr
        assert c.brush_state_get(sid).seq == 2


def test_deformctl_brush_use_session(daemon):
    move = ",".join(str(x) for x in MOVE)
    center = ",".join(str(x) for x in CENTER)

    def via_session(c, sid):
        run_ctl(daemon, "brush-state", sid, "--radius", "0.35", "--nu", "0.1", "--falloff", "2")
        run_ctl(daemon, "brush", sid, "--type", "grab", "--center", center, "--move", move,
                "--use-session", "radius,nu,falloff")

    def explicit(c, sid):
        run_ctl(daemon, "brush", sid, "--type", "grab", "--center", center, "--move", move,
                "--radius", "0.35", "--nu", "0.1", "--falloff", "2")

    assert positions_after(daemon, via_session) == positions_after(daemon, explicit)
    for bad in (["--use-session", "radius", "--radius", "0.5"], ["--use-session", "size"],
                ["--use-session", ","]):
        p = run_ctl(daemon, "brush", "1", "--type", "grab", "--center", center, "--move", move,
                    *bad, check=False)
        assert p.returncode == 2 and "--use-session" in p.stderr, (bad, p.stderr)


@pytest.mark.parametrize("as_json", [False, True])
def test_deformctl_watch_prints_brush_state_events(daemon, as_json):
    with grid_session(daemon, 3) as (info, _), \
            Client.connect_unix(daemon.socket_path, name="knobs") as c:
        sid = info.session_id
        args = (["--json"] if as_json else []) + ["watch", str(sid), "--count", "1"]
        w = subprocess.Popen([DEFORMCTL, "--socket", daemon.socket_path] + args,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             stdin=subprocess.DEVNULL)
        try:
            first = w.stdout.readline()              # printed once it has subscribed
            assert "watching" in first, first
            me = c.brush_state_set(sid, radius=0.125, nu=0.25).origin_id
            c.stroke(sid, Brush(center=CENTER, move=MOVE, radius=0.5))
            out, err = w.communicate(timeout=60)
        finally:
            if w.poll() is None:
                w.kill()
        assert w.returncode == 0, err
        lines = out.splitlines()
        assert len(lines) == 2, out                  # the brush event, then the version
        if as_json:
            ev, ver = json.loads(lines[0]), json.loads(lines[1])
            assert (ev["kind"], ev["seq"], ev["radius"], ev["nu"], ev["origin"],
                    ev["origin_id"], ev["origin_name"], ev["changed"]) == (
                "brush_state", 1, 0.125, 0.25, "client", me, "knobs", ["radius", "nu"])
            assert (ver["kind"], ver["version"]) == ("brush", 1)
        else:
            f = lines[0].split()
            assert f[:8] == ["brush_state", "seq", "1", "changed", "radius,nu", "by", "client",
                             str(me)] and "'knobs':" in lines[0]
            assert "radius 0.125 nu 0.25 " in lines[0]
            assert lines[1].startswith("version 1 brush")


def test_python_codecs_round_trip_the_events():
    st = brush_state.BrushState(7, 3, BS.RADIUS, Origin.DEVICE, (1 << 63) | 2, "Surface Dial",
                                brush_state.BrushValues(radius=0.5, nu=math.inf))
    p = brush_state.encode_brush_state(st)
    assert len(p) == 115 + len("Surface Dial") and brush_state.decode_brush_state(p) == st
    cur = brush_state.BrushCursor(7, Origin.DEVICE, 5, schema.CursorFlag.IN_RANGE,
                                  (0.1, 0.2, 0.3), 0.25)
    p = brush_state.encode_brush_cursor(cur)
    assert len(p) == 50 and brush_state.decode_brush_cursor(p) == cur
    mask, v = brush_state.values_with(brush_state.BrushValues(), radius=2, mirror=None)
    assert mask == BS.RADIUS | BS.MIRROR and v.radius == 2.0 and v.has_mirror == 0
    with pytest.raises(TypeError):
        brush_state.values_with(brush_state.BrushValues(), size=2)
