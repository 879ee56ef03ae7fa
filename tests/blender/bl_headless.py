"""Headless cases of the Blender add-on, one per Blender run (`blender -b --factory-startup
--python-exit-code 1 --python tests/blender/bl_headless.py -- --zip ZIP --case NAME --socket
PATH [--out FILE] [--daemon-pid PID]`), driven by tests/integration/test_blender.py, which
starts the daemon. A failed assertion ends Blender with exit code 1."""
import os
import select
import signal
import socket
import sys
import types

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bl_common as bc  # noqa: E402

A = bc.args()
ADDR = "unix:" + A.socket


def case_register():
    mod = bc.install(A.zip)
    assert mod.bl_info["blender"] >= (3, 4, 0)
    for op in ("connect", "share", "join", "stroke", "sync", "undo", "redo", "disconnect",
               "sculpt", "handles_set", "handle_drag"):
        assert hasattr(bpy.types, "DEFORMD_OT_" + op), op
    assert hasattr(bpy.types, "DEFORMD_PT_panel")
    assert hasattr(bpy.types.WindowManager, "deformd")
    assert bpy.app.timers.is_registered(mod.sync._timer)
    assert mod.deformd_client.__file__.startswith(os.path.dirname(mod.__file__))  # vendored
    bc.disable()
    assert not hasattr(bpy.types, "DEFORMD_OT_connect")
    assert not hasattr(bpy.types, "DEFORMD_PT_panel")
    assert not hasattr(bpy.types.WindowManager, "deformd")
    assert not bpy.app.timers.is_registered(mod.sync._timer)
    mod = bc.install(A.zip)                                   # enables again, same process
    bpy.ops.deformd.connect(address=ADDR)
    assert bc.state(mod).connected
    bc.disable()                                              # closes the connection
    assert not bc.state(mod).connected


def _shared(mod):
    bpy.ops.object.select_all(action="DESELECT")
    obj = bc.grid_object()
    bpy.ops.deformd.connect(address=ADDR)
    bpy.ops.deformd.share()
    sid = int(obj["deformd_session"])
    return obj, sid


def case_share_stroke():
    """Share, one scripted stroke through the operator; Blender's positions are the daemon's
    bit for bit. Writes base positions and the stroke for the test's Kelvinlet check."""
    mod = bc.install(A.zip)
    obj, sid = _shared(mod)
    base = bc.positions(obj).copy()
    c2 = bc.client(mod, A.socket)
    assert np.array_equal(bc.daemon_positions(c2, sid), base)  # upload kept every float
    info = [s for s in c2.list_sessions() if s.session_id == sid][0]
    assert info.nv == len(base) and info.name == obj.name
    stroke = dict(center=tuple(float(v) for v in base[300]), move=(0.05, -0.02, 0.08),
                  radius=0.3, nu=0.4)
    bpy.ops.deformd.stroke(brush="grab", **stroke)
    after = bc.positions(obj)
    assert np.array_equal(after.view(np.uint32), bc.daemon_positions(c2, sid).view(np.uint32))
    assert not np.array_equal(after, base)
    assert bc.state(mod).mirrors[sid].version == c2.get_mesh(sid).version
    bc.write_out(A.out, base=base.ravel().tolist(), after=after.ravel().tolist(), **stroke)


def case_second_user():
    """Another client strokes the session; the add-on's poll applies it (deformd.sync runs the
    timer's code) and the object matches GET_MESH; then a twist and a scale by the operator."""
    mod = bc.install(A.zip)
    obj, sid = _shared(mod)
    c2 = bc.client(mod, A.socket)
    base = bc.positions(obj)
    for k in range(3):
        ack = c2.stroke(sid, mod.deformd_client.Brush(
            type="grab", center=tuple(float(v) for v in base[100 + 50 * k]),
            move=(0.0, 0.03 * (k + 1), 0.05), radius=0.25))
    bc.sync_until(mod, sid, ack.version)
    assert np.array_equal(bc.positions(obj), bc.daemon_positions(c2, sid))
    bpy.ops.deformd.stroke(brush="twist", center=tuple(float(v) for v in base[200]),
                           twist=(0.0, 0.0, 0.4), radius=0.4)
    bpy.ops.deformd.stroke(brush="scale", center=tuple(float(v) for v in base[250]),
                           scale=0.2, radius=0.4, nu=0.3)
    assert np.array_equal(bc.positions(obj), bc.daemon_positions(c2, sid))
    assert bc.state(mod).versions_applied >= 5
    # a lost version: the add-on's next version does not follow -> resync by snapshot
    st = bc.state(mod)
    ack = c2.stroke(sid, mod.deformd_client.Brush(type="grab", center=(0.0, 0.0, 0.0),
                                                  move=(0.0, 0.0, 0.1), radius=0.3))
    lost = []
    while not any(getattr(e, "version", 0) == ack.version for e in lost):
        bc.wait_readable(st.client, "version %d" % ack.version)
        lost += st.client.poll()                            # taken away: never applied
    ack = c2.stroke(sid, mod.deformd_client.Brush(type="grab", center=(0.0, 0.0, 0.0),
                                                  move=(0.0, 0.1, 0.0), radius=0.3))
    bc.sync_until(mod, sid, ack.version)
    assert np.array_equal(bc.positions(obj), bc.daemon_positions(c2, sid))
    assert st.resyncs == 1


def case_brush_state():
    """BRUSH_STATE_SET by another client shows in the panel's values; an edit in the panel sends
    BRUSH_STATE_SET (the other client sees it)."""
    mod = bc.install(A.zip)
    obj, sid = _shared(mod)
    c2 = bc.client(mod, A.socket)
    st = c2.brush_state_set(sid, radius=0.37, nu=0.3, falloff=2, type="twist", strength=0.5)
    wm = bpy.context.window_manager.deformd
    while wm.brush_radius != np.float32(0.37):
        bc.wait_readable(bc.state(mod).client, "the BRUSH_STATE event")
        bpy.ops.deformd.sync()
    assert wm.brush_nu == np.float32(0.3) and wm.brush_falloff == 2
    assert wm.brush_type == "twist" and wm.brush_strength == np.float32(0.5)
    assert bc.state(mod).last_changer == "second-user"
    wm.brush_radius = 0.125                                   # the user edits the panel
    got = c2.brush_state_get(sid)
    assert got.radius == 0.125 and got.seq == st.seq + 1
    assert got.origin_name == "blender"
    # a stroke without explicit radius takes the panel's (session) brush
    bpy.ops.deformd.stroke(brush="grab", center=(0.0, 0.0, 0.0), move=(0.0, 0.0, 0.1))
    assert np.array_equal(bc.positions(obj), bc.daemon_positions(c2, sid))


def case_undo():
    mod = bc.install(A.zip)
    obj, sid = _shared(mod)
    c2 = bc.client(mod, A.socket)
    before = bc.positions(obj).copy()
    bpy.ops.deformd.stroke(brush="grab", center=tuple(float(v) for v in before[10]),
                           move=(0.1, 0.0, 0.0), radius=0.5)
    after = bc.positions(obj).copy()
    assert not np.array_equal(after, before)
    bpy.ops.deformd.undo()
    assert np.array_equal(bc.positions(obj), before)
    assert np.array_equal(bc.positions(obj), bc.daemon_positions(c2, sid))
    bpy.ops.deformd.redo()
    assert np.array_equal(bc.positions(obj), after)
    assert np.array_equal(bc.positions(obj), bc.daemon_positions(c2, sid))
    bpy.ops.deformd.undo()
    text = bc.report_of(bpy.ops.deformd.undo)                 # nothing left to undo
    assert "ESTATE" in text, text
    assert bc.state(mod).connected                            # a refusal keeps the connection


def case_join_reconnect():
    """Join by name into a new object; disconnect, another client strokes, reconnect resyncs."""
    mod = bc.install(A.zip)
    c2 = bc.client(mod, A.socket)
    with open(os.path.join(os.path.dirname(A.out), "join.obj"), "w") as f:
        for j in range(10):
            for i in range(10):
                f.write("v %g %g %g\n" % (i / 9, j / 9, 0.05 * ((i * j) % 3)))
        for j in range(9):
            for i in range(9):
                a = j * 10 + i + 1
                f.write("f %d %d %d\nf %d %d %d\n" % (a, a + 1, a + 11, a, a + 11, a + 10))
        path = f.name
    sid = c2.load_file(path, name="joinme").session_id
    bpy.ops.object.select_all(action="DESELECT")
    bpy.context.view_layer.objects.active = None
    bpy.ops.deformd.connect(address=ADDR)
    bpy.ops.deformd.join(session="joinme")
    obj = bpy.context.active_object
    assert obj.name.startswith("joinme") and int(obj["deformd_session"]) == sid
    assert len(obj.data.polygons) == 2 * 81
    assert np.array_equal(bc.positions(obj), bc.daemon_positions(c2, sid))
    bpy.ops.deformd.disconnect()
    kept = bc.positions(obj).copy()
    c2.stroke(sid, mod.deformd_client.Brush(type="grab", center=(0.5, 0.5, 0.0),
                                            move=(0.0, 0.0, 0.2), radius=0.3))
    assert np.array_equal(bc.positions(obj), kept)            # offline: as last synced
    bpy.ops.deformd.connect(address=ADDR)                     # resyncs the scene's sessions
    assert np.array_equal(bc.positions(obj), bc.daemon_positions(c2, sid))
    assert not np.array_equal(bc.positions(obj), kept)
    bpy.ops.deformd.join(session=str(sid))                    # by id onto the same object
    assert obj.name == bpy.context.active_object.name


def case_handles():
    """Handle-drag mode's operators: the selected vertices become the handles (energy, w, s
    from the panel); a move by an offset solves on the daemon and Blender shows its result."""
    mod = bc.install(A.zip)
    obj, sid = _shared(mod)
    c2 = bc.client(mod, A.socket)
    sel = np.zeros(len(obj.data.vertices), dtype=bool)
    sel[[0, 24, 600, 624, 312]] = True                     # corners and centre of the 25x25
    obj.data.vertices.foreach_set("select", sel)
    wm = bpy.context.window_manager.deformd
    wm.handle_energy, wm.handle_w, wm.handle_s = "arap", 2e-4, 0.02
    bpy.ops.deformd.handles_set()
    hs = c2.get_handles(sid)
    assert sorted(hs.handles) == [0, 24, 312, 600, 624]
    assert hs.energy == "arap"                              # panel values are float32
    assert hs.params.w == float(np.float32(2e-4)) and hs.params.s == float(np.float32(0.02))
    before = bc.positions(obj).copy()
    bpy.ops.deformd.handles_move(offset=(0.0, 0.0, 0.2), max_iters=100)
    after = bc.positions(obj)
    assert np.array_equal(after, bc.daemon_positions(c2, sid))
    dz = after[312, 2] - before[312, 2]
    assert dz > 0.1, dz                                     # the handle followed its target
    obj.data.vertices.foreach_set("select", np.zeros(len(sel), dtype=bool))
    t = bc.report_of(bpy.ops.deformd.handles_set)
    assert "select the handle vertices" in t, t


def case_elastic():
    """The active Elastic Deform brush -> the session brush (brush_map)."""
    mod = bc.install(A.zip)
    obj, sid = _shared(mod)
    c2 = bc.client(mod, A.socket)
    b = bpy.data.brushes.new("elastic", mode="SCULPT")
    b.sculpt_tool = "ELASTIC_DEFORM"
    b.elastic_deform_type = "GRAB_TRISCALE"
    b.elastic_deform_volume_preservation = 0.8
    b.strength = 0.7
    bpy.context.scene.tool_settings.sculpt.brush = b
    bpy.ops.deformd.brush_from_elastic()
    got = c2.brush_state_get(sid)
    assert (got.type, got.falloff, got.ratio, got.nu) == ("grab", 3, 2.0, 0.5)
    assert got.strength == float(np.float32(0.7))
    assert bpy.context.window_manager.deformd.brush_falloff == 3
    b.elastic_deform_type = "TWIST"
    b.elastic_deform_volume_preservation = 0.25
    bpy.ops.deformd.brush_from_elastic()
    got = c2.brush_state_get(sid)
    assert (got.type, got.falloff) == ("twist", 1) and got.nu == float(np.float32(0.25))
    b.sculpt_tool = "DRAW"
    t = bc.report_of(bpy.ops.deformd.brush_from_elastic)
    assert "not an Elastic Deform brush" in t, t


def case_modifiers():
    """The upload is the evaluated mesh: a Displace modifier's positions reach the daemon; a
    Subdivision modifier (another vertex count) is refused with a report, nothing shared."""
    mod = bc.install(A.zip)
    bpy.ops.deformd.connect(address=ADDR)
    c2 = bc.client(mod, A.socket)
    obj = bc.grid_object("displaced")
    m = obj.modifiers.new("d", "DISPLACE")
    m.strength = 0.25
    ev = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    want = np.empty(len(ev.data.vertices) * 3, dtype=np.float32)
    ev.data.vertices.foreach_get("co", want)
    assert not np.array_equal(want.reshape(-1, 3), bc.positions(obj))   # the modifier moves it
    bpy.ops.deformd.share()
    sid = int(obj["deformd_session"])
    assert np.array_equal(bc.daemon_positions(c2, sid), want.reshape(-1, 3))
    n = len(c2.list_sessions())
    sub = bc.grid_object("subdivided", n=4)
    sub.modifiers.new("s", "SUBSURF")
    t = bc.report_of(bpy.ops.deformd.share)
    assert "vertex count" in t, t
    assert len(c2.list_sessions()) == n and "deformd_session" not in sub


def case_tls():
    """TCP with the daemon's key and TLS (preferences key_file, tls_ca): share and stroke as on
    the Unix socket; a wrong key or no CA is a report, not a connection."""
    mod = bc.install(A.zip)
    p = mod.prefs.get()
    p.key_file, p.tls_ca = A.wrong_key_file, A.tls_ca
    t = bc.report_of(bpy.ops.deformd.connect, address=A.tcp)
    assert "EPROTO_AUTH" in t, t
    p.key_file, p.tls_ca = A.key_file, ""
    t = bc.report_of(bpy.ops.deformd.connect, address=A.tcp)     # plain TCP to a TLS daemon
    assert "deformd" in t and not bc.state(mod).connected, t
    p.tls_ca = A.tls_ca
    obj = bc.grid_object()
    bpy.ops.deformd.connect(address=A.tcp)
    assert bc.state(mod).client.authenticated
    bpy.ops.deformd.share()
    sid = int(obj["deformd_session"])
    bpy.ops.deformd.stroke(brush="grab", center=(0.0, 0.0, 0.0), move=(0.0, 0.0, 0.1),
                           radius=0.4)
    c2 = bc.client(mod, A.socket)
    assert np.array_equal(bc.positions(obj), bc.daemon_positions(c2, sid))


def case_errors():
    mod = bc.install(A.zip)
    t = bc.report_of(bpy.ops.deformd.connect, address="unix:/nonexistent/deformd.sock")
    assert "cannot reach deformd at unix:/nonexistent/deformd.sock" in t, t
    t = bc.report_of(bpy.ops.deformd.connect, address="nonsense")
    assert "neither unix:PATH nor HOST:PORT" in t, t
    t = bc.report_of(bpy.ops.deformd.share)
    assert "not connected" in t, t
    obj, sid = _shared(mod)
    t = bc.report_of(bpy.ops.deformd.join, session="no-such-session")
    assert "ENOTFOUND" in t, t
    t = bc.report_of(bpy.ops.deformd.join, session="987654321")
    assert "ENOTFOUND" in t, t
    t = bc.report_of(bpy.ops.deformd.stroke, brush="grab", center=(0, 0, 0), move=(0, 0, 1),
                     radius=0.3, nu=float("nan"))
    assert "EINVAL" in t or "nu" in t, t
    bpy.ops.deformd.stroke(brush="grab", center=(0.0, 0.0, 0.0), move=(0.0, 0.0, 0.1),
                           radius=0.3)
    synced = bc.positions(obj).copy()
    # the daemon goes away: the next poll reports it, the object stays as last synced
    st = bc.state(mod)
    os.kill(A.daemon_pid, signal.SIGTERM)
    t = None
    while t is None:             # what the daemon sent before closing (session closed) first
        r, _, _ = select.select([st.client.sock], [], [], 15.0)
        assert r, "the daemon's socket did not close"
        try:
            bpy.ops.deformd.sync()
        except RuntimeError as e:
            t = str(e)
    assert t.startswith("Error: deformd: connection lost") and "Traceback" not in t, t
    assert not st.connected and "disconnected" in st.status
    assert np.array_equal(bc.positions(obj), synced)
    t = bc.report_of(bpy.ops.deformd.stroke, brush="grab", move=(0, 0, 1))
    assert "not connected" in t, t
    t = bc.report_of(bpy.ops.deformd.connect, address=ADDR)
    assert "cannot reach deformd" in t, t
    bc.write_out(A.out, reports="ok")


class ProgressRecorder:
    """Stands in for progress.WM (the add-on's window-manager hook): records every call."""

    def __init__(self):
        self.calls = []

    def begin(self, lo, hi):
        self.calls.append(("begin", lo, hi))

    def update(self, v):
        self.calls.append(("update", v))

    def end(self):
        self.calls.append(("end",))


def big_grid_object(n):
    """An n x n vertex grid (2 (n-1)^2 triangles) built with numpy, wavy in z."""
    i, j = np.meshgrid(np.arange(n, dtype=np.float32), np.arange(n, dtype=np.float32))
    co = np.stack([i.ravel() / (n - 1), j.ravel() / (n - 1),
                   0.05 * np.sin(7 * i.ravel() / n) * np.cos(5 * j.ravel() / n)], axis=1)
    a = (np.arange(n - 1)[None, :] + n * np.arange(n - 1)[:, None]).ravel().astype(np.uint32)
    tri = np.stack([a, a + 1, a + n + 1, a, a + n + 1, a + n], axis=1).reshape(-1, 3)
    mesh = bpy.data.meshes.new("big")
    mesh.vertices.add(n * n)
    mesh.vertices.foreach_set("co", co.astype(np.float32).ravel())
    mesh.loops.add(3 * len(tri))
    mesh.loops.foreach_set("vertex_index", tri.ravel())
    mesh.polygons.add(len(tri))
    mesh.polygons.foreach_set("loop_start", np.arange(0, 3 * len(tri), 3, dtype=np.uint32))
    mesh.polygons.foreach_set("loop_total", np.full(len(tri), 3, dtype=np.uint32))
    mesh.update()
    obj = bpy.data.objects.new("big", mesh)
    bpy.context.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = obj
    return obj


def _check_progress(calls, what):
    """begin once first, end once last, updates strictly increasing in 0..100 ending at 100."""
    assert calls and calls[0][0] == "begin" and calls[-1] == ("end",), (what, calls)
    assert [c[0] for c in calls].count("begin") == 1, (what, calls)
    assert [c[0] for c in calls].count("end") == 1, (what, calls)
    ups = [c[1] for c in calls if c[0] == "update"]
    assert len(ups) >= 2, (what, calls)
    assert all(b > a for a, b in zip(ups, ups[1:])), (what, ups)
    assert 0 <= ups[0] and ups[-1] == 100, (what, ups)


def case_progress():
    """Share of a 300 x 300 grid (~5 MB PLY): Blender's progress indicator (through the
    add-on's hook progress.WM) follows the upload and parse WORK_PROGRESS events; handle set
    and move follow factorize / solve."""
    mod = bc.install(A.zip)
    rec = ProgressRecorder()
    mod.progress.WM = rec
    bpy.ops.object.select_all(action="DESELECT")
    obj = big_grid_object(300)
    bpy.ops.deformd.connect(address=ADDR)
    bpy.ops.deformd.share()
    sid = int(obj["deformd_session"])
    _check_progress(rec.calls, "share")
    c2 = bc.client(mod, A.socket)
    assert np.array_equal(bc.daemon_positions(c2, sid), bc.positions(obj))
    sel = np.zeros(len(obj.data.vertices), dtype=bool)
    sel[[0, 299, 45150]] = True
    obj.data.vertices.foreach_set("select", sel)
    rec.calls = []
    bpy.ops.deformd.handles_set()
    _check_progress(rec.calls, "handles_set")
    rec.calls = []
    bpy.ops.deformd.handles_move(offset=(0.0, 0.0, 0.1), max_iters=30)
    _check_progress([c for c in rec.calls], "handles_move")
    assert np.array_equal(bc.positions(obj), bc.daemon_positions(c2, sid))


def case_knob():
    """The daemon replays a PowerMate recording (hid_replay, speed 0) onto the shared session:
    every BRUSH_STATE the knob produces lands in the panel's values (checked after each one the
    add-on shows), and once the recording ended (the device UNPLUGGED) the panel holds the
    daemon's BRUSH_STATE_GET."""
    mod = bc.install(A.zip)
    dc = mod.deformd_client
    shown = []
    real = mod.props.set_from_state

    def watch(wm_props, st):
        real(wm_props, st)
        if bc.state(mod).brush_shown != (st.session_id, st.seq):
            return                                  # older than what the panel shows
        shown.append((st.origin, st.seq, st.radius, wm_props.brush_radius, st.nu,
                      wm_props.brush_nu, st.falloff, wm_props.brush_falloff))
    mod.props.set_from_state = watch                # sync and operators call it through props
    obj, sid = _shared(mod)                         # the first subscribe starts the replay
    c2 = bc.client(mod, A.socket)
    wm = bpy.context.window_manager.deformd
    st = bc.state(mod)
    # at speed 0 the knob may have finished during the share, whose BRUSH_STATE_GET then showed
    # its last state and the queued events would be skipped as older: forget what the panel
    # shows (as before any state) so each queued event is seen landing in the panel
    st.brush_shown = (sid, 0)
    shown.clear()
    while True:
        devs = [d for d in c2.devices_list() if d.dev_class]
        final = c2.brush_state_get(sid)
        if devs and all(d.state == dc.DevState.UNPLUGGED for d in devs) and \
                st.brush_shown == (sid, final.seq):
            break
        bc.wait_readable(st.client, "knob brush states / the device's end")
        bpy.ops.deformd.sync()
    assert final.origin == dc.Origin.DEVICE and final.seq > 1, final
    assert wm.brush_radius == np.float32(final.radius)
    assert wm.brush_nu == np.float32(final.nu) and wm.brush_falloff == final.falloff
    knob = [x for x in shown if x[0] == dc.Origin.DEVICE]
    assert len({x[2] for x in knob}) >= 2, knob            # the panel followed several turns
    for origin, seq, r, pr, nu, pnu, f, pf in shown:
        assert pr == np.float32(r) and pnu == np.float32(nu) and pf == f, (seq, r, pr)
    seqs = [x[1] for x in shown]
    assert seqs == sorted(seqs), seqs
    assert st.last_changer == final.origin_name


def _reconnect(expect):
    """Share, stroke; disconnect; another client strokes twice; reconnect: the object is the
    daemon's GET_MESH bit for bit and the add-on says how it resynced (`expect`: "replay" when
    the daemon still keeps the missed versions, "snapshot" when it keeps none)."""
    mod = bc.install(A.zip)
    obj, sid = _shared(mod)
    c2 = bc.client(mod, A.socket)
    base = bc.positions(obj).copy()
    bpy.ops.deformd.stroke(brush="grab", center=tuple(float(v) for v in base[200]),
                           move=(0.0, 0.0, 0.1), radius=0.4)
    st = bc.state(mod)
    held_version = st.mirrors[sid].version
    bpy.ops.deformd.disconnect()
    kept = bc.positions(obj).copy()
    for k in range(2):
        c2.stroke(sid, mod.deformd_client.Brush(
            type="grab", center=tuple(float(v) for v in base[300 + 40 * k]),
            move=(0.05, 0.0, -0.1), radius=0.5))
    assert c2.get_mesh(sid).version > held_version
    bpy.ops.deformd.connect(address=ADDR)
    got = bc.positions(obj)
    assert np.array_equal(got.view(np.uint32), bc.daemon_positions(c2, sid).view(np.uint32))
    assert not np.array_equal(got, kept)
    assert st.mirrors[sid].version == c2.get_mesh(sid).version
    assert (st.resumed_replay, st.resumed_snapshot) == \
        ((1, 0) if expect == "replay" else (0, 1)), (st.resumed_replay, st.resumed_snapshot)
    # live again: the next stroke by the other client arrives through the timer's code
    ack = c2.stroke(sid, mod.deformd_client.Brush(
        type="grab", center=tuple(float(v) for v in base[100]), move=(0.0, 0.1, 0.0),
        radius=0.3))
    bc.sync_until(mod, sid, ack.version)
    assert np.array_equal(bc.positions(obj), bc.daemon_positions(c2, sid))
    assert st.resyncs == 0                       # no gap after the resync


def case_reconnect_replay():
    _reconnect("replay")


def case_reconnect_snapshot():
    _reconnect("snapshot")


class _Layout:
    """Stands in for a panel's UILayout: records the text of every label drawn."""

    def __init__(self, out):
        self.out = out

    def box(self):
        return self

    def row(self, **kw):
        return self

    def column(self, **kw):
        return self

    def label(self, text="", **kw):
        self.out.append(text)

    def prop(self, *a, **kw):
        pass

    def operator(self, *a, **kw):
        return types.SimpleNamespace()


def panel_labels(mod):
    """The labels the add-on's sidebar panel draws now (its own draw(), a recording layout)."""
    out = []
    mod.panel.DEFORMD_PT_panel.draw(types.SimpleNamespace(layout=_Layout(out)), bpy.context)
    return out


def peers_answered(mod):
    """Runs the timer's code (deformd.sync) once, which must send SESSION_PEERS (due), then
    until its reply is collected, waiting on the add-on's socket in between."""
    st = bc.state(mod)
    bpy.ops.deformd.sync()
    assert st.peers_rid, "the timer sent no SESSION_PEERS"
    while st.peers_rid:
        bc.wait_readable(st.client, "the SESSION_PEERS reply")
        bpy.ops.deformd.sync()
    assert st.peers_sid == st.current_sid
    return st.peers


def case_peers():
    """Who else is connected: a second client with a HELLO name subscribes; once the subscriber
    count changes (the panel's session refresh), the timer's SESSION_PEERS lists it and the
    panel shows its name and principal; after it disconnects the list loses it."""
    mod = bc.install(A.zip)
    obj, sid = _shared(mod)
    me = "uid:%d" % os.getuid()
    rows = peers_answered(mod)                                 # a new session: listed at once
    assert [(p.name, p.principal, p.is_self) for p in rows] == [("blender", me, True)]
    assert mod.peers.others() == []
    assert "Also connected: 0" in panel_labels(mod)
    c2 = mod.deformd_client.Client.connect_unix(A.socket, timeout=10.0, name="second-sculptor")
    c2.subscribe(sid)
    bpy.ops.deformd.list_sessions()                            # the count changes: 1 -> 2
    assert bc.state(mod).subscribers == 2
    peers_answered(mod)
    others = mod.peers.others()
    assert [(p.name, p.principal, p.can_edit) for p in others] == \
        [("second-sculptor", me, True)]                       # one uid: the owner edits
    labels = panel_labels(mod)
    assert "Also connected: 1" in labels, labels
    assert "second-sculptor (%s)" % me in labels, labels
    # it disconnects: half-close and read until the daemon closes its end, so the daemon has
    # dropped its subscription before the next SESSION_PEERS
    c2.sock.shutdown(socket.SHUT_WR)
    while c2.sock.recv(1 << 16):
        pass
    c2.close()
    bpy.ops.deformd.list_sessions()                            # 2 -> 1
    assert bc.state(mod).subscribers == 1
    peers_answered(mod)
    assert mod.peers.others() == []
    labels = panel_labels(mod)
    assert "Also connected: 0" in labels and not any("second-sculptor" in t for t in labels)
    # the panel's session goes away: the list empties instead of showing stale rows
    bpy.ops.deformd.disconnect()
    assert bc.state(mod).peers == [] and mod.peers.others() == []


CASES = {n[len("case_"):]: f for n, f in globals().items() if n.startswith("case_")}
if A.case not in CASES:
    raise SystemExit("unknown case %r (known: %s)" % (A.case, ", ".join(sorted(CASES))))
CASES[A.case]()
print("bl_headless: case %s passed" % A.case)
