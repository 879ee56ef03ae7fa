"""Per-session access policy and membership (issue 12, "Per-session access"; PROTOCOL.md 4.34..4.36;
server/session/membership.h). Principals come from named TCP keys (peer_key alice / bob / carol;
key_file is the admin key). A session loaded in key mode (session_access = key) has a join key
nobody knows until its owner rotates it (SESSION_ACCESS NEW_KEY); a principal that JOINs with it
becomes a member and may edit; the others observe (observers on) or see nothing (observers off:
EPERM, and LIST hides the session). Only the owner or an admin closes, resets the rest shape or
changes the policy. A wrong key is EPERM, changes nothing and is rate-limited per peer like
failed AUTHs. The owner, policy, key hash and members survive a restart (store on), and a
schema 1 store (before the access table) is migrated."""
import json
import secrets
import sqlite3
import subprocess

import pytest

from conftest import DEFORMCTL, Daemon, check_stopped
from deformd_client import Brush, Client, DeformdError, errors as E
from helpers import downgrade_store, grid_obj
from test_session_access import write_key

WHO = ("admin", "alice", "bob", "carol")


@pytest.fixture
def keys(tmp_path):
    out = {}
    for who in WHO:
        out[who] = str(tmp_path / ("%s.key" % who))
        write_key(out[who])
    return out


def config(keys, extra=""):
    return ("key_file = %s\n" % keys["admin"] +
            "".join("peer_key = %s %s\n" % (w, keys[w]) for w in WHO[1:]) + extra)


def start(tmp_path, keys, run, extra="", store=None):
    d = tmp_path / ("run%d" % run)
    d.mkdir()
    store_line = "store = %s\n" % store if store else ""
    return Daemon(str(d), config(keys, store_line + extra), tcp=True)


def tcp(d, who) -> Client:
    return Client.connect_tcp("127.0.0.1", d.tcp_port, timeout=30.0, key_file=d.keys[who])


def stroke(c, sid):
    c.stroke(sid, Brush(center=(0.5, 0.5, 0.0), move=(0.0, 0.0, 0.05), radius=0.4))


def state(c, sid):
    m = c.get_mesh(sid, rest=True)
    return m.version, m.positions.tobytes(), m.rest.tobytes()


def refused(call, code=E.ErrorCode.EPERM, *needles):
    with pytest.raises(DeformdError) as ei:
        call()
    assert ei.value.code == code, ei.value
    for n in needles:
        assert n in str(ei.value), (n, str(ei.value))
    return str(ei.value)


@pytest.fixture
def run(tmp_path, keys):
    """start(run, extra, store) -> Daemon with d.keys; every daemon is stopped and checked."""
    made = []

    def make(n, extra="", store=None):
        d = start(tmp_path, keys, n, extra, store)
        d.keys = keys
        made.append(d)
        return d

    yield make
    for d in made:
        if not getattr(d, "killed", False):
            check_stopped(d, d.stop())


def test_key_mode_join_edit_rotate_and_owner_rights(run):
    d = run(1, "session_access = key\n")
    with tcp(d, "alice") as a, tcp(d, "bob") as b, tcp(d, "carol") as c:
        sid = a.load_mesh(grid_obj(6, 6), name="spot").session_id
        pol = b.session_access(sid)                      # anyone who may observe reads it
        assert (pol.mode_name, pol.observers, pol.owner, pol.members, pol.key) == \
            ("key", 1, "key:alice", 0, None)
        before = state(a, sid)
        msg = refused(lambda: stroke(b, sid), E.ErrorCode.EPERM, "needs the edit right",
                      "key:bob", "'spot'", "join with the session's key")
        assert "an observer" in msg
        assert b.get_mesh(sid).nv == 36                  # observers on: bob observes
        b.subscribe(sid)
        b.snapshot(sid)
        b.brush_state_get(sid)
        # a wrong key: EPERM, nothing changes
        refused(lambda: b.join(sid, secrets.token_bytes(32)), E.ErrorCode.EPERM,
                "wrong join key", "'spot'")
        assert a.session_access(sid).members == 0
        refused(lambda: stroke(b, sid), E.ErrorCode.EPERM, "needs the edit right")
        assert state(a, sid) == before
        # only the owner (or an admin) changes the policy or learns a key
        refused(lambda: b.session_access(sid, new_key=True), E.ErrorCode.EPERM,
                "needs the own right")
        key1 = a.session_access(sid, new_key=True).key
        assert key1 is not None and len(key1) == 32
        info = b.join(sid, key1.hex())
        assert info.members == 1 and info.key is None
        stroke(b, sid)                                   # a member edits
        assert state(a, sid)[0] == before[0] + 1
        b.undo(sid)
        # members do not own: close, reset rest and policy changes stay the owner's
        mid = state(a, sid)
        refused(lambda: b.close_session(sid), E.ErrorCode.EPERM, "needs the own right",
                "only the owner or an admin")
        refused(lambda: b.reset_rest(sid), E.ErrorCode.EPERM, "needs the own right")
        refused(lambda: b.session_access(sid, mode="open"), E.ErrorCode.EPERM)
        assert state(a, sid) == mid and a.session_access(sid).mode_name == "key"
        # a new key: the old one joins no more; members stay
        key2 = a.session_access(sid, new_key=True).key
        assert key2 != key1
        refused(lambda: c.join(sid, key1), E.ErrorCode.EPERM, "wrong join key")
        refused(lambda: stroke(c, sid), E.ErrorCode.EPERM, "needs the edit right")
        assert c.join(sid, key2).members == 2
        stroke(c, sid)
        stroke(b, sid)
        with tcp(d, "admin") as adm:                     # an admin resets the rest shape
            adm.reset_rest(sid)
        a.close_session(sid)                             # the owner closes
        assert a.list_sessions() == []
    log = d.log()
    assert "wrong join key" in log and "127.0.0.1" in log   # logged with the peer


def test_observers_off_hides_the_session_and_refuses_observing(run):
    d = run(1, "session_access = key\nsession_observers = off\n")
    with tcp(d, "alice") as a, tcp(d, "bob") as b, tcp(d, "carol") as c:
        sid = a.load_mesh(grid_obj(5, 5), name="secret").session_id
        pub = a.load_mesh(grid_obj(4, 4), name="public").session_id
        a.session_access(pub, mode="open")
        assert [s.name for s in b.list_sessions()] == ["public"]
        refused(lambda: b.subscribe(sid), E.ErrorCode.EPERM, "needs the observe right")
        refused(lambda: b.get_mesh(sid), E.ErrorCode.EPERM, "needs the observe right")
        refused(lambda: b.snapshot(sid), E.ErrorCode.EPERM)
        refused(lambda: b.open_session(sid), E.ErrorCode.EPERM)
        refused(lambda: b.stats(sid), E.ErrorCode.EPERM, "needs the observe right")
        refused(lambda: b.session_access(sid), E.ErrorCode.EPERM)
        key = a.session_access(sid, new_key=True).key
        b.join(sid, key)                                  # a member observes and lists it
        assert [s.name for s in b.list_sessions()] == ["secret", "public"]
        assert b.subscribe(sid).session_id == sid
        assert [s.name for s in c.list_sessions()] == ["public"]   # carol did not join
        a.session_access(sid, observers=True)             # observers on: carol sees it
        assert [s.name for s in c.list_sessions()] == ["secret", "public"]
        assert c.get_mesh(sid).nv == 25
        a.session_access(sid, mode="owner")               # owner mode: members observe only
        refused(lambda: stroke(b, sid), E.ErrorCode.EPERM, "needs the edit right",
                "owner-only")
        refused(lambda: c.join(sid, key), E.ErrorCode.EPERM, "owner-only")
        assert b.get_mesh(sid).nv == 25


def test_wrong_join_keys_are_rate_limited_per_peer(run):
    d = run(1, "session_access = key\nauth_fail_burst = 2\nauth_fail_refill_s = 3600\n")
    with tcp(d, "alice") as a, tcp(d, "bob") as b:
        sid = a.load_mesh(grid_obj(4, 4), name="spot").session_id
        key = a.session_access(sid, new_key=True).key
        for _ in range(2):
            refused(lambda: b.join(sid, secrets.token_bytes(32)), E.ErrorCode.EPERM,
                    "wrong join key")
        # out of tokens: even the right key is not checked; the connection stays open
        refused(lambda: b.join(sid, key), E.ErrorCode.ELIMIT, "too many wrong join keys",
                "retry in")
        assert a.session_access(sid).members == 0
        b.ping(b"still open")
        st = a.stats()
        assert (st["join_failed"], st["join_limited"], st["join_ok"]) == (2, 1, 0)


def test_bad_join_and_access_requests_change_nothing(run):
    d = run(1, "session_access = key\n")
    with tcp(d, "alice") as a:
        sid = a.load_mesh(grid_obj(4, 4), name="spot").session_id
        refused(lambda: a.join(sid + 100, secrets.token_bytes(32)), E.ErrorCode.ENOTFOUND)
        refused(lambda: a.session_access(sid + 100), E.ErrorCode.ENOTFOUND)
        with pytest.raises(ValueError):
            a.join(sid, b"short")
        raw = __import__("struct").pack("<QBBBB", sid, 9, 0, 0, 0)
        with pytest.raises(DeformdError) as ei:
            a._one(0x0017, raw)
        assert ei.value.code == E.ErrorCode.EINVAL and "mode 9" in str(ei.value)
        pol = a.session_access(sid)
        assert (pol.mode_name, pol.observers, pol.members) == ("key", 1, 0)


@pytest.mark.parametrize("extra, needle", [
    ("session_observers = maybe\n", "session_observers"),
    ("session_access = members\n", "session_access"),
])
def test_bad_access_settings_refuse_start(run, extra, needle):
    with pytest.raises(RuntimeError) as ei:
        run(1, extra)
    assert needle in str(ei.value)


def test_restart_keeps_owner_policy_and_members(run, tmp_path):
    store = str(tmp_path / "deformd.db")
    d = run(1, "session_access = key\n", store)
    with tcp(d, "alice") as a, tcp(d, "bob") as b:
        sid = a.load_mesh(grid_obj(5, 5), name="spot").session_id
        key = a.session_access(sid, observers=False, new_key=True).key
        b.join(sid, key)
        before = a.session_access(sid)
    d.proc.kill()                    # SIGKILL: the store alone carries the policy over
    d.proc.wait()
    d._log.close()
    d.killed = True
    d2 = run(2, "session_access = open\nsession_observers = on\n", store)
    with tcp(d2, "alice") as a, tcp(d2, "bob") as b, tcp(d2, "carol") as c:
        after = a.session_access(sid)
        assert (after.mode, after.observers, after.owner, after.members) == \
            (before.mode, before.observers, before.owner, before.members)
        stroke(b, sid)                                   # still a member, without a new join
        assert [s.name for s in c.list_sessions()] == []   # observers off, carol not a member
        refused(lambda: c.join(sid, secrets.token_bytes(32)), E.ErrorCode.EPERM,
                "wrong join key")
        assert c.join(sid, key).members == before.members + 1   # the key hash survived
        refused(lambda: b.close_session(sid), E.ErrorCode.EPERM, "needs the own right")
        fresh = a.load_mesh(grid_obj(4, 4), name="new").session_id
        assert a.session_access(fresh).mode_name == "open"      # new sessions: the config


def test_a_schema_1_store_is_migrated(run, tmp_path):
    store = str(tmp_path / "deformd.db")
    d = run(1, "", store)
    with tcp(d, "alice") as a:
        sid = a.load_mesh(grid_obj(4, 4), name="old").session_id
        a.set_handles(sid, [0, 5, 10], max_iters=5)     # an edit a schema 1 store can hold (a
        X = a.get_mesh(sid).positions                   # stroke is a recipe record since 3)
        a.move_handles(sid, [X[0:3], X[15:18], (X[30], X[31] + 0.1, X[32])], max_iters=5)
        v = a.open_session(sid).version
    check_stopped(d, d.stop())
    downgrade_store(store, 1)        # what a schema 1 store holds: no access table (store.h)
    d2 = run(2, "session_access = owner\n", store)
    assert "schema 1 migrated to 3" in d2.log()
    with tcp(d2, "alice") as a, tcp(d2, "admin") as adm:
        pol = a.session_access(sid)
        assert (pol.mode_name, pol.owner) == ("owner", "")   # the config's mode, no owner
        assert a.open_session(sid).version == v
        refused(lambda: stroke(a, sid), E.ErrorCode.EPERM, "needs the edit right")
        adm.close_session(sid)                                # admins own it
    check_stopped(d2, d2.stop())     # the daemon holds the store's lock until it stops
    db = sqlite3.connect(store)
    assert db.execute("PRAGMA user_version").fetchone()[0] == 3
    db.close()


def test_deformctl_access_and_join(run):
    d = run(1, "session_access = key\n")
    base = [DEFORMCTL, "--tcp", "127.0.0.1:%d" % d.tcp_port]

    def ctl(who, *args, json_out=True):
        r = subprocess.run(base + (["--json"] if json_out else []) +
                           ["--key-file", d.keys[who]] + list(args),
                           capture_output=True, text=True, timeout=60)
        return r.returncode, (json.loads(r.stdout) if json_out and r.stdout.strip() else
                              r.stdout), r.stderr

    with tcp(d, "alice") as a:
        sid = a.load_mesh(grid_obj(4, 4), name="spot").session_id
    rc, out, err = ctl("alice", "access", "spot", "--observers", "off", "--new-key")
    assert rc == 0, err
    assert out["mode"] == "key" and out["observers"] is False and out["owner"] == "key:alice"
    key = out["key"]
    assert len(bytes.fromhex(key)) == 32
    rc, out, _ = ctl("bob", "join", str(sid), "--key", "00" * 32)
    assert rc == 1 and out["name"] == "EPERM" and "wrong join key" in out["message"]
    rc, out, _ = ctl("bob", "join", str(sid), "--key", "zz")
    assert rc == 2 and out["source"] == "usage"
    rc, out, err = ctl("bob", "join", str(sid), "--key", key)
    assert rc == 0, err
    assert out["members"] == 1 and "key" not in out
    rc, out, _ = ctl("bob", "access", "spot")          # bob, a member, reads the policy
    assert rc == 0 and out["mode"] == "key" and out["members"] == 1
    rc, out, _ = ctl("bob", "access", "spot", "--mode", "open")
    assert rc == 1 and out["name"] == "EPERM" and "needs the own right" in out["message"]
    rc, out, _ = ctl("alice", "access", "spot", "--mode", "everyone")
    assert rc == 2 and out["source"] == "usage"
    rc, text, err = ctl("alice", "access", "spot", "--mode", "open", json_out=False)
    assert rc == 0, err
    assert "mode open" in text and "owner key:alice" in text
