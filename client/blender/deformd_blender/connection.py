"""Connection state of the add-on (one daemon connection per Blender process, main thread only):
the Client, the address, the sessions mirrored onto objects, the last error and counters the
panel shows. Blender properties cannot hold sockets, so this lives in a module-level object.

parse_address(text) -> ("unix", path) | ("tcp", (host, port)); errors are ValueError with a
message for self.report. describe(exc) turns any client or socket error into one line."""
import socket
import time
from typing import Dict, Optional

from .dc import Client, ConnectionClosed, DeformdError, ProtocolError

CLIENT_NAME = "blender"
TIMEOUT_S = 10.0


def parse_address(text: str):
    """`unix:PATH` (or a path starting with /) or `HOST:PORT`. ValueError otherwise."""
    text = (text or "").strip()
    if text.startswith("unix:"):
        path = text[5:]
        if not path:
            raise ValueError("address 'unix:' names no socket path")
        return "unix", path
    if text.startswith("/"):
        return "unix", text
    host, sep, port = text.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ValueError("address %r is neither unix:PATH nor HOST:PORT" % text)
    return "tcp", (host.strip("[]"), int(port))


def describe(exc: BaseException) -> str:
    """One line for a report: the daemon's error code and message, or the socket error."""
    if isinstance(exc, DeformdError):
        return "deformd: %s: %s" % (exc.name, exc.message)
    if isinstance(exc, ConnectionClosed):
        return "deformd: connection lost (%s)" % exc
    if isinstance(exc, (ProtocolError, ValueError)):
        return "deformd: %s" % exc
    if isinstance(exc, (socket.timeout, TimeoutError)):
        return "deformd: timed out (%s)" % exc
    if isinstance(exc, OSError):
        return "deformd: %s" % (exc.strerror or exc)
    return "deformd: %s: %s" % (type(exc).__name__, exc)


CLIENT_ERRORS = (DeformdError, ConnectionClosed, ProtocolError, OSError, ValueError,
                 TimeoutError)


class State:
    """Everything about the live connection; reset by disconnect()."""

    def __init__(self) -> None:
        self.client: Optional[Client] = None
        self.address = ""
        self.status = "disconnected"
        self.last_error = ""
        self.mirrors: Dict[int, object] = {}   # session id -> sync.Mirror
        self.held: Dict[int, object] = {}      # mirrors kept over a disconnect (for resume)
        self.held_address = ""                 # the daemon they came from
        self.current_sid = 0                   # the session the panel's brush belongs to
        self.sessions = []                     # last LIST_SESSIONS (SessionInfo items)
        self.subscribers = 0                   # of current_sid, from the last listing
        self.last_changer = ""                 # origin name of the last brush-state change
        self.applying_remote = False           # panel props being set from an event
        self.brush_shown = (0, 0)              # (session, seq) of the brush state in the panel
        self.brush_states_shown = 0            # brush states (events, replies) put in the panel
        self.ticks = 0                         # timer polls run
        self.versions_applied = 0
        self.resyncs = 0                       # snapshots taken after a gap
        self.resumed_replay = 0                # reconnects resynced by SUBSCRIBE from_version
        self.resumed_snapshot = 0              # ... for which the daemon sent a snapshot
        self.mesh_writes = 0
        self.rate_hz = 0.0                     # mesh updates per second (smoothed)
        self.last_apply_ms = 0.0
        self.last_write_t = 0.0                # perf_counter of the last mesh write
        self.last_list_t = 0.0
        self.list_rid = 0                      # LIST_SESSIONS in flight (the timer's)
        self.peers = []                        # SESSION_PEERS rows of peers_sid (peers.py)
        self.peers_sid = 0                     # the session `peers` belongs to
        self.peers_rid = 0                     # SESSION_PEERS in flight (the timer's)
        self.peers_rid_sid = 0                 # ... for this session
        self.last_peers_t = 0.0                # when the last one was sent / answered
        self.peers_subs = -1                   # `subscribers` when the last one was sent
        self.stroke_active = False             # the modal operator holds a stroke

    @property
    def connected(self) -> bool:
        return self.client is not None

    def connect(self, address: str, key_file: str = "", tls_ca: str = "") -> None:
        """Opens the connection (HELLO, AUTH with key_file when given; TCP over TLS verified
        against tls_ca when given). Raises CLIENT_ERRORS (ssl errors are OSErrors)."""
        self.disconnect()
        kind, where = parse_address(address)
        key = key_file or None
        try:
            if kind == "unix":
                c = Client.connect_unix(where, timeout=TIMEOUT_S, name=CLIENT_NAME, key_file=key)
            else:
                c = Client.connect_tcp(where[0], where[1], timeout=TIMEOUT_S, name=CLIENT_NAME,
                                       key_file=key, tls_ca=tls_ca or None)
        except DeformdError:
            raise
        except OSError as e:     # no daemon there (or TLS refused): say where we looked
            raise ValueError("cannot reach deformd at %s: %s" % (address, e.strerror or e))
        self.client = c
        self.address = address
        self.status = "connected to %s" % address
        self.last_error = ""

    def disconnect(self, why: str = "") -> None:
        """Closes the socket; objects keep the positions they were last synced to."""
        if self.client is not None:
            try:
                self.client.close()
            except OSError:
                pass
        self.client = None
        if self.mirrors:                       # the replicas the objects show, for resume
            if self.held_address != self.address:
                self.held.clear()
            self.held.update(self.mirrors)
            self.held_address = self.address
        self.mirrors.clear()
        self.stroke_active = False
        self.list_rid = 0
        self.peers, self.peers_sid, self.peers_rid, self.peers_rid_sid = [], 0, 0, 0
        self.last_peers_t, self.peers_subs = 0.0, -1
        self.status = "disconnected" + (": " + why if why else "")
        if why:
            self.last_error = why

    def lost(self, exc: BaseException) -> str:
        """The connection failed under a call: closes it, returns the report text."""
        msg = describe(exc)
        if isinstance(exc, (ConnectionClosed, OSError, ProtocolError)) and \
                not isinstance(exc, DeformdError):
            self.disconnect(msg)
        else:
            self.last_error = msg
        return msg

    def rate_now(self) -> float:
        """The smoothed write rate, 0 once no write came for a second."""
        return self.rate_hz if now() - self.last_write_t < 1.0 else 0.0

    def note_rate(self, dt_s: float) -> None:
        if dt_s > 0:
            inst = 1.0 / dt_s
            self.rate_hz = inst if self.rate_hz == 0 else 0.8 * self.rate_hz + 0.2 * inst


STATE = State()


def now() -> float:
    return time.perf_counter()
