"""Every number of the deformd wire protocol as Python values: message types and their bodies,
flags, feature bits, enums (IntEnum / IntFlag), limits and defaults.

This mirrors proto/wire_schema.h, the one source of truth (and core/admm/admm_defaults.h for the
ADMM defaults); tests/integration/test_schema.py compiles a dump of those headers and fails on
any difference with this module or with the tables of proto/PROTOCOL.md. Edit the header first.
"""
from enum import IntEnum, IntFlag
from typing import Dict, NamedTuple, Optional

# ------------------------------------------------------------------ frame
FRAME_MAGIC = 0x444D4644
PROTO_VERSION = 1
FRAME_HEADER_SIZE = 24


class FrameFlag(IntFlag):
    REPLY = 1 << 0
    EVENT = 1 << 1
    ERROR = 1 << 2
    MORE = 1 << 3


# ------------------------------------------------------------------ shared-memory ring file (6.1)
SHM_MAGIC = b"DFSHMRG1"
SHM_HEADER_BYTES = 4096
SHM_MIN_CAPACITY = 4096
SHM_MAX_CAPACITY = 4 << 30

# ------------------------------------------------------------------ limits (reported in hello)
MAX_FRAME_PAYLOAD = 64 << 20
MAX_MESH_VERTICES = 8 << 20
MAX_MESH_ELEMENTS = 32 << 20
MAX_MESH_BYTES = 1 << 30
MAX_PENDING_REQUESTS = 64
MAX_SESSIONS = 1024
MAX_NAME_LEN = 255
MAX_PATH_LEN = 4095
MAX_ERROR_MSG_LEN = 255
MAX_AUTH_TOKEN = 4096
MAX_PING_BYTES = 65536
MAX_PINNED_POINTS = 2048
MAX_BRUSH_STEPS = 1024
MAX_FALLOFF = 8
MAX_HANDLES = 1 << 20
MAX_AFFINE_SETS = 64
MAX_ANDERSON = 20
MAX_MOVE_ITERS = 1000000
MAX_STATS_ENTRIES = 1024
MAX_STATS_KEY_LEN = 63
STREAM_CHUNK_BYTES = 16 << 20
MAX_DEVICES = 256              # devices (HID)
MAX_PEERS = 4096               # rows of a peer_list (SESSION_PEERS reply)

LIMITS: Dict[str, int] = {k: v for k, v in dict(globals()).items()
                          if k.startswith("MAX_") or k == "STREAM_CHUNK_BYTES"}


# ------------------------------------------------------------------ message types
class MsgType(IntEnum):
    HELLO = 0x0001
    AUTH = 0x0002
    PING = 0x0003
    LOAD_MESH = 0x0010
    LIST_SESSIONS = 0x0011
    OPEN_SESSION = 0x0012
    CLOSE_SESSION = 0x0013
    SUBSCRIBE = 0x0014
    UNSUBSCRIBE = 0x0015
    STREAM_SHM = 0x0016
    SESSION_ACCESS = 0x0017    # per-session access
    JOIN = 0x0018
    SESSION_PEERS = 0x0019     # who is connected to a session (4.38)
    BRUSH_BEGIN = 0x0020
    BRUSH_UPDATE = 0x0021
    BRUSH_END = 0x0022
    BRUSH_CANCEL = 0x0023
    SET_BRUSH_PARAM = 0x0024
    BRUSH_STATE_GET = 0x0025
    BRUSH_STATE_SET = 0x0026
    HANDLES_SET = 0x0030
    HANDLES_MOVE = 0x0031
    RESET_REST = 0x0032
    UNDO = 0x0033
    REDO = 0x0034
    HANDLES_GET = 0x0035
    GET_MESH = 0x0040
    SNAPSHOT = 0x0041
    STATS = 0x0042
    DEVICES_LIST = 0x0050      # devices (HID)
    DEVICE_BIND = 0x0051
    DEVICE_VIEW = 0x0052
    DISPLACEMENT = 0x0080
    PROGRESS = 0x0081
    SESSION_CLOSED = 0x0082
    SHM_REF = 0x0083
    BRUSH_STATE = 0x0084
    BRUSH_CURSOR = 0x0085
    DEVICE_STATE = 0x0086      # devices (HID)
    WORK_PROGRESS = 0x0087     # opt-in progress of long work (PROTOCOL.md 4.37)
    QDISP = 0x0088             # quantized version delta (stream encoding, PROTOCOL.md 4.40)
    ZFRAME = 0x0089            # zstd-compressed stream event (PROTOCOL.md 4.41)
    ERROR = 0x00FF


class Bodies(NamedTuple):
    """Body names (PROTOCOL.md section 4) of a type as a request, its reply and as an event;
    None where the type is not valid that way."""
    request: Optional[str]
    reply: Optional[str]
    event: Optional[str]


BODIES: Dict[MsgType, Bodies] = {
    MsgType.HELLO: Bodies("hello", "hello_reply", None),
    MsgType.AUTH: Bodies("auth", "auth", None),
    MsgType.PING: Bodies("ping", "ping", None),
    MsgType.LOAD_MESH: Bodies("load_mesh", "load_reply", None),
    MsgType.LIST_SESSIONS: Bodies("empty", "session_list", None),
    MsgType.OPEN_SESSION: Bodies("open_session", "session_info", None),
    MsgType.CLOSE_SESSION: Bodies("session_ref", "ack", None),
    MsgType.SUBSCRIBE: Bodies("subscribe", "session_info", None),
    MsgType.UNSUBSCRIBE: Bodies("session_ref", "ack", None),
    MsgType.STREAM_SHM: Bodies("session_ref", "shm_info", None),
    MsgType.SESSION_ACCESS: Bodies("session_access", "access_info", None),
    MsgType.JOIN: Bodies("join", "access_info", None),
    MsgType.SESSION_PEERS: Bodies("session_ref", "peer_list", None),
    MsgType.BRUSH_BEGIN: Bodies("brush", "ack", None),
    MsgType.BRUSH_UPDATE: Bodies("brush_update", "ack", None),
    MsgType.BRUSH_END: Bodies("session_ref", "ack", None),
    MsgType.BRUSH_CANCEL: Bodies("session_ref", "ack", None),
    MsgType.SET_BRUSH_PARAM: Bodies("brush_param", "ack", None),
    MsgType.BRUSH_STATE_GET: Bodies("session_ref", "brush_state", None),
    MsgType.BRUSH_STATE_SET: Bodies("brush_state_set", "brush_state", None),
    MsgType.HANDLES_SET: Bodies("handles", "ack", None),
    MsgType.HANDLES_MOVE: Bodies("handle_move", "move_result", None),
    MsgType.RESET_REST: Bodies("session_ref", "ack", None),
    MsgType.UNDO: Bodies("session_ref", "ack", None),
    MsgType.REDO: Bodies("session_ref", "ack", None),
    MsgType.HANDLES_GET: Bodies("session_ref", "handles", None),
    MsgType.GET_MESH: Bodies("get_mesh", "mesh_chunk", None),
    MsgType.SNAPSHOT: Bodies("snapshot_req", "disp", None),
    MsgType.STATS: Bodies("stats_req", "stats", None),
    MsgType.DISPLACEMENT: Bodies(None, None, "disp"),
    MsgType.PROGRESS: Bodies(None, None, "progress"),
    MsgType.SESSION_CLOSED: Bodies(None, None, "session_ref"),
    MsgType.SHM_REF: Bodies(None, None, "shm_ref"),
    MsgType.BRUSH_STATE: Bodies(None, None, "brush_state"),
    MsgType.BRUSH_CURSOR: Bodies(None, None, "brush_cursor"),
    # devices (HID)
    MsgType.DEVICES_LIST: Bodies("empty", "device_list", None),
    MsgType.DEVICE_BIND: Bodies("device_bind", "empty", None),
    MsgType.DEVICE_VIEW: Bodies("device_view", "empty", None),
    MsgType.DEVICE_STATE: Bodies(None, None, "device_info"),
    MsgType.WORK_PROGRESS: Bodies(None, None, "work_progress"),
    MsgType.QDISP: Bodies(None, None, "qdisp"),
    MsgType.ZFRAME: Bodies(None, None, "zframe"),
    MsgType.ERROR: Bodies(None, None, None),
}


def body_of(msg_type: int, flags: int) -> Optional[str]:
    """Body name selected by (type, flags) as df_msg_body_kind does: "error" with ERROR, else the
    reply / event / request body; None for an unknown type or a direction it does not have."""
    try:
        b = BODIES[MsgType(msg_type)]
    except ValueError:
        return None
    if flags & FrameFlag.ERROR:
        return "error"
    if flags & FrameFlag.REPLY:
        return b.reply
    if flags & FrameFlag.EVENT:
        return b.event
    return b.request


# ------------------------------------------------------------------ feature bits
class Feature(IntFlag):
    """hello_reply features: only what exists (HID: the daemon's device subsystem runs)."""
    KELVINLET = 1 << 0
    ADMM = 1 << 1
    PATH_LOAD = 1 << 2
    AUTH = 1 << 3
    SPARSE_STREAM = 1 << 4
    TCP = 1 << 5
    HID = 1 << 6
    SHM_STREAM = 1 << 7


# A bit of the client's HELLO features only (proto/wire_schema.h DF_HELLO_WANT_OWNERS): the client
# decodes the owners trailer of a session_list (PROTOCOL.md 4.10, cluster mode).
HELLO_WANT_OWNERS = 1 << 16


# ------------------------------------------------------------------ enums
class LoadSource(IntEnum):
    INLINE = 0
    PATH = 1


class LoadOpt(IntFlag):
    EXT = 0x0001      # a file_name follows the data; the reply is a load_reply (with a report)
    TWO_D = 0x0002    # C DF_LOAD_OPT_2D: a 2D session even if the file gives z (all z 0)
    PROGRESS = 0x0004  # WORK_PROGRESS events of the upload and the parse (PROTOCOL.md 4.37)


class Format(IntEnum):
    AUTO = 0
    OBJ = 1
    OFF = 2
    PLY = 3
    MEDIT = 4
    TETGEN = 5


class MeshKind(IntEnum):
    POLYLINE = 1
    TRIANGLE = 2
    TET = 3


class BrushType(IntEnum):
    GRAB = 1
    TWIST = 2
    SCALE = 3
    PINCH = 4
    AFFINE = 5


class Integrator(IntEnum):
    EULER = 1
    RK4 = 2


class BrushParam(IntEnum):
    RADIUS = 1
    NU = 2
    STRENGTH = 3
    FALLOFF = 4
    RATIO = 5


class Energy(IntEnum):
    ARAP = 1
    ACAP = 2
    NEOHOOKEAN = 3
    CLOTH = 4
    POLYLINE = 5


class ChangeKind(IntEnum):
    BRUSH = 1
    BRUSH_CANCEL = 2
    HANDLE_MOVE = 3
    UNDO = 4
    REDO = 5
    RESET_REST = 6
    SNAPSHOT = 7


class DispEncoding(IntEnum):
    DENSE = 1
    SPARSE = 2


class MoveStatus(IntEnum):
    RUNNING = 0
    CONVERGED = 1
    BUDGET = 2
    SUPERSEDED = 3
    FAILED = 4


class MeshSection(IntEnum):
    POSITIONS = 1
    BASE = 2
    REST = 3
    ELEMENTS = 4
    FACES = 5


class PinFlag(IntFlag):
    DISPLACEMENT = 1 << 0
    GRADIENT = 1 << 1


class GetMeshFlag(IntFlag):
    REST = 1 << 0
    BASE = 1 << 1


class SubscribeFlag(IntFlag):
    SNAPSHOT = 1 << 0
    FROM_VERSION = 1 << 1  # resync: a u64 from_version follows (PROTOCOL.md 6.2)


class BrushStateField(IntFlag):
    """DF_BS_*: fields of the session brush (brush_state_set mask, brush_state changed, brush
    use_session). INTEGRATOR covers integrator and steps; MIRROR has_mirror, point and normal."""
    TYPE = 1 << 0
    RADIUS = 1 << 1
    NU = 1 << 2
    STRENGTH = 1 << 3
    FALLOFF = 1 << 4
    RATIO = 1 << 5
    INTEGRATOR = 1 << 6
    MIRROR = 1 << 7


class Origin(IntEnum):
    """Who changed the session brush / moved a brush cursor."""
    NONE = 0
    CLIENT = 1
    DEVICE = 2


class CursorFlag(IntFlag):
    IN_RANGE = 1 << 0
    STROKE_ACTIVE = 1 << 1


# ------------------------------------------------------------------ devices (HID)
class DevClass(IntEnum):
    NONE = 0
    KNOB = 1
    MOUSE3D = 2
    PEN = 3


class DevBackend(IntEnum):
    HIDAPI = 1
    LIBUSB = 2
    REPLAY = 3


class DevState(IntEnum):
    OPEN = 1
    CLOSED = 2
    ERROR = 3
    UNPLUGGED = 4


class AuthMethod(IntEnum):
    """auth `method` (PROTOCOL.md 4.3): the two steps of the HMAC-SHA256 exchange."""
    HMAC_CHALLENGE = 1
    HMAC_PROOF = 2


class AccessMode(IntEnum):
    """access_info `mode` (PROTOCOL.md 4.34, 4.36)."""
    OPEN = 1
    KEY = 2
    OWNER = 3


class AccessFlag(IntFlag):
    """session_access `flags` (PROTOCOL.md 4.35)."""
    NEW_KEY = 1 << 0


JOIN_KEY_BYTES = 32      # DF_JOIN_KEY_BYTES: a session's join key


class PeerFlag(IntFlag):
    """peer_info `flags` (PROTOCOL.md 4.38)."""
    SELF = 1 << 0     # the connection that asked
    EDIT = 1 << 1     # its principal holds the edit right on the session
    SHM = 1 << 2      # it streams through the shared-memory ring


class Transport(IntEnum):
    """peer_info `transport` (PROTOCOL.md 4.38)."""
    UNIX = 1
    TCP = 2


class WorkStage(IntEnum):
    """work_progress `stage` (PROTOCOL.md 4.37). New stages are added at the end: a stage not
    listed here arrives as a plain int."""
    UPLOAD = 1        # load: bytes of the inline upload received
    PARSE = 2         # load: bytes of the mesh file parsed
    FACTORIZE = 3     # handles set / move: ADMM solver build (analysis, factorization)
    SOLVE = 4         # handles move: ADMM iterations of the budget


class WorkOpt(IntFlag):
    """handles / handle_move `options` (optional trailing u32)."""
    PROGRESS = 1 << 0  # WORK_PROGRESS events of this request
    KELVINLET_GUESS = 1 << 1  # handle_move: seed ADMM with the Kelvinlet guess
    POLISH = 1 << 2  # handle_move: projected Newton after ADMM (df_admm_polish)


class StreamEnc(IntFlag):
    """hello / hello_reply `stream_encoding` (optional trailer, PROTOCOL.md 4.2); 0 = exact."""
    QUANTIZED = 1 << 0  # QDISP events: deltas quantized to 2 x error_bound
    ZSTD = 1 << 1       # stream events may come as ZFRAME (zstd)


# the range of a quantized stream's error_bound (DF_STREAM_ERROR_LO / _HI)
STREAM_ERROR_LO = 1e-30
STREAM_ERROR_HI = 1e30


# The AUTH exchange's sizes and MAC contexts (DF_AUTH_* of wire_schema.h; auth.py uses them).
AUTH_NONCE_BYTES = 32
AUTH_MAC_BYTES = 32
AUTH_CONTEXT_CLIENT = b"deformd-auth-v1 client"
AUTH_CONTEXT_SERVER = b"deformd-auth-v1 server"


# ------------------------------------------------------------------ defaults
# The brush every client starts from (DF_WIRE_BRUSH_DEFAULTS); Brush() uses these.
BRUSH_DEFAULTS = {"type": BrushType.GRAB, "dim": 3, "falloff": 1, "integrator": Integrator.EULER,
                  "steps": 1, "radius": 1.0, "ratio": 1.1, "nu": 0.5, "strength": 1.0}

# The handle-set (ADMM) defaults of core/admm/admm_defaults.h; HandleParams uses these.
ADMM_DEFAULTS = {"w": 1e-4, "s": 0.01, "rho": 0.0, "tol": 1e-11, "max_iters": 500,
                 "youngs": 1e7, "poisson": 0.45, "area_weighting": 0, "accelerate": 0,
                 "anderson_m": 5, "strain_min": 0.9, "strain_max": 1.1, "bending": 1e-3}
ADMM_DEFAULTS_NEOHOOKEAN = {"w": 500.0}
