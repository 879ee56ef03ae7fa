"""deformd_client — standard-library Python client of the deformd mesh deformation daemon.

    from deformd_client import Client, Brush, MeshState
    c = Client.connect_unix(path)            # or Client.connect_tcp(host, port)
    info = c.load_file("spot.obj")
    c.stroke(info.session_id, Brush(type="grab", center=(0, 0, 0), move=(0, 0.1, 0)))
    mesh = c.get_mesh(info.session_id)       # positions: array('f'), 3 per vertex

Errors from the daemon raise DeformdError(code, name, message).
"""
from .access import AccessInfo
from .auth import AuthError
from .brush_state import BrushCursor, BrushState, BrushValues
from .client import Client, MeshData, SessionClosed, ShmLost
from .devices import DeviceInfo
from .errors import ConnectionClosed, DeformdError, ErrorCode, error_name
from .frame import Frame, FrameDecoder, FrameError, encode_frame, encode_header
from .mesh_state import MeshState, OutOfSync
from .peers import Peer
from .messages import (AffineSet, Brush, HandleParams, HandleSet, LoadReport, MoveResult,
                       SessionInfo, ShmInfo)
from .schema import (BrushParam, BrushStateField, BrushType, ChangeKind, CursorFlag,
                     DispEncoding, Energy, Feature, Format, FrameFlag, GetMeshFlag, Integrator,
                     LoadOpt, LoadSource, MeshKind, MeshSection, MoveStatus, MsgType, Origin,
                     PinFlag, SubscribeFlag, DevClass, DevBackend, DevState, AuthMethod,
                     WorkOpt, WorkStage, PeerFlag, Transport)
from .progress import WorkProgress
from .stream import Disp, Progress, ShmRing
from .wire import ProtocolError

__all__ = [
    "AccessInfo", "Client", "MeshData", "SessionClosed", "ConnectionClosed", "DeformdError",
    "ErrorCode", "error_name",
    "Frame", "FrameDecoder", "FrameError", "encode_frame", "encode_header", "MeshState",
    "OutOfSync", "AffineSet", "Brush", "HandleParams", "HandleSet", "Disp", "LoadReport",
    "MoveResult",
    "Progress", "ProtocolError", "SessionInfo", "ShmInfo", "ShmLost", "ShmRing",
    "BrushParam", "BrushType", "ChangeKind", "DispEncoding", "Energy", "Feature", "Format",
    "FrameFlag", "GetMeshFlag", "Integrator", "LoadOpt", "LoadSource", "MeshKind", "MeshSection",
    "MoveStatus", "MsgType", "PinFlag", "SubscribeFlag",
    "BrushCursor", "BrushState", "BrushValues", "BrushStateField", "CursorFlag", "Origin",
    "DeviceInfo", "DevClass", "DevBackend", "DevState", "AuthError", "AuthMethod",
    "WorkProgress", "WorkOpt", "WorkStage", "Peer", "PeerFlag", "Transport",
]
__version__ = "0.1.0"
