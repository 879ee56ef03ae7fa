/* Unit tests for the timing of server/hid/hid_replay.c, on a fake clock (df_hid_replay_opts
 * now_us/sleep_us: sleeping advances it, nothing waits for real): each report is delivered exactly
 * at open (df_hid_replay_start_us) + recorded time / speed, reads time out after their timeout in
 * between, a zero timeout polls without sleeping, the end of the file unplugs at its last
 * recorded time, LOOP and HOLD; and one reader thread against one writer thread. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "server/hid/hid_source.h"
#include "tests/unit/unit_skip.h"
#include "tests/unit/hid/hid_files.h"
#include "tests/unit/hid/hid_expect.h"

#define PM_FILE "griffin-powermate_077d-0410_usb.raw.txt"
#define K20_FILE "huion-keydial-k20_256c-0069_usb_firmware-mode.hid"
#define NTRIG_FILE "ntrig-duosense-pen_1b96-1000_usb.hid"

typedef struct fake_clock {
    uint64_t now, n_sleeps;
} fake_clock;

static uint64_t fake_now(void *ctx) { return ((fake_clock *)ctx)->now; }

static void fake_sleep(void *ctx, uint64_t us)
{
    fake_clock *c = ctx;
    c->now += us;
    c->n_sleeps++;
}

static void load(const char *dir, const char *name, ex_file *f, char *path, size_t cap)
{
    snprintf(path, cap, "%s/%s", dir, name);
    size_t n = 0;
    char *text = hid_read_file(dir, name, &n);
    assert_non_null(text);
    text = realloc(text, n + 1);
    text[n] = 0;
    assert_int_equal(ex_parse(text, f), 0);
    free(text);
}

static df_hid_backend *make(const char *path, fake_clock *c, double speed, int at_end)
{
    df_hid_replay_opts o = { .speed = speed, .at_end = at_end, .now_us = fake_now,
                             .sleep_us = fake_sleep, .clock_ctx = c };
    df_hid_backend *b = NULL;
    df_error e;
    const char *files[] = { path };
    if (df_hid_backend_replay(files, 1, &o, &b, &e) != DF_OK) fail_msg("%s", e.msg);
    return b;
}

static df_hid_dev *open_node(df_hid_backend *b, const char *path, unsigned node)
{
    char p[1400];
    snprintf(p, sizeof p, "replay:%s#%u", path, node);
    df_hid_dev *d = NULL;
    df_error e;
    if (b->open(b, p, &d, &e) != DF_OK) fail_msg("%s", e.msg);
    return d;
}

/* Reads until a report or an error with timeout T (ms); counts the timeouts. */
static int read_until(df_hid_backend *b, df_hid_dev *d, uint8_t *buf, size_t cap, int T,
                      uint64_t *t, uint64_t *timeouts)
{
    int r;
    *timeouts = 0;
    while ((r = b->read(d, buf, cap, T, t, NULL)) == 0) ++*timeouts;
    return r;
}

/* Every report of node `node` arrives at t0 + time / speed; in between, reads with timeout T ms
 * return 0 exactly ceil(gap / T) - 1 times. The node unplugs at the file's last recorded time. */
static void check_timing(const char *dir, const char *name, unsigned node, double speed, int T)
{
    ex_file f;
    char path[1280];
    load(dir, name, &f, path, sizeof path);
    fake_clock c = { .now = 5000000 };
    df_hid_backend *b = make(path, &c, speed, DF_HID_REPLAY_END_UNPLUG);
    df_hid_dev *d = open_node(b, path, node);
    const uint64_t t0 = c.now, Tus = (uint64_t)T * 1000;
    uint64_t start = 0;
    assert_int_equal(df_hid_replay_start_us(b, d, &start, NULL), DF_OK);
    assert_int_equal(start, t0);
    assert_int_equal(df_hid_replay_start_us(b, NULL, &start, NULL), DF_EINVAL);
    assert_int_equal(df_hid_replay_start_us(NULL, d, &start, NULL), DF_EINVAL);
    uint8_t buf[DF_HID_READ_MAX];
    uint64_t t, timeouts, prev = t0;
    size_t seen = 0;
    for (size_t i = 0; i < f.n_ev; i++) {
        const ex_event *x = &f.ev[i];
        if (x->node != node || x->len == 0) continue;
        uint64_t due = t0 + (uint64_t)((double)x->time_us / speed);
        int r = read_until(b, d, buf, sizeof buf, T, &t, &timeouts);
        assert_int_equal(r, (int)x->len);
        assert_memory_equal(buf, f.bytes + x->off, x->len);
        assert_int_equal(t, x->time_us);
        assert_int_equal(c.now, due > prev ? due : prev);
        uint64_t gap = due > prev ? due - prev : 0;
        assert_int_equal(timeouts, gap ? (gap - 1) / Tus : 0);
        prev = c.now;
        seen++;
    }
    assert_true(seen > 0);
    assert_int_equal(df_hid_replay_start_us(b, d, &start, NULL), DF_OK);
    assert_int_equal(start, t0); /* constant while open */
    /* the end: unplug at the file's last recorded time (silent nodes too) */
    int r = read_until(b, d, buf, sizeof buf, T, &t, &timeouts);
    assert_int_equal(r, DF_ENOTFOUND);
    uint64_t end = t0 + (uint64_t)((double)f.end_us / speed);
    assert_int_equal(c.now, end > prev ? end : prev);
    b->close(d);
    df_hid_backend_destroy(b);
    ex_free(&f);
}

static void test_real_time(void **state)
{
    (void)state;
    char dir[1024];
    unit_hid_dir_or_skip(dir, sizeof dir);
    check_timing(dir, PM_FILE, 0, 1.0, 10);
    check_timing(dir, K20_FILE, 2, 1.0, 7);
    check_timing(dir, NTRIG_FILE, 0, 1.0, 3);
}

static void test_speed(void **state)
{
    (void)state;
    char dir[1024];
    unit_hid_dir_or_skip(dir, sizeof dir);
    check_timing(dir, PM_FILE, 0, 4.0, 10);
    check_timing(dir, PM_FILE, 0, 0.5, 100);
}

/* A silent node (K20 firmware mode: the vendor node D:0 sends nothing) unplugs with its file. */
static void test_silent_node(void **state)
{
    (void)state;
    char dir[1024], path[1280];
    unit_hid_dir_or_skip(dir, sizeof dir);
    ex_file f;
    load(dir, K20_FILE, &f, path, sizeof path);
    assert_int_equal(f.nodes[0].n_e, 0);
    fake_clock c = { .now = 0 };
    df_hid_backend *b = make(path, &c, 1.0, DF_HID_REPLAY_END_UNPLUG);
    df_hid_dev *d = open_node(b, path, 0);
    uint8_t buf[64];
    uint64_t t, timeouts;
    assert_int_equal(read_until(b, d, buf, sizeof buf, 50, &t, &timeouts), DF_ENOTFOUND);
    assert_int_equal(c.now, f.end_us);
    b->close(d);
    df_hid_backend_destroy(b);
    ex_free(&f);
}

/* Timeout 0 polls: returns 0 at once without sleeping while the next report is not due. */
static void test_poll(void **state)
{
    (void)state;
    char dir[1024], path[1280];
    unit_hid_dir_or_skip(dir, sizeof dir);
    ex_file f;
    load(dir, PM_FILE, &f, path, sizeof path);
    fake_clock c = { .now = 100 };
    df_hid_backend *b = make(path, &c, 1.0, DF_HID_REPLAY_END_UNPLUG);
    df_hid_dev *d = open_node(b, path, 0);
    uint8_t buf[64];
    uint64_t t;
    const ex_event *e0 = &f.ev[0], *e1 = &f.ev[1];
    assert_true(e1->time_us > e0->time_us);
    c.now += e0->time_us; /* the first report is due now */
    assert_int_equal(b->read(d, buf, sizeof buf, 0, &t, NULL), (int)e0->len);
    uint64_t sleeps = c.n_sleeps;
    assert_int_equal(b->read(d, buf, sizeof buf, 0, &t, NULL), 0);
    assert_int_equal(b->read(d, buf, sizeof buf, 0, &t, NULL), 0);
    assert_int_equal(c.n_sleeps, sleeps);
    c.now = 100 + e1->time_us; /* the clock moves on by itself */
    assert_int_equal(b->read(d, buf, sizeof buf, 0, &t, NULL), (int)e1->len);
    assert_int_equal(t, e1->time_us);
    assert_int_equal(c.n_sleeps, sleeps);
    b->close(d);
    df_hid_backend_destroy(b);
    ex_free(&f);
}

static void test_loop_and_hold(void **state)
{
    (void)state;
    char dir[1024], path[1280];
    unit_hid_dir_or_skip(dir, sizeof dir);
    ex_file f;
    load(dir, PM_FILE, &f, path, sizeof path);
    fake_clock c = { .now = 0 };
    df_hid_backend *b = make(path, &c, 1.0, DF_HID_REPLAY_END_LOOP);
    df_hid_dev *d = open_node(b, path, 0);
    uint8_t buf[64];
    uint64_t t, timeouts;
    /* three passes: pass k delivers report i at time_i + k * (end + 10 ms), never unplugs */
    for (uint64_t k = 0; k < 3; k++)
        for (size_t i = 0; i < f.n_ev; i++) {
            assert_int_equal(read_until(b, d, buf, sizeof buf, 20, &t, &timeouts), (int)f.ev[i].len);
            assert_memory_equal(buf, f.bytes + f.ev[i].off, f.ev[i].len);
            assert_int_equal(t, f.ev[i].time_us + k * (f.end_us + 10000));
            assert_int_equal(c.now, t);
        }
    b->close(d);
    df_hid_backend_destroy(b);

    c = (fake_clock){ .now = 0 };
    b = make(path, &c, 1.0, DF_HID_REPLAY_END_HOLD);
    d = open_node(b, path, 0);
    for (size_t i = 0; i < f.n_ev; i++)
        assert_int_equal(read_until(b, d, buf, sizeof buf, 20, &t, &timeouts), (int)f.ev[i].len);
    for (int i = 0; i < 3; i++) { /* held open: every read times out after its timeout */
        uint64_t before = c.now;
        assert_int_equal(b->read(d, buf, sizeof buf, 20, &t, NULL), 0);
        assert_int_equal(c.now, before + 20000);
    }
    df_hid_devinfo *list;
    size_t n;
    assert_int_equal(b->enumerate(b, &list, &n, NULL), DF_OK);
    assert_int_equal(n, 1); /* still present */
    df_hid_devinfo_free_list(list, n);
    b->close(d);
    df_hid_backend_destroy(b);
    ex_free(&f);
}

typedef struct rw_ctx {
    df_hid_backend *b;
    df_hid_dev *d;
    size_t n_read;
    int end_rc;
} rw_ctx;

static void *reader(void *arg)
{
    rw_ctx *x = arg;
    uint8_t buf[DF_HID_READ_MAX];
    uint64_t t;
    int r;
    while ((r = x->b->read(x->d, buf, sizeof buf, 10, &t, NULL)) >= 0) x->n_read += r > 0;
    x->end_rc = r;
    return NULL;
}

/* One reader thread and one writer (this thread) on one device: every write before the unplug is
 * captured once, in order, with a replay time that never goes back. */
static void test_reader_and_writer(void **state)
{
    (void)state;
    char dir[1024], path[1280];
    unit_hid_dir_or_skip(dir, sizeof dir);
    ex_file f;
    load(dir, NTRIG_FILE, &f, path, sizeof path);
    const char *files[] = { path };
    df_hid_replay_opts o = { .no_wait = 1 };
    df_hid_backend *b = NULL;
    assert_int_equal(df_hid_backend_replay(files, 1, &o, &b, NULL), DF_OK);
    rw_ctx x = { .b = b, .d = open_node(b, path, 0) };
    pthread_t th;
    assert_int_equal(pthread_create(&th, NULL, reader, &x), 0);
    size_t written = 0;
    for (uint32_t i = 0; i < 20000; i++) {
        uint8_t rep[5] = { 0x05, (uint8_t)i, (uint8_t)(i >> 8), (uint8_t)(i >> 16), 0 };
        int r = b->write_output(x.d, rep, sizeof rep, NULL);
        if (r == DF_ENOTFOUND) break;
        assert_int_equal(r, DF_OK);
        written++;
    }
    pthread_join(th, NULL);
    assert_int_equal(x.end_rc, DF_ENOTFOUND);
    size_t want = 0;
    for (size_t i = 0; i < f.n_ev; i++) want += f.ev[i].node == 0 && f.ev[i].len > 0;
    assert_int_equal(x.n_read, want);
    df_hid_replay_output *out;
    size_t n;
    assert_int_equal(df_hid_replay_outputs(b, 0, &out, &n, NULL), DF_OK);
    assert_int_equal(n, written);
    for (size_t i = 0; i < n; i++) {
        uint32_t v = out[i].data[1] | (uint32_t)out[i].data[2] << 8 | (uint32_t)out[i].data[3] << 16;
        assert_int_equal(v, i);
        assert_int_equal(out[i].seq, i);
        assert_true(out[i].time_us <= f.end_us);
        if (i) assert_true(out[i].time_us >= out[i - 1].time_us);
    }
    df_hid_replay_outputs_free(out, n);
    b->close(x.d);
    df_hid_backend_destroy(b);
    ex_free(&f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_real_time),
        cmocka_unit_test(test_speed),
        cmocka_unit_test(test_silent_node),
        cmocka_unit_test(test_poll),
        cmocka_unit_test(test_loop_and_hold),
        cmocka_unit_test(test_reader_and_writer),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
