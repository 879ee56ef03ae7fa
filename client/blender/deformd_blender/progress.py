"""Blender's progress indicator (the cursor / status bar) for long daemon work. The daemon sends
PROGRESS events for handle moves (ADMM iterates: iteration count, no total); the indicator shows
the iteration modulo 100 while a move runs and ends with the final iterate."""
import bpy

_active = {"on": False}


def show(ev) -> None:
    """ev: a Progress event (status, final, iteration)."""
    wm = bpy.context.window_manager
    if getattr(ev, "final", 1):
        if _active["on"]:
            wm.progress_end()
            _active["on"] = False
        return
    if not _active["on"]:
        wm.progress_begin(0, 100)
        _active["on"] = True
    wm.progress_update(ev.iteration % 100)


def stop() -> None:
    if _active["on"]:
        bpy.context.window_manager.progress_end()
        _active["on"] = False
