"""deformctl's rough edges (issue 9): one exit-code rule for every command (0 ok; 1 an error
from the daemon, the daemon unreachable, a local engine refusal or a local failure; 2 usage),
errors as a JSON object on stdout under --json, `close`, and messages that name the field, the
value and the option to use. Runs the real deformctl against the real daemon."""
import json
import os
import subprocess

import pytest

from conftest import DEFORMCTL
from helpers import grid_obj

POLYLINE_OBJ = "v 0 0 0\nv 1 0 0\nv 2 0.5 0\nv 3 0 0\nl 1 2 3 4\n"


def run(daemon, *args, env_socket=True, timeout=60):
    """deformctl with exactly `args` (no --socket added: the global options are under test);
    the daemon is found through $DEFORMD_SOCKET unless env_socket is False."""
    env = dict(os.environ)
    env.pop("DEFORMD_SOCKET", None)
    if env_socket:
        env["DEFORMD_SOCKET"] = daemon.socket_path
    return subprocess.run([DEFORMCTL] + [str(a) for a in args], capture_output=True, text=True,
                          timeout=timeout, stdin=subprocess.DEVNULL, env=env)


@pytest.fixture(scope="module")
def sessions(daemon, tmp_path_factory):
    """A triangle session and a polyline session, loaded under names unique to this module."""
    if not os.access(DEFORMCTL, os.X_OK):
        pytest.fail("%s is missing: build it first (make -j2)" % DEFORMCTL, pytrace=False)
    d = tmp_path_factory.mktemp("clierr")
    (d / "g.obj").write_bytes(grid_obj(6, 6))
    (d / "poly.obj").write_text(POLYLINE_OBJ)
    (d / "h.txt").write_text("0\n3\n")
    (d / "t.txt").write_text("0 0 0.1\n1 0 0.1\n")
    tri = int(run(daemon, "load", d / "g.obj", "--name", "clierr-tri").stdout)
    poly = int(run(daemon, "load", d / "poly.obj", "--name", "clierr-poly").stdout)
    yield {"tri": tri, "poly": poly, "dir": d}
    with daemon.unix_client() as c:
        for sid in (tri, poly):
            try:
                c.close_session(sid)
            except Exception:
                pass


# (id, argv with TRI/POLY/DIR placeholders, exit status, error name, source, stderr fragment)
CASES = [
    # usage errors (2): the global options included
    ("tcp-no-port", ["--tcp", "127.0.0.1", "list"], 2, "EINVAL", "usage", "HOST:PORT"),
    ("tcp-port-range", ["--tcp", ":99999", "list"], 2, "EINVAL", "usage", "--tcp"),
    ("tcp-port-range-host", ["--tcp", "127.0.0.1:99999", "list"], 2, "EINVAL", "usage",
     "out of range"),
    ("tcp-port-nan", ["--tcp", "127.0.0.1:abc", "list"], 2, "EINVAL", "usage", "'abc'"),
    ("tcp-after-command", ["ping", "--tcp=127.0.0.1:"], 2, "EINVAL", "usage", "--tcp"),
    ("socket-empty", ["--socket", "", "list"], 2, "EINVAL", "usage", "--socket"),
    ("socket-too-long", ["--socket", "/tmp/" + "s" * 200, "list"], 2, "EINVAL", "usage",
     "too long"),
    ("socket-and-tcp", ["--socket", "/x", "--tcp", "127.0.0.1:1", "list"], 2, "EINVAL", "usage",
     "exclusive"),
    ("unknown-global", ["--bogus", "list"], 2, "EINVAL", "usage", "--bogus"),
    ("unknown-command", ["frobnicate"], 2, "EINVAL", "usage", "frobnicate"),
    ("missing-command", [], 2, "EINVAL", "usage", "missing command"),
    ("extra-argument", ["list", "extra"], 2, "EINVAL", "usage", "extra"),
    ("missing-session", ["undo"], 2, "EINVAL", "usage", "missing argument"),
    ("close-missing-session", ["close"], 2, "EINVAL", "usage", "missing argument"),
    ("unknown-option", ["undo", "TRI", "--bogus"], 2, "EINVAL", "usage", "--bogus"),
    ("brush-bad-vector", ["brush", "TRI", "--type", "grab", "--center", "0,0", "--move", "0,0,1"],
     2, "EINVAL",
     "usage", "--center"),
    ("brush-radius", ["brush", "TRI", "--type", "grab", "--center", "0,0,0", "--move", "0,0,1",
                      "--radius", "0"], 2, "EINVAL", "usage", "--radius"),
    ("watch-count", ["watch", "TRI", "--count", "0"], 2, "EINVAL", "usage", "--count"),
    ("get-extension", ["get", "TRI", "--out", "DIR/x.txt"], 2, "EINVAL", "usage", "extension"),
    ("load-missing-file", ["load", "DIR/missing.obj"], 2, "EINVAL", "usage", "missing.obj"),
    ("handles-missing-file", ["handles", "TRI", "--energy", "arap", "--handles",
                              "DIR/missing.txt"], 2, "EINVAL", "usage", "missing.txt"),
    ("handles-rho", ["handles", "TRI", "--energy", "arap", "--handles", "DIR/h.txt", "--rho",
                     "0"], 2, "EINVAL", "usage", "--rho: 0 must be > 0"),
    ("move-missing-file", ["move", "TRI", "--targets", "DIR/missing.txt"], 2, "EINVAL", "usage",
     "missing.txt"),
    ("move-handles-without-node", ["move", "TRI", "--targets", "DIR/t.txt", "--handles",
                                   "DIR/h.txt"], 2, "EINVAL", "usage", ".node"),
    ("watch-shm-over-tcp", ["--tcp", "127.0.0.1:1", "watch", "TRI", "--shm"], 2, "EINVAL",
     "usage", "--shm"),
    ("session-empty", ["undo", ""], 2, "EINVAL", "usage", "SESSION is empty"),
    # errors (1): from the daemon, the daemon unreachable, refused locally, local failures
    ("no-such-session", ["undo", "987654321"], 1, "ENOTFOUND", "server", "server: ENOTFOUND"),
    ("close-no-such-session", ["close", "987654321"], 1, "ENOTFOUND", "server",
     "server: ENOTFOUND"),
    ("stats-no-such-name", ["stats", "--session", "clierr-nonexistent"], 1, "ENOTFOUND",
     "server", "server: ENOTFOUND"),
    ("unreachable", ["--socket", "/nonexistent/deformd.sock", "ping"], 1, "EIO", "client",
     "/nonexistent/deformd.sock"),
    ("get-poly-as-off", ["get", "POLY", "--out", "DIR/x.off"], 1, "EUNSUPPORTED", "client",
     "polyline"),
    ("get-unwritable", ["get", "TRI", "--out", "DIR/no/such/dir/x.obj"], 1, "EIO", "client",
     "x.obj"),
    ("brush-rejected", ["brush", "TRI", "--type", "scale", "--center", "0,0,0", "--scale", "0.1",
                        "--nu", "0.5"], 1, "ESINGULAR", "rejected", "rejected: ESINGULAR"),
    ("handles-wrong-energy", ["handles", "POLY", "--energy", "arap", "--handles", "DIR/h.txt"], 1,
     "EINVAL", "server", "server: EINVAL"),
]


def _argv(args, s):
    out = []
    for a in args:
        a = a.replace("DIR", str(s["dir"]))
        out.append(str(s["tri"]) if a == "TRI" else str(s["poly"]) if a == "POLY" else a)
    return out


@pytest.mark.parametrize("json_mode", [False, True], ids=["text", "json"])
@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_exit_status_and_json_error_table(daemon, sessions, case, json_mode):
    """Every error exits with the README's status (2 usage, 1 anything else), names itself on
    stderr, and under --json is also one JSON object on stdout with code, name and message."""
    _, args, status, name, source, fragment = case
    argv = _argv(args, sessions)
    p = run(daemon, *((["--json"] if json_mode else []) + argv))
    assert p.returncode == status, (argv, p.returncode, p.stdout, p.stderr)
    assert fragment in p.stderr, (argv, p.stderr)
    if not json_mode:
        assert p.stdout == "", (argv, p.stdout)
        return
    lines = p.stdout.splitlines()
    assert len(lines) == 1, (argv, p.stdout)
    j = json.loads(lines[0])
    assert j["ok"] is False and j["exit"] == status and j["source"] == source, j
    assert j["name"] == name and isinstance(j["code"], int) and j["code"] < 0, j
    assert j["message"] and j["message"] in p.stderr, (j, p.stderr)


def test_json_after_the_command_also_reports_errors_as_json(daemon, sessions):
    p = run(daemon, "undo", "987654321", "--json")
    assert p.returncode == 1
    j = json.loads(p.stdout)
    assert (j["name"], j["source"], j["exit"]) == ("ENOTFOUND", "server", 1)
    p = run(daemon, "brush", str(sessions["tri"]), "--json", "--type", "smudge")
    assert p.returncode == 2 and json.loads(p.stdout)["source"] == "usage"


def test_close_by_name_and_by_id(daemon, tmp_path):
    f = tmp_path / "c.obj"
    f.write_bytes(grid_obj(4, 4))
    a = int(run(daemon, "load", f, "--name", "clierr-close-a").stdout)
    b = int(run(daemon, "load", f, "--name", "clierr-close-b").stdout)
    p = run(daemon, "close", "clierr-close-a")
    assert p.returncode == 0 and p.stdout == "closed session %d\n" % a, (p.stdout, p.stderr)
    p = run(daemon, "--json", "close", b)
    assert p.returncode == 0 and json.loads(p.stdout) == {"session": b, "closed": True}
    ids = {s["session"] for s in json.loads(run(daemon, "--json", "list").stdout)["sessions"]}
    assert a not in ids and b not in ids
    p = run(daemon, "close", "clierr-close-a")
    assert p.returncode == 1 and "ENOTFOUND" in p.stderr
    h = run(daemon, "close", "--help")
    assert h.returncode == 0 and h.stdout.startswith("usage: deformctl close SESSION\n")


def test_close_frees_a_slot_after_the_session_limit(make_daemon, tmp_path):
    """At max_sessions `load` fails ELIMIT; `close` is the way out from the CLI."""
    d = make_daemon("max_sessions = 2\n")
    f = tmp_path / "c.obj"
    f.write_bytes(grid_obj(4, 4))
    for k in range(2):
        assert run(d, "load", f, "--name", "lim-%d" % k).returncode == 0
    p = run(d, "load", f, "--name", "lim-2")
    assert p.returncode == 1 and "ELIMIT" in p.stderr, p.stderr
    assert run(d, "close", "lim-0").returncode == 0
    p = run(d, "load", f, "--name", "lim-2")
    assert p.returncode == 0, p.stderr


@pytest.mark.parametrize("opt,value,text", [
    ("--w", "-1", "--w: -1 must be >= 0"),
    ("--s", "0", "--s: 0 must be > 0"),
    ("--rho", "-2.5", "--rho: -2.5 must be > 0"),
    ("--tol", "-1e-3", "--tol: -1e-3 must be >= 0"),
    ("--poisson", "0.5", "--poisson: 0.5 must be in (-1, 0.5)"),
    ("--youngs", "0", "--youngs: 0 must be > 0"),
])
def test_handles_names_the_bad_field_and_value(daemon, sessions, opt, value, text):
    p = run(daemon, "handles", sessions["tri"], "--energy", "neohookean", "--handles",
            sessions["dir"] / "h.txt", opt, value)
    assert p.returncode == 2 and text in p.stderr, p.stderr


def test_wrong_energy_names_the_energy_to_use(daemon, sessions):
    """ARAP on a polyline: the energy is named by its wire/CLI name, never a C constant."""
    p = run(daemon, "handles", sessions["poly"], "--energy", "arap", "--handles",
            sessions["dir"] / "h.txt")
    assert p.returncode == 1, p.stderr
    assert "energy arap needs triangles or tets" in p.stderr, p.stderr
    assert "this mesh is a polyline" in p.stderr and "--energy polyline" in p.stderr, p.stderr
    assert "DF_" not in p.stderr, p.stderr
    p = run(daemon, "handles", sessions["tri"], "--energy", "neohookean", "--handles",
            sessions["dir"] / "h.txt")
    assert p.returncode == 1 and "energy neohookean needs tets" in p.stderr, p.stderr
    assert "triangle mesh" in p.stderr and "DF_" not in p.stderr, p.stderr


@pytest.mark.parametrize("btype,load", [("grab", ["--move", "0,0,0.1"]),
                                        ("twist", ["--twist", "0,0.3,0"])])
def test_ratio_too_close_to_one_is_blamed_on_the_ratio(daemon, sessions, btype, load):
    p = run(daemon, "brush", sessions["tri"], "--type", btype, "--center", "0.5,0.5,0", *load,
            "--radius", "0.3", "--falloff", "3", "--ratio", "1.0000001")
    assert p.returncode == 1, p.stderr
    assert "ratio 1.0000001 is too close to 1 for falloff order 3" in p.stderr, p.stderr
    assert "1.05 or more" in p.stderr and "radius" not in p.stderr.replace("radii", ""), p.stderr
    assert "order >= 2" not in p.stderr, p.stderr
    # the range it names works
    p = run(daemon, "brush", sessions["tri"], "--type", btype, "--center", "0.5,0.5,0", *load,
            "--radius", "0.3", "--falloff", "3", "--ratio", "1.05")
    assert p.returncode == 0, p.stderr


def test_default_nu_works_for_every_brush_type(daemon, sessions):
    """No --nu: every --type works (the default is 0.45, documented in brush --help); an explicit
    --nu 0.5 with scale says which nu to pass."""
    sid = sessions["tri"]
    loads = {"grab": ["--move", "0,0,0.01"], "twist": ["--twist", "0,0.1,0"],
             "scale": ["--scale", "0.05"], "pinch": ["--matrix", "0.05,0,0,0,-0.05,0,0,0,0"],
             "affine": ["--matrix", "0.01,0.02,0,0,0.01,0,0,0,0.03"]}
    for t, load in loads.items():
        p = run(daemon, "brush", sid, "--type", t, "--center", "0.5,0.5,0", *load,
                "--radius", "0.3")
        assert p.returncode == 0, (t, p.stderr)
    p = run(daemon, "brush", sid, "--type", "scale", "--center", "0.5,0.5,0", "--scale", "0.05",
            "--radius", "0.3", "--nu", "0.5")
    assert p.returncode == 1 and "--nu 0.45" in p.stderr, p.stderr
    h = run(daemon, "brush", "--help").stdout
    assert "default 0.45" in h, h
    pin_help = " ".join(h.split("Options:")[1].split("--pin FILE")[1].split("--pin-mode")[0]
                        .split())
    assert "3D" in pin_help and "--mirror" in pin_help and "--moving" in pin_help, pin_help
