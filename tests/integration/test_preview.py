"""deformctl preview against the real daemon: a PNG of the session (rest | current, shaded by
displacement, colour bar). The PNG is decoded here with zlib (signature, chunk CRCs, IHDR, the
five scanline filters), the panel rectangles come from --json, and the displacement range is
checked against |current - rest| computed from the Python client's GET_MESH."""
import json
import math
import os
import struct
import subprocess
import zlib

import pytest

from conftest import DEFORMCTL
from helpers import grid_obj, tet_grid_medit


def read_png(path):
    """(width, height, rows of RGB bytes) of an 8-bit RGB, non-interlaced PNG; asserts validity."""
    with open(path, "rb") as f:
        data = f.read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, idat, ihdr, end = 8, b"", None, False
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        (crc,) = struct.unpack(">I", data[pos + 8 + n:pos + 12 + n])
        assert zlib.crc32(kind + body) == crc, kind
        if kind == b"IHDR":
            ihdr = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        elif kind == b"IEND":
            end = True
        pos += 12 + n
    assert ihdr and end
    w, h, depth, ctype, _, _, interlace = ihdr
    assert (depth, ctype, interlace) == (8, 2, 0)  # 8-bit RGB
    raw = zlib.decompress(idat)
    stride = 3 * w
    assert len(raw) == h * (stride + 1)
    rows, prev = [], bytearray(stride)
    for y in range(h):
        ft = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - 3] if i >= 3 else 0
            b = prev[i]
            c = prev[i - 3] if i >= 3 else 0
            if ft == 1:
                line[i] = (line[i] + a) & 255
            elif ft == 2:
                line[i] = (line[i] + b) & 255
            elif ft == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif ft == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pr = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                line[i] = (line[i] + pr) & 255
            else:
                assert ft == 0, ft
        rows.append(bytes(line))
        prev = line
    return w, h, rows


def panel(rows, r):
    x, y, w, h = r
    return [row[3 * x:3 * (x + w)] for row in rows[y:y + h]]


@pytest.fixture(scope="module")
def ctl(daemon):
    if not os.access(DEFORMCTL, os.X_OK):
        pytest.fail("%s is missing: build it first (make -j2)" % DEFORMCTL, pytrace=False)

    def run(*args, code=0):
        p = subprocess.run([DEFORMCTL, "--socket", daemon.socket_path] + [str(a) for a in args],
                           capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)
        assert p.returncode == code, (args, p.returncode, p.stdout, p.stderr)
        return p
    return run


def load(ctl, tmp_path, name, data):
    f = tmp_path / name
    f.write_bytes(data)
    return int(ctl("load", str(f)).stdout.strip())


def max_disp(daemon, sid):
    with daemon.unix_client() as c:
        m = c.get_mesh(sid, rest=True)
    best = 0.0
    for i in range(m.nv):
        best = max(best, math.sqrt(sum((m.positions[3 * i + k] - m.rest[3 * i + k]) ** 2
                                       for k in range(3))))
    return best


def test_preview_after_a_stroke_shows_rest_and_current_apart(ctl, daemon, tmp_path):
    sid = load(ctl, tmp_path, "g.obj", grid_obj(12, 10))
    before = tmp_path / "before.png"
    j = json.loads(ctl("--json", "preview", sid, "--out", before, "--size", "240x160").stdout)
    w, h, rows = read_png(str(before))
    assert (w, h) == (240, 160) == (j["width"], j["height"])
    assert j["view"] == "front" and j["max"] == 0 and j["triangles"] == 2 * 11 * 9
    left, right = panel(rows, j["panels"][0]), panel(rows, j["panels"][1])
    assert left == right  # nothing moved: the same picture twice
    assert len(set(b"".join(left)[i:i + 3] for i in range(0, len(b"".join(left)), 3))) > 2

    ctl("brush", sid, "--type", "grab", "--center", "0.5,0.5,0", "--move", "0.1,0.2,0.15",
        "--radius", "0.3")
    after = tmp_path / "after.png"
    j = json.loads(ctl("--json", "preview", sid, "--out", after, "--view", "iso",
                       "--size", "320x200").stdout)
    w, h, rows = read_png(str(after))
    assert (w, h) == (320, 200)
    assert j["view"] == "iso" and j["version"] == 1
    left, right = panel(rows, j["panels"][0]), panel(rows, j["panels"][1])
    assert left != right
    differing = sum(a != b for la, ra in zip(left, right) for a, b in zip(la, ra))
    assert differing > 100
    assert abs(j["max"] - max_disp(daemon, sid)) <= 1e-6 * max(1.0, j["max"])
    assert j["max"] > 0.05
    # the colour bar runs from the low end of the colour map to the high end: its ends differ
    bx, by, bw, bh = j["bar"]
    ends = [rows[by + bh // 2][3 * bx:3 * bx + 3], rows[by + bh // 2][3 * (bx + bw - 1):3 * (bx + bw)]]
    assert ends[0] != ends[1]
    # plain output names the file and the range
    p = ctl("preview", sid, "--out", tmp_path / "plain.png", "--view", "side")
    assert "wrote %s" % (tmp_path / "plain.png") in p.stdout and "side view" in p.stdout
    # the views give different pictures
    pics = {}
    for v in ("front", "side", "top", "iso"):
        out = tmp_path / ("v_%s.png" % v)
        ctl("preview", sid, "--out", out, "--view", v, "--size", "200x120")
        pics[v] = read_png(str(out))[2]
    assert len({b"".join(r) for r in pics.values()}) == 4


def test_preview_tet_and_2d_sessions(ctl, tmp_path):
    tid = load(ctl, tmp_path, "t.mesh", tet_grid_medit(4))
    j = json.loads(ctl("--json", "preview", tid, "--out", tmp_path / "t.png", "--view",
                       "iso").stdout)
    assert j["triangles"] > 0  # the boundary faces
    w, h, rows = read_png(str(tmp_path / "t.png"))
    assert (w, h) == (800, 400)
    line = tmp_path / "line.obj"
    line.write_text("v 0 0 0\nv 1 0.2 0\nv 2 0 0.3\nv 3 0.5 0\nl 1 2\nl 2 3\nl 3 4\n")
    lid = int(ctl("load", line).stdout.strip())
    j = json.loads(ctl("--json", "preview", lid, "--out", tmp_path / "l.png", "--size",
                       "200x100").stdout)
    assert (j["segments"], j["triangles"]) == (3, 0)   # a polyline is drawn as lines
    rows = read_png(str(tmp_path / "l.png"))[2]
    assert panel(rows, j["panels"][0]) == panel(rows, j["panels"][1])
    bg = rows[0][:3]
    assert any(row[i:i + 3] != bg for row in panel(rows, j["panels"][0])
               for i in range(0, len(row), 3))
    flat = tmp_path / "flat.obj"
    flat.write_text("v 0 0\nv 1 0\nv 0 1\nv 1 1\nf 1 2 3\nf 2 4 3\n")
    fid = int(ctl("load", flat).stdout.strip())
    p = ctl("--json", "preview", fid, "--out", tmp_path / "f.png", "--view", "side")
    assert json.loads(p.stdout)["view"] == "front"
    assert "2D" in p.stderr and "flat" in p.stderr


def test_preview_errors(ctl, daemon, tmp_path):
    sid = load(ctl, tmp_path, "e.obj", grid_obj(4, 4))
    for args, what in ((["--out", tmp_path / "x.jpg"], ".png"), ([], "--out"),
                       (["--out", tmp_path / "x.png", "--size", "10x10"], "--size"),
                       (["--out", tmp_path / "x.png", "--size", "big"], "--size"),
                       (["--out", tmp_path / "x.png", "--view", "under"], "--view")):
        p = ctl("preview", sid, *args, code=2)
        assert what in p.stderr
    assert not (tmp_path / "x.png").exists()
    p = ctl("preview", "999999", "--out", tmp_path / "x.png", code=1)
    assert "ENOTFOUND" in p.stderr and not (tmp_path / "x.png").exists()
    p = ctl("--json", "preview", sid, "--out", tmp_path / "no" / "dir" / "x.png", code=1)
    e = json.loads(p.stdout)
    assert e["ok"] is False and e["source"] == "client" and "x.png" in e["message"]
    assert not (tmp_path / "no").exists()
