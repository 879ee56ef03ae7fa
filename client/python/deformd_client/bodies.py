"""Every message body both ways, by name (PROTOCOL.md section 4, schema.BODIES): decode_body(name,
payload) returns a Python object and encode_body(name, obj) gives the payload back, byte for byte
for every payload the decoder accepts. decode_frame_body picks the body from (type, flags) as the
C df_msg_body_kind does. The per-message functions live in messages.py and stream.py; this module
adds the directions a client does not need in normal use (decoding requests, encoding replies and
events), for tools, tests and fake servers."""
import struct
from dataclasses import dataclass
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

from . import access as ac
from . import peers as pr
from . import brush_state as bs
from . import devices as dv
from . import messages as m
from . import progress as pg
from . import schema
from . import stream as st
from . import stream_enc as se
from .wire import ProtocolError, Reader, pack_str


@dataclass
class Hello:
    min_version: int
    max_version: int
    features: int
    client_name: str
    stream_encoding: Optional[int] = None   # None: no trailer (the original layout, 4.2)
    error_bound: float = 0.0


@dataclass
class LoadMesh:
    """One load_mesh chunk (4.5); file_name only with options LOAD_OPT_EXT."""
    source: int
    format: int
    options: int
    total_size: int
    part2_offset: int
    offset: int
    name: str
    path: str
    data: bytes
    file_name: str = ""


@dataclass
class BrushBegin:
    session_id: int
    brush: m.Brush


@dataclass
class BrushUpdate:
    session_id: int
    move: List[float]
    twist: List[float]
    scale: float
    matrix: List[float]


@dataclass
class HandleMove:
    session_id: int
    max_iters: int
    max_ms: int
    progress_every: int
    targets: List[Tuple[float, float, float]]
    options: Optional[int] = None   # the optional trailing field; None: absent


def _end(r: Reader, v):
    r.end()
    return v


def _fixed(fmt: str, what: str) -> Callable[[bytes], tuple]:
    def dec(p: bytes) -> tuple:
        r = Reader(p, what)
        return _end(r, r.take(fmt))
    return dec


# ------------------------------------------------------------------ decoders a client lacks
def decode_subscribe(p: bytes) -> tuple:
    """(session_id, flags[, from_version]): from_version only with flag FROM_VERSION."""
    r = Reader(p, "subscribe")
    sid, flags = r.take("QI")
    if flags & m.SUBSCRIBE_FROM_VERSION:
        return _end(r, (sid, flags, r.take("Q")))
    return _end(r, (sid, flags))


def decode_empty(p: bytes) -> None:
    if len(p):
        raise ProtocolError("empty body: %d trailing bytes" % len(p))


def decode_hello(p: bytes) -> Hello:
    r = Reader(p, "hello")
    lo, hi, feat = r.take("HHI")
    h = Hello(lo, hi, feat, r.str())
    if r.off < len(r.p):                       # the optional stream-encoding trailer
        enc, res, bound = r.take("BBd")
        if res:
            raise ProtocolError("hello: reserved %d is not 0" % res)
        try:
            m.check_stream_encoding(enc, bound)
        except ValueError as e:
            raise ProtocolError(str(e)) from None
        h.stream_encoding, h.error_bound = enc, bound
    return _end(r, h)


def decode_auth(p: bytes) -> Tuple[int, bytes]:
    r = Reader(p, "auth")
    method, reserved, n = r.take("HHI")
    if reserved:
        raise ProtocolError("auth: reserved field %d" % reserved)
    return _end(r, (method, r.raw(n)))


def decode_load_mesh(p: bytes) -> LoadMesh:
    r = Reader(p, "load_mesh")
    source, fmt, options, total, part2, offset = r.take("BBHQQQ")
    name, path = r.str(), r.str()
    data = r.raw(r.take("I"))
    file_name = r.str() if options & m.LOAD_OPT_EXT else ""
    return _end(r, LoadMesh(source, fmt, options, total, part2, offset, name, path, data,
                            file_name))


def decode_open_session(p: bytes) -> Tuple[int, str]:
    r = Reader(p, "open_session")
    sid = r.take("Q")
    return _end(r, (sid, r.str()))


def decode_brush(p: bytes) -> BrushBegin:
    r = Reader(p, "brush")
    v = r.take(m.BRUSH_STRUCT.format.lstrip("<"))
    (sid, btype, dim, falloff, integ, steps, moving, has_mirror, radius, ratio, nu,
     strength) = v[:12]
    center, move, twist, scale = v[12:15], v[15:18], v[18:21], v[21]
    matrix, mirror, n_pinned, pin_flags = v[22:31], v[31:37], v[37], v[38]
    names = {int(t): k for k, t in m.BRUSH_TYPES.items()}
    integs = {int(t): k for k, t in m.INTEGRATORS.items()}
    if btype not in names or integ not in integs:
        raise ProtocolError("brush: type %d / integrator %d" % (btype, integ))
    if n_pinned > schema.MAX_PINNED_POINTS:
        raise ProtocolError("brush: %d pinned points" % n_pinned)
    if moving > 1 or has_mirror > 1:
        raise ProtocolError("brush: moving %d / has_mirror %d not 0 or 1" % (moving, has_mirror))
    if (pin_flags != 0) if n_pinned == 0 else not 1 <= pin_flags <= 3:
        raise ProtocolError("brush: pin_flags %d with %d pinned points" % (pin_flags, n_pinned))
    if not has_mirror and any(mirror):
        raise ProtocolError("brush: mirror plane given without has_mirror (not representable)")
    pinned = [tuple(r.take("3d")) for _ in range(n_pinned)]
    use_session = r.take("H") if r.off < len(p) else None   # optional trailing field
    if use_session is not None and use_session & ~sum(schema.BrushStateField):
        raise ProtocolError("brush: use_session bits 0x%x not defined" % use_session)
    options = None    # optional, after use_session (4.12)
    if use_session is not None and 0 < len(p) - r.off <= 5:
        options = r.take("I")
        if options & ~sum(schema.WorkOpt):
            raise ProtocolError("brush: options 0x%x has unknown bits" % options)
    surface = r.take("B") if options is not None and r.off < len(p) else None
    if surface is not None and surface > 1:
        raise ProtocolError("brush: surface %d not 0 or 1" % surface)
    b = m.Brush(type=names[btype], center=list(center), move=list(move), twist=list(twist),
                scale=scale, matrix=list(matrix), radius=radius, nu=nu, strength=strength,
                falloff=falloff, ratio=ratio, dim=dim, integrator=integs[integ], steps=steps,
                moving=bool(moving), mirror=list(mirror) if has_mirror else None,
                pinned=pinned, pin_flags=pin_flags, use_session=use_session, options=options,
                surface=surface)
    return _end(r, BrushBegin(sid, b))


def decode_brush_update(p: bytes) -> BrushUpdate:
    v = _fixed("Q3d3dd9d", "brush_update")(p)
    return BrushUpdate(v[0], list(v[1:4]), list(v[4:7]), v[7], list(v[8:17]))


def decode_brush_param(p: bytes) -> Tuple[int, str, float]:
    sid, param, value = _fixed("QBd", "brush_param")(p)
    names = {int(t): k for k, t in m.BRUSH_PARAMS.items()}
    if param not in names:
        raise ProtocolError("brush_param: param %d" % param)
    return sid, names[param], value


def decode_handle_move(p: bytes) -> HandleMove:
    r = Reader(p, "handle_move")
    sid, iters, ms, every, n = r.take("QIIII")
    if n > schema.MAX_HANDLES:
        raise ProtocolError("handle_move: %d targets" % n)
    targets = [tuple(r.take("3d")) for _ in range(n)]
    return _end(r, HandleMove(sid, iters, ms, every, targets, m._read_options(r, "handle_move")))


def decode_stats_req(p: bytes) -> int:
    return _fixed("Q", "stats_req")(p)


# ------------------------------------------------------------------ encoders a client lacks
def encode_error(e: Tuple[int, str]) -> bytes:
    return struct.pack("<i", e[0]) + pack_str(e[1])


def encode_hello_reply(h: m.HelloReply) -> bytes:
    return struct.pack("<HHIIIIIIQQBB", h.version, h.server_max_version, h.features,
                       h.max_frame_payload, h.max_mesh_vertices, h.max_mesh_elements,
                       h.max_pending_requests, h.max_sessions, h.max_mesh_bytes,
                       h.max_client_queue_bytes, h.auth_required, 0) + pack_str(h.server_name) + (
        struct.pack("<BBd", h.stream_encoding, 0, h.error_bound) if h.has_stream else b"")


def encode_qdisp(q: se.QDisp) -> bytes:
    """A qdisp body (PROTOCOL.md 4.40) of q's rows."""
    rows = bytearray()

    def varint(v: int) -> None:
        while v >= 0x80:
            rows.append((v & 0x7F) | 0x80)
            v >>= 7
        rows.append(v)

    prev = -1
    for j, i in enumerate(q.idx):
        varint(i - prev - 1)
        prev = i
        for k in range(3):
            d = q.dq[3 * j + k]
            varint(2 * d if d >= 0 else -2 * d - 1)   # zigzag
    return struct.pack("<QQQBBHIIId", q.session_id, q.version, q.base_version, q.kind, 0, 0, q.nv,
                       q.count, len(rows), q.step) + bytes(rows)


def decode_zframe(p: bytes) -> Tuple[int, int, bytes]:
    """A zframe body (4.41): (inner_type, raw_len, zstd bytes), not decompressed."""
    r = Reader(p, "zframe")
    inner, res, raw_len, zlen = r.take("HHII")
    z = r.raw(zlen)
    if res or inner not in (m.DISPLACEMENT, m.PROGRESS, m.QDISP) or zlen < 1 or \
            raw_len > m.MAX_FRAME_PAYLOAD:
        raise ProtocolError("zframe: inner type 0x%x reserved %d raw_len %d zlen %d"
                            % (inner, res, raw_len, zlen))
    return _end(r, (inner, raw_len, z))


def encode_zframe(z: Tuple[int, int, bytes]) -> bytes:
    return struct.pack("<HHII", z[0], 0, z[1], len(z[2])) + z[2]


def encode_session_info(s: m.SessionInfo) -> bytes:
    return struct.pack("<QQBBHIIII", s.session_id, s.version, s.kind, s.planar, s.subscribers,
                       s.nv, s.ne, s.undo_depth, s.redo_depth) + pack_str(s.name)


def encode_load_reply(s: m.SessionInfo) -> bytes:
    out = encode_session_info(s)
    if s.report is not None:
        t = s.report
        out += struct.pack("<BBH11I", t.format, t.index_base, 0, t.input_polygons,
                           t.polygons_triangulated, t.dropped_elements, t.duplicate_elements,
                           t.degenerate_elements, t.inverted_elements, t.nonmanifold_edges,
                           t.nonmanifold_faces, t.boundary_edges, t.boundary_faces,
                           t.unused_vertices)
    return out


def encode_session_list(items: Sequence[m.SessionInfo]) -> bytes:
    """The list, and the owners trailer when the decoded list had one (has_owners) or any item
    names an owner (PROTOCOL.md 4.10)."""
    out = struct.pack("<I", len(items)) + b"".join(encode_session_info(s) for s in items)
    if getattr(items, "has_owners", False) or any(s.owner is not None for s in items):
        out += struct.pack("<I", len(items)) + b"".join(
            struct.pack("<Q", s.session_id) + pack_str(s.owner or "") for s in items)
    return out


def encode_ack(a: m.Ack) -> bytes:
    return struct.pack("<QQ", a.session_id, a.version)


def encode_move_result(x: m.MoveResult) -> bytes:
    return struct.pack("<QQBIddd", x.session_id, x.version, x.status, x.iterations, x.objective,
                       x.residual, x.elapsed_ms)


def encode_mesh_chunk(c: st.MeshChunk) -> bytes:
    return struct.pack("<QQBBBBIIIII", c.session_id, c.version, c.kind, c.planar, c.section, 0,
                       c.nv, c.ne, c.nf, c.offset, c.count) + c.data.tobytes()


def encode_progress(x: st.Progress) -> bytes:
    return struct.pack("<BBHIddd", x.status, x.final, 0, x.iteration, x.objective, x.residual,
                       x.elapsed_ms) + st.encode_disp(x.disp)


def encode_stats(items: Dict[str, float]) -> bytes:
    return struct.pack("<I", len(items)) + b"".join(
        pack_str(k) + struct.pack("<d", v) for k, v in items.items())


# ------------------------------------------------------------------ the table
BODY_CODECS: Dict[str, Tuple[Callable[[bytes], Any], Callable[[Any], bytes]]] = {
    "empty": (decode_empty, lambda _: b""),
    "error": (m.decode_error, encode_error),
    "hello": (decode_hello, lambda h: m.encode_hello(h.min_version, h.max_version, h.features,
                                                     h.client_name, h.stream_encoding,
                                                     h.error_bound)),
    "hello_reply": (m.decode_hello_reply, encode_hello_reply),
    "auth": (decode_auth, lambda a: m.encode_auth(*a)),
    "ping": (bytes, bytes),
    "load_mesh": (decode_load_mesh, lambda x: m.encode_load_mesh(
        x.source, x.format, x.name, x.path, x.total_size, x.part2_offset, x.offset, x.data,
        x.options, x.file_name)),
    "session_ref": (m.decode_session_ref, m.encode_session_ref),
    "open_session": (decode_open_session, lambda x: m.encode_open_session(*x)),
    "subscribe": (decode_subscribe, lambda x: m.encode_subscribe(*x)),
    "session_info": (m.decode_session_info, encode_session_info),
    "load_reply": (m.decode_load_reply, encode_load_reply),
    "session_list": (m.decode_session_list, encode_session_list),
    "ack": (m.decode_ack, encode_ack),
    "brush": (decode_brush, lambda x: m.encode_brush(x.session_id, x.brush)),
    "brush_update": (decode_brush_update, lambda x: m.encode_brush_update(
        x.session_id, x.move, x.twist, x.scale, x.matrix)),
    "brush_param": (decode_brush_param, lambda x: m.encode_brush_param(*x)),
    "handles": (m.decode_handles, lambda h: m.encode_handles(h.session_id, h.energy, h.handles,
                                                             h.params, h.affine, h.options)),
    "handle_move": (decode_handle_move, lambda x: m.encode_handle_move(
        x.session_id, x.targets, x.max_iters, x.max_ms, x.progress_every, x.options)),
    "move_result": (m.decode_move_result, encode_move_result),
    "get_mesh": (_fixed("QI", "get_mesh"), lambda x: m.encode_get_mesh(*x)),
    "mesh_chunk": (st.decode_mesh_chunk, encode_mesh_chunk),
    "snapshot_req": (_fixed("QQ", "snapshot_req"), lambda x: m.encode_snapshot_req(*x)),
    "disp": (st.decode_disp, st.encode_disp),
    "progress": (st.decode_progress, encode_progress),
    "stats_req": (decode_stats_req, m.encode_stats_req),
    "stats": (m.decode_stats, encode_stats),
    "shm_info": (m.decode_shm_info, m.encode_shm_info),
    "shm_ref": (m.decode_shm_ref, lambda x: m.encode_shm_ref(*x)),
    "brush_state_set": (bs.decode_brush_state_set, lambda x: bs.encode_brush_state_set(*x)),
    "brush_state": (bs.decode_brush_state, bs.encode_brush_state),
    "brush_cursor": (bs.decode_brush_cursor, bs.encode_brush_cursor),
    # devices (HID)
    "device_info": (dv.decode_device_info, dv.encode_device_info),
    "device_list": (dv.decode_device_list, dv.encode_device_list),
    "device_bind": (dv.decode_device_bind, lambda x: dv.encode_device_bind(*x)),
    "device_view": (dv.decode_device_view, lambda x: dv.encode_device_view(
        x.device_id, x.session_id, x.view_proj, x.viewport)),
    # per-session access
    "session_access": (ac.decode_session_access, lambda x: ac.encode_session_access(
        x.session_id, x.mode, x.observers, x.flags)),
    "join": (ac.decode_join, lambda x: ac.encode_join(*x)),
    "access_info": (ac.decode_access_info, ac.encode_access_info),
    "work_progress": (pg.decode_work_progress, pg.encode_work_progress),
    # session peers
    "peer_list": (pr.decode_peer_list, pr.encode_peer_list),
    # negotiated stream encodings (PROTOCOL.md 4.40, 4.41)
    "qdisp": (se.decode_qdisp, encode_qdisp),
    "zframe": (decode_zframe, encode_zframe),
}


def decode_body(name: str, payload: bytes) -> Any:
    """The object of body `name` in `payload`; ProtocolError when it does not decode."""
    return BODY_CODECS[name][0](bytes(payload))


def encode_body(name: str, obj: Any) -> bytes:
    """The payload of body `name` holding `obj` (inverse of decode_body)."""
    return BODY_CODECS[name][1](obj)


def decode_frame_body(msg_type: int, flags: int, payload: bytes) -> Tuple[str, Any]:
    """(body name, object) of a frame's payload, the body chosen by (type, flags)."""
    name = schema.body_of(msg_type, flags)
    if name is None:
        raise ProtocolError("type 0x%04x with flags 0x%x has no body" % (msg_type, flags))
    return name, decode_body(name, payload)


__all__ = ["BODY_CODECS", "decode_body", "encode_body", "decode_frame_body", "Hello", "LoadMesh",
           "BrushBegin", "BrushUpdate", "HandleMove"]
