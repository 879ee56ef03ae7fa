/* Unit tests for server/hid/hid_manager.c with a fake live backend (the hid_source.h seam) on a
 * real libuv loop and compute pool: a 3D mouse (the SpaceNavigator's descriptor) opens at start,
 * its reports become a stroke on the session (an internal BRUSH_BEGIN keyed by the device id), a
 * read error mid-stroke closes it as ERROR and ends the stroke through BRUSH_END (one undo step),
 * a hotplug notification reopens it with the same id, an enumeration without it marks it
 * UNPLUGGED, binding checks its arguments, an unbound device follows the most recently active
 * session (its stroke on the previous one ends first), and shutdown joins the reader thread and
 * closes the device. The loop is run until each expected state is reached (no sleeps; a guard fails a test
 * that would hang). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <cmocka.h>

#include "server/exec/job.h"
#include "server/exec/pool.h"
#include "server/hid/hid_manager.h"
#include "server/hid/hid_mgr_internal.h"
#include "server/hid/hid_recording.h"
#include "server/session/session.h"
#include "tests/unit/server/hid_live_rig.h"

/* ------------------------------------------------------------------------- the fake backend */
typedef struct fake {
    df_hid_backend b;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    df_hid_devinfo info;
    int present;                 /* listed by enumerate */
    int fail;                    /* reads return this (< 0) while set */
    uint8_t pk[32][8];
    size_t len[32];
    uint64_t t[32];
    int head, tail;
    int opens, closes, open_now;
    df_hid_change_fn fn;
    void *user;
} fake;

typedef struct fake_dev {
    fake *f;
} fake_dev;

static int f_enumerate(df_hid_backend *b, df_hid_devinfo **out, size_t *n, df_error *err)
{
    fake *f = (fake *)b;
    *out = NULL;
    *n = 0;
    pthread_mutex_lock(&f->mu);
    int present = f->present;
    pthread_mutex_unlock(&f->mu);
    if (!present) return DF_OK;
    *out = calloc(1, sizeof **out);
    if (!*out || df_hid_devinfo_copy(*out, &f->info, err) != DF_OK) return DF_ENOMEM;
    *n = 1;
    return DF_OK;
}

static int f_open(df_hid_backend *b, const char *path, df_hid_dev **out, df_error *err)
{
    fake *f = (fake *)b;
    if (strcmp(path, f->info.path) != 0 || !f->present)
        return df_error_set(err, DF_ENOTFOUND, "fake: no %s", path);
    fake_dev *d = calloc(1, sizeof *d);
    d->f = f;
    pthread_mutex_lock(&f->mu);
    f->opens++;
    f->open_now++;
    pthread_mutex_unlock(&f->mu);
    *out = (df_hid_dev *)d;
    return DF_OK;
}

static int f_read(df_hid_dev *dd, uint8_t *buf, size_t cap, int timeout_ms, uint64_t *time_us,
                  df_error *err)
{
    fake *f = ((fake_dev *)dd)->f;
    struct timespec until;
    clock_gettime(CLOCK_REALTIME, &until);
    until.tv_nsec += (long)timeout_ms * 1000000L;
    until.tv_sec += until.tv_nsec / 1000000000L;
    until.tv_nsec %= 1000000000L;
    int rc = 0;
    pthread_mutex_lock(&f->mu);
    while (!f->fail && f->head == f->tail)
        if (pthread_cond_timedwait(&f->cv, &f->mu, &until) != 0) break;
    if (f->fail) {
        rc = df_error_set(err, f->fail, "fake: %s", f->info.path);
    } else if (f->head != f->tail) {
        int k = f->head++;
        rc = (int)(f->len[k] < cap ? f->len[k] : cap);
        memcpy(buf, f->pk[k], (size_t)rc);
        *time_us = f->t[k];
    }
    pthread_mutex_unlock(&f->mu);
    return rc;
}

static int f_write(df_hid_dev *d, const uint8_t *data, size_t len, df_error *err)
{
    (void)d, (void)data, (void)len;
    return df_error_set(err, DF_EUNSUPPORTED, "fake: no output");
}

static int f_control(df_hid_dev *d, uint8_t rt, uint8_t rq, uint16_t v, uint16_t i, df_error *err)
{
    (void)d, (void)rt, (void)rq, (void)v, (void)i;
    return df_error_set(err, DF_EUNSUPPORTED, "fake: no control");
}

static void f_close(df_hid_dev *dd)
{
    fake *f = ((fake_dev *)dd)->f;
    pthread_mutex_lock(&f->mu);
    f->closes++;
    f->open_now--;
    pthread_mutex_unlock(&f->mu);
    free(dd);
}

static int f_watch(df_hid_backend *b, df_hid_change_fn fn, void *user, df_error *err)
{
    (void)err;
    fake *f = (fake *)b;
    f->fn = fn;
    f->user = user;
    return DF_OK;
}

static fake *g_fake;            /* outlives destroy: the test reads its counters afterwards */
static void f_destroy(df_hid_backend *b)
{
    (void)b;                    /* freed by the test */
}

static void push(fake *f, uint64_t t, const uint8_t *p, size_t n)
{
    pthread_mutex_lock(&f->mu);
    memcpy(f->pk[f->tail], p, n);
    f->len[f->tail] = n;
    f->t[f->tail++] = t;
    pthread_cond_broadcast(&f->cv);
    pthread_mutex_unlock(&f->mu);
}

static void set_fail(fake *f, int code, int present)
{
    pthread_mutex_lock(&f->mu);
    f->fail = code;
    f->present = present;
    pthread_cond_broadcast(&f->cv);
    pthread_mutex_unlock(&f->mu);
}

/* --------------------------------------------------------------------------------- harness */
static df_hid_device *the_dev(df_server *srv) { return srv->hid->devs; }
static int is_open(void *a) { return the_dev(a)->state == DF_DEVSTATE_OPEN; }
static int is_error(void *a) { return the_dev(a)->state == DF_DEVSTATE_ERROR; }
static int is_gone(void *a) { return the_dev(a)->state == DF_DEVSTATE_UNPLUGGED; }
static int three_events(void *a) { return the_dev(a)->events == 3; }
static df_session *g_s;
static int stroke_open(void *a) { return df_session_stroke(g_s, the_dev(a)->id) != NULL; }
static int stroke_gone(void *a)
{
    (void)a;
    return g_s->strokes == NULL && !g_s->running && !g_s->jhead;
}
static int idle(void *a) { return !df_hid_manager_busy(a); }
static uint64_t g_want_events;
static df_session *g_s2;
static int n_events(void *a) { return the_dev(a)->events >= g_want_events; }
static int stroke_open_s2(void *a) { return df_session_stroke(g_s2, the_dev(a)->id) != NULL; }
static int s2_stroke_gone(void *a)
{
    (void)a;
    return g_s2->strokes == NULL && !g_s2->running && !g_s2->jhead;
}

static void test_live_device_stroke_error_hotplug_unplug_shutdown(void **state)
{
    (void)state;
    static hid_rig rig;
    hid_rig *g = &rig;
    hid_rig_recording(g, "3dconnexion-spacenavigator_046d-c626_usb.hid");
    df_error e;

    fake *f = g_fake = calloc(1, sizeof *f);
    pthread_mutex_init(&f->mu, NULL);
    pthread_cond_init(&f->cv, NULL);
    f->b = (df_hid_backend){.kind = DF_HID_BACKEND_HIDAPI, .name = "fake", .enumerate =
                            f_enumerate, .open = f_open, .read = f_read, .write_output = f_write,
                            .control = f_control, .close = f_close, .watch = f_watch,
                            .destroy = f_destroy};
    hid_rig_devinfo(g, &f->info, "fake:0", "Fake Navigator", 0x046d, 0xc626);
    f->info.bus = DF_HID_BUS_USB;
    f->present = 1;

    static df_server srv;
    hid_rig_start(g, &srv, &g_s); /* g_s: the most recently active session */
    assert_int_equal(df_hid_config_set(&srv.cfg.hid, "hid.3d-mouse.deadzone", "0", &e), DF_OK);

    assert_int_equal(df_hid_manager_start_with(&srv, &f->b, NULL, NULL, &e), DF_OK);
    df_hid_device *d = the_dev(&srv);
    assert_non_null(d);
    uint64_t id = d->id;
    assert_true(id == ((1ull << 63) | 1));
    assert_int_equal(d->cls.cls, DF_HID_CLASS_MOUSE3D);
    assert_int_equal(d->state, DF_DEVSTATE_OPEN);
    df_msg_device_list l;
    assert_int_equal(df_hid_manager_list(&srv, &l, &e), DF_OK);
    assert_int_equal(l.count, 1);
    assert_int_equal(l.items[0].dev_class, DF_DEVCLASS_MOUSE3D);
    assert_string_equal(l.items[0].name, "Fake Navigator");
    df_msg_device_list_free(&l);

    /* button 1 down, then two translation reports: a stroke keyed by the device id */
    const uint8_t down[3] = {3, 1, 0}, mv[7] = {1, 100, 0, 0, 0, 0, 0};
    push(f, 0, down, 3);
    push(f, 8000, mv, 7);
    push(f, 16000, mv, 7);
    hid_rig_run_until(g, three_events, &srv, "three reports handled");
    hid_rig_run_until(g, stroke_open, &srv, "the device's stroke is open");
    assert_int_equal(d->strokes_begun, 1);
    assert_int_equal(d->active, g_s->id);

    /* a read error mid-stroke: ERROR, the stroke ends through BRUSH_END (an undo step) */
    set_fail(f, DF_EIO, 1);
    hid_rig_run_until(g, is_error, &srv, "state ERROR");
    assert_non_null(strstr(d->error, "fake: fake:0"));
    hid_rig_run_until(g, stroke_gone, &srv, "stroke ended");
    assert_int_equal(d->strokes_ended, 1);
    assert_true(df_history_can_undo(&g_s->hist) >= 1);
    assert_int_equal(f->closes, 1);

    /* hotplug: the backend says something changed; the device is back, same id */
    set_fail(f, 0, 1);
    f->fn(f->user);
    hid_rig_run_until(g, is_open, &srv, "reopened after hotplug");
    assert_true(the_dev(&srv) == d && d->id == id && srv.hid->ndev == 1);
    assert_int_equal(f->opens, 2);

    /* it leaves: the next enumeration closes it as UNPLUGGED */
    set_fail(f, 0, 0);
    f->fn(f->user);
    hid_rig_run_until(g, is_gone, &srv, "unplugged");
    assert_string_equal(d->error, "no longer present");
    assert_int_equal(f->closes, 2);

    /* binding checks device and session; a bound session that closes unbinds */
    assert_int_equal(df_hid_manager_bind(&srv, id, 999, &e), DF_ENOTFOUND);
    assert_int_equal(df_hid_manager_bind(&srv, id ^ 1, g_s->id, &e), DF_ENOTFOUND);
    assert_int_equal(df_hid_manager_bind(&srv, id, g_s->id, &e), DF_OK);
    assert_int_equal(d->bound, g_s->id);

    /* back again; unbound, it follows the most recently active session: a stroke there, and
     * when another session becomes the most recent, that stroke ends (BRUSH_END) first */
    set_fail(f, 0, 1);
    f->fn(f->user);
    hid_rig_run_until(g, is_open, &srv, "reopened");
    assert_int_equal(df_hid_manager_bind(&srv, id, 0, &e), DF_OK);
    df_mesh m2 = tiny_mesh();
    df_session *s2;
    assert_int_equal(df_session_create(&srv, &m2, "t2", &s2, &e), DF_OK);
    srv.last_change_session = s2->id;
    const uint8_t up[3] = {3, 0, 0};
    g_want_events = d->events + 4;
    push(f, 100000, up, 3);
    push(f, 108000, down, 3);
    push(f, 116000, mv, 7);
    push(f, 124000, mv, 7);     /* the first after a reopen has no dt yet */
    hid_rig_run_until(g, n_events, &srv, "reports after the reopen handled");
    g_s2 = s2;
    hid_rig_run_until(g, stroke_open_s2, &srv, "a stroke on the most recent session");
    assert_int_equal(d->active, s2->id);
    srv.last_change_session = g_s->id;
    g_want_events = d->events + 1;
    push(f, 132000, mv, 7);
    hid_rig_run_until(g, n_events, &srv, "one more report");
    hid_rig_run_until(g, s2_stroke_gone, &srv, "the stroke on the other session ended");
    assert_int_equal(d->active, g_s->id);
    assert_true(df_history_can_undo(&s2->hist) >= 1);

    /* shutdown joins its reader and closes it */
    df_hid_manager_stop(&srv);
    assert_int_equal(d->th_running, 0);
    assert_int_equal(f->open_now, 0);
    assert_int_equal(f->closes, 3);
    hid_rig_run_until(g, idle, &srv, "posted reports drained");
    df_session_close(g_s);
    df_job_pump(g_s);
    df_session_close(s2);
    df_job_pump(s2);
    df_hid_manager_free(&srv);
    assert_null(srv.hid);
    hid_rig_finish(g, &srv);
    pthread_mutex_destroy(&f->mu);
    pthread_cond_destroy(&f->cv);
    free(f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_live_device_stroke_error_hotplug_unplug_shutdown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
