"""deformd's own command line and configuration: --help, bad options and config files are
refused with a message, TCP is off unless configured, the default socket lives under
$XDG_RUNTIME_DIR, --log-level debug logs requests, max_sessions is enforced."""
import os
import socket
import subprocess
import tempfile
import time

import pytest

from conftest import DEFORMD
from deformd_client import Client, DeformdError, errors as E, frame as fr, messages as m
from helpers import grid_obj


def run(*args, env=None, timeout=10):
    return subprocess.run([DEFORMD] + list(args), capture_output=True, text=True,
                          timeout=timeout, stdin=subprocess.DEVNULL, env=env)


def test_help_lists_every_option():
    p = run("--help")
    assert p.returncode == 0
    for opt in ("--socket", "--tcp", "--config", "--foreground", "--log-level", "--help"):
        assert opt in p.stdout, opt


@pytest.mark.parametrize("args", [["--bogus"], ["--log-level", "loud"], ["--tcp", "nope"],
                                  ["--config", "/nonexistent/deformd.conf"]])
def test_bad_command_lines_are_refused(args):
    p = run("--foreground", "--socket", "none", *args)
    assert p.returncode != 0 and p.stderr.strip(), (args, p.returncode, p.stderr)


def test_bad_config_file_names_the_line(tmp_path):
    conf = tmp_path / "d.conf"
    conf.write_text("# ok\nlog_level = info\nfrobnicate = 1\n")
    p = run("--foreground", "--config", str(conf), "--socket", str(tmp_path / "s"))
    assert p.returncode != 0 and "d.conf:3" in p.stderr, p.stderr


@pytest.mark.parametrize("lines,where,what", [
    ("hid.knob.radius_step = 1.2\nhid.knob.radiuss = 2\n", "d.conf:2", "radiuss"),
    ("hid.pen.pressure_gamma = 0\n", "d.conf:1", "pressure_gamma"),
    ("hid.3d-mouse.radius_step = 1.2\n", "d.conf:1", "not a 3d-mouse key"),
    ("hid.046d:c62.deadzone = 0.1\n", "d.conf:1", "VID:PID"),
    ("hid.knob.nu_min = 0.4\nhid.knob.nu_max = 0.3\n", "d.conf", "nu_min 0.4 above nu_max"),
])
def test_bad_hid_keys_name_the_file_and_line(tmp_path, lines, where, what):
    conf = tmp_path / "d.conf"
    conf.write_text(lines)
    p = run("--foreground", "--config", str(conf), "--socket", str(tmp_path / "s"))
    assert p.returncode != 0 and where in p.stderr and what in p.stderr, p.stderr


def test_tcp_is_off_unless_configured_and_the_default_socket_is_under_xdg():
    with tempfile.TemporaryDirectory(prefix="deformd-xdg-") as xdg:
        env = dict(os.environ, XDG_RUNTIME_DIR=xdg)
        proc = subprocess.Popen([DEFORMD, "--foreground", "--log-level", "debug"],
                                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                stderr=subprocess.PIPE, env=env, text=True)
        try:
            path = os.path.join(xdg, "deformd.sock")
            for _ in range(1200):                          # 60 s guard
                if os.path.exists(path):
                    break
                time.sleep(0.05)
            with Client.connect_unix(path, timeout=10) as c:
                h = c.server
                assert not h.features & m.FEAT_TCP
                assert not h.features & m.FEAT_PATH_LOAD      # no allow_paths configured
                with pytest.raises(DeformdError) as ei:
                    c.load_mesh(path="/etc/hostname")
                assert ei.value.code in (E.EUNSUPPORTED, E.EINVAL)
                c.ping(b"debug me")
        finally:
            proc.terminate()
            _, err = proc.communicate(timeout=15)
        assert proc.returncode == 0, err
        assert "ping" in err                                  # debug logs every request
        assert not os.path.exists(path), "socket file left behind"


def test_max_sessions_is_enforced(make_daemon):
    d = make_daemon("max_sessions = 2\n")
    with d.unix_client() as c:
        assert c.server.max_sessions == 2
        a = c.load_mesh(grid_obj(3, 3), fmt=".obj").session_id
        c.load_mesh(grid_obj(3, 3), fmt=".obj")
        with pytest.raises(DeformdError) as ei:
            c.load_mesh(grid_obj(3, 3), fmt=".obj")
        assert ei.value.code == E.ELIMIT
        c.close_session(a)
        c.load_mesh(grid_obj(3, 3), fmt=".obj")               # room again


def test_tcp_listener_accepts_raw_clients(daemon):
    s = socket.create_connection(("127.0.0.1", daemon.tcp_port), timeout=5)
    s.sendall(fr.encode_frame(m.PING, b"tcp", 9))
    dec = fr.FrameDecoder()
    frames = []
    while not frames:
        frames = dec.feed(s.recv(4096))
    assert frames[0].payload == b"tcp" and frames[0].request_id == 9 and frames[0].is_reply
    s.close()
