"""Device strokes through the real daemon (issue 11): a SpaceNavigator's cursor and grab stroke
(tip = the recorded axes integrated with their timestamps times sensitivity and the session's
bounding-box diagonal, computed here from the recorded bytes), the same stroke cut by the end
of the recording (unplug mid-stroke: it ends cleanly, exactly like a client's stroke with that
tip), and the recorded N-trig pen cast through a client's view onto a plane: strokes with the
pressure as strength and the begin/end count of its tip switch, and an unplug mid-stroke.
Helpers: test_hid.py (run_replay, replay_config) and hid_files.py (independent readers)."""
import math
import os

import pytest

from deformd_client import Brush, DeviceInfo, DevState, Origin
from deformd_client.brush_state import BrushCursor, BrushState

import hid_files as hf
from test_hid import SPOT, replay_config, run_replay

NAV = "3dconnexion-spacenavigator_046d-c626_usb.hid"
NTRIG = "ntrig-duosense-pen_1b96-1000_usb.hid"
SENS = 0.75          # hid.3d-mouse.sensitivity (scale units per second at full deflection)
MOUSE_CFG = "hid.3d-mouse.deadzone = 0\nhid.3d-mouse.sensitivity = %r\ncursor_hz = 0\n" % SENS


def obj_bbox(path):
    """Centre and diagonal of the bounding box of an OBJ's vertices (double, as the daemon)."""
    lo, hi = [math.inf] * 3, [-math.inf] * 3
    for line in open(path):
        if line.startswith("v "):
            v = [float(x) for x in line.split()[1:4]]
            lo = [min(a, b) for a, b in zip(lo, v)]
            hi = [max(a, b) for a, b in zip(hi, v)]
    return [0.5 * (a + b) for a, b in zip(lo, hi)], math.sqrt(sum((b - a) ** 2
                                                                  for a, b in zip(lo, hi)))


def integrate(node, events, scale):
    """Sum of the translation steps of the 3D mouse reports: per report carrying X/Y/Z, each
    axis v (deadzone 0) moves v / logical_max * SENS * dt * scale, dt = seconds since the
    previous report with the same report id, at most 0.05 (0 for the first)."""
    fields = hf.parse_descriptor(node.desc)
    ids = hf.uses_ids(fields)
    axes = [hf.find_field(fields, "input", 0x00010030 + k) for k in range(3)]
    last, total = {}, [0.0, 0.0, 0.0]
    for t, rep in events:
        vals = [hf.read_element(rep, f, i, ids) for f, i in axes]
        if any(v is None for v in vals):
            continue                            # another report (rotation, buttons)
        rid = rep[0] if ids else 0
        dt = 0.0 if rid not in last else min(0.05, (t - last[rid]) / 1e6)
        last[rid] = t
        for k, ((f, _), v) in enumerate(zip(axes, vals)):
            total[k] += v / f.logical_max * SENS * dt * scale
    return total


def nav_node():
    return [n for n in hf.read_recording(os.path.join(hf.HID_DIR, NAV)) if n.desc][0]


def test_spacenavigator_cursor_is_the_integrated_axes(make_daemon):
    """The recorded file moves the cursor (no button during the motion): the last BRUSH_CURSOR
    of the device is the session's bounding-box centre plus the integrated translation."""
    node = nav_node()
    d = make_daemon(replay_config([NAV], MOUSE_CFG))
    c, sid, events = run_replay(d)
    centre, diag = obj_bbox(SPOT)
    want = [a + b for a, b in zip(centre, integrate(node, node.events, diag))]
    cur = [e for e in events if isinstance(e, BrushCursor) and e.origin == Origin.DEVICE]
    assert cur, "no cursor event"
    assert any(abs(a - b) > 1e-6 for a, b in zip(cur[-1].center, centre)), "the cursor moved"
    for a, b in zip(cur[-1].center, want):
        assert math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-12), (cur[-1].center, want)
    c.close()


@pytest.mark.parametrize("release", [True, False], ids=["released", "unplugged-mid-stroke"])
def test_spacenavigator_grab_tip_and_mesh(make_daemon, tmp_path, release):
    """A recording derived from the SpaceNavigator's: button 1 pressed, the recorded motion, then
    released (or the recording ends with the button down: unplug mid-stroke). The stroke's tip
    is the integrated motion, and the mesh equals that of a client grab stroke with that tip at
    the bounding-box centre (the session brush's radius, nu, falloff): nothing half-applied."""
    node = nav_node()
    motion = [(t + 1000, e) for t, e in node.events if e[0] in (1, 2)]
    events = [(0, bytes([3, 1, 0]))] + motion
    if release:
        events.append((motion[-1][0] + 8000, bytes([3, 0, 0])))
    path = str(tmp_path / "nav-stroke.hid")
    hf.write_recording(path, node, events)
    d = make_daemon("hid = off\nhid_replay_speed = 0\nhid_replay = %s\n%s" % (path, MOUSE_CFG))
    c, sid, evs = run_replay(d, before_subscribe=lambda c, s: c.brush_state_set(s, radius=0.4))
    centre, diag = obj_bbox(SPOT)
    tip = integrate(node, motion, diag)
    dev = c.devices_list()[0]
    st = c.stats(dev.device_id)
    assert (st["strokes_begun"], st["strokes_ended"], st["stroke_open"]) == (1, 1, 0)
    got = [st["last.tip_x"], st["last.tip_y"], st["last.tip_z"]]
    assert max(abs(x) for x in tip) > 1e-4
    for a, b in zip(got, tip):
        assert math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-15), (got, tip)
    mesh = c.get_mesh(sid)                  # queued behind the device's BRUSH_END
    s = c.stats(sid)
    assert s["open_strokes"] == 0 and s["undo_depth"] == 1
    ref = c.load_file(SPOT, name="ref").session_id
    c.stroke(ref, Brush(type="grab", center=centre, move=got, radius=0.4))
    want = c.get_mesh(ref)
    assert mesh.positions == want.positions
    assert mesh.positions != c.get_mesh(ref, base=True).base
    assert c.ping(b"x") == b"x"
    c.close()


def pen_setup(c, sid, device_id):
    """Identity view (orthographic: pixel -> the plane's x, y in [-1, 1]) on a 960 x 720
    viewport: every pen position hits the [-1.5, 1.5]^2 plane."""
    ident = [1.0 if i % 5 == 0 else 0.0 for i in range(16)]
    c.device_view(device_id, sid, ident, [0, 0, 960, 720])


def pen_expected(node, upto=None):
    """(strokes, max strength, last strength, barrel presses) from the pen reports: a stroke per
    Tip Switch rising edge, strength = pressure / logical max (strength_max 1, gamma 1) of the
    reports with the tip down."""
    fields = hf.parse_descriptor(node.desc)
    ids = hf.uses_ids(fields)
    tip = hf.find_field(fields, "input", 0x000D0042)
    barrel = hf.find_field(fields, "input", 0x000D0044)
    pres = hf.find_field(fields, "input", 0x000D0030)
    strokes, smax, slast, presses, down, bdown = 0, 0.0, 0.0, 0, 0, 0
    for _, rep in node.events[:upto]:
        t = hf.read_element(rep, *tip, ids)
        if t is None:
            continue
        b = hf.read_element(rep, *barrel, ids)
        if t:
            s = hf.read_element(rep, *pres, ids) / pres[0].logical_max
            strokes += not down
            smax, slast = max(smax, s), s
        if b and not bdown:
            presses += 1
        down, bdown = t, b
    return strokes, smax, slast, presses, down


def test_ntrig_pen_strokes_pressure_as_strength(make_daemon, tmp_path):
    node = [n for n in hf.read_recording(os.path.join(hf.HID_DIR, NTRIG)) if n.desc][0]
    plane = tmp_path / "plane.obj"
    plane.write_bytes(hf.grid_obj())
    d = make_daemon(replay_config([NTRIG]))
    with d.unix_client() as c0:
        pens = [x for x in c0.devices_list() if x.class_name == "pen"]
        assert len(pens) == 1
    c, sid, evs = run_replay(d, mesh=str(plane),
                             before_subscribe=lambda c, s: pen_setup(c, s, pens[0].device_id))
    strokes, smax, slast, presses, _ = pen_expected(node)
    assert strokes == 7 and presses == 2
    st = c.stats(pens[0].device_id)
    assert (st["strokes_begun"], st["strokes_ended"]) == (strokes, strokes), st
    assert math.isclose(st["strength_max"], smax, rel_tol=1e-12), st
    assert math.isclose(st["last.strength"], slast, rel_tol=1e-12), st
    types = [e for e in evs if isinstance(e, BrushState) and e.origin == Origin.DEVICE]
    assert len(types) == presses and all(e.changed.name == "TYPE" for e in types)
    c.get_mesh(sid)
    s = c.stats(sid)
    assert s["open_strokes"] == 0 and s["version"] > 0
    c.close()


def test_pen_without_view_makes_no_stroke(make_daemon, tmp_path):
    plane = tmp_path / "plane.obj"
    plane.write_bytes(hf.grid_obj())
    d = make_daemon(replay_config([NTRIG]))
    c, sid, evs = run_replay(d, mesh=str(plane))
    pen = [x for x in c.devices_list() if x.class_name == "pen"][0]
    st = c.stats(pen.device_id)
    assert st["events"] > 0 and st["strokes_begun"] == 0
    assert c.stats(sid)["version"] == 0
    assert d.log().count("has no view of session") == 1      # logged once
    c.close()


def test_pen_unplugged_mid_stroke_ends_it(make_daemon, tmp_path):
    """The N-trig recording cut while the tip is down in its second stroke: the stroke ends
    through BRUSH_END (one undo step per stroke), the device is UNPLUGGED, the daemon serves."""
    node = [n for n in hf.read_recording(os.path.join(hf.HID_DIR, NTRIG)) if n.desc][0]
    cut, seen = None, 0
    for i in range(1, len(node.events)):
        s = pen_expected(node, i)
        if s[0] == 2 and s[4] and seen > 10:
            cut = i
            break
        seen += s[0] == 2
    assert cut
    path = str(tmp_path / "ntrig-cut.hid")
    hf.write_recording(path, node, node.events[:cut])
    plane = tmp_path / "plane.obj"
    plane.write_bytes(hf.grid_obj())
    d = make_daemon("hid = off\nhid_replay_speed = 0\nhid_replay = %s\n" % path)
    with d.unix_client() as c0:
        pen = c0.devices_list()[0]
    c, sid, evs = run_replay(d, mesh=str(plane),
                             before_subscribe=lambda c, s: pen_setup(c, s, pen.device_id))
    gone = [e for e in evs if isinstance(e, DeviceInfo) and e.state == DevState.UNPLUGGED]
    assert gone and gone[-1].device_id == pen.device_id
    st = c.stats(pen.device_id)
    assert (st["strokes_begun"], st["strokes_ended"], st["stroke_open"]) == (2, 2, 0)
    c.snapshot(sid)                         # queued behind the device's BRUSH_END
    s = c.stats(sid)
    assert s["open_strokes"] == 0 and s["undo_depth"] == 2
    assert c.load_file(SPOT).session_id and c.ping(b"ok") == b"ok"
    c.close()
