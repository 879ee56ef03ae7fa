"""The Python client's non-blocking API (client/python/deformd_client/poll.py, issue 13: the
Blender add-on's 60 Hz timer must never wait on the daemon): poll() returns what has arrived,
poll_reply(rid) a complete reply or None, both without blocking, and the socket is back to
blocking with the client's timeout afterwards (a following large upload must not meet a
non-blocking socket). Waits below are select() on the socket (for the data), never sleeps."""
import select
from array import array

import pytest

from deformd_client import Brush, ConnectionClosed, DeformdError, MeshState, MsgType
from deformd_client import messages as m
from helpers import grid_obj


def _wait_reply(c, rid):
    """poll_reply until complete, waiting on the socket in between (no sleeps)."""
    while True:
        parts = c.poll_reply(rid)
        if parts is not None:
            return parts
        assert c.sock.gettimeout() == c.timeout
        r, _, _ = select.select([c.sock], [], [], 10.0)
        assert r, "no reply to request %d within 10 s" % rid


def _client(daemon, transport):
    return daemon.unix_client() if transport == "unix" else daemon.tcp_client()


@pytest.mark.parametrize("transport", ["unix", "tcp"])
def test_poll_is_empty_and_leaves_the_socket_blocking(daemon, transport):
    with _client(daemon, transport) as c:
        assert c.poll() == []
        assert c.sock.gettimeout() == c.timeout
        assert c.poll_reply(12345) is None              # never sent: never ready
        assert not c.reply_ready(12345)
        big = grid_obj(400, 400)                        # ~8 MB: many sendall rounds
        info = c.load_mesh(big, fmt=".obj", name="poll-then-load-" + transport)
        assert info.nv == 400 * 400
        c.close_session(info.session_id)


@pytest.mark.parametrize("transport", ["unix", "tcp"])
def test_in_flight_update_and_stream_through_poll(daemon, transport):
    """One BRUSH_BEGIN and BRUSH_UPDATEs sent with send(), collected with poll_reply; the
    displacement of each arrives through poll() (queued before its ack) and a replica fed only
    by poll() ends byte-identical to GET_MESH."""
    with _client(daemon, transport) as c:
        sid = c.load_mesh(grid_obj(30, 30), fmt=".obj", name="poll-stream-" + transport).session_id
        c.subscribe(sid)
        rep = MeshState.sync(c, sid)
        brush = Brush(type="grab", center=(0.5, 0.5, 0.0), radius=0.3)
        ack = m.decode_ack(b"".join(p.payload for p in _wait_reply(
            c, c.send(MsgType.BRUSH_BEGIN, m.encode_brush(sid, brush)))))
        versions = []
        for k in range(1, 4):
            rid = c.send(MsgType.BRUSH_UPDATE, m.encode_brush_update(sid, (0.0, 0.0, 0.02 * k)))
            ack = m.decode_ack(b"".join(p.payload for p in _wait_reply(c, rid)))
            evs = c.poll()
            assert [e.version for e in evs] == [ack.version]
            for e in evs:
                assert rep.apply(e)
            versions.append(ack.version)
        assert versions == sorted(versions) and len(set(versions)) == 3
        c.brush_end(sid)
        assert rep.tobytes() == c.get_mesh(sid).positions.tobytes()
        assert c.poll() == []
        c.close_session(sid)


def test_poll_reply_raises_the_error_reply(daemon):
    with daemon.unix_client() as c:
        sid = c.load_mesh(grid_obj(5, 5), fmt=".obj", name="poll-error").session_id
        rid = c.send(MsgType.BRUSH_UPDATE, m.encode_brush_update(sid, (0.0, 0.0, 0.1)))
        with pytest.raises(DeformdError) as e:
            _wait_reply(c, rid)
        assert e.value.name == "ESTATE"                 # no stroke open
        assert c.poll_reply(rid) is None                # consumed: the request is done
        assert c.ping(b"still framed") == b"still framed"
        c.close_session(sid)


def test_poll_reports_a_closed_connection(make_daemon):
    d = make_daemon()
    c = d.unix_client()
    try:
        sid = c.load_mesh(grid_obj(5, 5), fmt=".obj", name="poll-closed").session_id
        c.subscribe(sid)
        assert c.poll() == []
        assert d.stop() == 0
        with pytest.raises(ConnectionClosed):
            while True:                                 # the daemon's goodbye, then EOF
                select.select([c.sock], [], [], 10.0)
                c.poll()
    finally:
        c.close()


def test_poll_returns_what_came_before_the_close(make_daemon):
    """A version that arrived before the daemon closed the connection comes out of poll() (read
    in the same drain as the end of stream); the next poll raises ConnectionClosed."""
    d = make_daemon()
    c = d.unix_client()
    try:
        sid = c.load_mesh(grid_obj(5, 5), fmt=".obj", name="poll-goodbye").session_id
        c.subscribe(sid)
        with d.unix_client() as c2:
            ack = c2.stroke(sid, Brush(type="grab", center=(0.5, 0.5, 0.0), move=(0, 0, 0.1),
                                       radius=0.3))
        r, _, _ = select.select([c.sock], [], [], 10.0)   # the version is in c's socket buffer
        assert r
        assert d.stop() == 0
        select.select([c.sock], [], [], 10.0)
        evs = c.poll()
        assert [e.version for e in evs] == [ack.version]
        with pytest.raises(ConnectionClosed):
            while True:
                select.select([c.sock], [], [], 10.0)
                c.poll()
    finally:
        c.close()
