"""Blocking client of deformd: one socket, one request at a time, events queued meanwhile.

    with Client.connect_unix("/run/user/1000/deformd.sock") as c:
        sid = c.load_mesh(path_or_bytes).session_id
        c.subscribe(sid)
        c.stroke(sid, Brush(type="grab", center=(0, 0, 0), move=(0, 0.1, 0), radius=0.5))
        for ev in c.events(timeout=1.0):
            print(ev.version, ev.kind_name, ev.count)

Replies are matched to requests by request id; stream frames (displacements, progress, session
closed) that arrive while waiting are assembled from their chunks and queued for events().
Error replies raise DeformdError(code, name, message).

On the Unix socket, stream_shm(sid) moves a subscribed session's large stream frames to a
shared-memory ring the daemon writes once for all subscribers (PROTOCOL.md 6.1); events() reads
them from the ring transparently, and reports frames overwritten before they were read as ShmLost
events (resync with snapshot()).

Progress of long work (PROTOCOL.md 4.37): load_mesh, load_file, set_handles and move_handles take
an optional `progress` callback. When given, the request asks the daemon for WORK_PROGRESS events
and the callback is called with each progress.WorkProgress (stage "upload" / "parse" /
"factorize" / "solve", done, total, final, elapsed_ms) while the call waits, in order, all before
the call returns (none after the reply; at most ~20 per second per request plus each stage's
final event). It runs on the calling thread inside the call: it may update a UI (e.g. Blender's
window_manager.progress_update) but must not use this Client; an exception it raises propagates
out of the call (the connection stays usable: the reply is collected by the next wait, or
dropped). A daemon without the feature refuses the request (EPROTO_RESERVED / EPROTO_TRAILING):
call again without `progress`.
"""
import os
import secrets
import socket
import ssl
import time
from array import array
from collections import deque
from dataclasses import dataclass
from typing import Deque, Dict, Iterator, List, Optional, Set, Tuple, Union

from . import auth
from . import brush_state as bs
from . import devices as dv
from . import frame as fr
from . import messages as m
from . import progress as pg
from . import schema
from . import stream as st
from . import stream_enc as se
from .access_requests import AccessRequestsMixin
from .edit_requests import EditRequestsMixin
from .poll import PollMixin
from .stream import ShmRing
from .errors import EMOVED, ConnectionClosed, DeformdError, error_name, moved_address
from .wire import ProtocolError

DEFAULT_TIMEOUT_S = 60.0
RECV_BYTES = 1 << 20


@dataclass
class SessionClosed:
    """Event: the session was destroyed (closed by a client or evicted)."""
    session_id: int
    kind_name: str = "session_closed"


@dataclass
class MeshData:
    """A get-mesh reply: float32 positions (3*nv), element indices (elem_size*ne, u32), optional
    boundary faces of a tet mesh (3*nf) and, when asked, rest and base positions."""
    session_id: int
    version: int
    kind: int
    planar: int
    nv: int
    ne: int
    nf: int
    positions: array
    elements: array
    faces: array
    rest: Optional[array] = None
    base: Optional[array] = None

    @property
    def elem_size(self) -> int:
        return m.ELEM_SIZE.get(self.kind, 0)


@dataclass
class ShmLost:
    """Event: a frame of a session's shared-memory stream (Client.stream_shm) was overwritten in
    the ring before this client read it (PROTOCOL.md 6.1: the client read too slowly). A version,
    or part of one, is missed: resync the replica with snapshot(). Told apart from the other
    events by `type` == messages.SHM_REF (the event that referenced the frame) or `lost` True;
    MeshState.apply returns False for it (and changes nothing). The remaining chunks of a version
    whose chunk was lost are dropped, so no partial version is ever queued."""
    session_id: int
    position: int
    length: int
    type: int = m.SHM_REF
    lost: bool = True
    kind_name: str = "shm_lost"


Event = Union[st.Disp, st.Progress, se.QDisp, SessionClosed, ShmLost, bs.BrushState, bs.BrushCursor,
              pg.WorkProgress]
ProgressFn = pg.ProgressFn  # a progress callback (load_mesh, load_file, set_handles, move_handles)

class Client(PollMixin, EditRequestsMixin, AccessRequestsMixin):
    """A connection to deformd. Not thread-safe: use one Client per thread."""

    def __init__(self, sock: socket.socket, timeout: float = DEFAULT_TIMEOUT_S,
                 hello: bool = True, name: str = "deformd-python", key: Optional[bytes] = None,
                 key_file: Optional[str] = None, encoding: Optional[int] = None,
                 error: float = 0.0) -> None:
        """With `key` (bytes) or `key_file` (a path, auth.load_key) the connection authenticates
        right after HELLO (authenticate); without, a server that requires AUTH answers other
        requests EPROTO_AUTH. `encoding` / `error`: the stream encoding asked in HELLO (hello())."""
        self.sock = sock
        self.timeout = timeout
        self._decoder = fr.FrameDecoder()
        self._frames: Deque[fr.Frame] = deque()   # received, not yet consumed
        self._events: Deque[Event] = deque()      # complete events, oldest first
        self._partial: Dict[Tuple[int, int, int], List] = {}  # (type, session, version) -> chunks
        self._wire: Dict[Tuple[int, int, int], int] = {}  # ... -> wire bytes of those chunks
        self._next_id = 1
        self._pending: Dict[int, List[fr.Frame]] = {}   # sent, not awaited: frames so far
        self._done: Dict[int, List[fr.Frame]] = {}      # complete replies not yet collected
        self._work_cbs: Dict[int, ProgressFn] = {}      # request id -> its progress callback
        self._closed = False
        self._shm: Dict[int, ShmRing] = {}          # session -> mapped ring (stream_shm)
        self._shm_gap: Set[int] = set()             # sessions whose ring lost a chunk
        self._shm_detaching: Set[int] = set()       # attach failed: refs count as lost
        self.server: Optional[m.HelloReply] = None
        self.authenticated = False
        # cluster mode (PROTOCOL.md 4.39): an EMOVED answer moves the client to the owner's
        # address (TCP, same name, key and TLS context) and retries the request once there
        self.follow_moved = True
        self.moves = 0                               # redirects followed so far
        self._name, self._key = name, key
        self._encoding, self._error = encoding, error  # asked again after a redirect
        self._ssl_context: Optional[ssl.SSLContext] = None
        try:
            if key_file is not None and key is None:
                key = auth.load_key(key_file)
            if hello:
                self.server = self.hello(name, encoding, error)
                if key is not None:
                    self.authenticate(key)
        except BaseException:
            self.sock.close()
            raise

    # ------------------------------------------------------------------ connection
    @classmethod
    def connect_unix(cls, path: str, timeout: float = DEFAULT_TIMEOUT_S, hello: bool = True,
                     name: str = "deformd-python", key: Optional[bytes] = None,
                     key_file: Optional[str] = None, encoding: Optional[int] = None,
                     error: float = 0.0) -> "Client":
        s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        s.settimeout(timeout)
        try:
            s.connect(path)
        except OSError:
            s.close()
            raise
        return cls(s, timeout, hello, name, key, key_file, encoding, error)

    @classmethod
    def connect_tcp(cls, host: str, port: int, timeout: float = DEFAULT_TIMEOUT_S,
                    hello: bool = True, name: str = "deformd-python",
                    key: Optional[bytes] = None, key_file: Optional[str] = None,
                    tls_ca: Optional[str] = None, ssl_context: Optional[ssl.SSLContext] = None,
                    server_hostname: Optional[str] = None, encoding: Optional[int] = None,
                    error: float = 0.0) -> "Client":
        """With `tls_ca` (a PEM file of the CA that signed the daemon's tls_cert) or a ready
        `ssl_context`, the connection is TLS (the daemon's tls_cert / tls_key): the certificate
        is verified against the CA and must name `server_hostname` (default: `host`); failures
        raise ssl.SSLError (ssl.SSLCertVerificationError for a certificate from another CA or
        for another name). Key authentication then runs inside TLS."""
        if tls_ca is not None and ssl_context is None:
            ssl_context = ssl.create_default_context(cafile=tls_ca)
            ssl_context.minimum_version = ssl.TLSVersion.TLSv1_3
        s = socket.create_connection((host, port), timeout=timeout)
        try:
            s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            if ssl_context is not None:
                s = ssl_context.wrap_socket(s, server_hostname=server_hostname or host)
        except BaseException:
            s.close()
            raise
        c = cls(s, timeout, hello, name, key, key_file, encoding, error)
        c._ssl_context = ssl_context
        return c

    def move_to(self, host: str, port: int) -> None:
        """Replaces the connection by a new one to the daemon at host:port (TCP, with this
        client's name, key, TLS context and stream encoding), HELLO and AUTH done: the cluster redirect (EMOVED).
        Replies and events not yet read from the old connection, and its subscriptions and
        shared-memory rings, are dropped: subscribe again on the new daemon."""
        s = socket.create_connection((host, port), timeout=self.timeout)
        try:
            s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            if self._ssl_context is not None:
                s = self._ssl_context.wrap_socket(s, server_hostname=host)
        except BaseException:
            s.close()
            raise
        old = self.sock
        for sid in list(self._shm):
            self._drop_shm(sid)
        self.sock = s
        self._decoder = fr.FrameDecoder()
        self._frames.clear()
        self._partial.clear()
        self._pending.clear()
        self._done.clear()
        self._work_cbs.clear()
        old.close()
        self.authenticated = False
        self.server = self.hello(self._name, self._encoding, self._error)
        if self._key is not None:
            self.authenticate(self._key)
        self.moves += 1

    def close(self) -> None:
        """Closes the socket and every shared-memory ring mapping."""
        if not self._closed:
            self._closed = True
            self.sock.close()
            for sid in list(self._shm):
                self._drop_shm(sid)

    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # ------------------------------------------------------------------ framing
    def send(self, msg_type: int, payload: bytes = b"", flags: int = 0,
             request_id: Optional[int] = None) -> int:
        """Sends one frame; returns its request id (a fresh one unless given). Several requests
        may be in flight: wait_reply() collects each reply by id, in any order."""
        if request_id is None:
            request_id = self._next_id
            self._next_id += 1
        frame = fr.encode_frame(msg_type, payload, request_id, flags)
        self.sock.settimeout(self.timeout)   # blocking (with the call timeout), whatever came before
        try:
            self.sock.sendall(frame)
        except (BrokenPipeError, ConnectionResetError) as e:
            # the server closed the connection: report its ERROR event when it sent one
            self._raise_why_closed(e)
        except BaseException as e:
            # part of the frame may be on the wire: nothing more can be framed on this
            # connection, so it is closed rather than left to send a corrupt stream
            self.close()
            if isinstance(e, OSError):
                raise ConnectionClosed("sending a %d-byte frame failed (%s): connection closed"
                                       % (len(frame), e)) from e
            raise
        self._pending.setdefault(request_id, [])
        return request_id

    def _raise_why_closed(self, cause: BaseException) -> None:
        """The daemon closed the connection under a send: raises the DeformdError of the
        ERROR event it sent before closing (e.g. refused at max_clients, a timeout), else
        ConnectionClosed."""
        try:
            while self._read_more(time.monotonic()):
                pass
        except ConnectionClosed:
            pass
        for f in self._frames:
            if f.is_error and f.type == m.ERROR and f.request_id == 0:
                code, msg = m.decode_error(f.payload)
                raise DeformdError(code, error_name(code), msg) from cause
        raise ConnectionClosed("deformd closed the connection") from cause

    def _keep_reply(self, f: fr.Frame) -> None:
        """Files a reply frame of a request nobody is waiting for yet (dropped if unknown)."""
        parts = self._pending.get(f.request_id)
        if parts is None:
            return
        parts.append(f)
        if f.is_error or not f.more:
            self._done[f.request_id] = self._pending.pop(f.request_id)

    def _read_more(self, deadline: Optional[float]) -> bool:
        """Reads from the socket into the frame queue. False on timeout. The socket's timeout
        is back at self.timeout on return, on every path (a deadline in the past makes the read
        non-blocking, and a later sendall must not inherit that)."""
        if deadline is not None:
            # past the deadline: one non-blocking read still collects what already arrived
            self.sock.settimeout(max(0.0, deadline - time.monotonic()))
        else:
            self.sock.settimeout(None)
        try:
            data = self.sock.recv(RECV_BYTES)
        except (socket.timeout, BlockingIOError, ssl.SSLWantReadError):
            return False
        except ConnectionResetError as e:
            raise ConnectionClosed("connection reset by deformd") from e
        finally:
            self.sock.settimeout(self.timeout)
        if not data:
            raise ConnectionClosed("deformd closed the connection")
        self._frames.extend(self._decoder.feed(data))
        return True

    def recv_frame(self, timeout: Optional[float] = None) -> Optional[fr.Frame]:
        """Next raw frame (None on timeout). Bypasses reply matching and event assembly; an
        SHM_REF comes as it is (shm_frame() reads the frame it references)."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while not self._frames:
            if not self._read_more(deadline):
                return None
        return self._frames.popleft()

    # ------------------------------------------------------------------ events
    def _take_event_frame(self, f: fr.Frame, wire: int = 0) -> None:
        """Assembles stream chunks; completed events go to the event queue (a version's Disp /
        QDisp has .wire_bytes: the bytes its frames took on the wire, `wire` for a frame that
        came inside a ZFRAME). An SHM_REF is
        replaced by the frame it references in the shared-memory ring (or a ShmLost event).
        A WORK_PROGRESS event goes to its request's progress callback (else to the queue)."""
        if f.type == m.WORK_PROGRESS and f.is_event:
            w = pg.decode_work_progress(f.payload, f.request_id)
            cb = self._work_cbs.get(f.request_id)
            if cb is None:
                self._events.append(w)
            else:
                cb(w)
            return
        if f.type == m.SHM_REF:
            sid, position, length = m.decode_shm_ref(f.payload)
            inner = self._resolve_ref(sid, position, length)
            if inner is None:
                self._shm_lost(sid, position, length)
            else:
                self._take_event_frame(inner)
            return
        if f.type in (m.BRUSH_STATE, m.BRUSH_CURSOR):
            self._events.append(bs.decode_brush_state(f.payload) if f.type == m.BRUSH_STATE
                                else bs.decode_brush_cursor(f.payload))
            return
        if f.type == m.SESSION_CLOSED:
            sid = m.decode_session_ref(f.payload)
            self._drop_shm(sid)
            self._events.append(SessionClosed(sid))
            return
        if f.type == m.DEVICE_STATE:    # devices (HID): a DeviceInfo event
            self._events.append(dv.decode_device_info(f.payload))
            return
        wire = wire or fr.HEADER_SIZE + len(f.payload)
        if f.type == m.ZFRAME:      # a compressed stream event (hello stream_encoding ZSTD)
            self._take_event_frame(se.unwrap_zframe(f), wire)
            return
        if f.type == m.QDISP:       # a quantized version delta (hello stream_encoding QUANTIZED)
            q = se.decode_qdisp(f.payload)
            key = (f.type, q.session_id, q.version)
            chunks = self._partial.setdefault(key, [])
            chunks.append(q)
            self._wire[key] = self._wire.get(key, 0) + wire
            if not f.more:
                del self._partial[key]
                ev = se.join_qdisp(chunks)
                ev.wire_bytes = self._wire.pop(key)
                self._events.append(ev)
            return
        if f.type == m.DISPLACEMENT:
            d = st.decode_disp(f.payload)
            key = (f.type, d.session_id, d.version)
            if self._orphan_chunk(key, d.offset):
                return
            chunks = self._partial.setdefault(key, [])
            chunks.append(d)
            self._wire[key] = self._wire.get(key, 0) + wire
            if not f.more:
                del self._partial[key]
                ev = st.join_disp(chunks)
                ev.wire_bytes = self._wire.pop(key, 0)
                self._events.append(ev)
            return
        if f.type == m.PROGRESS:
            p = st.decode_progress(f.payload)
            key = (f.type, p.disp.session_id, p.disp.version)
            if self._orphan_chunk(key, p.disp.offset):
                return
            chunks = self._partial.setdefault(key, [])
            chunks.append(p)
            self._wire[key] = self._wire.get(key, 0) + wire
            if not f.more:
                del self._partial[key]
                p0 = chunks[0]
                p0.disp = st.join_disp([c.disp for c in chunks])
                p0.disp.wire_bytes = self._wire.pop(key, 0)
                self._events.append(p0)
            return
        if f.is_error:
            code, msg = m.decode_error(f.payload)
            raise DeformdError(code, error_name(code), msg)
        raise ProtocolError("unexpected event type 0x%x" % f.type)

    def shm_frame(self, f: fr.Frame) -> Optional[fr.Frame]:
        """The event frame an SHM_REF frame `f` references, read from the session's ring, or
        None when it was overwritten before it could be read (lost: resync with snapshot()).
        ProtocolError for a malformed reference, a reference outside the ring, a session
        without a ring (stream_shm not called) or a referenced frame that is not an event."""
        return self._resolve_ref(*m.decode_shm_ref(f.payload))

    def _resolve_ref(self, sid: int, position: int, length: int) -> Optional[fr.Frame]:
        """shm_frame for an already decoded reference."""
        ring = self._shm.get(sid)
        if ring is None:
            if sid in self._shm_detaching:
                return None
            raise ProtocolError("SHM_REF for session %d, which has no shared-memory stream"
                                % sid)
        inner = ring.read(position, length)
        if inner is not None and (not inner.is_event or inner.type == m.SHM_REF):
            raise ProtocolError("shm ring frame at %d is type 0x%x flags 0x%x, not an event"
                                % (position, inner.type, inner.flags))
        return inner

    def _shm_lost(self, sid: int, position: int, length: int) -> None:
        """A ring frame was overwritten: drops the session's partly assembled versions (their
        remaining chunks are dropped too, see _orphan_chunk) and queues a ShmLost event."""
        for key in [k for k in self._partial if k[1] == sid]:
            del self._partial[key]
        self._shm_gap.add(sid)
        self._events.append(ShmLost(sid, position, length))

    def _orphan_chunk(self, key: Tuple[int, int, int], offset: int) -> bool:
        """True for a continuation chunk of a version whose earlier chunk was lost from the
        shared-memory ring (dropped: a ShmLost event was queued instead)."""
        sid = key[1]
        if sid not in self._shm_gap or key in self._partial:
            return False
        if offset == 0:                 # a version starts: the gap is over
            self._shm_gap.discard(sid)
            return False
        return True

    def _drop_shm(self, session_id: int) -> None:
        ring = self._shm.pop(session_id, None)
        if ring is not None:
            ring.close()
        self._shm_gap.discard(session_id)

    def shm_ring(self, session_id: int) -> Optional[ShmRing]:
        """The session's mapped shared-memory ring (stream_shm), None when there is none."""
        return self._shm.get(session_id)

    def events(self, timeout: float = 1.0, max_events: Optional[int] = None) -> Iterator[Event]:
        """Yields queued and arriving events (Disp, Progress, SessionClosed, ShmLost, BrushState,
        BrushCursor: tell them apart by kind_name) until none
        arrives for `timeout` seconds (or max_events were yielded). Frames of a shared-memory
        stream (stream_shm) come as if they had arrived on the socket. Replies arriving
        meanwhile are kept for wait_reply()."""
        n = 0
        while max_events is None or n < max_events:
            if self._events:
                n += 1
                yield self._events.popleft()
                continue
            f = self.recv_frame(timeout)
            if f is None:
                return
            if f.is_event or (f.type == m.ERROR and f.request_id == 0 and not f.is_reply):
                self._take_event_frame(f)
            else:
                self._keep_reply(f)

    def next_event(self, timeout: float = 1.0) -> Optional[Event]:
        """The next event, or None when none arrives within `timeout` seconds."""
        for ev in self.events(timeout, max_events=1):
            return ev
        return None

    def pending_events(self) -> int:
        return len(self._events)

    # ------------------------------------------------------------------ requests
    def wait_reply(self, rid: int, timeout: Optional[float] = None) -> List[fr.Frame]:
        """Frames of the reply to request `rid` (several when chunked with FLAG_MORE). Events
        arriving meanwhile are queued. Raises DeformdError on an error reply, TimeoutError,
        ConnectionClosed."""
        timeout = self.timeout if timeout is None else timeout
        deadline = time.monotonic() + timeout
        parts = self._done.pop(rid, None)
        if parts is None:
            parts = self._pending.pop(rid, [])
            while not parts or (parts[-1].more and not parts[-1].is_error):
                while not self._frames:
                    if not self._read_more(deadline):
                        self._pending[rid] = parts
                        raise TimeoutError("no reply to request %d within %.1f s"
                                           % (rid, timeout))
                f = self._frames.popleft()
                if f.is_event or (f.type == m.ERROR and f.request_id == 0 and not f.is_reply):
                    self._take_event_frame(f)
                elif f.request_id == rid:
                    parts.append(f)
                else:
                    self._keep_reply(f)
        if parts[-1].is_error:
            code, msg = m.decode_error(parts[-1].payload)
            raise DeformdError(code, error_name(code), msg)
        return parts

    def request(self, msg_type: int, payload: bytes = b"",
                timeout: Optional[float] = None) -> List[fr.Frame]:
        """Sends one request and waits for its reply. An EMOVED answer (cluster mode) moves the
        client to the session's owner (move_to) and sends the request there once more, when
        follow_moved is set (the default)."""
        try:
            return self.wait_reply(self.send(msg_type, payload), timeout)
        except DeformdError as e:
            addr = moved_address(e.message) if e.code == EMOVED and self.follow_moved else None
            if addr is None:
                raise
            self.move_to(*addr)
            return self.wait_reply(self.send(msg_type, payload), timeout)

    def _one(self, msg_type: int, payload: bytes = b"") -> bytes:
        parts = self.request(msg_type, payload)
        return b"".join(p.payload for p in parts)

    def _request_progress(self, msg_type: int, payload: bytes,
                          progress: Optional["ProgressFn"]) -> bytes:
        """send + _wait_with_progress, following an EMOVED redirect once as request() does."""
        try:
            return self._wait_with_progress(self.send(msg_type, payload), progress)
        except DeformdError as e:
            addr = moved_address(e.message) if e.code == EMOVED and self.follow_moved else None
            if addr is None:
                raise
            self.move_to(*addr)
            return self._wait_with_progress(self.send(msg_type, payload), progress)

    def _wait_with_progress(self, rid: int, progress: Optional["ProgressFn"],
                            timeout: Optional[float] = None) -> bytes:
        """wait_reply(rid) with `progress` receiving that request's WORK_PROGRESS events."""
        if progress is not None:
            self._work_cbs[rid] = progress
        try:
            return b"".join(p.payload for p in self.wait_reply(rid, timeout))
        finally:
            self._work_cbs.pop(rid, None)

    # ------------------------------------------------------------------ handshake
    def hello(self, name: str = "deformd-python", encoding: Optional[int] = None,
              error: float = 0.0) -> m.HelloReply:
        """HELLO (asking for the cluster's owners trailer of LIST_SESSIONS). `encoding`
        (StreamEnc bits, m.STREAM_ENCODINGS) and `error` (the absolute error bound of QUANTIZED,
        mesh units) ask for a stream encoding (PROTOCOL.md 4.2); None sends the original hello
        (exact float32 stream). A bad request is refused by the daemon (DeformdError EINVAL)."""
        body = m.encode_hello(1, fr.PROTO_VERSION, schema.HELLO_WANT_OWNERS, name, encoding,
                              error)
        self.server = m.decode_hello_reply(self._one(m.HELLO, body))
        return self.server

    def auth(self, method: int, token: bytes) -> Tuple[int, bytes]:
        """One AUTH request; returns the reply's (method, token)."""
        return m.decode_auth(self._one(m.AUTH, m.encode_auth(method, token)))

    def authenticate(self, key: bytes) -> None:
        """The HMAC-SHA256 exchange (PROTOCOL.md 4.3) with `key`: raises DeformdError when the
        server refuses it (EPROTO_AUTH: wrong key; ELIMIT: too many failures) and
        auth.AuthError when the server fails to prove that it knows the key."""
        nc = secrets.token_bytes(schema.AUTH_NONCE_BYTES)
        method, ns = self.auth(schema.AuthMethod.HMAC_CHALLENGE, nc)
        if method != schema.AuthMethod.HMAC_CHALLENGE or len(ns) != schema.AUTH_NONCE_BYTES:
            raise auth.AuthError("auth: unexpected challenge reply (method %d, %d bytes)"
                                 % (method, len(ns)))
        method, proof = self.auth(schema.AuthMethod.HMAC_PROOF, auth.mac(key, ns, nc, "client"))
        if method != schema.AuthMethod.HMAC_PROOF or \
                not auth.verify(auth.mac(key, ns, nc, "server"), proof):
            self.close()
            raise auth.AuthError("auth: the server did not prove that it knows the key "
                                 "(connection closed)")
        self.authenticated = True
        self._key = key      # a cluster redirect (move_to) authenticates with it again

    def ping(self, data: bytes = b"") -> bytes:
        """Echo; returns the bytes the daemon sent back."""
        return self._one(m.PING, bytes(data))

    # ------------------------------------------------------------------ sessions
    def load_mesh(self, data: Optional[bytes] = None, path: Optional[str] = None,
                  fmt: Union[int, str] = m.FMT_AUTO, name: str = "",
                  ele: Optional[bytes] = None, file_name: str = "",
                  two_d: bool = False, progress: Optional["ProgressFn"] = None) -> m.SessionInfo:
        """Creates a session from inline file bytes (`data`; for TetGen pass the .node bytes as
        data and the .ele bytes as ele) or from a server-side `path`. fmt: a FMT_* value or a
        file extension (".obj"). file_name (uploads): the user's file name, which the daemon's
        errors name and, without `name`, the session is named after ("spot", "spot-2", ...).
        two_d: a 2D session even if the file gives z (every z must be 0); otherwise the session
        is 2D only when the file declares it (OBJ `v x y`, ...).
        The returned SessionInfo carries the reader's LoadReport in .report (dropped,
        duplicate, degenerate and inverted elements, non-manifold edges, unused vertices).
        progress: a callback for the upload and parse stages (see the module doc)."""
        if isinstance(fmt, str):
            fmt = m.FORMAT_BY_EXT[fmt.lower()]
        opts = m.LOAD_OPT_EXT | (m.LOAD_OPT_2D if two_d else 0) | \
            (m.LOAD_OPT_PROGRESS if progress is not None else 0)
        if path is not None:
            rid = self.send(m.LOAD_MESH, m.encode_load_mesh(m.LOAD_PATH, fmt, name, path, 0, 0, 0,
                                                            b"", opts))
            return m.decode_load_reply(self._wait_with_progress(rid, progress))
        if data is None:
            raise ValueError("load_mesh needs data or path")
        part2 = 0
        if ele is not None:
            part2 = len(data)
            data = bytes(data) + bytes(ele)
            fmt = m.FMT_TETGEN
        total = len(data)
        rid = self._next_id
        self._next_id += 1
        if progress is not None:    # upload progress arrives between the chunks' sends
            self._work_cbs[rid] = progress
        off = 0
        while True:
            chunk = data[off:off + m.LOAD_CHUNK_BYTES]
            last = off + len(chunk) >= total
            self.send(m.LOAD_MESH, m.encode_load_mesh(m.LOAD_INLINE, fmt, name, "", total, part2,
                                                      off, chunk, opts, file_name),
                      0 if last else fr.FLAG_MORE, rid)
            off += len(chunk)
            if last:
                break
        return m.decode_load_reply(self._wait_with_progress(rid, progress))

    def load_file(self, filename: str, name: str = "", two_d: bool = False,
                  progress: Optional["ProgressFn"] = None) -> m.SessionInfo:
        """Reads a local mesh file and uploads it inline (X.node brings X.ele along, X.NODE
        brings X.ELE: the case of the extension is kept). The daemon's errors name the file and,
        without `name`, the session is named after it. Raises ValueError for an extension that
        names no mesh format. two_d and progress as in load_mesh."""
        stem, ext = os.path.splitext(filename)
        base = os.path.basename(filename)
        if ext.lower() in (".node", ".ele"):
            upper = ext[1:].isupper()
            node = stem + (".NODE" if upper else ".node")
            other = stem + (".ELE" if upper else ".ele")
            with open(node, "rb") as f:
                data = f.read()
            with open(other, "rb") as f:
                return self.load_mesh(data, ele=f.read(), name=name, file_name=base,
                                      two_d=two_d, progress=progress)
        if ext.lower() not in m.FORMAT_BY_EXT:
            raise ValueError("%s: mesh format not recognised from the file name; formats: .obj, "
                             ".off, .ply, .mesh (MEDIT), .node + .ele (TetGen)" % filename)
        with open(filename, "rb") as f:
            data = f.read()
        return self.load_mesh(data, fmt=m.FORMAT_BY_EXT[ext.lower()], name=name, file_name=base,
                              two_d=two_d, progress=progress)

    def list_sessions(self) -> List[m.SessionInfo]:
        return m.decode_session_list(self._one(m.LIST_SESSIONS))

    def open_session(self, session_id: int = 0, name: str = "") -> m.SessionInfo:
        return m.decode_session_info(self._one(m.OPEN_SESSION,
                                               m.encode_open_session(session_id, name)))

    def close_session(self, session_id: int) -> m.Ack:
        return m.decode_ack(self._one(m.CLOSE_SESSION, m.encode_session_ref(session_id)))

    def subscribe(self, session_id: int, snapshot: bool = False,
                  from_version: Optional[int] = None) -> m.SessionInfo:
        """Subscribes to the displacement stream; with snapshot=True a dense snapshot event of
        the current version comes first. With from_version=V (the version whose displacements
        the caller holds, e.g. a MeshState's .version after a reconnect; PROTOCOL.md 6.2) the
        events that come first bring it to the returned SessionInfo.version: the versions
        V+1 .. that version exactly as they were broadcast (none when V is current), or, when
        the daemon no longer keeps them or V is ahead of the session, one dense snapshot of
        that version (kind CHANGE_SNAPSHOT). MeshState.apply takes either."""
        if from_version is not None and snapshot:
            raise ValueError("subscribe: snapshot and from_version are exclusive")
        body = (m.encode_subscribe(session_id, m.SUBSCRIBE_FROM_VERSION, from_version)
                if from_version is not None else
                m.encode_subscribe(session_id, m.SUBSCRIBE_SNAPSHOT if snapshot else 0))
        return m.decode_session_info(self._one(m.SUBSCRIBE, body))

    def unsubscribe(self, session_id: int) -> m.Ack:
        """Leaves the session's stream; this also ends its shared-memory stream, whose mapping
        is closed once the reply arrived (references queued before it are still read)."""
        try:
            return m.decode_ack(self._one(m.UNSUBSCRIBE, m.encode_session_ref(session_id)))
        finally:
            self._drop_shm(session_id)

    def stream_shm(self, session_id: int) -> m.ShmInfo:
        """Moves the subscribed session's stream frames of [min_frame, max_frame] bytes to the
        daemon's shared-memory ring (PROTOCOL.md 6.1; Unix socket on the daemon's host only):
        maps the ring file read-only and from then on resolves each SHM_REF event to the frame
        it references, so events() and MeshState work unchanged. A frame overwritten before it
        was read (a slow reader) becomes a ShmLost event: resync with snapshot(). The mapping
        lasts until unsubscribe(), SESSION_CLOSED or close(); calling again is a no-op.

        DeformdError from the daemon: ESTATE (not subscribed), ENOTFOUND, EUNSUPPORTED (TCP, or
        disabled: hello feature FEAT_SHM_STREAM clear), EIO. When the ring cannot be mapped
        (OSError, e.g. a daemon of another user; ProtocolError for a bad header) the connection
        is unsubscribed from the session before the error is raised, since the daemon would
        otherwise keep sending references this client cannot read: subscribe() again to use the
        socket stream."""
        info = m.decode_shm_info(self._one(m.STREAM_SHM, m.encode_session_ref(session_id)))
        old = self._shm.get(session_id)
        if old is not None and (old.info.path, old.info.capacity) == (info.path, info.capacity):
            old.info = info
            return info
        self._drop_shm(session_id)
        try:
            if info.session_id != session_id:
                raise ProtocolError("shm_info for session %d, asked for %d"
                                    % (info.session_id, session_id))
            self._shm[session_id] = ShmRing(info)
        except (OSError, ValueError):   # ValueError: ProtocolError, or mmap refusing the file
            self._shm_detaching.add(session_id)
            try:
                self.unsubscribe(session_id)
            except DeformdError:
                pass
            finally:
                self._shm_detaching.discard(session_id)
            raise
        return info

    # ------------------------------------------------------------------ reads
    def get_mesh(self, session_id: int, rest: bool = False, base: bool = False) -> MeshData:
        flags = (m.GET_MESH_REST if rest else 0) | (m.GET_MESH_BASE if base else 0)
        parts = self.request(m.GET_MESH, m.encode_get_mesh(session_id, flags))
        return st.assemble_mesh([st.decode_mesh_chunk(p.payload) for p in parts], MeshData)

    def snapshot(self, session_id: int, version: int = 0) -> st.Disp:
        """Dense displacements of `version` (0: current) for a resync."""
        parts = self.request(m.SNAPSHOT, m.encode_snapshot_req(session_id, version))
        return st.join_disp([st.decode_disp(p.payload) for p in parts])

    def stats(self, session_id: int = 0) -> Dict[str, float]:
        """Daemon-wide (0) or one session's counters, key -> value."""
        return m.decode_stats(self._one(m.STATS, m.encode_stats_req(session_id)))
