"""Bringing sessions onto objects and keeping them in sync: attach() (subscribe, base positions,
snapshot), tick() (the 60 Hz timer and deformd.sync: non-blocking read, every version applied to
the numpy replica, one mesh write per object; the session list and the peer list, peers.py,
requested and collected without waiting), resync on a gap, and the timer itself."""
import bpy
import numpy as np

from . import overlay, peers, prefs, progress
from . import props as panel_props
from .connection import CLIENT_ERRORS, STATE, TIMEOUT_S as STATE_TIMEOUT_S, describe, now
from .dc import MsgType, messages
from .mirror import SNAPSHOT as SNAPSHOT_KIND, Gap, Mirror

TIMER_INTERVAL_S = 1.0 / 60.0
LIST_EVERY_S = 2.0
QUIET_S = 0.25     # overlay mode: the stream is paused after this long without a version
SESSION_KEY = "deformd_session"   # object custom property: the session id (a string: u64)


def session_of(obj) -> int:
    """The session id kept on an object (0: none)."""
    try:
        return int(obj.get(SESSION_KEY, "0")) if obj is not None else 0
    except (TypeError, ValueError):
        return 0


def attach(obj, sid: int) -> Mirror:
    """Subscribes to session `sid` and shows it on mesh object `obj` (the same vertex count):
    base positions, the current version from a snapshot, the mesh written. Raises CLIENT_ERRORS
    (ValueError for a vertex count mismatch, nothing changed then)."""
    c = STATE.client
    info = c.subscribe(sid)
    if info.nv != len(obj.data.vertices):
        c.unsubscribe(sid)
        raise ValueError("session %d has %d vertices, object %s has %d"
                         % (sid, info.nv, obj.name, len(obj.data.vertices)))
    mesh = c.get_mesh(sid, base=True)
    m = Mirror(sid, obj.name, np.frombuffer(mesh.base, dtype=np.float32))
    m.apply(c.snapshot(sid))
    STATE.mirrors[sid] = m
    obj[SESSION_KEY] = str(sid)
    STATE.current_sid = sid
    STATE.subscribers = info.subscribers
    m.write(obj.data)
    STATE.mesh_writes += 1
    panel_props.set_from_state(panel_props.get(), c.brush_state_get(sid))
    return m


def resync(m: Mirror) -> None:
    """Replaces the replica's displacements by a dense snapshot of the current version."""
    m.apply(STATE.client.snapshot(m.sid))
    STATE.resyncs += 1


def resume(obj, m: Mirror) -> Mirror:
    """Subscribes again to the session of a mirror held since the last disconnect and brings it
    to the current version by SUBSCRIBE from_version = m.version (PROTOCOL.md 6.2): the daemon
    replays the versions missed, or sends one snapshot when it no longer keeps them (or the
    session never reached m.version); the replica applies either. Counts STATE.resumed_replay /
    STATE.resumed_snapshot. Raises CLIENT_ERRORS; ValueError for a vertex count that changed."""
    c = STATE.client
    start = m.version
    info = c.subscribe(m.sid, from_version=start)
    if info.nv != m.nv or len(obj.data.vertices) != m.nv:
        c.unsubscribe(m.sid)
        raise ValueError("session %d has %d vertices, object %s has %d"
                         % (m.sid, info.nv, obj.name, len(obj.data.vertices)))
    STATE.mirrors[m.sid] = m
    mode = "replay" if info.version == start else None
    # the resync frames come first on the connection: read until the first one says which
    # (a snapshot carries kind SNAPSHOT) and the replica holds the reply's version
    while mode is None or m.version != info.version:
        ev = c.next_event(timeout=STATE_TIMEOUT_S)
        if ev is None:
            raise TimeoutError("session %d: no resync frame within %g s"
                               % (m.sid, STATE_TIMEOUT_S))
        d = getattr(ev, "disp", ev)
        if mode is None and getattr(d, "session_id", 0) == m.sid and hasattr(d, "kind"):
            mode = "snapshot" if d.kind == SNAPSHOT_KIND else "replay"
        _take(ev)
        if STATE.mirrors.get(m.sid) is not m:
            raise ValueError("session %d was closed during its resync" % m.sid)
    if mode == "replay":
        STATE.resumed_replay += 1
    else:
        STATE.resumed_snapshot += 1
    STATE.current_sid = m.sid
    STATE.subscribers = info.subscribers
    m.write(obj.data)
    STATE.mesh_writes += 1
    panel_props.set_from_state(panel_props.get(), c.brush_state_get(m.sid))
    return m


def reattach_scene(scene) -> int:
    """After a (re)connect: every object of `scene` that names a session is subscribed again and
    resynced: by resume() when this Blender still holds the object's replica from before the
    disconnect (same object, same vertex count), else by attach() (a full snapshot). Returns
    how many; objects whose session is gone keep their positions."""
    n = 0
    held, STATE.held = (STATE.held if STATE.held_address == STATE.address else {}), {}
    for obj in scene.objects:
        sid = session_of(obj)
        if sid and obj.type == "MESH" and sid not in STATE.mirrors:
            m = held.get(sid)
            try:
                if m is not None and m.object_name == obj.name and \
                        m.nv == len(obj.data.vertices):
                    resume(obj, m)
                else:
                    attach(obj, sid)
                n += 1
            except CLIENT_ERRORS as e:
                STATE.last_error = describe(e)
                if not STATE.connected:
                    break
    return n


def _take(ev) -> None:
    kind = getattr(ev, "kind_name", "")
    if kind == "brush_state":
        if ev.session_id == STATE.current_sid:
            panel_props.set_from_state(panel_props.get(), ev)
        return
    if kind in ("brush_cursor", "device_state"):
        return
    if kind == "session_closed":
        STATE.mirrors.pop(ev.session_id, None)
        STATE.last_error = "session %d was closed" % ev.session_id
        return
    sid = getattr(getattr(ev, "disp", ev), "session_id", 0)
    m = STATE.mirrors.get(sid)
    if m is None:
        return
    if getattr(ev, "lost", False):
        resync(m)
        return
    if hasattr(ev, "disp"):
        progress.show(ev)
    try:
        if m.apply(ev):
            STATE.versions_applied += 1
    except Gap:
        resync(m)
    m.last_arrival_t = now()


def _write(m: Mirror, force: bool, t: float) -> None:
    obj = bpy.data.objects.get(m.object_name)
    if obj is None or obj.type != "MESH" or len(obj.data.vertices) != m.nv:
        STATE.mirrors.pop(m.sid, None)
        return
    if not m.dirty or obj.mode == "EDIT":
        return
    p = prefs.get()
    big = p is not None and m.nv > p.overlay_threshold
    if big and not force:
        overlay.show(m, obj)
        live = STATE.stroke_active or t - m.last_arrival_t < QUIET_S
        if live and t - m.last_write_t < (p.write_interval if p else 0.5):
            return
    t0 = now()
    m.write(obj.data)
    t1 = now()
    if m.last_write_t:
        STATE.note_rate(t1 - m.last_write_t)
    m.last_write_t = t1
    STATE.last_write_t = t1
    STATE.last_apply_ms = (t1 - t0) * 1e3
    STATE.mesh_writes += 1
    if big:
        overlay.hide(m.sid)


def tick(force: bool = False) -> str:
    """Applies what has arrived (never blocking on the socket; a snapshot request only on a gap)
    and writes each changed object once. force: write large meshes now too (deformd.sync).
    Returns "" or the error text (the connection is closed when it was lost)."""
    STATE.ticks += 1
    c = STATE.client
    if c is None:
        return ""
    t = now()
    try:
        evs = c.poll()
        for ev in evs:
            _take(ev)
        t = now()
        for m in list(STATE.mirrors.values()):
            _write(m, force, t)
        _list_sessions(c, t)
        peers.poll(c, t)
    except CLIENT_ERRORS as e:
        return STATE.lost(e)
    _redraw()
    return ""


def _list_sessions(c, t: float) -> None:
    """Every LIST_EVERY_S: LIST_SESSIONS sent, its reply collected on a later tick (never
    waited for); refreshes the join list and the subscriber count."""
    if STATE.list_rid:
        parts = c.poll_reply(STATE.list_rid)
        if parts is None:
            return
        STATE.list_rid = 0
        STATE.sessions = messages.decode_session_list(b"".join(p.payload for p in parts))
        for s in STATE.sessions:
            if s.session_id == STATE.current_sid:
                STATE.subscribers = s.subscribers
    elif t - STATE.last_list_t > LIST_EVERY_S:
        STATE.last_list_t = t
        STATE.list_rid = c.send(MsgType.LIST_SESSIONS)


def _redraw() -> None:
    wm = bpy.context.window_manager
    for w in getattr(wm, "windows", []):
        for a in w.screen.areas:
            if a.type in ("VIEW_3D",):
                a.tag_redraw()


def _timer():
    try:
        tick()
    except Exception as e:           # never let the timer die; the panel shows the error
        STATE.last_error = "deformd: %s: %s" % (type(e).__name__, e)
        print("deformd_blender:", STATE.last_error)
    return TIMER_INTERVAL_S


def start_timer() -> None:
    if not bpy.app.timers.is_registered(_timer):
        bpy.app.timers.register(_timer, first_interval=TIMER_INTERVAL_S, persistent=True)


def stop_timer() -> None:
    if bpy.app.timers.is_registered(_timer):
        bpy.app.timers.unregister(_timer)
