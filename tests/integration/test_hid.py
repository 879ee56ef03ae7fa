"""HID devices through the real daemon (issue 11, "Daemon integration"): every shared recording
replayed with `hid_replay` (at once: hid_replay_speed = 0, the recorded timestamps still drive
the mappers), knob events checked against values computed here from the recorded bytes and the
configured mapping, the PowerMate LED and the Surface Dial's haptic output reports against the
bytes the descriptor dictates, device listing and binding, and the real hidapi/libusb backends
on this machine (no device: the daemon starts and lists none). 3D mouse and pen strokes, and a
device unplugged mid-stroke: test_hid_strokes.py.

Replay devices start when a client first subscribes (after its reply), so a subscriber sees
every event; the end of a recording is a DEVICE_STATE event with state UNPLUGGED."""
import math
import os
import subprocess

import pytest

from deformd_client import DeformdError, DeviceInfo, DevState, Feature, Origin
from deformd_client.brush_state import BrushState

import hid_files as hf

MESHES = os.environ.get("MESHES", os.path.join(hf.ROOT, "..", "shared", "meshes"))
SPOT = os.path.join(MESHES, "spot.obj")
DEFORMCTL = os.path.join(hf.ROOT, os.environ.get("BUILD", "build"), "bin", "deformctl")
ALL_FILES = sorted(f for f in os.listdir(hf.HID_DIR) if f.endswith((".hid", ".raw.txt")))


def replay_config(files, extra=""):
    return "hid = off\nhid_replay_speed = 0\nhid_replay = %s\n%s" % (
        ",".join(os.path.join(hf.HID_DIR, f) for f in files), extra)


def run_replay(d, mesh=SPOT, before_subscribe=None):
    """Loads `mesh`, optionally calls before_subscribe(client, session_id), subscribes (which
    starts the replay: every classified device opens) and collects events until each of them
    reported UNPLUGGED (the end of its recording). Returns (client, session id, events)."""
    c = d.unix_client()
    sid = c.load_file(mesh).session_id
    if before_subscribe:
        before_subscribe(c, sid)
    driven = {x.device_id for x in c.devices_list() if x.dev_class}
    assert driven, "no classified device to wait for"
    c.subscribe(sid)
    events, gone = [], set()
    while not driven <= gone:
        ev = c.next_event(timeout=30.0)
        assert ev is not None, "no UNPLUGGED event within 30 s; log:\n" + d.log()
        events.append(ev)
        if isinstance(ev, DeviceInfo) and ev.state == DevState.UNPLUGGED:
            gone.add(ev.device_id)
    return c, sid, events


@pytest.mark.parametrize("name", ALL_FILES)
def test_every_recording_replays_through_the_daemon(make_daemon, name):
    """Every node of every shared file is listed with its ids; each classified node is opened,
    handles exactly its recorded reports and ends UNPLUGGED; the daemon keeps serving."""
    nodes = hf.read_recording(os.path.join(hf.HID_DIR, name))
    d = make_daemon(replay_config([name]))
    with d.unix_client() as c0:
        listed = c0.devices_list()
        assert c0.server.features & Feature.HID
    raw = name.endswith(".raw.txt")
    with_desc = [n for n in nodes if n.desc or raw]
    assert len(listed) == len(with_desc), listed
    for dev, node in zip(listed, with_desc):
        assert (dev.vid, dev.pid) == (node.vid or 0x077D, node.pid or 0x0410), dev
        assert dev.state == DevState.CLOSED and dev.backend_name == "replay"
    if not any(dev.dev_class for dev in listed):
        return                                  # nothing to drive: nothing is opened
    c, sid, events = run_replay(d)
    for dev, node in zip(c.devices_list(), with_desc):
        st = c.stats(dev.device_id)
        if dev.dev_class == 0:
            assert dev.state == DevState.CLOSED and st["events"] == 0
            continue
        assert dev.state == DevState.UNPLUGGED, dev
        assert "end of the recording" in dev.error
        assert st["events"] == len(node.events), (dev.name, st)
        assert st["strokes_begun"] == st["strokes_ended"], st
    c.get_mesh(sid)           # queued behind the devices' BRUSH_END (STATS is not a session job)
    assert c.stats(sid)["open_strokes"] == 0
    assert c.ping(b"still serving") == b"still serving"
    c.close()


def knob_expected(reports, button_of, rotation_of, radius=1.0, nu=0.5, falloff=1, step=1.1,
                  nu_step=0.05, falloff_max=3, nu_min=-1.0, nu_max=0.5):
    """The session brush changes a knob makes (hid_config.h defaults: rotate = radius *=
    radius_step ^ detents, press_rotate = nu += nu_step * detents clamped to [nu_min, nu_max],
    press without rotation = next falloff order 1..falloff_max) with one detent per dial unit:
    a list of (field, value)."""
    out, pressed, rotated = [], False, False
    for rep in reports:
        b, r = button_of(rep), rotation_of(rep)
        if b is None:
            continue
        if b and not pressed:
            pressed, rotated = True, False
        if r:
            if pressed:
                rotated = True
                new = min(nu_max, max(nu_min, nu + nu_step * r))
                if new != nu:
                    nu = new
                    out.append(("nu", nu))
            else:
                radius *= step ** r
                out.append(("radius", radius))
        if not b and pressed:
            pressed = False
            if not rotated:
                falloff = falloff % falloff_max + 1
                out.append(("falloff", falloff))
    return out


def observed(events):
    out = []
    for ev in events:
        if isinstance(ev, BrushState) and ev.origin == Origin.DEVICE:
            names = [f.name.lower() for f in type(ev.changed) if f & ev.changed]
            assert len(names) == 1, names
            out.append((names[0], getattr(ev.values, names[0])))
    return out


def same(a, b):
    assert [k for k, _ in a] == [k for k, _ in b], (a, b)
    for (k, x), (_, y) in zip(a, b):
        assert math.isclose(x, y, rel_tol=1e-12, abs_tol=1e-15), (k, x, y)


def test_powermate_knob_radius_nu_falloff_and_led(make_daemon):
    """PowerMate raw packets [button][s8 rotation]...: rotation scales the radius, press+rotate
    moves nu (from 0.2, set by a client first), press alone cycles the falloff; the LED shows the
    session's radius when the knob starts driving it and after every radius change, by the
    vendor control transfer 0x41/0x01, wValue 1, wIndex = brightness (255 * log(r / 0.01) /
    log(1 / 0.01), clamped to 0..255)."""
    name = "griffin-powermate_077d-0410_usb.raw.txt"
    node = hf.read_recording(os.path.join(hf.HID_DIR, name))[0]
    d = make_daemon(replay_config([name]))
    c, sid, events = run_replay(d, before_subscribe=lambda c, s: c.brush_state_set(s, nu=0.2))
    reports = [e for _, e in node.events]
    want = knob_expected(reports, lambda r: r[0] & 1, lambda r: struct_s8(r[1]), nu=0.2)
    assert {k for k, _ in want} == {"radius", "nu", "falloff"}
    same(observed(events), want)
    dev = c.devices_list()[0]
    st = c.stats(dev.device_id)
    leds = [k for k in st if k.startswith("ctl.")]
    radii = [1.0] + [v for k, v in want if k == "radius"]    # the level at attach, then turns
    assert len(leds) == len(radii)
    for key, r in zip(sorted(leds, key=lambda k: int(k.split(".")[1])), radii):
        rt, req, value, index = (int(x, 16) for x in key.split(".")[2].split("_"))
        b = 255 * math.log(r / 0.01) / math.log(1 / 0.01)
        assert (rt, req, value) == (0x41, 0x01, 0x0001)
        assert abs(index - min(255, max(0, b))) <= 1, (key, r)
    c.close()


def struct_s8(b):
    return b - 256 if b > 127 else b


def test_surface_dial_knob_and_haptic_reports(make_daemon):
    """Surface Dial (Dial s16 in report 1, one detent per unit by config): radius events, the
    falloff press, and one haptic Click output report per change laid out from the descriptor
    (Repeat Count = detents - 1, Manual Trigger = the Click ordinal, Retrigger Period = 80 ms)."""
    name = "microsoft-surface-dial_045e-091b_bt.hid"
    node = hf.read_recording(os.path.join(hf.HID_DIR, name))[0]
    fields = hf.parse_descriptor(node.desc)
    dial, di = hf.find_field(fields, "input", 0x00010037)
    btn, bi = hf.find_field(fields, "input", 0x00090001)
    ids = hf.uses_ids(fields)
    d = make_daemon(replay_config([name], "hid.knob.dial_units_per_detent = 1\n"))
    c, sid, events = run_replay(d)
    reports = [e for _, e in node.events]
    want = knob_expected(reports, lambda r: hf.read_element(r, btn, bi, ids),
                         lambda r: hf.read_element(r, dial, di, ids) or 0)
    assert [k for k, _ in want].count("falloff") == 1 and len(want) > 5
    same(observed(events), want)
    dev = c.devices_list()[0]
    assert dev.haptics == 1
    st = c.stats(dev.device_id)
    outs = sorted((k for k in st if k.startswith("out.")), key=lambda k: int(k.split(".")[1]))
    expect = []
    for rep in reports:
        r = hf.read_element(rep, dial, di, ids)
        if r:
            expect.append(hf.haptic_click_report(node.desc, abs(r) - 1, 80))
    expect.append(hf.haptic_click_report(node.desc, 0, 80))          # the falloff press
    assert [bytes.fromhex(k.split(".")[2]) for k in outs] == expect
    c.close()


def test_haptics_off_sends_no_output(make_daemon):
    name = "microsoft-surface-dial_045e-091b_bt.hid"
    d = make_daemon(replay_config([name], "hid.knob.dial_units_per_detent = 1\n"
                                          "hid.045e:091b.haptics = no\n"))
    c, sid, events = run_replay(d)
    dev = c.devices_list()[0]
    assert dev.haptics == 0 and len(observed(events)) > 5
    assert not [k for k in c.stats(dev.device_id) if k.startswith("out.")]
    c.close()


def test_bind_unbind_and_errors(make_daemon):
    d = make_daemon(replay_config(["griffin-powermate_077d-0410_usb.raw.txt"]))
    with d.unix_client() as c:
        a = c.load_file(SPOT, name="a").session_id
        b = c.load_file(SPOT, name="b").session_id
        dev = c.devices_list()[0]
        c.device_bind(dev.device_id, b)
        assert c.devices_list()[0].bound_session == b
        with pytest.raises(DeformdError) as e:
            c.device_bind(dev.device_id, 999)
        assert e.value.name == "ENOTFOUND"
        with pytest.raises(DeformdError) as e:
            c.device_bind((1 << 63) | 77, a)
        assert e.value.name == "ENOTFOUND"
        with pytest.raises(DeformdError) as e:
            c.device_view(dev.device_id, 999, [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1],
                          [0, 0, 100, 100])
        assert e.value.name == "ENOTFOUND"
        assert c.devices_list()[0].bound_session == b      # nothing changed
        c.device_bind(dev.device_id, 0)
        assert c.devices_list()[0].bound_session == 0
        # a bound device drives its session, not the most recently active one: subscribing to
        # b starts the replay (so no event of b is missed), then a becomes the most recent
        c.device_bind(dev.device_id, b)
        c.subscribe(b)
        c.subscribe(a)
        seen = set()
        while True:
            ev = c.next_event(timeout=30.0)
            assert ev is not None
            if isinstance(ev, BrushState):
                seen.add(ev.session_id)
            if isinstance(ev, DeviceInfo) and ev.state == DevState.UNPLUGGED:
                break
        assert seen == {b}
        # closing the bound session unbinds it
        c.close_session(b)
        assert c.devices_list()[0].bound_session == 0


def test_real_backends_start_and_list_no_device(make_daemon):
    """hid = on (the default) with this machine's hidapi and libusb: no HID device here, so the
    daemon starts, sets the HID feature, lists none, and deformctl says so plainly."""
    d = make_daemon("hid = on\nhid_enumerate_s = 1\n")
    with d.unix_client() as c:
        assert c.server.features & Feature.HID
        assert c.devices_list() == []
        assert c.stats()["hid.devices"] == 0
    assert "hid: no HID devices" in d.log()
    out = subprocess.run([DEFORMCTL, "--socket", d.socket_path, "devices"], capture_output=True,
                         text=True, check=True).stdout
    assert out.strip() == "no HID devices"
    js = subprocess.run([DEFORMCTL, "--socket", d.socket_path, "--json", "devices"],
                        capture_output=True, text=True, check=True).stdout
    assert js.strip() == '{"devices":[]}'


def test_hid_off_no_feature_no_devices(make_daemon):
    d = make_daemon("hid = off\n")
    with d.unix_client() as c:
        assert not c.server.features & Feature.HID
        assert c.devices_list() == []
        with pytest.raises(DeformdError) as e:
            c.device_bind((1 << 63) | 1, 0)
        assert e.value.name == "ENOTFOUND" and "off" in e.value.message


def test_deformctl_devices_lists_and_binds(make_daemon):
    d = make_daemon(replay_config(["3dconnexion-spacenavigator_046d-c626_usb.hid"]))
    with d.unix_client() as c:
        sid = c.load_file(SPOT, name="spot").session_id
    run = lambda *a: subprocess.run([DEFORMCTL, "--socket", d.socket_path] + list(a),  # noqa
                                    capture_output=True, text=True)
    out = run("devices")
    assert out.returncode == 0
    line = out.stdout.splitlines()[1].split()
    assert line[:5] == ["1", "3d-mouse", "046d:c626", "closed", "-"], out.stdout
    assert run("devices", "bind", "1", "spot").returncode == 0
    assert run("devices").stdout.splitlines()[1].split()[4] == str(sid)
    bad = run("devices", "bind", "5", "spot")
    assert bad.returncode == 1 and "ENOTFOUND" in bad.stderr
    assert run("devices", "bind", "1").returncode == 2
    assert run("devices", "bind", "1", "none").returncode == 0
    assert run("devices").stdout.splitlines()[1].split()[4] == "-"


def test_bad_replay_config_is_refused(tmp_path):
    deformd = os.path.join(hf.ROOT, os.environ.get("BUILD", "build"), "bin", "deformd")
    bad = tmp_path / "bad.hid"
    bad.write_text("R: 3 05 01\nE: 000000.000000 2 01\n")
    r = subprocess.run([deformd, "--foreground", "--socket", str(tmp_path / "s.sock"),
                        "--hid-replay", str(bad)], capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and "bad.hid" in r.stderr, r.stderr   # a config error, as below
    r = subprocess.run([deformd, "--foreground", "--socket", str(tmp_path / "s.sock"),
                        "--hid-replay", str(tmp_path / "missing.hid")], capture_output=True,
                       text=True, timeout=60)
    assert r.returncode == 2 and "missing.hid" in r.stderr, r.stderr


def test_deformctl_watch_prints_device_and_brush_events(make_daemon):
    """`deformctl watch` (its subscribe starts the replay) prints the knob's brush changes and
    the device's state lines; it ends when the session is closed after the unplug line."""
    d = make_daemon(replay_config(["griffin-powermate_077d-0410_usb.raw.txt"]))
    with d.unix_client() as c:
        sid = c.load_file(SPOT).session_id
        p = subprocess.Popen([DEFORMCTL, "--socket", d.socket_path, "watch", str(sid)],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        lines = []
        for line in p.stdout:
            lines.append(line.strip())
            if line.startswith("device ") and " unplugged " in line:
                break
        c.close_session(sid)
        rest, err = p.communicate(timeout=60)
        assert p.returncode == 0, err
    dev = [x for x in lines if x.startswith("device 1 knob 077d:0410 ")]
    assert dev[0].split()[4] == "open" and dev[-1].split()[4] == "unplugged", lines
    assert "end of the recording" in dev[-1]
    node = hf.read_recording(os.path.join(hf.HID_DIR, "griffin-powermate_077d-0410_usb.raw.txt"))
    want = knob_expected([e for _, e in node[0].events], lambda r: r[0] & 1,
                         lambda r: struct_s8(r[1]))     # nu stays at its 0.5 limit here
    assert sum(x.startswith("brush_state ") for x in lines) == len(want) == 10, lines
