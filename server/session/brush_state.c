/* brush_state.c — a session's current brush and the rate-limited brush cursor (brush_state.h). */
#include "server/session/brush_state.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <uv.h>

#include "core/kelvinlet/kelvinlet.h"
#include "proto/wire_core_map.h"
#include "server/log.h"
#include "server/net/reply.h"
#include "server/session/session.h"

#define DF_CURSOR_MAX_ORIGINS 64 /* origins remembered per session (the oldest idle one goes) */

/* One origin's cursor on a session: when its last event went out and the value held back. */
typedef struct cursor_slot {
    uint8_t kind;
    uint64_t id;
    int sent;                    /* an event of this origin was sent (last_ns valid) */
    uint64_t last_ns;            /* uv_hrtime() of that event */
    int held;                    /* `msg` waits for the end of the interval */
    df_msg_brush_cursor msg;     /* the held value */
} cursor_slot;

/* The per-session rate limiter: its slots and the timer that sends held values. */
struct df_cursor_limiter {
    uv_timer_t timer;            /* on srv->loop; data = this */
    df_session *s;
    cursor_slot slots[DF_CURSOR_MAX_ORIGINS];
    int n;
};

void df_brush_state_to_wire(const df_brush_state *b, df_msg_brush_values *v)
{
    memset(v, 0, sizeof *v);
    v->type = b->type;
    v->falloff = b->falloff;
    v->integrator = b->integrator;
    v->has_mirror = b->has_mirror;
    v->steps = b->steps;
    v->radius = b->radius;
    v->nu = b->nu;
    v->strength = b->strength;
    v->ratio = b->ratio;
    memcpy(v->mirror_point, b->mirror_point, sizeof v->mirror_point);
    memcpy(v->mirror_normal, b->mirror_normal, sizeof v->mirror_normal);
}

void df_brush_state_from_wire(const df_msg_brush_values *v, df_brush_state *out)
{
    memset(out, 0, sizeof *out);
    out->type = v->type;
    out->falloff = v->falloff;
    out->integrator = v->integrator;
    out->has_mirror = v->has_mirror;
    out->steps = v->steps;
    out->radius = v->radius;
    out->nu = v->nu;
    out->strength = v->strength;
    out->ratio = v->ratio;
    memcpy(out->mirror_point, v->mirror_point, sizeof out->mirror_point);
    memcpy(out->mirror_normal, v->mirror_normal, sizeof out->mirror_normal);
}

void df_brush_state_defaults(df_brush_state *out)
{
    df_msg_brush_values v;
    df_msg_brush_values_defaults(&v);
    df_brush_state_from_wire(&v, out);
}

void df_brush_state_merge(df_brush_state *dst, unsigned mask, const df_brush_state *v)
{
    if (mask & DF_BS_TYPE) dst->type = v->type;
    if (mask & DF_BS_RADIUS) dst->radius = v->radius;
    if (mask & DF_BS_NU) dst->nu = v->nu;
    if (mask & DF_BS_STRENGTH) dst->strength = v->strength;
    if (mask & DF_BS_FALLOFF) dst->falloff = v->falloff;
    if (mask & DF_BS_RATIO) dst->ratio = v->ratio;
    if (mask & DF_BS_INTEGRATOR) {
        dst->integrator = v->integrator;
        dst->steps = v->steps;
    }
    if (mask & DF_BS_MIRROR) {
        dst->has_mirror = v->has_mirror;
        memcpy(dst->mirror_point, v->mirror_point, sizeof dst->mirror_point);
        memcpy(dst->mirror_normal, v->mirror_normal, sizeof dst->mirror_normal);
    }
}

int df_brush_state_check(const df_brush_state *cur, unsigned mask, const df_brush_state *v,
                         const char *what, df_error *err)
{
    if (mask == 0) return df_error_set(err, DF_EINVAL, "%s: mask 0 sets nothing", what);
    if (mask & ~DF_BS_ALL)
        return df_error_set(err, DF_EINVAL, "%s: field bits 0x%x are not defined (known: 0x%x)",
                            what, mask & ~DF_BS_ALL, DF_BS_ALL);
    df_msg_brush_values mv;
    df_brush_state_to_wire(v, &mv);
    int rc = df_msg_brush_values_check(&mv, mask, what, err);
    if (rc != DF_OK) return rc;
    if ((mask & DF_BS_STRENGTH) && fabs(v->strength) > DF_BRUSH_MAX_STRENGTH)
        return df_error_set(err, DF_EINVAL, "%s: strength %g outside [-%g, %g]", what,
                            v->strength, DF_BRUSH_MAX_STRENGTH, DF_BRUSH_MAX_STRENGTH);
    /* The kernel the merged state describes must satisfy the engine (nu range, radii range):
     * checked on a stationary, unmirrored 3D grab, which has no type- or centre-dependent
     * singularity. */
    df_brush_state m = *cur;
    df_brush_state_merge(&m, mask, v);
    df_kelvinlet_brush b;
    df_kelvinlet_brush_defaults(&b);
    b.order = m.falloff;
    b.ratio = m.ratio;
    b.radius = m.radius;
    b.nu = m.nu;
    df_kelvinlet_prepared prep;
    df_error e;
    rc = df_kelvinlet_prepare(&b, &prep, &e);
    if (rc != DF_OK)
        return df_error_set(err, DF_EINVAL, "%s: radius %g, nu %g, falloff %u, ratio %g refused "
                            "(%s)", what, m.radius, m.nu, m.falloff, m.ratio, e.msg);
    df_kelvinlet_prepared_free(&prep);
    return DF_OK;
}

const df_brush_state *df_brush_state_get(const df_session *s)
{
    return &s->brush;
}

void df_brush_state_msg(const df_session *s, unsigned changed, df_msg_brush_state *out)
{
    memset(out, 0, sizeof *out);
    out->session_id = s->id;
    out->seq = s->brush_seq;
    out->changed = (uint16_t)changed;
    out->origin_kind = s->brush_by.kind;
    out->origin_id = s->brush_by.id;
    snprintf(out->origin_name, sizeof out->origin_name, "%s", s->brush_by.name);
    df_brush_state_to_wire(&s->brush, &out->v);
}

int df_brush_state_apply(df_session *s, unsigned mask, const df_brush_state *v,
                         const df_origin *who, df_error *err)
{
    if (who && who->kind > DF_ORIGIN_MAX)
        return df_error_set(err, DF_EINVAL, "brush_state: origin kind %u not in 0..%d",
                            who->kind, DF_ORIGIN_MAX);
    int rc = df_brush_state_check(&s->brush, mask, v, "brush_state_set", err);
    if (rc != DF_OK) return rc;
    df_brush_state_merge(&s->brush, mask, v);
    s->brush_seq++;
    s->brush_by.kind = who ? who->kind : DF_ORIGIN_NONE;
    s->brush_by.id = who ? who->id : 0;
    snprintf(s->brush_by.name, sizeof s->brush_by.name, "%s",
             who && who->name ? who->name : "");
    df_msg_brush_state m;
    df_brush_state_msg(s, mask, &m);
    df_error e;
    df_sbuf *f = df_out_brush_state(DF_MSG_BRUSH_STATE, DF_FLAG_EVENT, 0, &m, &e);
    if (f) {
        df_session_broadcast(s, f);
        df_sbuf_unref(f);
    } else {
        df_log(DF_LOG_ERROR, "session %llu: brush_state event not sent: %s",
               (unsigned long long)s->id, e.msg);
    }
    s->srv->stats.brush_state_changes++;
    return DF_OK;
}

/* ------------------------------------------------------------------------- brush cursor */
uint64_t (*df_brush_cursor_clock)(void) = uv_hrtime;

int df_cursor_rate_decide(uint64_t now_ns, uint64_t last_ns, int sent_before,
                          uint64_t interval_ns, int held, uint64_t *due_ns)
{
    if (interval_ns == 0) return 1;                       /* unlimited */
    if (!held && (!sent_before || (now_ns >= last_ns && now_ns - last_ns >= interval_ns)))
        return 1;
    *due_ns = last_ns + interval_ns;                       /* a held value replaces the older */
    return 0;
}

static void cursor_send(df_session *s, const df_msg_brush_cursor *m)
{
    df_error e;
    df_sbuf *f = df_out_brush_cursor(DF_MSG_BRUSH_CURSOR, DF_FLAG_EVENT, 0, m, &e);
    if (!f) {
        df_log(DF_LOG_ERROR, "session %llu: brush_cursor event not sent: %s",
               (unsigned long long)s->id, e.msg);
        return;
    }
    df_session_broadcast(s, f);
    df_sbuf_unref(f);
    s->srv->stats.brush_cursor_events++;
}

static uint64_t cursor_interval_ns(const df_session *s)
{
    int hz = s->srv->cfg.cursor_hz;
    return hz > 0 ? (uint64_t)1000000000u / (uint64_t)hz : 0;
}

static void cursor_on_timer(uv_timer_t *t);

/* Arms the limiter's timer for the earliest held slot (stops it when none is held). The timer
 * counts whole milliseconds of loop time (itself truncated to ms): the delay is rounded up and
 * one more ms added after refreshing the loop time, so a held value never goes out early (at
 * most ~2 ms late). */
static void cursor_arm(struct df_cursor_limiter *cl, uint64_t now_ns)
{
    uint64_t interval = cursor_interval_ns(cl->s), due = UINT64_MAX;
    for (int i = 0; i < cl->n; i++)
        if (cl->slots[i].held && cl->slots[i].last_ns + interval < due)
            due = cl->slots[i].last_ns + interval;
    if (due == UINT64_MAX) {
        uv_timer_stop(&cl->timer);
        return;
    }
    uv_update_time(cl->timer.loop);
    uint64_t ms = due > now_ns ? (due - now_ns + 999999u) / 1000000u + 1 : 0;
    uv_timer_start(&cl->timer, cursor_on_timer, ms, 0);
}

/* Sends every held value whose interval has ended (the trailing edge), re-arms for the rest. */
static void cursor_flush_due(struct df_cursor_limiter *cl, uint64_t now_ns)
{
    uint64_t interval = cursor_interval_ns(cl->s);
    for (int i = 0; i < cl->n; i++) {
        cursor_slot *sl = &cl->slots[i];
        if (sl->held && now_ns >= sl->last_ns + interval) {
            sl->held = 0;
            sl->sent = 1;
            sl->last_ns = now_ns;
            cursor_send(cl->s, &sl->msg);
        }
    }
    cursor_arm(cl, now_ns);
}

static void cursor_on_timer(uv_timer_t *t)
{
    struct df_cursor_limiter *cl = t->data;
    cursor_flush_due(cl, df_brush_cursor_clock());
}

/* The slot of origin (kind, id), made when new; when all are taken, the one idle longest is
 * reused (its held value, if any, is sent first). */
static cursor_slot *cursor_slot_of(struct df_cursor_limiter *cl, uint8_t kind, uint64_t id)
{
    for (int i = 0; i < cl->n; i++)
        if (cl->slots[i].kind == kind && cl->slots[i].id == id) return &cl->slots[i];
    cursor_slot *sl;
    if (cl->n < DF_CURSOR_MAX_ORIGINS) {
        sl = &cl->slots[cl->n++];
    } else {
        sl = &cl->slots[0];
        for (int i = 1; i < cl->n; i++)
            if (cl->slots[i].last_ns < sl->last_ns) sl = &cl->slots[i];
        if (sl->held) cursor_send(cl->s, &sl->msg);
    }
    memset(sl, 0, sizeof *sl);
    sl->kind = kind;
    sl->id = id;
    return sl;
}

void df_brush_cursor_publish(df_session *s, const df_origin *who, const double center[3],
                             double radius, unsigned flags)
{
    df_msg_brush_cursor m = {.session_id = s->id,
                             .origin_kind = who ? who->kind : DF_ORIGIN_NONE,
                             .origin_id = who ? who->id : 0,
                             .flags = (uint8_t)(flags & DF_CURSOR_FLAGS_ALL),
                             .center = {center[0], center[1], center[2]},
                             .radius = radius};
    df_error e;
    df_buf probe;
    df_buf_init(&probe);
    int rc = df_msg_brush_cursor_encode(&m, &probe, &e); /* the event's own checks */
    df_buf_free(&probe);
    if (rc != DF_OK || (flags & ~DF_CURSOR_FLAGS_ALL)) {
        df_log(DF_LOG_DEBUG, "session %llu: brush cursor dropped: %s", (unsigned long long)s->id,
               rc != DF_OK ? e.msg : "undefined flag bits");
        return;
    }
    uint64_t interval = cursor_interval_ns(s);
    if (interval == 0 || !s->srv->loop) { /* unlimited (or no loop to send held values) */
        cursor_send(s, &m);
        return;
    }
    struct df_cursor_limiter *cl = s->cursor;
    if (!cl) {
        cl = calloc(1, sizeof *cl);
        if (!cl) {
            cursor_send(s, &m); /* out of memory: unlimited rather than lost */
            return;
        }
        uv_timer_init(s->srv->loop, &cl->timer); /* active only while a value is held */
        cl->timer.data = cl;
        cl->s = s;
        s->cursor = cl;
    }
    cursor_slot *sl = cursor_slot_of(cl, m.origin_kind, m.origin_id);
    uint64_t now = df_brush_cursor_clock(), due = 0;
    if (df_cursor_rate_decide(now, sl->last_ns, sl->sent, interval, sl->held, &due)) {
        sl->sent = 1;
        sl->last_ns = now;
        cursor_send(s, &m);
        return;
    }
    sl->msg = m;
    if (!sl->held) {
        sl->held = 1;
        cursor_arm(cl, now);
    }
}

void df_brush_state_release(df_session *s)
{
    struct df_cursor_limiter *cl = s->cursor;
    if (!cl) return;
    s->cursor = NULL;
    uv_timer_stop(&cl->timer);
    cl->s = NULL;
    uv_close((uv_handle_t *)&cl->timer, (uv_close_cb)free); /* timer is the first member */
}
