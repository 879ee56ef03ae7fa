"""Client-side replica of a session's positions, kept in sync by the displacement stream.

Every stream frame carries float32 displacements u_i = x_i - X_i from the session's base
(load-time) positions X; a replica computes x_i = X_i + u_i in float32, so every client that
applies the same versions holds byte-identical positions (positions.tobytes()).
"""
import operator
from array import array
from typing import Optional

from . import messages as m
from . import stream as st
from . import stream_enc as se


class OutOfSync(RuntimeError):
    """A frame's base_version is not the replica's version: resync with a snapshot."""


class MeshState:
    """base: array('f') of 3*nv base positions (get_mesh(..., base=True).base); version: the
    version those displacements describe (0 for the base itself)."""

    def __init__(self, base: array, version: int = 0, disp: Optional[array] = None) -> None:
        if len(base) % 3:
            raise ValueError("base has %d floats, not a multiple of 3" % len(base))
        self.nv = len(base) // 3
        self.base = array("f", base)
        self.disp = array("f", bytes(4 * len(base))) if disp is None else array("f", disp)
        self.positions = array("f", self.base)
        if disp is not None:
            self.positions = array("f", map(operator.add, self.base, self.disp))
        self.version = version
        self.applied = 0
        self.quant: Optional[se.QuantState] = None   # made by the first QDisp (4.40)

    @classmethod
    def sync(cls, client, session_id: int) -> "MeshState":
        """A replica at the session's current version: base positions from get_mesh(base=True)
        plus the exact displacements of a dense snapshot."""
        mesh = client.get_mesh(session_id, base=True)
        st = cls(mesh.base, 0)
        st.apply(client.snapshot(session_id))
        return st

    def apply(self, d) -> bool:
        """Applies one whole version: a Disp from Client.events()/snapshot() or a Progress
        (its iterate). Returns False (and changes nothing) for a version already applied;
        raises OutOfSync when versions were missed (resync: apply(client.snapshot(sid))).
        A SNAPSHOT (dense, kind 7) always applies. A Client ShmLost event (`lost` True: a
        shared-memory stream frame was overwritten unread) returns False and changes nothing;
        the next version then raises OutOfSync unless the replica was resynced. Brush state,
        brush cursor and device state events move no vertex: False."""
        if getattr(d, "lost", False) or getattr(d, "kind_name", "") in ("brush_state",
                                                                       "brush_cursor",
                                                                       "device_state"):
            return False
        if isinstance(d, st.Progress):
            d = d.disp
        if isinstance(d, se.QDisp):
            return self._apply_q(d)
        if d.nv != self.nv:
            raise ValueError("frame for %d vertices, replica has %d" % (d.nv, self.nv))
        if d.kind != m.CHANGE_SNAPSHOT:
            if d.version <= self.version:
                return False
            if d.base_version != self.version:
                raise OutOfSync("frame %d applies to version %d, replica is at %d"
                                % (d.version, d.base_version, self.version))
        elif d.encoding != m.DISP_DENSE or d.count != self.nv:
            raise ValueError("a snapshot must be dense and complete")
        u, x, base = self.disp, self.positions, self.base
        if d.encoding == m.DISP_DENSE:
            if d.offset == 0 and d.count == self.nv:
                # a double sum of two float32 values rounded to float32 is the float32 sum
                self.disp = array("f", d.xyz)
                self.positions = array("f", map(operator.add, base, self.disp))
            else:
                o = 3 * d.offset
                for k in range(3 * d.count):
                    u[o + k] = d.xyz[k]
                    x[o + k] = base[o + k] + d.xyz[k]
        else:
            xyz = d.xyz
            for j, i in enumerate(d.idx):
                for c in range(3):
                    v = xyz[3 * j + c]
                    u[3 * i + c] = v
                    x[3 * i + c] = base[3 * i + c] + v
        self.version = d.version
        self.applied += 1
        self.quant = None   # exact displacements: a later QDisp starts from K of these
        return True

    def _apply_q(self, q: "se.QDisp") -> bool:
        """A quantized version delta (a client connected with stream encoding QUANTIZED): the
        shown displacements become fl32(step * K), within the error bound of the exact ones."""
        if q.nv != self.nv:
            raise ValueError("frame for %d vertices, replica has %d" % (q.nv, self.nv))
        if q.version <= self.version:
            return False
        if q.base_version != self.version:
            raise OutOfSync("frame %d applies to version %d, replica is at %d"
                            % (q.version, q.base_version, self.version))
        if self.quant is None or self.quant.step != q.step:
            self.quant = se.QuantState(q.step, self.disp)
        changed = self.quant.apply(q, self.disp)
        u, x, base = self.disp, self.positions, self.base
        if changed is None:
            self.positions = array("f", map(operator.add, base, u))
        else:
            for i in changed:
                for c in range(3):
                    x[3 * i + c] = base[3 * i + c] + u[3 * i + c]
        self.version = q.version
        self.applied += 1
        return True

    def tobytes(self) -> bytes:
        return self.positions.tobytes()
