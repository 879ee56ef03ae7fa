"""GUI case (under xvfb-run, software GL, Blender started with --enable-event-simulate and a
user config whose userpref.blend turns the splash off): the modal sculpt operator driven by
simulated mouse events, the 60 Hz timer applying a second user's stroke, the large-mesh overlay
path, screenshots before and after. Steps run from a bpy.app.timers generator so that Blender's
event loop processes each simulated event and redraws in between. Results go to --out as JSON;
Blender exits 0 only when every check passed."""
import os
import sys
import traceback

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bl_common as bc  # noqa: E402

A = bc.args()
STEP_S = 0.05
MAX_WAIT_STEPS = 400
R = {"passed": False}


def view3d():
    for w in bpy.context.window_manager.windows:
        for a in w.screen.areas:
            if a.type == "VIEW_3D":
                for r in a.regions:
                    if r.type == "WINDOW":
                        return w, a, r
    raise AssertionError("no 3D view")


def shot(name):
    w, a, r = view3d()
    path = os.path.join(os.path.dirname(A.out), name + ".png")
    with bpy.context.temp_override(window=w, area=a, region=r):
        bpy.ops.screen.screenshot(filepath=path)
    R[name] = path
    return path


def pixels(path):
    img = bpy.data.images.load(path)
    px = np.empty(img.size[0] * img.size[1] * 4, dtype=np.float32)
    img.pixels.foreach_get(px)
    bpy.data.images.remove(img)
    return px


def drag(w, x0, y0, dx, dy, n, ctrl=False):
    """Queues the events of one drag: press at (x0, y0), n moves to (x0+dx, y0+dy), release.
    Blender's loop hands them to the modal operator in order (moves that come while an update is
    in flight are coalesced)."""
    w.event_simulate(type="MOUSEMOVE", value="NOTHING", x=x0, y=y0)
    w.event_simulate(type="LEFTMOUSE", value="PRESS", x=x0, y=y0, ctrl=ctrl)
    for k in range(1, n + 1):
        w.event_simulate(type="MOUSEMOVE", value="NOTHING", x=x0 + dx * k // n,
                         y=y0 + dy * k // n, ctrl=ctrl)
    w.event_simulate(type="LEFTMOUSE", value="RELEASE", x=x0 + dx, y=y0 + dy, ctrl=ctrl)


def steps():
    mod = bc.install(A.zip)
    st = bc.state(mod)
    km = bpy.context.window_manager.keyconfigs.addon.keymaps["3D View"]
    assert any(k.idname == "deformd.sculpt" and k.type == "D" and k.ctrl and k.shift
               for k in km.keymap_items)
    bpy.ops.object.select_all(action="SELECT")
    bpy.ops.object.delete()
    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32, radius=1.0)
    obj = bpy.context.active_object
    obj.scale = (4.5, 3.0, 3.0)                  # object space != world space
    mod.prefs.get().brush_pixels = 20
    bpy.ops.deformd.connect(address="unix:" + A.socket)
    bpy.ops.deformd.share()
    sid = int(obj["deformd_session"])
    R["session"] = sid
    c2 = bc.client(mod, A.socket)
    w, a, r = view3d()
    # the add-on's panel drawn in the sidebar's open tab (Item): Blender 3.4 has no API to pick
    # a sidebar tab, so a subclass in the "Item" category runs the panel's own draw()
    drawn = {"n": 0}

    class ItemTabPanel(mod.panel.DEFORMD_PT_panel):
        bl_idname = "DEFORMD_PT_test_item"
        bl_category = "Item"

        def draw(self, context):
            super().draw(context)
            drawn["n"] += 1
    bpy.utils.register_class(ItemTabPanel)
    a.spaces[0].show_region_ui = True
    yield
    before_px = pixels(shot("before"))
    rest = bc.positions(obj).copy()
    w, a, r = view3d()
    cx, cy = r.x + r.width // 2, r.y + r.height // 2
    with bpy.context.temp_override(window=w, area=a, region=r):
        assert bpy.ops.deformd.sculpt("INVOKE_DEFAULT") == {"RUNNING_MODAL"}
    yield
    ticks0 = st.ticks
    drag(w, cx, cy, 60, 40, 12)                              # a grab stroke
    yield
    for _ in range(MAX_WAIT_STEPS):
        if mod.modal.STATS["last"] is not None:
            break
        yield
    grab = mod.modal.STATS["last"]
    assert not grab["twisting"]
    # object space -> world -> screen: the centre is under the press, centre + move under the
    # release (the view-plane move at the hit depth, through the object's scale)
    from bpy_extras.view3d_utils import location_3d_to_region_2d
    from mathutils import Vector
    mw = obj.matrix_world
    rv3d = a.spaces[0].region_3d
    p0 = location_3d_to_region_2d(r, rv3d, mw @ Vector(grab["center"]))
    p1 = location_3d_to_region_2d(r, rv3d, mw @ (Vector(grab["center"]) + Vector(grab["move"])))
    R["press_px"], R["release_px"] = tuple(p0), tuple(p1)
    assert abs(p0.x - r.width // 2) < 1.0 and abs(p0.y - r.height // 2) < 1.0, p0
    assert abs(p1.x - (r.width // 2 + 60)) < 1.0 and abs(p1.y - (r.height // 2 + 40)) < 1.0, p1
    drag(w, cx - 20, cy + 15, 45, 0, 8, ctrl=True)           # Ctrl: twist
    yield
    for _ in range(MAX_WAIT_STEPS):
        if mod.modal.STATS["last"]["twisting"]:
            break
        yield
    tw = mod.modal.STATS["last"]
    R["twist"] = list(tw["twist"])
    p = mod.prefs.get()
    assert abs(Vector(tw["twist"]).length - 45 * p.twist_per_pixel) < 1e-5, tw   # float32 math
    w.event_simulate(type="ESC", value="PRESS", x=cx, y=cy)
    w.event_simulate(type="ESC", value="RELEASE", x=cx, y=cy)
    yield
    # the modal strokes: Blender shows exactly the daemon's positions
    for _ in range(MAX_WAIT_STEPS):
        if st.mirrors[sid].version == c2.get_mesh(sid).version and not st.mirrors[sid].dirty:
            break
        yield
    mine = bc.positions(obj)
    assert np.array_equal(mine, bc.daemon_positions(c2, sid))
    assert not np.array_equal(mine, rest)
    R["versions"] = st.mirrors[sid].version
    R["max_displacement"] = float(np.abs(mine - rest).max())
    # a second user's stroke arrives through the 60 Hz timer alone (no sync call here)
    ack = c2.stroke(sid, mod.deformd_client.Brush(type="grab", center=(0.0, -1.0, 0.0),
                                                  move=(0.0, -0.1, 0.0), radius=0.5, nu=0.4))
    for _ in range(MAX_WAIT_STEPS):
        if st.mirrors[sid].version >= ack.version and not st.mirrors[sid].dirty:
            break
        yield
    assert np.array_equal(bc.positions(obj), bc.daemon_positions(c2, sid))
    R["timer_ticks"] = st.ticks - ticks0
    # large-mesh path: overlay while the stream runs, the mesh written when it pauses
    mod.prefs.get().overlay_threshold = 100
    mod.prefs.get().write_interval = 60.0
    draws0 = mod.overlay.STATS["draws"]
    c2.brush_begin(sid, mod.deformd_client.Brush(type="grab", center=(0.0, 0.0, 1.0),
                                                 radius=0.5))
    ack = c2.brush_update(sid, (0.0, 0.0, 0.2))
    shown = False
    for _ in range(MAX_WAIT_STEPS):
        if st.mirrors[sid].version >= ack.version and mod.overlay.STATS["draws"] > draws0:
            shown = True
            break
        yield
    assert shown, "the overlay was not drawn"
    c2.brush_end(sid)
    for _ in range(MAX_WAIT_STEPS):                          # the stream pauses: written
        if not st.mirrors[sid].dirty:
            break
        yield
    assert np.array_equal(bc.positions(obj), bc.daemon_positions(c2, sid))
    assert not mod.overlay.shown()
    mod.prefs.get().overlay_threshold = 10 ** 6
    # handle-drag mode: the top cap's vertices become handles and follow a simulated drag
    cur = bc.positions(obj)
    sel = cur[:, 2] > 0.9 * cur[:, 2].max()
    obj.data.vertices.foreach_set("select", sel)
    bpy.context.window_manager.deformd.handle_max_iters = 60
    bpy.ops.deformd.handles_set()
    v0 = st.mirrors[sid].version
    hstats = mod.handles.STATS
    with bpy.context.temp_override(window=w, area=a, region=r):
        assert bpy.ops.deformd.handle_drag("INVOKE_DEFAULT") == {"RUNNING_MODAL"}
    yield
    drag(w, cx, cy, 0, 40, 4)
    yield
    for _ in range(MAX_WAIT_STEPS):                          # every move answered
        if hstats["moves_sent"] and hstats["moves_done"] == hstats["moves_sent"]:
            break
        yield
    w.event_simulate(type="ESC", value="PRESS", x=cx, y=cy + 40)
    w.event_simulate(type="ESC", value="RELEASE", x=cx, y=cy + 40)
    yield
    for _ in range(MAX_WAIT_STEPS):
        if st.mirrors[sid].version > v0 and \
                st.mirrors[sid].version == c2.get_mesh(sid).version and not st.mirrors[sid].dirty:
            break
        yield
    after_drag = bc.positions(obj)
    assert np.array_equal(after_drag, bc.daemon_positions(c2, sid))
    R["handle_move"] = float(np.abs(after_drag[sel] - cur[sel]).max())
    assert R["handle_move"] > 0
    yield
    yield
    after_px = pixels(shot("after"))
    R["pixels_changed"] = int(np.count_nonzero(np.abs(after_px - before_px) > 1e-3))
    R["updates_sent"] = mod.modal.STATS["updates_sent"]
    R["blender_positions_hex"] = bc.positions(obj).tobytes().hex()
    R["panel_draws"] = drawn["n"]
    R["passed"] = R["pixels_changed"] > 0 and drawn["n"] > 0


def run():
    gen = steps()

    def step():
        try:
            next(gen)
            R["steps"] = R.get("steps", 0) + 1
            return STEP_S
        except StopIteration:
            finish(0 if R["passed"] else 1)
        except Exception:
            traceback.print_exc()
            finish(1)
        return None
    bpy.app.timers.register(step, first_interval=0.5)


def finish(code):
    bc.write_out(A.out, **R)
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


run()
