#!/usr/bin/env python3
"""bench_hid.py — device report to subscriber event latency (issue 11, Bench), measured against a
real $BUILD/bin/deformd replaying recordings in real time (hid_replay_speed = 1) and printed with
the target by `make bench`:
  1. a knob turn: the Surface Dial recording (one detent per unit), each BRUSH_STATE event against
     its report's due time;
  2. a 3D-mouse stroke update: a SpaceNavigator recording derived from the shared one (button
     down, then 60 translation reports 8 ms apart, each moving the tip) on a 100k-vertex session,
     each DISPLACEMENT event against its report's due time (compute included).
A report's due time is the client's receipt of the device's DEVICE_STATE open event plus the
report's recorded time (the replay delivers each report at open + recorded time), so the figures
include that event's own latency (a constant offset of the same order). Every line reads
"what: measured (target ...) ok|MISS"; exit status 0 when every measurement ran (targets are
reported, not enforced). Environment: BUILD, MESHES, PYTHONPATH (see make bench)."""
import os
import sys
import tempfile
import time

from conftest import Daemon
from deformd_client import DeviceInfo, DevState, Origin
from deformd_client.brush_state import BrushState
from deformd_client.stream import Disp
from helpers import grid_obj
import hid_files as hf


def report(what, value, unit, target, ok):
    print("  %-62s %10.3f %-3s (target %s) %s" % (what, value, unit, target,
                                                   "ok" if ok else "MISS"))


def pct(xs, p):
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(round(p / 100.0 * (len(xs) - 1))))]


def run(tmps, files, extra, mesh_bytes, due_us, want):
    """Starts a daemon replaying `files` in real time, loads mesh_bytes, subscribes and returns
    the latencies (ms) of the first `want` events matching the kinds, against due_us[i]."""
    tmp = tempfile.TemporaryDirectory(prefix="deformd-bench-")
    d = Daemon(tmp.name, "hid = off\nhid_replay = %s\n%s" % (",".join(files), extra), tcp=False)
    tmps.append((tmp, d))
    c = d.unix_client()
    sid = c.load_mesh(data=mesh_bytes, fmt=".obj").session_id
    c.subscribe(sid)
    t_open, lat = None, []
    while len(lat) < want:
        ev = c.next_event(timeout=30.0)
        now = time.monotonic()
        if ev is None:
            raise RuntimeError("only %d of %d events" % (len(lat), want))
        if isinstance(ev, DeviceInfo):
            if ev.state == DevState.OPEN and t_open is None:
                t_open = now
            elif ev.state == DevState.UNPLUGGED:
                break
        elif t_open is not None and (isinstance(ev, Disp) or
                                     (isinstance(ev, BrushState) and ev.origin == Origin.DEVICE)):
            lat.append((now - t_open) * 1e3 - due_us[len(lat)] / 1e3)
    c.close()
    return lat


def bench_knob(tmps):
    name = os.path.join(hf.HID_DIR, "microsoft-surface-dial_045e-091b_bt.hid")
    node = hf.read_recording(name)[0]
    fields = hf.parse_descriptor(node.desc)
    dial, di = hf.find_field(fields, "input", 0x00010037)
    due = [t for t, e in node.events if hf.read_element(e, dial, di, hf.uses_ids(fields))]
    lat = run(tmps, [name], "hid.knob.dial_units_per_detent = 1\n", grid_obj(8, 8), due,
              len(due))
    report("knob turn -> brush_state event, p50 (%d events)" % len(lat), pct(lat, 50), "ms",
           "-", True)
    report("knob turn -> brush_state event, p99", pct(lat, 99), "ms", "<= 2", pct(lat, 99) <= 2)


def bench_mouse(tmps):
    node = [n for n in hf.read_recording(os.path.join(hf.HID_DIR, "3dconnexion-spacenavigator_"
                                                      "046d-c626_usb.hid")) if n.desc][0]
    t0, events, due = 100000, [(100000, bytes([3, 1, 0]))], []
    for k in range(60):                        # X grows: every report moves the tip
        t = t0 + 8000 * (k + 1)
        events.append((t, bytes([1, 100, 0, 20, 0, 0, 0])))
        due.append(t)
    events.append((t0 + 8000 * 62, bytes([3, 0, 0])))
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "nav.hid")
        hf.write_recording(path, node, events)
        lat = run(tmps, [path], "hid.3d-mouse.deadzone = 0\n", grid_obj(317, 317), due[1:],
                  len(due) - 1)
    report("3d-mouse stroke update -> displacement, 100k vertices, p50", pct(lat, 50), "ms",
           "-", True)
    report("3d-mouse stroke update -> displacement, 100k vertices, p99", pct(lat, 99), "ms",
           "<= 2", pct(lat, 99) <= 2)


def main():
    print("bench_hid: device report -> subscriber event latency (replay timestamps vs receipt)")
    tmps, errors = [], 0
    try:
        for name, fn in (("knob", bench_knob), ("3d mouse", bench_mouse)):
            print(" %s" % name)
            try:
                fn(tmps)
            except Exception as e:   # reported; the other section still runs
                errors += 1
                print("  %s: did not run: %r" % (name, e))
    finally:
        for tmp, d in tmps:
            d.stop()
            tmp.cleanup()
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
