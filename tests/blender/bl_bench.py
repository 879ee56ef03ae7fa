"""Blender-in-the-loop figures (run inside headless Blender by tests/bench/bench_blender.py):
for grids of --sizes vertices, the add-on shares the grid, opens a stroke and, per update, sends
BRUSH_UPDATE and runs the add-on's sync tick until Blender's mesh holds that version (select()
on the socket in between): update sent -> vertex positions applied in Blender. At the largest
size also the overlay path (overlay threshold below the vertex count: the tick updates the
replica and the overlay's positions, the mesh is not written). The mesh path includes Blender's
depsgraph evaluation of the written mesh (what a redraw would do). Results as JSON to --out."""
import argparse
import json
import os
import select
import sys
import time

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bl_common as bc  # noqa: E402

argv = sys.argv[sys.argv.index("--") + 1:]
p = argparse.ArgumentParser()
p.add_argument("--zip", required=True)
p.add_argument("--socket", required=True)
p.add_argument("--out", required=True)
p.add_argument("--sizes", default="100,316,1000")     # grid sides: side^2 vertices
p.add_argument("--updates", type=int, default=30)
A = p.parse_args(argv)


def wait_version(mod, m, version, overlay):
    """Ticks until the version is applied; returns the depsgraph evaluation's ms (0 overlay)."""
    st = bc.state(mod)
    while m.version < version or (not overlay and m.dirty):
        if not st.client.pending_events():
            select.select([st.client.sock], [], [], 30.0)
        mod.sync.tick(force=not overlay)
    if overlay:
        m.positions()          # what the overlay batch is built from
        return 0.0
    t0 = time.perf_counter()
    bpy.context.evaluated_depsgraph_get()   # Blender re-evaluates the written mesh
    return (time.perf_counter() - t0) * 1e3


def stroke_figures(mod, obj, sid, updates, overlay):
    st = bc.state(mod)
    c = st.client
    m = st.mirrors[sid]
    dc = mod.deformd_client
    c.brush_begin(sid, dc.Brush(type="grab", center=(0.0, 0.0, 0.0), radius=0.3, nu=0.45))
    st.stroke_active = overlay
    lat, acks, evals = [], [], []
    for k in range(1, updates + 1):
        t0 = time.perf_counter()
        rid = c.send(dc.MsgType.BRUSH_UPDATE,
                     dc.messages.encode_brush_update(sid, (0.0, 0.0, 0.002 * k)))
        ack = dc.messages.decode_ack(b"".join(f.payload for f in c.wait_reply(rid)))
        acks.append((time.perf_counter() - t0) * 1e3)
        evals.append(wait_version(mod, m, ack.version, overlay))
        lat.append((time.perf_counter() - t0) * 1e3)
    c.brush_end(sid)
    st.stroke_active = False
    mod.sync.tick(force=True)
    assert np.array_equal(bc.positions(obj), np.frombuffer(c.get_mesh(sid).positions,
                                                           dtype=np.float32).reshape(-1, 3))
    return lat, acks, evals


def main():
    mod = bc.install(A.zip)
    bpy.ops.deformd.connect(address="unix:" + A.socket)
    res = []
    sizes = [int(s) for s in A.sizes.split(",")]
    for side in sizes:
        bpy.ops.object.select_all(action="SELECT")
        bpy.ops.object.delete()
        bpy.ops.mesh.primitive_grid_add(x_subdivisions=side - 1, y_subdivisions=side - 1,
                                        size=2.0)
        obj = bpy.context.active_object
        nv = len(obj.data.vertices)
        dg = bpy.context.evaluated_depsgraph_get()
        t0 = time.perf_counter()
        data, _ = mod.upload.object_ply(obj, dg)
        t1 = time.perf_counter()
        bpy.ops.deformd.share()
        t2 = time.perf_counter()
        sid = int(obj["deformd_session"])
        updates = A.updates if nv < 500000 else max(5, A.updates // 3)
        mod.prefs.get().overlay_threshold = 10 ** 9
        lat, acks, evals = stroke_figures(mod, obj, sid, updates, overlay=False)
        r = {"nv": nv, "ply_ms": (t1 - t0) * 1e3, "ply_mb": len(data) / 1e6,
             "share_ms": (t2 - t1) * 1e3, "mesh": lat, "ack": acks, "eval": evals}
        if side == sizes[-1]:
            mod.prefs.get().overlay_threshold = 0
            mod.prefs.get().write_interval = 1e9
            r["overlay"], r["overlay_ack"], _ = stroke_figures(mod, obj, sid, updates,
                                                               overlay=True)
        res.append(r)
        bc.state(mod).client.close_session(sid)
        bc.state(mod).mirrors.pop(sid, None)
    with open(A.out, "w") as f:
        json.dump(res, f)


main()
