"""Negotiated stream encodings (proto/PROTOCOL.md 4.2, 4.40, 4.41): the QDISP body (a quantized
version delta: varint rows) and the ZFRAME body (a stream event compressed by zstd, decompressed
here through libzstd, the C library the daemon uses: Debian's libzstd1, loaded with ctypes so
the client needs no extra Python package).

Quantized replica rule (4.40): a client holding the exact displacements u of a snapshot holds
K = floor(u / q + 0.5) (double arithmetic) steps per component; each QDISP row adds its dq to K,
and the displacement the client shows is then fl32(q * K) for every vertex."""
import ctypes
import ctypes.util
import math
from array import array
from dataclasses import dataclass, field
from typing import List, Optional

from . import frame as fr
from . import messages as m
from .wire import ProtocolError, Reader

_QDISP_HEAD = "QQQBBHIIId"       # 48 bytes
_QDISP_PROGRESS = "BBHIddd"       # 32 bytes: the optional progress trailer (flags bit 0)
_FLAG_PROGRESS = 1
_DQ_LIMIT = 1 << 53


@dataclass
class QProgress:
    """The progress trailer of a QDISP (4.40): the handle-move iterate's fields, as in PROGRESS."""
    status: int
    final: int
    iteration: int
    objective: float
    residual: float
    elapsed_ms: float


@dataclass
class QDisp:
    """One quantized version delta (all chunks joined): rows idx[i] change by dq[3i:3i+3] steps
    of `step` mesh units."""
    session_id: int
    version: int
    base_version: int
    kind: int
    nv: int
    count: int
    step: float
    idx: List[int]
    dq: List[int]
    # bytes of its frames on the wire (compressed size for ZFRAME); not part of equality
    wire_bytes: int = field(default=0, compare=False)
    kind_name: str = "qdisp"
    # the iterate's fields when the version is a PROGRESS iterate (flags bit 0), else None
    progress: Optional[QProgress] = None


def _varint(p, off: int, n: int):
    v = shift = 0
    while off < n and shift < 70:
        b = p[off]
        off += 1
        v |= (b & 0x7F) << shift
        if not b & 0x80:
            if b == 0 and shift:
                break                   # not the shortest form: refused (one encoding a value)
            return v, off
        shift += 7
    raise ProtocolError("qdisp: truncated row, or a varint longer than 10 bytes or not in its "
                        "shortest form")


def decode_qdisp(p: bytes) -> QDisp:
    r = Reader(p, "qdisp")
    sid, ver, base, kind, flags, r2, nv, count, rows_bytes, step = r.take(_QDISP_HEAD)
    if flags & ~_FLAG_PROGRESS or r2:
        raise ProtocolError("qdisp: unknown flags 0x%x or reserved field not 0" % flags)
    if sid == 0 or ver <= base or not 1 <= kind < m.CHANGE_SNAPSHOT or not 1 <= nv <= \
            m.MAX_MESH_VERTICES or count > nv or not (step > 0 and math.isfinite(step)):
        raise ProtocolError("qdisp: bad header (session %d version %d base %d kind %d nv %d "
                            "count %d step %r)" % (sid, ver, base, kind, nv, count, step))
    off, n = r.off, len(p)
    tail = 32 if flags & _FLAG_PROGRESS else 0
    if rows_bytes + tail != n - off:
        raise ProtocolError("qdisp: rows_bytes %d (+%d trailer) but %d bytes follow"
                            % (rows_bytes, tail, n - off))
    prog = None
    if tail:
        t = Reader(p[n - tail:], "qdisp")
        status, final, res, it, obj, resid, ms = t.take(_QDISP_PROGRESS)
        if res or kind != m.CHANGE_HANDLE_MOVE or final > 1 or \
                not all(math.isfinite(x) for x in (obj, resid, ms)) or resid < 0 or ms < 0:
            raise ProtocolError("qdisp: bad progress trailer (kind %d, final %d, residual %r)"
                                % (kind, final, resid))
        prog = QProgress(status, final, it, obj, resid, ms)
        n -= tail
    idx: List[int] = []
    dq: List[int] = []
    prev = -1
    for _ in range(count):
        gap, off = _varint(p, off, n)
        prev += 1 + gap
        if prev >= nv:
            raise ProtocolError("qdisp: row index %d beyond nv %d" % (prev, nv))
        idx.append(prev)
        for _k in range(3):
            z, off = _varint(p, off, n)
            d = (z >> 1) ^ -(z & 1)
            if not -_DQ_LIMIT < d < _DQ_LIMIT:
                raise ProtocolError("qdisp: change out of +-2^53 steps")
            dq.append(d)
    if off != n:
        raise ProtocolError("qdisp: %d bytes after the rows" % (n - off))
    return QDisp(sid, ver, base, kind, nv, count, step, idx, dq, progress=prog)


def join_qdisp(chunks: List[QDisp]) -> QDisp:
    first = chunks[0]
    out = QDisp(first.session_id, first.version, first.base_version, first.kind, first.nv, 0,
                first.step, [], [])
    for c in chunks:
        if (c.session_id, c.version, c.step) != (first.session_id, first.version, first.step):
            raise ProtocolError("qdisp chunks of different versions mixed")
        if out.idx and c.idx and c.idx[0] <= out.idx[-1]:
            raise ProtocolError("qdisp chunk rows not increasing")
        out.idx += c.idx
        out.dq += c.dq
        out.progress = out.progress or c.progress
    out.count = len(out.idx)
    return out


_zstd = None


def _lib():
    global _zstd
    if _zstd is None:
        name = ctypes.util.find_library("zstd") or "libzstd.so.1"
        lib = ctypes.CDLL(name)
        lib.ZSTD_decompress.restype = ctypes.c_size_t
        lib.ZSTD_decompress.argtypes = [ctypes.c_void_p, ctypes.c_size_t, ctypes.c_char_p,
                                        ctypes.c_size_t]
        lib.ZSTD_isError.restype = ctypes.c_uint
        lib.ZSTD_isError.argtypes = [ctypes.c_size_t]
        lib.ZSTD_getErrorName.restype = ctypes.c_char_p
        lib.ZSTD_getErrorName.argtypes = [ctypes.c_size_t]
        _zstd = lib
    return _zstd


def zstd_decompress(z: bytes, raw_len: int) -> bytes:
    """Decompresses one zstd frame that must hold exactly raw_len bytes (ProtocolError else)."""
    lib = _lib()
    dst = ctypes.create_string_buffer(max(raw_len, 1))
    n = lib.ZSTD_decompress(dst, raw_len, z, len(z))
    if lib.ZSTD_isError(n):
        raise ProtocolError("zframe: zstd: %s" % lib.ZSTD_getErrorName(n).decode())
    if n != raw_len:
        raise ProtocolError("zframe: %d bytes decompressed, raw_len says %d" % (n, raw_len))
    return dst.raw[:raw_len]


def unwrap_zframe(f: fr.Frame) -> fr.Frame:
    """The stream event frame a ZFRAME carries (same flags and request id)."""
    r = Reader(f.payload, "zframe")
    inner, res, raw_len, zlen = r.take("HHII")
    z = r.raw(zlen)
    r.end()
    if res or inner not in (m.DISPLACEMENT, m.PROGRESS, m.QDISP) or zlen < 1 or \
            raw_len > m.MAX_FRAME_PAYLOAD:
        raise ProtocolError("zframe: inner type 0x%x, reserved %d, raw_len %d, zlen %d"
                            % (inner, res, raw_len, zlen))
    return fr.Frame(inner, f.flags, f.request_id, zstd_decompress(z, raw_len))


def quantize(u: float, step: float) -> int:
    """K of one component: floor(u / q + 0.5) in double, clamped to +-(2^52 - 1) (4.40)."""
    k = math.floor(u / step + 0.5)
    lim = (1 << 52) - 1
    return max(-lim, min(lim, k))


class QuantState:
    """The quantized side of a replica: K per component, and whether the shown displacements
    are still the exact ones of the last snapshot (then the next QDISP rewrites all of them)."""

    def __init__(self, step: float, disp: array) -> None:
        self.step = step
        self.K = [quantize(u, step) for u in disp]
        self.exact = True

    def apply(self, q: QDisp, disp: array) -> Optional[List[int]]:
        """Adds q's rows to K and writes fl32(step * K) into disp: every component after an
        exact snapshot (returns None), else the changed vertices' (returns their indices)."""
        if q.step != self.step:
            raise ProtocolError("qdisp step %r, replica step %r" % (q.step, self.step))
        K, s = self.K, self.step
        for j, i in enumerate(q.idx):
            for k in range(3):
                K[3 * i + k] += q.dq[3 * j + k]
        if self.exact:
            self.exact = False
            for c in range(len(K)):
                disp[c] = s * K[c]
            return None
        for i in q.idx:
            for k in range(3):
                disp[3 * i + k] = s * K[3 * i + k]
        return q.idx
