"""Client-chosen names (issue 9 items 5 and 6): log lines escape control bytes, names must be
UTF-8 without control characters, the chunks of a load keep one name, session names are unique."""
import struct

import pytest

from deformd_client import DeformdError, errors as E, frame as fr, messages as m
from helpers import grid_obj
from rawwire import read_frames

FORGED = "deformd[error]: forged line"


def raw_load_payload(name: bytes, data: bytes, offset: int = 0, total: int = 0) -> bytes:
    """A LOAD_MESH inline body with raw name bytes (the Python encoder only takes str)."""
    return (struct.pack("<BBHQQQ", m.LOAD_INLINE, m.FMT_OBJ, 0, total or len(data), 0, offset)
            + struct.pack("<H", len(name)) + name + struct.pack("<H", 0)
            + struct.pack("<I", len(data)) + data)


def one_frame(sock, data: bytes):
    sock.sendall(data)
    frames, closed = read_frames(sock, 5.0)
    assert frames, "no reply (closed=%s)" % closed
    return frames[0]


def session_names(daemon):
    with daemon.unix_client() as c:
        return [s.name for s in c.list_sessions()]


def test_log_escapes_control_bytes(make_daemon):
    """A name echoed into a log line (debug log of an error reply) cannot forge a line or carry a
    terminal escape: control bytes are written as \\xNN."""
    d = make_daemon("log_level = debug\n")
    evil = "nope\n" + FORGED + "\x1b[2J\r"
    with d.unix_client() as c:
        with pytest.raises(DeformdError) as ei:
            c.open_session(name=evil)
        assert ei.value.code == E.ENOTFOUND
        c.ping(b"sync")  # the error reply was logged before this reply was sent
    log = d.log()
    assert "\\x0a" + FORGED in log, log[-2000:]
    assert not any(line.startswith(FORGED) for line in log.splitlines()), log[-2000:]
    assert "\x1b" not in log and "\r" not in log


@pytest.mark.parametrize("name", [b"bad\xff", b"ab\xc3", b"\xed\xa0\x80x", b"\xc0\xafx",
                                  b"new\nline", b"esc\x1b[31m", b"c1\xc2\x9b"])
def test_session_name_must_be_utf8_without_controls(daemon, name):
    before = session_names(daemon)
    s = daemon.raw_unix(hello=True)
    f = one_frame(s, fr.encode_frame(m.LOAD_MESH, raw_load_payload(name, grid_obj(2, 2)), 5))
    assert f.is_error and f.request_id == 5 and f.type == m.LOAD_MESH
    code, msg = m.decode_error(f.payload)
    assert code == E.EINVAL and "load_mesh: name" in msg, msg
    s.close()
    assert session_names(daemon) == before


@pytest.mark.parametrize("name", [b"bad\xff", b"\xf5\x80\x80\x80", b"tab\there"])
def test_client_name_must_be_utf8_without_controls(daemon, name):
    s = daemon.raw_unix()
    body = struct.pack("<HHI", 1, 1, 0) + struct.pack("<H", len(name)) + name
    f = one_frame(s, fr.encode_frame(m.HELLO, body, 3))
    assert f.is_error and f.request_id == 3
    code, msg = m.decode_error(f.payload)
    assert code == E.EINVAL and "client_name" in msg, msg
    # the HELLO did not succeed: other requests are still refused
    f = one_frame(s, fr.encode_frame(m.LIST_SESSIONS, b"", 4))
    assert f.is_error and m.decode_error(f.payload)[0] == E.ESTATE
    s.close()


def test_utf8_names_are_accepted(daemon):
    with daemon.unix_client() as c:
        c.hello("clïent ✓")
        info = c.load_mesh(grid_obj(2, 2), fmt=".obj", name="grille-é-✓")
        assert info.name == "grille-é-✓"
        c.close_session(info.session_id)


def test_chunk_with_another_name_is_refused(daemon):
    data = grid_obj(3, 3)
    half = len(data) // 2
    s = daemon.raw_unix(hello=True)
    s.sendall(fr.encode_frame(m.LOAD_MESH, raw_load_payload(b"chunk-a", data[:half], 0,
                                                            len(data)), 8, fr.FLAG_MORE))
    f = one_frame(s, fr.encode_frame(m.LOAD_MESH, raw_load_payload(b"chunk-b", data[half:], half,
                                                                   len(data)), 8))
    assert f.is_error and f.request_id == 8
    code, msg = m.decode_error(f.payload)
    assert code == E.EPROTO_CHUNK and "name" in msg, msg
    s.close()
    names = session_names(daemon)
    assert "chunk-a" not in names and "chunk-b" not in names


def test_session_names_are_unique(daemon):
    with daemon.unix_client() as c:
        first = c.load_mesh(grid_obj(2, 2), fmt=".obj", name="unique-name")
        with pytest.raises(DeformdError) as ei:
            c.load_mesh(grid_obj(3, 3), fmt=".obj", name="unique-name")
        assert ei.value.code == E.EEXIST and ei.value.name == "EEXIST"
        assert "unique-name" in ei.value.message and "in use" in ei.value.message
        assert [s.session_id for s in c.list_sessions() if s.name == "unique-name"] == \
            [first.session_id]
        assert c.open_session(name="unique-name").session_id == first.session_id
        # once the first is closed the name is free again
        c.close_session(first.session_id)
        again = c.load_mesh(grid_obj(3, 3), fmt=".obj", name="unique-name")
        assert again.session_id != first.session_id
        c.close_session(again.session_id)
