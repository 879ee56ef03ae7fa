"""Who else is connected to the panel's session: SESSION_PEERS (PROTOCOL.md 4.38) polled from the
60 Hz timer without ever waiting on the socket. At most one request is in flight; a new one is
sent once a second (PEERS_EVERY_S), at once when the session shown changes or when the
subscriber count (SUBSCRIBE / LIST_SESSIONS session info) changes.
Its reply is collected by a later tick (poll_reply), so the UI never waits for more than the
non-blocking read the timer does anyway. The panel shows STATE.peers minus this connection's own
row (flag SELF)."""
from .connection import STATE
from .dc import DeformdError, MsgType, messages, peers as wire_peers

PEERS_EVERY_S = 1.0


def reset() -> None:
    """Forgets the list and any request in flight (disconnect, session closed)."""
    STATE.peers = []
    STATE.peers_sid = 0
    STATE.peers_rid = 0
    STATE.peers_rid_sid = 0
    STATE.last_peers_t = 0.0
    STATE.peers_subs = -1


def others():
    """The peers of the panel's session other than this connection, in subscription order."""
    if STATE.peers_sid != STATE.current_sid:
        return []
    return [p for p in STATE.peers if not p.is_self]


def _due(t: float) -> bool:
    if STATE.peers_sid != STATE.current_sid:
        return True                              # another session shown: list it now
    if STATE.subscribers != STATE.peers_subs:
        return True                              # someone came or went (session info says)
    return t - STATE.last_peers_t >= PEERS_EVERY_S


def poll(c, t: float) -> None:
    """One timer step: collects the reply in flight if it has arrived, else sends the next
    request when due. A refused request (the session closed, the observe right withdrawn)
    empties the list and shows the error; transport errors propagate to the caller (tick)."""
    if STATE.peers_rid:
        try:
            parts = c.poll_reply(STATE.peers_rid)
        except DeformdError as e:
            sid = STATE.peers_rid_sid
            STATE.peers_rid = 0
            STATE.peers, STATE.peers_sid = [], sid
            STATE.last_peers_t = t
            if sid in STATE.mirrors:             # else it was closed: its event said so
                STATE.last_error = "deformd: peers of session %d: %s: %s" % (sid, e.name,
                                                                               e.message)
            return
        if parts is None:
            return
        STATE.peers = wire_peers.decode_peer_list(b"".join(p.payload for p in parts))
        STATE.peers_sid = STATE.peers_rid_sid
        STATE.peers_rid = 0
        STATE.last_peers_t = t
        return
    sid = STATE.current_sid
    if not sid or sid not in STATE.mirrors:
        if STATE.peers:
            reset()
        return
    if _due(t):
        STATE.last_peers_t = t
        STATE.peers_subs = STATE.subscribers
        STATE.peers_rid_sid = sid
        STATE.peers_rid = c.send(MsgType.SESSION_PEERS, messages.encode_session_ref(sid))
