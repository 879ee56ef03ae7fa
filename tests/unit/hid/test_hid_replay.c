/* Unit tests for server/hid/hid_replay.c (through the seam, hid_source.h): every file of the shared
 * HID folder replayed at once (no waiting): the devices, their descriptors, every report's bytes
 * and recorded time in file order, the unplug at the end; captured output reports and control
 * transfers; refusals of bad files, options and calls. Expected values come from hid_expect.h,
 * a reader of the files written apart from the parser the backend uses. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <cmocka.h>

#include "server/hid/hid_source.h"
#include "tests/unit/unit_skip.h"
#include "tests/unit/hid/hid_files.h"
#include "tests/unit/hid/hid_expect.h"

#define MAX_FILES 64
#define PM_FILE "griffin-powermate_077d-0410_usb.raw.txt"
#define DIAL_FILE "microsoft-surface-dial_045e-091b_bt.hid"

static int cmp_str(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

static int ends_with(const char *s, const char *suf)
{
    size_t n = strlen(s), k = strlen(suf);
    return n >= k && strcmp(s + n - k, suf) == 0;
}

/* The .hid and .raw.txt files of the shared folder, sorted, as dir/name (malloc'd). */
static size_t list_files(const char *dir, char **out)
{
    DIR *d = opendir(dir);
    assert_non_null(d);
    size_t n = 0;
    for (struct dirent *e; (e = readdir(d));) {
        if (!ends_with(e->d_name, ".hid") && !ends_with(e->d_name, ".raw.txt")) continue;
        assert_true(n < MAX_FILES);
        out[n] = malloc(strlen(dir) + strlen(e->d_name) + 2);
        sprintf(out[n++], "%s/%s", dir, e->d_name);
    }
    closedir(d);
    qsort(out, n, sizeof *out, cmp_str);
    return n;
}

static void load_expect(const char *path, ex_file *f)
{
    const char *slash = strrchr(path, '/');
    char dir[1024];
    snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
    size_t n = 0;
    char *text = hid_read_file(dir, slash + 1, &n);
    assert_non_null(text);
    text = realloc(text, n + 1);
    text[n] = 0;
    if (ex_parse(text, f) != 0) fail_msg("test reader cannot parse %s", path);
    free(text);
}

static void check_info(const df_hid_devinfo *in, const char *path, const ex_file *f, unsigned d)
{
    char want[DF_HID_PATH_MAX];
    snprintf(want, sizeof want, "replay:%s#%u", path, d);
    assert_string_equal(in->path, want);
    assert_int_equal(in->backend, DF_HID_BACKEND_REPLAY);
    const ex_node *nd = &f->nodes[d];
    if (f->any_r) {
        assert_int_equal(in->raw_powermate, 0);
        assert_int_equal(in->vid, nd->vid);
        assert_int_equal(in->pid, nd->pid);
        assert_int_equal(in->bus, nd->bus);
        assert_string_equal(in->name, nd->name);
        assert_int_equal(in->desc_len, nd->r_len);
        assert_non_null(in->desc);
        assert_memory_equal(in->desc, nd->r, nd->r_len);
    } else {
        assert_int_equal(in->raw_powermate, 1);
        assert_int_equal(in->vid, nd->vid ? nd->vid : DF_HID_POWERMATE_VID);
        assert_int_equal(in->pid, nd->pid ? nd->pid : DF_HID_POWERMATE_PID);
        assert_int_equal(in->bus, nd->bus ? nd->bus : DF_HID_BUS_USB);
        assert_string_equal(in->name, nd->name[0] ? nd->name : "Griffin PowerMate");
        assert_null(in->desc);
        assert_int_equal(in->desc_len, 0);
    }
}

/* Reads every report of node d of f from the open device and checks bytes, times, the unplug. */
static size_t check_reports(df_hid_backend *b, df_hid_dev *dev, const ex_file *f, unsigned d)
{
    static uint8_t buf[DF_HID_READ_MAX];
    size_t got = 0;
    df_error e;
    for (size_t i = 0; i < f->n_ev; i++) {
        const ex_event *x = &f->ev[i];
        if (x->node != d || x->len == 0) continue;
        uint64_t t = 0;
        int r = b->read(dev, buf, sizeof buf, 1000, &t, &e);
        if (r <= 0) fail_msg("event %zu of node %u: read %d: %s", i, d, r, e.msg);
        assert_int_equal((size_t)r, x->len);
        assert_memory_equal(buf, f->bytes + x->off, x->len);
        assert_int_equal(t, x->time_us);
        got++;
    }
    uint64_t t = 0;
    assert_int_equal(b->read(dev, buf, sizeof buf, 1000, &t, &e), DF_ENOTFOUND);
    assert_non_null(strstr(e.msg, "unplugged"));
    assert_int_equal(b->read(dev, buf, sizeof buf, 0, &t, &e), DF_ENOTFOUND);
    return got;
}

static void test_every_shared_file(void **state)
{
    (void)state;
    char dir[1024];
    unit_hid_dir_or_skip(dir, sizeof dir);
    char *files[MAX_FILES];
    size_t nf = list_files(dir, files);
    int have_raw = 0;
    for (size_t i = 0; i < nf; i++) have_raw |= ends_with(files[i], PM_FILE);
    assert_true(nf > 1 && have_raw); /* the folder as its README lists it */
    static ex_file ex[MAX_FILES];
    size_t want_dev = 0, want_ev = 0;
    for (size_t i = 0; i < nf; i++) {
        load_expect(files[i], &ex[i]);
        for (unsigned d = 0; d < ex[i].n_nodes; d++) {
            if (!ex_is_device(&ex[i], d)) continue;
            want_dev++;
            for (size_t k = 0; k < ex[i].n_ev; k++)
                want_ev += ex[i].ev[k].node == d && ex[i].ev[k].len > 0;
        }
    }
    df_hid_backend *b = NULL;
    df_error e;
    df_hid_replay_opts o = { .no_wait = 1 };
    if (df_hid_backend_replay((const char *const *)files, nf, &o, &b, &e) != DF_OK)
        fail_msg("%s", e.msg);
    assert_int_equal(b->kind, DF_HID_BACKEND_REPLAY);
    assert_string_equal(b->name, "replay");
    assert_null(b->watch);
    df_hid_devinfo *list = NULL;
    size_t n = 0;
    assert_int_equal(b->enumerate(b, &list, &n, &e), DF_OK);
    assert_int_equal(n, want_dev);
    size_t k = 0, got_ev = 0;
    for (size_t i = 0; i < nf; i++)
        for (unsigned d = 0; d < ex[i].n_nodes; d++) {
            if (!ex_is_device(&ex[i], d)) continue;
            check_info(&list[k], files[i], &ex[i], d);
            df_hid_dev *dev = NULL;
            if (b->open(b, list[k].path, &dev, &e) != DF_OK) fail_msg("%s", e.msg);
            got_ev += check_reports(b, dev, &ex[i], d);
            b->close(dev);
            /* unplugged: no longer listed, cannot be opened again */
            assert_int_equal(b->open(b, list[k].path, &dev, &e), DF_ENOTFOUND);
            assert_non_null(strstr(e.msg, list[k].path));
            k++;
        }
    assert_int_equal(got_ev, want_ev);
    df_hid_devinfo_free_list(list, n);
    assert_int_equal(b->enumerate(b, &list, &n, &e), DF_OK);
    assert_int_equal(n, 0);
    assert_null(list);
    df_hid_backend_destroy(b);
    for (size_t i = 0; i < nf; i++) { ex_free(&ex[i]); free(files[i]); }
}

/* Index of the i-th (0-based) report of node d in f. */
static const ex_event *nth(const ex_file *f, unsigned d, size_t i)
{
    for (size_t k = 0; k < f->n_ev; k++)
        if (f->ev[k].node == d && f->ev[k].len > 0 && i-- == 0) return &f->ev[k];
    fail_msg("node %u has fewer reports", d);
    return NULL;
}

static void read_n(df_hid_backend *b, df_hid_dev *dev, int n)
{
    uint8_t buf[DF_HID_READ_MAX];
    uint64_t t;
    for (int i = 0; i < n; i++) assert_true(b->read(dev, buf, sizeof buf, 1000, &t, NULL) > 0);
}

static void test_outputs_captured(void **state)
{
    (void)state;
    char dir[1024], dial[1280], pm[1280];
    unit_hid_dir_or_skip(dir, sizeof dir);
    snprintf(dial, sizeof dial, "%s/%s", dir, DIAL_FILE);
    snprintf(pm, sizeof pm, "%s/%s", dir, PM_FILE);
    ex_file xd, xp;
    load_expect(dial, &xd);
    load_expect(pm, &xp);
    const char *files[] = { dial, pm };
    df_hid_backend *b = NULL;
    df_error e;
    df_hid_replay_opts o = { .no_wait = 1 };
    assert_int_equal(df_hid_backend_replay(files, 2, &o, &b, &e), DF_OK);
    char pd[1400], pp[1400];
    snprintf(pd, sizeof pd, "replay:%s#0", dial);
    snprintf(pp, sizeof pp, "replay:%s#0", pm);
    df_hid_dev *d = NULL, *p = NULL;
    assert_int_equal(b->open(b, pd, &d, &e), DF_OK);
    assert_int_equal(b->open(b, pp, &p, &e), DF_OK);
    assert_int_equal(b->open(b, pd, &d, &e), DF_EIO); /* already open */
    assert_non_null(strstr(e.msg, "already open"));

    static const uint8_t haptic[] = { 0x01, 0x00, 0x05, 0x50, 0x00 }; /* README's example */
    static const uint8_t led[] = { 0x04, 0x01 };
    assert_int_equal(b->write_output(d, haptic, sizeof haptic, &e), DF_OK); /* before any read */
    read_n(b, d, 2);
    assert_int_equal(b->write_output(d, led, sizeof led, &e), DF_OK);
    assert_int_equal(b->control(d, 0x41, 1, 1, 7, &e), DF_EUNSUPPORTED);
    read_n(b, p, 3);
    assert_int_equal(b->control(p, DF_HID_POWERMATE_LED_REQTYPE, DF_HID_POWERMATE_LED_REQUEST,
                                DF_HID_POWERMATE_LED_STATIC, 200, &e), DF_OK);
    assert_int_equal(b->write_output(p, led, sizeof led, &e), DF_EUNSUPPORTED);
    assert_int_equal(b->write_output(d, led, 0, &e), DF_EINVAL);
    assert_int_equal(b->write_output(d, NULL, 2, &e), DF_EINVAL);

    df_hid_replay_output *out = NULL;
    size_t n = 0;
    assert_int_equal(df_hid_replay_outputs(b, 0, &out, &n, &e), DF_OK);
    assert_int_equal(n, 3);
    for (size_t i = 0; i < n; i++) assert_int_equal(out[i].seq, i);
    assert_string_equal(out[0].path, pd);
    assert_int_equal(out[0].is_control, 0);
    assert_int_equal(out[0].time_us, 0); /* nothing delivered yet */
    assert_int_equal(out[0].len, sizeof haptic);
    assert_memory_equal(out[0].data, haptic, sizeof haptic);
    assert_int_equal(out[1].time_us, nth(&xd, 0, 1)->time_us);
    assert_memory_equal(out[1].data, led, sizeof led);
    assert_string_equal(out[2].path, pp);
    assert_int_equal(out[2].is_control, 1);
    assert_null(out[2].data);
    assert_int_equal(out[2].time_us, nth(&xp, 0, 2)->time_us);
    assert_int_equal(out[2].request_type, 0x41);
    assert_int_equal(out[2].request, 1);
    assert_int_equal(out[2].value, 1);
    assert_int_equal(out[2].index, 200);
    df_hid_replay_outputs_free(out, n);
    assert_int_equal(df_hid_replay_outputs(b, 2, &out, &n, &e), DF_OK); /* from index 2 */
    assert_int_equal(n, 1);
    assert_int_equal(out[0].seq, 2);
    df_hid_replay_outputs_free(out, n);
    assert_int_equal(df_hid_replay_outputs(b, 3, &out, &n, &e), DF_OK);
    assert_int_equal(n, 0);
    assert_null(out);

    /* after the unplug the device takes nothing more */
    uint8_t buf[64];
    uint64_t t;
    int r;
    while ((r = b->read(d, buf, sizeof buf, 1000, &t, &e)) > 0) {}
    assert_int_equal(r, DF_ENOTFOUND);
    assert_int_equal(b->write_output(d, led, sizeof led, &e), DF_ENOTFOUND);
    assert_int_equal(df_hid_replay_outputs(b, 0, &out, &n, &e), DF_OK);
    assert_int_equal(n, 3);
    df_hid_replay_outputs_free(out, n);
    /* truncation to cap */
    assert_int_equal(b->read(p, buf, 2, 1000, &t, &e), 2);
    assert_memory_equal(buf, xp.bytes + nth(&xp, 0, 3)->off, 2);
    b->close(d);
    b->close(p);
    df_hid_backend_destroy(b);
    ex_free(&xd);
    ex_free(&xp);
}

/* Feature reports: sent ones are captured (is_feature), none can be read back (a recording holds
 * no answers); a PowerMate has none; a backend without the entries refuses through the
 * df_hid_*_feature wrappers. With END_HOLD the device stays open after its last report. */
static void test_features_captured(void **state)
{
    (void)state;
    char dir[1024], sw[1280], pm[1280];
    unit_hid_dir_or_skip(dir, sizeof dir);
    snprintf(sw, sizeof sw, "%s/%s", dir, "microsoft-sidewinder-ff2_045e-001b_usb.hid");
    snprintf(pm, sizeof pm, "%s/%s", dir, PM_FILE);
    const char *files[] = { sw, pm };
    df_hid_backend *b = NULL;
    df_error e;
    df_hid_replay_opts o = { .no_wait = 1, .at_end = DF_HID_REPLAY_END_HOLD };
    assert_int_equal(df_hid_backend_replay(files, 2, &o, &b, &e), DF_OK);
    char ps[1400], pp[1400];
    snprintf(ps, sizeof ps, "replay:%s#0", sw);
    snprintf(pp, sizeof pp, "replay:%s#0", pm);
    df_hid_dev *d = NULL, *p = NULL;
    assert_int_equal(b->open(b, ps, &d, &e), DF_OK);
    assert_int_equal(b->open(b, pp, &p, &e), DF_OK);
    uint8_t buf[64];
    uint64_t t;
    int r, reports = 0;
    while ((r = b->read(d, buf, sizeof buf, 0, &t, &e)) > 0) reports++;
    assert_int_equal(r, 0); /* held: silent, not unplugged */
    assert_true(reports > 0);
    static const uint8_t create[] = { 0x01, 0x01, 0x0a, 0x00 }; /* the file's example */
    assert_int_equal(df_hid_send_feature(b, d, create, sizeof create, &e), DF_OK);
    uint8_t get[5] = { 0x02 };
    assert_int_equal(df_hid_get_feature(b, d, get, sizeof get, &e), DF_EUNSUPPORTED);
    assert_non_null(strstr(e.msg, "answers no feature"));
    assert_int_equal(df_hid_send_feature(b, p, create, sizeof create, &e), DF_EUNSUPPORTED);
    assert_int_equal(df_hid_send_feature(b, d, create, 0, &e), DF_EINVAL);
    static const uint8_t start[] = { 0x0a, 0x01, 0x01, 0x01 };
    assert_int_equal(b->write_output(d, start, sizeof start, &e), DF_OK);
    df_hid_replay_output *out = NULL;
    size_t n = 0;
    assert_int_equal(df_hid_replay_outputs(b, 0, &out, &n, &e), DF_OK);
    assert_int_equal(n, 2);
    assert_int_equal(out[0].is_feature, 1);
    assert_int_equal(out[0].is_control, 0);
    assert_int_equal(out[0].len, sizeof create);
    assert_memory_equal(out[0].data, create, sizeof create);
    assert_int_equal(out[1].is_feature, 0);
    assert_memory_equal(out[1].data, start, sizeof start);
    df_hid_replay_outputs_free(out, n);
    df_hid_backend bare;
    memset(&bare, 0, sizeof bare);
    bare.name = "bare";
    assert_int_equal(df_hid_send_feature(&bare, d, create, sizeof create, &e), DF_EUNSUPPORTED);
    assert_int_equal(df_hid_get_feature(&bare, d, get, sizeof get, &e), DF_EUNSUPPORTED);
    assert_int_equal(df_hid_send_feature(b, NULL, create, sizeof create, &e), DF_EINVAL);
    b->close(d);
    b->close(p);
    df_hid_backend_destroy(b);
}

/* A temporary file holding text; its path in out. */
static void temp_file(const char *text, char *out, size_t cap)
{
    const char *tmp = getenv("TMPDIR");
    snprintf(out, cap, "%s/df_hid_replay_XXXXXX", tmp && tmp[0] ? tmp : "/tmp");
    int fd = mkstemp(out);
    assert_true(fd >= 0);
    assert_int_equal(write(fd, text, strlen(text)), (ssize_t)strlen(text));
    close(fd);
}

static void test_refusals(void **state)
{
    (void)state;
    df_hid_backend *b = NULL;
    df_error e;
    const char *missing[] = { "/nonexistent/dir/file.hid" };
    assert_int_equal(df_hid_backend_replay(missing, 1, NULL, &b, &e), DF_EIO);
    assert_non_null(strstr(e.msg, missing[0]));
    assert_null(b);
    assert_int_equal(df_hid_backend_replay(missing, 0, NULL, &b, &e), DF_EINVAL);
    char bad[256], empty[256], good[256];
    temp_file("D: 0\nR: 3 05 01\n", bad, sizeof bad);          /* 2 bytes, 3 declared */
    temp_file("# only a comment\n\n", empty, sizeof empty);
    temp_file("R: 2 a1 01\nI: 3 1 2\nE: 0.000010 1 07\nE: 0.000020 0\n", good, sizeof good);
    const char *f1[] = { good, bad };
    assert_int_equal(df_hid_backend_replay(f1, 2, NULL, &b, &e), DF_EFORMAT);
    assert_non_null(strstr(e.msg, bad));
    assert_non_null(strstr(e.msg, "line 2"));
    const char *f2[] = { empty };
    assert_int_equal(df_hid_backend_replay(f2, 1, NULL, &b, &e), DF_EFORMAT);
    assert_non_null(strstr(e.msg, "no device"));
    const char *f3[] = { good };
    df_hid_replay_opts o = { .speed = -1 };
    assert_int_equal(df_hid_backend_replay(f3, 1, &o, &b, &e), DF_EINVAL);
    o = (df_hid_replay_opts){ .at_end = 7 };
    assert_int_equal(df_hid_backend_replay(f3, 1, &o, &b, &e), DF_EINVAL);
    assert_null(b);

    o = (df_hid_replay_opts){ .no_wait = 1 };
    assert_int_equal(df_hid_backend_replay(f3, 1, &o, &b, &e), DF_OK);
    df_hid_dev *d = NULL;
    assert_int_equal(b->open(b, "/dev/hidraw0", &d, &e), DF_EINVAL);
    assert_int_equal(b->open(b, "replay:/no/such#0", &d, &e), DF_ENOTFOUND);
    assert_null(d);
    char path[300];
    snprintf(path, sizeof path, "replay:%s#0", good);
    assert_int_equal(b->open(b, path, &d, &e), DF_OK);
    uint8_t buf[8];
    uint64_t t = 0;
    assert_int_equal(b->read(d, buf, 0, 10, &t, &e), DF_EINVAL);
    assert_int_equal(b->read(d, NULL, 8, 10, &t, &e), DF_EINVAL);
    assert_int_equal(b->read(d, buf, 8, -1, &t, &e), DF_EINVAL);
    /* the zero-length report is skipped, the device then unplugs */
    assert_int_equal(b->read(d, buf, 8, 10, &t, &e), 1);
    assert_int_equal(buf[0], 0x07);
    assert_int_equal(t, 10);
    assert_int_equal(b->read(d, buf, 8, 10, &t, &e), DF_ENOTFOUND);
    b->close(d);
    df_hid_replay_output *out;
    size_t n;
    assert_int_equal(df_hid_replay_outputs(NULL, 0, &out, &n, &e), DF_EINVAL);
    df_hid_backend_destroy(b);
    df_hid_backend_destroy(NULL);
    unlink(bad);
    unlink(empty);
    unlink(good);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_shared_file),
        cmocka_unit_test(test_outputs_captured),
        cmocka_unit_test(test_features_captured),
        cmocka_unit_test(test_refusals),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
