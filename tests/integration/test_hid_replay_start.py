"""The replay clock a client can read (issue 11 Bench: tests/bench/bench_hid.py times device
reports with it): a replay device's stats key `replay.start_us` is CLOCK_MONOTONIC (us) at its
open, which happens while the first subscribe is handled (hid_manager.h), so it lies between
the client's clock just before SUBSCRIBE and just after its reply; each report's event arrives
no earlier than start + its recorded time (hid_replay_speed 1); the key is there only while the
device is open. Orderings of one clock, no duration bound."""
import os
import time

from deformd_client import DeviceInfo, DevState, Origin
from deformd_client.brush_state import BrushState

import hid_files as hf

DIAL = "microsoft-surface-dial_045e-091b_bt.hid"


def mono_us():
    return time.monotonic_ns() // 1000          # CLOCK_MONOTONIC, as the daemon's replay clock


def test_replay_start_is_the_replay_clock(make_daemon, tmp_path):
    node = [n for n in hf.read_recording(os.path.join(hf.HID_DIR, DIAL)) if n.desc][0]
    turn = bytes([1, 0, 1, 0, 0, 0, 0, 0, 0])   # report 1: Dial +1 (README "Surface Dial")
    events = [(200000, turn), (600000, turn)]
    path = tmp_path / "dial.hid"
    hf.write_recording(str(path), node, events)
    d = make_daemon("hid = off\nhid_replay_speed = 1\nhid_replay = %s\n"
                    "hid.knob.dial_units_per_detent = 1\n" % path)
    c = d.unix_client()
    sid = c.load_mesh(hf.grid_obj(), fmt=".obj").session_id
    dev = c.devices_list()[0]
    assert "replay.start_us" not in c.stats(dev.device_id)     # not open before a subscriber
    c.device_bind(dev.device_id, sid)
    before = mono_us()
    c.subscribe(sid)
    after = mono_us()
    start = c.stats(dev.device_id)["replay.start_us"]
    assert before <= start <= after, (before, start, after)
    seen, gone = [], False
    while not gone:
        ev = c.next_event(timeout=30.0)
        assert ev is not None, "no UNPLUGGED event within 30 s; log:\n" + d.log()
        now = mono_us()
        if isinstance(ev, BrushState) and ev.origin == Origin.DEVICE:
            seen.append((now, ev))
        gone = isinstance(ev, DeviceInfo) and ev.state == DevState.UNPLUGGED
    assert len(seen) == len(events)
    for (t_ev, _), (t_rec, _) in zip(seen, events):
        assert t_ev >= start + t_rec, (t_ev, start, t_rec)
    assert "replay.start_us" not in c.stats(dev.device_id)     # closed at the end
    c.close()
