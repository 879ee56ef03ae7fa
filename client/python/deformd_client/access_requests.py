"""Per-session access, peers and HID device requests of the deformd Python client (PROTOCOL.md
4.30-4.38), as a mixin of Client."""
from typing import List, Optional, Sequence, Union

from . import access as ac
from . import devices as dv
from . import messages as m
from . import peers as pr
from . import schema


class AccessRequestsMixin:
    """Mixin of Client (client.py): needs its request(), _one(), send() and
    _request_progress() / _wait_with_progress()."""

    # ------------------------------------------------------------------ per-session access
    def session_access(self, session_id: int, mode: Optional[str] = None,
                       observers: Optional[bool] = None,
                       new_key: bool = False) -> ac.AccessInfo:
        """The session's access policy (PROTOCOL.md 4.34): with no change given, reads it (any
        principal that may observe); mode "open" / "key" / "owner", observers True / False or
        new_key=True change it (owner or admin only: EPERM otherwise). A new join key (new_key,
        or a switch to key mode without one) comes back in .key (32 bytes) to the owner only."""
        if mode is not None and mode not in ac.MODES:
            raise ValueError("mode %r: open, key or owner" % (mode,))
        payload = ac.encode_session_access(session_id, int(ac.MODES[mode]) if mode else 0,
                                           ac.OBSERVERS[observers],
                                           int(schema.AccessFlag.NEW_KEY) if new_key else 0)
        return ac.decode_access_info(self._one(m.SESSION_ACCESS, payload))

    def join(self, session_id: int, key: Union[bytes, str]) -> ac.AccessInfo:
        """Becomes a member of a key-mode session with its join key (32 bytes, or 64 hex
        digits); membership belongs to this connection's principal and outlasts it. A wrong key
        is EPERM (and rate-limited per peer: ELIMIT)."""
        raw = bytes.fromhex(key) if isinstance(key, str) else bytes(key)
        return ac.decode_access_info(self._one(m.JOIN, ac.encode_join(session_id, raw)))

    def session_peers(self, session_id: int) -> List[pr.Peer]:
        """Who is connected to the session (PROTOCOL.md 4.38): one Peer per connection
        subscribed to it, in subscription order: client_id, name (its HELLO client_name),
        principal, transport, flags (PeerFlag: SELF marks this connection's own row, EDIT a
        peer that may edit, SHM one on the shared-memory stream). Needs the observe right
        (DeformdError EPERM); ENOTFOUND for an unknown session."""
        return pr.decode_peer_list(self._one(m.SESSION_PEERS, m.encode_session_ref(session_id)))

    # ------------------------------------------------------------------ devices (HID)
    def devices_list(self) -> List[dv.DeviceInfo]:
        """The daemon's HID devices (open or not), in id order."""
        return dv.decode_device_list(self._one(m.DEVICES_LIST))

    def device_bind(self, device_id: int, session_id: int = 0) -> None:
        """Binds a device to a session (0: unbind, it follows the most recently active
        session). ENOTFOUND for an unknown device or session."""
        self._one(m.DEVICE_BIND, dv.encode_device_bind(device_id, session_id))

    def device_view(self, device_id: int, session_id: int, view_proj: Sequence[float],
                    viewport: Sequence[float]) -> None:
        """Publishes the view a pen is cast through: view_proj 16 floats (row-major, mesh space
        -> OpenGL clip space), viewport (x, y, width, height) in pixels, y down. Also binds the
        device to session_id."""
        self._one(m.DEVICE_VIEW, dv.encode_device_view(device_id, session_id, view_proj,
                                                         viewport))
