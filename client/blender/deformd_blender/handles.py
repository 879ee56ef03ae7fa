"""Handle-drag mode: the session's handles (deformd.handles_set: the selected vertices) follow a
left drag in the view plane (at the handles' centroid depth, converted to object space) and the
daemon solves the energy chosen in the panel (HANDLES_MOVE). One move is in flight at a time;
newer mouse positions wait and go out when its reply arrives (the daemon would supersede it
anyway). Nothing blocks: after the release the last targets go out when the move in flight
answers, and the 60 Hz timer shows the iterates (PROGRESS events, with Blender's progress
indicator). Esc / right click / Enter leaves the mode. Max iterations: the panel's value (0: the
daemon's default)."""
import bpy
import numpy as np
from bpy_extras import view3d_utils
from mathutils import Vector

from . import props, sync
from .connection import CLIENT_ERRORS, STATE
from .dc import MsgType, messages
from .operators import need_session

TICK_S = 1.0 / 60.0
STATS = {"moves_sent": 0, "moves_done": 0}


class DEFORMD_OT_handle_drag(bpy.types.Operator):
    """Drag the session's handles with the mouse (left drag; Esc / right click ends)"""
    bl_idname = "deformd.handle_drag"
    bl_label = "Drag Handles"

    def invoke(self, context, event):
        try:
            self.sid = need_session(context)
            hs = STATE.client.get_handles(self.sid)
        except CLIENT_ERRORS as e:
            self.report({"ERROR"}, STATE.lost(e))
            return {"CANCELLED"}
        if context.area is None or context.area.type != "VIEW_3D":
            self.report({"ERROR"}, "deformd: run handle drag in a 3D view")
            return {"CANCELLED"}
        self.idx = np.asarray(hs.handles, dtype=np.int64)
        self.max_iters = props.get(context).handle_max_iters
        self.obj = context.active_object
        self.dragging = False
        self.rid = 0
        self.pending = None
        self.timer = context.window_manager.event_timer_add(TICK_S, window=context.window)
        context.window_manager.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def _targets(self, context, event):
        coord = (event.mouse_region_x, event.mouse_region_y)
        now_w = view3d_utils.region_2d_to_location_3d(context.region, context.region_data,
                                                      coord, self.anchor_w)
        off = self.inv3 @ (now_w - self.anchor_w)
        return (self.start + np.asarray(off, dtype=np.float64)).tolist()

    def _pump(self):
        c = STATE.client
        if self.rid:
            if c.poll_reply(self.rid) is None:
                return
            self.rid = 0
            STATS["moves_done"] += 1
        if self.pending is not None:
            self.rid = c.send(MsgType.HANDLES_MOVE, messages.encode_handle_move(
                self.sid, self.pending, self.max_iters, 0, 10))
            self.pending = None
            STATS["moves_sent"] += 1

    def modal(self, context, event):
        try:
            return self._modal(context, event)
        except CLIENT_ERRORS as e:
            self.report({"ERROR"}, STATE.lost(e))
            self._cleanup(context)
            return {"CANCELLED"}

    def _modal(self, context, event):
        if not STATE.connected or self.sid not in STATE.mirrors:
            self._cleanup(context)
            return {"CANCELLED"}
        if event.value == "PRESS" and event.type in ("ESC", "RIGHTMOUSE", "RET"):
            self._cleanup(context)
            return {"FINISHED"}
        if event.type == "LEFTMOUSE" and event.value == "PRESS":
            m = STATE.mirrors[self.sid]
            self.start = m.positions()[self.idx].astype(np.float64)
            mw = self.obj.matrix_world
            self.anchor_w = mw @ Vector(self.start.mean(axis=0).tolist())
            self.inv3 = mw.inverted().to_3x3()
            self.dragging = True
            STATE.stroke_active = True
            return {"RUNNING_MODAL"}
        if event.type == "MOUSEMOVE" and self.dragging:
            self.pending = self._targets(context, event)
            self._pump()
            return {"RUNNING_MODAL"}
        if event.type == "TIMER" and (self.dragging or self.rid or self.pending is not None):
            self._pump()
            if not (self.dragging or self.rid or self.pending is not None):
                sync.tick(force=True)
            return {"RUNNING_MODAL"}
        if event.type == "LEFTMOUSE" and event.value == "RELEASE" and self.dragging:
            self.pending = self._targets(context, event)
            self._pump()
            self.dragging = False
            STATE.stroke_active = False
            return {"RUNNING_MODAL"}
        return {"PASS_THROUGH"}

    def _cleanup(self, context):
        STATE.stroke_active = False
        if getattr(self, "timer", None) is not None:
            context.window_manager.event_timer_remove(self.timer)
            self.timer = None


CLASSES = (DEFORMD_OT_handle_drag,)
