"""The Python client's socket state between calls (issue 10): a call whose deadline has passed
(events(timeout=0)) reads without blocking, and the socket must be back to blocking (with the
client's timeout) afterwards, or the next large sendall raises BlockingIOError with part of a
frame on the wire. A send that fails half way closes the client instead of leaving a torn frame.
"""
import socket

import pytest

from deformd_client import Client
from deformd_client.errors import ConnectionClosed
from helpers import grid_obj


def big_obj() -> bytes:
    """A ~8 MB grid OBJ (far more than a Unix socket buffer holds), generated: no meshes needed."""
    data = grid_obj(400, 400)
    assert len(data) > 7 << 20
    return data


@pytest.mark.parametrize("transport", ["unix", "tcp"])
def test_large_load_after_events_timeout_zero(daemon, transport):
    data = big_obj()
    with (daemon.unix_client() if transport == "unix" else daemon.tcp_client()) as c:
        assert list(c.events(timeout=0)) == []
        info = c.load_mesh(data, fmt=".obj", name="after-events-0-" + transport)
        assert c.sock.gettimeout() == c.timeout          # restored, not left non-blocking
        assert info.nv == 400 * 400
        assert c.next_event(timeout=0) is None
        assert c.sock.gettimeout() == c.timeout
        c.close_session(info.session_id)
        assert c.ping(b"still framed") == b"still framed"


def test_timeout_error_restores_socket(daemon):
    """wait_reply's TimeoutError (deadline already passed) leaves the socket blocking too."""
    with daemon.unix_client() as c:
        with pytest.raises(TimeoutError):
            c.wait_reply(999999, timeout=0)                # never sent: no reply can come
        info = c.load_mesh(big_obj(), fmt=".obj", name="after-timeout-error")
        assert c.sock.gettimeout() == c.timeout
        c.close_session(info.session_id)


def test_failed_send_closes_client_instead_of_tearing_a_frame():
    """A peer that never reads: sendall times out part way; the client closes itself (a later
    send cannot append a frame to the torn one)."""
    a, b = socket.socketpair()
    try:
        a.settimeout(0.2)
        c = Client(a, timeout=0.2, hello=False)
        with pytest.raises(ConnectionClosed):
            c.send(0x0003, b"x" * (8 << 20))
        assert a.fileno() == -1                            # closed
        with pytest.raises(OSError):
            c.send(0x0003, b"")
    finally:
        b.close()
