"""Non-blocking reads for event loops that must never wait on the daemon (a GUI timer, the
Blender add-on's 60 Hz poll): a mixin of Client.

    rid = c.send(MsgType.BRUSH_UPDATE, payload)      # one request in flight
    ...                                                # each tick of the host's loop:
    for ev in c.poll():                                # whatever has arrived, never blocking
        ...
    parts = c.poll_reply(rid)                          # None until the reply is complete

Both read only what the socket already holds (a zero timeout), file replies for wait_reply /
poll_reply and assemble events exactly like events(); the socket is back to blocking with the
client's timeout when they return, on every path (Client._read_more restores it), so the next
request's sendall never meets a non-blocking socket.
"""
from typing import List, Optional

from . import frame as fr
from . import messages as m
from .errors import ConnectionClosed, DeformdError, error_name

RECV_BYTES = 1 << 20       # Client.RECV_BYTES: what one read takes at most
POLL_MAX_BYTES = 64 << 20   # per poll(): a daemon streaming faster than we read cannot pin us


class PollMixin:
    """poll / poll_reply / reply_ready for Client (uses its _read_more, _frames, _events,
    _pending, _done, _take_event_frame, _keep_reply)."""

    def _drain_now(self, max_bytes: int) -> None:
        """Reads what the socket holds now (at most about max_bytes) and sorts the frames:
        events to the event queue, replies to their requests; frames that arrived before the
        daemon closed the connection are sorted too. Raises ConnectionClosed when the daemon
        closed the connection, DeformdError for an unsolicited ERROR event (e.g. the daemon
        shutting down or a timeout), ProtocolError for a malformed frame."""
        reads = max(1, max_bytes // RECV_BYTES)
        try:
            for _ in range(reads):                 # each read takes at most RECV_BYTES
                if not self._read_more(0.0):       # deadline in the past: zero timeout
                    break
        finally:
            while self._frames:
                f = self._frames.popleft()
                if f.is_event or (f.type == m.ERROR and f.request_id == 0 and not f.is_reply):
                    self._take_event_frame(f)
                else:
                    self._keep_reply(f)

    def poll(self, max_bytes: int = POLL_MAX_BYTES) -> List:
        """Every event complete now (queued or arrived on the socket), oldest first, without
        blocking: [] when nothing has arrived. Replies that arrive meanwhile are kept for
        wait_reply() / poll_reply(). Errors: ConnectionClosed (raised once every event that
        arrived before the close was returned: a poll that finds the connection closed returns
        the queued events first, the next one raises), DeformdError (an unsolicited error
        event), ProtocolError. Main thread of the client only (one Client per thread)."""
        try:
            self._drain_now(max_bytes)
        except ConnectionClosed:
            if not self._events:
                raise
        out = list(self._events)
        self._events.clear()
        return out

    def reply_ready(self, rid: int) -> bool:
        """True when the whole reply to request `rid` has arrived (reads without blocking;
        events are queued for poll()/events())."""
        if rid not in self._done:
            self._drain_now(POLL_MAX_BYTES)
        return rid in self._done

    def poll_reply(self, rid: int) -> Optional[List[fr.Frame]]:
        """The frames of the reply to `rid` when it is complete, else None; never blocks.
        Raises DeformdError for an error reply (the request is then done). A request id that
        was never sent stays None forever."""
        if not self.reply_ready(rid):
            return None
        parts = self._done.pop(rid)
        if parts[-1].is_error:
            code, msg = m.decode_error(parts[-1].payload)
            raise DeformdError(code, error_name(code), msg)
        return parts
