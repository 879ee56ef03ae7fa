/* Unit test of the HID latency bench's recordings (tests/bench/hid_bench_rec.py, issue 11 Bench):
 * the generator writes them into a fresh temporary folder; each must parse with
 * server/hid/hid_recording.c, carry the shared file's real descriptor and ids (read here from the
 * shared file with the same parser, not from the generator), and every report must decode with
 * the descriptor (server/hid/hid_desc.c) to the length the descriptor gives and to the usage
 * values of the generator's manifest (<file>.expect: `<time_us> <len> <page>:<usage>=<value>...`
 * per E: line). The generator runs under $PYTHON (default /usr/bin/python3) from the repository
 * root, where the unit suite runs. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <cmocka.h>

#include "server/hid/hid_desc.h"
#include "server/hid/hid_recording.h"
#include "tests/unit/unit_skip.h"
#include "tests/unit/hid/hid_files.h"

#define GENERATOR "tests/bench/hid_bench_rec.py"

static char g_dir[1024];     /* the temporary folder of this run */
static char g_hid[1024];     /* the shared HID folder */

static int setup(void **state)
{
    (void)state;
    g_dir[0] = '\0';
    return 0;
}

/* Runs the generator into a new temporary folder (g_dir). */
static void generate(void)
{
    if (access(GENERATOR, R_OK) != 0)
        unit_skip("%s not found (run from the repository root)", GENERATOR);
    const char *tmp = getenv("TMPDIR");
    snprintf(g_dir, sizeof g_dir, "%s/df-hid-bench-XXXXXX", tmp && *tmp ? tmp : "/tmp");
    assert_non_null(mkdtemp(g_dir));
    const char *py = getenv("PYTHON");
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "HID_DIR='%s' '%s' %s '%s' >/dev/null", g_hid,
             py && *py ? py : "/usr/bin/python3", GENERATOR, g_dir);
    int rc = system(cmd);
    if (rc != 0) fail_msg("'%s' exited with %d", cmd, rc);
}

static int teardown(void **state)
{
    (void)state;
    if (!g_dir[0]) return 0;
    static const char *const names[] = {"knob.hid", "knob.hid.expect", "mouse3d.hid",
                                        "mouse3d.hid.expect"};
    char p[1200];
    for (size_t i = 0; i < sizeof names / sizeof *names; i++) {
        snprintf(p, sizeof p, "%s/%s", g_dir, names[i]);
        unlink(p);
    }
    rmdir(g_dir);
    g_dir[0] = '\0';
    return 0;
}

static df_hid_recording parse_file(const char *dir, const char *name)
{
    size_t n = 0;
    char *text = hid_read_file(dir, name, &n);
    if (!text) fail_msg("cannot read %s/%s", dir, name);
    df_hid_recording rec;
    df_error e;
    if (df_hid_recording_parse(text, n, &rec, &e) != DF_OK) fail_msg("%s: %s", name, e.msg);
    free(text);
    return rec;
}

/* Value of the input element with usage page:usage in report `rid`; fails when absent. */
static int64_t usage_value(const df_hid_desc *d, const uint8_t *buf, size_t n, unsigned rid,
                           unsigned page, unsigned usage)
{
    const df_hid_report *r = df_hid_desc_report(d, DF_HID_INPUT, rid);
    assert_non_null(r);
    uint32_t u = (uint32_t)page << 16 | usage;
    for (size_t i = r->first_field; i < r->first_field + r->n_fields; i++) {
        const df_hid_field *f = &d->fields[i];
        if (!(f->flags & DF_HID_F_VARIABLE) || u < f->usage_min || u > f->usage_max) continue;
        unsigned idx = f->usage_min < f->usage_max ? u - f->usage_min : 0;
        if (idx >= f->count) continue;
        int64_t v;
        df_error e;
        if (df_hid_field_value(f, buf, n, idx, &v, &e) != DF_OK) fail_msg("%s", e.msg);
        return v;
    }
    fail_msg("report %u has no usage %x:%x", rid, page, usage);
    return 0;
}

/* Checks generated file `name` against shared file `source` (node 0) and its manifest. Returns
 * the number of reports. */
static size_t check(const char *name, const char *source, uint32_t vid, uint32_t pid)
{
    df_hid_recording rec = parse_file(g_dir, name), src = parse_file(g_hid, source);
    assert_int_equal(rec.n_devices, 1);
    const df_hid_rec_device *dv = &rec.devices[0], *sv = &src.devices[0];
    assert_int_equal(dv->desc_len, sv->desc_len);
    assert_memory_equal(dv->desc, sv->desc, sv->desc_len);
    assert_string_equal(dv->name, sv->name);
    assert_int_equal(dv->bus, sv->bus);
    assert_int_equal(dv->vid, vid);
    assert_int_equal(dv->pid, pid);
    df_hid_desc d;
    df_error e;
    if (df_hid_desc_parse(dv->desc, dv->desc_len, &d, &e) != DF_OK) fail_msg("%s", e.msg);

    char mname[256];
    snprintf(mname, sizeof mname, "%s.expect", name);
    size_t mn = 0;
    char *raw = hid_read_file(g_dir, mname, &mn), *man = malloc(mn + 1);
    assert_non_null(raw);
    assert_non_null(man);
    memcpy(man, raw, mn);
    man[mn] = '\0';
    free(raw);
    char *save = NULL, *line = strtok_r(man, "\n", &save);
    size_t k = 0;
    for (; line; line = strtok_r(NULL, "\n", &save), k++) {
        assert_true(k < rec.n_events);
        const df_hid_rec_event *ev = &rec.events[k];
        const uint8_t *b = df_hid_rec_event_bytes(&rec, ev);
        unsigned long long t;
        size_t len;
        int used = 0;
        assert_int_equal(sscanf(line, "%llu %zu%n", &t, &len, &used), 2);
        assert_int_equal(ev->time_us, t);
        assert_int_equal(ev->len, len);
        if (k) assert_true(ev->time_us >= rec.events[k - 1].time_us);
        const df_hid_report *r;
        if (df_hid_report_decode(&d, b, ev->len, &r, &e) != DF_OK)
            fail_msg("report %zu: %s", k, e.msg);
        assert_int_equal(r->bytes, ev->len);
        unsigned page, usage;
        long long want;
        int m = 0;
        for (const char *p = line + used; sscanf(p, " %x:%x=%lld%n", &page, &usage, &want, &m) == 3;
             p += m)
            assert_int_equal(usage_value(&d, b, ev->len, r->id, page, usage), want);
    }
    assert_int_equal(k, rec.n_events);
    free(man);
    df_hid_desc_free(&d);
    df_hid_recording_free(&rec);
    df_hid_recording_free(&src);
    return k;
}

static void test_bench_recordings(void **state)
{
    (void)state;
    unit_hid_dir_or_skip(g_hid, sizeof g_hid);
    generate();
    size_t knob = check("knob.hid", "microsoft-surface-dial_045e-091b_bt.hid", 0x045e, 0x091b);
    size_t m3d = check("mouse3d.hid", "3dconnexion-spacenavigator_046d-c626_usb.hid", 0x046d,
                       0xc626);
    assert_true(knob > 0 && m3d > 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_bench_recordings, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
