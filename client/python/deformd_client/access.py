"""Per-session access bodies of the deformd protocol (PROTOCOL.md 4.34..4.36, proto/msg_access.c):
session_access (SESSION_ACCESS request: read or change a session's policy), join (JOIN request:
become a member with the session's join key) and access_info (their reply). Encoders return
payload bytes; decoders take one whole payload and raise ProtocolError on a short, long or
inconsistent body."""
import struct
from dataclasses import dataclass
from typing import Optional

from . import schema
from .schema import AccessFlag, AccessMode
from .wire import ProtocolError, Reader, pack_str

MODE_NAMES = {AccessMode.OPEN: "open", AccessMode.KEY: "key", AccessMode.OWNER: "owner"}
MODES = {v: k for k, v in MODE_NAMES.items()}
OBSERVERS = {None: 0, False: 1, True: 2}     # session_access observers: keep, off, on


@dataclass
class SessionAccess:
    """A SESSION_ACCESS request: mode 0 / observers 0 / flags 0 keep (all 0: read)."""
    session_id: int
    mode: int = 0            # 0 keep, else AccessMode
    observers: int = 0       # 0 keep, 1 off, 2 on
    flags: int = 0           # AccessFlag (NEW_KEY)


@dataclass
class AccessInfo:
    """A session's access policy (SESSION_ACCESS / JOIN reply)."""
    session_id: int
    mode: int                # AccessMode
    observers: int           # 0/1
    members: int             # principals that joined
    owner: str               # the owner's principal, "" when none is recorded
    key: Optional[bytes] = None  # a new join key (NEW_KEY, sent to the owner only)

    @property
    def mode_name(self) -> str:
        return MODE_NAMES[AccessMode(self.mode)]


def encode_session_access(session_id: int, mode: int = 0, observers: int = 0,
                          flags: int = 0) -> bytes:
    return struct.pack("<QBBBB", session_id, mode, observers, flags, 0)


def decode_session_access(p: bytes) -> SessionAccess:
    r = Reader(p, "session_access")
    sid, mode, obs, flags, reserved = r.take("QBBBB")
    r.end()
    if sid == 0:
        raise ProtocolError("session_access: session_id 0 is not a session")
    if mode > max(AccessMode) or obs > 2 or flags & ~int(sum(AccessFlag)) or reserved:
        raise ProtocolError("session_access: bad mode, observers, flags or reserved")
    return SessionAccess(sid, mode, obs, flags)


def encode_join(session_id: int, key: bytes) -> bytes:
    if len(key) != schema.JOIN_KEY_BYTES:
        raise ValueError("join: the key has %d bytes, need %d (64 hex digits)"
                         % (len(key), schema.JOIN_KEY_BYTES))
    return struct.pack("<Q", session_id) + bytes(key)


def decode_join(p: bytes):
    r = Reader(p, "join")
    sid = r.take("Q")
    key = r.raw(schema.JOIN_KEY_BYTES)
    r.end()
    if sid == 0:
        raise ProtocolError("join: session_id 0 is not a session")
    return sid, key


def decode_access_info(p: bytes) -> AccessInfo:
    r = Reader(p, "access_info")
    sid, mode, obs, reserved, members = r.take("QBBHI")
    owner = r.str()
    key_len = r.take("H")
    if key_len not in (0, schema.JOIN_KEY_BYTES):
        raise ProtocolError("access_info: key_len %d (0 or %d)" % (key_len,
                                                                 schema.JOIN_KEY_BYTES))
    key = r.raw(key_len) if key_len else None
    r.end()
    if sid == 0 or mode not in MODE_NAMES or obs > 1 or reserved:
        raise ProtocolError("access_info: bad session_id, mode, observers or reserved")
    if len(owner.encode("utf-8", "surrogateescape")) > schema.MAX_NAME_LEN:
        raise ProtocolError("access_info: owner exceeds its limit")
    return AccessInfo(sid, mode, obs, members, owner, key)


def encode_access_info(a: AccessInfo) -> bytes:
    key = a.key or b""
    return struct.pack("<QBBHI", a.session_id, a.mode, a.observers, 0, a.members) + \
        pack_str(a.owner) + struct.pack("<H", len(key)) + key


__all__ = ["SessionAccess", "AccessInfo", "MODE_NAMES", "MODES", "OBSERVERS",
           "encode_session_access", "decode_session_access", "encode_join", "decode_join",
           "encode_access_info", "decode_access_info"]
