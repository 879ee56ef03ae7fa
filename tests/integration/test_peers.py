"""Who is connected to a session: SESSION_PEERS (PROTOCOL.md 4.38, server/handlers/h_peers.c).
One row per connection subscribed to the session: its connection id, the client_name of its
HELLO, its principal, its transport and flags SELF (the asking connection), EDIT (its principal
may edit the session under the session's access policy) and SHM (shared-memory stream). Needs
the observe right; an unknown session is ENOTFOUND. A disconnect removes the row: the tests wait
for the daemon to have dropped the connection by half-closing it and reading until the daemon
closes its end (the daemon forgets a connection's subscriptions before it closes the socket)."""
import json
import os
import socket
import struct
import subprocess

import pytest

from conftest import DEFORMCTL
from deformd_client import Client, DeformdError, PeerFlag, ProtocolError, Transport, schema
from deformd_client import errors as E
from deformd_client import messages as m, peers as pr
from helpers import grid_obj
from test_membership import run, keys, tcp  # noqa: F401 (fixtures: TCP keys alice/bob/carol)


def gone(c: Client) -> None:
    """Disconnects c and returns once the daemon has closed the connection (after it dropped
    c's subscriptions): half-close, then read (and discard) until the daemon's end-of-stream."""
    c.sock.shutdown(socket.SHUT_WR)
    while c.sock.recv(1 << 16):
        pass
    c.close()


def rows(peers):
    """{client_id: (name, principal, transport, flags)} of a peer list (ids are unique)."""
    out = {p.client_id: (p.name, p.principal, p.transport, p.flags) for p in peers}
    assert len(out) == len(peers), peers
    return out


def own_id(peers):
    mine = [p.client_id for p in peers if p.flags & PeerFlag.SELF]
    assert len(mine) == 1, peers
    return mine[0]


def test_two_named_clients_see_each_other_then_a_disconnect(daemon):
    uid = "uid:%d" % os.getuid()
    with Client.connect_unix(daemon.socket_path, name="alice-ws") as a, \
            Client.connect_unix(daemon.socket_path, name="bob laptop") as b:
        sid = a.load_mesh(grid_obj(5, 5), name="peers").session_id
        assert a.session_peers(sid) == []                     # loading subscribes nobody
        a.subscribe(sid)
        b.subscribe(sid)
        pa, pb = a.session_peers(sid), b.session_peers(sid)
        ida, idb = own_id(pa), own_id(pb)
        assert ida != idb
        assert [p.client_id for p in pa] == [ida, idb]         # subscription order
        # the same rows from either side, SELF on the asker's own row only
        both = {ida: ("alice-ws", uid, Transport.UNIX), idb: ("bob laptop", uid, Transport.UNIX)}
        for seen, me in ((pa, ida), (pb, idb)):
            for cid, (name, principal, transport, flags) in rows(seen).items():
                assert (name, principal, transport) == both[cid]
                assert bool(flags & PeerFlag.SELF) == (cid == me)
                assert flags & PeerFlag.EDIT                   # one uid: the owner, both edit
                assert not flags & PeerFlag.SHM
        # SHM once b reads the shared-memory stream
        b.stream_shm(sid)
        shm = {p.client_id: bool(p.flags & PeerFlag.SHM) for p in a.session_peers(sid)}
        assert shm == {ida: False, idb: True}
        # unsubscribe removes the row; subscribing again puts it back (at the end)
        b.unsubscribe(sid)
        assert [p.client_id for p in a.session_peers(sid)] == [ida]
        b.subscribe(sid)
        assert [p.client_id for p in a.session_peers(sid)] == [ida, idb]
        gone(b)
        left = a.session_peers(sid)
        assert [(p.client_id, p.name, p.flags & PeerFlag.SELF) for p in left] == \
            [(ida, "alice-ws", PeerFlag.SELF)]


def test_pipelined_subscribe_then_peers_lists_the_subscription(daemon):
    """SESSION_PEERS is a session request (FIFO): sent right behind a SUBSCRIBE on the same
    connection, without waiting for its reply, it sees that subscription."""
    with Client.connect_unix(daemon.socket_path, name="pipeliner") as c:
        sid = c.load_mesh(grid_obj(4, 4)).session_id
        r1 = c.send(m.SUBSCRIBE, m.encode_subscribe(sid))
        r2 = c.send(m.SESSION_PEERS, m.encode_session_ref(sid))
        r3 = c.send(m.GET_MESH, m.encode_get_mesh(sid))        # a FIFO barrier behind them
        c.wait_reply(r3)
        c.wait_reply(r1)
        peers = pr.decode_peer_list(c.wait_reply(r2)[0].payload)
        assert [(p.name, p.flags & PeerFlag.SELF) for p in peers] == \
            [("pipeliner", PeerFlag.SELF)]


def test_unknown_session_and_bad_requests(daemon):
    with Client.connect_unix(daemon.socket_path) as c:
        with pytest.raises(DeformdError) as ei:
            c.session_peers(987654)
        assert ei.value.code == E.ErrorCode.ENOTFOUND and "987654" in str(ei.value)
        # a truncated session_ref and session id 0: refused, the connection lives on
        rid = c.send(m.SESSION_PEERS, b"\x01\x00")
        with pytest.raises(DeformdError) as ei:
            c.wait_reply(rid)
        assert ei.value.code == E.ErrorCode.EPROTO_TRUNCATED
        with pytest.raises(DeformdError) as ei:
            c.session_peers(0)
        assert ei.value.code == E.ErrorCode.EINVAL
        assert c.ping(b"alive") == b"alive"


def test_edit_follows_the_access_mode_and_observe_is_needed(run):  # noqa: F811
    d = run(1, "session_access = owner\n")
    with tcp(d, "alice") as a, tcp(d, "bob") as b, tcp(d, "carol") as c:
        sid = a.load_mesh(grid_obj(5, 5), name="owned").session_id
        a.subscribe(sid)
        b.subscribe(sid)                                       # observers on: bob observes
        got = {p.principal: p for p in b.session_peers(sid)}
        assert set(got) == {"key:alice", "key:bob"}
        assert all(p.transport == Transport.TCP for p in got.values())
        assert got["key:alice"].flags & PeerFlag.EDIT           # the owner edits
        assert not got["key:bob"].flags & PeerFlag.EDIT         # owner mode: bob only observes
        assert got["key:bob"].flags & PeerFlag.SELF and not got["key:alice"].flags & PeerFlag.SELF
        # open mode: every principal edits, and the rows say so at once
        a.session_access(sid, mode="open")
        assert all(p.flags & PeerFlag.EDIT for p in c.session_peers(sid))
        # observers off in owner mode: carol may not observe, so she may not list the peers
        a.session_access(sid, mode="owner", observers=False)
        with pytest.raises(DeformdError) as ei:
            c.session_peers(sid)
        assert ei.value.code == E.ErrorCode.EPERM
        assert "needs the observe right" in str(ei.value) and "key:carol" in str(ei.value)
        # the owner still lists both, bob (subscribed before) without EDIT
        flags = {p.principal: p.flags for p in a.session_peers(sid)}
        assert flags["key:alice"] & PeerFlag.EDIT and not flags["key:bob"] & PeerFlag.EDIT


def test_deformctl_peers(daemon):
    base = [DEFORMCTL, "--socket", daemon.socket_path]
    with Client.connect_unix(daemon.socket_path, name="sculptor one") as a, \
            Client.connect_unix(daemon.socket_path, name="viewer") as b:
        sid = a.load_mesh(grid_obj(4, 4), name="ctlpeers").session_id
        a.subscribe(sid)
        b.subscribe(sid)
        b.stream_shm(sid)
        want = a.session_peers(sid)
        r = subprocess.run(base + ["--json", "peers", "ctlpeers"], capture_output=True,
                           text=True, timeout=60)
        assert r.returncode == 0, r.stderr
        out = json.loads(r.stdout)
        assert out["ok"] is True and out["session"] == sid
        assert [(p["id"], p["name"], p["principal"], p["transport"], p["self"], p["edit"],
                 p["shm"]) for p in out["peers"]] == \
            [(p.client_id, p.name, p.principal, p.transport_name, False,
              bool(p.flags & PeerFlag.EDIT), bool(p.flags & PeerFlag.SHM)) for p in want]
        r = subprocess.run(base + ["peers", str(sid)], capture_output=True, text=True,
                           timeout=60)
        assert r.returncode == 0, r.stderr
        lines = r.stdout.splitlines()
        assert lines[0] == "session %d: 2 peers" % sid
        for p, line in zip(want, lines[1:]):
            assert line.startswith("client %d '%s' as %s over unix, edit" % (
                p.client_id, p.name, p.principal)), line
            assert line.endswith(", shm") == bool(p.flags & PeerFlag.SHM), line
        assert len(lines) == 3
        r = subprocess.run(base + ["--json", "peers", "no-such-session"], capture_output=True,
                           text=True, timeout=60)
        assert r.returncode == 1 and json.loads(r.stdout)["name"] == "ENOTFOUND"


def _patched(p, off, fmt, value):
    b = bytearray(p)
    struct.pack_into(fmt, b, off, value)
    return bytes(b)


def test_python_peer_list_codec_round_trip_and_refusals():
    rows = [pr.Peer(5, PeerFlag.EDIT | PeerFlag.SHM, Transport.UNIX, "blender", "uid:1000"),
            pr.Peer(9, PeerFlag.SELF, Transport.TCP, "", "key:bob")]
    p = pr.encode_peer_list(rows)
    assert len(p) == 4 + sum(12 + 2 + len(r.name) + 2 + len(r.principal) for r in rows)
    back = pr.decode_peer_list(p)
    assert back == rows
    assert [r.label for r in back] == ["blender", "key:bob"]
    assert [r.transport_name for r in back] == ["unix", "tcp"]
    assert pr.decode_peer_list(pr.encode_peer_list([])) == []
    # row 0 at 4: client_id 4, flags 12, transport 13, reserved 14; count at 0
    for off, fmt, value, needle in ((4, "<Q", 0, "client_id 0"), (12, "<B", 0x10, "flag"),
                                    (13, "<B", 3, "transport 3"), (14, "<H", 1, "reserved"),
                                    (0, "<I", schema.MAX_PEERS + 1, "exceed")):
        with pytest.raises(ProtocolError) as ei:
            pr.decode_peer_list(_patched(p, off, fmt, value))
        assert needle in str(ei.value)
    for bad in (p[:-1], p + b"\0", _patched(p, 0, "<I", 3)):
        with pytest.raises(ProtocolError):
            pr.decode_peer_list(bad)
