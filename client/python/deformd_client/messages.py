"""Message types and body codecs of the deformd protocol (proto/messages.h, proto/msg_*.c).

Encoders return the payload bytes (no frame header); decoders take one whole payload and return
a plain object (a dataclass), raising ProtocolError on a short, long or inconsistent body.
Wire: little-endian; strings are u16 length + UTF-8 bytes; positions/displacements float32,
parameters float64; vertex indices u32.
"""
import struct
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Sequence, Tuple

from . import schema
from .schema import SHM_HEADER_BYTES, SHM_MAGIC, SHM_MIN_CAPACITY  # noqa: F401
from .schema import (MAX_AFFINE_SETS, MAX_HANDLES, MAX_PATH_LEN, BrushParam,  # noqa: F401
                     BrushType, ChangeKind, DispEncoding, Energy, Feature, Format, GetMeshFlag,
                     Integrator, LoadOpt, LoadSource, WorkOpt, MeshKind, MeshSection, MoveStatus, MsgType,
                     PinFlag, StreamEnc, SubscribeFlag)
from .wire import ProtocolError, Reader, enum_value, f64_rows, pack_str, u32_array, vec

# ------------------------------------------------------------------ numbers (schema.py)
# Every wire number lives in schema.py (mirror of proto/wire_schema.h, checked by a test); the
# flat names below (HELLO, MAX_FALLOFF, FEAT_TCP, CHANGE_UNDO, ...) are aliases of its members.
globals().update({t.name: t for t in MsgType})
TYPE_NAMES = {int(t): t.name.lower() for t in MsgType}
globals().update(schema.LIMITS)
LOAD_CHUNK_BYTES = 8 << 20     # bytes of mesh data per load chunk this client sends

globals().update({"FEAT_" + f.name: f for f in Feature})
globals().update({"FMT_" + f.name: f for f in Format})
FORMAT_BY_EXT = {".obj": Format.OBJ, ".off": Format.OFF, ".ply": Format.PLY,
                 ".mesh": Format.MEDIT, ".node": Format.TETGEN}
LOAD_INLINE, LOAD_PATH = LoadSource.INLINE, LoadSource.PATH
LOAD_OPT_EXT = LoadOpt.EXT       # load_mesh options: file_name follows; reply has a LoadReport
LOAD_OPT_2D = LoadOpt.TWO_D      # load_mesh options: a 2D session even if the file gives z
LOAD_OPT_PROGRESS = LoadOpt.PROGRESS  # load_mesh options: WORK_PROGRESS events (4.37)
LOAD_OPTS_ALL = LOAD_OPT_EXT | LOAD_OPT_2D | LOAD_OPT_PROGRESS

BRUSH_TYPES = {t.name.lower(): t for t in BrushType}
INTEGRATORS = {t.name.lower(): t for t in Integrator}
BRUSH_PARAMS = {t.name.lower(): t for t in BrushParam}
ENERGIES = {t.name.lower(): t for t in Energy}

globals().update({"CHANGE_" + k.name: k for k in ChangeKind})
CHANGE_NAMES = {int(k): k.name.lower() for k in ChangeKind}
DISP_DENSE, DISP_SPARSE = DispEncoding.DENSE, DispEncoding.SPARSE
globals().update({"MOVE_" + k.name: k for k in MoveStatus})
MOVE_STATUS_NAMES = {int(k): k.name.lower() for k in MoveStatus}
globals().update({"SECTION_" + k.name: k for k in MeshSection})
GET_MESH_REST, GET_MESH_BASE = GetMeshFlag.REST, GetMeshFlag.BASE
SUBSCRIBE_SNAPSHOT = SubscribeFlag.SNAPSHOT
STREAM_ENC_QUANTIZED, STREAM_ENC_ZSTD = StreamEnc.QUANTIZED, StreamEnc.ZSTD
# `deformctl watch --encoding` / Client(encoding=...) names of the stream encodings
STREAM_ENCODINGS = {"exact": 0, "quantized": StreamEnc.QUANTIZED, "zstd": StreamEnc.ZSTD,
                    "quantized+zstd": StreamEnc.QUANTIZED | StreamEnc.ZSTD}
SUBSCRIBE_FROM_VERSION = SubscribeFlag.FROM_VERSION
ELEM_SIZE = {MeshKind.POLYLINE: 2, MeshKind.TRIANGLE: 3, MeshKind.TET: 4}


# ------------------------------------------------------------------ bodies
@dataclass
class HelloReply:
    version: int
    server_max_version: int
    features: int
    max_frame_payload: int
    max_mesh_vertices: int
    max_mesh_elements: int
    max_pending_requests: int
    max_sessions: int
    max_mesh_bytes: int
    max_client_queue_bytes: int
    auth_required: int
    server_name: str
    has_stream: bool = False        # the optional stream-encoding trailer was present (4.2b)
    stream_encoding: int = 0        # StreamEnc bits granted (0: exact float32)
    error_bound: float = 0.0        # QUANTIZED: the absolute error bound E, mesh units


def check_stream_encoding(encoding: int, error_bound: float, msg: str = "hello") -> None:
    """Raises ValueError unless (encoding, error_bound) is a valid stream encoding request
    (PROTOCOL.md 4.2): StreamEnc bits only; with QUANTIZED a finite bound in
    [STREAM_ERROR_LO, STREAM_ERROR_HI], without it 0."""
    if encoding & ~int(StreamEnc.QUANTIZED | StreamEnc.ZSTD):
        raise ValueError("%s: unknown stream_encoding bits 0x%x" % (msg, encoding))
    if encoding & StreamEnc.QUANTIZED:
        if not (schema.STREAM_ERROR_LO <= error_bound <= schema.STREAM_ERROR_HI):
            raise ValueError("%s: error_bound %r of a quantized stream must be finite and in "
                             "[%g, %g] mesh units" % (msg, error_bound, schema.STREAM_ERROR_LO,
                                                      schema.STREAM_ERROR_HI))
    elif error_bound != 0:
        raise ValueError("%s: error_bound %r without QUANTIZED must be 0" % (msg, error_bound))


def encode_hello(min_version: int = 1, max_version: int = 1, features: int = 0,
                 client_name: str = "", stream_encoding: Optional[int] = None,
                 error_bound: float = 0.0) -> bytes:
    """stream_encoding None: no trailer (the original layout, exact stream); else the
    10-byte trailer u8 stream_encoding, u8 reserved, f64 error_bound (PROTOCOL.md 4.2)."""
    out = struct.pack("<HHI", min_version, max_version, features) + pack_str(client_name)
    if stream_encoding is not None:
        out += struct.pack("<BBd", stream_encoding, 0, error_bound)
    return out


def decode_hello_reply(p: bytes) -> HelloReply:
    r = Reader(p, "hello_reply")
    v = r.take("HHIIIIIIQQBB")
    name = r.str()
    trailer = None
    if r.off < len(r.p):
        trailer = r.take("BBd")
    r.end()
    if v[10] > 1 or v[11]:
        raise ProtocolError("hello_reply: auth_required %d / reserved %d" % (v[10], v[11]))
    h = HelloReply(v[0], v[1], Feature(v[2]), *v[3:11], server_name=name)
    if trailer is not None:
        if trailer[1]:
            raise ProtocolError("hello_reply: reserved %d is not 0" % trailer[1])
        try:
            check_stream_encoding(trailer[0], trailer[2], "hello_reply")
        except ValueError as e:
            raise ProtocolError(str(e)) from None
        h.has_stream, h.stream_encoding, h.error_bound = True, StreamEnc(trailer[0]), trailer[2]
    return h


def encode_auth(method: int, token: bytes) -> bytes:
    return struct.pack("<HHI", method, 0, len(token)) + bytes(token)


def decode_auth(p: bytes) -> Tuple[int, bytes]:
    """An auth body (request or reply, PROTOCOL.md 4.3): (method, token)."""
    r = Reader(p, "auth")
    method, reserved, n = r.take("HHI")
    if reserved:
        raise ProtocolError("auth: reserved %d is not 0" % reserved)
    if n > schema.LIMITS["MAX_AUTH_TOKEN"]:
        raise ProtocolError("auth: token of %d bytes exceeds %d"
                            % (n, schema.LIMITS["MAX_AUTH_TOKEN"]))
    token = r.raw(n)
    r.end()
    return method, token


def decode_error(p: bytes):
    """Returns (code, message); bytes of the message that are not UTF-8 read as U+FFFD."""
    r = Reader(p, "error")
    code = r.take("i")
    msg = r.text()
    r.end()
    return code, msg


def encode_load_mesh(source: int, fmt: int, name: str, path: str, total_size: int,
                     part2_offset: int, offset: int, data: bytes, options: int = 0,
                     file_name: str = "") -> bytes:
    """options LOAD_OPT_EXT appends file_name (the user's file, for messages and the default
    session name) and asks for a load_reply with the reader's report."""
    body = (struct.pack("<BBHQQQ", source, fmt, options, total_size, part2_offset, offset)
            + pack_str(name) + pack_str(path) + struct.pack("<I", len(data)) + bytes(data))
    if options & LOAD_OPT_EXT:
        body += pack_str(file_name)
    return body


def encode_session_ref(session_id: int) -> bytes:
    return struct.pack("<Q", session_id)


def decode_session_ref(p: bytes) -> int:
    r = Reader(p, "session_ref")
    sid = r.take("Q")
    r.end()
    return sid


def encode_open_session(session_id: int = 0, name: str = "") -> bytes:
    return struct.pack("<Q", session_id) + pack_str(name)


def encode_subscribe(session_id: int, flags: int = 0, from_version: int = 0) -> bytes:
    """flags SUBSCRIBE_FROM_VERSION appends the u64 from_version (PROTOCOL.md 4.8)."""
    if flags & SUBSCRIBE_FROM_VERSION:
        return struct.pack("<QIQ", session_id, flags, from_version)
    if from_version:
        raise ValueError("from_version without flag SUBSCRIBE_FROM_VERSION")
    return struct.pack("<QI", session_id, flags)


@dataclass
class SessionInfo:
    session_id: int
    version: int
    kind: int
    planar: int
    subscribers: int
    nv: int
    ne: int
    undo_depth: int
    redo_depth: int
    name: str
    report: Optional["LoadReport"] = None   # LOAD_MESH with LOAD_OPT_EXT only
    owner: Optional[str] = None   # LIST_SESSIONS of a cluster daemon: the owner's host:port
                                  # ("" while no daemon holds it; PROTOCOL.md 4.10)


@dataclass
class LoadReport:
    """What the daemon's reader found in a loaded file (PROTOCOL.md 4.9b)."""
    format: int
    index_base: int
    input_polygons: int
    polygons_triangulated: int
    dropped_elements: int
    duplicate_elements: int
    degenerate_elements: int
    inverted_elements: int
    nonmanifold_edges: int
    nonmanifold_faces: int
    boundary_edges: int
    boundary_faces: int
    unused_vertices: int


def _read_session_info(r: Reader) -> SessionInfo:
    sid, ver, kind, *rest = r.take("QQBBHIIII")
    return SessionInfo(sid, ver, enum_value(MeshKind, kind, "session_info: kind"), *rest,
                       name=r.str())


def decode_session_info(p: bytes) -> SessionInfo:
    r = Reader(p, "session_info")
    s = _read_session_info(r)
    r.end()
    return s


def decode_load_reply(p: bytes) -> SessionInfo:
    """LOAD_MESH reply: session_info, then (LOAD_OPT_EXT) the 48-byte report in .report."""
    r = Reader(p, "load_reply")
    s = _read_session_info(r)
    if r.off < len(p):
        fmt, base, reserved = r.take("BBH")
        if reserved:
            raise ProtocolError("load_reply: reserved field is not 0")
        s.report = LoadReport(fmt, base, *r.take("11I"))
    r.end()
    return s


class SessionList(list):
    """A decoded session_list: a list of SessionInfo; has_owners is True when the body carried
    the owners trailer (PROTOCOL.md 4.10; also for an empty list, so it re-encodes exactly)."""
    has_owners: bool = False


def decode_session_list(p: bytes) -> List[SessionInfo]:
    """The list, and (a cluster daemon, to a client whose HELLO set HELLO_WANT_OWNERS) the
    owners trailer into each item's .owner (SessionList.has_owners)."""
    r = Reader(p, "session_list")
    n = r.take("I")
    out = SessionList(_read_session_info(r) for _ in range(n))
    if r.off < len(p):
        out.has_owners = True
        if r.take("I") != n:
            raise ProtocolError("session_list: owners trailer count is not the list's")
        for s in out:
            if r.take("Q") != s.session_id:
                raise ProtocolError("session_list: owners trailer out of order")
            s.owner = r.str()
    r.end()
    return out


@dataclass
class Ack:
    session_id: int
    version: int


def decode_ack(p: bytes) -> Ack:
    r = Reader(p, "ack")
    v = r.take("QQ")
    r.end()
    return Ack(*v)


@dataclass
class Brush:
    """Every Kelvinlet brush parameter of a stroke (proto/messages.h df_msg_brush)."""
    type: str = schema.BRUSH_DEFAULTS["type"].name.lower()
    center: Sequence[float] = (0.0, 0.0, 0.0)
    move: Optional[Sequence[float]] = None
    twist: Optional[Sequence[float]] = None
    scale: float = 0.0
    matrix: Optional[Sequence[float]] = None
    radius: float = schema.BRUSH_DEFAULTS["radius"]
    nu: float = schema.BRUSH_DEFAULTS["nu"]
    strength: float = schema.BRUSH_DEFAULTS["strength"]
    falloff: int = schema.BRUSH_DEFAULTS["falloff"]
    ratio: float = schema.BRUSH_DEFAULTS["ratio"]
    dim: int = schema.BRUSH_DEFAULTS["dim"]
    integrator: str = schema.BRUSH_DEFAULTS["integrator"].name.lower()
    steps: int = schema.BRUSH_DEFAULTS["steps"]
    moving: bool = False
    mirror: Optional[Sequence[float]] = None   # (px, py, pz, nx, ny, nz)
    pinned: Sequence[Sequence[float]] = field(default_factory=list)
    pin_flags: int = 0   # PIN_* bits; 0 = PIN_DISPLACEMENT when points are pinned
    # BrushStateField bits: take these fields from the session brush (brush_state_set) instead
    # of the values above. None: the field is not sent (the original layout, old daemons).
    use_session: Optional[int] = None
    # WorkOpt bits (PROGRESS: WORK_PROGRESS of the pinned points' LU), sent after use_session
    # (then written as 0 when None). None: not sent. Client.brush_begin(progress=) sets it.
    options: Optional[int] = None
    # 1: surface-aware (attenuated by the distance along the mesh; disconnected parts stay at
    # rest). None: not sent (old daemons); sending it also sends use_session and options (0 when None).
    surface: Optional[int] = None


PIN_DISPLACEMENT, PIN_GRADIENT = PinFlag.DISPLACEMENT, PinFlag.GRADIENT
BRUSH_STRUCT = struct.Struct("<QBBBBHBB4d3d3d3dd9d3d3dIB")
assert BRUSH_STRUCT.size == 253


def encode_brush(session_id: int, b: Brush) -> bytes:
    if b.type not in BRUSH_TYPES:
        raise ValueError("brush type %r not one of %s" % (b.type, sorted(BRUSH_TYPES)))
    if b.integrator not in INTEGRATORS:
        raise ValueError("integrator %r not one of %s" % (b.integrator, sorted(INTEGRATORS)))
    mirror = vec(b.mirror, 6, "mirror") if b.mirror is not None else [0.0] * 6
    pin_flags = (b.pin_flags or PIN_DISPLACEMENT) if len(b.pinned) else 0
    head = BRUSH_STRUCT.pack(
        session_id, BRUSH_TYPES[b.type], b.dim, b.falloff, INTEGRATORS[b.integrator], b.steps,
        1 if b.moving else 0, 1 if b.mirror is not None else 0,
        float(b.radius), float(b.ratio), float(b.nu), float(b.strength),
        *vec(b.center, 3, "center"), *vec(b.move, 3, "move"), *vec(b.twist, 3, "twist"),
        float(b.scale), *vec(b.matrix, 9, "matrix"), *mirror, len(b.pinned), pin_flags)
    opts = b.options is not None or b.surface is not None
    tail = b"" if b.use_session is None and not opts else \
        struct.pack("<H", int(b.use_session or 0))
    if opts:
        tail += struct.pack("<I", int(b.options or 0))
    if b.surface is not None:
        tail += struct.pack("<B", int(b.surface))
    return head + f64_rows(b.pinned, "pinned point") + tail


def encode_brush_update(session_id: int, move=None, twist=None, scale: float = 0.0,
                        matrix=None) -> bytes:
    return struct.pack("<Q3d3dd9d", session_id, *vec(move, 3, "move"), *vec(twist, 3, "twist"),
                       float(scale), *vec(matrix, 9, "matrix"))


def encode_brush_param(session_id: int, param: str, value: float) -> bytes:
    if param not in BRUSH_PARAMS:
        raise ValueError("brush parameter %r not one of %s" % (param, sorted(BRUSH_PARAMS)))
    return struct.pack("<QBd", session_id, BRUSH_PARAMS[param], float(value))


@dataclass
class AffineSet:
    """Rows of A V_t = b for every vertex t in indices (1..3 rows of 3 numbers)."""
    A: Sequence[Sequence[float]]
    b: Sequence[float]
    indices: Sequence[int]


@dataclass
class HandleParams:
    """Solver settings of a handle set (proto/PROTOCOL.md 4.15). for_energy() gives the
    reference defaults (df_msg_handles_defaults)."""
    w: float = schema.ADMM_DEFAULTS["w"]
    s: float = schema.ADMM_DEFAULTS["s"]
    rho: float = schema.ADMM_DEFAULTS["rho"]
    tol: float = schema.ADMM_DEFAULTS["tol"]
    max_iters: int = schema.ADMM_DEFAULTS["max_iters"]
    youngs: float = schema.ADMM_DEFAULTS["youngs"]
    poisson: float = schema.ADMM_DEFAULTS["poisson"]
    strain_min: float = schema.ADMM_DEFAULTS["strain_min"]
    strain_max: float = schema.ADMM_DEFAULTS["strain_max"]
    bending: float = schema.ADMM_DEFAULTS["bending"]
    area_weighting: bool = bool(schema.ADMM_DEFAULTS["area_weighting"])
    accelerate: bool = bool(schema.ADMM_DEFAULTS["accelerate"])
    anderson_m: int = schema.ADMM_DEFAULTS["anderson_m"]

    @classmethod
    def for_energy(cls, energy: str, **overrides) -> "HandleParams":
        p = cls(**schema.ADMM_DEFAULTS_NEOHOOKEAN) if energy == "neohookean" else cls()
        for k, v in overrides.items():
            if v is not None:
                if not hasattr(p, k):
                    raise TypeError("unknown handle parameter %r" % k)
                setattr(p, k, v)
        return p


HANDLES_STRUCT = struct.Struct("<QBBBB9dII")
assert HANDLES_STRUCT.size == 92


def encode_handles(session_id: int, energy: str, handles: Sequence[int], p: HandleParams,
                   affine: Sequence[AffineSet] = (), options: Optional[int] = None) -> bytes:
    """options: WorkOpt bits (PROGRESS: WORK_PROGRESS events), the optional trailing field:
    None leaves it out (the original layout), an int (0 too) appends it."""
    if energy not in ENERGIES:
        raise ValueError("energy %r not one of %s" % (energy, sorted(ENERGIES)))
    out = [HANDLES_STRUCT.pack(session_id, ENERGIES[energy], 1 if p.area_weighting else 0,
                               1 if p.accelerate else 0, p.anderson_m, float(p.w), float(p.s),
                               float(p.rho), float(p.tol), float(p.youngs), float(p.poisson),
                               float(p.strain_min), float(p.strain_max), float(p.bending),
                               p.max_iters, len(handles)),
           u32_array(handles), struct.pack("<I", len(affine))]
    for a in affine:
        rows = len(a.A)
        if len(a.b) != rows:
            raise ValueError("affine set: %d rows of A but %d entries of b" % (rows, len(a.b)))
        out.append(struct.pack("<B", rows) + f64_rows(a.A, "affine row")
                   + struct.pack("<%dd" % rows, *[float(x) for x in a.b])
                   + struct.pack("<I", len(a.indices)) + u32_array(a.indices))
    if options is not None:
        out.append(struct.pack("<I", options))
    return b"".join(out)


@dataclass
class HandleSet:
    """A session's handle set as returned by Client.get_handles (HANDLES_GET reply, the handles
    body of PROTOCOL.md 4.15): energy name, every parameter, the handle vertex indices in handle
    order (the order move targets follow) and the affine constraint sets."""
    session_id: int
    energy: str
    params: HandleParams
    handles: List[int]
    affine: List[AffineSet]
    options: Optional[int] = None   # WorkOpt bits of a HANDLES_SET request; None: field absent
                                    # (always so in a HANDLES_GET reply)


ENERGY_NAMES = {v: k for k, v in ENERGIES.items()}


def _count(r: Reader, what: str, limit: int) -> int:
    n = r.take("I")
    if n > limit:
        raise ProtocolError("%s: %s %d exceeds limit %d" % (r.what, what, n, limit))
    return n


def decode_handles(p: bytes) -> HandleSet:
    """Inverse of encode_handles; ProtocolError on a truncated/trailing body or a bad enum."""
    r = Reader(p, "handles")
    v = r.take(HANDLES_STRUCT.format.lstrip("<"))
    (session_id, energy, area, accel, anderson_m, w, s, rho, tol, youngs, poisson, smin, smax,
     bending, max_iters, nh) = v
    if energy not in ENERGY_NAMES:
        raise ProtocolError("handles: energy %d not in 1..%d" % (energy, len(ENERGIES)))
    if area > 1 or accel > 1:
        raise ProtocolError("handles: area_weighting %d / accelerate %d not 0 or 1"
                            % (area, accel))
    if nh > MAX_HANDLES:
        raise ProtocolError("handles: n_handles %d exceeds limit %d" % (nh, MAX_HANDLES))
    handles = list(r.farray("I", nh))
    affine: List[AffineSet] = []
    for _ in range(_count(r, "n_affine", MAX_AFFINE_SETS)):
        rows = r.take("B")
        if not 1 <= rows <= 3:
            raise ProtocolError("handles: affine rows %d not in 1..3" % rows)
        A = [list(r.take("3d")) for _ in range(rows)]
        b = [r.take("d") for _ in range(rows)]
        idx = list(r.farray("I", _count(r, "affine n_indices", MAX_HANDLES)))
        affine.append(AffineSet(A=A, b=b, indices=idx))
    options = _read_options(r, "handles")
    r.end()
    params = HandleParams(w=w, s=s, rho=rho, tol=tol, max_iters=max_iters, youngs=youngs,
                          poisson=poisson, strain_min=smin, strain_max=smax, bending=bending,
                          area_weighting=bool(area), accelerate=bool(accel),
                          anderson_m=anderson_m)
    return HandleSet(session_id, ENERGY_NAMES[energy], params, handles, affine, options)


def _read_options(r: Reader, what: str) -> Optional[int]:
    """The optional trailing u32 `options` (WorkOpt bits) of handles / handle_move, read as the
    C decoder does: None when the body ends (absent); unknown bits are a ProtocolError."""
    left = len(r.p) - r.off
    if left == 0 or left > 4:
        return None     # absent, or trailing bytes r.end() refuses
    o = r.take("I")     # 1..3 bytes: a cut field (truncated)
    if o & ~int(WorkOpt.PROGRESS):
        raise ProtocolError("%s: options 0x%x has unknown bits" % (what, o))
    return o


def encode_handle_move(session_id: int, targets: Sequence[Sequence[float]], max_iters: int = 0,
                       max_ms: int = 0, progress_every: int = 0,
                       options: Optional[int] = None) -> bytes:
    """options: WorkOpt bits (PROGRESS: WORK_PROGRESS events), as in encode_handles."""
    return (struct.pack("<QIIII", session_id, max_iters, max_ms, progress_every, len(targets))
            + f64_rows(targets, "target")
            + (struct.pack("<I", options) if options is not None else b""))


@dataclass
class MoveResult:
    session_id: int
    version: int
    status: int
    iterations: int
    objective: float
    residual: float
    elapsed_ms: float

    @property
    def status_name(self) -> str:
        return MOVE_STATUS_NAMES.get(self.status, "unknown")


def decode_move_result(p: bytes) -> MoveResult:
    r = Reader(p, "move_result")
    sid, ver, status, *rest = r.take("QQBIddd")
    r.end()
    return MoveResult(sid, ver, enum_value(MoveStatus, status, "move_result: status"), *rest)


def encode_get_mesh(session_id: int, flags: int = 0) -> bytes:
    return struct.pack("<QI", session_id, flags)


def encode_snapshot_req(session_id: int, version: int = 0) -> bytes:
    return struct.pack("<QQ", session_id, version)


def encode_stats_req(session_id: int = 0) -> bytes:
    return struct.pack("<Q", session_id)


def decode_stats(p: bytes) -> Dict[str, float]:
    r = Reader(p, "stats")
    n = r.take("I")
    out: Dict[str, float] = {}
    for _ in range(n):
        k = r.str()
        if k in out:
            raise ProtocolError("stats: key %r twice" % k)
        out[k] = r.take("d")
    r.end()
    return out


# ------------------------------------------------------------------ shared-memory stream (6.1)
SHM_REF_STRUCT = struct.Struct("<QQII")
assert SHM_REF_STRUCT.size == 24


@dataclass
class ShmInfo:
    """STREAM_SHM reply (PROTOCOL.md 4.24): the session's ring file and which event frames go
    through it (those whose whole length, header included, is in [min_frame, max_frame])."""
    session_id: int
    capacity: int
    min_frame: int
    max_frame: int
    path: str


def decode_shm_info(p: bytes) -> ShmInfo:
    """ProtocolError on a truncated/trailing body, session id 0, capacity below 4096, frame
    bounds not min_frame <= max_frame <= capacity, or a path that is not 1..4095 bytes of
    NUL-free UTF-8 starting with '/'."""
    r = Reader(p, "shm_info")
    sid, capacity, min_frame, max_frame = r.take("QQII")
    n = r.take("H")
    raw = r.raw(n)
    r.end()
    if sid == 0:
        raise ProtocolError("shm_info: session_id 0 is not a session")
    if capacity < SHM_MIN_CAPACITY:
        raise ProtocolError("shm_info: capacity %d below %d" % (capacity, SHM_MIN_CAPACITY))
    if not min_frame <= max_frame <= capacity:
        raise ProtocolError("shm_info: frame bounds %d..%d not within capacity %d"
                            % (min_frame, max_frame, capacity))
    if not 1 <= n <= MAX_PATH_LEN:
        raise ProtocolError("shm_info: path of %d bytes not in 1..%d" % (n, MAX_PATH_LEN))
    try:
        path = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        raise ProtocolError("shm_info: path is not UTF-8 (%s)" % e) from None
    if "\0" in path or not path.startswith("/"):
        raise ProtocolError("shm_info: path %r is not an absolute path" % path)
    return ShmInfo(sid, capacity, min_frame, max_frame, path)


def encode_shm_info(info: ShmInfo) -> bytes:
    """Body of a STREAM_SHM reply (used by tests to forge replies)."""
    return (struct.pack("<QQII", info.session_id, info.capacity, info.min_frame, info.max_frame)
            + pack_str(info.path))


def encode_shm_ref(session_id: int, position: int, length: int) -> bytes:
    """Body of an SHM_REF event (used by tests to forge stream frames)."""
    return SHM_REF_STRUCT.pack(session_id, position, length, 0)


def decode_shm_ref(p: bytes) -> Tuple[int, int, int]:
    """SHM_REF body (PROTOCOL.md 4.25) -> (session_id, position, length). ProtocolError on a
    truncated/trailing body, a non-zero reserved field, session id 0 or length below 24 (a
    frame header)."""
    r = Reader(p, "shm_ref")
    sid, position, length, reserved = r.take("QQII")
    r.end()
    if reserved != 0:
        raise ProtocolError("shm_ref: reserved field %d" % reserved)
    if sid == 0:
        raise ProtocolError("shm_ref: session_id 0 is not a session")
    if length < 24:
        raise ProtocolError("shm_ref: length %d shorter than a frame header" % length)
    return sid, position, length
