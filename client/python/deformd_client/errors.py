"""Error codes of deformd (core/common/df_error.h, proto/wire_error.h) and the client's exceptions."""

from enum import IntEnum


class ErrorCode(IntEnum):
    """Wire error codes: core/common/df_error.h (-1 ..) and proto/wire_error.h (-100 ..);
    tests/integration/test_schema.py checks them against both headers and PROTOCOL.md 7."""
    OK = 0
    EINVAL = -1
    ENOMEM = -2
    ESINGULAR = -3
    EIO = -4
    EFORMAT = -5
    ELIMIT = -6
    ENOTFOUND = -7
    ESTATE = -8
    EUNSUPPORTED = -9
    EINTERNAL = -10
    EEXIST = -11
    EPERM = -12
    EMOVED = -13
    EPROTO_BADMAGIC = -100
    EPROTO_BADVERSION = -101
    EPROTO_BADTYPE = -102
    EPROTO_TOOLARGE = -103
    EPROTO_TRUNCATED = -104
    EPROTO_TRAILING = -105
    EPROTO_BADFLAGS = -106
    EPROTO_RESERVED = -107
    EPROTO_BUSY = -108
    EPROTO_AUTH = -109
    EPROTO_CHUNK = -110


globals().update(ErrorCode.__members__)   # the flat names: errors.EINVAL, errors.EPROTO_BUSY, ...
ERROR_NAMES = {int(c): c.name for c in ErrorCode}


def error_name(code: int) -> str:
    """Stable short name of a DF_E* code ("EINVAL"), "EUNKNOWN" for anything else."""
    return ERROR_NAMES.get(code, "EUNKNOWN")


class DeformdError(Exception):
    """An error reply from the daemon: code (negative DF_E*), its stable name and the message."""

    def __init__(self, code: int, name: str, message: str) -> None:
        super().__init__("%s (%d): %s" % (name, code, message))
        self.code = code
        self.name = name
        self.message = message


class ConnectionClosed(ConnectionError):
    """The daemon closed the connection (or it broke) before the expected reply arrived."""


def moved_address(message: str):
    """The owner's (host, port) of an EMOVED message "MOVED <session_id> <host:port>" (PROTOCOL.md
    7, cluster mode), or None when the message is not of that form."""
    parts = message.split()
    if len(parts) != 3 or parts[0] != "MOVED" or ":" not in parts[2]:
        return None
    host, _, port = parts[2].rpartition(":")
    try:
        p = int(port)
    except ValueError:
        return None
    if not host or not 0 < p < 65536:
        return None
    return host.strip("[]"), p
