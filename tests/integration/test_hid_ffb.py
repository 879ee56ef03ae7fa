"""HID force feedback through the real daemon (issue 11, optional part: "Force feedback (PID page
0x0F, the SideWinder file) for a constant force proportional to the live grab's Kelvinlet force
vector"; server/hid/hid_mgr_ffb.h).

The SideWinder Force Feedback 2 recording is replayed (hid_replay_end = hold: the joystick stays
open after its last report), a client strokes a grab on the session the joystick follows, and
the output and feature reports the replay backend captured (device stats `out.N.HEX`,
`feat.N.HEX`) must equal the reports computed here: the Kelvinlet grab force from the paper's
formula (single scale: u(0) = ((a - b) / eps + a / (2 eps)) f with a = 1, b = 1 / (4 (1 - nu)),
so f = tip / kappa), projected on (x, y), times ffb_gain, clamped to 1, in polar form; every
report laid out from the descriptor's fields as parsed by hid_files.py (not by the daemon's
parser). With the default config the joystick is not driven and nothing is sent."""
import math
import os

from deformd_client import Brush, DevState

import hid_files as hf

SW = "microsoft-sidewinder-ff2_045e-001b_usb.hid"
MESHES = os.environ.get("MESHES", os.path.join(hf.ROOT, "..", "shared", "meshes"))
SPOT = os.path.join(MESHES, "spot.obj")


def PID(u):
    return 0x000F0000 | u


def config(extra=""):
    return ("hid = off\nhid_replay_speed = 0\nhid_replay_end = hold\nhid_replay = %s\n%s"
            % (os.path.join(hf.HID_DIR, SW), extra))


def report(fields, kind, collection, values):
    """The `kind` report of the collection with usage `collection`: values maps an element's
    usage to its logical value; an array field (fewer elements than usages) maps the usage it
    selects to True. Elements not named stay 0."""
    rid = next(f.report_id for f in fields if f.kind == kind and collection in f.collections)
    mine = [f for f in fields if f.kind == kind and f.report_id == rid]
    nbits = max(f.bit_offset + f.size * f.count for f in mine)
    v = 0
    for f in mine:
        mask = (1 << f.size) - 1
        if f.usages and len(f.usages) > f.count:                    # array: the selection
            sel = [u for u in f.usages if values.get(u) is True]
            if sel:
                v |= (f.usages.index(sel[0]) + f.logical_min) << f.bit_offset
            continue
        for k in range(f.count):
            u = f.usages[min(k, len(f.usages) - 1)] if f.usages else None
            if u in values:
                v |= (values[u] & mask) << (f.bit_offset + k * f.size)
    return bytes([rid]) + v.to_bytes((nbits + 7) // 8, "little")


def field(fields, kind, usage, collection):
    return next(f for f in fields if f.kind == kind and usage in f.usages
                and collection in f.collections)


def grab_force(tip, radius, nu):
    """Kelvinlet grab force of a single-scale 3D brush whose centre moves by tip."""
    a, b = 1.0, 1.0 / (4.0 * (1.0 - nu))
    kappa = (a - b) / radius + a / (2.0 * radius)
    return [t / kappa for t in tip]


def lround(x):
    return int(math.floor(x + 0.5)) if x >= 0 else -int(math.floor(-x + 0.5))


def expected_reports(desc, tips, radius, nu, strength, gain):
    """(kind, bytes) the daemon must send for a stroke through `tips` (begin, then updates)."""
    fl = hf.parse_descriptor(desc)
    direction = field(fl, "output", 0x000A0001, PID(0x57))
    duration = field(fl, "output", PID(0x50), PID(0x21))
    gain_f = field(fl, "output", PID(0x52), PID(0x21))
    magnitude = field(fl, "output", PID(0x70), PID(0x73))

    def effect_and_force(tip):
        f = grab_force([strength * t for t in tip], radius, nu)
        r = math.hypot(f[0], f[1])
        m = min(1.0, r * gain)
        deg = math.atan2(f[0], f[1]) * 180.0 / math.pi if r > 0 else 0.0
        deg = deg + 360.0 if deg < 0 else deg
        scaled = deg * 10.0 ** (-direction.unit_exponent)       # degrees -> 0.01 degree
        dlog = lround(direction.logical_min + (scaled - direction.physical_min) *
                      (direction.logical_max - direction.logical_min) /
                      (direction.physical_max - direction.physical_min))
        eff = report(fl, "output", PID(0x21), {
            PID(0x22): 1, PID(0x26): True, PID(0x50): (1 << duration.size) - 1,   # infinite
            PID(0x54): 0, PID(0x51): 0, PID(0x52): gain_f.logical_max,
            0x00010030: 1, 0x00010031: 1, PID(0x56): 1, 0x000A0001: dlog, 0x000A0002: 0})
        cf = report(fl, "output", PID(0x73), {PID(0x22): 1,
                                               PID(0x70): lround(m * magnitude.logical_max)})
        return eff, cf

    out = [("out", report(fl, "output", PID(0x96), {PID(0x97): True})),
           ("feat", report(fl, "feature", PID(0xAB), {PID(0x26): True, 0x0001003B: 0}))]
    eff, cf = effect_and_force(tips[0])
    out += [("out", eff), ("out", cf),
            ("out", report(fl, "output", PID(0x77), {PID(0x22): 1, PID(0x79): True,
                                                      PID(0x7C): 1}))]
    for tip in tips[1:]:
        e2, c2 = effect_and_force(tip)
        if e2 != eff:
            out.append(("out", e2))
        if c2 != cf:
            out.append(("out", c2))
        eff, cf = e2, c2
    out += [("out", report(fl, "output", PID(0x77), {PID(0x22): 1, PID(0x7B): True,
                                                      PID(0x7C): 0})),
            ("out", report(fl, "output", PID(0x90), {PID(0x22): 1}))]
    return out


def captured(stats):
    """(kind, bytes) of the device's captured output/feature reports, in call order."""
    keys = [k for k in stats if k.startswith(("out.", "feat."))]
    keys.sort(key=lambda k: int(k.split(".")[1]))
    return [(k.split(".")[0], bytes.fromhex(k.split(".")[2])) for k in keys]


def start(d):
    """Loads spot, subscribes (the replay starts: the joystick opens). Returns (client, sid,
    the joystick's device id)."""
    c = d.unix_client()
    sid = c.load_file(SPOT).session_id
    c.subscribe(sid)
    devs = c.devices_list()
    assert len(devs) == 1 and devs[0].vid == 0x045E and devs[0].pid == 0x001B
    return c, sid, devs[0]


RADIUS, NU, STRENGTH, GAIN = 0.3, 0.3, 1.5, 40.0
TIPS = [(0.02, 0.01, 0.0), (0.02, 0.01, 0.0), (-0.03, 0.02, 0.05), (0.0, -0.5, 0.0),
        (0.01, 0.004, -0.2)]


def stroke(c, sid, tips):
    c.brush_begin(sid, Brush(type="grab", center=(0.0, 0.0, 0.0), move=tips[0], radius=RADIUS,
                             nu=NU, strength=STRENGTH, falloff=1))
    for t in tips[1:]:
        c.brush_update(sid, move=t)
    c.brush_end(sid)


def test_grab_plays_its_kelvinlet_force(make_daemon):
    """Create, load and start on the begin; direction / magnitude reports when their bytes
    change (ffb_hz 0: every update; a repeated tip sends nothing; the large tip clamps to full
    scale); stop and free on the end. A second stroke creates the effect again, without
    re-enabling the actuators."""
    d = make_daemon(config("hid.045e:001b.force_feedback = yes\nhid.045e:001b.ffb_gain = %r\n"
                           "hid.045e:001b.ffb_hz = 0\n" % GAIN))
    c, sid, dev = start(d)
    assert dev.state == DevState.OPEN and dev.dev_class == 0
    node = hf.read_recording(os.path.join(hf.HID_DIR, SW))[0]
    want = expected_reports(node.desc, TIPS, RADIUS, NU, STRENGTH, GAIN)
    # the clamp is exercised, and not every report is clamped
    mags = [int.from_bytes(b[2:4], "little", signed=True) for k, b in want if b[0] == 5]
    assert 255 in mags and any(0 < m < 255 for m in mags)
    stroke(c, sid, TIPS)
    st = c.stats(dev.device_id)
    assert st["force_feedback"] == 1
    got = captured(st)
    assert got == want, d.log()
    assert st["ffb.reports"] == len(want)
    stroke(c, sid, TIPS[:1])
    again = captured(c.stats(dev.device_id))[len(want):]
    second = expected_reports(node.desc, TIPS[:1], RADIUS, NU, STRENGTH, GAIN)[1:]
    assert again == second
    c.close()


def test_rate_limited_updates_are_the_strokes_forces(make_daemon):
    """With the default rate (ffb_hz 100) an update may be deferred (sent at the end of its
    interval) or replaced by a later one: the reports between start and stop are each one of
    the stroke's computed reports, in order, and the stroke still starts and stops exactly."""
    d = make_daemon(config("hid.045e:001b.force_feedback = yes\nhid.045e:001b.ffb_gain = %r\n"
                           % GAIN))
    c, sid, dev = start(d)
    node = hf.read_recording(os.path.join(hf.HID_DIR, SW))[0]
    full = expected_reports(node.desc, TIPS, RADIUS, NU, STRENGTH, GAIN)
    stroke(c, sid, TIPS)
    got = captured(c.stats(dev.device_id))
    assert got[:5] == full[:5] and got[-2:] == full[-2:]
    middle, allowed = got[5:-2], full[5:-2]
    pos = 0
    for rep in middle:   # a subsequence of the unlimited stream
        while pos < len(allowed) and allowed[pos] != rep:
            pos += 1
        assert pos < len(allowed), (rep, allowed)
        pos += 1
    c.close()


def test_default_config_sends_nothing(make_daemon):
    """Off by default: the joystick (no mapper class) is listed but not opened, and a grab
    stroke sends it no report."""
    d = make_daemon(config())
    c, sid, dev = start(d)
    assert dev.state != DevState.OPEN
    stroke(c, sid, TIPS)
    st = c.stats(dev.device_id)
    assert st["force_feedback"] == 0 and st["ffb.reports"] == 0
    assert captured(st) == []
    c.close()


def test_force_feedback_config_errors(make_daemon, tmp_path):
    """force_feedback is a device key (a class section refuses it); bad values are refused."""
    import subprocess
    deformd = os.path.join(hf.ROOT, os.environ.get("BUILD", "build"), "bin", "deformd")
    for line, msg in [("hid.knob.force_feedback = yes", "device key"),
                      ("hid.045e:001b.force_feedback = maybe", "yes or no"),
                      ("hid.045e:001b.ffb_gain = 0", "ffb_gain"),
                      ("hid.045e:001b.ffb_hz = 5000", "ffb_hz"),
                      ("hid_replay_end = later", "unplug|hold|loop")]:
        cfg = tmp_path / "bad.conf"
        cfg.write_text(line + "\n")
        r = subprocess.run([deformd, "--foreground", "--config", str(cfg),
                            "--socket", str(tmp_path / "s")], capture_output=True, text=True,
                           timeout=30)
        assert r.returncode != 0 and msg in r.stderr and "bad.conf:1" in r.stderr, r.stderr
