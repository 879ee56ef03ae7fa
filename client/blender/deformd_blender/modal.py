"""The interactive sculpt operator: left drag in the 3D view -> BRUSH_BEGIN / UPDATE / END.

The centre is a ray cast onto the object (object space); the mouse moves in the view plane at the
hit depth, converted to object space (scale and rotation respected: the inverse of the object's
3x3 matrix); the radius is the preference's brush size in pixels unprojected at the hit depth.
Ctrl at the press: a twist brush, the horizontal drag turning about the view axis. At most one
BRUSH_UPDATE is in flight: newer mouse positions replace the pending load and go out when the
reply arrives (the 60 Hz timer applies the versions). Esc / right click cancels the stroke."""
import bpy
from bpy_extras import view3d_utils
from mathutils import Vector

from . import prefs, props, sync
from .connection import CLIENT_ERRORS, STATE
from .dc import Brush, MsgType, messages
from .operators import need_session

TICK_S = 1.0 / 120.0
STATS = {"updates_sent": 0, "strokes": 0, "last": None}   # last: the last stroke's loads


def hit_point(context, obj, coord):
    """World and object-space hit of the mouse ray on obj, or (None, None)."""
    region, rv3d = context.region, context.region_data
    origin = view3d_utils.region_2d_to_origin_3d(region, rv3d, coord)
    direction = view3d_utils.region_2d_to_vector_3d(region, rv3d, coord)
    inv = obj.matrix_world.inverted()
    o = inv @ origin
    d = (inv.to_3x3() @ direction).normalized()
    ok, loc, _n, _i = obj.ray_cast(o, d, depsgraph=context.evaluated_depsgraph_get())
    if not ok:
        return None, None
    return obj.matrix_world @ loc, loc


def view_plane_point(context, coord, depth_world):
    return view3d_utils.region_2d_to_location_3d(context.region, context.region_data, coord,
                                                 depth_world)


class DEFORMD_OT_sculpt(bpy.types.Operator):
    """Sculpt the active object's session with the mouse (left drag; Ctrl: twist; Esc: cancel)"""
    bl_idname = "deformd.sculpt"
    bl_label = "Sculpt (deformd)"

    def invoke(self, context, event):
        try:
            self.sid = need_session(context)
        except ValueError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        if context.area is None or context.area.type != "VIEW_3D":
            self.report({"ERROR"}, "deformd: run the sculpt operator in a 3D view")
            return {"CANCELLED"}
        self.obj = context.active_object
        self.stroking = False
        self.rid = 0            # the BRUSH_UPDATE in flight (0: none)
        self.pending = None     # the newest load not yet sent: (move, twist)
        self.sent = None        # the last load sent
        self.timer = context.window_manager.event_timer_add(TICK_S, window=context.window)
        context.window_manager.modal_handler_add(self)
        context.workspace.status_text_set("deformd: drag to sculpt, Ctrl-drag twists, "
                                          "Esc / right click ends")
        return {"RUNNING_MODAL"}

    # ------------------------------------------------------------------ loads
    def _begin(self, context, event) -> bool:
        coord = (event.mouse_region_x, event.mouse_region_y)
        hw, ho = hit_point(context, self.obj, coord)
        if hw is None:
            return False
        p = prefs.get(context)
        px = p.brush_pixels if p else 60
        edge_w = view_plane_point(context, (coord[0] + px, coord[1]), hw)
        inv = self.obj.matrix_world.inverted()
        radius = max((inv @ edge_w - ho).length, 1e-6)
        self.hit_world, self.coord0 = hw, coord
        self.inv3 = inv.to_3x3()
        self.twisting = event.ctrl
        rv3d = context.region_data
        view_dir = rv3d.view_rotation @ Vector((0.0, 0.0, -1.0))
        self.axis = (self.inv3 @ view_dir).normalized()
        self.twist_rate = p.twist_per_pixel if p else 0.01
        w = props.get(context)
        b = Brush(type="twist" if self.twisting else "grab", center=tuple(ho), radius=radius,
                  nu=w.brush_nu, strength=w.brush_strength, falloff=w.brush_falloff,
                  ratio=w.brush_ratio)
        STATE.client.brush_begin(self.sid, b)
        self.radius = radius
        self.center = tuple(ho)
        self.sent = self.pending = None       # loads are per stroke (cumulative since begin)
        self.stroking = True
        STATE.stroke_active = True
        STATS["strokes"] += 1
        return True

    def _load(self, context, event):
        coord = (event.mouse_region_x, event.mouse_region_y)
        if self.twisting:
            angle = (coord[0] - self.coord0[0]) * self.twist_rate
            return None, tuple(self.axis * angle)
        now_w = view_plane_point(context, coord, self.hit_world)
        return tuple(self.inv3 @ (now_w - self.hit_world)), None

    def _pump(self) -> None:
        """Collects the in-flight reply (never blocking) and sends the pending load."""
        c = STATE.client
        if self.rid:
            if c.poll_reply(self.rid) is None:
                return
            self.rid = 0
        if self.pending is not None and self.pending != self.sent:
            move, twist = self.pending
            self.rid = c.send(MsgType.BRUSH_UPDATE,
                              messages.encode_brush_update(self.sid, move, twist))
            self.sent = self.pending
            STATS["updates_sent"] += 1
        self.pending = None

    def _finish(self, cancel: bool) -> None:
        c = STATE.client
        if self.rid:
            c.wait_reply(self.rid)
            self.rid = 0
        final = self.sent
        if not cancel and self.pending is not None and self.pending != self.sent:
            c.brush_update(self.sid, *self.pending)
            final = self.pending
        STATS["last"] = {"center": self.center, "radius": self.radius, "twisting": self.twisting,
                         "move": final[0] if final else None,
                         "twist": final[1] if final else None}
        if cancel:
            c.brush_cancel(self.sid)
        else:
            c.brush_end(self.sid)
        self.stroking = False
        STATE.stroke_active = False

    # ------------------------------------------------------------------ events
    def modal(self, context, event):
        try:
            return self._modal(context, event)
        except CLIENT_ERRORS as e:
            msg = STATE.lost(e)
            self.report({"ERROR"}, msg)
            self._cleanup(context)
            return {"CANCELLED"}

    def _modal(self, context, event):
        if not STATE.connected or self.sid not in STATE.mirrors:
            self._cleanup(context)
            return {"CANCELLED"}
        if event.type in ("ESC", "RIGHTMOUSE") and event.value == "PRESS":
            if self.stroking:
                self._finish(cancel=True)
            self._cleanup(context)
            sync.tick(force=True)
            return {"CANCELLED"}
        if event.type == "LEFTMOUSE" and event.value == "PRESS" and not self.stroking:
            if not self._begin(context, event):
                return {"PASS_THROUGH"}
            return {"RUNNING_MODAL"}
        if event.type == "LEFTMOUSE" and event.value == "RELEASE" and self.stroking:
            self.pending = self._load(context, event)
            self._finish(cancel=False)
            sync.tick(force=True)
            return {"RUNNING_MODAL"}
        if event.type == "MOUSEMOVE" and self.stroking:
            self.pending = self._load(context, event)
            self._pump()
            return {"RUNNING_MODAL"}
        if event.type == "TIMER" and self.stroking:
            self._pump()
            return {"RUNNING_MODAL"}
        if event.type in ("RET", "NUMPAD_ENTER") and event.value == "PRESS" and not self.stroking:
            self._cleanup(context)
            return {"FINISHED"}
        return {"PASS_THROUGH"}

    def _cleanup(self, context) -> None:
        STATE.stroke_active = False
        if getattr(self, "timer", None) is not None:
            context.window_manager.event_timer_remove(self.timer)
            self.timer = None
        context.workspace.status_text_set(None)


CLASSES = (DEFORMD_OT_sculpt,)
