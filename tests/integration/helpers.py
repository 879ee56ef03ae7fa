"""Shared helpers of the integration suite: generated meshes, a reference Kelvinlet grab
(de Goes & James 2017, eqs. 6-7), small file readers for what deformctl writes."""
import contextlib
import math
from array import array
from typing import List, Sequence, Tuple


def grid_obj(n: int, m: int, size: float = 1.0, symmetric: bool = False) -> bytes:
    """An n x m vertex grid over [0, size]^2 on the surface z = 0.1 sin(3x + 2y) (not planar),
    or, with symmetric, z = 0.1 cos(6 (x - size/2)) sin(2y) (mirror-symmetric about
    x = size/2: vertex (i, j) mirrors (n-1-i, j) exactly); two triangles per cell, as OBJ."""
    lines = ["# deformd test grid %dx%d" % (n, m)]
    for j in range(m):
        for i in range(n):
            y = size * j / (m - 1)
            if symmetric:
                d = size * (2 * i - (n - 1)) / (2 * (n - 1))   # signed distance to the plane
                lines.append("v %s %.6f %.6f" % (_sym(size / 2, d), y,
                                                  0.1 * math.cos(6 * abs(d)) * math.sin(2 * y)))
                continue
            x = size * i / (n - 1)
            lines.append("v %.6f %.6f %.6f" % (x, y, 0.1 * math.sin(3 * x + 2 * y)))
    for j in range(m - 1):
        for i in range(n - 1):
            a = j * n + i + 1
            lines.append("f %d %d %d" % (a, a + 1, a + n + 1))
            lines.append("f %d %d %d" % (a, a + n + 1, a + n))
    return ("\n".join(lines) + "\n").encode()


def _sym(c: float, d: float) -> str:
    """c + d printed so that c + d and c - d are exact mirror images in binary (dyadic)."""
    q = round(d * 1024) / 1024.0
    return repr(c + q)


def obj_bytes_positions(data: bytes) -> array:
    """The `v x y z` rows of OBJ text as float32 xyz (how the daemon stores positions)."""
    out = array("f")
    for line in data.decode().splitlines():
        t = line.split()
        if t and t[0] == "v":
            out.extend((float(t[1]), float(t[2]), float(t[3])))
    return out


def grab_displacement(x: Sequence[float], center: Sequence[float], tip: Sequence[float],
                      radius: float, nu: float) -> Tuple[float, float, float]:
    """Single-scale regularized Kelvinlet grab, eq. (6) with the force from eq. (7):
    u(r) = c eps K_eps(r) tip, K_eps(r) = (a-b)/r_e I + b/r_e^3 r r^T + a eps^2/(2 r_e^3) I,
    r = x - center, r_e = sqrt(|r|^2 + eps^2), a = 1 (mu drops out), b = a / (4 (1 - nu))
    (0 for nu = +-inf), c = 2 / (3a - 2b)."""
    a = 1.0
    b = 0.0 if math.isinf(nu) else a / (4.0 * (1.0 - nu))
    c = 2.0 / (3.0 * a - 2.0 * b)
    eps = radius
    r = [x[k] - center[k] for k in range(3)]
    re = math.sqrt(sum(v * v for v in r) + eps * eps)
    diag = (a - b) / re + a * eps * eps / (2.0 * re ** 3)
    rt = sum(r[k] * tip[k] for k in range(3))
    return tuple(c * eps * (diag * tip[k] + b / re ** 3 * r[k] * rt) for k in range(3))


def read_obj_positions(path: str) -> Tuple[List[Tuple[float, float, float]], int]:
    """Vertices of an OBJ file and its face count."""
    verts, faces = [], 0
    with open(path) as f:
        for line in f:
            t = line.split()
            if not t:
                continue
            if t[0] == "v":
                verts.append((float(t[1]), float(t[2]), float(t[3])))
            elif t[0] == "f":
                faces += 1
    return verts, faces


def read_off_positions(path: str) -> Tuple[List[Tuple[float, float, float]], int]:
    with open(path) as f:
        tokens = [t for line in f for t in line.split("#")[0].split()]
    assert tokens[0] == "OFF"
    nv, nf = int(tokens[1]), int(tokens[2])
    vals = tokens[4:4 + 3 * nv]
    verts = [(float(vals[3 * i]), float(vals[3 * i + 1]), float(vals[3 * i + 2]))
             for i in range(nv)]
    return verts, nf


def read_node_positions(path: str) -> List[Tuple[float, float, float]]:
    with open(path) as f:
        rows = [line.split("#")[0].split() for line in f]
    rows = [r for r in rows if r]
    n = int(rows[0][0])
    return [(float(r[1]), float(r[2]), float(r[3])) for r in rows[1:1 + n]]


def read_indices(path: str) -> List[int]:
    with open(path) as f:
        return [int(line.split()[0]) for line in f if line.strip()]


def tet_grid(n: int, size: float = 1.0):
    """An n x n x n vertex cube split into 6 positively oriented tets per cell (Kuhn).
    Returns (positions [(x, y, z)], tets [(a, b, c, d)] 0-based)."""
    def vid(i, j, k):
        return (k * n + j) * n + i
    pts = [(size * i / (n - 1), size * j / (n - 1), size * k / (n - 1))
           for k in range(n) for j in range(n) for i in range(n)]
    perms = [(0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)]
    tets = []
    for k in range(n - 1):
        for j in range(n - 1):
            for i in range(n - 1):
                for p in perms:
                    c = [i, j, k]
                    path = [vid(*c)]
                    for ax in p:
                        c[ax] += 1
                        path.append(vid(*c))
                    a, b, cc, d = path
                    if _signed_volume(pts[a], pts[b], pts[cc], pts[d]) < 0:
                        b, cc = cc, b
                    tets.append((a, b, cc, d))
    return pts, tets


def _signed_volume(a, b, c, d) -> float:
    u = [b[k] - a[k] for k in range(3)]
    v = [c[k] - a[k] for k in range(3)]
    w = [d[k] - a[k] for k in range(3)]
    return (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
            + u[2] * (v[0] * w[1] - v[1] * w[0])) / 6.0


def tet_grid_medit(n: int, size: float = 1.0) -> bytes:
    """tet_grid(n) as a MEDIT .mesh file (1-based indices, reference 0 on every row)."""
    pts, tets = tet_grid(n, size)
    out = ["MeshVersionFormatted 1", "Dimension 3", "Vertices", str(len(pts))]
    out += ["%.6f %.6f %.6f 0" % p for p in pts]
    out += ["Tetrahedra", str(len(tets))]
    out += ["%d %d %d %d 0" % tuple(v + 1 for v in t) for t in tets]
    out.append("End")
    return ("\n".join(out) + "\n").encode()


@contextlib.contextmanager
def grid_session(daemon, n: int):
    """Loads a fresh n x n grid_obj as an unnamed session of `daemon`; yields (session_info,
    positions as array('f')) and closes the session afterwards (if it still exists)."""
    from deformd_client import DeformdError  # the client package is importable in tests
    data = grid_obj(n, n)
    with daemon.unix_client() as c:
        info = c.load_mesh(data, fmt=".obj", name="")
    try:
        yield info, obj_bytes_positions(data)
    finally:
        with daemon.unix_client() as c:
            try:
                c.close_session(info.session_id)
            except DeformdError:
                pass


_SESSIONS_V1 = (
    "CREATE TABLE sessions_v1(id INTEGER PRIMARY KEY, name TEXT NOT NULL, kind INTEGER NOT NULL,"
    " planar INTEGER NOT NULL, nv INTEGER NOT NULL, ne INTEGER NOT NULL, nf INTEGER NOT NULL,"
    " base BLOB NOT NULL, elems BLOB, faces BLOB, version INTEGER NOT NULL,"
    " brush BLOB, brush_seq INTEGER NOT NULL DEFAULT 0, handles BLOB,"
    " cur BLOB, rest BLOB, log_bytes INTEGER NOT NULL DEFAULT 0)")


def downgrade_store(store: str, version: int) -> None:
    """Rewrites a (recipe-free) current store file (server/store/store.h, schema 3) as the
    layout deformd wrote at schema `version` 1 or 2: the large values back in the session
    rows' own columns, no blobs table, no recipe / snap_version / replay_ns columns; version 1
    also without the access table. The daemon must be stopped."""
    import sqlite3

    def blob(name):
        return "(SELECT data FROM blobs WHERE session = s.id AND name = '%s')" % name
    db = sqlite3.connect(store)
    try:
        assert db.execute("SELECT count(*) FROM changes WHERE recipe IS NOT NULL").fetchone() \
            == (0,), "recipe records have no version-%d form" % version
        db.execute(_SESSIONS_V1)
        db.execute("INSERT INTO sessions_v1 SELECT s.id, s.name, s.kind, s.planar, s.nv, s.ne, "
                   "s.nf, %s, %s, %s, s.version, s.brush, s.brush_seq, %s, %s, %s, s.log_bytes "
                   "FROM sessions s" % tuple(blob(n) for n in ("base", "elems", "faces",
                                                               "handles", "cur", "rest")))
        db.execute("DROP TABLE sessions")
        db.execute("ALTER TABLE sessions_v1 RENAME TO sessions")
        db.execute("DROP TABLE blobs")
        db.execute("ALTER TABLE changes DROP COLUMN recipe")
        if version == 1:
            db.execute("DROP TABLE access")
        db.execute("PRAGMA user_version = %d" % version)
        db.commit()
    finally:
        db.close()
