"""Raw-socket helpers for the malformed-frame tests: send arbitrary bytes, collect frames."""
import socket
import time
from typing import List, Tuple

from deformd_client import frame as fr


def read_frames(sock: socket.socket, timeout: float = 2.0,
                want: int = 1) -> Tuple[List[fr.Frame], bool]:
    """Reads until `want` frames arrived, the peer closed, or `timeout` passed.
    Returns (frames, closed)."""
    dec = fr.FrameDecoder()
    frames: List[fr.Frame] = []
    deadline = time.monotonic() + timeout
    while len(frames) < want:
        left = deadline - time.monotonic()
        if left <= 0:
            return frames, False
        sock.settimeout(left)
        try:
            data = sock.recv(65536)
        except socket.timeout:
            return frames, False
        except ConnectionResetError:
            return frames, True
        if not data:
            return frames, True
        frames += dec.feed(data)
    return frames, False


def wait_closed(sock: socket.socket, timeout: float = 3.0) -> bool:
    """True when the peer closes (EOF or reset) within `timeout`; frames are discarded."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        sock.settimeout(max(0.01, deadline - time.monotonic()))
        try:
            data = sock.recv(65536)
        except socket.timeout:
            return False
        except (ConnectionResetError, BrokenPipeError):
            return True
        if not data:
            return True
    return False
