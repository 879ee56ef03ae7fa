/* Unit tests for server/hid/hid_mgr_ffb.c with a fake live backend that answers feature reports
 * (what the replay backend cannot: Block Load), on a real libuv loop and compute pool: a grab
 * stroke on the session makes the SideWinder FF2 (its real descriptor) enable its actuators,
 * create the effect and read Block Load, and every later report uses the block the device
 * answered; a Block Load status other than Success stops there (no effect reports) until the
 * strokes end, and the next stroke tries again; with a rate limit the latest force still
 * arrives (trailing edge); a device that fails mid-stroke stops its effect before it closes; a
 * twist stroke plays nothing. The loop runs until each expected state is reached (no sleeps). */
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

#include "proto/messages.h"
#include "server/exec/job.h"
#include "server/exec/pool.h"
#include "server/handlers/handlers.h"
#include "server/hid/hid_ffb.h"
#include "server/hid/hid_manager.h"
#include "server/hid/hid_mgr_ffb.h"
#include "server/hid/hid_mgr_internal.h"
#include "server/hid/hid_recording.h"
#include "server/session/session.h"
#include "tests/unit/server/hid_live_rig.h"

#define MAXR 256

/* ------------------------------------------------------------------------- the fake backend */
typedef struct fake {
    df_hid_backend b;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    df_hid_devinfo info;
    int fail;                    /* reads return this (< 0) while set */
    uint8_t block, status;       /* the Block Load answer: block, status array index (1..3) */
    int n;                       /* captured reports */
    int feature[MAXR];
    uint8_t data[MAXR][64];
    size_t len[MAXR];
} fake;

typedef struct fake_dev { fake *f; } fake_dev;

static int f_enumerate(df_hid_backend *b, df_hid_devinfo **out, size_t *n, df_error *err)
{
    fake *f = (fake *)b;
    *out = calloc(1, sizeof **out);
    if (!*out || df_hid_devinfo_copy(*out, &f->info, err) != DF_OK) return DF_ENOMEM;
    *n = 1;
    return DF_OK;
}

static int f_open(df_hid_backend *b, const char *path, df_hid_dev **out, df_error *err)
{
    (void)path, (void)err;
    fake_dev *d = calloc(1, sizeof *d);
    d->f = (fake *)b;
    *out = (df_hid_dev *)d;
    return DF_OK;
}

/* No input reports: waits up to timeout_ms for a failure to be set. */
static int f_read(df_hid_dev *dd, uint8_t *buf, size_t cap, int timeout_ms, uint64_t *time_us,
                  df_error *err)
{
    (void)buf, (void)cap, (void)time_us;
    fake *f = ((fake_dev *)dd)->f;
    struct timespec until;
    clock_gettime(CLOCK_REALTIME, &until);
    until.tv_nsec += (long)timeout_ms * 1000000L;
    until.tv_sec += until.tv_nsec / 1000000000L;
    until.tv_nsec %= 1000000000L;
    pthread_mutex_lock(&f->mu);
    while (!f->fail)
        if (pthread_cond_timedwait(&f->cv, &f->mu, &until) != 0) break;
    int rc = f->fail ? df_error_set(err, f->fail, "fake: read failed") : 0;
    pthread_mutex_unlock(&f->mu);
    return rc;
}

static int keep(fake *f, int feature, const uint8_t *data, size_t len)
{
    pthread_mutex_lock(&f->mu);
    if (f->n < MAXR && len <= sizeof f->data[0]) {
        f->feature[f->n] = feature;
        memcpy(f->data[f->n], data, len);
        f->len[f->n++] = len;
    }
    pthread_mutex_unlock(&f->mu);
    return DF_OK;
}

static int f_write(df_hid_dev *d, const uint8_t *data, size_t len, df_error *err)
{
    (void)err;
    return keep(((fake_dev *)d)->f, 0, data, len);
}

static int f_send_feature(df_hid_dev *d, const uint8_t *data, size_t len, df_error *err)
{
    (void)err;
    return keep(((fake_dev *)d)->f, 1, data, len);
}

/* Block Load (report 2 of the SideWinder: [02][block][status 1..3][RAM pool u16]). */
static int f_get_feature(df_hid_dev *d, uint8_t *buf, size_t cap, df_error *err)
{
    fake *f = ((fake_dev *)d)->f;
    if (buf[0] != 2 || cap < 5) return df_error_set(err, DF_EINVAL, "fake: feature %u", buf[0]);
    const uint8_t r[5] = {2, f->block, f->status, 0x00, 0x10};
    memcpy(buf, r, 5);
    return 5;
}

static int f_control(df_hid_dev *d, uint8_t rt, uint8_t rq, uint16_t v, uint16_t i, df_error *err)
{
    (void)d, (void)rt, (void)rq, (void)v, (void)i;
    return df_error_set(err, DF_EUNSUPPORTED, "fake: no control");
}

static void f_close(df_hid_dev *dd) { free(dd); }
static void f_destroy(df_hid_backend *b) { (void)b; }

/* --------------------------------------------------------------------------------- harness */
static fake *g_f;
static df_session *g_s;
static int g_want;
static int reports_at_least(void *a) { (void)a; return g_f->n >= g_want; }
static int no_stroke(void *a) { (void)a; return g_s->strokes == NULL; }
static int has_stroke(void *a) { (void)a; return g_s->strokes != NULL; }
/* The second update is committed and no force waits for the timer. */
static int settled(void *a)
{
    df_hid_device *d = ((df_server *)a)->hid->devs;
    return g_s->strokes && g_s->strokes->tip[0] == 0.4 && !df_hid_ffb_pending(d) && g_f->n >= 7;
}
static int dev_error(void *a) { return ((df_server *)a)->hid->devs->state == DF_DEVSTATE_ERROR; }

/* Queues a brush request on behalf of a client with id 42 (as the daemon would). */
static void request(df_server *srv, uint16_t type, const df_job_kind *kind, const df_buf *b)
{
    df_req r = {.srv = srv, .c = NULL, .type = type, .len = (uint32_t)b->len, .origin_id = 42};
    df_error e;
    assert_int_equal(df_job_request(&r, b->data, kind, &e), DF_OK);
}

static void begin(df_server *srv, uint8_t type, double mx, double my)
{
    df_msg_brush m;
    df_msg_brush_defaults(&m);
    m.session_id = g_s->id;
    m.type = type;
    m.radius = 0.5;
    m.move[0] = mx;
    m.move[1] = my;
    m.twist[2] = type == DF_BRUSH_GRAB ? 0 : 0.2;
    df_buf b;
    df_buf_init(&b);
    df_error e;
    assert_int_equal(df_msg_brush_encode(&m, &b, &e), DF_OK);
    request(srv, DF_MSG_BRUSH_BEGIN, &df_k_brush_begin, &b);
    df_buf_free(&b);
}

static void update(df_server *srv, double mx, double my)
{
    df_msg_brush_update u;
    memset(&u, 0, sizeof u);
    u.session_id = g_s->id;
    u.move[0] = mx;
    u.move[1] = my;
    df_buf b;
    df_buf_init(&b);
    df_error e;
    assert_int_equal(df_msg_brush_update_encode(&u, &b, &e), DF_OK);
    request(srv, DF_MSG_BRUSH_UPDATE, &df_k_brush_update, &b);
    df_buf_free(&b);
}

static void end(df_server *srv)
{
    df_msg_session_ref m = {.session_id = g_s->id};
    df_buf b;
    df_buf_init(&b);
    df_error e;
    assert_int_equal(df_msg_session_ref_encode(&m, &b, &e), DF_OK);
    request(srv, DF_MSG_BRUSH_END, &df_k_brush_end, &b);
    df_buf_free(&b);
}

/* Report k's id byte / second byte (the effect block of every block report). */
static uint8_t rid(int k) { return g_f->data[k][0]; }
static uint8_t blk(int k) { return g_f->data[k][1]; }

static void test_block_load_refusal_rate_limit_and_error(void **state)
{
    (void)state;
    static hid_rig rig;
    hid_rig *g = &rig;
    hid_rig_recording(g, "microsoft-sidewinder-ff2_045e-001b_usb.hid");
    df_error e;

    fake *f = g_f = calloc(1, sizeof *f);
    pthread_mutex_init(&f->mu, NULL);
    pthread_cond_init(&f->cv, NULL);
    f->b = (df_hid_backend){.kind = DF_HID_BACKEND_HIDAPI, .name = "fake", .enumerate =
                            f_enumerate, .open = f_open, .read = f_read, .write_output = f_write,
                            .control = f_control, .close = f_close, .destroy = f_destroy,
                            .send_feature = f_send_feature, .get_feature = f_get_feature};
    hid_rig_devinfo(g, &f->info, "fake:ffb", "Fake SideWinder", 0x045e, 0x001b);
    f->block = 3;
    f->status = 2; /* Block Load Full first */

    static df_server srv;
    hid_rig_start(g, &srv, &g_s);
    assert_int_equal(df_hid_config_set(&srv.cfg.hid, "hid.045e:001b.force_feedback", "yes", &e),
                     DF_OK);
    assert_int_equal(df_hid_config_set(&srv.cfg.hid, "hid.045e:001b.ffb_hz", "1", &e), DF_OK);
    assert_int_equal(df_hid_manager_start_with(&srv, &f->b, NULL, NULL, &e), DF_OK);
    df_hid_device *d = srv.hid->devs;
    assert_int_equal(d->cls.cls, DF_HID_CLASS_NONE);
    assert_int_equal(d->state, DF_DEVSTATE_OPEN); /* opened for its force feedback */

    /* a twist stroke plays nothing */
    begin(&srv, DF_BRUSH_TWIST, 0, 0);
    hid_rig_run_until(g, has_stroke, &srv, "twist stroke open");
    end(&srv);
    hid_rig_run_until(g, no_stroke, &srv, "twist stroke ended");
    assert_int_equal(f->n, 0);

    /* Block Load says Full: actuators enabled, effect created, nothing else */
    begin(&srv, DF_BRUSH_GRAB, 0.1, 0.05);
    g_want = 2;
    hid_rig_run_until(g, reports_at_least, &srv, "enable + create");
    update(&srv, 0.2, 0.05);
    end(&srv);
    hid_rig_run_until(g, no_stroke, &srv, "refused stroke ended");
    assert_int_equal(f->n, 2);
    assert_int_equal(f->feature[0], 0);
    assert_int_equal(rid(0), 12); /* Device Control */
    assert_int_equal(f->feature[1], 1);
    assert_int_equal(rid(1), 1);  /* Create New Effect (feature 1) */

    /* Success with block 3: create, set effect, constant force, start (no second enable) */
    f->status = 1;
    begin(&srv, DF_BRUSH_GRAB, 0.1, 0.05);
    g_want = 6;
    hid_rig_run_until(g, reports_at_least, &srv, "the effect starts");
    assert_int_equal(f->feature[2], 1);
    assert_int_equal(rid(3), 1);
    assert_int_equal(rid(4), 5);
    assert_int_equal(rid(5), 10);
    for (int k = 3; k < 6; k++) assert_int_equal(blk(k), 3);
    assert_int_equal(f->data[5][2], 1); /* Op Effect Start */
    uint8_t first_cf[4];
    memcpy(first_cf, f->data[4], 4);
    /* two quick updates under a 1 Hz limit: the latest force arrives (now or at the end of
     * the interval); a larger tip, same direction -> a larger magnitude, last report */
    update(&srv, 0.3, 0.15);
    update(&srv, 0.4, 0.2);
    hid_rig_run_until(g, settled, &srv, "the latest force sent");
    int last = f->n - 1;
    assert_int_equal(rid(last), 5);
    assert_int_equal(blk(last), 3);
    int16_t m0 = (int16_t)(first_cf[2] | first_cf[3] << 8);
    int16_t m1 = (int16_t)(f->data[last][2] | f->data[last][3] << 8);
    assert_true(m1 > m0 && m0 > 0);
    assert_true(m1 == 255 || abs(m1 - 4 * m0) <= 2); /* 4x the tip: 4x (both rounded) */

    /* a read error mid-stroke: the device closes as ERROR, its effect stopped and freed */
    int before = f->n;
    pthread_mutex_lock(&f->mu);
    f->fail = DF_EIO;
    pthread_cond_broadcast(&f->cv);
    pthread_mutex_unlock(&f->mu);
    hid_rig_run_until(g, dev_error, &srv, "device closed on error");
    assert_int_equal(f->n, before + 2);
    assert_int_equal(rid(before), 10);
    assert_int_equal(blk(before), 3);
    assert_int_equal(f->data[before][2], 3); /* Op Effect Stop */
    assert_int_equal(rid(before + 1), 11);   /* Block Free */
    assert_int_equal(blk(before + 1), 3);
    end(&srv);
    hid_rig_run_until(g, no_stroke, &srv, "stroke ended");
    assert_int_equal(f->n, before + 2);      /* nothing after the close */

    df_hid_manager_stop(&srv);
    uv_run(&g->loop, UV_RUN_NOWAIT); /* the closed rate-limit timer's close completes */
    df_session_close(g_s);
    df_job_pump(g_s);
    df_hid_manager_free(&srv);
    hid_rig_finish(g, &srv);
    pthread_mutex_destroy(&f->mu);
    pthread_cond_destroy(&f->cv);
    free(f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_block_load_refusal_rate_limit_and_error),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
