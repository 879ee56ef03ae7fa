/* Unit tests for server/hid/hid_mapper.c (issue 11): robustness of the dispatch on real data.
 * Every event of every shared file (all nodes) goes through the mapper of every classified node
 * of every file, whole and cut at every length: a feed either succeeds with at most
 * DF_HID_MAX_ACTIONS actions or refuses with DF_EFORMAT and leaves the state as it was. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <dirent.h>
#include <cmocka.h>

#include "server/hid/hid_mapper.h"
#include "tests/unit/hid/hid_replay.h"

#define MAX_FILES 32

static size_t list_files(char names[][256], size_t cap)
{
    char dir[1024];
    unit_hid_dir_or_skip(dir, sizeof dir);
    DIR *dh = opendir(dir);
    assert_non_null(dh);
    size_t n = 0;
    struct dirent *ent;
    while ((ent = readdir(dh)) && n < cap) {
        size_t l = strlen(ent->d_name);
        if (l < 5 || strcmp(ent->d_name + l - 4, ".hid") != 0 || l >= 256) continue;
        memcpy(names[n++], ent->d_name, l + 1);
    }
    closedir(dh);
    return n;
}

static void feed_all(df_hid_mapper *m, const df_hid_recording *src, size_t *ok, size_t *refused)
{
    df_hid_brush b = {DF_HID_BRUSH_GRAB, 1, 0.25, 0.45, 1.0};
    df_hid_action act[DF_HID_MAX_ACTIONS];
    for (size_t i = 0; i < src->n_events; i++) {
        const df_hid_rec_event *ev = &src->events[i];
        const uint8_t *bytes = df_hid_rec_event_bytes(src, ev);
        size_t lens[2] = {ev->len, ev->len / 2}; /* whole, and cut short */
        for (int c = 0; c < 2; c++) {
            df_hid_mapper before = *m;
            size_t n = 99;
            df_error e;
            int rc = df_hid_mapper_feed(m, bytes, lens[c], ev->time_us, &b, act,
                                        DF_HID_MAX_ACTIONS, &n, &e);
            if (rc == DF_OK) {
                assert_true(n <= DF_HID_MAX_ACTIONS);
                for (size_t k = 0; k < n; k++) replay_apply(&b, &act[k]);
                (*ok)++;
            } else {
                if (rc != DF_EFORMAT) fail_msg("event %zu: rc %d: %s", i, rc, e.msg);
                assert_int_equal(n, 0);
                assert_memory_equal(m, &before, sizeof *m);
                (*refused)++;
            }
        }
    }
    size_t n = 0;
    assert_int_equal(df_hid_mapper_unplug(m, act, DF_HID_MAX_ACTIONS, &n, NULL), DF_OK);
    assert_true(n <= 2);
}

static void test_cross_feed(void **state)
{
    (void)state;
    static char names[MAX_FILES][256];
    size_t nf = list_files(names, MAX_FILES);
    assert_true(nf > 0);
    replay *files = calloc(nf, sizeof *files);
    assert_non_null(files);
    for (size_t i = 0; i < nf; i++) replay_load(names[i], &files[i]);
    size_t mappers = 0, ok = 0, refused = 0;
    for (size_t i = 0; i < nf; i++)
        for (size_t k = 0; k < files[i].rec.n_devices; k++) {
            if (files[i].ci[k].cls == DF_HID_CLASS_NONE) continue;
            df_hid_mapper m;
            assert_int_equal(df_hid_mapper_init(&m, &files[i].ci[k], &files[i].desc[k], NULL, NULL),
                             DF_OK);
            mappers++;
            for (size_t j = 0; j < nf; j++) feed_all(&m, &files[j].rec, &ok, &refused);
        }
    assert_int_equal(mappers, 10); /* the classified nodes of test_hid_class.c */
    assert_true(ok > 0 && refused > 0);
    printf("%zu mappers, %zu feeds accepted, %zu refused\n", mappers, ok, refused);
    for (size_t i = 0; i < nf; i++) replay_free(&files[i]);
    free(files);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cross_feed),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
