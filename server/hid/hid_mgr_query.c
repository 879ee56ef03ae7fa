/* hid_mgr_query.c — the HID manager's requests: DEVICES_LIST, DEVICE_BIND, DEVICE_VIEW, a
 * device's stats and the daemon-wide counts (see hid_manager.h), and srv->hid_ops. Loop thread. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "server/hid/hid_manager.h"
#include "server/hid/hid_mgr_ffb.h"
#include "server/hid/hid_mgr_internal.h"
#include "server/session/session.h"

/* ------------------------------------------------------------------------- list, bind, view */
int df_hid_manager_list(df_server *srv, df_msg_device_list *out, df_error *err)
{
    memset(out, 0, sizeof *out);
    df_hid_manager *m = srv->hid;
    if (!m || m->ndev == 0) return DF_OK;
    out->items = calloc(m->ndev, sizeof *out->items);
    if (!out->items) return df_error_set(err, DF_ENOMEM, "devices_list: out of memory");
    for (df_hid_device *d = m->devs; d; d = d->next) df_hid_device_info(d, &out->items[out->count++]);
    return DF_OK;
}

/* DF_ENOTFOUND for device id `id`, named as `deformctl devices` numbers it (n of (1 << 63) | n)
 * with the id, so a user who typed the number recognises it. */
static int no_device(const df_server *srv, const char *what, uint64_t id, df_error *err)
{
    if (id & DF_HID_ID_BIT)
        return df_error_set(err, DF_ENOTFOUND, "%s: no device %llu (id %llu)%s", what,
                            (unsigned long long)(id & ~DF_HID_ID_BIT), (unsigned long long)id,
                            srv->hid ? "" : ": the HID subsystem is off");
    return df_error_set(err, DF_ENOTFOUND, "%s: no device %llu (device ids have bit 63 set)%s",
                        what, (unsigned long long)id,
                        srv->hid ? "" : ": the HID subsystem is off");
}

/* The device to bind: it exists and drives sessions (a class); the session (0: none) is live. */
static int lookup(df_server *srv, uint64_t device_id, uint64_t session_id, const char *what,
                  df_hid_device **d, df_error *err)
{
    *d = srv->hid ? df_hid_find(srv->hid, device_id) : NULL;
    if (!*d) return no_device(srv, what, device_id, err);
    if ((*d)->cls.cls == DF_HID_CLASS_NONE)
        return df_error_set(err, DF_EINVAL, "%s: device %llu (%04x:%04x '%s') is not a knob, "
                            "3d-mouse or pen: it drives no session", what,
                            (unsigned long long)(device_id & ~DF_HID_ID_BIT), (*d)->info.vid,
                            (*d)->info.pid, (*d)->info.name);
    if (session_id && !df_session_find(srv, session_id))
        return df_error_set(err, DF_ENOTFOUND, "%s: no session %llu", what,
                            (unsigned long long)session_id);
    return DF_OK;
}

static void rebind(df_hid_device *d, uint64_t session_id)
{
    uint64_t before = d->bound;
    d->bound = session_id;
    if (before == session_id) return;
    if (d->stroke && d->stroke_session != session_id) df_hid_drive_end_stroke(d);
    uint64_t old = d->active;
    if (d->state == DF_DEVSTATE_OPEN) {
        df_session *s = df_hid_drive_session(d);
        d->active = s ? s->id : 0;
    }
    if (old && old != d->active) df_hid_device_announce(d, old);
    df_hid_device_announce(d, d->active ? d->active : session_id);
}

int df_hid_manager_bind(df_server *srv, uint64_t device_id, uint64_t session_id, df_error *err)
{
    df_hid_device *d;
    int rc = lookup(srv, device_id, session_id, "device_bind", &d, err);
    if (rc != DF_OK) return rc;
    if (session_id != d->bound) d->have_view = 0; /* a view belongs to its session */
    rebind(d, session_id);
    return DF_OK;
}

int df_hid_manager_view(df_server *srv, const df_msg_device_view *v, df_error *err)
{
    df_hid_device *d;
    int rc = lookup(srv, v->device_id, v->session_id, "device_view", &d, err);
    if (rc == DF_OK) rc = df_pen_view_check(v->view_proj, v->viewport, err);
    if (rc != DF_OK) return rc;
    memcpy(d->view_proj, v->view_proj, sizeof d->view_proj);
    memcpy(d->viewport, v->viewport, sizeof d->viewport);
    d->have_view = 1;
    d->logged_no_view = 0;
    rebind(d, v->session_id);
    return DF_OK;
}

/* ----------------------------------------------------------------------------------- stats */
int df_hid_manager_device_stats(df_server *srv, uint64_t device_id,
                                void (*put)(void *ctx, const char *key, double v), void *ctx,
                                df_error *err)
{
    df_hid_device *d = srv->hid ? df_hid_find(srv->hid, device_id) : NULL;
    if (!d) return no_device(srv, "stats", device_id, err);
    put(ctx, "class", d->cls.cls);
    put(ctx, "state", d->state);
    put(ctx, "events", (double)d->events);
    put(ctx, "actions", (double)d->actions);
    put(ctx, "strokes_begun", (double)d->strokes_begun);
    put(ctx, "strokes_ended", (double)d->strokes_ended);
    put(ctx, "stroke_open", d->stroke);
    put(ctx, "requests_failed", (double)d->requests_failed);
    put(ctx, "bound_session", (double)d->bound);
    put(ctx, "active_session", (double)d->active);
    put(ctx, "last.tip_x", d->last_tip[0]);
    put(ctx, "last.tip_y", d->last_tip[1]);
    put(ctx, "last.tip_z", d->last_tip[2]);
    put(ctx, "last.twist_x", d->last_twist[0]);
    put(ctx, "last.twist_y", d->last_twist[1]);
    put(ctx, "last.twist_z", d->last_twist[2]);
    put(ctx, "last.strength", d->last_strength);
    put(ctx, "strength_max", d->strength_max);
    put(ctx, "force_feedback", d->ffb != NULL);
    put(ctx, "ffb.reports", (double)df_hid_ffb_reports(d));
    df_hid_backend *b = srv->hid->be[d->be];
    if (d->be != DF_HID_BE_REPLAY || !b) return DF_OK;
    uint64_t start;
    if (d->dev && df_hid_replay_start_us(b, d->dev, &start, NULL) == DF_OK)
        put(ctx, "replay.start_us", (double)start);
    df_hid_replay_output *outs = NULL;
    size_t n = 0;
    if (df_hid_replay_outputs(b, 0, &outs, &n, err) != DF_OK) return DF_OK;
    size_t k = 0;
    for (size_t i = 0; i < n; i++) {
        if (strcmp(outs[i].path, d->info.path) != 0) continue;
        char key[DF_MAX_STATS_KEY_LEN + 1];
        int w;
        if (outs[i].is_control) {
            w = snprintf(key, sizeof key, "ctl.%zu.%02x_%02x_%04x_%04x", k, outs[i].request_type,
                         outs[i].request, outs[i].value, outs[i].index);
        } else {
            w = snprintf(key, sizeof key, "%s.%zu.", outs[i].is_feature ? "feat" : "out", k);
            for (size_t j = 0; j < outs[i].len && w + 2 < (int)sizeof key; j++)
                w += snprintf(key + w, sizeof key - (size_t)w, "%02x", outs[i].data[j]);
        }
        k++;
        put(ctx, key, (double)outs[i].time_us);
    }
    df_hid_replay_outputs_free(outs, n);
    return DF_OK;
}

void df_hid_manager_counts(const df_server *srv, uint32_t *devices, uint32_t *open,
                           uint64_t *events)
{
    *devices = *open = 0;
    *events = 0;
    const df_hid_manager *m = srv->hid;
    if (!m) return;
    *devices = m->ndev;
    *events = m->events;
    for (const df_hid_device *d = m->devs; d; d = d->next) *open += d->state == DF_DEVSTATE_OPEN;
}

const df_hid_ops df_hid_manager_ops = {
    .list = df_hid_manager_list,
    .bind = df_hid_manager_bind,
    .view = df_hid_manager_view,
    .device_stats = df_hid_manager_device_stats,
    .counts = df_hid_manager_counts,
    .session_active = df_hid_manager_session_active,
    .session_gone = df_hid_manager_session_gone,
    .strokes_changed = df_hid_ffb_strokes_changed,
};
