"""Loading meshes safely and helpfully (issue 9: items 1, 2, 14 at load, and the load rough
edges): server-side paths are checked on the resolved path for both TetGen halves, FIFOs and
devices are refused at once, missing and disallowed files get one answer, parse errors never quote
server-side files, float32 overflow is refused in every format, T1.NODE finds T1.ELE, unknown
extensions list the formats, dropped elements are reported by `deformctl load`, upload errors
name the user's file, and sessions are named after their file by default."""
import json
import os
import shutil
import subprocess

import pytest

from conftest import DEFORMCTL
from deformd_client import DeformdError, errors as E
from helpers import grid_obj

SECRET = b"root:*:19000:0:99999:7:::\n"
NODE = b"4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n"
ELE = b"1 4 0\n1 1 2 3 4\n"
TRI = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"


@pytest.fixture
def jail(tmp_path, make_daemon):
    """A daemon whose only allowed folder is tmp_path/allowed; tmp_path/outside holds a secret."""
    allowed = tmp_path / "allowed"
    outside = tmp_path / "outside"
    allowed.mkdir()
    outside.mkdir()
    (outside / "shadow").write_bytes(SECRET)
    (outside / "x.obj").write_bytes(TRI)
    d = make_daemon("allow_paths = %s\n" % os.path.realpath(str(allowed)), tcp=True)
    return d, allowed, outside


def refused(c, path):
    with pytest.raises(DeformdError) as ei:
        c.load_mesh(path=str(path))
    return ei.value


def ctl(d, *args):
    return subprocess.run([DEFORMCTL, "--socket", d.socket_path] + [str(a) for a in args],
                          capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)


def test_tetgen_ele_symlink_out_of_the_allowed_folder_is_refused(jail):
    d, allowed, outside = jail
    (allowed / "X.node").write_bytes(NODE)
    os.symlink(str(outside / "shadow"), str(allowed / "X.ele"))
    (allowed / "Z.node").write_bytes(NODE)
    os.symlink("/dev/zero", str(allowed / "Z.ele"))
    with d.tcp_client(timeout=20) as c:
        for name in ("X.node", "Z.node", "X.ele"):
            e = refused(c, allowed / name)
            assert e.code == E.EIO and "not allowed or not found" in e.message, e
            assert "99999" not in e.message and str(outside) not in e.message
    assert d.alive()


def test_parse_errors_of_server_side_files_never_quote_them(jail):
    d, allowed, _ = jail
    (allowed / "S.node").write_bytes(NODE)
    (allowed / "S.ele").write_bytes(SECRET)
    (allowed / "s.off").write_bytes(SECRET)
    (allowed / "s.obj").write_bytes(b"v root:*:19000 0 0\n")
    with d.unix_client() as c:
        for name, where in (("S.node", "S.ele:1:"), ("s.off", "s.off:1:"), ("s.obj", "s.obj:1:")):
            e = refused(c, allowed / name)
            assert e.code == E.EFORMAT and where in e.message, e
            assert "root:" not in e.message and "19000" not in e.message, e


def test_fifo_fails_promptly_and_the_daemon_still_stops(jail):
    d, allowed, _ = jail
    os.mkfifo(str(allowed / "F.obj"))
    with d.unix_client(timeout=10) as c:   # before the fix the reply never came
        e = refused(c, allowed / "F.obj")
        assert e.code == E.EIO and "not a regular file" in e.message
        assert c.load_mesh(TRI, fmt=".obj").nv == 3   # the pool is free
    assert d.stop() == 0


def test_missing_and_disallowed_files_get_one_answer(jail):
    d, allowed, outside = jail
    (allowed / "ok.obj").write_bytes(TRI)
    with d.unix_client() as c:
        assert c.load_mesh(path=str(allowed / "ok.obj")).nv == 3
        missing = refused(c, allowed / "missing.obj")
        disallowed = refused(c, outside / "x.obj")
        via_proc = refused(c, "/proc/self/cwd/x.obj")
        dotdot = refused(c, allowed / ".." / "outside" / "x.obj")
    assert missing.code == disallowed.code == via_proc.code == dotdot.code == E.EIO
    for e, given in ((missing, allowed / "missing.obj"), (disallowed, outside / "x.obj"),
                     (via_proc, "/proc/self/cwd/x.obj")):
        assert e.message == ("load_mesh: %s: not allowed or not found (config allow_paths)"
                             % given)
    assert d.dir not in via_proc.message   # the daemon's cwd is not revealed


HUGE = {
    ".obj": b"v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n",
    ".off": b"OFF\n3 1 0\n0 0 0\n1 0 3.5e38\n0 1 0\n3 0 1 2\n",
    ".ply": b"ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
            b"property double z\nelement face 1\nproperty list uchar int vertex_indices\n"
            b"end_header\n0 0 0\n1 0 0\n0 -1e39 0\n3 0 1 2\n",
    ".mesh": b"MeshVersionFormatted 1\nDimension 3\nVertices\n3\n0 0 0 0\n1e39 0 0 0\n"
             b"0 1 0 0\nTriangles\n1\n1 2 3 0\nEnd\n",
}


@pytest.mark.parametrize("ext", sorted(HUGE))
def test_coordinates_beyond_float32_are_refused_at_load(jail, ext):
    d, allowed, _ = jail
    (allowed / ("huge" + ext)).write_bytes(HUGE[ext])
    with d.unix_client() as c:
        with pytest.raises(DeformdError) as ei:
            c.load_mesh(HUGE[ext], fmt=ext, file_name="huge" + ext)
        assert ei.value.code == E.EFORMAT and "float32" in ei.value.message
        assert ei.value.message.startswith("huge" + ext) and "vertex" in ei.value.message
        e = refused(c, allowed / ("huge" + ext))
        assert e.code == E.EFORMAT and "float32" in e.message
        assert c.list_sessions() == []


def test_tetgen_node_beyond_float32_is_refused(jail):
    d, allowed, _ = jail
    with d.unix_client() as c:
        with pytest.raises(DeformdError) as ei:
            c.load_mesh(NODE.replace(b"4 0 0 1", b"4 0 0 3.5e38"), ele=ELE, file_name="big.node")
        assert ei.value.code == E.EFORMAT
        assert "big.node:5: vertex 3 coordinate z is outside the float32 range" in ei.value.message


def test_upper_case_tetgen_pair_loads(jail):
    d, allowed, _ = jail
    (allowed / "T1.NODE").write_bytes(NODE)
    (allowed / "T1.ELE").write_bytes(ELE)
    p = ctl(d, "--json", "load", allowed / "T1.NODE")
    assert p.returncode == 0, p.stderr
    j = json.loads(p.stdout)
    assert (j["kind"], j["nv"], j["ne"], j["name"]) == ("tet", 4, 1, "T1")
    assert j["report"]["format"] == "tetgen"
    with d.unix_client() as c:
        assert c.load_mesh(path=str(allowed / "T1.NODE")).ne == 1
        assert c.load_file(str(allowed / "T1.ELE")).ne == 1


def test_unknown_extension_names_the_formats(jail):
    d, allowed, _ = jail
    (allowed / "spot.stl").write_bytes(TRI)
    p = ctl(d, "load", allowed / "spot.stl")
    assert p.returncode == 2
    assert "not recognised" in p.stderr and ".obj" in p.stderr and ".node + .ele" in p.stderr
    assert "cannot read" not in p.stderr
    with d.unix_client() as c:
        e = refused(c, allowed / "spot.stl")
        assert e.code == E.EFORMAT and "not recognised" in e.message and ".mesh" in e.message


def test_dropped_elements_and_findings_are_reported(jail, meshes):
    d, allowed, _ = jail
    mixed = allowed / "mixed.obj"
    mixed.write_bytes(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 3\nl 1 4\n")
    p = ctl(d, "--json", "load", mixed)
    assert p.returncode == 0, p.stderr
    r = json.loads(p.stdout)["report"]
    assert (r["dropped_elements"], r["duplicate_elements"], r["unused_vertices"]) == (1, 1, 1)
    p = ctl(d, "load", mixed)
    assert p.returncode == 0 and p.stdout.strip().isdigit()
    assert "1 lower-dimensional elements dropped" in p.stderr
    assert "1 duplicate elements" in p.stderr and "1 unused vertices" in p.stderr
    (allowed / "tet.mesh").write_bytes(
        b"MeshVersionFormatted 1\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n0 1 0 0\n"
        b"0 0 1 0\nEdges\n2\n1 2 0\n2 3 0\nTetrahedra\n1\n1 2 3 4 0\nEnd\n")
    with d.unix_client() as c:
        info = c.load_mesh(path=str(allowed / "tet.mesh"))
        assert info.kind == 3 and info.report.dropped_elements == 2   # its Edges section
        shutil.copy(os.path.join(meshes, "bunny.mesh"), str(allowed / "bunny.mesh"))
        bunny = c.load_mesh(path=str(allowed / "bunny.mesh"))
        assert bunny.report.boundary_faces == 670 and bunny.report.dropped_elements == 0
        clean = c.load_mesh(TRI, fmt=".obj", file_name="tri.obj")
        assert clean.report.dropped_elements == 0 and clean.report.unused_vertices == 0
    p = ctl(d, "load", allowed / "tet.mesh")
    assert p.returncode == 0 and "2 lower-dimensional elements dropped" in p.stderr
    p = ctl(d, "load", allowed / "bunny.mesh")
    assert p.returncode == 0 and p.stderr == ""


def test_upload_errors_name_the_users_file(jail, tmp_path):
    d, _, _ = jail
    bad = tmp_path / "broken-mesh.obj"
    bad.write_bytes(b"v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n")
    p = ctl(d, "load", bad, "--name", "whatever")
    assert p.returncode == 1
    assert "broken-mesh.obj:2:" in p.stderr and "upload" not in p.stderr
    assert "whatever:" not in p.stderr
    (tmp_path / "b.node").write_bytes(NODE)
    (tmp_path / "b.ele").write_bytes(b"1 4 0\n1 1 2 3 9\n")
    with d.unix_client() as c:
        with pytest.raises(DeformdError) as ei:
            c.load_file(str(tmp_path / "b.node"))
        assert ei.value.message.startswith("b.ele:2:"), ei.value
        with pytest.raises(DeformdError) as ei:
            c.load_mesh(b"v 0 0 0\nv 1 zero 0\n", fmt=".obj", name="s")
        assert ei.value.message.startswith("upload:2:")   # no file name sent: generic


def test_sessions_are_named_after_their_file(jail, tmp_path):
    d, allowed, _ = jail
    f = allowed / "spot.obj"
    f.write_bytes(grid_obj(4, 4))
    first = ctl(d, "--json", "load", f)
    second = ctl(d, "--json", "load", f)
    assert json.loads(first.stdout)["name"] == "spot"
    assert json.loads(second.stdout)["name"] == "spot-2"
    odd = tmp_path / "we\x01ird name.v2.obj"
    odd.write_bytes(TRI)
    with d.unix_client() as c:
        assert c.load_mesh(path=str(f)).name == "spot-3"
        assert c.load_file(str(odd)).name == "we_ird name.v2"
        assert c.load_file(str(f), name="mine").name == "mine"
        assert c.load_mesh(TRI, fmt=".obj").name.startswith("session-")


FLAT = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n"


def test_load_options_ext_and_2d_together(jail):
    """LOAD_MESH options is one field: bit 0 EXT (file_name, load report), bit 1 2D. Both work
    together for uploads (every chunk repeats them) and for path loads; a chunk whose options
    differ ends the upload; unknown bits are EPROTO_RESERVED."""
    from deformd_client import frame as fr, messages as m
    d, allowed, _ = jail
    (allowed / "flat.obj").write_bytes(FLAT)
    with d.unix_client() as c:
        up = c.load_mesh(FLAT, fmt=".obj", file_name="flat.obj", two_d=True)
        assert up.planar == 1 and up.name == "flat" and up.report is not None
        assert up.report.format == m.FMT_OBJ
        three = c.load_mesh(FLAT, fmt=".obj", file_name="flat.obj")
        assert three.planar == 0 and three.name == "flat-2" and three.report is not None
        p2 = c.load_mesh(path=str(allowed / "flat.obj"), two_d=True)
        assert p2.planar == 1 and p2.name == "flat-3" and p2.report is not None
        p3 = c.load_mesh(path=str(allowed / "flat.obj"), name="p3")
        assert p3.planar == 0
        # two chunks, both with EXT | 2D
        opts = m.LOAD_OPT_EXT | m.LOAD_OPT_2D
        rid = c.send(m.LOAD_MESH, m.encode_load_mesh(m.LOAD_INLINE, m.FMT_OBJ, "chunked", "",
                                                     len(FLAT), 0, 0, FLAT[:20], opts, "f.obj"),
                     fr.FLAG_MORE)
        c.send(m.LOAD_MESH, m.encode_load_mesh(m.LOAD_INLINE, m.FMT_OBJ, "chunked", "",
                                               len(FLAT), 0, 20, FLAT[20:], opts, "f.obj"),
               0, rid)
        ch = m.decode_load_reply(b"".join(f.payload for f in c.wait_reply(rid)))
        assert ch.planar == 1 and ch.report is not None
        # a second chunk without the 2D bit does not continue the upload
        rid = c.send(m.LOAD_MESH, m.encode_load_mesh(m.LOAD_INLINE, m.FMT_OBJ, "bad", "",
                                                     len(FLAT), 0, 0, FLAT[:20], opts, "f.obj"),
                     fr.FLAG_MORE)
        c.send(m.LOAD_MESH, m.encode_load_mesh(m.LOAD_INLINE, m.FMT_OBJ, "bad", "", len(FLAT),
                                               0, 20, FLAT[20:], m.LOAD_OPT_EXT, "f.obj"), 0, rid)
        with pytest.raises(DeformdError) as ei:
            c.wait_reply(rid)
        assert ei.value.code == E.EPROTO_CHUNK
        with pytest.raises(DeformdError) as ei:
            c._one(m.LOAD_MESH, m.encode_load_mesh(m.LOAD_INLINE, m.FMT_OBJ, "u", "", len(FLAT),
                                                   0, 0, FLAT, 0x0008))   # bit 2 is PROGRESS
        assert ei.value.code == E.EPROTO_RESERVED and "unknown bits 0x8" in ei.value.message
    # deformctl: --2d and the load report together
    p = ctl(d, "--json", "load", allowed / "flat.obj", "--2d", "--name", "ctl2d")
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout)
    assert "report" in out
    with d.unix_client() as c:
        assert c.open_session(out["session"]).planar == 1
