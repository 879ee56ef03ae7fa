/* dc_brush.h — deformctl's local pre-flight check of a brush stroke (part of deformctl, not of
 * libdeformclient, which needs no Kelvinlet solver): runs the Kelvinlet engine's own validation
 * (core/kelvinlet) on the stroke that deformctl is about to send, so that strokes the daemon
 * would reject (pinch gradient not symmetric/traceless, nu outside [-1, 0.5], scale at
 * nu = 0.5, radius out of range, coincident pins...) fail with a clear message before
 * connecting. */
#ifndef DF_CTL_DC_BRUSH_H
#define DF_CTL_DC_BRUSH_H

#include "core/common/df_error.h"
#include "core/kelvinlet/kelvinlet.h"
#include "proto/messages.h"

/* Pinned sets up to this size are checked locally by factorizing K_pp (at most 12 n = 768 rows,
 * a few ms); larger sets are left to the daemon (its LU is cached per session). */
#define DC_BRUSH_LOCAL_PIN_CHECK_MAX 64u

/* Converts a begin message `b` and the cumulative load `u` into the engine's brush description,
 * the way the daemon does (df_wire_brush_to_core of proto/wire_core_map.h, loads multiplied by
 * b->strength). No validation: a type or integrator outside the wire enums gives type -1, which
 * the engine refuses. */
void dc_brush_to_kelvinlet(const df_msg_brush *b, const df_msg_brush_update *u,
                           df_kelvinlet_brush *out);

/* Validates the stroke `b` + `u` with the engine: df_kelvinlet_prepare without pins; with pins
 * (b->n_pinned <= DC_BRUSH_LOCAL_PIN_CHECK_MAX) df_kelvinlet_constraints_create + _solve with the
 * daemon's pin kernel (brush radius, ratio, nu, falloff). Returns DF_OK or the engine's error
 * (DF_EINVAL, DF_ESINGULAR, DF_EUNSUPPORTED, DF_ELIMIT, DF_ENOMEM) with its message in `err`.
 * Larger pinned sets skip the pin part of the check (the daemon still validates them). */
int dc_brush_check(const df_msg_brush *b, const df_msg_brush_update *u, df_error *err);

#endif
