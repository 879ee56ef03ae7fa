"""Window-manager properties the panel shows (runtime only, never saved in the .blend): the
session brush, mirrored from BRUSH_STATE events and sent back with BRUSH_STATE_SET when the user
edits a value; the handle-drag settings; the session to join."""
import bpy

from .connection import CLIENT_ERRORS, STATE

BRUSH_TYPES = [(t, t.capitalize(), "") for t in ("grab", "twist", "scale", "pinch", "affine")]
ENERGIES = [("arap", "ARAP", "As-rigid-as-possible"),
            ("neo_hookean", "Neo-Hookean", "Neo-Hookean elastic energy")]
BRUSH_FIELDS = ("type", "radius", "nu", "strength", "falloff", "ratio")


def _send_brush_field(field):
    def update(self, context):
        if STATE.applying_remote or not STATE.connected or not STATE.current_sid:
            return
        value = getattr(self, "brush_" + field)
        try:
            st = STATE.client.brush_state_set(STATE.current_sid, **{field: value})
            set_from_state(self, st)
        except CLIENT_ERRORS as e:
            STATE.lost(e)
    return update


def set_from_state(wm_props, st) -> None:
    """Shows a BrushState (event or reply) in the panel without echoing it back. A state older
    than the one shown (seq below the shown one's, same session: an event queued before a
    BRUSH_STATE_GET reply that already showed it) is ignored."""
    shown = STATE.brush_shown
    if shown[0] == st.session_id and st.seq < shown[1]:
        return
    STATE.brush_shown = (st.session_id, st.seq)
    STATE.brush_states_shown += 1
    STATE.applying_remote = True
    try:
        for f in BRUSH_FIELDS:
            setattr(wm_props, "brush_" + f, getattr(st, f))
        STATE.last_changer = st.origin_name
    finally:
        STATE.applying_remote = False


_ITEMS = []   # Blender keeps only pointers to dynamic enum strings: hold them here


def session_items(self, context):
    items = [(str(s.session_id), "%s (#%d, %d verts)" % (s.name or "unnamed", s.session_id, s.nv),
              "%d subscriber(s), version %d" % (s.subscribers, s.version))
             for s in STATE.sessions]
    _ITEMS[:] = items or [("0", "(no sessions listed)", "")]
    return _ITEMS


class DeformdProps(bpy.types.PropertyGroup):
    brush_type: bpy.props.EnumProperty(name="Type", items=BRUSH_TYPES,
                                       update=_send_brush_field("type"))
    brush_radius: bpy.props.FloatProperty(name="Radius", default=0.1, min=1e-6,
                                          precision=4, update=_send_brush_field("radius"))
    brush_nu: bpy.props.FloatProperty(name="Nu", default=0.45, min=-1.0, max=0.5,
                                      update=_send_brush_field("nu"))
    brush_strength: bpy.props.FloatProperty(name="Strength", default=1.0,
                                            update=_send_brush_field("strength"))
    brush_falloff: bpy.props.IntProperty(name="Falloff", default=1, min=1, max=8,
                                         update=_send_brush_field("falloff"))
    brush_ratio: bpy.props.FloatProperty(name="Ratio", default=1.1, min=1.0001,
                                         update=_send_brush_field("ratio"))
    join_session: bpy.props.EnumProperty(name="Session", items=session_items)
    handle_energy: bpy.props.EnumProperty(name="Energy", items=ENERGIES)
    handle_w: bpy.props.FloatProperty(name="w", default=1e-4, min=0.0, precision=6)
    handle_s: bpy.props.FloatProperty(name="s", default=0.01, min=0.0, precision=4)
    handle_max_iters: bpy.props.IntProperty(name="Max iterations", default=0, min=0,
                                            description="Per drag move; 0: the daemon's default")


def get(context=None):
    return (context or bpy.context).window_manager.deformd


def register_props():
    bpy.types.WindowManager.deformd = bpy.props.PointerProperty(type=DeformdProps)


def unregister_props():
    del bpy.types.WindowManager.deformd


CLASSES = (DeformdProps,)
