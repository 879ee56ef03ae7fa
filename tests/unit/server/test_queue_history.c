/* Unit tests for the pure server pieces: shared buffers (refcounts), the bounded output queue
 * (byte accounting of pending + in-flight items, the limit, the empty-queue exception, batching,
 * ring growth, completion order) and the undo/redo history (commit, undo, redo, redo tail
 * dropped by a commit, depth cap, errors). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdlib.h>
#include <math.h>
#include <string.h>
#include <cmocka.h>

#include "server/session/history.h"
#include "server/net/outq.h"
#include "server/net/sbuf.h"

static df_sbuf *make(size_t len, uint8_t fill)
{
    df_sbuf *b = df_sbuf_new(len);
    assert_non_null(b);
    memset(b->data, fill, len);
    b->len = len;
    return b;
}

static void test_sbuf_refcount_and_adopt(void **state)
{
    (void)state;
    df_sbuf *b = make(10, 1);
    assert_int_equal(atomic_load(&b->refs), 1);
    assert_ptr_equal(df_sbuf_ref(b), b);
    assert_int_equal(atomic_load(&b->refs), 2);
    df_sbuf_unref(b);
    assert_int_equal(atomic_load(&b->refs), 1);
    df_sbuf_unref(b); /* freed (ASan would flag a leak or double free) */
    uint8_t *raw = malloc(5);
    assert_non_null(raw);
    memcpy(raw, "hello", 5);
    df_sbuf *a = df_sbuf_adopt(raw, 5);
    assert_non_null(a);
    assert_int_equal(a->len, 5);
    assert_memory_equal(a->data, "hello", 5);
    df_sbuf_unref(a);
    assert_null(df_sbuf_ref(NULL));
    df_sbuf_unref(NULL);
}

static void test_outq_accounting_and_limit(void **state)
{
    (void)state;
    df_outq q;
    df_outq_init(&q, 1000);
    df_sbuf *a = make(400, 'a'), *b = make(500, 'b'), *c = make(200, 'c');
    assert_int_equal(df_outq_push(&q, a), DF_OK);
    assert_int_equal(df_outq_push(&q, b), DF_OK);
    assert_int_equal(q.bytes, 900);
    assert_int_equal(atomic_load(&a->refs), 2); /* the queue holds a reference */
    /* 900 + 200 > 1000: refused, nothing changes */
    assert_int_equal(df_outq_push(&q, c), DF_ELIMIT);
    assert_int_equal(q.bytes, 900);
    assert_int_equal(q.count, 2);
    assert_int_equal(atomic_load(&c->refs), 1);
    /* taking items puts them in flight; they still count against the limit */
    df_sbuf *out[DF_OUTQ_MAX_BATCH];
    assert_int_equal(df_outq_take(&q, out, 1), 1);
    assert_ptr_equal(out[0], a);
    assert_int_equal(df_outq_pending(&q), 1);
    assert_int_equal(df_outq_push(&q, c), DF_ELIMIT);
    df_outq_complete(&q, 1);
    assert_int_equal(q.bytes, 500);
    assert_true(q.total_bytes == 400);
    assert_int_equal(atomic_load(&a->refs), 1);
    assert_int_equal(df_outq_push(&q, c), DF_OK); /* 700 now */
    assert_int_equal(df_outq_take(&q, out, DF_OUTQ_MAX_BATCH), 2);
    assert_ptr_equal(out[0], b);
    assert_ptr_equal(out[1], c);
    assert_int_equal(df_outq_take(&q, out, DF_OUTQ_MAX_BATCH), 0);
    df_outq_complete(&q, 5); /* clamps to what is in flight */
    assert_int_equal(q.bytes, 0);
    assert_int_equal(q.count, 0);
    assert_true(q.total_bytes == 1100);
    assert_true(q.total_items == 3);
    /* an empty queue accepts one frame larger than the limit, but nothing after it */
    df_sbuf *big = make(5000, 'z');
    assert_int_equal(df_outq_push(&q, big), DF_OK);
    assert_int_equal(df_outq_push(&q, a), DF_ELIMIT);
    df_outq_clear(&q);
    assert_int_equal(q.bytes, 0);
    assert_int_equal(atomic_load(&big->refs), 1);
    df_sbuf_unref(a);
    df_sbuf_unref(b);
    df_sbuf_unref(c);
    df_sbuf_unref(big);
}

static void test_outq_ring_growth_and_batches(void **state)
{
    (void)state;
    df_outq q;
    df_outq_init(&q, 1u << 20);
    enum { N = 300 };
    df_sbuf *bufs[N];
    size_t total = 0;
    for (int i = 0; i < N; i++) {
        bufs[i] = make((size_t)(i % 7) + 1, (uint8_t)i);
        total += bufs[i]->len;
        assert_int_equal(df_outq_push(&q, bufs[i]), DF_OK);
        if (i % 50 == 49) { /* interleave completions to wrap the ring */
            df_sbuf *out[DF_OUTQ_MAX_BATCH];
            size_t n = df_outq_take(&q, out, 30);
            assert_int_equal(n, 30);
            df_outq_complete(&q, n);
        }
    }
    assert_int_equal(q.count, N - 6 * 30);
    /* remaining items come out in push order, at most DF_OUTQ_MAX_BATCH at a time */
    int next = 180;
    df_sbuf *out[DF_OUTQ_MAX_BATCH];
    size_t n;
    while ((n = df_outq_take(&q, out, 1000)) > 0) {
        assert_true(n <= DF_OUTQ_MAX_BATCH);
        for (size_t k = 0; k < n; k++) assert_ptr_equal(out[k], bufs[next++]);
        df_outq_complete(&q, n);
    }
    assert_int_equal(next, N);
    assert_true(q.total_bytes == total);
    assert_int_equal(q.bytes, 0);
    df_outq_clear(&q);
    for (int i = 0; i < N; i++) {
        assert_int_equal(atomic_load(&bufs[i]->refs), 1);
        df_sbuf_unref(bufs[i]);
    }
}

static void test_history_undo_redo(void **state)
{
    (void)state;
    double s0[3] = {0, 0, 0}, s1[3] = {1, 0, 0}, s2[3] = {2, 0, 0}, s3[3] = {3, 0, 0};
    df_history h;
    df_error e;
    assert_int_equal(df_history_init(&h, s0, 3, 4, &e), DF_OK);
    assert_int_equal(df_history_can_undo(&h), 0);
    assert_null(df_history_undo(&h, &e));
    assert_int_equal(e.code, DF_ESTATE);
    assert_int_equal(df_history_commit(&h, s1, &e), DF_OK);
    assert_int_equal(df_history_commit(&h, s2, &e), DF_OK);
    assert_int_equal(df_history_can_undo(&h), 2);
    const double *p = df_history_undo(&h, &e);
    assert_non_null(p);
    assert_true(p[0] == 1.0);
    p = df_history_undo(&h, &e);
    assert_true(p[0] == 0.0);
    assert_int_equal(df_history_can_redo(&h), 2);
    p = df_history_redo(&h, &e);
    assert_true(p[0] == 1.0);
    /* a commit drops the redo tail (state 2) */
    assert_int_equal(df_history_commit(&h, s3, &e), DF_OK);
    assert_int_equal(df_history_can_redo(&h), 0);
    assert_null(df_history_redo(&h, &e));
    assert_int_equal(e.code, DF_ESTATE);
    p = df_history_undo(&h, &e);
    assert_true(p[0] == 1.0);
    p = df_history_redo(&h, &e);
    assert_true(p[0] == 3.0);
    /* the commit copied the data: changing the caller's array changes nothing */
    s3[0] = 99;
    assert_true(h.state[0] == 3.0);
    /* committing the current state again adds no step and keeps the redo tail */
    p = df_history_undo(&h, &e);
    assert_true(p[0] == 1.0);
    assert_int_equal(df_history_commit(&h, s1, &e), DF_OK);
    assert_int_equal(df_history_can_undo(&h), 1);
    assert_int_equal(df_history_can_redo(&h), 1);
    p = df_history_redo(&h, &e);
    assert_true(p[0] == 3.0);
    /* the current state plus two one-vertex steps (dense: 3 XORs, no index, is smaller) */
    assert_int_equal(df_history_bytes(&h),
                     3 * sizeof(double) + 2 * (3 * sizeof(uint64_t) + sizeof(df_history_step)));
    df_history_free(&h);
    assert_int_equal(df_history_can_undo(&h), 0);
}

static void test_history_depth_cap_and_errors(void **state)
{
    (void)state;
    df_history h;
    df_error e;
    double v[3] = {0, 0, 0};
    assert_int_equal(df_history_init(&h, v, 3, 3, &e), DF_OK);
    for (int i = 1; i <= 10; i++) {
        v[0] = i;
        assert_int_equal(df_history_commit(&h, v, &e), DF_OK);
        assert_true(h.count <= 2); /* steps between the 3 states */
    }
    assert_int_equal(h.dropped, 8);
    /* keeps the newest 3 states: 8, 9, 10 -> two undos, then ESTATE */
    assert_int_equal(df_history_can_undo(&h), 2);
    assert_true(df_history_undo(&h, &e)[0] == 9.0);
    assert_true(df_history_undo(&h, &e)[0] == 8.0);
    assert_null(df_history_undo(&h, &e));
    df_history_free(&h);
    assert_int_equal(df_history_init(&h, v, 0, 3, &e), DF_EINVAL);
    assert_int_equal(df_history_init(&h, v, 2, 3, &e), DF_EINVAL); /* not whole vertices */
    assert_int_equal(df_history_init(&h, v, 3, 1, &e), DF_EINVAL);
    assert_int_equal(df_history_init(&h, NULL, 3, 3, &e), DF_EINVAL);
    assert_int_equal(df_history_commit(&h, v, &e), DF_EINVAL); /* not initialized */
}

/* State k of the budget tests: every vertex moves (dense steps), with awkward bit patterns
 * (-0.0, subnormals, huge values) that only a bit-exact history restores. */
#define HB_NV 1000
static void hb_state(double *x, int k)
{
    for (int i = 0; i < 3 * HB_NV; i++)
        x[i] = (i % 7 == 0) ? (k % 2 ? -0.0 : 0.0)
               : (i % 11 == 0) ? 4.9e-324 * (k + 1)
                               : (double)k * 1e300 / (i + 1) + i * 1e-3;
}

static void test_history_byte_budget_drops_oldest_steps(void **state)
{
    (void)state;
    static double x[3 * HB_NV], want[3 * HB_NV];
    const size_t state_bytes = 3 * HB_NV * sizeof(double);
    const size_t dense_step = 3 * HB_NV * sizeof(uint64_t) + sizeof(df_history_step);
    df_history h;
    df_error e;
    hb_state(x, 0);
    assert_int_equal(df_history_init(&h, x, 3 * HB_NV, 64, &e), DF_OK);
    /* room for the state and two dense steps, not three */
    size_t budget = state_bytes + 2 * dense_step + dense_step / 2;
    assert_int_equal(df_history_set_max_bytes(&h, budget), 0);
    for (int k = 1; k <= 6; k++) {
        hb_state(x, k);
        assert_int_equal(df_history_commit(&h, x, &e), DF_OK);
        assert_true(df_history_bytes(&h) <= budget);
    }
    assert_int_equal(df_history_can_undo(&h), 2);
    assert_int_equal(h.dropped, 4);
    assert_int_equal(df_history_bytes(&h), state_bytes + 2 * dense_step);
    /* undo / redo restore states 5, 4 and back bit for bit; no further */
    for (int k = 5; k >= 4; k--) {
        const double *p = df_history_undo(&h, &e);
        hb_state(want, k);
        assert_non_null(p);
        assert_memory_equal(p, want, state_bytes);
    }
    assert_null(df_history_undo(&h, &e));
    assert_int_equal(e.code, DF_ESTATE);
    hb_state(want, 5);
    assert_int_equal(df_history_peek(&h, 1, x, &e), DF_OK); /* peek does not move */
    assert_memory_equal(x, want, state_bytes);
    assert_int_equal(df_history_can_undo(&h), 0);
    assert_int_equal(df_history_peek(&h, -1, x, &e), DF_ESTATE);
    assert_memory_equal(df_history_redo(&h, &e), want, state_bytes);
    /* shrinking the budget drops more (only below the current state) */
    assert_int_equal(df_history_set_max_bytes(&h, 0), 1);
    assert_int_equal(df_history_can_undo(&h), 0);
    assert_int_equal(df_history_can_redo(&h), 1);
    assert_int_equal(h.dropped, 5);
    /* a step larger than the whole budget is dropped at once: the state is always kept */
    hb_state(x, 9);
    assert_int_equal(df_history_commit(&h, x, &e), DF_OK);
    assert_int_equal(df_history_can_undo(&h), 0);
    assert_memory_equal(h.state, x, state_bytes);
    assert_int_equal(df_history_bytes(&h), state_bytes);
    df_history_free(&h);
}

static void test_history_sparse_steps_store_only_changed_vertices(void **state)
{
    (void)state;
    static double x[3 * HB_NV], s0[3 * HB_NV], s1[3 * HB_NV];
    df_history h;
    df_error e;
    hb_state(s0, 3);
    memcpy(x, s0, sizeof x);
    assert_int_equal(df_history_init(&h, x, 3 * HB_NV, 8, &e), DF_OK);
    size_t b0 = df_history_bytes(&h);
    assert_true(signbit(x[21]));
    x[21] = 0.0;                            /* -0.0 -> 0.0: only the sign bit differs */
    x[3 * 500] = nextafter(x[3 * 500], INFINITY); /* one ulp */
    x[3 * 999 + 2] = 7.0;
    memcpy(s1, x, sizeof x);
    assert_int_equal(df_history_commit(&h, x, &e), DF_OK);
    assert_int_equal(df_history_bytes(&h) - b0,
                     3 * (sizeof(uint32_t) + 3 * sizeof(uint64_t)) + sizeof(df_history_step));
    assert_memory_equal(df_history_undo(&h, &e), s0, sizeof s0);
    assert_memory_equal(df_history_redo(&h, &e), s1, sizeof s1);
    df_history_free(&h);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sbuf_refcount_and_adopt),
        cmocka_unit_test(test_outq_accounting_and_limit),
        cmocka_unit_test(test_outq_ring_growth_and_batches),
        cmocka_unit_test(test_history_undo_redo),
        cmocka_unit_test(test_history_depth_cap_and_errors),
        cmocka_unit_test(test_history_byte_budget_drops_oldest_steps),
        cmocka_unit_test(test_history_sparse_steps_store_only_changed_vertices),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
