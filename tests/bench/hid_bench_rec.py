#!/usr/bin/env python3
"""hid_bench_rec.py — hid-recorder files for the HID latency bench (bench_hid.py), written from
the real report descriptors of ../shared/hid/ with input reports at known times:
  knob:     Microsoft Surface Dial (045e:091b, report 1: [01][b0 Button1, b1 Touch][Dial s16]
            [X u16][Y u16][Width]), one report per detent every KNOB_PERIOD_US, rotation +1 / -1
            dial units in runs of KNOB_RUN (so the radius oscillates and never reaches a limit);
  3d-mouse: 3Dconnexion SpaceNavigator (046d:c626, report 1: X Y Z s16, report 2: Rx Ry Rz s16,
            report 3: buttons bit 0 / bit 1), the documented cadence: button 1 down, then every
            M3D_PERIOD_US report 1 (constant X deflection) followed by report 2 (no rotation),
            the zero frames three times, button 1 up.
Layouts: ../shared/hid/README.md "Report layouts" (the bench's unit test
tests/unit/hid/test_hid_bench_rec.c decodes every report written here with the daemon's
descriptor parser and compares the usages' values with the manifest this module writes).

Run as a script: `hid_bench_rec.py OUTDIR` writes knob.hid, mouse3d.hid and, beside each, a
manifest (<name>.expect, one line per E: report: `<time_us> <len> <page>:<usage>=<value> ...`)."""
import os
import struct
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
HID_DIR = os.environ.get("HID_DIR", os.path.join(ROOT, "..", "shared", "hid"))
DIAL_FILE = "microsoft-surface-dial_045e-091b_bt.hid"
M3D_FILE = "3dconnexion-spacenavigator_046d-c626_usb.hid"

LEAD_US = 200000          # first report this long after the replay starts
KNOB_DETENTS = 200
KNOB_PERIOD_US = 20000    # a detent every 20 ms
KNOB_RUN = 10             # 10 detents clockwise, 10 counter-clockwise, ...
M3D_UPDATES = 200         # report 1 + report 2 pairs with translation during the stroke
M3D_PERIOD_US = 8000      # the SpaceNavigator's documented cadence
M3D_X = 100               # constant X deflection, logical range -350..350

# usages (page << 16 | id) the manifest names
U_BUTTON1 = (0x09, 0x01)
U_DIAL = (0x01, 0x37)
U_X, U_Y, U_Z, U_RX, U_RY, U_RZ = ((0x01, u) for u in range(0x30, 0x36))


def read_node(name, node=0):
    """(descriptor bytes, name, bus, vid, pid) of device node `node` of a shared recording."""
    desc, dev_name, ids, cur = None, "", None, 0
    with open(os.path.join(HID_DIR, name)) as f:
        for line in f:
            line = line.rstrip("\r\n")
            if line.startswith("D:"):
                cur = int(line[2:])
            elif cur != node:
                continue
            elif line.startswith("R:"):
                parts = line[2:].split()
                desc = bytes(int(x, 16) for x in parts[1:])
                if len(desc) != int(parts[0]):
                    raise ValueError("%s: R: length %s, %d bytes" % (name, parts[0], len(desc)))
            elif line.startswith("N:"):
                dev_name = line[2:].strip()
            elif line.startswith("I:"):
                ids = tuple(int(x, 16) for x in line[2:].split())
    if desc is None or ids is None:
        raise ValueError("%s: node %d has no R: or I: line" % (name, node))
    return desc, dev_name, ids[0], ids[1], ids[2]


def write_recording(path, source, node, events, comment):
    """Writes a hid-recorder file: the descriptor/name/ids of `source` node `node`, then the
    events [(time_us, bytes, {usage: value})]. Returns the manifest lines (also written to
    path + '.expect')."""
    desc, name, bus, vid, pid = read_node(source, node)
    out = ["# CONSTRUCTED by tests/bench/hid_bench_rec.py for the HID latency bench: %s" % comment,
           "# descriptor, name and ids: ../shared/hid/%s (node %d)" % (source, node),
           "D: 0",
           "R: %d %s" % (len(desc), " ".join("%02x" % b for b in desc)),
           "N: %s" % name,
           "I: %x %04x %04x" % (bus, vid, pid)]
    manifest = []
    for t, data, values in events:
        out.append("E: %06d.%06d %d %s" % (t // 1000000, t % 1000000, len(data),
                                            " ".join("%02x" % b for b in data)))
        manifest.append("%d %d %s" % (t, len(data), " ".join(
            "%x:%x=%d" % (u[0], u[1], v) for u, v in sorted(values.items()))))
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")
    with open(path + ".expect", "w") as f:
        f.write("\n".join(manifest) + "\n")
    return manifest


def knob_events(detents=KNOB_DETENTS, period_us=KNOB_PERIOD_US, run=KNOB_RUN):
    """[(time_us, report bytes, usages)]: one Surface Dial report per detent; the k-th (0-based)
    turns by +1 when (k // run) is even, else -1."""
    ev = []
    for k in range(detents):
        d = 1 if (k // run) % 2 == 0 else -1
        ev.append((LEAD_US + k * period_us, struct.pack("<BBhHHB", 1, 0, d, 0, 0, 0),
                   {U_BUTTON1: 0, U_DIAL: d}))
    return ev


def knob_rotation(k, run=KNOB_RUN):
    """Dial units of the k-th knob report (as knob_events writes it)."""
    return 1 if (k // run) % 2 == 0 else -1


def mouse3d_events(updates=M3D_UPDATES, period_us=M3D_PERIOD_US, x=M3D_X):
    """[(time_us, report bytes, usages)]: a SpaceNavigator stroke at the device's documented
    cadence (a report every period_us, report 1 then report 2). Button 1 down at LEAD_US; pair k
    (0..updates-1): report 1 (X = x) at LEAD_US + (2k + 1) period_us, report 2 (no rotation) one
    period later; then three zero pairs, then button 1 up one period after the last."""
    def axes(rid, a, b, c):
        u = (U_X, U_Y, U_Z) if rid == 1 else (U_RX, U_RY, U_RZ)
        return struct.pack("<Bhhh", rid, a, b, c), {u[0]: a, u[1]: b, u[2]: c}
    ev = [(LEAD_US, struct.pack("<BBB", 3, 1, 0), {U_BUTTON1: 1})]
    t = LEAD_US
    for k in range(updates + 3):
        xv = x if k < updates else 0
        t = LEAD_US + (2 * k + 1) * period_us
        ev.append((t,) + axes(1, xv, 0, 0))
        t += period_us
        ev.append((t,) + axes(2, 0, 0, 0))
    ev.append((t + period_us, struct.pack("<BBB", 3, 0, 0), {U_BUTTON1: 0}))
    return ev


def write_all(outdir):
    """Writes knob.hid and mouse3d.hid (+ manifests) into outdir; returns their paths."""
    knob = os.path.join(outdir, "knob.hid")
    m3d = os.path.join(outdir, "mouse3d.hid")
    write_recording(knob, DIAL_FILE, 0, knob_events(),
                    "%d detents, one every %d us, runs of %d" % (KNOB_DETENTS, KNOB_PERIOD_US,
                                                               KNOB_RUN))
    write_recording(m3d, M3D_FILE, 0, mouse3d_events(),
                    "button 1 down, %d report 1/2 pairs X=%d, a report every %d us, 3 zero pairs, "
                    "button 1 up" % (M3D_UPDATES, M3D_X, M3D_PERIOD_US))
    return knob, m3d


if __name__ == "__main__":
    if len(sys.argv) != 2 or not os.path.isdir(sys.argv[1]):
        sys.exit("usage: hid_bench_rec.py OUTDIR (an existing directory)")
    for p in write_all(sys.argv[1]):
        print(p)
