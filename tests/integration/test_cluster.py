"""Cluster mode (server/cluster/cluster.h, issue 15): three daemons and one redis-server on
loopback ports.

- clients connected to different daemons join one session (redirected to its owner: EMOVED),
  stroke it concurrently and converge bit-identically (every subscriber's replica equals GET_MESH
  from the owner); deformctl on a non-owner follows the redirect too;
- kill -9 of the owner in the middle of a stroke storm, several times: a new owner serves once
  the lease expired, and no acknowledged edit is lost: the session's version and positions equal
  those of a single plain daemon (the "shadow") that received exactly the acknowledged requests
  (and the one in flight when the cluster applied it before dying);
- a stale owner (SIGSTOP past its lease, SIGCONT) cannot append (fencing) and drops the session;
- Redis killed (-9) and restarted with its AOF: nothing acknowledged is lost, editing continues.
Failover times are printed (timing is never asserted)."""
import os
import signal
import subprocess
import threading
import time

from cluster_harness import (GRID, LEASE_MS, Cluster, Redis, brush_of, owner_port, poll_until, reconnect,
                             redis_cmd, run_strokes, storm)
from conftest import DEFORMCTL
from deformd_client import DeformdError, MeshState
from deformd_client import errors as E
from deformd_client import messages as m
from deformd_client.stream import Disp
from helpers import grid_obj, obj_bytes_positions

def test_clients_on_three_daemons_stroke_one_session_and_converge(tmp_path):
    r = Redis(str(tmp_path))
    cl = Cluster(r, 3)
    clients = []
    try:
        d0, d1, d2 = cl.daemons
        data = grid_obj(24, 24)
        X = obj_bytes_positions(data)
        with d0.unix_client() as a:
            sid = a.load_mesh(data, fmt=".obj", name="shared").session_id
        clients = [d.tcp_client() for d in (d0, d1, d2) for _ in range(2)]
        for c in clients:
            c.subscribe(sid)
        # the four clients of d1 and d2 were redirected to the owner d0
        assert [owner_port(c) for c in clients] == [d0.tcp_port] * 6
        assert [c.moves for c in clients] == [0, 0, 1, 1, 1, 1]
        errors = []
        start = threading.Barrier(len(clients))
        strokes, updates = 4, 2

        def worker(k):
            c = clients[k]
            try:
                start.wait()
                run_strokes(c, sid, X, 7 * k, strokes, updates, k)
            except Exception as e:  # reported below with the client number
                errors.append((k, repr(e)))

        threads = [threading.Thread(target=worker, args=(k,)) for k in range(len(clients))]
        for t in threads:
            t.start()
        for t in threads:
            t.join(120)
        assert not errors, errors
        expected = len(clients) * strokes * (1 + updates)
        with d0.unix_client() as owner:
            final = owner.get_mesh(sid)
        assert final.version == expected
        for k, c in enumerate(clients):
            replica = MeshState(X)
            for ev in c.events(timeout=5.0):
                if isinstance(ev, Disp):
                    replica.apply(ev)
                if replica.version == expected:
                    break
            assert replica.version == expected, "client %d" % k
            assert replica.tobytes() == final.positions.tobytes(), "client %d diverged" % k
        # deformctl on a daemon that does not own the session follows the redirect
        out = subprocess.run([DEFORMCTL, "--tcp", "127.0.0.1:%d" % d2.tcp_port, "undo", str(sid)],
                             capture_output=True, text=True, timeout=30)
        assert out.returncode == 0, out.stderr
        with d0.unix_client() as owner:
            assert owner.get_mesh(sid).version == expected + 1
        # LIST_SESSIONS on any daemon: every session of the cluster with its owner's address
        with d1.tcp_client() as c:
            s2 = c.load_mesh(grid_obj(4, 4), fmt=".obj", name="second").session_id
        with d2.unix_client() as c:
            infos = {i.session_id: i for i in c.list_sessions()}
        assert sorted(infos) == sorted([sid, s2])
        assert (infos[sid].name, infos[sid].nv, infos[sid].version, infos[sid].owner) == \
            ("shared", len(X) // 3, expected + 1, "127.0.0.1:%d" % d0.tcp_port)
        assert (infos[s2].name, infos[s2].nv, infos[s2].owner) == \
            ("second", 16, "127.0.0.1:%d" % d1.tcp_port)
        # a client whose HELLO did not ask for owners gets the plain list (old clients)
        with d2.unix_client(hello=False) as old:
            old.server = m.decode_hello_reply(old._one(m.HELLO, m.encode_hello(1, 1, 0, "old")))
            plain = old.list_sessions()
        assert sorted(i.session_id for i in plain) == sorted([sid, s2])
        assert all(i.owner is None for i in plain)
        # a close through any daemon closes it on its owner and in Redis
        with d2.tcp_client() as c:
            c.close_session(s2)
            assert c.moves == 1
            assert [i.session_id for i in c.list_sessions()] == [sid]
        assert redis_cmd(r.port, "EXISTS", "deformd:{%d}:snap" % s2).startswith(b":0")
        assert redis_cmd(r.port, "EXISTS", "deformd:{%d}:snap" % sid).startswith(b":1")
        # without following, the redirect names the owner
        with d1.tcp_client() as c:
            c.follow_moved = False
            try:
                c.get_mesh(sid)
                raise AssertionError("a non-owner served the session")
            except DeformdError as e:
                assert e.code == E.EMOVED
                assert e.message == "MOVED %d 127.0.0.1:%d" % (sid, d0.tcp_port)
    finally:
        for c in clients:
            c.close()
        cl.stop()
        r.stop()


KILLS = 10


def test_kill9_owner_mid_storm_loses_no_acknowledged_edit(tmp_path, make_daemon):
    r = Redis(str(tmp_path))
    cl = Cluster(r, 3)
    with storm(cl, make_daemon(), r) as s:
        watcher = None
        try:
            # a subscriber on another daemon (redirected to the owner), resyncing after each failover
            replica = MeshState(s.X)
            watcher = cl.daemons[1].tcp_client()
            watcher.subscribe(s.sid)
            times = []
            for kill in range(KILLS):
                target = s.acked + 5 + kill      # versions acknowledged before the kill
                owner = cl.by_port(owner_port(s.w))
                assert owner is not None
                t_kill = s.storm_until_killed(owner, target)
                if t_kill is None:
                    t_kill = time.monotonic()
                cl.kill9(owner)                   # its replacement joins the cluster
                s.reconnect_writer(kill)
                times.append(time.monotonic() - t_kill)
                s.resync()
                try:                              # what reached it before its daemon died
                    for ev in watcher.events(timeout=0.2):
                        if isinstance(ev, Disp):
                            replica.apply(ev)
                except (ConnectionError, OSError):
                    pass                          # the owner it was redirected to is gone
                watcher.close()
                watcher = reconnect(cl, s.sid, kill + 1)
                watcher.subscribe(s.sid, from_version=replica.version)
            s.steps(8)                           # the last owner keeps serving
            s.check(s.w)
            final = s.w.get_mesh(s.sid)
            for ev in watcher.events(timeout=5.0):
                if isinstance(ev, Disp):
                    replica.apply(ev)
                if replica.version == final.version:
                    break
            assert replica.version == final.version
            assert replica.tobytes() == final.positions.tobytes(), "the subscriber diverged"
            print("cluster failover after kill -9 (lease %d ms): %s s; acked edits lost: 0"
                  % (LEASE_MS, ", ".join("%.2f" % t for t in times)))
        finally:
            if watcher:
                watcher.close()


def test_stale_owner_is_fenced_and_drops_the_session(tmp_path):
    r = Redis(str(tmp_path))
    cl = Cluster(r, 2)
    try:
        d0, d1 = cl.daemons
        data = grid_obj(GRID, GRID)
        X = obj_bytes_positions(data)
        x = d0.tcp_client()
        x.follow_moved = False
        sid = x.load_mesh(data, fmt=".obj", name="fenced").session_id
        x.brush_begin(sid, brush_of(X, 1))
        os.kill(d0.proc.pid, signal.SIGSTOP)
        try:
            def take_over():
                with d1.tcp_client(timeout=5.0) as c:
                    c.follow_moved = False      # the stopped owner would not answer
                    return c.get_mesh(sid).version
            v_taken = poll_until(take_over, "d1 taking over from the stopped owner")
            assert v_taken == 1                 # the begin; its stroke ended by the restore
            with d1.tcp_client() as y:
                y.follow_moved = False
                v_new = y.stroke(sid, brush_of(X, 2)).version
        finally:
            os.kill(d0.proc.pid, signal.SIGCONT)
        # the woken owner's write is refused (fenced), or it already dropped the session
        try:
            x.brush_update(sid, move=(0.05, 0, 0))
            raise AssertionError("a fenced owner acknowledged a change")
        except DeformdError as e:
            assert e.code in (E.ESTATE, E.EMOVED), e
        with d1.tcp_client() as y:
            assert y.get_mesh(sid).version == v_new     # nothing of the stale owner
        def dropped():
            with d0.tcp_client(timeout=5.0) as c:
                c.follow_moved = False
                try:
                    c.get_mesh(sid)
                except DeformdError as e:
                    if e.code == E.EMOVED:
                        return e.message
                raise OSError("d0 still serves the session")
        # the drop runs on the owner's loop after the refusal went out: waited for, not assumed
        assert poll_until(dropped, "d0 dropping the session") == \
            "MOVED %d 127.0.0.1:%d" % (sid, d1.tcp_port)
        log = d0.log()
        assert "session %d dropped from this daemon" % sid in log
        assert "fenced" in log
        x.close()
    finally:
        cl.stop()
        r.stop()


def test_redis_killed_and_restarted_with_aof_loses_nothing_acknowledged(tmp_path, make_daemon):
    r = Redis(str(tmp_path))
    cl = Cluster(r, 2)
    try:
        with storm(cl, make_daemon()) as s:
            s.steps(10)
            port = r.port
            r.kill9()
            s.step_refused("a change was acknowledged without Redis")   # Redis down: not acked
            r = Redis(str(tmp_path), port)        # the same AOF
            s.reconnect_writer(1)
            s.resync()
            s.steps(8)
            s.check(s.w)
    finally:
        r.stop()                              # the restarted Redis


def test_start_refused_without_redis_and_warned_of_weak_persistence(tmp_path):
    """A daemon whose Redis does not answer refuses to start, naming it; one whose Redis would
    lose acknowledged changes (appendfsync everysec) says so at start."""
    from conftest import DEFORMD, free_tcp_port
    port = free_tcp_port()
    conf = tmp_path / "d.conf"
    conf.write_text("store = %s\ncluster = redis://127.0.0.1:%d\nadvertise = 127.0.0.1:1\n"
                    % (tmp_path / "l.db", port))
    out = subprocess.run([DEFORMD, "--foreground", "--config", str(conf), "--socket",
                          str(tmp_path / "s.sock")], capture_output=True, text=True, timeout=30)
    assert out.returncode != 0
    assert "cluster redis 127.0.0.1:%d: cannot connect" % port in out.stderr, out.stderr
    r = Redis(str(tmp_path))
    redis_cmd(r.port, "CONFIG", "SET", "appendfsync", "everysec")
    cl = Cluster(r, 1)
    try:
        assert "has appendfsync everysec: a crash of its machine may lose acknowledged" \
            in cl.daemons[0].log()
    finally:
        cl.stop()
        r.stop()


def test_takeover_onto_a_daemon_with_a_session_of_the_same_name(tmp_path):
    """Names are per daemon: the new owner already holding a session of that name still takes
    the session over, under its name, at its last acknowledged state."""
    r = Redis(str(tmp_path))
    cl = Cluster(r, 2)
    try:
        d0, d1 = cl.daemons
        data = grid_obj(8, 8)
        X = obj_bytes_positions(data)
        with d0.unix_client() as a, d1.unix_client() as b:
            s0 = a.load_mesh(data, fmt=".obj", name="same").session_id
            s1 = b.load_mesh(data, fmt=".obj", name="same").session_id
            v = a.stroke(s0, brush_of(X, 3)).version
            want = a.get_mesh(s0).positions.tobytes()
        cl.kill9(d0)

        def served():
            with d1.tcp_client(timeout=5.0) as c:
                c.follow_moved = False
                return c.get_mesh(s0)
        m0 = poll_until(served, "d1 taking session %d over" % s0)
        assert (m0.version, m0.positions.tobytes()) == (v, want)
        with d1.unix_client() as c:
            names = {i.session_id: (i.name, i.owner) for i in c.list_sessions()}
        here = "127.0.0.1:%d" % d1.tcp_port
        assert names[s0] == ("same", here) and names[s1] == ("same", here)
    finally:
        cl.stop()
        r.stop()


def test_redirect_authenticates_with_the_same_key(tmp_path):
    """Daemons with a key_file: a redirected Python client and deformctl authenticate on the owner
    with the key they used on the first daemon."""
    import secrets
    from deformd_client import Client
    kf = tmp_path / "cluster.key"
    kf.write_text(secrets.token_hex(32) + "\n")
    os.chmod(kf, 0o600)
    r = Redis(str(tmp_path))
    cl = Cluster(r, 2, "key_file = %s\n" % kf)
    try:
        d0, d1 = cl.daemons
        data = grid_obj(8, 8)
        with d0.unix_client() as a:
            sid = a.load_mesh(data, fmt=".obj").session_id
        with Client.connect_tcp("127.0.0.1", d1.tcp_port, key_file=str(kf)) as c:
            assert c.get_mesh(sid).version == 0
            assert c.moves == 1 and c.authenticated and owner_port(c) == d0.tcp_port
        out = subprocess.run([DEFORMCTL, "--tcp", "127.0.0.1:%d" % d1.tcp_port, "--key-file",
                              str(kf), "brush", str(sid), "--type", "grab", "--center", "0,0,0", "--move",
                              "0,0,0.1", "--radius", "0.5"],
                             capture_output=True, text=True, timeout=30)
        assert out.returncode == 0, out.stderr
        with d0.unix_client() as a:
            assert a.get_mesh(sid).version == 1
    finally:
        cl.stop()
        r.stop()
