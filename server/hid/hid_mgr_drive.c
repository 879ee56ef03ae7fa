/* hid_mgr_drive.c — a device's mapper actions become what a client would send (see
 * hid_manager.h): brush-state changes and cursor events on the session, and BRUSH_BEGIN /
 * SET_BRUSH_PARAM / BRUSH_UPDATE / BRUSH_END requests queued through df_job_request with an
 * internal df_req (no connection, origin_id = the device id). Loop thread only. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "proto/messages.h"
#include "server/exec/job.h"
#include "server/handlers/handlers.h"
#include "server/hid/hid_mgr_internal.h"
#include "server/log.h"
#include "server/session/brush_state.h"
#include "server/session/session.h"

/* The mapper's brush bits are the wire's (hid_action.h defines them apart: server/hid/ does not
 * see proto/); checked here, where both are visible. */
#define SAME(a, b) ((int)(a) == (int)(b))
_Static_assert(SAME(DF_HID_BS_TYPE, DF_BS_TYPE) && SAME(DF_HID_BS_RADIUS, DF_BS_RADIUS) &&
               SAME(DF_HID_BS_NU, DF_BS_NU) && SAME(DF_HID_BS_STRENGTH, DF_BS_STRENGTH) &&
               SAME(DF_HID_BS_FALLOFF, DF_BS_FALLOFF) && SAME(DF_HID_BS_RATIO, DF_BS_RATIO) &&
               SAME(DF_HID_BS_INTEGRATOR, DF_BS_INTEGRATOR) &&
               SAME(DF_HID_BS_MIRROR, DF_BS_MIRROR), "hid brush bits = wire DF_BS_*");
_Static_assert(SAME(DF_HID_CUR_IN_RANGE, DF_CURSOR_IN_RANGE) &&
               SAME(DF_HID_CUR_STROKE, DF_CURSOR_STROKE_ACTIVE), "hid cursor flags = wire");
_Static_assert(SAME(DF_HID_CLASS_KNOB, DF_DEVCLASS_KNOB) &&
               SAME(DF_HID_CLASS_MOUSE3D, DF_DEVCLASS_MOUSE3D) &&
               SAME(DF_HID_CLASS_PEN, DF_DEVCLASS_PEN), "classes = wire");
_Static_assert(SAME(DF_HID_BACKEND_HIDAPI, DF_DEVBACKEND_HIDAPI) &&
               SAME(DF_HID_BACKEND_LIBUSB, DF_DEVBACKEND_LIBUSB) &&
               SAME(DF_HID_BACKEND_REPLAY, DF_DEVBACKEND_REPLAY), "backends = wire");
_Static_assert(SAME(DF_HID_BRUSH_GRAB, DF_BRUSH_GRAB) && SAME(DF_HID_BRUSH_AFFINE,
               DF_BRUSH_AFFINE), "brush types = wire");
#undef SAME

/* Fields a device stroke takes from the session brush (all but the strength: a pen's comes from
 * its pressure, a 3D mouse's is the session's). */
#define DRIVE_USE_SESSION (DF_BS_TYPE | DF_BS_RADIUS | DF_BS_NU | DF_BS_FALLOFF | DF_BS_RATIO | \
                           DF_BS_INTEGRATOR | DF_BS_MIRROR)

static df_origin origin_of(const df_hid_device *d)
{
    df_origin o = {.kind = DF_ORIGIN_DEVICE, .id = d->id, .name = d->info.name};
    return o;
}

df_session *df_hid_drive_session(df_hid_device *d)
{
    df_server *srv = d->mgr->srv;
    df_session *s = d->bound ? df_session_find(srv, d->bound) : NULL;
    if (!s && srv->last_change_session) s = df_session_find(srv, srv->last_change_session);
    return s;
}

/* Queues request `type` with payload `b` of kind `kind` on behalf of d (as a client would). */
static int submit(df_hid_device *d, uint16_t type, const df_job_kind *kind, const df_buf *b)
{
    df_req r = {.srv = d->mgr->srv, .c = NULL, .type = type, .id = 0,
                .len = (uint32_t)b->len, .origin_id = d->id};
    df_error err;
    int rc = df_job_request(&r, b->data, kind, &err);
    if (rc != DF_OK) {
        d->requests_failed++;
        df_log(DF_LOG_DEBUG, "hid: %s: %s refused: %s", d->info.path, df_msg_type_name(type),
               err.msg);
    }
    return rc;
}

static int send_ref(df_hid_device *d, uint16_t type, const df_job_kind *kind, uint64_t sid)
{
    df_buf b;
    df_buf_init(&b);
    df_msg_session_ref m = {.session_id = sid};
    df_error err;
    int rc = df_msg_session_ref_encode(&m, &b, &err);
    if (rc == DF_OK) rc = submit(d, type, kind, &b);
    df_buf_free(&b);
    return rc;
}

void df_hid_drive_end_stroke(df_hid_device *d)
{
    if (!d->stroke) return;
    d->stroke = 0;
    d->strokes_ended++;
    if (df_session_find(d->mgr->srv, d->stroke_session))
        send_ref(d, DF_MSG_BRUSH_END, &df_k_brush_end, d->stroke_session);
}

/* Bounding box of the session's current positions: centre and diagonal. */
static void bbox(const df_session *s, double centre[3], double *diag)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int32_t i = 0; i < s->nv; i++)
        for (int k = 0; k < 3; k++) {
            double v = s->cur[3 * (size_t)i + k];
            if (v < lo[k]) lo[k] = v;
            if (v > hi[k]) hi[k] = v;
        }
    double d2 = 0;
    for (int k = 0; k < 3; k++) {
        centre[k] = 0.5 * (lo[k] + hi[k]);
        d2 += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    }
    *diag = sqrt(d2);
}

static void output(df_hid_device *d, const df_hid_action *a);

/* d now drives s: the 3d-mouse cursor starts at the bounding-box centre and its integration
 * scale is the diagonal (0-size meshes keep scale 1); a knob with an LED (PowerMate) shows the
 * session's radius at once. */
static void attach(df_hid_device *d, df_session *s)
{
    uint64_t old = d->active;
    d->active = s->id;
    int led = df_hid_mapper_led_level(&d->map, df_brush_state_get(s)->radius);
    if (led >= 0 && old != s->id) {
        df_hid_action a = {.kind = DF_HID_ACT_LED, .led = led};
        output(d, &a);
    }
    if (d->cls.cls == DF_HID_CLASS_MOUSE3D && d->cursor_session != s->id) {
        double diag;
        bbox(s, d->cursor, &diag);
        if (diag > 0 && isfinite(diag)) df_hid_mapper_set_scale(&d->map, diag);
        d->cursor_session = s->id;
    }
    if (old != s->id) df_hid_device_announce(d, s->id);
}

/* The pen ray-cast cache of session s (made on first use), or NULL when it has no surface. */
static df_pen_cache *pen_cache(df_hid_manager *m, df_session *s)
{
    for (df_hid_pencache *p = m->pens; p; p = p->next)
        if (p->session_id == s->id) return p->pc;
    df_hid_pencache *p = calloc(1, sizeof *p);
    df_error err;
    if (!p) return NULL;
    if (df_pen_cache_create(&s->mesh, &p->pc, &err) != DF_OK) {
        df_log(DF_LOG_WARN, "hid: session %llu: no pen target: %s", (unsigned long long)s->id,
               err.msg);
        p->pc = NULL; /* remembered: no retry per report */
    }
    p->session_id = s->id;
    p->next = m->pens;
    m->pens = p;
    return p->pc;
}

void df_hid_drive_pen_forget(df_hid_manager *m, uint64_t session_id)
{
    df_hid_pencache **pp = &m->pens;
    while (*pp) {
        df_hid_pencache *p = *pp;
        if (session_id == 0 || p->session_id == session_id) {
            *pp = p->next;
            df_pen_cache_free(p->pc);
            free(p);
        } else {
            pp = &p->next;
        }
    }
}

/* Where the pen at normalized xy points on s: 1 with centre, 0 no view / miss / error. */
static int pen_hit(df_hid_device *d, df_session *s, const double xy[2], double centre[3])
{
    if (!d->have_view || d->bound != s->id) {
        if (!d->logged_no_view++)
            df_log(DF_LOG_INFO, "hid: pen %s has no view of session %llu (DEVICE_VIEW): no "
                   "strokes", d->info.path, (unsigned long long)s->id);
        return 0;
    }
    df_pen_cache *pc = pen_cache(d->mgr, s);
    if (!pc) return 0;
    df_error err;
    int rc = df_pen_target(pc, s->cur, atomic_load(&s->version), d->view_proj, d->viewport,
                           xy[0], xy[1], centre, &err);
    if (rc < 0) df_log(DF_LOG_DEBUG, "hid: pen %s: %s", d->info.path, err.msg);
    return rc == 1;
}

static void cursor_action(df_hid_device *d, df_session *s, const df_hid_action *a)
{
    df_origin o = origin_of(d);
    double radius = df_brush_state_get(s)->radius, c[3];
    if (a->cursor_mode == DF_HID_CUR_DELTA) {
        for (int k = 0; k < 3; k++) d->cursor[k] += a->move[k];
        df_brush_cursor_publish(s, &o, d->cursor, radius, a->cursor_flags);
    } else if (!(a->cursor_flags & DF_HID_CUR_IN_RANGE)) {
        double zero[3] = {0, 0, 0};
        df_brush_cursor_publish(s, &o, d->stroke ? d->stroke_center : zero, radius, 0);
    } else if (d->have_view && d->bound == s->id && pen_hit(d, s, a->xy, c)) {
        df_brush_cursor_publish(s, &o, c, radius, a->cursor_flags);
    }
}

static void brush_set(df_hid_device *d, df_session *s, const df_hid_action *a)
{
    df_brush_state v = *df_brush_state_get(s);
    if (a->mask & DF_HID_BS_TYPE) v.type = a->brush.type;
    if (a->mask & DF_HID_BS_FALLOFF) v.falloff = a->brush.falloff;
    if (a->mask & DF_HID_BS_RADIUS) v.radius = a->brush.radius;
    if (a->mask & DF_HID_BS_NU) v.nu = a->brush.nu;
    if (a->mask & DF_HID_BS_STRENGTH) v.strength = a->brush.strength;
    df_origin o = origin_of(d);
    df_error err;
    if (df_brush_state_apply(s, a->mask, &v, &o, &err) != DF_OK) {
        d->requests_failed++;
        df_log(DF_LOG_DEBUG, "hid: %s: brush change refused: %s", d->info.path, err.msg);
    }
}

/* The strength of d's stroke: a pen's pressure mapping, else the session brush's. */
static double stroke_strength(const df_hid_device *d, df_session *s, const df_hid_action *a)
{
    double v = d->cls.cls == DF_HID_CLASS_PEN ? a->strength : df_brush_state_get(s)->strength;
    return isfinite(v) ? v : 1.0;
}

static void stroke_begin(df_hid_device *d, df_session *s, const df_hid_action *a)
{
    if (d->stroke) df_hid_drive_end_stroke(d);
    d->stroke_skipped = 0;
    double centre[3];
    if (d->cls.cls == DF_HID_CLASS_PEN) {
        if (!pen_hit(d, s, a->xy, centre)) {
            d->stroke_skipped = 1;
            return;
        }
    } else {
        memcpy(centre, d->cursor, sizeof centre);
    }
    df_msg_brush m;
    df_msg_brush_defaults(&m);
    m.session_id = s->id;
    m.use_session = DRIVE_USE_SESSION;
    memcpy(m.center, centre, sizeof centre);
    memcpy(m.twist, a->twist, sizeof m.twist);
    if (d->cls.cls != DF_HID_CLASS_PEN) memcpy(m.move, a->move, sizeof m.move);
    m.strength = stroke_strength(d, s, a);
    df_buf b;
    df_buf_init(&b);
    df_error err;
    int rc = df_msg_brush_encode(&m, &b, &err);
    if (rc == DF_OK) rc = submit(d, DF_MSG_BRUSH_BEGIN, &df_k_brush_begin, &b);
    df_buf_free(&b);
    if (rc != DF_OK) {
        d->stroke_skipped = 1;
        return;
    }
    d->stroke = 1;
    d->stroke_session = s->id;
    d->stroke_strength = m.strength;
    memcpy(d->stroke_center, centre, sizeof centre);
    memcpy(d->last_tip, m.move, sizeof d->last_tip);
    memcpy(d->last_twist, m.twist, sizeof d->last_twist);
    d->last_strength = m.strength;
    if (fabs(m.strength) > d->strength_max) d->strength_max = fabs(m.strength);
    d->strokes_begun++;
}

static void stroke_update(df_hid_device *d, df_session *s, const df_hid_action *a)
{
    if (!d->stroke || d->stroke_session != s->id) return;
    double strength = stroke_strength(d, s, a);
    df_buf b;
    df_buf_init(&b);
    df_error err;
    if (isfinite(strength) && strength != d->stroke_strength) {
        df_msg_brush_param p = {.session_id = s->id, .param = DF_BP_STRENGTH, .value = strength};
        if (df_msg_brush_param_encode(&p, &b, &err) == DF_OK &&
            submit(d, DF_MSG_SET_BRUSH_PARAM, &df_k_set_brush_param, &b) == DF_OK) {
            d->stroke_strength = strength;
            d->last_strength = strength;
            if (fabs(strength) > d->strength_max) d->strength_max = fabs(strength);
        }
        df_buf_reset(&b);
    }
    df_msg_brush_update u;
    memset(&u, 0, sizeof u);
    u.session_id = s->id;
    memcpy(u.twist, a->twist, sizeof u.twist);
    if (d->cls.cls == DF_HID_CLASS_PEN) {
        double c[3];
        if (pen_hit(d, s, a->xy, c))
            for (int k = 0; k < 3; k++) u.move[k] = c[k] - d->stroke_center[k];
        else
            memcpy(u.move, d->last_tip, sizeof u.move); /* off the surface: hold */
    } else {
        memcpy(u.move, a->move, sizeof u.move);
    }
    if (df_msg_brush_update_encode(&u, &b, &err) == DF_OK)
        submit(d, DF_MSG_BRUSH_UPDATE, &df_k_brush_update, &b);
    memcpy(d->last_tip, u.move, sizeof d->last_tip);
    memcpy(d->last_twist, u.twist, sizeof d->last_twist);
    df_buf_free(&b);
}

static void output(df_hid_device *d, const df_hid_action *a)
{
    df_hid_backend *b = d->mgr->be[d->be];
    df_error err;
    int rc = DF_OK;
    if (!d->dev) return;
    if (a->kind == DF_HID_ACT_HAPTIC)
        rc = b->write_output(d->dev, a->bytes, a->n_bytes, &err);
    else
        rc = b->control(d->dev, DF_HID_POWERMATE_LED_REQTYPE, DF_HID_POWERMATE_LED_REQUEST,
                        DF_HID_POWERMATE_LED_STATIC, (uint16_t)(a->led < 0 ? 0 : a->led > 255
                                                                                 ? 255 : a->led),
                        &err);
    if (rc != DF_OK && !d->logged_error++)
        df_log(DF_LOG_WARN, "hid: %s: output failed: %s", d->info.path, err.msg);
}

static void apply(df_hid_device *d, df_session *s, const df_hid_action *a)
{
    d->actions++;
    switch (a->kind) {
    case DF_HID_ACT_BRUSH_SET: brush_set(d, s, a); break;
    case DF_HID_ACT_CURSOR: cursor_action(d, s, a); break;
    case DF_HID_ACT_STROKE_BEGIN: stroke_begin(d, s, a); break;
    case DF_HID_ACT_STROKE_UPDATE: stroke_update(d, s, a); break;
    case DF_HID_ACT_STROKE_END:
        if (d->stroke && d->stroke_session == s->id) df_hid_drive_end_stroke(d);
        d->stroke_skipped = 0;
        break;
    case DF_HID_ACT_HAPTIC:
    case DF_HID_ACT_LED: output(d, a); break;
    default: break;
    }
}

static void to_hid_brush(const df_brush_state *bs, df_hid_brush *out)
{
    out->type = bs->type;
    out->falloff = bs->falloff;
    out->radius = bs->radius;
    out->nu = bs->nu;
    out->strength = bs->strength;
}

void df_hid_drive_report(df_hid_device *d, const uint8_t *buf, size_t len, uint64_t time_us)
{
    if (!d->mapper_ok) return;
    df_session *s = df_hid_drive_session(d);
    if (!s) {
        if (!d->logged_no_session++)
            df_log(DF_LOG_INFO, "hid: %s: no session to drive (bind one, or use one)",
                   d->info.path);
        return;
    }
    d->logged_no_session = 0;
    if (d->stroke && d->stroke_session != s->id) df_hid_drive_end_stroke(d);
    if (d->active != s->id) attach(d, s);
    df_hid_brush cur;
    to_hid_brush(df_brush_state_get(s), &cur);
    df_hid_action acts[DF_HID_MAX_ACTIONS];
    size_t n = 0;
    df_error err;
    if (df_hid_mapper_feed(&d->map, buf, len, time_us, &cur, acts, DF_HID_MAX_ACTIONS, &n,
                           &err) != DF_OK) {
        df_log(DF_LOG_DEBUG, "hid: %s: report of %zu bytes ignored: %s", d->info.path, len,
               err.msg);
        return;
    }
    for (size_t i = 0; i < n; i++) apply(d, s, &acts[i]);
}

void df_hid_drive_unplug(df_hid_device *d)
{
    if (!d->mapper_ok) return;
    df_hid_action acts[DF_HID_MAX_ACTIONS];
    size_t n = 0;
    df_error err;
    df_session *s = d->stroke ? df_session_find(d->mgr->srv, d->stroke_session)
                              : df_hid_drive_session(d);
    if (df_hid_mapper_unplug(&d->map, acts, DF_HID_MAX_ACTIONS, &n, &err) == DF_OK && s)
        for (size_t i = 0; i < n; i++)
            if (acts[i].kind != DF_HID_ACT_HAPTIC && acts[i].kind != DF_HID_ACT_LED)
                apply(d, s, &acts[i]);
    df_hid_drive_end_stroke(d); /* whatever the mapper said: nothing stays open */
}
