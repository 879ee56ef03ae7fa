"""A session's positions as numpy float32 arrays, fed by the displacement stream, written to a
Blender mesh with one foreach_set("co") per tick.

Positions are x = X + u in float32 (X: the daemon's base positions, u: the stream's
displacements), exactly what every other client and GET_MESH hold (PROTOCOL.md 6). apply() takes
the versions of one tick in order and only updates u; positions are formed once per write."""
import numpy as np

from .dc import messages as m

DENSE = m.DISP_DENSE
SNAPSHOT = m.CHANGE_SNAPSHOT


class Gap(RuntimeError):
    """A version does not follow the replica's: resync from a snapshot."""


class Mirror:
    """object_name: the Blender object showing session `sid`; base: (nv, 3) float32."""

    def __init__(self, sid: int, object_name: str, base: np.ndarray) -> None:
        self.sid = sid
        self.object_name = object_name
        self.base = np.ascontiguousarray(base, dtype=np.float32).reshape(-1, 3)
        self.nv = self.base.shape[0]
        self.disp = np.zeros_like(self.base)
        self.version = 0
        self.written_version = -1     # the version the mesh shows
        self.last_write_t = 0.0
        self.last_arrival_t = 0.0     # when the newest version was applied (perf_counter)

    def apply(self, d) -> bool:
        """One whole version (a Disp, or a Progress's disp). False for a version already held;
        Gap when versions were missed; ValueError for a frame of another vertex count."""
        d = getattr(d, "disp", d)
        if d.nv != self.nv:
            raise ValueError("session %d sent %d vertices, the object has %d"
                             % (self.sid, d.nv, self.nv))
        if d.kind != SNAPSHOT:
            if d.version <= self.version:
                return False
            if d.base_version != self.version:
                raise Gap("version %d follows %d, the object holds %d"
                          % (d.version, d.base_version, self.version))
        xyz = np.frombuffer(d.xyz, dtype=np.float32).reshape(-1, 3)
        if d.encoding == DENSE:
            self.disp[d.offset:d.offset + d.count] = xyz
        elif d.count:
            self.disp[np.frombuffer(d.idx, dtype=np.uint32)] = xyz
        self.version = d.version
        return True

    def positions(self) -> np.ndarray:
        """(nv, 3) float32 x = X + u (float32 addition, as the daemon does)."""
        return self.base + self.disp

    @property
    def dirty(self) -> bool:
        return self.written_version != self.version

    def write(self, mesh) -> None:
        """One foreach_set("co") and mesh.update(): the mesh shows this version."""
        mesh.vertices.foreach_set("co", self.positions().ravel())
        mesh.update()
        self.written_version = self.version


def mesh_positions(mesh) -> np.ndarray:
    """(nv, 3) float32 copy of a mesh's vertex coordinates (foreach_get)."""
    out = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", out)
    return out.reshape(-1, 3)
