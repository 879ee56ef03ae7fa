"""Per-session access and per-principal quotas (issue 12, access control items 3 and 4;
PROTOCOL.md 4.34). Two principals come from two named TCP keys (peer_key alice / bob); key_file
is the admin key. The creator of a session owns it: only the owner or an admin may close it or
reset its rest shape; with session_access = owner the others may only observe. A refusal is
EPERM naming the missing right and changes nothing. Quotas (quota_sessions, quota_upload_mb,
quota_memory_mb) refuse a load with ELIMIT naming the quota and the principal, and closing a
session releases its share. DEVICE_BIND needs the edit right; session_access (of sessions
loaded afterwards) and the quotas change on SIGHUP."""
import json
import os
import secrets
import subprocess

import pytest

from conftest import DEFORMCTL
from deformd_client import Brush, Client, DeformdError, errors as E
from helpers import grid_obj
from test_hid import replay_config
from test_reload import rewrite_and_hup


def write_key(path) -> None:
    with open(path, "w") as f:
        f.write(secrets.token_hex(32) + "\n")
    os.chmod(path, 0o600)


@pytest.fixture
def keys(tmp_path):
    out = {}
    for who in ("admin", "alice", "bob"):
        out[who] = str(tmp_path / ("%s.key" % who))
        write_key(out[who])
    return out


def start(make_daemon, keys, extra=""):
    cfg = ("key_file = %s\npeer_key = alice %s\npeer_key = bob %s\n"
           % (keys["admin"], keys["alice"], keys["bob"])) + extra
    return make_daemon(cfg, tcp=True)


def tcp(d, keyfile) -> Client:
    return Client.connect_tcp("127.0.0.1", d.tcp_port, timeout=30.0, key_file=keyfile)


def stroke(c, sid):
    c.stroke(sid, Brush(center=(0.5, 0.5, 0.0), move=(0.0, 0.0, 0.05), radius=0.4))


def state(u):
    return [(s.session_id, s.name, s.version, s.undo_depth) for s in u.list_sessions()]


def refused(call, right):
    with pytest.raises(DeformdError) as ei:
        call()
    assert ei.value.code == E.ErrorCode.EPERM, ei.value
    assert "needs the %s right" % right in str(ei.value), ei.value
    return str(ei.value)


def test_open_mode_members_edit_but_only_owner_or_admin_closes(make_daemon, keys):
    d = start(make_daemon, keys)
    with tcp(d, keys["alice"]) as a, tcp(d, keys["bob"]) as b, d.unix_client() as u:
        sid = a.load_mesh(grid_obj(6, 6), name="spot").session_id
        v0 = a.open_session(sid).version
        stroke(b, sid)                             # open (default): members edit
        b.undo(sid)
        b.redo(sid)
        assert a.open_session(sid).version > v0
        before = state(u)
        msg = refused(lambda: b.close_session(sid), "own")
        assert "key:bob" in msg and "owner key:alice" in msg and "'spot'" in msg
        refused(lambda: b.reset_rest(sid), "own")
        assert state(u) == before                  # nothing changed
        a.reset_rest(sid)                          # the owner may
        a.close_session(sid)
        assert u.list_sessions() == []
        sid2 = b.load_mesh(grid_obj(5, 5), name="bobs").session_id
    with tcp(d, keys["admin"]) as adm:             # key_file: the admin closes anything
        adm.close_session(sid2)
        assert adm.list_sessions() == []


def test_owner_mode_others_only_observe(make_daemon, keys):
    d = start(make_daemon, keys, "session_access = owner\n")
    with tcp(d, keys["alice"]) as a, tcp(d, keys["bob"]) as b, d.unix_client() as u:
        sid = a.load_mesh(grid_obj(6, 6), name="spot").session_id
        stroke(a, sid)
        before = state(u)
        mesh = b.get_mesh(sid)                     # observe: get mesh, snapshot, subscribe
        assert mesh.nv == 36
        b.snapshot(sid)
        b.subscribe(sid)
        b.brush_state_get(sid)
        msg = refused(lambda: b.brush_begin(sid, Brush(center=(0.5, 0.5, 0.0),
                                                       move=(0.0, 0.0, 0.05), radius=0.4)),
                      "edit")
        assert "an observer" in msg
        refused(lambda: b.undo(sid), "edit")
        refused(lambda: b.set_handles(sid, [0, 1]), "edit")
        refused(lambda: b.brush_state_set(sid, radius=0.2), "edit")
        refused(lambda: b.close_session(sid), "own")
        assert state(u) == before
        stroke(u, sid)      # the daemon's own uid on the Unix socket is an admin
        u.close_session(sid)
        assert u.list_sessions() == []


def test_quota_sessions_refused_then_released_after_close(make_daemon, keys):
    d = start(make_daemon, keys, "quota_sessions = 1\n")
    with tcp(d, keys["alice"]) as a, tcp(d, keys["bob"]) as b:
        sid = a.load_mesh(grid_obj(4, 4), name="one").session_id
        with pytest.raises(DeformdError) as ei:
            a.load_mesh(grid_obj(4, 4), name="two")
        assert ei.value.code == E.ErrorCode.ELIMIT
        assert "quota_sessions" in str(ei.value) and "key:alice" in str(ei.value)
        assert [s.name for s in a.list_sessions()] == ["one"]
        other = b.load_mesh(grid_obj(4, 4), name="bobs")  # per principal
        a.close_session(sid)
        a.load_mesh(grid_obj(4, 4), name="two")            # released
        b.close_session(other.session_id)


def test_quota_upload_mb(make_daemon, keys):
    big = grid_obj(110, 110)           # each upload is more than half a MiB, less than one
    assert (1 << 19) < len(big) < (1 << 20), len(big)
    d = start(make_daemon, keys, "quota_upload_mb = 1\n")
    with tcp(d, keys["alice"]) as a:
        sid = a.load_mesh(big, name="first").session_id
        with pytest.raises(DeformdError) as ei:
            a.load_mesh(big, name="second")
        assert ei.value.code == E.ErrorCode.ELIMIT
        assert "quota_upload_mb" in str(ei.value) and "key:alice" in str(ei.value)
        assert [s.name for s in a.list_sessions()] == ["first"]
        a.close_session(sid)
        a.load_mesh(big, name="second")


BYTES_PER_VERTEX = 160    # DF_SESSION_BYTES_PER_VERTEX: the least a new session is charged


def test_quota_memory_mb(make_daemon, keys):
    d = start(make_daemon, keys, "quota_memory_mb = 1\n")
    with tcp(d, keys["alice"]) as a, tcp(d, keys["bob"]) as b:
        sid = a.load_mesh(grid_obj(60, 60), name="fits").session_id
        held = a.stats(sid)["memory_bytes"]
        assert held < (1 << 20)                              # one fits ...
        assert held + 60 * 60 * BYTES_PER_VERTEX > (1 << 20)  # ... a second cannot
        with pytest.raises(DeformdError) as ei:
            a.load_mesh(grid_obj(60, 60), name="over")
        assert ei.value.code == E.ErrorCode.ELIMIT
        msg = str(ei.value)
        assert "quota_memory_mb" in msg and "key:alice" in msg and "1 MiB" in msg
        assert [s.name for s in a.list_sessions()] == ["fits"]
        other = b.load_mesh(grid_obj(60, 60), name="bobs")  # bob's own quota
        a.close_session(sid)
        a.load_mesh(grid_obj(60, 60), name="over")            # released by the close
        b.close_session(other.session_id)


@pytest.mark.parametrize("extra, needle", [
    ("session_access = everyone\n", "session_access"),
    ("quota_sessions = -1\n", "quota_sessions"),
    ("peer_key = bad/name /tmp/x\n", "peer_key"),
])
def test_bad_access_settings_refuse_start(make_daemon, keys, extra, needle):
    with pytest.raises(RuntimeError) as ei:
        start(make_daemon, keys, extra)
    assert needle in str(ei.value)


def test_deformctl_with_a_named_key_gets_eperm(make_daemon, keys):
    d = start(make_daemon, keys)
    with tcp(d, keys["alice"]) as a, d.unix_client() as u:
        a.load_mesh(grid_obj(4, 4), name="spot")
        base = [DEFORMCTL, "--tcp", "127.0.0.1:%d" % d.tcp_port, "--json"]
        r = subprocess.run(base + ["--key-file", keys["bob"], "close", "spot"],
                           capture_output=True, text=True, timeout=60)
        assert r.returncode == 1, (r.stdout, r.stderr)
        out = json.loads(r.stdout)
        assert out["name"] == "EPERM" and out["code"] == E.ErrorCode.EPERM
        assert "needs the own right" in out["message"] and "key:bob" in out["message"]
        assert [s.name for s in u.list_sessions()] == ["spot"]
        r = subprocess.run(base + ["--key-file", keys["alice"], "close", "spot"],
                           capture_output=True, text=True, timeout=60)
        assert r.returncode == 0, (r.stdout, r.stderr)
        assert u.list_sessions() == []


def test_sighup_switches_session_access_of_new_sessions_and_quotas_live(make_daemon, keys):
    d = start(make_daemon, keys)
    with tcp(d, keys["alice"]) as a, tcp(d, keys["bob"]) as b:
        sid = a.load_mesh(grid_obj(5, 5), name="spot").session_id
        stroke(b, sid)                                      # open: bob edits
        keys_cfg = ("key_file = %s\npeer_key = alice %s\npeer_key = bob %s\n"
                    % (keys["admin"], keys["alice"], keys["bob"]))
        rewrite_and_hup(d, keys_cfg + "session_access = owner\nquota_sessions = 2\n",
                        "session_access owner, session_observers on, quota_sessions 2")
        stroke(b, sid)               # a session keeps the mode it was loaded with
        sid2 = a.load_mesh(grid_obj(4, 4), name="two").session_id
        refused(lambda: stroke(b, sid2), "edit")            # a new one takes the new mode
        with pytest.raises(DeformdError) as ei:
            a.load_mesh(grid_obj(4, 4), name="three")
        assert ei.value.code == E.ErrorCode.ELIMIT and "quota_sessions" in str(ei.value)


def test_device_bind_needs_the_edit_right(make_daemon, keys):
    d = start(make_daemon, keys, replay_config(["griffin-powermate_077d-0410_usb.raw.txt"],
                                               "session_access = owner\n"))
    with tcp(d, keys["alice"]) as a, tcp(d, keys["bob"]) as b:
        sid = a.load_mesh(grid_obj(5, 5), name="spot").session_id
        (knob,) = b.devices_list()
        assert knob.class_name == "knob"
        refused(lambda: b.device_bind(knob.device_id, sid), "edit")
        assert b.devices_list()[0].bound_session == 0           # nothing bound
        a.device_bind(knob.device_id, sid)                     # the owner may
        assert b.devices_list()[0].bound_session == sid
