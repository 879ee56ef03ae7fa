/* hid_mgr_ffb.c — a force-feedback joystick plays the live grab's Kelvinlet force: see
 * hid_mgr_ffb.h. Loop thread only. */
#include "server/hid/hid_mgr_ffb.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "server/hid/hid_config.h"
#include "server/hid/hid_ffb.h"
#include "server/hid/hid_mgr_internal.h"
#include "server/log.h"
#include "server/session/session.h"
#include "server/session/stroke_force.h"

#define FFB_MAX_REPORT 64 /* bytes of the PID reports kept for comparison (SideWinder: <= 16) */

struct df_hid_ffbdev {
    df_hid_ffb f;                /* the device's PID report layout */
    double gain;                 /* ffb_gain */
    int hz;                      /* ffb_hz (0: no rate limit) */
    int actuators;               /* Device Control Enable Actuators sent since the open */
    int playing;                 /* an effect was created and started */
    int refused;                 /* Create New Effect / Block Load failed: nothing until the
                                    grab strokes end */
    unsigned block;              /* its effect block index */
    uint64_t session_id;         /* the session whose strokes it plays */
    uint8_t effect[FFB_MAX_REPORT], force[FFB_MAX_REPORT]; /* last Set Effect / Constant Force */
    size_t n_effect, n_force;
    double magnitude, deg;       /* the latest force (sent, or pending) */
    int pending;                 /* the latest force waits for the rate-limit timer */
    uint64_t last_ms;            /* uv_now of the last update sent */
    int timer_init, timer_closed;
    uv_timer_t timer;
    uint64_t reports;            /* reports sent (output + feature) */
    int logged;                  /* an output error was logged (once per open) */
};

void df_hid_ffb_setup(df_hid_device *d)
{
    if (d->ffb || !d->have_desc) return;
    df_hid_params p;
    df_error err;
    if (df_hid_config_resolve(&d->mgr->srv->cfg.hid, DF_HID_CLASS_NONE, d->info.vid, d->info.pid,
                              &p, &err) != DF_OK || !p.force_feedback)
        return;
    df_hid_ffb f;
    if (df_hid_ffb_init(&d->desc, &f, &err) != DF_OK || !f.present || !f.operation.present) {
        df_log(DF_LOG_WARN, "hid: %s (%s): force_feedback = yes, but its descriptor has no PID "
               "constant-force output reports", d->info.path, d->info.name);
        return;
    }
    d->ffb = calloc(1, sizeof *d->ffb);
    if (!d->ffb) {
        df_log(DF_LOG_ERROR, "hid: %s: out of memory for force feedback", d->info.path);
        return;
    }
    d->ffb->f = f;
    d->ffb->gain = p.ffb_gain;
    d->ffb->hz = p.ffb_hz;
    d->ffb->timer.data = d;
    df_log(DF_LOG_INFO, "hid: %s (%s): force feedback on (gain %g, %d Hz)", d->info.path,
           d->info.name, p.ffb_gain, p.ffb_hz);
}

/* Sends one report (feature 1: SET_REPORT Feature); errors logged once per open. */
static int send_report(df_hid_device *d, int feature, const uint8_t *b, size_t n)
{
    df_hid_backend *be = d->mgr->be[d->be];
    df_error err;
    if (!d->dev || !be) return DF_ENOTFOUND;
    int rc = feature ? df_hid_send_feature(be, d->dev, b, n, &err)
                     : be->write_output(d->dev, b, n, &err);
    if (rc == DF_OK) d->ffb->reports++;
    else if (!d->ffb->logged++)
        df_log(DF_LOG_WARN, "hid: %s: force feedback report failed: %s", d->info.path, err.msg);
    return rc;
}

/* The Set Effect and Set Constant Force reports of the latest force into the buffers. */
static int build(df_hid_device *d, uint8_t *effect, size_t *ne, uint8_t *force, size_t *nf)
{
    struct df_hid_ffbdev *x = d->ffb;
    df_hid_ffb_effect fx = {.block = x->block, .duration_ms = DF_HID_FFB_INFINITE, .gain = 1.0,
                            .trigger_button = 0, .axes = 3, .polar = 1,
                            .direction_deg = {x->deg, 0}};
    df_error err;
    if (df_hid_ffb_set_constant_effect(&x->f, &fx, effect, FFB_MAX_REPORT, ne, &err) != DF_OK ||
        df_hid_ffb_constant_force(&x->f, x->block, x->magnitude, force, FFB_MAX_REPORT, nf,
                                  &err) != DF_OK) {
        df_log(DF_LOG_WARN, "hid: %s: force feedback: %s", d->info.path, err.msg);
        return DF_EINVAL;
    }
    return DF_OK;
}

/* Sends Set Effect / Set Constant Force when their bytes differ from the last sent. */
static void flush(df_hid_device *d)
{
    struct df_hid_ffbdev *x = d->ffb;
    uint8_t effect[FFB_MAX_REPORT], force[FFB_MAX_REPORT];
    size_t ne, nf;
    x->pending = 0;
    x->last_ms = uv_now(d->mgr->srv->loop);
    if (build(d, effect, &ne, force, &nf) != DF_OK) return;
    if (ne != x->n_effect || memcmp(effect, x->effect, ne) != 0) {
        send_report(d, 0, effect, ne);
        memcpy(x->effect, effect, ne);
        x->n_effect = ne;
    }
    if (nf != x->n_force || memcmp(force, x->force, nf) != 0) {
        send_report(d, 0, force, nf);
        memcpy(x->force, force, nf);
        x->n_force = nf;
    }
}

static void on_timer(uv_timer_t *t)
{
    df_hid_device *d = t->data;
    if (d->ffb && d->ffb->pending && d->ffb->playing && !d->mgr->stopping) flush(d);
}

/* The latest force is sent now, or at the end of the rate-limit interval. */
static void update(df_hid_device *d)
{
    struct df_hid_ffbdev *x = d->ffb;
    uv_loop_t *loop = d->mgr->srv->loop;
    uint64_t now = uv_now(loop), interval = x->hz > 0 ? (uint64_t)(1000 / x->hz) : 0;
    if (interval == 0 || now - x->last_ms >= interval) {
        flush(d);
        return;
    }
    x->pending = 1;
    if (!x->timer_init) {
        uv_timer_init(loop, &x->timer);
        uv_unref((uv_handle_t *)&x->timer);
        x->timer_init = 1;
    }
    if (!uv_is_active((uv_handle_t *)&x->timer))
        uv_timer_start(&x->timer, on_timer, interval - (now - x->last_ms), 0);
}

/* Creates, loads and starts the effect for session sid. */
static void start(df_hid_device *d, uint64_t sid)
{
    struct df_hid_ffbdev *x = d->ffb;
    uint8_t b[FFB_MAX_REPORT];
    size_t n;
    df_error err;
    if (!x->actuators && x->f.control.present &&
        df_hid_ffb_device_control(&x->f, DF_HID_PID_ENABLE_ACTUATORS, b, sizeof b, &n, &err) ==
            DF_OK && send_report(d, 0, b, n) == DF_OK)
        x->actuators = 1;
    x->block = 1;
    if (x->f.create.present) {
        if (df_hid_ffb_create_new_effect(&x->f, 0, b, sizeof b, &n, &err) != DF_OK ||
            send_report(d, 1, b, n) != DF_OK) {
            x->refused = 1;
            return;
        }
        int rc = df_hid_ffb_block_load_request(&x->f, b, sizeof b, &n, &err);
        if (rc == DF_OK) rc = df_hid_get_feature(d->mgr->be[d->be], d->dev, b, n, &err);
        unsigned block = 0, status = 0;
        if (rc > 0 && df_hid_ffb_block_load_parse(&x->f, b, (size_t)rc, &block, &status, &err) ==
                          DF_OK) {
            if (status != DF_HID_PID_BLOCK_LOAD_SUCCESS || block == 0) {
                df_log(DF_LOG_WARN, "hid: %s: force feedback: the device refused the effect "
                       "(block load status 0x%x, block %u)", d->info.path, status, block);
                x->refused = 1;
                return;
            }
            x->block = block;
        } else if (rc == DF_EUNSUPPORTED) {
            df_log(DF_LOG_DEBUG, "hid: %s: no block load reply (%s): effect block 1",
                   d->info.path, err.msg);
        } else {
            df_log(DF_LOG_WARN, "hid: %s: force feedback: block load: %s", d->info.path,
                   err.msg);
            x->refused = 1;
            return;
        }
    }
    x->playing = 1;
    x->session_id = sid;
    x->n_effect = x->n_force = 0;
    flush(d);
    if (df_hid_ffb_operation(&x->f, x->block, DF_HID_PID_OP_START, 1, b, sizeof b, &n, &err) ==
        DF_OK)
        send_report(d, 0, b, n);
}

void df_hid_ffb_stop(df_hid_device *d, uint64_t session_id, int close)
{
    struct df_hid_ffbdev *x = d->ffb;
    if (!x) return;
    if (x->playing && (!session_id || x->session_id == session_id)) {
        uint8_t b[FFB_MAX_REPORT];
        size_t n;
        df_error err;
        if (df_hid_ffb_operation(&x->f, x->block, DF_HID_PID_OP_STOP, 0, b, sizeof b, &n, &err) ==
            DF_OK)
            send_report(d, 0, b, n);
        if (x->f.block_free.present &&
            df_hid_ffb_block_free(&x->f, x->block, b, sizeof b, &n, &err) == DF_OK)
            send_report(d, 0, b, n);
        x->playing = 0;
        x->pending = 0;
        if (x->timer_init && !x->timer_closed) uv_timer_stop(&x->timer);
    }
    if (!session_id || x->session_id == session_id) x->refused = 0;
    if (close) {
        x->actuators = 0;
        x->logged = 0;
    }
}

void df_hid_ffb_strokes_changed(df_server *srv, df_session *s)
{
    df_hid_manager *m = srv->hid;
    if (!m || m->stopping || !s) return;
    for (df_hid_device *d = m->devs; d; d = d->next) {
        struct df_hid_ffbdev *x = d->ffb;
        if (!x || d->state != DF_DEVSTATE_OPEN) continue;
        df_session *t = df_hid_drive_session(d);
        if (x->playing && (!t || x->session_id != t->id)) df_hid_ffb_stop(d, 0, 0);
        if (t != s) continue;
        double f[3];
        if (!df_session_grab_force(s, f)) {
            df_hid_ffb_stop(d, 0, 0);
            continue;
        }
        df_hid_ffb_from_force(f, x->gain, &x->magnitude, &x->deg);
        if (!x->playing && !x->refused) start(d, s->id);
        else if (x->playing) update(d);
    }
}

void df_hid_ffb_close(df_hid_device *d)
{
    struct df_hid_ffbdev *x = d->ffb;
    if (!x || !x->timer_init || x->timer_closed) return;
    uv_timer_stop(&x->timer);
    uv_close((uv_handle_t *)&x->timer, NULL);
    x->timer_closed = 1;
}

void df_hid_ffb_free(df_hid_device *d)
{
    if (!d) return;
    free(d->ffb);
    d->ffb = NULL;
}

uint64_t df_hid_ffb_reports(const df_hid_device *d)
{
    return d->ffb ? d->ffb->reports : 0;
}

int df_hid_ffb_pending(const df_hid_device *d)
{
    return d->ffb ? d->ffb->pending : 0;
}
