"""Unix-socket access control (issue 12, access control item 1): SO_PEERCRED is read per
connection and, with allow_uids / allow_gids, a peer matching neither list gets one ERROR event
(EPROTO_AUTH, naming its uid and pid) and is closed, before any request runs; the refusal is
logged with uid and pid and counted (clients_refused_peer). A listed uid, a listed primary group,
or a listed user name are let in. Bad entries refuse start-up with a message naming the key."""
import os
import pwd
import socket
import subprocess
import tempfile
import time

import pytest

from conftest import DEFORMD, Daemon, check_stopped
from deformd_client import DeformdError, errors as E, frame as fr, messages as m
from rawwire import read_frames, wait_closed

START_TIMEOUT_S = 15.0


class TcpReadyDaemon(Daemon):
    """A daemon whose readiness is checked over TCP only (its Unix socket may refuse the test)."""

    def _wait_ready(self) -> None:
        deadline = time.monotonic() + 15.0
        last = None
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                raise RuntimeError("deformd exited with status %d:\n%s"
                                   % (self.proc.returncode, self.log()))
            try:
                with self.tcp_client() as c:
                    c.ping(b"ready")
                return
            except (OSError, DeformdError) as e:
                last = e
                time.sleep(0.05)
        self.proc.kill()
        raise RuntimeError("deformd not ready (last error %r):\n%s" % (last, self.log()))


@pytest.fixture
def tcp_ready_daemon():
    made = []

    def make(extra_config: str) -> Daemon:
        tmp = tempfile.TemporaryDirectory(prefix="deformd-it-")
        d = TcpReadyDaemon(tmp.name, extra_config, tcp=True)
        made.append((d, tmp))
        return d

    yield make
    for d, tmp in made:
        check_stopped(d, d.stop())
        tmp.cleanup()


def other_uid() -> int:
    """A uid that is not ours (nobody's, or ours + 1)."""
    try:
        u = pwd.getpwnam("nobody").pw_uid
    except KeyError:
        u = os.getuid() + 1
    return u if u != os.getuid() else os.getuid() + 1


def test_unlisted_uid_gets_an_error_frame_and_is_closed(tcp_ready_daemon):
    d = tcp_ready_daemon("allow_uids = %d\n" % other_uid())
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.connect(d.socket_path)
    # a request sent right away is never executed: the refusal comes first, then the close.
    # The daemon may have closed before the request is written (EPIPE): the refusal frame is
    # still in this socket's receive queue, and the request was never executed either way.
    try:
        s.sendall(fr.encode_frame(m.LIST_SESSIONS, b"", 7))
    except (BrokenPipeError, ConnectionResetError):
        pass
    frames, closed = read_frames(s, timeout=10.0, want=2)
    assert closed or wait_closed(s, 10.0), "refused peer not closed"
    assert len(frames) == 1, frames
    f = frames[0]
    assert f.is_error and f.type == m.ERROR and f.request_id == 0
    code, msg = m.decode_error(f.payload)
    assert code == E.ErrorCode.EPROTO_AUTH, (code, msg)
    assert ("uid %d" % os.getuid()) in msg and ("pid %d" % os.getpid()) in msg, msg
    assert "allow_uids" in msg, msg
    s.close()
    log = d.log()
    assert "refused" in log and ("uid %d" % os.getuid()) in log and ("pid %d" % os.getpid()) in log
    with d.tcp_client() as c:
        st = c.stats()
        assert st["clients_refused_peer"] == 1
        assert st["requests_ok"] + st["requests_failed"] >= 1  # the TCP pings; nothing else
        assert c.list_sessions() == []


@pytest.mark.parametrize("setting", ["uid", "name", "gid", "uid_among_others"])
def test_listed_peer_is_served(tcp_ready_daemon, setting):
    me = os.getuid()
    conf = {"uid": "allow_uids = %d\n" % me,
            "name": "allow_uids = %s\n" % pwd.getpwuid(me).pw_name,
            "gid": "allow_uids = %d\nallow_gids = %d\n" % (other_uid(), os.getgid()),
            "uid_among_others": "allow_uids = %d, %d\n" % (other_uid(), me)}[setting]
    d = tcp_ready_daemon(conf)
    with d.unix_client() as c:
        assert c.ping(b"in") == b"in"
        assert c.stats()["clients_refused_peer"] == 0


@pytest.mark.parametrize("conf,needle", [
    ("allow_uids = no-such-user-deformd\n", "allow_uids: no user 'no-such-user-deformd'"),
    ("allow_gids = no-such-group-deformd\n", "allow_gids: no group 'no-such-group-deformd'"),
    ("allow_uids = ,\n", "allow_uids: empty list"),
])
def test_bad_allow_lists_refuse_start(tmp_path, conf, needle):
    cfg = tmp_path / "d.conf"
    cfg.write_text(conf)
    r = subprocess.run([DEFORMD, "--foreground", "--config", str(cfg), "--socket",
                        str(tmp_path / "d.sock")], stdin=subprocess.DEVNULL,
                       capture_output=True, timeout=START_TIMEOUT_S,
                       env=dict(os.environ, XDG_RUNTIME_DIR=str(tmp_path)))
    assert r.returncode != 0
    err = r.stderr.decode("utf-8", "replace")
    assert needle in err, err
    assert not os.path.exists(tmp_path / "d.sock")
