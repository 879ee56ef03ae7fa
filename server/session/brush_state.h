/* brush_state.h — a session's current brush (issue 11, "Session brush state") and the brush
 * cursor events.
 *
 * Each session has one brush state (type, radius, nu, strength, falloff order, ratio,
 * integrator + steps, mirror) that outlives strokes: clients get and set it (BRUSH_STATE_GET /
 * BRUSH_STATE_SET, PROTOCOL.md), devices change it (knobs), and a BRUSH_BEGIN whose
 * `use_session` bits name fields takes those fields from it. It starts as the wire's brush
 * defaults (DF_WIRE_BRUSH_DEFAULTS: GRAB, radius 1, nu 0.5, strength 1, falloff 1, ratio 1.1,
 * Euler 1 step, no mirror with normal (1,0,0)). Every change bumps the session's brush `seq`
 * (not its version: a brush change is no undo step and moves no vertex) and is broadcast as a
 * BRUSH_STATE event, carrying the new state and who made it, to every subscriber of the session.
 *
 * The brush cursor (where a device points: centre in mesh coordinates, radius) is broadcast as
 * BRUSH_CURSOR events rate-limited per (session, origin) to the config's `cursor_hz`; the latest
 * value of an interval is sent at its end (trailing edge), so the last position is never lost.
 *
 * Everything here runs on the loop thread (it reads and writes session fields that only the
 * loop thread owns; workers never read them: a BRUSH_BEGIN copies what it uses when it is
 * decoded). A later issue (durable store) persists `df_session.brush`: the whole state is that
 * one struct. */
#ifndef DF_SERVER_BRUSH_STATE_H
#define DF_SERVER_BRUSH_STATE_H

#include <stdint.h>

#include "core/common/df_error.h"
#include "proto/wire_schema.h"

/* Largest |strength| of a brush: a stroke (BRUSH_BEGIN, SET_BRUSH_PARAM) or the session brush. */
#define DF_BRUSH_MAX_STRENGTH 1e6

typedef struct df_session df_session;
struct df_msg_brush_state;
struct df_cursor_limiter;

/* The session brush. Values use the wire's units and enums (proto/wire_schema.h):
 * type df_brush_type (1..5), falloff 1..DF_MAX_FALLOFF, integrator df_integrator (1 Euler,
 * 2 RK4), steps 1..DF_MAX_BRUSH_STEPS, has_mirror 0/1; radius (mesh units, finite, > 0), nu
 * (Poisson ratio in [-1, 0.5] or +-inf), strength (load multiplier, |strength| <= 1e6), ratio
 * (finite, > 1), mirror plane point and normal (finite; normal non-zero when has_mirror). */
typedef struct df_brush_state {
    uint8_t type, falloff, integrator, has_mirror;
    uint16_t steps;
    double radius, nu, strength, ratio, mirror_point[3], mirror_normal[3];
} df_brush_state;

/* Who changed the brush / moved the cursor: kind DF_ORIGIN_NONE / CLIENT / DEVICE (wire enum),
 * id the connection id or device id, name the client's HELLO name or the device name (may be
 * NULL or ""; copied, at most DF_MAX_NAME_LEN bytes are kept). */
typedef struct df_origin {
    uint8_t kind;
    uint64_t id;
    const char *name;
} df_origin;

/* Who made a session brush's last change (a copy of the df_origin; kind NONE: nobody yet). */
typedef struct df_brush_changer {
    uint8_t kind;
    uint64_t id;
    char name[DF_MAX_NAME_LEN + 1];
} df_brush_changer;

/* The state every session starts with (DF_WIRE_BRUSH_DEFAULTS, mirror normal (1,0,0)). */
void df_brush_state_defaults(df_brush_state *out);

/* Copies the fields of `v` selected by `mask` (DF_BS_* bits, as df_brush_state_apply) into
 * `dst`; the others stay. No checks. Pure. */
void df_brush_state_merge(df_brush_state *dst, unsigned mask, const df_brush_state *v);

/* Checks the fields of `v` selected by `mask` (DF_BS_* bits; unknown bits are refused) as they
 * would replace those of `cur`: each field's range (as BRUSH_BEGIN / SET_BRUSH_PARAM), then the
 * Kelvinlet engine's kernel rules on the merged state (nu in [-1, 0.5] or +-inf, radii
 * radius * ratio^k within the engine's range). Type- and centre-dependent singularities (a scale
 * brush at nu 0.5) are the stroke's to refuse. `what` prefixes messages. DF_OK or DF_EINVAL with
 * a message naming the field and value. Pure (any thread). */
int df_brush_state_check(const df_brush_state *cur, unsigned mask, const df_brush_state *v,
                         const char *what, df_error *err);

/* Sets the fields of `v` selected by `mask` (DF_BS_*; DF_BS_INTEGRATOR also sets steps,
 * DF_BS_MIRROR has_mirror + point + normal) on session `s`. Validates every masked field first
 * (df_brush_state_check); on error nothing changes and nothing is sent. On success bumps the
 * session's brush seq by 1, records `who` as the last changer and broadcasts a BRUSH_STATE
 * event (changed = mask, origin = who) to every subscriber of s. The session version is not
 * changed and no undo step is made. `who` may be NULL (origin NONE). mask 0 is refused.
 * Returns DF_OK or DF_EINVAL (err names the field). Loop thread. */
int df_brush_state_apply(df_session *s, unsigned mask, const df_brush_state *v,
                         const df_origin *who, df_error *err);

/* The session's current brush state (owned by s, valid until the next apply). Loop thread. */
const df_brush_state *df_brush_state_get(const df_session *s);

/* Publishes the brush cursor of `who` on `s`: a BRUSH_CURSOR event {origin kind/id, flags
 * (DF_CURSOR_* bits: bit0 in range, bit1 stroke active), center (mesh coordinates), radius} to
 * every subscriber, rate-limited per (session, origin) to the config's cursor_hz (0 =
 * unlimited): a value arriving within 1/cursor_hz of the previous event of that origin is held
 * and replaces any held one; the held value is sent when the interval ends (a libuv timer on
 * the server's loop), so the last value is never lost. Non-finite values are dropped (logged
 * at debug). Loop thread. */
void df_brush_cursor_publish(df_session *s, const df_origin *who, const double center[3],
                             double radius, unsigned flags);

/* Converts the wire's brush values (brush_state_set body) to a df_brush_state and back. Pure. */
struct df_msg_brush_values;
void df_brush_state_from_wire(const struct df_msg_brush_values *w, df_brush_state *out);
void df_brush_state_to_wire(const df_brush_state *b, struct df_msg_brush_values *out);

/* Fills the BRUSH_STATE body of session `s`: its id, brush seq, the last changer as origin, the
 * full state, and `changed` (0 for a get). Loop thread. */
void df_brush_state_msg(const df_session *s, unsigned changed, struct df_msg_brush_state *out);

/* Frees the session's brush/cursor resources (the cursor timer is closed on the loop and freed
 * in its close callback). Called by df_session_destroy. NULL-safe on an unused state. */
void df_brush_state_release(df_session *s);

/* The limiter's clock in ns (monotonic): uv_hrtime. Unit tests replace it to drive the limiter
 * without depending on how fast they run; set it before the first publish, loop thread. */
extern uint64_t (*df_brush_cursor_clock)(void);

/* The rate limiter's decision, a pure function of times (unit-tested without a clock).
 * now_ns: the time of the new value; last_ns: when this origin's last event was sent (ignored
 * when !sent_before); interval_ns: 1e9 / cursor_hz (0 = unlimited); held: 1 when a value is
 * already waiting for the end of the interval. Returns 1 = send now, 0 = hold the value; when
 * holding, *due_ns is the time the held value is to be sent (last_ns + interval_ns). */
int df_cursor_rate_decide(uint64_t now_ns, uint64_t last_ns, int sent_before,
                          uint64_t interval_ns, int held, uint64_t *due_ns);

#endif
