"""Displacement stream and get-mesh bodies (proto/PROTOCOL.md 4.19-4.22, section 5-6): decode
one chunk, join the chunks of one version or one get-mesh reply; and ShmRing, the reader of a
session's shared-memory stream ring (section 6.1), whose frames are stream frames like these."""
import mmap
import os
import struct
from array import array
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Sequence

from . import frame as fr
from . import messages as m
from .messages import (CHANGE_NAMES, DISP_DENSE, DISP_SPARSE, ELEM_SIZE, SECTION_BASE,
                       SECTION_ELEMENTS, SECTION_FACES, SECTION_POSITIONS, SECTION_REST)
from .schema import ChangeKind, DispEncoding, MeshKind, MeshSection, MoveStatus
from .wire import ProtocolError, Reader, enum_value


@dataclass
class Disp:
    """One session version (or one chunk of it): float32 displacements u_i = x_i - X_i from the
    session's base positions X. DENSE: rows offset..offset+count-1; SPARSE: rows idx[k]."""
    session_id: int
    version: int
    base_version: int
    kind: int
    encoding: int
    nv: int
    total: int
    offset: int
    count: int
    idx: Optional[array]   # array('I') of count vertex indices (SPARSE), else None
    xyz: array             # array('f') of 3*count displacement components
    # bytes its frames took on the wire (Client events; 0 elsewhere); not part of equality
    wire_bytes: int = field(default=0, compare=False)

    @property
    def kind_name(self) -> str:
        return CHANGE_NAMES.get(self.kind, "unknown")

    def vertices(self) -> Sequence[int]:
        """Vertex index of every row."""
        if self.idx is not None:
            return self.idx
        return range(self.offset, self.offset + self.count)


DISP_STRUCT = struct.Struct("<QQQBBHIIII")
assert DISP_STRUCT.size == 44


def _read_disp(r: Reader) -> Disp:
    sid, ver, base, kind, enc, res, nv, total, offset, count = r.take("QQQBBHIIII")
    if res != 0:
        raise ProtocolError("disp: reserved field %d" % res)
    if enc == DISP_DENSE:
        xyz = r.farray("f", 3 * count)
        idx = None
    elif enc == DISP_SPARSE:
        raw = r.raw(16 * count)
        words = array("I")
        words.frombytes(raw)
        floats = array("f")
        floats.frombytes(raw)
        idx = words[0::4]
        xyz = array("f", bytes(12 * count))
        xyz[0::3] = floats[1::4]
        xyz[1::3] = floats[2::4]
        xyz[2::3] = floats[3::4]
    else:
        raise ProtocolError("disp: encoding %d" % enc)
    if offset + count > total or (enc == DISP_DENSE and total != nv):
        raise ProtocolError("disp: rows [%d, +%d) of %d (nv %d)" % (offset, count, total, nv))
    return Disp(sid, ver, base, enum_value(ChangeKind, kind, "disp: kind"), DispEncoding(enc), nv,
                total, offset, count, idx, xyz)


def encode_disp(d: Disp) -> bytes:
    """Body of one disp chunk (used by tests to forge stream frames)."""
    head = DISP_STRUCT.pack(d.session_id, d.version, d.base_version, d.kind, d.encoding, 0, d.nv,
                            d.total, d.offset, d.count)
    if d.encoding == DISP_DENSE:
        return head + d.xyz.tobytes()
    rows = bytearray()
    for k in range(d.count):
        rows += struct.pack("<I3f", d.idx[k], *d.xyz[3 * k:3 * k + 3])
    return head + bytes(rows)


def decode_disp(p: bytes) -> Disp:
    r = Reader(p, "disp")
    d = _read_disp(r)
    r.end()
    return d


@dataclass
class Progress:
    """One ADMM iterate of a handle move; `disp` is the iterate as a session version."""
    status: int
    final: int
    iteration: int
    objective: float
    residual: float
    elapsed_ms: float
    disp: Disp


def decode_progress(p: bytes) -> Progress:
    r = Reader(p, "progress")
    status, final, res, it, obj, resid, ms = r.take("BBHIddd")
    status = enum_value(MoveStatus, status, "progress: status")
    if res != 0:
        raise ProtocolError("progress: reserved field %d" % res)
    d = _read_disp(r)
    r.end()
    return Progress(status, final, it, obj, resid, ms, d)


def join_disp(chunks: List[Disp]) -> Disp:
    """Concatenates the chunks of one version (in arrival order) into one Disp of all rows."""
    if len(chunks) == 1 and chunks[0].count == chunks[0].total:
        return chunks[0]
    first = chunks[0]
    xyz = array("f")
    idx = array("I") if first.encoding == DISP_SPARSE else None
    expect = 0
    for c in chunks:
        if (c.session_id, c.version, c.encoding, c.total) != \
                (first.session_id, first.version, first.encoding, first.total):
            raise ProtocolError("disp chunks of different versions mixed")
        if c.offset != expect:
            raise ProtocolError("disp chunk at row %d, expected %d" % (c.offset, expect))
        expect += c.count
        xyz += c.xyz
        if idx is not None:
            idx += c.idx
    if expect != first.total:
        raise ProtocolError("disp chunks hold %d of %d rows" % (expect, first.total))
    return Disp(first.session_id, first.version, first.base_version, first.kind, first.encoding,
                first.nv, first.total, 0, expect, idx, xyz)


@dataclass
class MeshChunk:
    session_id: int
    version: int
    kind: int
    planar: int
    section: int
    nv: int
    ne: int
    nf: int
    offset: int
    count: int
    data: array   # array('f') 3*count (xyz sections) or array('I') rows*width (index sections)


def _section_rows(c) -> int:
    return {SECTION_POSITIONS: c.nv, SECTION_BASE: c.nv, SECTION_REST: c.nv,
            SECTION_ELEMENTS: c.ne, SECTION_FACES: c.nf}[c.section]


def decode_mesh_chunk(p: bytes) -> MeshChunk:
    r = Reader(p, "mesh_chunk")
    sid, ver, kind, planar, section, res, nv, ne, nf, off, count = r.take("QQBBBBIIIII")
    if res != 0:
        raise ProtocolError("mesh_chunk: reserved field %d" % res)
    if kind not in ELEM_SIZE or section not in (1, 2, 3, 4, 5):
        raise ProtocolError("mesh_chunk: kind %d section %d" % (kind, section))
    if section in (SECTION_POSITIONS, SECTION_BASE, SECTION_REST):
        data = r.farray("f", 3 * count)
    else:
        width = ELEM_SIZE[kind] if section == SECTION_ELEMENTS else 3
        data = r.farray("I", width * count)
    r.end()
    c = MeshChunk(sid, ver, MeshKind(kind), planar, MeshSection(section), nv, ne, nf, off, count,
                  data)
    if off + count > _section_rows(c):
        raise ProtocolError("mesh_chunk: rows [%d, +%d) beyond section %d" % (off, count, section))
    return c


def assemble_mesh(chunks: List[MeshChunk], cls):
    """Joins the chunks of a get-mesh reply into cls(session_id, version, kind, planar, nv, ne,
    nf, positions, elements, faces, rest, base)."""
    if not chunks:
        raise ProtocolError("get_mesh: empty reply")
    c0 = chunks[0]
    sections: Dict[int, array] = {}
    rows: Dict[int, int] = {}
    for c in chunks:
        if (c.session_id, c.version, c.kind, c.nv, c.ne, c.nf) != \
                (c0.session_id, c0.version, c0.kind, c0.nv, c0.ne, c0.nf):
            raise ProtocolError("get_mesh: chunks disagree on the mesh header")
        have = rows.get(c.section, 0)
        if c.offset != have:
            raise ProtocolError("get_mesh: section %d chunk at row %d, expected %d"
                                % (c.section, c.offset, have))
        if c.section in sections:
            sections[c.section] += c.data     # += on arrays is a memcpy, extend() is not
        else:
            sections[c.section] = c.data
        rows[c.section] = have + c.count
    for sec, n in rows.items():
        full = c0.nv if sec in (1, 2, 3) else c0.ne if sec == 4 else c0.nf
        if n != full:
            raise ProtocolError("get_mesh: section %d has %d of %d rows" % (sec, n, full))
    if SECTION_POSITIONS not in sections and c0.nv:
        raise ProtocolError("get_mesh: no positions")
    return cls(c0.session_id, c0.version, c0.kind, c0.planar, c0.nv, c0.ne, c0.nf,
               sections.get(SECTION_POSITIONS, array("f")),
               sections.get(SECTION_ELEMENTS, array("I")),
               sections.get(SECTION_FACES, array("I")),
               sections.get(SECTION_REST), sections.get(SECTION_BASE))


# ------------------------------------------------------------------ shared-memory ring (6.1)
_SHM_HEADER = struct.Struct("<8sIIQQQQ")   # magic, header_bytes, reserved, capacity, session,
#                                            valid_from, head
_U64 = struct.Struct("<Q")
_SHM_OFF_VALID_FROM = 32
_SHM_OFF_HEAD = 40


class ShmRing:
    """A read-only mapping of one session's shared-memory stream ring (PROTOCOL.md 6.1), made by
    Client.stream_shm. `frames` and `lost` count the references read from it and the frames
    found overwritten. Raises OSError when the file cannot be opened or mapped and
    ProtocolError when its header does not match `info`."""

    def __init__(self, info: m.ShmInfo) -> None:
        self.info = info
        self.frames = 0
        self.lost = 0
        fd = os.open(info.path, os.O_RDONLY | getattr(os, "O_CLOEXEC", 0))
        try:
            size = os.fstat(fd).st_size
            if size < m.SHM_HEADER_BYTES + info.capacity:
                raise ProtocolError("shm ring %s: %d bytes, need %d header + %d data"
                                    % (info.path, size, m.SHM_HEADER_BYTES, info.capacity))
            self.map = mmap.mmap(fd, 0, access=mmap.ACCESS_READ)
        finally:
            os.close(fd)
        try:
            self._check()
        except ProtocolError:
            self.map.close()
            raise

    def _check(self) -> None:
        magic, header_bytes, reserved, capacity, sid, _, _ = _SHM_HEADER.unpack_from(self.map, 0)
        what = "shm ring %s" % self.info.path
        if magic != m.SHM_MAGIC:
            raise ProtocolError("%s: magic %r, not %r" % (what, magic, m.SHM_MAGIC))
        if header_bytes != m.SHM_HEADER_BYTES or reserved != 0:
            raise ProtocolError("%s: header_bytes %d (reserved %d), not %d"
                                % (what, header_bytes, reserved, m.SHM_HEADER_BYTES))
        if capacity != self.info.capacity:
            raise ProtocolError("%s: capacity %d, the reply said %d"
                                % (what, capacity, self.info.capacity))
        if sid != self.info.session_id:
            raise ProtocolError("%s: session %d, the reply said %d"
                                % (what, sid, self.info.session_id))
        if len(self.map) < header_bytes + capacity:
            raise ProtocolError("%s: %d bytes mapped, need %d"
                                % (what, len(self.map), header_bytes + capacity))

    def valid_from(self) -> int:
        """Stream positions below this may have been overwritten."""
        return _U64.unpack_from(self.map, _SHM_OFF_VALID_FROM)[0]

    def head(self) -> int:
        """Stream position after the last frame the daemon wrote."""
        return _U64.unpack_from(self.map, _SHM_OFF_HEAD)[0]

    def read(self, position: int, length: int) -> Optional[fr.Frame]:
        """The frame an SHM_REF (position, length) names, or None when it was overwritten before
        or while it was copied (lost). ProtocolError when (position, length) cannot be a frame of
        this ring or the bytes are not one whole frame.

        Python issues no fences: the protocol's acquire loads are approximated by reading
        valid_from with struct.unpack_from before and after copying the bytes."""
        cap = self.info.capacity
        off = position % cap
        if off + length > cap:
            raise ProtocolError("shm_ref: frame of %d bytes at %d crosses the end of the %d-byte"
                                " ring" % (length, position, cap))
        if position + length > self.head():
            raise ProtocolError("shm_ref: frame [%d, +%d) beyond the ring's head %d"
                                % (position, length, self.head()))
        if position < self.valid_from():
            self.lost += 1
            return None
        start = m.SHM_HEADER_BYTES + off
        head = self.map[start:start + fr.HEADER_SIZE]
        payload = self.map[start + fr.HEADER_SIZE:start + length]
        if position < self.valid_from():
            self.lost += 1
            return None
        try:
            mtype, flags, rid, plen, ver = fr.decode_header(head)
        except fr.FrameError as e:
            raise ProtocolError("shm ring frame at %d: %s" % (position, e)) from None
        if fr.HEADER_SIZE + plen != length:
            raise ProtocolError("shm ring frame at %d: %d payload bytes, the reference says %d"
                                % (position, plen, length - fr.HEADER_SIZE))
        self.frames += 1
        return fr.Frame(mtype, flags, rid, payload, ver)

    def close(self) -> None:
        self.map.close()
