"""Session peer bodies of the deformd protocol (PROTOCOL.md 4.38, proto/msg_peers.c): the
SESSION_PEERS reply, peer_list, one peer_info row per connection subscribed to the session.
Decoders take one whole payload and raise ProtocolError on a short, long or inconsistent body."""
import struct
from dataclasses import dataclass
from typing import List, Sequence

from . import schema
from .schema import PeerFlag, Transport
from .wire import ProtocolError, Reader, pack_str

PEER_INFO_FIXED = "QBBH"     # client_id, flags, transport, reserved; then name, principal
TRANSPORT_NAMES = {Transport.UNIX: "unix", Transport.TCP: "tcp"}


@dataclass
class Peer:
    """One connection subscribed to a session (SESSION_PEERS row)."""
    client_id: int           # the daemon's connection id
    flags: int               # PeerFlag bits
    transport: int           # Transport
    name: str                # the client_name of its HELLO ("" when none)
    principal: str           # who it acts as: "uid:1000", "key:NAME", "admin", "tcp"

    @property
    def is_self(self) -> bool:
        """This row is the connection that asked."""
        return bool(self.flags & PeerFlag.SELF)

    @property
    def can_edit(self) -> bool:
        """Its principal holds the edit right on the session."""
        return bool(self.flags & PeerFlag.EDIT)

    @property
    def shm(self) -> bool:
        """It reads the shared-memory stream."""
        return bool(self.flags & PeerFlag.SHM)

    @property
    def transport_name(self) -> str:
        return TRANSPORT_NAMES[Transport(self.transport)]

    @property
    def label(self) -> str:
        """What to show for it: its HELLO name, else its principal, else its id."""
        return self.name or self.principal or "client %d" % self.client_id


def _read_peer(r: Reader) -> Peer:
    cid, flags, transport, reserved = r.take(PEER_INFO_FIXED)
    name, principal = r.str(), r.str()
    if cid == 0:
        raise ProtocolError("peer_info: client_id 0 is not a connection")
    if flags & ~int(sum(PeerFlag)):
        raise ProtocolError("peer_info: unknown flag bits 0x%x" % (flags & ~int(sum(PeerFlag))))
    if transport not in TRANSPORT_NAMES:
        raise ProtocolError("peer_info: transport %d (1 unix, 2 tcp)" % transport)
    if reserved:
        raise ProtocolError("peer_info: reserved %d is not 0" % reserved)
    size = lambda t: len(t.encode("utf-8", "surrogateescape"))  # noqa: E731 (wire bytes)
    if size(name) > schema.MAX_NAME_LEN or size(principal) > schema.MAX_NAME_LEN:
        raise ProtocolError("peer_info: a string exceeds its limit")
    return Peer(cid, flags, transport, name, principal)


def decode_peer_list(p: bytes) -> List[Peer]:
    r = Reader(p, "peer_list")
    n = r.take("I")
    if n > schema.MAX_PEERS:
        raise ProtocolError("peer_list: %d peers exceed limit %d" % (n, schema.MAX_PEERS))
    out = [_read_peer(r) for _ in range(n)]
    r.end()
    return out


def encode_peer(x: Peer) -> bytes:
    return struct.pack("<" + PEER_INFO_FIXED, x.client_id, x.flags, x.transport, 0) + \
        pack_str(x.name) + pack_str(x.principal)


def encode_peer_list(items: Sequence[Peer]) -> bytes:
    return struct.pack("<I", len(items)) + b"".join(encode_peer(x) for x in items)


__all__ = ["Peer", "TRANSPORT_NAMES", "decode_peer_list", "encode_peer", "encode_peer_list"]
