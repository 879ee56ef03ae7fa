"""The Blender add-on (client/blender/deformd_blender, issue 13) in the real Blender that Debian
packages: each case of tests/blender/bl_headless.py runs in its own headless Blender
(`blender -b --factory-startup --python-exit-code 1`) against a daemon this test starts, with
the add-on installed from build/blender/deformd_blender.zip (what `make` builds) into a temporary
user scripts folder. tests/blender/bl_gui.py drives the modal sculpt operator under Xvfb with
simulated events. A missing blender / xvfb-run skips (fails under CI=true: make deps installs
them)."""
import json
import math
import os
import shutil
import subprocess

import numpy as np
import pytest

from conftest import BUILD, ROOT, skip_or_fail
from helpers import grab_displacement
from test_hid import replay_config
from test_tls import make_ca, make_server_cert, write_key

ZIP = os.path.join(BUILD, "blender", "deformd_blender.zip")
SCRIPTS = os.path.join(ROOT, "tests", "blender")
BLENDER_TIMEOUT_S = 120


def need(program):
    path = shutil.which(program)
    if path is None:
        skip_or_fail("%s not installed (make deps installs it)" % program)
    return path


def blender_env(tmp_path):
    """A private user config / scripts / temp folder: no user add-ons or preferences leak in,
    and Blender's quit.blend lands in the test's folder."""
    env = dict(os.environ)
    for k, sub in (("BLENDER_USER_CONFIG", "config"), ("BLENDER_USER_SCRIPTS", "scripts"),
                   ("TEMP", "temp"), ("TMPDIR", "temp")):
        os.makedirs(tmp_path / sub, exist_ok=True)
        env[k] = str(tmp_path / sub)
    env.pop("PYTHONPATH", None)
    return env


def run_blender(args, env, script, extra):
    need("blender")
    if not os.path.isfile(ZIP):
        pytest.fail("%s is missing: build it first (make -j2)" % ZIP, pytrace=False)
    cmd = args + ["--python", os.path.join(SCRIPTS, script), "--", "--zip", ZIP] + extra
    p = subprocess.run(cmd, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                       stderr=subprocess.STDOUT, timeout=BLENDER_TIMEOUT_S)
    out = p.stdout.decode("utf-8", "replace")
    assert p.returncode == 0, "blender exited with %d:\n%s" % (p.returncode, out[-6000:])
    assert "Traceback" not in out, out[-6000:]
    return out


def headless(tmp_path, case, daemon, out=None):
    extra = ["--case", case, "--socket", daemon.socket_path, "--daemon-pid", str(daemon.proc.pid)]
    if out is not None:
        extra += ["--out", str(out)]
    log = run_blender(["blender", "-b", "--factory-startup", "--python-exit-code", "1"],
                      blender_env(tmp_path), "bl_headless.py", extra)
    assert "bl_headless: case %s passed" % case in log, log[-4000:]
    return log


@pytest.mark.parametrize("case", ["register", "second_user", "brush_state", "undo",
                                  "join_reconnect", "handles", "elastic", "modifiers", "progress",
                                  "peers"])
def test_blender_headless(tmp_path, make_daemon, case):
    headless(tmp_path, case, make_daemon(), tmp_path / "out.json")


def test_blender_knob_drives_the_panel(tmp_path, make_daemon):
    """A PowerMate recording replayed by the daemon (hid_replay, speed 0) changes the session
    brush; the panel's values follow each BRUSH_STATE and end at BRUSH_STATE_GET's."""
    d = make_daemon(replay_config(["griffin-powermate_077d-0410_usb.raw.txt"]))
    headless(tmp_path, "knob", d)


@pytest.mark.parametrize("case,config", [("reconnect_replay", ""),
                                         ("reconnect_snapshot", "resync_ring_mb = 0\n")])
def test_blender_reconnect_resync(tmp_path, make_daemon, case, config):
    """Reconnect after another client's strokes: SUBSCRIBE from_version replays what the object
    missed when the daemon keeps it (resync ring), a snapshot when it keeps nothing (ring 0);
    either way the object is GET_MESH bit for bit and the add-on counts which it was."""
    headless(tmp_path, case, make_daemon(config))


def test_blender_scripted_stroke_is_the_kelvinlet_grab(tmp_path, make_daemon):
    """deformd.stroke (object space) gives Blender the daemon's positions bit for bit (checked
    inside Blender against GET_MESH) and those are the Kelvinlet grab of the reference formula
    on the uploaded positions, i.e. the operator sent what it was given."""
    out = tmp_path / "stroke.json"
    headless(tmp_path, "share_stroke", make_daemon(), out)
    r = json.loads(out.read_text())
    base = np.array(r["base"], dtype=np.float64).reshape(-1, 3)
    after = np.array(r["after"], dtype=np.float64).reshape(-1, 3)
    worst = 0.0
    for x, y in zip(base, after):
        u = grab_displacement(x, r["center"], r["move"], r["radius"], r["nu"])
        worst = max(worst, max(abs(y[k] - x[k] - u[k]) for k in range(3)))
    assert worst < 1e-5, worst
    assert np.abs(after - base).max() > 0.01


def test_blender_tcp_with_key_and_tls(tmp_path, make_daemon):
    """The add-on over TCP with the daemon's key and TLS (preferences key_file and tls_ca)."""
    pki = str(tmp_path / "pki")
    os.makedirs(pki)
    ca = make_ca(pki, "ca")
    cert = make_server_cert(pki, ca, "server")
    kf, wrong = str(tmp_path / "deformd.key"), str(tmp_path / "wrong.key")
    write_key(kf)
    write_key(wrong)
    d = make_daemon("key_file = %s\ntls_cert = %s\ntls_key = %s\n" % (kf, cert[0], cert[1]),
                    tcp=True, tls_ca=ca[0])
    extra = ["--case", "tls", "--socket", d.socket_path, "--tcp", "localhost:%d" % d.tcp_port,
             "--key-file", kf, "--wrong-key-file", wrong, "--tls-ca", ca[0]]
    log = run_blender(["blender", "-b", "--factory-startup", "--python-exit-code", "1"],
                      blender_env(tmp_path), "bl_headless.py", extra)
    assert "bl_headless: case tls passed" in log, log[-4000:]


def test_blender_error_reports(tmp_path, make_daemon):
    """Bad address, missing socket, unknown session, a refused stroke, the daemon going away:
    each an operator report (no traceback); the object keeps its last synced positions."""
    d = make_daemon()
    headless(tmp_path, "errors", d, tmp_path / "errors.json")
    assert not d.alive()        # the case stopped it (SIGTERM); teardown checks its status 0


def test_blender_gui_modal_sculpt(tmp_path, make_daemon):
    """Under Xvfb (software GL, splash off through a user preferences file): the modal sculpt
    operator driven by simulated mouse events (grab, Ctrl twist) deforms the mesh exactly as the
    daemon says, the 60 Hz timer applies another user's stroke, the large-mesh overlay is drawn
    and the mesh written when the stream pauses, the handle drag moves the handles, the panel
    draws, and a screenshot differs from the one before the stroke."""
    need("xvfb-run")
    d = make_daemon()
    env = blender_env(tmp_path)
    run_blender(["blender", "-b", "--factory-startup", "--python-exit-code", "1"], env,
                "bl_userpref.py", [])
    assert os.path.isfile(os.path.join(env["BLENDER_USER_CONFIG"], "userpref.blend"))
    env["LIBGL_ALWAYS_SOFTWARE"] = "1"
    out = tmp_path / "gui.json"
    log = run_blender(["xvfb-run", "-a", "-s", "-screen 0 800x600x24", "blender",
                       "--window-geometry", "0", "0", "640", "480", "--enable-event-simulate",
                       "--python-exit-code", "1"], env, "bl_gui.py",
                      ["--socket", d.socket_path, "--out", str(out)])
    r = json.loads(out.read_text())
    assert r["passed"], log[-4000:]
    assert r["timer_ticks"] > 0 and r["updates_sent"] >= 1 and r["versions"] >= 2
    assert r["panel_draws"] > 0 and r["handle_move"] > 0
    with d.unix_client() as c:
        pos = np.frombuffer(c.get_mesh(r["session"]).positions, dtype=np.float32)
    assert pos.tobytes().hex() == r["blender_positions_hex"]
    for shot in ("before", "after"):
        assert os.path.getsize(r[shot]) > 1000
    assert r["pixels_changed"] > 0
    assert math.isfinite(r["max_displacement"]) and r["max_displacement"] > 0
