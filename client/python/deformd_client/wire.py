"""Low-level helpers shared by the body codecs: a bounds-checked little-endian reader and the
packing of strings, vectors and index arrays (proto/PROTOCOL.md section 2)."""
import struct
from array import array
from typing import List, Optional, Sequence


class ProtocolError(ValueError):
    """A payload that does not decode (truncated, trailing bytes, bad value)."""


def enum_value(cls, v: int, what: str):
    """The member of IntEnum/IntFlag `cls` with value v; ProtocolError naming `what` when v is not
    a value of the wire enum (as the C decoders refuse it)."""
    try:
        return cls(v)
    except ValueError:
        raise ProtocolError("%s %d is not a %s value" % (what, v, cls.__name__)) from None


class Reader:
    """Sequential little-endian reader over one payload; every read checks the bounds and raises
    ProtocolError naming the message (`what`) when the payload is short."""

    def __init__(self, p: bytes, what: str) -> None:
        self.p = memoryview(p)
        self.off = 0
        self.what = what

    def take(self, fmt: str):
        st = struct.Struct("<" + fmt)
        if self.off + st.size > len(self.p):
            raise ProtocolError("%s: truncated at byte %d" % (self.what, self.off))
        v = st.unpack_from(self.p, self.off)
        self.off += st.size
        return v if len(v) > 1 else v[0]

    def raw(self, n: int) -> bytes:
        if self.off + n > len(self.p):
            raise ProtocolError("%s: truncated at byte %d (need %d)" % (self.what, self.off, n))
        b = bytes(self.p[self.off:self.off + n])
        self.off += n
        return b

    def str(self) -> str:
        """A u16-length string. UTF-8 by the protocol, but like the C decoders any bytes are
        accepted: undecodable bytes become lone surrogates ("surrogateescape"), which pack_str
        writes back as the same bytes, so every string round-trips exactly."""
        n = self.take("H")
        return self.raw(n).decode("utf-8", "surrogateescape")

    def text(self) -> str:
        """A u16-length string for people (error messages): undecodable bytes become U+FFFD."""
        n = self.take("H")
        return self.raw(n).decode("utf-8", "replace")

    def farray(self, typecode: str, count: int) -> array:
        a = array(typecode)
        n = count * a.itemsize
        if self.off + n > len(self.p):
            raise ProtocolError("%s: truncated at byte %d (need %d)" % (self.what, self.off, n))
        a.frombytes(self.p[self.off:self.off + n])
        self.off += n
        return a

    def end(self) -> None:
        if self.off != len(self.p):
            raise ProtocolError("%s: %d trailing bytes" % (self.what, len(self.p) - self.off))


def pack_str(s: str) -> bytes:
    b = s.encode("utf-8", "surrogateescape")
    if len(b) > 0xFFFF:
        raise ValueError("string of %d bytes too long" % len(b))
    return struct.pack("<H", len(b)) + b


def vec(v: Optional[Sequence[float]], n: int, what: str) -> List[float]:
    if v is None:
        return [0.0] * n
    v = [float(x) for x in v]
    if len(v) != n:
        raise ValueError("%s needs %d numbers, got %d" % (what, n, len(v)))
    return v


def u32_array(values: Sequence[int]) -> bytes:
    a = array("I", (int(x) for x in values))
    assert a.itemsize == 4
    return a.tobytes()


def f64_rows(rows: Sequence[Sequence[float]], what: str) -> bytes:
    flat: List[float] = []
    for r in rows:
        flat += vec(r, 3, what)
    return struct.pack("<%dd" % len(flat), *flat)
