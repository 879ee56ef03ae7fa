"""Scriptable operators, one per action (pipelines and tests drive these; the panel's buttons
call them too). Every daemon or socket error becomes a report (self.report), never a traceback;
a lost connection leaves the objects as they were last synced."""
import bpy
import numpy as np

from . import brush_map, prefs, progress, props, sync, upload
from .connection import CLIENT_ERRORS, STATE, describe
from .dc import Brush

FLOAT3 = dict(size=3, subtype="XYZ")
MOVE_TIMEOUT_S = 600.0      # a handle solve may run long (max_iters 0: the daemon's default)
# Blender's progress indicator (0..100) over the WORK_PROGRESS stages of share and handles
SHARE_STAGES = {"upload": (0.0, 50.0), "parse": (50.0, 100.0)}
SET_STAGES = {"factorize": (0.0, 100.0)}
SOLVE_STAGES = {"factorize": (0.0, 10.0), "solve": (10.0, 100.0)}


def _fail(op, exc) -> set:
    msg = STATE.lost(exc)
    op.report({"ERROR"}, msg)
    return {"CANCELLED"}


def need_session(context) -> int:
    """The session of the active object (ValueError with the reason when there is none)."""
    if not STATE.connected:
        raise ValueError("not connected (deformd.connect first)")
    sid = sync.session_of(context.active_object)
    if not sid or sid not in STATE.mirrors:
        raise ValueError("the active object is not in a session (share or join first)")
    return sid


class DEFORMD_OT_connect(bpy.types.Operator):
    """Connect to a deformd daemon (and resync every object of the scene that names a session)"""
    bl_idname = "deformd.connect"
    bl_label = "Connect"
    address: bpy.props.StringProperty(name="Address", description="unix:PATH or HOST:PORT")

    def execute(self, context):
        p = prefs.get(context)
        addr = self.address or (p.address if p else "")
        try:
            STATE.connect(addr, p.key_file if p else "", p.tls_ca if p else "")
            sync.start_timer()
            n = sync.reattach_scene(context.scene)
            STATE.sessions = STATE.client.list_sessions() if STATE.connected else []
        except CLIENT_ERRORS as e:
            STATE.disconnect(describe(e))
            self.report({"ERROR"}, describe(e))
            return {"CANCELLED"}
        self.report({"INFO"}, "deformd: connected to %s%s" % (
            addr, " (%d object(s) resynced)" % n if n else ""))
        return {"FINISHED"}


class DEFORMD_OT_disconnect(bpy.types.Operator):
    """Disconnect; objects keep the positions they were last synced to"""
    bl_idname = "deformd.disconnect"
    bl_label = "Disconnect"

    def execute(self, context):
        STATE.disconnect()
        return {"FINISHED"}


class DEFORMD_OT_share(bpy.types.Operator):
    """Upload the active mesh object (evaluated, object space) as a new session"""
    bl_idname = "deformd.share"
    bl_label = "Share Active Object"
    name: bpy.props.StringProperty(name="Session name", default="")

    def execute(self, context):
        obj = context.active_object
        try:
            if not STATE.connected:
                raise ValueError("not connected (deformd.connect first)")
            data, nv = upload.object_ply(obj, context.evaluated_depsgraph_get())
            if nv != len(obj.data.vertices):
                raise ValueError("modifiers change %s's vertex count (%d -> %d): apply them "
                                 "first" % (obj.name, len(obj.data.vertices), nv))
            with progress.work(SHARE_STAGES) as cb:
                info = STATE.client.load_mesh(data, fmt=".ply", name=self.name or obj.name,
                                              file_name=obj.name + ".ply", progress=cb)
            if info.nv != nv:
                STATE.client.close_session(info.session_id)
                raise ValueError("deformd kept %d of %d vertices (loose vertices?): not shared"
                                 % (info.nv, nv))
            sync.attach(obj, info.session_id)
        except CLIENT_ERRORS as e:
            return _fail(self, e)
        self.report({"INFO"}, "deformd: %s shared as session %d" % (obj.name, info.session_id))
        return {"FINISHED"}


def _new_object(context, sid: int, name: str):
    """A mesh object built from the session's current mesh (triangles; a tet mesh's boundary)."""
    md = STATE.client.get_mesh(sid)
    pos = np.frombuffer(md.positions, dtype=np.float32)
    if md.elem_size == 3:
        tri = np.frombuffer(md.elements, dtype=np.uint32)
    elif md.nf:
        tri = np.frombuffer(md.faces, dtype=np.uint32)
    else:
        raise ValueError("session %d is not a surface or tet mesh: nothing to show" % sid)
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(md.nv)
    mesh.vertices.foreach_set("co", pos)
    nt = len(tri) // 3
    mesh.loops.add(3 * nt)
    mesh.loops.foreach_set("vertex_index", tri.astype(np.uint32))   # uint32: the raw-copy path
    mesh.polygons.add(nt)
    mesh.polygons.foreach_set("loop_start", np.arange(0, 3 * nt, 3, dtype=np.uint32))
    mesh.polygons.foreach_set("loop_total", np.full(nt, 3, dtype=np.uint32))
    mesh.update()
    obj = bpy.data.objects.new(name, mesh)
    context.collection.objects.link(obj)
    context.view_layer.objects.active = obj
    return obj


class DEFORMD_OT_join(bpy.types.Operator):
    """Join a session (id or name) onto the active mesh object (same vertex count), or into a
    new object built from the session's mesh"""
    bl_idname = "deformd.join"
    bl_label = "Join Session"
    session: bpy.props.StringProperty(name="Session", description="Session id or name")

    def execute(self, context):
        key = self.session or props.get(context).join_session
        try:
            if not STATE.connected:
                raise ValueError("not connected (deformd.connect first)")
            if not key or key == "0":
                raise ValueError("no session given")
            c = STATE.client
            info = c.open_session(int(key)) if key.isdigit() else c.open_session(0, key)
            obj = context.active_object
            if obj is None or obj.type != "MESH" or len(obj.data.vertices) != info.nv:
                obj = _new_object(context, info.session_id, info.name or "session")
            sync.attach(obj, info.session_id)
        except CLIENT_ERRORS as e:
            return _fail(self, e)
        self.report({"INFO"}, "deformd: %s joined session %d" % (obj.name, info.session_id))
        return {"FINISHED"}


class DEFORMD_OT_stroke(bpy.types.Operator):
    """One whole brush stroke (object space) on the active object's session; parameters left
    unset take the session brush shown in the panel"""
    bl_idname = "deformd.stroke"
    bl_label = "Stroke"
    brush: bpy.props.EnumProperty(name="Brush", items=props.BRUSH_TYPES)
    center: bpy.props.FloatVectorProperty(name="Center", **FLOAT3)
    move: bpy.props.FloatVectorProperty(name="Move", **FLOAT3)
    twist: bpy.props.FloatVectorProperty(name="Twist", description="Rotation vector (rad)",
                                         **FLOAT3)
    scale: bpy.props.FloatProperty(name="Scale", description="Dilation at the centre")
    pinch: bpy.props.FloatVectorProperty(name="Pinch", size=9,
                                         description="Centre gradient, row-major 3x3 "
                                                     "(symmetric traceless for pinch)")
    radius: bpy.props.FloatProperty(name="Radius", default=0.1, min=1e-6)
    nu: bpy.props.FloatProperty(name="Nu", default=0.45, min=-1.0, max=0.5)
    strength: bpy.props.FloatProperty(name="Strength", default=1.0)
    falloff: bpy.props.IntProperty(name="Falloff", default=1, min=1, max=8)
    ratio: bpy.props.FloatProperty(name="Ratio", default=1.1, min=1.0001)

    def _value(self, context, name):
        if self.properties.is_property_set(name):
            return getattr(self, name)
        return getattr(props.get(context), "brush_" + name)

    def execute(self, context):
        try:
            sid = need_session(context)
            btype = self.brush if self.properties.is_property_set("brush") else \
                props.get(context).brush_type
            b = Brush(type=btype, center=tuple(self.center), radius=self._value(context, "radius"),
                      nu=self._value(context, "nu"), strength=self._value(context, "strength"),
                      falloff=self._value(context, "falloff"), ratio=self._value(context, "ratio"))
            if btype == "grab":
                b.move = tuple(self.move)
            elif btype == "twist":
                b.twist = tuple(self.twist)
            elif btype == "scale":
                b.scale = self.scale
            else:
                b.matrix = tuple(self.pinch)
            STATE.client.stroke(sid, b)
        except CLIENT_ERRORS as e:
            return _fail(self, e)
        err = sync.tick(force=True)
        if err:
            self.report({"ERROR"}, err)
            return {"CANCELLED"}
        return {"FINISHED"}


class DEFORMD_OT_sync(bpy.types.Operator):
    """Apply every version that has arrived now (what the 60 Hz timer does), writing large
    meshes too"""
    bl_idname = "deformd.sync"
    bl_label = "Sync"

    def execute(self, context):
        if not STATE.connected:
            self.report({"ERROR"}, "deformd: not connected")
            return {"CANCELLED"}
        err = sync.tick(force=True)
        if err:
            self.report({"ERROR"}, err)
            return {"CANCELLED"}
        return {"FINISHED"}


class _History:
    def execute(self, context):
        try:
            sid = need_session(context)
            getattr(STATE.client, self.action)(sid)
        except CLIENT_ERRORS as e:
            return _fail(self, e)
        err = sync.tick(force=True)
        if err:
            self.report({"ERROR"}, err)
            return {"CANCELLED"}
        return {"FINISHED"}


class DEFORMD_OT_undo(_History, bpy.types.Operator):
    """Undo the session's last change (for everyone in the session)"""
    bl_idname = "deformd.undo"
    bl_label = "Undo"
    action = "undo"


class DEFORMD_OT_redo(_History, bpy.types.Operator):
    """Redo the session's last undone change"""
    bl_idname = "deformd.redo"
    bl_label = "Redo"
    action = "redo"


class DEFORMD_OT_list_sessions(bpy.types.Operator):
    """Refresh the list of the daemon's sessions"""
    bl_idname = "deformd.list_sessions"
    bl_label = "Refresh Sessions"

    def execute(self, context):
        try:
            if not STATE.connected:
                raise ValueError("not connected (deformd.connect first)")
            STATE.sessions = STATE.client.list_sessions()
            for s in STATE.sessions:           # the panel's count (and peers.py's trigger)
                if s.session_id == STATE.current_sid:
                    STATE.subscribers = s.subscribers
        except CLIENT_ERRORS as e:
            return _fail(self, e)
        return {"FINISHED"}


class DEFORMD_OT_brush_from_elastic(bpy.types.Operator):
    """Set the session brush from the active sculpt brush (Elastic Deform: type, falloff and
    ratio, volume preservation as nu clamped to 0.5, strength)"""
    bl_idname = "deformd.brush_from_elastic"
    bl_label = "Use Elastic Deform Brush"

    def execute(self, context):
        try:
            sid = need_session(context)
            sculpt = context.tool_settings.sculpt
            brush = sculpt.brush if sculpt is not None else None
            if brush is None:
                raise ValueError("no active sculpt brush")
            fields = brush_map.from_brush(brush)
            props.set_from_state(props.get(context),
                                 STATE.client.brush_state_set(sid, **fields))
        except CLIENT_ERRORS as e:
            return _fail(self, e)
        return {"FINISHED"}


def selected_vertices(obj) -> np.ndarray:
    if obj.mode == "EDIT":
        obj.update_from_editmode()
    sel = np.empty(len(obj.data.vertices), dtype=bool)
    obj.data.vertices.foreach_get("select", sel)
    return np.flatnonzero(sel).astype(np.uint32)


class DEFORMD_OT_handles_set(bpy.types.Operator):
    """The selected vertices become the session's handles (energy, w, s from the panel)"""
    bl_idname = "deformd.handles_set"
    bl_label = "Set Handles"

    def execute(self, context):
        try:
            sid = need_session(context)
            idx = selected_vertices(context.active_object)
            if not len(idx):
                raise ValueError("select the handle vertices first")
            p = props.get(context)
            with progress.work(SET_STAGES) as cb:
                STATE.client.set_handles(sid, idx.tolist(), energy=p.handle_energy,
                                         w=p.handle_w, s=p.handle_s, progress=cb)
        except CLIENT_ERRORS as e:
            return _fail(self, e)
        self.report({"INFO"}, "deformd: %d handle(s)" % len(idx))
        return {"FINISHED"}


def handle_targets(sid: int, offset) -> list:
    """Current positions of the session's handles moved by `offset` (object space)."""
    hs = STATE.client.get_handles(sid)
    pos = STATE.mirrors[sid].positions()[np.asarray(hs.handles, dtype=np.int64)]
    return (pos.astype(np.float64) + np.asarray(offset, dtype=np.float64)).tolist()


class DEFORMD_OT_handles_move(bpy.types.Operator):
    """Move every handle by an offset (object space) and solve (progress shown meanwhile: the
    solve's WORK_PROGRESS; no PROGRESS iterates, whose indicator would start over after it)"""
    bl_idname = "deformd.handles_move"
    bl_label = "Move Handles"
    offset: bpy.props.FloatVectorProperty(name="Offset", **FLOAT3)
    max_iters: bpy.props.IntProperty(name="Max iterations", default=0, min=0)

    def execute(self, context):
        try:
            sid = need_session(context)
            with progress.work(SOLVE_STAGES) as cb:
                STATE.client.move_handles(sid, handle_targets(sid, self.offset),
                                          max_iters=self.max_iters, progress_every=0,
                                          timeout=MOVE_TIMEOUT_S, progress=cb)
        except CLIENT_ERRORS as e:
            return _fail(self, e)
        err = sync.tick(force=True)
        if err:
            self.report({"ERROR"}, err)
            return {"CANCELLED"}
        return {"FINISHED"}


CLASSES = (DEFORMD_OT_connect, DEFORMD_OT_disconnect, DEFORMD_OT_share, DEFORMD_OT_join,
           DEFORMD_OT_stroke, DEFORMD_OT_sync, DEFORMD_OT_undo, DEFORMD_OT_redo,
           DEFORMD_OT_list_sessions, DEFORMD_OT_brush_from_elastic, DEFORMD_OT_handles_set,
           DEFORMD_OT_handles_move)
