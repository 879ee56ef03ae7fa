"""The Python client package: vendored into the add-on by `make` (build/blender/deformd_blender.zip
holds deformd_blender/deformd_client, copied from client/python by the Makefile); a checkout run
without the build falls back to an installed deformd_client."""
try:
    from . import deformd_client as client  # noqa: F401  (vendored copy)
except ImportError:                             # pragma: no cover - development checkout
    import deformd_client as client            # noqa: F401

Client = client.Client
DeformdError = client.DeformdError
ConnectionClosed = client.ConnectionClosed
ProtocolError = client.ProtocolError
Brush = client.Brush
MsgType = client.MsgType
messages = client.messages
peers = client.peers
