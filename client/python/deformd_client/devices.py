"""Device (HID) bodies of the deformd protocol (PROTOCOL.md 4.30..4.33, proto/msg_device.c):
device_info (a DEVICES_LIST item and the DEVICE_STATE event), device_list, device_bind and
device_view. Encoders return payload bytes; decoders take one whole payload and raise
ProtocolError on a short, long or inconsistent body."""
import math
import struct
from dataclasses import dataclass
from typing import List, Sequence

from . import schema
from .schema import DevBackend, DevClass, DevState
from .wire import ProtocolError, Reader, enum_value, pack_str

DEVICE_INFO_FIXED = "QBBBBHHQQB"      # then str name, str path, str error
CLASS_NAMES = {DevClass.NONE: "none", DevClass.KNOB: "knob", DevClass.MOUSE3D: "3d-mouse",
               DevClass.PEN: "pen"}


@dataclass
class DeviceInfo:
    device_id: int
    dev_class: int          # DevClass
    backend: int            # DevBackend
    state: int              # DevState
    bus: int                # linux/input.h bus: 3 USB, 5 Bluetooth, 0x18 I2C
    vid: int
    pid: int
    bound_session: int      # 0: follows the most recently active session
    active_session: int     # the session it drives now, 0 none
    haptics: int            # 0/1
    name: str
    path: str
    error: str

    kind_name = "device_state"   # as a DEVICE_STATE event (Client.events())

    @property
    def class_name(self) -> str:
        """"knob", "3d-mouse", "pen" or "none" (the names of listings and config)."""
        return CLASS_NAMES[DevClass(self.dev_class)]

    @property
    def state_name(self) -> str:
        return DevState(self.state).name.lower()

    @property
    def backend_name(self) -> str:
        return DevBackend(self.backend).name.lower()


def _read_info(r: Reader) -> DeviceInfo:
    did, cls, backend, state, bus, vid, pid, bound, active, haptics = r.take(DEVICE_INFO_FIXED)
    if did == 0:
        raise ProtocolError("device_info: device_id 0 is not a device")
    enum_value(DevClass, cls, "device_info: class")
    enum_value(DevBackend, backend, "device_info: backend")
    enum_value(DevState, state, "device_info: state")
    if haptics > 1:
        raise ProtocolError("device_info: haptics %d not 0/1" % haptics)
    name, path, error = r.str(), r.str(), r.str()
    size = lambda t: len(t.encode("utf-8", "surrogateescape"))  # noqa: E731 (wire bytes)
    if size(name) > schema.MAX_NAME_LEN or size(path) > schema.MAX_PATH_LEN \
            or size(error) > schema.MAX_ERROR_MSG_LEN:
        raise ProtocolError("device_info: a string exceeds its limit")
    return DeviceInfo(did, cls, backend, state, bus, vid, pid, bound, active, haptics, name,
                      path, error)


def decode_device_info(p: bytes) -> DeviceInfo:
    r = Reader(p, "device_info")
    d = _read_info(r)
    r.end()
    return d


def encode_device_info(d: DeviceInfo) -> bytes:
    return struct.pack("<" + DEVICE_INFO_FIXED, d.device_id, d.dev_class, d.backend, d.state,
                       d.bus, d.vid, d.pid, d.bound_session, d.active_session, d.haptics) + \
        pack_str(d.name) + pack_str(d.path) + pack_str(d.error)


def decode_device_list(p: bytes) -> List[DeviceInfo]:
    r = Reader(p, "device_list")
    n = r.take("I")
    if n > schema.MAX_DEVICES:
        raise ProtocolError("device_list: %d devices exceed limit %d" % (n, schema.MAX_DEVICES))
    out = [_read_info(r) for _ in range(n)]
    r.end()
    return out


def encode_device_list(items: Sequence[DeviceInfo]) -> bytes:
    return struct.pack("<I", len(items)) + b"".join(encode_device_info(d) for d in items)


def encode_device_bind(device_id: int, session_id: int = 0) -> bytes:
    """session_id 0 unbinds: the device follows the most recently active session."""
    return struct.pack("<QQ", device_id, session_id)


def decode_device_bind(p: bytes):
    r = Reader(p, "device_bind")
    v = r.take("QQ")
    r.end()
    if v[0] == 0:
        raise ProtocolError("device_bind: device_id 0 is not a device")
    return v


@dataclass
class DeviceView:
    device_id: int
    session_id: int
    view_proj: List[float]   # 16, row-major, mesh space -> clip space (OpenGL)
    viewport: List[float]    # x, y, width, height in pixels, y down


def encode_device_view(device_id: int, session_id: int, view_proj: Sequence[float],
                       viewport: Sequence[float]) -> bytes:
    vp, port = [float(x) for x in view_proj], [float(x) for x in viewport]
    if len(vp) != 16 or len(port) != 4:
        raise ValueError("device_view: view_proj needs 16 values, viewport 4")
    return struct.pack("<QQ16d4d", device_id, session_id, *vp, *port)


def decode_device_view(p: bytes) -> DeviceView:
    r = Reader(p, "device_view")
    v = r.take("QQ16d4d")
    r.end()
    d = DeviceView(v[0], v[1], list(v[2:18]), list(v[18:22]))
    if d.device_id == 0 or d.session_id == 0:
        raise ProtocolError("device_view: device_id and session_id must be non-zero")
    if not all(math.isfinite(x) for x in d.view_proj + d.viewport):
        raise ProtocolError("device_view: non-finite view_proj / viewport")
    if not (d.viewport[2] > 0 and d.viewport[3] > 0):
        raise ProtocolError("device_view: viewport width and height must be positive")
    return d


__all__ = ["DeviceInfo", "DeviceView", "CLASS_NAMES", "decode_device_info",
           "encode_device_info", "decode_device_list", "encode_device_list",
           "encode_device_bind", "decode_device_bind", "encode_device_view",
           "decode_device_view"]
