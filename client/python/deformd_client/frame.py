"""Frame codec of the deformd wire protocol (proto/frame.h, proto/PROTOCOL.md).

Every message is one frame: a 24-byte little-endian header followed by ``payload_len`` bytes.

    offset  type  field
       0    u32   magic        0x444D4644 (bytes b"DFMD")
       4    u16   version      PROTO_VERSION
       6    u16   type         message type (see messages.py)
       8    u16   flags        FLAG_* bits
      10    u16   reserved     must be 0
      12    u64   request_id   echoed by replies; 0 on plain events
      20    u32   payload_len  <= MAX_FRAME_PAYLOAD

Pure functions and a small incremental decoder; no I/O here.
"""
import struct
from typing import List, NamedTuple, Optional

from .schema import FRAME_HEADER_SIZE as HEADER_SIZE
from .schema import FRAME_MAGIC, MAX_FRAME_PAYLOAD, PROTO_VERSION, FrameFlag  # noqa: F401

FLAG_REPLY = FrameFlag.REPLY
FLAG_EVENT = FrameFlag.EVENT
FLAG_ERROR = FrameFlag.ERROR
FLAG_MORE = FrameFlag.MORE

_HEADER = struct.Struct("<IHHHHQI")
assert _HEADER.size == HEADER_SIZE


class FrameError(ValueError):
    """The byte stream does not follow the framing rules (bad magic, version, length)."""


class Frame(NamedTuple):
    type: int
    flags: int
    request_id: int
    payload: bytes            # bytes, or a bytearray for large payloads (no extra copy)
    version: int = PROTO_VERSION

    @property
    def is_reply(self) -> bool:
        return bool(self.flags & FLAG_REPLY)

    @property
    def is_event(self) -> bool:
        return bool(self.flags & FLAG_EVENT)

    @property
    def is_error(self) -> bool:
        return bool(self.flags & FLAG_ERROR)

    @property
    def more(self) -> bool:
        return bool(self.flags & FLAG_MORE)


def encode_header(msg_type: int, flags: int, request_id: int, payload_len: int,
                  magic: int = FRAME_MAGIC, version: int = PROTO_VERSION,
                  reserved: int = 0) -> bytes:
    """Returns the 24-byte header. magic/version/reserved are overridable so tests can forge
    malformed frames; payload_len is not checked here for the same reason."""
    return _HEADER.pack(magic, version, msg_type, flags, reserved, request_id, payload_len)


def encode_frame(msg_type: int, payload: bytes = b"", request_id: int = 0, flags: int = 0) -> bytes:
    """Returns header + payload. Raises FrameError when the payload exceeds MAX_FRAME_PAYLOAD."""
    if len(payload) > MAX_FRAME_PAYLOAD:
        raise FrameError("payload of %d bytes exceeds the %d-byte frame limit"
                         % (len(payload), MAX_FRAME_PAYLOAD))
    return encode_header(msg_type, flags, request_id, len(payload)) + bytes(payload)


def decode_header(buf: bytes):
    """Parses the first 24 bytes of buf. Returns (type, flags, request_id, payload_len, version).
    Raises FrameError on a short buffer, bad magic, unknown version, non-zero reserved or an
    oversized length."""
    if len(buf) < HEADER_SIZE:
        raise FrameError("header truncated: %d of %d bytes" % (len(buf), HEADER_SIZE))
    magic, version, mtype, flags, reserved, rid, plen = _HEADER.unpack_from(buf, 0)
    if magic != FRAME_MAGIC:
        raise FrameError("bad magic 0x%08x" % magic)
    if version != PROTO_VERSION:
        raise FrameError("unsupported protocol version %d" % version)
    if reserved != 0:
        raise FrameError("reserved header field is %d, must be 0" % reserved)
    if plen > MAX_FRAME_PAYLOAD:
        raise FrameError("payload length %d exceeds the %d-byte limit" % (plen, MAX_FRAME_PAYLOAD))
    return mtype, flags, rid, plen, version


class FrameDecoder:
    """Incremental decoder: feed() arbitrary byte slices, collect complete frames.

    Handles frames split across reads and several frames per read; a large payload is copied
    once, into a buffer of its final size. After a FrameError the decoder is poisoned (the
    stream cannot be resynchronised) and raises again on every feed."""

    def __init__(self) -> None:
        self._head = bytearray()          # bytes of the next header (and what follows it)
        self._hdr = None                  # parsed header of the frame being filled
        self._body: Optional[bytearray] = None
        self._fill = 0
        self._error: Optional[FrameError] = None

    def feed(self, data: bytes) -> List[Frame]:
        if self._error is not None:
            raise self._error
        out: List[Frame] = []
        view = memoryview(data)
        pos = 0
        while True:
            if self._hdr is None:
                take = min(HEADER_SIZE - len(self._head), len(view) - pos)
                self._head += view[pos:pos + take]
                pos += take
                if len(self._head) < HEADER_SIZE:
                    return out
                try:
                    self._hdr = decode_header(self._head)
                except FrameError as e:
                    self._error = e
                    raise
                self._head = bytearray()
                self._body = bytearray(self._hdr[3])
                self._fill = 0
            mtype, flags, rid, plen, ver = self._hdr
            take = min(plen - self._fill, len(view) - pos)
            if take:
                self._body[self._fill:self._fill + take] = view[pos:pos + take]
                self._fill += take
                pos += take
            if self._fill < plen:
                return out
            out.append(Frame(mtype, flags, rid, bytes(self._body) if plen < 4096 else self._body,
                             ver))
            self._hdr, self._body = None, None
            if pos == len(view):
                return out

    @property
    def pending(self) -> int:
        """Bytes buffered that do not yet form a complete frame."""
        return len(self._head) + (self._fill if self._hdr is not None else 0)
