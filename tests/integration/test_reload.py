"""deformd --check-config and SIGHUP reload (server/config_check.h, server/reload.h).

SIGHUP: the live settings (log_level, allow_paths, max_clients, ...) change, observed through
requests; a settings change that needs a restart is logged by name; a file with an error is
logged with its FILE:LINE and the daemon keeps serving with its previous settings."""
import os
import signal
import subprocess
import time

import pytest

from conftest import DEFORMD
from deformd_client import Client, DeformdError
from helpers import grid_obj

WAIT_S = 15.0


def wait_log(d, needle: str, after: int) -> str:
    """Waits until the daemon's log holds `needle` past offset `after`; returns that part."""
    deadline = time.monotonic() + WAIT_S
    while time.monotonic() < deadline:
        tail = d.log()[after:]
        if needle in tail:
            return tail
        assert d.alive(), "deformd died:\n%s" % d.log()[-3000:]
        time.sleep(0.02)
    raise AssertionError("%r not logged within %.0f s:\n%s" % (needle, WAIT_S, d.log()[-3000:]))


def rewrite_and_hup(d, text: str, needle: str) -> str:
    """Replaces the daemon's config file with `text`, sends SIGHUP, waits for `needle`."""
    at = len(d.log())
    with open(d.config_path, "w") as f:
        f.write(text)
    d.proc.send_signal(signal.SIGHUP)
    return wait_log(d, needle, at)


def hello_named(d, name: str) -> None:
    with Client.connect_unix(d.socket_path, hello=False) as c:
        c.hello(name)
        c.ping(b"x")


@pytest.fixture
def mesh_dir(tmp_path):
    """A directory outside every allow_paths entry holding one small OBJ."""
    d = tmp_path / "meshes-later"
    d.mkdir()
    (d / "grid.obj").write_bytes(grid_obj(4, 4))
    return str(d.resolve())


def test_sighup_changes_log_level_and_allow_paths_live(make_daemon, mesh_dir):
    d = make_daemon("")
    path = os.path.join(mesh_dir, "grid.obj")
    with d.unix_client() as c:
        with pytest.raises(DeformdError):
            c.load_mesh(path=path, fmt=".obj")
    at = len(d.log())
    hello_named(d, "before-reload-client")
    assert "before-reload-client" not in d.log()[at:]  # info: the HELLO name is a debug line

    rewrite_and_hup(d, "log_level = debug\nallow_paths = %s\n" % mesh_dir,
                    "configuration reloaded")
    at = len(d.log())
    hello_named(d, "after-reload-client")
    wait_log(d, "'after-reload-client'", at)
    with d.unix_client() as c:
        info = c.load_mesh(path=path, fmt=".obj")
        assert info.nv == 16
        c.close_session(info.session_id)

    # back to info and an allow list without that directory: refused again, quiet again
    rewrite_and_hup(d, "log_level = info\nallow_paths = %s/nonexistent-dir\n"
                    % os.path.dirname(mesh_dir), "configuration reloaded")
    at = len(d.log())
    with d.unix_client() as c:
        with pytest.raises(DeformdError):
            c.load_mesh(path=path, fmt=".obj")
    hello_named(d, "quiet-again-client")
    assert "quiet-again-client" not in d.log()[at:]


def test_sighup_max_clients_applies_to_new_connections(make_daemon):
    d = make_daemon("")
    rewrite_and_hup(d, "max_clients = 1\n", "configuration reloaded")
    with d.unix_client() as first:
        with pytest.raises((DeformdError, OSError)) as e:
            with d.unix_client(timeout=10) as second:
                second.ping(b"y")
        assert "max_clients" in str(e.value)
        assert first.ping(b"still") == b"still"


def test_sighup_with_a_broken_file_keeps_the_old_settings(make_daemon, mesh_dir):
    d = make_daemon("")
    path = os.path.join(mesh_dir, "grid.obj")
    rewrite_and_hup(d, "log_level = debug\nallow_paths = %s\n" % mesh_dir,
                    "configuration reloaded")
    tail = rewrite_and_hup(d, "log_level = info\nallow_paths = /\nmax_clients = many\n",
                           "keeping the current settings")
    assert "%s:3: max_clients" % d.config_path in tail
    assert "configuration reloaded" not in tail
    at = len(d.log())
    hello_named(d, "still-debug-client")  # log_level stays debug
    wait_log(d, "'still-debug-client'", at)
    with d.unix_client() as c:  # allow_paths stays the old list: this directory loads
        info = c.load_mesh(path=path, fmt=".obj")
        c.close_session(info.session_id)
    assert d.alive()


def test_sighup_names_the_settings_that_need_a_restart(make_daemon):
    d = make_daemon("")
    tail = rewrite_and_hup(d, "threads = 2\nmax_sessions = 3\nhid.knob.radius_step = 1.2\n",
                           "configuration reloaded")
    warn = [l for l in tail.splitlines() if "need a restart" in l]
    assert len(warn) == 1 and "threads" in warn[0] and "hid.*" in warn[0], tail
    assert "max_sessions" not in warn[0]
    assert "max_sessions 3" in tail


def check(*args, cwd=None):
    return subprocess.run([DEFORMD, "--check-config"] + list(args), capture_output=True,
                          text=True, cwd=cwd, timeout=30)


def test_check_config_ok_binds_nothing(tmp_path):
    conf = tmp_path / "ok.conf"
    conf.write_text("log_level = debug\nmax_clients = 8\n")
    sock = tmp_path / "s.sock"
    r = check("--config", str(conf), "--socket", str(sock))
    assert r.returncode == 0 and r.stdout == "config ok\n", r
    assert not sock.exists()


def test_check_config_names_file_and_line_of_each_problem(tmp_path):
    conf = tmp_path / "bad.conf"
    lines = ["# comment", "allow_paths = /nonexistent-deformd-dir",
             "socket_group = no-such-group-deformd", "tcp = 0.0.0.0:0",
             "socket = %s/missing-dir/s.sock" % tmp_path]
    conf.write_text("\n".join(lines) + "\n")
    r = check("--config", str(conf))
    assert r.returncode == 2 and r.stdout == "", r
    err = r.stderr.splitlines()
    assert len(err) == 4, r.stderr
    for key in ("allow_paths", "socket_group", "tcp", "socket"):
        n = next(i + 1 for i, l in enumerate(lines) if l.startswith(key + " "))
        assert any(l.startswith("%s:%d: " % (conf, n)) for l in err), (key, r.stderr)
    # the command line overrides the file and is named as such
    r = check("--config", str(conf), "--socket", str(tmp_path / "x" / "s.sock"))
    assert any(l.startswith("command line: socket") for l in r.stderr.splitlines()), r.stderr


def test_check_config_reports_a_parse_error_and_a_bad_replay_file(tmp_path):
    conf = tmp_path / "parse.conf"
    conf.write_text("log_level = info\n\nthreads = 0\n")
    r = check("--config", str(conf))
    assert r.returncode == 2 and "%s:3: threads" % conf in r.stderr, r
    bad = tmp_path / "bad.hid"
    bad.write_text("this is not a hid-recorder file\n")
    conf.write_text("hid = off\nhid_replay = %s\n" % bad)
    r = check("--config", str(conf), "--socket", str(tmp_path / "s.sock"))
    assert r.returncode == 2 and r.stderr.startswith("%s:2: hid_replay" % conf), r


def test_sighup_of_a_daemonized_deformd_rereads_a_relative_config_path(tmp_path):
    """Without --foreground deformd forks and moves to /; SIGHUP still finds `--config rel.conf`
    from the directory it was started in."""
    (tmp_path / "rel.conf").write_text("log_level = info\n")
    sock = str(tmp_path / "d.sock")
    log_path = tmp_path / "d.log"
    with open(log_path, "wb") as log:
        r = subprocess.run([DEFORMD, "--config", "rel.conf", "--socket", sock], cwd=str(tmp_path),
                           stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                           timeout=60)
    assert r.returncode == 0, log_path.read_text()  # the parent exits once the child is ready
    pids = [int(p) for p in os.listdir("/proc") if p.isdigit() and
            _cmdline(p).startswith(DEFORMD + "\0") and sock in _cmdline(p)]
    assert len(pids) == 1, pids
    try:
        assert os.readlink("/proc/%d/cwd" % pids[0]) == "/"
        at = len(log_path.read_text())
        (tmp_path / "rel.conf").write_text("log_level = debug\n")
        os.kill(pids[0], signal.SIGHUP)
        deadline = time.monotonic() + WAIT_S
        while "configuration reloaded" not in log_path.read_text()[at:]:
            assert time.monotonic() < deadline, log_path.read_text()
            time.sleep(0.02)
        assert "keeping the current settings" not in log_path.read_text()[at:]
        assert os.readlink("/proc/%d/cwd" % pids[0]) == "/"
        with Client.connect_unix(sock, hello=False) as c:
            c.hello("daemonized-debug")
        at2 = log_path.read_text()
        assert "'daemonized-debug'" in at2[at:], at2
    finally:
        os.kill(pids[0], signal.SIGTERM)
        deadline = time.monotonic() + WAIT_S
        while os.path.exists("/proc/%d" % pids[0]) and _cmdline(str(pids[0])):
            assert time.monotonic() < deadline
            time.sleep(0.02)


def _cmdline(pid: str) -> str:
    try:
        with open("/proc/%s/cmdline" % pid) as f:
            return f.read()
    except OSError:
        return ""
