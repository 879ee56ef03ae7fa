"""The sidebar panel (3D view > N > deformd): connection, share / join, the session brush (live:
BRUSH_STATE events update it; edits send BRUSH_STATE_SET), handles, undo / redo, who else is in
the session, the update rate."""
import bpy

from . import overlay, peers, props, sync
from .connection import STATE


class DEFORMD_PT_panel(bpy.types.Panel):
    bl_label = "deformd"
    bl_idname = "DEFORMD_PT_panel"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "deformd"

    def draw(self, context):
        lay = self.layout
        w = props.get(context)
        box = lay.box()
        box.label(text=STATE.status, icon="LINKED" if STATE.connected else "UNLINKED")
        if STATE.last_error:
            box.label(text=STATE.last_error, icon="ERROR")
        row = box.row()
        row.operator("deformd.connect")
        row.operator("deformd.disconnect")
        if not STATE.connected:
            return
        sid = sync.session_of(context.active_object)
        col = lay.column(align=True)
        col.operator("deformd.share")
        row = col.row(align=True)
        row.prop(w, "join_session", text="")
        row.operator("deformd.list_sessions", text="", icon="FILE_REFRESH")
        col.operator("deformd.join").session = ""
        if not sid or sid not in STATE.mirrors:
            return
        m = STATE.mirrors[sid]
        lay.label(text="Session %d, version %d, %d vertices" % (sid, m.version, m.nv))
        lay.label(text="Subscribers: %d (you included)" % STATE.subscribers)
        _draw_peers(lay)
        if STATE.last_changer:
            lay.label(text="Brush last changed by: %s" % STATE.last_changer)
        if STATE.resumed_replay or STATE.resumed_snapshot:
            lay.label(text="Reconnects resynced: %d by replay, %d by snapshot"
                      % (STATE.resumed_replay, STATE.resumed_snapshot))
        box = lay.box()
        box.label(text="Session brush")
        for f in props.BRUSH_FIELDS:
            box.prop(w, "brush_" + f)
        box.operator("deformd.brush_from_elastic")
        lay.operator("deformd.sculpt", icon="SCULPTMODE_HLT")
        row = lay.row(align=True)
        row.operator("deformd.undo", icon="LOOP_BACK")
        row.operator("deformd.redo", icon="LOOP_FORWARDS")
        box = lay.box()
        box.label(text="Handle drag (selected vertices)")
        box.prop(w, "handle_energy")
        row = box.row()
        row.prop(w, "handle_w")
        row.prop(w, "handle_s")
        box.prop(w, "handle_max_iters")
        box.operator("deformd.handles_set")
        box.operator("deformd.handle_drag")
        lay.label(text="Mesh writes: %.0f Hz, last %.1f ms%s" % (
            STATE.rate_now(), STATE.last_apply_ms, " (overlay live)" if overlay.shown() else ""))


def peer_line(p) -> str:
    """One peer of the panel's list: its HELLO name (else its principal), then its principal
    when the name is shown, its transport when TCP, and "observer" when it may not edit."""
    text = p.label
    if p.name and p.principal:
        text += " (%s)" % p.principal
    if p.transport_name == "tcp":
        text += ", tcp"
    if not p.can_edit:
        text += ", observer"
    return text


def _draw_peers(lay) -> None:
    """Who else is connected (SESSION_PEERS, refreshed by the timer about once a second)."""
    rows = peers.others()
    box = lay.box()
    box.label(text="Also connected: %d" % len(rows), icon="COMMUNITY")
    for p in rows:
        box.label(text=peer_line(p), icon="USER")


CLASSES = (DEFORMD_PT_panel,)
