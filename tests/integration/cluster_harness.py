"""Test harness of cluster mode (server/cluster/cluster.h): one redis-server and several deformd
daemons on loopback ports, each daemon in a tmp dir of its own with its own local store.

Redis runs with `--save '' --appendonly yes --appendfsync always` in a tmp dir, so that a kill -9
of Redis loses nothing it acknowledged (the cluster's durability is Redis's AOF). Waits poll with a
deadline (Redis readiness, a lease expiry), never sleep for a fixed time to wait for something."""
import os
import shutil
import signal
import socket
import subprocess
import tempfile
import time
from typing import List, Optional

from conftest import Daemon, check_stopped, free_tcp_port, skip_or_fail
from deformd_client import DeformdError

REDIS = shutil.which("redis-server")
LEASE_MS = 1000
DEADLINE_S = 20.0      # bound of every poll below (lease expiry is 1 s)


def redis_cmd(port: int, *args: str) -> bytes:
    """One command over RESP on a fresh connection; returns the raw reply (first line)."""
    parts = [b"*%d\r\n" % len(args)]
    for a in args:
        b = a.encode()
        parts.append(b"$%d\r\n%s\r\n" % (len(b), b))
    with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
        s.sendall(b"".join(parts))
        data = b""
        while not data.endswith(b"\r\n"):
            chunk = s.recv(65536)
            if not chunk:
                break
            data += chunk
        return data


class Redis:
    """A redis-server of its own (AOF, fsync always) in `dir` on a free loopback port."""

    def __init__(self, dir: str, port: Optional[int] = None) -> None:
        if not REDIS:
            skip_or_fail("redis-server not installed (make deps installs it)")
        self.dir = dir
        self.port = port or free_tcp_port()
        self.log = open(os.path.join(dir, "redis.log"), "ab")
        self.proc = subprocess.Popen(
            [REDIS, "--port", str(self.port), "--bind", "127.0.0.1", "--save", "",
             "--appendonly", "yes", "--appendfsync", "always", "--dir", dir],
            stdin=subprocess.DEVNULL, stdout=self.log, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + DEADLINE_S
        while True:
            try:
                if redis_cmd(self.port, "PING").startswith(b"+PONG"):
                    return
            except OSError:
                pass
            assert self.proc.poll() is None, "redis-server exited"
            assert time.monotonic() < deadline, "redis-server not ready"
            time.sleep(0.02)

    @property
    def url(self) -> str:
        return "redis://127.0.0.1:%d" % self.port

    def kill9(self) -> None:
        self.proc.kill()
        self.proc.wait()
        self.log.close()

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            self.proc.wait(30)
        self.log.close()


class Cluster:
    """`n` daemons sharing `redis`; daemons killed with kill9 are replaced by start()."""

    def __init__(self, redis: Redis, n: int, extra: str = "") -> None:
        self.redis = redis
        self.extra = extra
        self.tmps: List[tempfile.TemporaryDirectory] = []
        self.daemons: List[Daemon] = []
        self.dead: List[Daemon] = []
        for _ in range(n):
            self.daemons.append(self.start())

    def start(self) -> Daemon:
        t = tempfile.TemporaryDirectory(prefix="deformd-cluster-")
        self.tmps.append(t)
        cfg = ("store = %s\ncluster = %s\ncluster_lease_ms = %d\n%s"
               % (os.path.join(t.name, "local.db"), self.redis.url, LEASE_MS, self.extra))
        return Daemon(t.name, cfg, tcp=True)

    def by_port(self, port: int) -> Optional[Daemon]:
        for d in self.daemons:
            if d.tcp_port == port:
                return d
        return None

    def kill9(self, d: Daemon) -> None:
        """kill -9 of daemon d; a fresh daemon (new dir, new port) takes its place."""
        d.proc.kill()
        d.proc.wait()
        d._log.close()
        i = self.daemons.index(d)
        self.dead.append(d)
        self.daemons[i] = self.start()

    def stop(self) -> None:
        for d in self.daemons:
            if d.proc.poll() is not None:    # died during the test: its log tells why
                print("daemon on port %d exited with %s:\n%s" % (d.tcp_port, d.proc.returncode,
                                                                d.log()[-3000:]))
        for d in self.daemons:
            if d.proc.poll() is None and d.proc.returncode is None:
                try:
                    os.kill(d.proc.pid, signal.SIGCONT)   # a test may have stopped it
                except OSError:
                    pass
            check_stopped(d, d.stop())
        for t in self.tmps:
            t.cleanup()


def owner_port(c) -> int:
    """The TCP port of the daemon a (moved) client is connected to, 0 on a Unix socket."""
    try:
        return c.sock.getpeername()[1]
    except (OSError, TypeError, IndexError):
        return 0


def poll_until(fn, what: str, deadline_s: float = DEADLINE_S):
    """Calls fn() until it returns without OSError / DeformdError / ConnectionError (a lease not
    expired yet, its holder dead), at most deadline_s; returns its value."""
    deadline = time.monotonic() + deadline_s
    last = None
    while time.monotonic() < deadline:
        try:
            return fn()
        except (OSError, DeformdError, ConnectionError) as e:
            last = e
            time.sleep(0.02)
    raise AssertionError("%s: not within %.0f s (last error %r)" % (what, deadline_s, last))
