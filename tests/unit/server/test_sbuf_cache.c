/* Unit tests for server/net/sbuf.c's reuse of large buffers: a kept block serves a later request
 * with its whole capacity (at least the request, at most a quarter more), comes back with one
 * reference and len 0, is never handed out twice, and small buffers are unaffected. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "server/net/sbuf.h"

#define MB ((size_t)1 << 20)

static void test_reuse_large(void **state)
{
    (void)state;
    df_sbuf *a = df_sbuf_new(3 * MB);
    assert_non_null(a);
    memset(a->data, 0xab, 3 * MB);
    a->len = 3 * MB;
    df_sbuf_unref(a);
    /* a request a little smaller: served (by the kept block or a fresh one) with room for it */
    df_sbuf *b = df_sbuf_new(3 * MB - 1000);
    assert_non_null(b);
    assert_true(b->cap >= 3 * MB - 1000);
    assert_true(b->cap <= 3 * MB - 1000 + (3 * MB - 1000) / 4);
    assert_int_equal(b->len, 0);
    assert_int_equal(atomic_load(&b->refs), 1);
    /* a second live request of the same size never gets the same block */
    df_sbuf *c = df_sbuf_new(3 * MB - 1000);
    assert_non_null(c);
    assert_ptr_not_equal(b, c);
    assert_ptr_not_equal(b->data, c->data);
    memset(b->data, 1, b->cap);
    memset(c->data, 2, c->cap);
    assert_int_equal(b->data[b->cap - 1], 1);
    df_sbuf_ref(b);
    df_sbuf_unref(b); /* still referenced: not kept */
    assert_int_equal(b->data[0], 1);
    df_sbuf_unref(b);
    df_sbuf_unref(c);
}

static void test_much_smaller_request_not_served_by_big_block(void **state)
{
    (void)state;
    df_sbuf *a = df_sbuf_new(8 * MB);
    assert_non_null(a);
    df_sbuf_unref(a);
    df_sbuf *b = df_sbuf_new(2 * MB);
    assert_non_null(b);
    assert_true(b->cap >= 2 * MB && b->cap <= 2 * MB + MB / 2);
    df_sbuf_unref(b);
}

static void test_small_and_many(void **state)
{
    (void)state;
    df_sbuf *s = df_sbuf_new(100);
    assert_non_null(s);
    assert_int_equal(s->cap, 100);
    df_sbuf_unref(s);
    /* more large buffers than are kept: every one usable, all released without leaks (asan) */
    df_sbuf *v[12];
    for (int i = 0; i < 12; i++) {
        v[i] = df_sbuf_new((size_t)(i + 1) * MB);
        assert_non_null(v[i]);
        v[i]->data[v[i]->cap - 1] = (uint8_t)i;
    }
    for (int i = 0; i < 12; i++) df_sbuf_unref(v[i]);
    for (int i = 0; i < 12; i++) {
        v[i] = df_sbuf_new((size_t)(i + 1) * MB);
        assert_non_null(v[i]);
        assert_true(v[i]->cap >= (size_t)(i + 1) * MB);
    }
    for (int i = 0; i < 12; i++) df_sbuf_unref(v[i]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reuse_large),
        cmocka_unit_test(test_much_smaller_request_not_served_by_big_block),
        cmocka_unit_test(test_small_and_many),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
