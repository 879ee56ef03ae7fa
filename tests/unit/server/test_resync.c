/* Unit tests for server/session/resync.c, the per-session ring of recently broadcast versions:
 * versions kept by reference (each frame's count goes up by one, never copied), eviction of the
 * oldest versions, whole, by bytes, lookup and coverage of a resync range, a gap or a version
 * larger than the budget clearing the ring, budget 0 keeping nothing, and every reference
 * released by trim and free (the counts come back to the test's own reference; ASan checks the
 * rest under `make asan`). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "server/session/resync.h"

#define NF 64

/* Frames made by the test: one reference each held here until the end. */
static df_sbuf *frames[NF];

static int setup(void **state)
{
    (void)state;
    for (int i = 0; i < NF; i++) {
        frames[i] = df_sbuf_new((size_t)(100 + 10 * i));
        if (!frames[i]) return -1;
        frames[i]->len = (size_t)(100 + 10 * i);
        memset(frames[i]->data, i, frames[i]->len);
    }
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    for (int i = 0; i < NF; i++) {
        assert_int_equal(atomic_load(&frames[i]->refs), 1); /* nothing left in any ring */
        df_sbuf_unref(frames[i]);
    }
    return 0;
}

static int refs(int i) { return atomic_load(&frames[i]->refs); }

/* Version v (1-based) is made of the frames [2(v-1), 2(v-1)+1]. */
static uint64_t vbytes(uint64_t v) { return df_resync_version_bytes(frames + 2 * (v - 1), 2); }

static int push(df_resync *r, uint64_t v, uint64_t max)
{
    df_error e;
    return df_resync_push(r, v, frames + 2 * (v - 1), 2, max, &e);
}

static void test_keeps_references_and_finds_versions(void **state)
{
    (void)state;
    df_resync r;
    df_resync_init(&r);
    assert_int_equal(df_resync_first(&r), 0);
    assert_null(df_resync_find(&r, 1));
    for (uint64_t v = 1; v <= 20; v++) assert_int_equal(push(&r, v, UINT64_MAX), DF_OK);
    assert_int_equal(r.count, 20); /* past the first growth of the entry array */
    assert_int_equal(df_resync_first(&r), 1);
    assert_int_equal(df_resync_last(&r), 20);
    uint64_t total = 0;
    for (uint64_t v = 1; v <= 20; v++) {
        const df_resync_ver *e = df_resync_find(&r, v);
        assert_non_null(e);
        assert_int_equal(e->version, v);
        assert_int_equal(e->n, 2);
        assert_ptr_equal(e->frames[0], frames[2 * (v - 1)]); /* the same buffer, not a copy */
        assert_ptr_equal(e->frames[1], frames[2 * (v - 1) + 1]);
        assert_int_equal(refs(2 * (int)(v - 1)), 2);
        total += vbytes(v);
    }
    assert_int_equal(r.bytes, total);
    assert_null(df_resync_find(&r, 0));
    assert_null(df_resync_find(&r, 21));
    /* coverage: from 0 .. 19 to 20; not from 20 (nothing to do), not to anything but 20 */
    assert_true(df_resync_covers(&r, 0, 20));
    assert_true(df_resync_covers(&r, 19, 20));
    assert_false(df_resync_covers(&r, 20, 20));
    assert_false(df_resync_covers(&r, 21, 20));
    assert_false(df_resync_covers(&r, 5, 21)); /* the ring does not reach the current version */
    df_resync_free(&r);
    for (int i = 0; i < 40; i++) assert_int_equal(refs(i), 1);
    assert_int_equal(r.count, 0);
}

static void test_eviction_drops_oldest_whole_versions_by_bytes(void **state)
{
    (void)state;
    df_resync r;
    df_resync_init(&r);
    /* a budget that holds exactly versions 8, 9, 10 (computed from the frames' sizes) */
    uint64_t max = vbytes(8) + vbytes(9) + vbytes(10);
    for (uint64_t v = 1; v <= 10; v++) {
        assert_int_equal(push(&r, v, max), DF_OK);
        assert_true(r.bytes <= max);
    }
    assert_int_equal(df_resync_first(&r), 8);
    assert_int_equal(df_resync_last(&r), 10);
    assert_int_equal(r.bytes, max);
    assert_int_equal(r.dropped, 7);
    for (int i = 0; i < 14; i++) assert_int_equal(refs(i), 1); /* versions 1..7 released */
    for (int i = 14; i < 20; i++) assert_int_equal(refs(i), 2);
    assert_true(df_resync_covers(&r, 7, 10));  /* 8, 9, 10 kept */
    assert_false(df_resync_covers(&r, 6, 10)); /* 7 was dropped */
    assert_null(df_resync_find(&r, 7));
    /* one byte less than the three: the oldest (8) goes, whole */
    uint64_t freed = df_resync_trim(&r, max - 1);
    assert_int_equal(freed, vbytes(8));
    assert_int_equal(df_resync_first(&r), 9);
    assert_int_equal(refs(14), 1);
    assert_int_equal(refs(15), 1);
    assert_int_equal(df_resync_trim(&r, 0), vbytes(9) + vbytes(10));
    assert_int_equal(r.count, 0);
    assert_int_equal(r.bytes, 0);
    df_resync_free(&r);
}

static void test_gap_big_version_and_zero_budget_clear(void **state)
{
    (void)state;
    df_resync r;
    df_resync_init(&r);
    for (uint64_t v = 1; v <= 4; v++) assert_int_equal(push(&r, v, UINT64_MAX), DF_OK);
    /* a gap (5 never pushed): 6 cannot be reached from 1..4, they go */
    assert_int_equal(push(&r, 6, UINT64_MAX), DF_OK);
    assert_int_equal(r.count, 1);
    assert_int_equal(df_resync_first(&r), 6);
    assert_false(df_resync_covers(&r, 3, 6));
    assert_true(df_resync_covers(&r, 5, 6));
    for (int i = 0; i < 8; i++) assert_int_equal(refs(i), 1);
    /* a version larger than the budget on its own: nothing kept (older ones would leave a hole) */
    assert_int_equal(push(&r, 7, vbytes(7) - 1), DF_OK);
    assert_int_equal(r.count, 0);
    assert_int_equal(r.bytes, 0);
    assert_int_equal(refs(10), 1);
    assert_int_equal(refs(12), 1);
    /* budget 0 keeps nothing */
    assert_int_equal(push(&r, 8, 0), DF_OK);
    assert_int_equal(r.count, 0);
    assert_false(df_resync_covers(&r, 7, 8));
    /* and the ring starts over at any version afterwards */
    assert_int_equal(push(&r, 9, UINT64_MAX), DF_OK);
    assert_int_equal(push(&r, 10, UINT64_MAX), DF_OK);
    assert_true(df_resync_covers(&r, 8, 10));
    /* a version with no frames is still a version */
    df_error e;
    assert_int_equal(df_resync_push(&r, 11, NULL, 0, UINT64_MAX, &e), DF_OK);
    assert_true(df_resync_covers(&r, 8, 11));
    assert_int_equal(df_resync_find(&r, 11)->n, 0);
    df_resync_free(&r);
    df_resync_free(&r); /* twice: harmless */
}

static void test_wraparound_keeps_order(void **state)
{
    (void)state;
    df_resync r;
    df_resync_init(&r);
    /* a budget of 5 versions of the larger sizes: the entry array wraps around many times */
    uint64_t max = vbytes(32) * 5;
    for (uint64_t v = 1; v <= 32; v++) {
        assert_int_equal(push(&r, v, max), DF_OK);
        uint64_t first = df_resync_first(&r), sum = 0;
        for (uint64_t k = first; k <= v; k++) {
            const df_resync_ver *e = df_resync_find(&r, k);
            assert_non_null(e);
            assert_int_equal(e->version, k);
            sum += e->bytes;
        }
        assert_int_equal(sum, r.bytes);
        assert_true(r.bytes <= max);
        assert_true(r.count >= (v < 5 ? v : 5)); /* older versions are smaller: 5 fit */
    }
    df_resync_free(&r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_keeps_references_and_finds_versions),
        cmocka_unit_test(test_eviction_drops_oldest_whole_versions_by_bytes),
        cmocka_unit_test(test_gap_big_version_and_zero_budget_clear),
        cmocka_unit_test(test_wraparound_keeps_order),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
