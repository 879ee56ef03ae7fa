"""The session brush (PROTOCOL.md 4.14a-4.14c): the brush_state_set request, the brush_state
body (reply to BRUSH_STATE_GET / BRUSH_STATE_SET and the BRUSH_STATE event) and the brush_cursor
event. Decoders check what the C decoders check (proto/msg_brush_state.c); every payload they
accept encodes back to the same bytes."""
import math
import struct
from dataclasses import dataclass
from typing import Dict, Optional, Sequence, Tuple

from . import schema
from .schema import BrushStateField, BrushType, CursorFlag, Integrator, Origin
from .wire import ProtocolError, Reader, pack_str, vec

BS_ALL = sum(BrushStateField)
CURSOR_FLAGS_ALL = sum(CursorFlag)
VALUES_STRUCT = struct.Struct("<BBBBH4d3d3d")
assert VALUES_STRUCT.size == 86
CURSOR_STRUCT = struct.Struct("<QBQB3dd")
assert CURSOR_STRUCT.size == 50

# keyword of Client.brush_state_set / deformctl option -> the field bit it sets
FIELD_BITS: Dict[str, BrushStateField] = {
    "type": BrushStateField.TYPE, "radius": BrushStateField.RADIUS, "nu": BrushStateField.NU,
    "strength": BrushStateField.STRENGTH, "falloff": BrushStateField.FALLOFF,
    "ratio": BrushStateField.RATIO, "integrator": BrushStateField.INTEGRATOR,
    "steps": BrushStateField.INTEGRATOR, "mirror": BrushStateField.MIRROR}


@dataclass
class BrushValues:
    """Every field of a session brush. type / integrator are lower-case names ("grab", "rk4");
    mirror_point / mirror_normal are carried even when has_mirror is 0."""
    type: str = schema.BRUSH_DEFAULTS["type"].name.lower()
    radius: float = schema.BRUSH_DEFAULTS["radius"]
    nu: float = schema.BRUSH_DEFAULTS["nu"]
    strength: float = schema.BRUSH_DEFAULTS["strength"]
    falloff: int = schema.BRUSH_DEFAULTS["falloff"]
    ratio: float = schema.BRUSH_DEFAULTS["ratio"]
    integrator: str = schema.BRUSH_DEFAULTS["integrator"].name.lower()
    steps: int = schema.BRUSH_DEFAULTS["steps"]
    has_mirror: int = 0
    mirror_point: Tuple[float, float, float] = (0.0, 0.0, 0.0)
    mirror_normal: Tuple[float, float, float] = (1.0, 0.0, 0.0)

    @property
    def mirror(self) -> Optional[Tuple[float, ...]]:
        """(px, py, pz, nx, ny, nz) when mirrored, else None."""
        return tuple(self.mirror_point) + tuple(self.mirror_normal) if self.has_mirror else None


@dataclass
class BrushState:
    """A session's brush as of change number `seq` (0: the defaults, never changed). changed:
    the BrushStateField bits of this change (0 in a get reply); origin: who made the (last)
    change, origin_id its connection or device id, origin_name its HELLO or device name."""
    session_id: int
    seq: int
    changed: BrushStateField
    origin: Origin
    origin_id: int
    origin_name: str
    values: BrushValues
    kind_name: str = "brush_state"

    def __getattr__(self, name):        # state.radius, state.nu, ... read the values
        if name in BrushValues.__dataclass_fields__ or name == "mirror":
            return getattr(self.values, name)
        raise AttributeError(name)


@dataclass
class BrushCursor:
    """Event: where `origin` points its brush (centre in mesh coordinates, radius); flags
    CursorFlag.IN_RANGE / STROKE_ACTIVE."""
    session_id: int
    origin: Origin
    origin_id: int
    flags: CursorFlag
    center: Tuple[float, float, float]
    radius: float
    kind_name: str = "brush_cursor"


_TYPES = {t.name.lower(): t for t in BrushType}
_INTEGS = {t.name.lower(): t for t in Integrator}


def _check(v: BrushValues, mask: int, what: str) -> None:
    """The ranges of proto/messages.h df_msg_brush_values for the fields in `mask`."""
    if mask & ~BS_ALL:
        raise ProtocolError("%s: field bits 0x%x are not defined" % (what, mask & ~BS_ALL))
    bad = None
    if mask & BrushStateField.TYPE and (isinstance(v.type, int) or v.type not in _TYPES):
        bad = "type %r" % (v.type,)
    elif mask & BrushStateField.RADIUS and not (math.isfinite(v.radius) and v.radius > 0):
        bad = "radius %r (finite, > 0)" % v.radius
    elif mask & BrushStateField.NU and math.isnan(v.nu):
        bad = "nu NaN"
    elif mask & BrushStateField.STRENGTH and not math.isfinite(v.strength):
        bad = "strength %r (finite)" % v.strength
    elif mask & BrushStateField.FALLOFF and not 1 <= v.falloff <= schema.MAX_FALLOFF:
        bad = "falloff %r (1..%d)" % (v.falloff, schema.MAX_FALLOFF)
    elif mask & BrushStateField.RATIO and not (math.isfinite(v.ratio) and v.ratio > 1):
        bad = "ratio %r (finite, > 1)" % v.ratio
    elif mask & BrushStateField.INTEGRATOR and (
            isinstance(v.integrator, int) or v.integrator not in _INTEGS
            or not 1 <= v.steps <= schema.MAX_BRUSH_STEPS):
        bad = "integrator %r / steps %r" % (v.integrator, v.steps)
    elif mask & BrushStateField.MIRROR and (
            v.has_mirror not in (0, 1)
            or not all(math.isfinite(x) for x in tuple(v.mirror_point) + tuple(v.mirror_normal))
            or (v.has_mirror and not any(v.mirror_normal))):
        bad = "mirror %r %r %r" % (v.has_mirror, v.mirror_point, v.mirror_normal)
    if bad:
        raise ProtocolError("%s: %s" % (what, bad))


def _num(names: dict, x) -> int:
    """The wire number of an enum name, or x itself when it is a raw number (a field outside a
    set's mask may carry any byte)."""
    return int(x) if isinstance(x, int) else int(names.get(x, 0))


def _pack_values(v: BrushValues) -> bytes:
    """Every field as it is (fields outside a set's mask are carried, not checked)."""
    return VALUES_STRUCT.pack(
        _num(_TYPES, v.type), int(v.falloff), _num(_INTEGS, v.integrator),
        int(v.has_mirror), int(v.steps), float(v.radius), float(v.nu), float(v.strength),
        float(v.ratio), *vec(v.mirror_point, 3, "mirror_point"),
        *vec(v.mirror_normal, 3, "mirror_normal"))


def _read_values(r: Reader) -> BrushValues:
    """The 86 value bytes; a type / integrator number outside its enum stays a number."""
    t, falloff, integ, has_mirror, steps, radius, nu, strength, ratio, *mr = r.take(
        VALUES_STRUCT.format.lstrip("<"))
    tnames = {int(x): k for k, x in _TYPES.items()}
    inames = {int(x): k for k, x in _INTEGS.items()}
    return BrushValues(tnames.get(t, t), radius, nu, strength, falloff, ratio,
                       inames.get(integ, integ), steps, has_mirror, tuple(mr[:3]),
                       tuple(mr[3:]))


def encode_brush_state_set(session_id: int, mask: int, v: BrushValues) -> bytes:
    if mask == 0:
        raise ValueError("brush_state_set: mask 0 sets nothing")
    _check(v, mask, "brush_state_set")
    return struct.pack("<QH", session_id, mask) + _pack_values(v)


def decode_brush_state_set(p: bytes) -> Tuple[int, int, BrushValues]:
    """(session_id, mask, values). Fields outside the mask are kept as they are."""
    r = Reader(p, "brush_state_set")
    sid, mask = r.take("QH")
    v = _read_values(r)
    r.end()
    if sid == 0 or mask == 0:
        raise ProtocolError("brush_state_set: session_id %d / mask %d" % (sid, mask))
    _check(v, mask, "brush_state_set")
    return sid, mask, v


def encode_brush_state(s: BrushState) -> bytes:
    _check(s.values, BS_ALL, "brush_state")
    return (struct.pack("<QQHBQ", s.session_id, s.seq, int(s.changed), int(s.origin),
                        s.origin_id) + pack_str(s.origin_name) + _pack_values(s.values))


def decode_brush_state(p: bytes) -> BrushState:
    r = Reader(p, "brush_state")
    sid, seq, changed, origin, origin_id = r.take("QQHBQ")
    name = r.str()
    v = _read_values(r)
    r.end()
    if sid == 0:
        raise ProtocolError("brush_state: session_id 0 is not a session")
    if changed & ~BS_ALL or origin not in set(int(o) for o in Origin):
        raise ProtocolError("brush_state: changed 0x%x / origin %d" % (changed, origin))
    _check(v, BS_ALL, "brush_state")
    return BrushState(sid, seq, BrushStateField(changed), Origin(origin), origin_id, name, v)


def encode_brush_cursor(c: BrushCursor) -> bytes:
    return CURSOR_STRUCT.pack(c.session_id, int(c.origin), c.origin_id, int(c.flags),
                              *vec(c.center, 3, "center"), float(c.radius))


def decode_brush_cursor(p: bytes) -> BrushCursor:
    r = Reader(p, "brush_cursor")
    sid, origin, origin_id, flags, x, y, z, radius = r.take(CURSOR_STRUCT.format.lstrip("<"))
    r.end()
    if sid == 0 or origin not in set(int(o) for o in Origin) or flags & ~CURSOR_FLAGS_ALL:
        raise ProtocolError("brush_cursor: session_id %d / origin %d / flags 0x%x"
                            % (sid, origin, flags))
    if not all(math.isfinite(a) for a in (x, y, z)) or not (math.isfinite(radius)
                                                            and radius > 0):
        raise ProtocolError("brush_cursor: centre (%r, %r, %r) / radius %r" % (x, y, z, radius))
    return BrushCursor(sid, Origin(origin), origin_id, CursorFlag(flags), (x, y, z), radius)


def values_with(base: BrushValues, **fields) -> Tuple[int, BrushValues]:
    """(mask, values): `base` with the keyword fields of Client.brush_state_set replaced
    (type, radius, nu, strength, falloff, ratio, integrator, steps, mirror: None for off or
    (px, py, pz, nx, ny, nz)). integrator and steps are one field on the wire: the one not
    given keeps base's value. TypeError for an unknown keyword."""
    v = BrushValues(**{k: getattr(base, k) for k in BrushValues.__dataclass_fields__})
    mask = 0
    for k, x in fields.items():
        if k not in FIELD_BITS:
            raise TypeError("unknown brush state field %r (fields: %s)"
                            % (k, ", ".join(FIELD_BITS)))
        mask |= FIELD_BITS[k]
        if k == "mirror":
            m6: Sequence[float] = vec(x, 6, "mirror") if x is not None else (0, 0, 0, 1, 0, 0)
            v.has_mirror = 1 if x is not None else 0
            v.mirror_point, v.mirror_normal = tuple(m6[:3]), tuple(m6[3:])
        elif k in ("type", "integrator"):
            setattr(v, k, str(x).lower())
        elif k in ("falloff", "steps"):
            setattr(v, k, int(x))
        else:
            setattr(v, k, float(x))
    return mask, v
