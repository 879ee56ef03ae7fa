"""Blender's progress indicator (the cursor / status bar) for long daemon work.

Two sources:
- WORK_PROGRESS (PROTOCOL.md 4.37), asked for by share (stages upload, parse) and handle set /
  move (factorize, solve): `work(ranges)` gives the Client's `progress=` callback, which maps each
  stage's done/total into that stage's slice of 0..100 (e.g. upload 0-50, parse 50-100), never
  going back, begins the indicator on the first event and ends it when the `with` block ends.
- PROGRESS events of handle moves seen by the timer (ADMM iterates, no total): `show(ev)` shows
  the iteration modulo 100 while a move runs and ends with the final iterate.

Every window-manager call goes through the module-level hook WM (begin(lo, hi), update(v),
end()): headless Blender has no indicator to look at, so a test swaps WM for a recorder."""
import contextlib

import bpy


class WindowManagerHook:
    """The real indicator: bpy.context.window_manager.progress_begin / update / end."""

    def begin(self, lo: float, hi: float) -> None:
        bpy.context.window_manager.progress_begin(lo, hi)

    def update(self, value: float) -> None:
        bpy.context.window_manager.progress_update(value)

    def end(self) -> None:
        bpy.context.window_manager.progress_end()


WM = WindowManagerHook()
_active = {"on": False}


def _begin() -> None:
    if not _active["on"]:
        WM.begin(0, 100)
        _active["on"] = True


def show(ev) -> None:
    """ev: a Progress event (status, final, iteration)."""
    if getattr(ev, "final", 1):
        stop()
        return
    _begin()
    WM.update(ev.iteration % 100)


def stop() -> None:
    if _active["on"]:
        _active["on"] = False
        WM.end()


@contextlib.contextmanager
def work(ranges):
    """ranges: {stage name: (lo, hi)} in 0..100 (stages not named are ignored). Yields the
    callback for a Client request's `progress=`; the indicator ends when the block ends (also on
    an error). Values passed to WM.update never decrease within one block."""
    last = {"v": -1.0}

    def cb(w) -> None:
        span = ranges.get(w.stage_name)
        if span is None:
            return
        lo, hi = span
        frac = 1.0 if w.final else w.fraction
        v = max(last["v"], lo + (hi - lo) * frac)
        _begin()
        if v > last["v"]:
            last["v"] = v
            WM.update(v)

    try:
        yield cb
    finally:
        stop()
