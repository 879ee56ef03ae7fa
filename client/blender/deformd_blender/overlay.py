"""Large meshes: the live stroke drawn as a GPU point overlay (gpu module) from the replica,
while the mesh itself is written only when the stream pauses (sync._write). One draw handler for
every 3D view; the point batch is rebuilt when the replica's version changes."""
import bpy

_shown = {}          # session id -> (object name, mirror)
_cache = {}          # session id -> (version, batch)
_handle = {"h": None}
STATS = {"draws": 0, "batches": 0}   # draw calls and point batches built (tests, the panel)
POINT_SIZE = 2.0
COLOR = (1.0, 0.55, 0.1, 1.0)


def build_batch(positions):
    """A POINTS batch of (n, 3) float32 object-space positions (GUI only: gpu needs a context)."""
    import gpu
    from gpu_extras.batch import batch_for_shader
    shader = gpu.shader.from_builtin("3D_UNIFORM_COLOR")
    return shader, batch_for_shader(shader, "POINTS", {"pos": positions})


def _draw():
    import gpu
    for sid, (name, m) in list(_shown.items()):
        obj = bpy.data.objects.get(name)
        if obj is None:
            continue
        ver, batch = _cache.get(sid, (None, None))
        if ver != m.version:
            shader, batch = build_batch(m.positions())
            _cache[sid] = (m.version, batch)
            STATS["batches"] += 1
        shader = gpu.shader.from_builtin("3D_UNIFORM_COLOR")
        gpu.state.point_size_set(POINT_SIZE)
        gpu.matrix.push()
        gpu.matrix.multiply_matrix(obj.matrix_world)
        shader.bind()
        shader.uniform_float("color", COLOR)
        batch.draw(shader)
        gpu.matrix.pop()
        STATS["draws"] += 1


def show(m, obj) -> None:
    """Draw session m's replica over obj until hide(m.sid). No-op in background mode."""
    if bpy.app.background:
        _shown[m.sid] = (obj.name, m)
        return
    _shown[m.sid] = (obj.name, m)
    if _handle["h"] is None:
        _handle["h"] = bpy.types.SpaceView3D.draw_handler_add(_draw, (), "WINDOW", "POST_VIEW")


def hide(sid: int) -> None:
    _shown.pop(sid, None)
    _cache.pop(sid, None)


def shown() -> bool:
    return bool(_shown)


def remove() -> None:
    _shown.clear()
    _cache.clear()
    if _handle["h"] is not None:
        bpy.types.SpaceView3D.draw_handler_remove(_handle["h"], "WINDOW")
        _handle["h"] = None
