"""Displacement stream and get-mesh bodies (proto/PROTOCOL.md 4.19-4.22, section 5-6): decode
one chunk, join the chunks of one version or one get-mesh reply."""
import struct
from array import array
from dataclasses import dataclass
from typing import Dict, List, Optional, Sequence

from .messages import (CHANGE_NAMES, DISP_DENSE, DISP_SPARSE, ELEM_SIZE, SECTION_BASE,
                       SECTION_ELEMENTS, SECTION_FACES, SECTION_POSITIONS, SECTION_REST)
from .wire import ProtocolError, Reader


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
    return Disp(sid, ver, base, kind, enc, nv, total, offset, count, idx, xyz)


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
    c = MeshChunk(sid, ver, kind, planar, section, nv, ne, nf, off, count, data)
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
