"""Fixtures of the deformd integration suite.

`daemon` (session scope) starts the real $BUILD/bin/deformd (BUILD defaults to "build", relative
to the repo root) in the foreground on a temporary Unix socket and a free loopback TCP port, waits
until it answers a ping on both, and on teardown stops it with SIGTERM and checks it exits with
status 0 and that its log holds no ThreadSanitizer report (`make tsan` builds an instrumented
deformd; TSAN_OPTIONS=halt_on_error=1 also ends it at the first report, failing the suite).
`make_daemon` starts extra daemons with their own config (e.g. a small output queue).
Meshes come from $MESHES (default ../shared/meshes next to the repo); `meshes` skips when absent
(skip_or_fail: under CI=true every skip is a failure). A missing deformd always fails.
"""
import os
import signal
import socket
import subprocess
import tempfile
import time
from typing import Optional

import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
from deformd_client import Client, DeformdError, FrameDecoder, encode_frame
from deformd_client.messages import HELLO, encode_hello

BUILD = os.path.join(ROOT, os.environ.get("BUILD", "build"))
DEFORMD = os.path.join(BUILD, "bin", "deformd")
DEFORMCTL = os.path.join(BUILD, "bin", "deformctl")
MESHES = os.environ.get("MESHES") or os.path.join(ROOT, "..", "shared", "meshes")

READY_TIMEOUT_S = 15.0
STOP_TIMEOUT_S = 15.0


def free_tcp_port() -> int:
    """A loopback port that was free a moment ago (bound to 0 then released)."""
    s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


class Daemon:
    """One running deformd: its socket path, TCP port, process and log file."""

    def __init__(self, tmpdir: str, extra_config: str = "", tcp: bool = True,
                 tls_ca: Optional[str] = None) -> None:
        self.dir = tmpdir
        self.tls_ca = tls_ca   # the daemon's TCP is TLS (tls_cert): clients verify with this CA
        self.socket_path = os.path.join(tmpdir, "deformd.sock")
        self.tcp_port = free_tcp_port() if tcp else 0
        self.log_path = os.path.join(tmpdir, "deformd.log")
        self.config_path = os.path.join(tmpdir, "deformd.conf")
        with open(self.config_path, "w") as f:
            f.write("# written by tests/integration/conftest.py\n")
            f.write("log_level = info\n")
            f.write("store = none\n")   # memory only unless the test's extra_config sets a store
            if os.path.isdir(MESHES):
                f.write("allow_paths = %s\n" % os.path.realpath(MESHES))
            f.write(extra_config)
        args = [DEFORMD, "--foreground", "--config", self.config_path,
                "--socket", self.socket_path]
        if tcp:
            args += ["--tcp", "127.0.0.1:%d" % self.tcp_port]
        self._log = open(self.log_path, "wb")
        env = dict(os.environ)
        env["XDG_RUNTIME_DIR"] = tmpdir
        env["XDG_STATE_HOME"] = tmpdir      # a default store (store = "") stays in the tmp dir
        env.pop("STATE_DIRECTORY", None)
        self.proc = subprocess.Popen(args, stdin=subprocess.DEVNULL, stdout=self._log,
                                     stderr=subprocess.STDOUT, env=env, cwd=tmpdir)
        self._wait_ready()

    def log(self) -> str:
        if not self._log.closed:
            self._log.flush()
        with open(self.log_path, "rb") as f:
            return f.read().decode("utf-8", "replace")

    def _wait_ready(self) -> None:
        deadline = time.monotonic() + READY_TIMEOUT_S
        last = None
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                raise RuntimeError("deformd exited with status %d before it was ready:\n%s"
                                   % (self.proc.returncode, self.log()))
            try:
                with self.unix_client() as c:
                    c.ping(b"ready")
                if self.tcp_port:
                    with self.tcp_client() as c:
                        c.ping(b"ready")
                return
            except (OSError, DeformdError) as e:
                last = e
                time.sleep(0.05)
        self.proc.kill()
        raise RuntimeError("deformd not ready after %.0f s (last error: %r):\n%s"
                           % (READY_TIMEOUT_S, last, self.log()))

    def unix_client(self, timeout: float = 30.0, hello: bool = True) -> Client:
        return Client.connect_unix(self.socket_path, timeout=timeout, hello=hello)

    def tcp_client(self, timeout: float = 30.0, hello: bool = True) -> Client:
        return Client.connect_tcp("127.0.0.1", self.tcp_port, timeout=timeout, hello=hello,
                                  tls_ca=self.tls_ca)

    def raw_unix(self, timeout: float = 5.0, hello: bool = False) -> socket.socket:
        """A plain socket; with hello=True the HELLO exchange is done (and checked) on it."""
        s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        s.settimeout(timeout)
        s.connect(self.socket_path)
        if hello:
            s.sendall(encode_frame(HELLO, encode_hello(1, 1, 0, "raw"), 0xFFFF))
            dec = FrameDecoder()
            frames = []
            while not frames:
                data = s.recv(65536)
                assert data, "deformd closed the connection during HELLO"
                frames = dec.feed(data)
            assert frames[0].request_id == 0xFFFF and not frames[0].is_error
        return s

    def alive(self) -> bool:
        return self.proc.poll() is None

    def stop(self) -> int:
        """SIGTERM, wait; returns the exit status (kills and returns -9 on a hang)."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(STOP_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
                self._log.close()
                return -9
        self._log.close()
        return self.proc.returncode


TSAN_MARK = "WARNING: ThreadSanitizer"


def check_stopped(d: "Daemon", rc: int) -> None:
    """Fails when the stopped daemon `d` (exit status rc) logged a sanitizer report or did not exit
    with status 0 (the log is kept in the tmp dir's deformd-it-last-failure.log)."""
    log = d.log()
    if rc != 0 or TSAN_MARK in log:
        with open(os.path.join(tempfile.gettempdir(), "deformd-it-last-failure.log"), "w") as f:
            f.write(log)
    at = log.find(TSAN_MARK)
    assert at < 0, "ThreadSanitizer report in deformd's log:\n%s" % log[max(0, at - 200):at + 6000]
    assert rc == 0, "deformd exited with status %d on SIGTERM:\n%s" % (rc, log[-4000:])


@pytest.fixture(autouse=True)
def _private_state_home(tmp_path_factory, monkeypatch):
    """Every daemon a test starts itself (not through Daemon, which writes store = none) keeps
    its default store (XDG_STATE_HOME/deformd/deformd.db) in a directory of its own test, never
    in the user's home nor shared between tests."""
    monkeypatch.setenv("XDG_STATE_HOME", str(tmp_path_factory.mktemp("state")))
    monkeypatch.delenv("STATE_DIRECTORY", raising=False)


def _require_binary() -> None:
    if not os.access(DEFORMD, os.X_OK):
        pytest.fail("%s is missing: build it first (make -j2)" % DEFORMD, pytrace=False)


@pytest.fixture(scope="session")
def daemon():
    _require_binary()
    with tempfile.TemporaryDirectory(prefix="deformd-it-") as tmp:
        d = Daemon(tmp)
        yield d
        check_stopped(d, d.stop())


@pytest.fixture
def make_daemon():
    """Factory: make_daemon(extra_config) -> Daemon, stopped (and checked) after the test."""
    _require_binary()
    made = []
    tmps = []

    def make(extra_config: str = "", tcp: bool = False, tls_ca: Optional[str] = None) -> Daemon:
        tmp = tempfile.TemporaryDirectory(prefix="deformd-it-")
        tmps.append(tmp)
        d = Daemon(tmp.name, extra_config, tcp, tls_ca)
        made.append(d)
        return d

    yield make
    for d in made:
        check_stopped(d, d.stop())
    for t in tmps:
        t.cleanup()


def skip_or_fail(reason: str) -> None:
    """The suite's one skip helper: skips the running test with `reason`, or, under CI (environment
    CI=true), fails it, so that a missing prerequisite fails a CI run instead of thinning it out."""
    if os.environ.get("CI") == "true":
        pytest.fail("%s (CI=true: a skip is a failure)" % reason, pytrace=False)
    pytest.skip(reason)


@pytest.fixture(scope="session")
def meshes() -> str:
    """The shared mesh folder; skips the test (with the reason) when it is absent (fails under CI)."""
    if not os.path.isdir(MESHES):
        skip_or_fail("shared meshes not found at %s (set MESHES)" % MESHES)
    return MESHES
