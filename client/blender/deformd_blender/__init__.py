"""deformd for Blender: live multi-user sculpting of a mesh shared through the deformd daemon.

Modules: prefs (address, key, overlay threshold), props (the panel's values), panel, operators
(scriptable: deformd.connect / share / join / stroke / sync / undo / redo / disconnect, ...),
modal (the mouse sculpt operator and the handle drag), sync (the 60 Hz poll and resync),
mirror (the numpy replica), upload (binary PLY), overlay (GPU points for large meshes),
brush_map (Elastic Deform -> session brush), connection (state and error text), progress."""
bl_info = {
    "name": "deformd",
    "author": "deformd",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "3D View > Sidebar > deformd",
    "description": "Live multi-user Kelvinlet sculpting through the deformd daemon",
    "category": "Sculpt",
}

import bpy  # noqa: E402

from . import handles, modal, operators, overlay, panel, prefs, progress, props, sync  # noqa: E402
from .connection import STATE  # noqa: E402

CLASSES = (prefs.CLASSES + props.CLASSES + operators.CLASSES + modal.CLASSES + handles.CLASSES
           + panel.CLASSES)


_KEYMAPS = []   # (keymap, item) added to the add-on key configuration


def register():
    for c in CLASSES:
        bpy.utils.register_class(c)
    props.register_props()
    sync.start_timer()
    kc = bpy.context.window_manager.keyconfigs.addon
    if kc is not None:                     # None in background mode
        km = kc.keymaps.new(name="3D View", space_type="VIEW_3D")
        _KEYMAPS.append((km, km.keymap_items.new("deformd.sculpt", "D", "PRESS", ctrl=True,
                                                 shift=True)))


def unregister():
    for km, kmi in _KEYMAPS:
        km.keymap_items.remove(kmi)
    _KEYMAPS.clear()
    sync.stop_timer()
    STATE.disconnect()
    overlay.remove()
    progress.stop()
    props.unregister_props()
    for c in reversed(CLASSES):
        bpy.utils.unregister_class(c)
