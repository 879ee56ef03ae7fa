"""HID devices as a user meets their errors (issue 11 review): a device named by the number
`deformctl devices` shows (errors say "no device 99", not only its 64-bit id), a device of no
class cannot be bound (it would drive nothing), a pen view that cannot be cast through is refused
at DEVICE_VIEW, a recording whose report descriptor is malformed lists its device as ERROR with
the parser's reason, an unreadable --hid-replay path names the file and the reason, and a session
closed while a device's stroke is open: the stroke counts as ended, the device keeps running and
the daemon keeps serving (its SIGTERM, with the replay thread waiting for the next report, exits
cleanly: the fixture checks status 0)."""
import os
import subprocess

import pytest

from deformd_client import Brush, CursorFlag, DeformdError, DevState, Origin
from deformd_client.brush_state import BrushCursor

import hid_files as hf
from test_hid import DEFORMCTL, SPOT, replay_config

POWERMATE = "griffin-powermate_077d-0410_usb.raw.txt"
PS3 = "sony-ps3-controller_054c-0268_usb.hid"          # no knob, 3D mouse or pen: class none
NTRIG = "ntrig-duosense-pen_1b96-1000_usb.hid"
NAV = "3dconnexion-spacenavigator_046d-c626_usb.hid"
IDENT = [1.0 if i % 5 == 0 else 0.0 for i in range(16)]


def test_errors_name_the_device_number_and_refuse_classless_devices(make_daemon):
    d = make_daemon(replay_config([POWERMATE, PS3, NTRIG]))
    with d.unix_client() as c:
        sid = c.load_file(SPOT).session_id
        knob, ps3, pen = c.devices_list()
        assert (knob.class_name, ps3.dev_class, pen.class_name) == ("knob", 0, "pen")
        for call in (lambda: c.device_bind((1 << 63) | 99, sid),
                     lambda: c.device_view((1 << 63) | 99, sid, IDENT, [0, 0, 10, 10]),
                     lambda: c.stats((1 << 63) | 99)):
            with pytest.raises(DeformdError) as e:
                call()
            assert e.value.name == "ENOTFOUND"
            assert "no device 99 (id %d)" % ((1 << 63) | 99) in e.value.message, e.value.message
        with pytest.raises(DeformdError) as e:
            c.device_bind(ps3.device_id, sid)
        assert e.value.name == "EINVAL" and "device 2 (054c:0268" in e.value.message
        assert "not a knob, 3d-mouse or pen" in e.value.message, e.value.message
        # a singular view_proj: no ray can be cast through it; refused, nothing bound
        with pytest.raises(DeformdError) as e:
            c.device_view(pen.device_id, sid, [0.0] * 16, [0, 0, 960, 720])
        assert e.value.name == "EINVAL" and "singular" in e.value.message, e.value.message
        assert [x.bound_session for x in c.devices_list()] == [0, 0, 0]
        c.device_view(pen.device_id, sid, IDENT, [0, 0, 960, 720])
        assert c.devices_list()[2].bound_session == sid
    bad = subprocess.run([DEFORMCTL, "--socket", d.socket_path, "devices", "bind", "99", "1"],
                         capture_output=True, text=True)
    assert bad.returncode == 1 and "no device 99 " in bad.stderr, bad.stderr


def test_malformed_descriptor_is_listed_as_error(make_daemon, tmp_path):
    """A recording whose descriptor the parser refuses (a Collection item cut short): the daemon
    starts, lists the device with state ERROR and the parser's message, and never opens it."""
    path = tmp_path / "cut.hid"
    path.write_text("N: Cut Knob\nI: 3 1234 5678\nR: 3 05 01 a1\nE: 000000.000000 1 00\n")
    d = make_daemon("hid = off\nhid_replay_speed = 0\nhid_replay = %s\n" % path)
    with d.unix_client() as c:
        (dev,) = c.devices_list()
        assert dev.state == DevState.ERROR, dev
        assert dev.error.startswith("report descriptor refused: "), dev.error
        assert "truncated" in dev.error, dev.error
        c.subscribe(c.load_file(SPOT).session_id)        # starts the replay devices
        assert c.stats(dev.device_id)["events"] == 0
        assert c.devices_list()[0].state == DevState.ERROR
    out = subprocess.run([DEFORMCTL, "--socket", d.socket_path, "devices"], capture_output=True,
                         text=True, check=True).stdout.splitlines()
    assert out[1].split()[:4] == ["1", "none", "1234:5678", "error"], out
    assert "report descriptor refused" in out[1]


def test_replay_path_that_cannot_be_read_names_it(tmp_path):
    deformd = os.path.join(hf.ROOT, os.environ.get("BUILD", "build"), "bin", "deformd")
    r = subprocess.run([deformd, "--foreground", "--socket", str(tmp_path / "s.sock"),
                        "--hid-replay", str(tmp_path)], capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 2, r.stderr                  # a config error, like a missing file
    assert "%s: cannot read: %s" % (tmp_path, os.strerror(21)) in r.stderr, r.stderr  # EISDIR


def test_session_closed_mid_device_stroke(make_daemon, tmp_path):
    """A SpaceNavigator stroke (button 1 down, the recorded motion) whose release comes 60 s
    later; the session is closed while the stroke is open. The stroke counts as ended with it,
    the device stays open and follows the next session, and clients keep working."""
    node = [n for n in hf.read_recording(os.path.join(hf.HID_DIR, NAV)) if n.desc][0]
    motion = [(t + 1000, e) for t, e in node.events if e[0] in (1, 2)]
    events = [(0, bytes([3, 1, 0]))] + motion + [(60000000, bytes([3, 0, 0]))]
    path = tmp_path / "nav-long.hid"
    hf.write_recording(str(path), node, events)
    d = make_daemon("hid = off\nhid_replay = %s\ncursor_hz = 0\nhid.3d-mouse.deadzone = 0\n"
                    % path)
    c = d.unix_client()
    sid = c.load_file(SPOT).session_id
    dev = c.devices_list()[0]
    c.subscribe(sid)
    while True:                                         # the device's stroke moves the cursor
        ev = c.next_event(timeout=30.0)
        assert ev is not None, d.log()
        if (isinstance(ev, BrushCursor) and ev.origin == Origin.DEVICE
                and ev.flags & CursorFlag.STROKE_ACTIVE):
            break
    st = c.stats(dev.device_id)
    assert (st["strokes_begun"], st["stroke_open"]) == (1, 1), st
    c.close_session(sid)
    st = c.stats(dev.device_id)
    assert (st["strokes_begun"], st["strokes_ended"], st["stroke_open"]) == (1, 1, 0), st
    assert c.devices_list()[0].state == DevState.OPEN
    s2 = c.load_file(SPOT).session_id
    ack = c.stroke(s2, Brush(type="grab", center=[0, 0, 0], move=[0.01, 0, 0], radius=0.4))
    assert ack.version == 1
    assert c.stats(s2)["undo_depth"] == 1 and c.ping(b"x") == b"x"
    c.close()


def test_deformctl_devices_says_when_hid_is_off(make_daemon):
    d = make_daemon("hid = off\n")
    out = subprocess.run([DEFORMCTL, "--socket", d.socket_path, "devices"], capture_output=True,
                         text=True, check=True).stdout
    assert out.startswith("no HID devices: the daemon's HID subsystem is off"), out
