"""Independent readers of the shared HID recordings for the integration tests (test_hid*.py):
the hid-recorder text format (../shared/hid/README.md) and a minimal report-descriptor walker
that finds where a usage lives, its logical range and the layout of an output report. Written
from the HID specification and the README, not from the daemon's C code, so the tests compute
their expected values on their own."""
import os
import struct
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Tuple

ROOT = os.path.realpath(os.path.join(os.path.dirname(__file__), "..", ".."))
HID_DIR = os.environ.get("HID_DATA", os.path.join(ROOT, "..", "shared", "hid"))


@dataclass
class Node:
    """One device (D: node) of a recording."""
    index: int
    desc: bytes = b""
    name: str = ""
    bus: int = 0
    vid: int = 0
    pid: int = 0
    events: List[Tuple[int, bytes]] = field(default_factory=list)   # (time_us, report)


def read_recording(path: str) -> List[Node]:
    """The nodes of a hid-recorder file (or of the PowerMate raw file: one node, no R: line)."""
    nodes: Dict[int, Node] = {}
    cur = 0
    for line in open(path, encoding="utf-8", errors="replace"):
        line = line.rstrip("\n")
        if not line or line.startswith("#"):
            continue
        tag, _, rest = line.partition(":")
        rest = rest.strip()
        if tag == "D":
            cur = int(rest)
            continue
        n = nodes.setdefault(cur, Node(cur))
        if tag == "R":
            parts = rest.split()
            n.desc = bytes(int(x, 16) for x in parts[1:])
            assert len(n.desc) == int(parts[0])
        elif tag == "N":
            n.name = rest
        elif tag == "I":
            n.bus, n.vid, n.pid = (int(x, 16) for x in rest.split())
        elif tag == "E":
            parts = rest.split()
            sec, usec = parts[0].split(".")
            data = bytes(int(x, 16) for x in parts[2:])
            assert len(data) == int(parts[1])
            n.events.append((int(sec) * 1000000 + int(usec), data))
    return [nodes[k] for k in sorted(nodes)]


def write_recording(path: str, node: Node, events: List[Tuple[int, bytes]]) -> None:
    """A one-node hid-recorder file with node's descriptor and ids and the given events."""
    with open(path, "w") as f:
        f.write("# derived from a shared recording by tests/integration/hid_files.py\n")
        f.write("R: %d %s\n" % (len(node.desc), " ".join("%02x" % b for b in node.desc)))
        f.write("N: %s\n" % node.name)
        f.write("I: %x %04x %04x\n" % (node.bus, node.vid, node.pid))
        for t, data in events:
            f.write("E: %06d.%06d %d %s\n" % (t // 1000000, t % 1000000, len(data),
                                              " ".join("%02x" % b for b in data)))


# ------------------------------------------------------------------ report descriptors
@dataclass
class Field:
    kind: str            # "input", "output", "feature"
    report_id: int
    bit_offset: int      # from the start of the report data (after the id byte)
    size: int
    count: int
    usages: List[int]    # page << 16 | id, one per element (the last repeats)
    logical_min: int
    logical_max: int
    physical_min: int
    physical_max: int
    collections: List[int]   # usages of the enclosing collections, outermost first


def _signed(v: int, size: int) -> int:
    return v - (1 << (8 * size)) if size and v >> (8 * size - 1) else v


def parse_descriptor(desc: bytes) -> List[Field]:
    """Every main item of a report descriptor as Fields (constants included)."""
    g = {"page": 0, "lmin": 0, "lmax": 0, "pmin": 0, "pmax": 0, "size": 0, "count": 0, "id": 0}
    stack, usages, umin, coll, out = [], [], None, [], []
    offsets: Dict[Tuple[str, int], int] = {}
    i = 0
    while i < len(desc):
        p = desc[i]
        if p == 0xFE:                                   # long item
            i += 3 + desc[i + 1]
            continue
        size = (0, 1, 2, 4)[p & 3]
        typ, tag = (p >> 2) & 3, p >> 4
        raw = int.from_bytes(desc[i + 1:i + 1 + size], "little")
        i += 1 + size
        if typ == 1:                                    # global
            key = {0: "page", 1: "lmin", 2: "lmax", 3: "pmin", 4: "pmax", 7: "size", 8: "id",
                   9: "count"}.get(tag)
            if tag in (1, 2, 3, 4):
                raw = _signed(raw, size)
            if key:
                g[key] = raw
            elif tag == 10:
                stack.append(dict(g))
            elif tag == 11:
                g = stack.pop()
        elif typ == 2:                                  # local
            full = raw if size == 4 else (g["page"] << 16) | raw
            if tag == 0:
                usages.append(full)
            elif tag == 1:
                umin = full
            elif tag == 2 and umin is not None:
                usages.extend(range(umin, full + 1))
                umin = None
        elif typ == 0:                                  # main
            if tag == 10:
                coll.append(usages[0] if usages else 0)
            elif tag == 12:
                coll.pop()
            elif tag in (8, 9, 11):
                kind = {8: "input", 9: "output", 11: "feature"}[tag]
                k = (kind, g["id"])
                off = offsets.get(k, 0)
                pmin, pmax = g["pmin"], g["pmax"]
                if pmin == 0 and pmax == 0:
                    pmin, pmax = g["lmin"], g["lmax"]
                out.append(Field(kind, g["id"], off, g["size"], g["count"], list(usages),
                                 g["lmin"], g["lmax"], pmin, pmax, list(coll)))
                offsets[k] = off + g["size"] * g["count"]
            usages, umin = [], None
    return out


def find_field(fields: List[Field], kind: str, usage: int) -> Optional[Tuple[Field, int]]:
    """(field, element index) of the first `kind` element with `usage`."""
    for f in fields:
        if f.kind == kind and usage in f.usages:
            return f, f.usages.index(usage)
    return None


def read_element(report: bytes, f: Field, index: int, uses_ids: bool) -> Optional[int]:
    """Element `index` of field f in a report as read (id byte first when ids are used)."""
    if uses_ids and (not report or report[0] != f.report_id):
        return None
    data = report[1:] if uses_ids else report
    bit = f.bit_offset + index * f.size
    if (bit + f.size + 7) // 8 > len(data):
        return None
    v = int.from_bytes(data, "little") >> bit & ((1 << f.size) - 1)
    if f.logical_min < 0 and v >> (f.size - 1):
        v -= 1 << f.size
    return v


def uses_ids(fields: List[Field]) -> bool:
    return any(f.report_id for f in fields)


def haptic_click_report(desc: bytes, repeat: int, retrigger_ms: int) -> bytes:
    """The Haptics page (0x0E) output report that plays the Click waveform (0x0E:0x1003):
    Manual Trigger (0x0E:0x21) = the ordinal whose Waveform List (0x0E:0x10) entry is Click,
    Repeat Count (0x0E:0x24), Retrigger Period (0x0E:0x25) in ms, laid out as the descriptor's
    output fields say."""
    fields = parse_descriptor(desc)
    click = [f for f in fields if 0x000E0010 in f.collections and f.physical_min == 0x1003]
    assert click, "no Click in the waveform list"
    ordinal = click[0].usages[0] & 0xFFFF
    trig = find_field(fields, "output", 0x000E0021)
    assert trig
    rid = trig[0].report_id
    outs = [f for f in fields if f.kind == "output" and f.report_id == rid]
    nbits = max(f.bit_offset + f.size * f.count for f in outs)
    value = 0
    want = {0x000E0021: ordinal, 0x000E0024: repeat, 0x000E0025: retrigger_ms}
    for f in outs:
        for k in range(f.count):
            u = f.usages[min(k, len(f.usages) - 1)]
            if u in want:
                value |= (want[u] & ((1 << f.size) - 1)) << (f.bit_offset + k * f.size)
    body = value.to_bytes((nbits + 7) // 8, "little")
    return (bytes([rid]) if rid else b"") + body


def grid_obj(n: int = 8, half: float = 1.5) -> bytes:
    """An n x n flat triangle grid in z = 0 over [-half, half]^2, as OBJ text."""
    lines = []
    for j in range(n + 1):
        for i in range(n + 1):
            lines.append("v %.17g %.17g 0" % (-half + 2 * half * i / n, -half + 2 * half * j / n))
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i + 1
            lines.append("f %d %d %d" % (a, a + 1, a + n + 2))
            lines.append("f %d %d %d" % (a, a + n + 2, a + n + 1))
    return ("\n".join(lines) + "\n").encode()


def unpack_i16(b: bytes, off: int) -> int:
    return struct.unpack_from("<h", b, off)[0]
