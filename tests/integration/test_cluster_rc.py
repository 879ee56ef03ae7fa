"""Cluster mode over a Redis Cluster of three masters (server/cluster/redis.h slot routing,
issue 15): `cluster = redis://HOST:PORT,HOST:PORT,...` names seed nodes; each command goes to the
master of its key's hash slot, a session's keys (hash tag {ID}) sharing one slot.

- sessions created through different daemons land on different masters: each session's keys are
  on the master CLUSTER KEYSLOT + CLUSTER NODES name, and nowhere else; each daemon was given one
  seed only, and found the others through the slot map;
- clients on three daemons stroke two sessions (on different masters) concurrently and converge
  bit-identically (every subscriber's replica equals GET_MESH from the owner); LIST_SESSIONS
  lists all;
- kill -9 of a session's owner in the middle of a stroke storm, twice: a new owner serves it, and
  no acknowledged edit is lost (the positions equal those of a plain "shadow" daemon that received
  exactly the acknowledged requests);
- the session's slot migrated to another master while its owner writes (CLUSTER SETSLOT
  IMPORTING / MIGRATING, MIGRATE, SETSLOT NODE): writes during the migration follow -ASK, those
  after it -MOVED, and nothing acknowledged is lost;
- the master holding a session killed (-9) and restarted with its AOF: the change in the gap is
  refused (EIO, not acknowledged), the daemons reconnect to it, nothing acknowledged is lost.
Every wait polls with a deadline; nothing is timed."""
import threading

import pytest

from cluster_harness import Cluster, RedisCluster, cli, owner_port, poll_until, run_strokes, storm
from deformd_client import MeshState
from deformd_client.stream import Disp
from helpers import grid_obj, obj_bytes_positions


@pytest.fixture(scope="module")
def rc(tmp_path_factory):
    c = RedisCluster(str(tmp_path_factory.mktemp("rc")))
    yield c
    c.stop()


def keys_of(sid):
    return ["deformd:{%d}:%s" % (sid, k) for k in ("lease", "epoch", "snap")]


def holders(rc, key):
    """The ports of the masters where key exists (EXISTS on each; a node that does not serve the
    slot answers with a redirect, not 1)."""
    out = []
    for p in rc.ports:
        try:
            if cli(p, "EXISTS", key) == "1":
                out.append(p)
        except AssertionError:
            pass
    return out


def test_sessions_on_different_masters_converge(rc):
    cl = Cluster(rc, 3, urls=[rc.seed(k) for k in range(3)])   # one seed each
    clients = []
    try:
        data = grid_obj(20, 20)
        X = obj_bytes_positions(data)
        sids = []
        for k in range(4):                         # 4 sessions, through the 3 daemons
            with cl.daemons[k % 3].unix_client() as a:
                sids.append(a.load_mesh(data, fmt=".obj", name="s%d" % k).session_id)
        masters = {}
        for sid in sids:
            m = rc.master_of("deformd:{%d}:lease" % sid)
            for key in keys_of(sid):
                assert rc.master_of(key) == m        # one hash tag, one slot
                assert holders(rc, key) == [m], key
            masters[sid] = m
        assert len(set(masters.values())) >= 2, masters
        # the global keys each live on their own slot's master
        for key in ("deformd:sessions", "deformd:next_id"):
            assert holders(rc, key) == [rc.master_of(key)], key
        # two sessions on different masters, each stroked by one client per daemon
        s_a = sids[0]
        s_b = next(s for s in sids if masters[s] != masters[s_a])
        work = {s_a: [], s_b: []}
        for sid in (s_a, s_b):
            for d in cl.daemons:
                c = d.tcp_client()
                c.subscribe(sid)
                clients.append(c)
                work[sid].append(c)
        errors = []
        start = threading.Barrier(len(clients))
        strokes, updates = 3, 2

        def worker(sid, k, c):
            try:
                start.wait()
                run_strokes(c, sid, X, 5 * k, strokes, updates, k)
            except Exception as e:  # reported below with the session and client
                errors.append((sid, k, repr(e)))

        threads = [threading.Thread(target=worker, args=(sid, k, c))
                   for sid in work for k, c in enumerate(work[sid])]
        for t in threads:
            t.start()
        for t in threads:
            t.join(120)
        assert not errors, errors
        expected = 3 * strokes * (1 + updates)
        for sid in (s_a, s_b):
            owner = cl.by_port(owner_port(work[sid][0]))
            with owner.unix_client() as o:
                final = o.get_mesh(sid)
            assert final.version == expected
            for k, c in enumerate(work[sid]):
                assert owner_port(c) == owner.tcp_port
                replica = MeshState(X)
                for ev in c.events(timeout=5.0):
                    if isinstance(ev, Disp) and ev.session_id == sid:
                        replica.apply(ev)
                    if replica.version == expected:
                        break
                assert replica.version == expected, "session %d client %d" % (sid, k)
                assert replica.tobytes() == final.positions.tobytes(), \
                    "session %d client %d diverged" % (sid, k)
        with cl.daemons[2].unix_client() as c:
            listed = {i.session_id: i for i in c.list_sessions()}
        assert set(sids) <= set(listed)
        assert listed[s_a].version == expected and listed[s_b].version == expected
    finally:
        for c in clients:
            c.close()
        cl.stop()


def test_kill9_owner_loses_no_acknowledged_edit(rc, make_daemon):
    cl = Cluster(rc, 3)
    with storm(cl, make_daemon()) as s:
        for kill in range(2):
            target = s.acked + 6
            owner = cl.by_port(owner_port(s.w))
            assert owner is not None
            s.storm_until_killed(owner, target)
            cl.kill9(owner)
            s.reconnect_writer(kill)
            assert owner_port(s.w) != owner.tcp_port
            s.resync()
        s.steps(8)
        s.check(s.w)
        print("Redis Cluster: %d kill -9 of the owner; acked edits lost: 0" % 2)


def migrate_slot(rc, slot, src, dst, between=None):
    """Moves `slot` from master port src to dst the way redis-cli --cluster reshard does, calling
    between() once the keys are on dst but before the slot is assigned to it (ASK window)."""
    ids = rc.node_ids()
    cli(dst, "CLUSTER", "SETSLOT", str(slot), "IMPORTING", ids[src])
    cli(src, "CLUSTER", "SETSLOT", str(slot), "MIGRATING", ids[dst])
    while True:
        keys = cli(src, "CLUSTER", "GETKEYSINSLOT", str(slot), "100").split()
        if not keys:
            break
        cli(src, "MIGRATE", "127.0.0.1", str(dst), "", "0", "5000", "KEYS", *keys)
    if between:
        between()
    for p in rc.ports:
        cli(p, "CLUSTER", "SETSLOT", str(slot), "NODE", ids[dst])
    rc.wait_ok()


def test_slot_migration_is_followed(rc, make_daemon):
    cl = Cluster(rc, 2)
    with storm(cl, make_daemon()) as s:
        s.steps(6)
        key = "deformd:{%d}:lease" % s.sid
        src = rc.master_of(key)
        dst = next(p for p in rc.ports if p != src)
        slot = rc.keyslot(key)

        def count(p):
            return int(cli(p, "CLUSTER", "COUNTKEYSINSLOT", str(slot)))

        def during():                       # keys on dst, slot still src's: -ASK
            n = count(dst)
            assert n >= 4 and count(src) == 0
            s.steps(6)
            assert count(src) == 0 and count(dst) >= n   # written on dst after ASKING

        migrate_slot(rc, slot, src, dst, during)
        assert rc.master_of(key) == dst
        s.steps(8)                          # the daemon's map says src: -MOVED
        s.check(s.w)
        for k in keys_of(s.sid):
            assert holders(rc, k) == [dst], k
        # the renewals followed too: the lease is still the owner's after several ttls
        owner = cl.by_port(owner_port(s.w))
        v = s.acked
        # PTTL only falls between renewals, so a reading above the one before it shows a renewal
        # (pipelined, redirected) landed on the new master. Comparing with the first reading alone
        # could never pass when that reading was taken in the renewal's own millisecond (= ttl).
        last = [int(cli(dst, "PTTL", key))]
        assert last[0] > 0

        def renewed():
            now = int(cli(dst, "PTTL", key))
            assert now > 0, "the lease expired on the new master (PTTL %d)" % now
            went_up, last[0] = now > last[0], now
            if not went_up:
                raise OSError("lease not renewed yet")
        poll_until(renewed, "the lease renewed on the new master")
        s.step()
        assert s.acked == v + 1 and owner_port(s.w) == owner.tcp_port
        s.check(s.w)
        assert "dropped from this daemon" not in owner.log()


def test_master_killed_and_restarted_with_aof_loses_nothing_acknowledged(rc, make_daemon):
    cl = Cluster(rc, 2)
    with storm(cl, make_daemon()) as s:
        s.steps(10)
        k = rc.ports.index(rc.master_of("deformd:{%d}:lease" % s.sid))
        rc.kill9(k)
        s.step_refused("a change was acknowledged without its Redis master")   # not acknowledged
        rc.restart(k)
        s.reconnect_writer(1)
        s.resync()
        s.steps(8)
        s.check(s.w)
