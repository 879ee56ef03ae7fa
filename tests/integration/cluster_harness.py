"""Test harness of cluster mode (server/cluster/cluster.h): one redis-server (or a Redis Cluster of
several masters) and several deformd daemons on loopback ports, each daemon in a tmp dir of its own
with its own local store; and the stroke storm (Storm) the failover tests drive through it, mirrored
onto a plain "shadow" daemon that receives exactly the acknowledged requests.

Redis runs with `--save '' --appendonly yes --appendfsync always` in a tmp dir, so that a kill -9
of Redis loses nothing it acknowledged (the cluster's durability is Redis's AOF). Waits poll with a
deadline (Redis readiness, a lease expiry), never sleep for a fixed time to wait for something."""
import contextlib
import os
import shutil
import signal
import socket
import subprocess
import tempfile
import threading
import time
from typing import List, Optional

from conftest import Daemon, check_stopped, free_tcp_port, skip_or_fail
from deformd_client import Brush, DeformdError
from deformd_client import errors as E
from helpers import grid_obj, obj_bytes_positions

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


REDIS_CLI = shutil.which("redis-cli")


def cli(port: int, *args: str) -> str:
    """redis-cli -p port args... (raw output, stripped); raises on a failed run."""
    out = subprocess.run([REDIS_CLI, "-h", "127.0.0.1", "-p", str(port), "--raw"] + list(args),
                         capture_output=True, text=True, timeout=30)
    assert out.returncode == 0, out.stderr
    return out.stdout.strip()


class RedisCluster:
    """A Redis Cluster of `n` masters (no replicas) on free loopback ports, each redis-server
    with its AOF (fsync always) and cluster config file in a dir of its own under `dir`; created
    with `redis-cli --cluster create`, ready when every node says cluster_state:ok (polled)."""

    def __init__(self, dir: str, n: int = 3) -> None:
        if not REDIS or not REDIS_CLI:
            skip_or_fail("redis-server / redis-cli not installed (make deps installs them)")
        self.dir = dir
        self.ports = [free_tcp_port() for _ in range(n)]
        self.cports = [free_tcp_port() for _ in range(n)]  # not PORT + 10000 (may be > 65535)
        self.procs = [None] * n
        self.logs = [None] * n
        for k in range(n):
            os.makedirs(os.path.join(dir, "node-%d" % self.ports[k]))
            self.start_node(k)
        for k in range(n):
            self.wait_ping(k)
        out = subprocess.run([REDIS_CLI, "--cluster", "create"] +
                             ["127.0.0.1:%d" % p for p in self.ports] +
                             ["--cluster-replicas", "0", "--cluster-yes"],
                             capture_output=True, text=True, timeout=60)
        assert out.returncode == 0, out.stdout + out.stderr
        self.wait_ok()

    def start_node(self, k: int) -> None:
        """Starts node k in its dir (its AOF and nodes.conf: a restart rejoins as it was)."""
        p = self.ports[k]
        d = os.path.join(self.dir, "node-%d" % p)
        self.logs[k] = open(os.path.join(d, "redis.log"), "ab")
        self.procs[k] = subprocess.Popen(
            [REDIS, "--port", str(p), "--bind", "127.0.0.1", "--save", "",
             "--appendonly", "yes", "--appendfsync", "always", "--dir", d,
             "--cluster-enabled", "yes", "--cluster-config-file", "nodes.conf",
             "--cluster-node-timeout", "5000", "--cluster-port", str(self.cports[k])],
            stdin=subprocess.DEVNULL, stdout=self.logs[k], stderr=subprocess.STDOUT)

    def wait_ping(self, k: int) -> None:
        deadline = time.monotonic() + DEADLINE_S
        while True:
            try:
                if redis_cmd(self.ports[k], "PING").startswith(b"+PONG"):
                    return
            except OSError:
                pass
            assert self.procs[k].poll() is None, "redis-server exited"
            assert time.monotonic() < deadline, "redis-server not ready"
            time.sleep(0.02)

    def kill9(self, k: int) -> None:
        self.procs[k].kill()
        self.procs[k].wait()
        self.logs[k].close()

    def restart(self, k: int) -> None:
        """Node k started again after kill9 (same port, AOF, nodes.conf); waits for the cluster."""
        self.start_node(k)
        self.wait_ping(k)
        self.wait_ok()

    def wait_ok(self) -> None:
        """Polls until every node says cluster_state:ok and agrees on the slot owners."""
        deadline = time.monotonic() + DEADLINE_S
        while True:
            infos = [cli(p, "CLUSTER", "INFO") for p in self.ports]
            maps = [self.slot_ranges(p) for p in self.ports]
            if all("cluster_state:ok" in i for i in infos) and all(m == maps[0] for m in maps):
                return
            assert time.monotonic() < deadline, "Redis Cluster not ok: %s" % infos
            time.sleep(0.05)

    @property
    def url(self) -> str:
        return "redis://" + ",".join("127.0.0.1:%d" % p for p in self.ports)

    def seed(self, k: int) -> str:
        """The url of node k alone (a seed that may own none of a session's slots)."""
        return "redis://127.0.0.1:%d" % self.ports[k]

    def node_ids(self) -> dict:
        """port -> cluster node id (CLUSTER MYID)."""
        return {p: cli(p, "CLUSTER", "MYID") for p in self.ports}

    def slot_ranges(self, port: int) -> list:
        """[(lo, hi, master port)] sorted, as node `port` sees them (CLUSTER NODES)."""
        ranges = []
        for line in cli(port, "CLUSTER", "NODES").splitlines():
            f = line.split()
            if "master" not in f[2]:
                continue
            mport = int(f[1].split("@")[0].rsplit(":", 1)[1])
            for r in f[8:]:
                if r.startswith("["):
                    continue          # a slot being migrated / imported
                lo, _, hi = r.partition("-")
                ranges.append((int(lo), int(hi or lo), mport))
        return sorted(ranges)

    def keyslot(self, key: str) -> int:
        return int(cli(self.ports[0], "CLUSTER", "KEYSLOT", key))

    def master_of(self, key: str) -> int:
        """The port of the master serving key's slot."""
        s = self.keyslot(key)
        for lo, hi, p in self.slot_ranges(self.ports[0]):
            if lo <= s <= hi:
                return p
        raise AssertionError("slot %d unassigned" % s)

    def stop(self) -> None:
        for proc in self.procs:
            if proc.poll() is None:
                proc.terminate()
                proc.wait(30)
        for log in self.logs:
            if not log.closed:
                log.close()


class Cluster:
    """`n` daemons sharing `redis`; daemons killed with kill9 are replaced by start()."""

    def __init__(self, redis, n: int, extra: str = "", urls: Optional[List[str]] = None) -> None:
        """redis: a Redis or a RedisCluster (its .url); urls: daemon k's `cluster` value instead
        (e.g. one seed node each)."""
        self.redis = redis
        self.extra = extra
        self.tmps: List[tempfile.TemporaryDirectory] = []
        self.daemons: List[Daemon] = []
        self.dead: List[Daemon] = []
        for k in range(n):
            self.daemons.append(self.start(urls[k] if urls else None))

    def start(self, url: Optional[str] = None) -> Daemon:
        t = tempfile.TemporaryDirectory(prefix="deformd-cluster-")
        self.tmps.append(t)
        cfg = ("store = %s\ncluster = %s\ncluster_lease_ms = %d\n%s"
               % (os.path.join(t.name, "local.db"), url or self.redis.url, LEASE_MS, self.extra))
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


GRID = 16


def brush_of(X, k):
    vi = (k * 37) % (len(X) // 3)
    return Brush(type="grab" if k % 3 else "twist", center=X[3 * vi:3 * vi + 3],
                 move=(0.01, 0.0, 0.02 * (1 + k % 4)), twist=(0, 0, 0.1), radius=0.3, nu=0.4)


def run_strokes(c, sid, X, first, n, updates, k):
    """n strokes by client c on session sid: each a begin (brush_of(X, first + stroke)), `updates`
    updates moving (0.01 u, 0, 0.01 k) for u = 1..updates, and an end."""
    for s in range(n):
        c.brush_begin(sid, brush_of(X, first + s))
        for u in range(1, updates + 1):
            c.brush_update(sid, move=(0.01 * u, 0, 0.01 * k))
        c.brush_end(sid)


class Storm:
    """One writer stroking a cluster session, mirrored request by request onto a plain daemon
    (the shadow) once acknowledged: the shadow holds what the cluster must hold."""

    def __init__(self, cl, shadow, data):
        self.cl = cl
        self.X = obj_bytes_positions(data)
        d0 = cl.daemons[0]
        with d0.unix_client() as a:
            self.sid = a.load_mesh(data, fmt=".obj", name="storm").session_id
        self.sh = shadow.unix_client()
        self.ssid = self.sh.load_mesh(data, fmt=".obj", name="storm").session_id
        self.w = d0.tcp_client()
        self.inflight = None       # (op, args) sent to the cluster, not acknowledged
        self.open = False          # a stroke is open on the shadow
        self.acked = 0             # versions acknowledged so far
        self.k = 0

    def apply(self, c, sid, op, args):
        if op == "begin":
            return c.brush_begin(sid, args)
        if op == "update":
            return c.brush_update(sid, move=args)
        return c.brush_end(sid)

    def step(self):
        """The next request of the storm (strokes of begin, two updates, end), mirrored."""
        phase = self.k % 4
        op = ("begin", "update", "update", "end")[phase]
        args = brush_of(self.X, self.k // 4) if op == "begin" else (0.01 * phase, 0, 0.01)
        self.inflight = (op, args)
        ack = self.apply(self.w, self.sid, op, args)
        self.inflight = None
        self.apply(self.sh, self.ssid, op, args)
        self.open = op != "end"
        self.acked = ack.version
        self.k += 1

    def after_failover(self, version):
        """The cluster came back at `version`: the in-flight request counts when it was applied
        (it bumped the version); a stroke left open was ended by the restore."""
        sv = self.sh.get_mesh(self.ssid).version
        if version == sv + 1 and self.inflight and self.inflight[0] != "end":
            self.apply(self.sh, self.ssid, *self.inflight)
            self.open = True
        self.inflight = None
        if self.open:
            self.sh.brush_end(self.ssid)
            self.open = False
        self.k += (-self.k) % 4      # the next request begins a stroke

    def steps(self, n):
        """n more requests of the storm (step)."""
        for _ in range(n):
            self.step()

    def storm_until_killed(self, owner, target):
        """Steps until the acknowledged version reaches target, then has owner (a Daemon)
        killed (-9) from another thread while the next requests are in flight, stepping on until
        the writer fails (connection lost, or EIO / ESTATE); waits for owner's exit. Returns the
        monotonic time of the kill order, None when the writer failed before target."""
        fire = threading.Event()
        killer = threading.Thread(target=lambda: (fire.wait(60), owner.proc.kill()))
        killer.start()
        t_kill = None
        try:
            while True:
                self.step()
                if self.acked >= target and not fire.is_set():
                    fire.set()            # killed while the next requests are in flight
                    t_kill = time.monotonic()
        except (ConnectionError, OSError, DeformdError) as e:
            if isinstance(e, DeformdError):
                assert e.code in (E.EIO, E.ESTATE), e
        fire.set()
        killer.join(30)
        owner.proc.wait()
        return t_kill

    def step_refused(self, why):
        """The next request must be refused with EIO (Redis down: not acknowledged); why: the
        assertion message when it is acknowledged."""
        try:
            self.step()
            raise AssertionError(why)
        except DeformdError as e:
            assert e.code == E.EIO, e

    def reconnect_writer(self, k):
        """Closes the writer and reconnects it through daemon k (reconnect)."""
        self.w.close()
        self.w = reconnect(self.cl, self.sid, k)

    def resync(self):
        """After a failover: after_failover at the writer's version, then check through it."""
        self.after_failover(self.w.get_mesh(self.sid).version)
        self.check(self.w)

    def close(self):
        """Closes the writer and the shadow's client."""
        self.w.close()
        self.sh.close()

    def check(self, c):
        m = c.get_mesh(self.sid)
        ref = self.sh.get_mesh(self.ssid)
        assert m.version >= self.acked, "acked version %d lost (now %d)" % (self.acked, m.version)
        assert m.version == ref.version
        assert m.positions.tobytes() == ref.positions.tobytes(), "positions differ at version %d" \
            % m.version


def reconnect(cl, sid, k):
    """A client on a live daemon, following redirects, once the session is served again."""
    def attempt():
        c = cl.daemons[k % len(cl.daemons)].tcp_client(timeout=5.0)
        try:
            c.get_mesh(sid)
        except BaseException:
            c.close()
            raise
        return c
    return poll_until(attempt, "a new owner serving session %d" % sid)


@contextlib.contextmanager
def storm(cl, shadow, redis=None):
    """A Storm on cluster cl over a GRID x GRID grid, mirrored onto shadow (a plain Daemon); on
    leaving (normally or not): the storm's clients closed, cl stopped, then redis (a Redis) when
    given."""
    s = None
    try:
        s = Storm(cl, shadow, grid_obj(GRID, GRID))
        yield s
    finally:
        if s:
            s.close()
        cl.stop()
        if redis:
            redis.stop()
