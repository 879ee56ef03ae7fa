"""Brush strokes and handle moves of the deformd Python client (PROTOCOL.md 4.11-4.17): the
requests that edit a session, as a mixin of Client."""
import dataclasses
from typing import Optional, Sequence

from . import brush_state as bs
from . import messages as m
from . import progress as pg
from .progress import ProgressFn


class EditRequestsMixin:
    """Mixin of Client (client.py): needs its request(), _one(), send() and
    _request_progress() / _wait_with_progress()."""

    # ------------------------------------------------------------------ brush
    def brush_begin(self, session_id: int, brush: m.Brush,
                    progress: Optional["ProgressFn"] = None) -> m.Ack:
        """Opens a stroke. progress: a callback for the "factorize" stage of the LU of the
        brush's pinned points (built by the begin when its load is non-zero, else by the first
        update; see the module doc); the stroke's later updates report to brush_update's."""
        if progress is not None:
            brush = dataclasses.replace(brush, options=pg.WORK_OPT_PROGRESS)
        return m.decode_ack(self._request_progress(m.BRUSH_BEGIN,
                                                   m.encode_brush(session_id, brush), progress))

    def brush_update(self, session_id: int, move=None, twist=None, scale: float = 0.0,
                     matrix=None, progress: Optional["ProgressFn"] = None) -> m.Ack:
        """Cumulative load since the stroke began (same meaning as in Brush). progress: the
        pin LU's "factorize" events when this update (re)builds it, for a stroke whose
        brush_begin asked for progress."""
        return m.decode_ack(self._request_progress(
            m.BRUSH_UPDATE, m.encode_brush_update(session_id, move, twist, scale, matrix),
            progress))

    def brush_end(self, session_id: int) -> m.Ack:
        return m.decode_ack(self._one(m.BRUSH_END, m.encode_session_ref(session_id)))

    def brush_cancel(self, session_id: int) -> m.Ack:
        return m.decode_ack(self._one(m.BRUSH_CANCEL, m.encode_session_ref(session_id)))

    def stroke(self, session_id: int, brush: m.Brush,
               progress: Optional["ProgressFn"] = None) -> m.Ack:
        """One whole stroke committed as one version (like `deformctl brush`): begin with the
        brush's load (applied as its first update), then end. Returns the end's ack. progress:
        as in brush_begin."""
        self.brush_begin(session_id, brush, progress)
        return self.brush_end(session_id)

    def set_brush_param(self, session_id: int, param: str, value: float) -> m.Ack:
        """param: radius | nu | strength | falloff | ratio."""
        return m.decode_ack(self._one(m.SET_BRUSH_PARAM,
                                      m.encode_brush_param(session_id, param, value)))

    def brush_state_get(self, session_id: int) -> bs.BrushState:
        """The session brush (PROTOCOL.md 4.14a): values, seq, last changer (changed 0)."""
        return bs.decode_brush_state(self._one(m.BRUSH_STATE_GET,
                                               m.encode_session_ref(session_id)))

    def brush_state_set(self, session_id: int, **fields) -> bs.BrushState:
        """Sets fields of the session brush: type, radius, nu, strength, falloff, ratio,
        integrator, steps, mirror (None = off, or (px, py, pz, nx, ny, nz)). Giving only one of
        integrator / steps (one wire field) reads the other from the daemon first. Returns the
        new state; subscribers get it as a BrushState event naming this client. DeformdError
        EINVAL (nothing changed) for a bad value."""
        base = bs.BrushValues()
        if ("integrator" in fields) != ("steps" in fields):
            base = self.brush_state_get(session_id).values
        mask, v = bs.values_with(base, **fields)
        return bs.decode_brush_state(self._one(m.BRUSH_STATE_SET,
                                               bs.encode_brush_state_set(session_id, mask, v)))

    # ------------------------------------------------------------------ handles
    def set_handles(self, session_id: int, handles: Sequence[int], energy: str = "arap",
                    affine: Sequence[m.AffineSet] = (),
                    progress: Optional["ProgressFn"] = None, **params) -> m.Ack:
        """Defines the session's handle set (replacing any previous one). params: any field of
        messages.HandleParams (w, s, rho, tol, max_iters, youngs, poisson, strain_min,
        strain_max, bending, area_weighting, accelerate, anderson_m); the rest take the
        reference defaults for `energy` (w 1e-4, s 0.01, rho 0 = the solver's adaptive penalty;
        Neo-Hookean w 500; an explicit rho must exceed w / s). progress: a callback for the solver build
        ("factorize" stage; see the module doc)."""
        p = m.HandleParams.for_energy(energy, **params)
        rid = self.send(m.HANDLES_SET, m.encode_handles(
            session_id, energy, handles, p, affine,
            pg.WORK_OPT_PROGRESS if progress is not None else None))
        return m.decode_ack(self._wait_with_progress(rid, progress))

    def get_handles(self, session_id: int) -> m.HandleSet:
        """The session's current handle set (energy, every parameter, handle indices in handle
        order, affine sets). DeformdError ENOTFOUND when the session has no handle set."""
        return m.decode_handles(self._one(m.HANDLES_GET, m.encode_session_ref(session_id)))

    def move_handles(self, session_id: int, targets: Sequence[Sequence[float]],
                     max_iters: int = 0, max_ms: int = 0, progress_every: int = 0,
                     timeout: Optional[float] = None,
                     progress: Optional["ProgressFn"] = None,
                     kelvinlet_guess: bool = False, polish: bool = False) -> m.MoveResult:
        """Moves the handles to `targets` (one xyz per handle) and waits for the final result;
        progress iterates (and displacement frames) are queued as events. progress: a callback
        for the "solve" stage (iterations of the budget) and a solver rebuild ("factorize"); see
        the module doc. kelvinlet_guess: the solver starts from the Kelvinlet field of the
        handles' move, support-restricted and line-searched (never a higher starting objective
        than the plain start; option bit KELVINLET_GUESS, PROTOCOL.md 4.16). polish: after ADMM, a
        projected-Newton polish to a relative KKT residual of 1e-9 (option bit POLISH; tet
        meshes with arap, acap or neohookean; the result's residual is then its KKT residual)."""
        opts = (pg.WORK_OPT_PROGRESS if progress is not None else 0) | (
            int(m.WorkOpt.KELVINLET_GUESS) if kelvinlet_guess else 0) | (
            int(m.WorkOpt.POLISH) if polish else 0)
        rid = self.send(m.HANDLES_MOVE, m.encode_handle_move(
            session_id, targets, max_iters, max_ms, progress_every, opts or None))
        return m.decode_move_result(self._wait_with_progress(rid, progress, timeout))

    def reset_rest(self, session_id: int) -> m.Ack:
        return m.decode_ack(self._one(m.RESET_REST, m.encode_session_ref(session_id)))

    def undo(self, session_id: int) -> m.Ack:
        return m.decode_ack(self._one(m.UNDO, m.encode_session_ref(session_id)))

    def redo(self, session_id: int) -> m.Ack:
        return m.decode_ack(self._one(m.REDO, m.encode_session_ref(session_id)))

