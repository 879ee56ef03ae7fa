/* test_stroke_recipe — a stroke kept as its request (server/session/stroke_recipe.h): a replay
 * reproduces the live stroke's arithmetic bit for bit (computed here independently from the
 * Kelvinlet engine, the way h_brush.c publishes), does not depend on the thread count, covers
 * pinned and moving brushes; the blob round-trips and malformed blobs are refused; the checksum
 * sees every bit. */
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "server/session/stroke_recipe.h"

#define N 40 /* grid side: 1600 vertices */

static double *grid(void)
{
    double *p = malloc(3 * N * N * sizeof *p);
    for (int j = 0; j < N; j++)
        for (int i = 0; i < N; i++) {
            double *v = p + 3 * (j * N + i);
            v[0] = i / (double)(N - 1) + 1e-9 * j; /* not float-exact: full double bits */
            v[1] = j / (double)(N - 1);
            v[2] = 0.1 * sin(3.0 * v[0]) * cos(2.0 * v[1]);
        }
    return p;
}

static df_stroke_recipe grab_recipe(void)
{
    df_stroke_recipe r;
    memset(&r, 0, sizeof r);
    df_kelvinlet_brush_defaults(&r.brush);
    r.brush.radius = 0.1;
    r.brush.nu = 0.45;
    r.brush.order = 3;
    r.brush.centre[0] = 0.4;
    r.brush.centre[1] = 0.6;
    r.strength = 0.8;
    r.load[0] = 0.02;
    r.load[2] = 0.05;
    return r;
}

/* The live path, independently: loaded brush, prepare, displacements at fl32(from), then
 * m = fl32(x0 + d) - x0 and to = from + m written out longhand. */
static void live(const df_stroke_recipe *r, const double *from, double *to)
{
    size_t n = 3 * N * N;
    float *x0 = malloc(n * sizeof *x0), *d = malloc(n * sizeof *d);
    for (size_t i = 0; i < n; i++) x0[i] = (float)from[i];
    df_kelvinlet_brush b = r->brush;
    for (int i = 0; i < 3; i++) b.tip[i] = r->strength * r->load[i];
    for (int i = 0; i < 3; i++) b.omega[i] = r->strength * r->load[3 + i];
    b.s = r->strength * r->load[6];
    for (int i = 0; i < 9; i++) b.grad[i] = r->strength * r->load[7 + i];
    df_kelvinlet_prepared prep;
    df_error e;
    assert_int_equal(df_kelvinlet_prepare(&b, &prep, &e), DF_OK);
    prep.threads = 1;
    assert_int_equal(df_kelvinlet_displacements(&prep, x0, N * N, d, &e), DF_OK);
    for (size_t i = 0; i < n; i++) {
        volatile float s = x0[i] + d[i]; /* float32 rounding, as the live stroke */
        float m = s - x0[i];
        to[i] = from[i] + (double)m;
    }
    free(x0);
    free(d);
}

static void test_replay_matches_live(void **st)
{
    (void)st;
    double *from = grid(), *a = malloc(3 * N * N * 8), *b = malloc(3 * N * N * 8);
    df_stroke_recipe r = grab_recipe();
    df_error e;
    live(&r, from, a);
    assert_int_equal(df_stroke_recipe_replay(&r, from, N * N, 0, 1, b, &e), DF_OK);
    assert_memory_equal(a, b, 3 * N * N * 8);
    assert_int_equal(df_stroke_recipe_replay(&r, from, N * N, 0, 2, b, &e), DF_OK);
    assert_memory_equal(a, b, 3 * N * N * 8);
    assert_true(memcmp(a, from, 3 * N * N * 8) != 0); /* it did move */
    /* a different load gives a different state (the recipe is used, not ignored) */
    r.load[0] = 0.03;
    assert_int_equal(df_stroke_recipe_replay(&r, from, N * N, 0, 1, b, &e), DF_OK);
    assert_true(memcmp(a, b, 3 * N * N * 8) != 0);
    free(from);
    free(a);
    free(b);
}

static void test_pinned_and_moving(void **st)
{
    (void)st;
    double *from = grid(), *a = malloc(3 * N * N * 8), *b = malloc(3 * N * N * 8);
    df_error e;
    df_stroke_recipe r = grab_recipe();
    double pins[6] = {0.45, 0.6, 0.0, 0.3, 0.55, 0.0};
    r.n_pins = 2;
    r.pins = pins;
    r.pin_flags = DF_KELVINLET_PIN_DISPLACEMENT;
    assert_int_equal(df_stroke_recipe_replay(&r, from, N * N, 0, 1, a, &e), DF_OK);
    assert_int_equal(df_stroke_recipe_replay(&r, from, N * N, 0, 2, b, &e), DF_OK);
    assert_memory_equal(a, b, 3 * N * N * 8);
    r.n_pins = 0;
    r.pins = NULL;
    r.pin_flags = 0;
    r.brush.moving = 1;
    r.brush.steps = 4;
    assert_int_equal(df_stroke_recipe_replay(&r, from, N * N, 0, 1, a, &e), DF_OK);
    assert_int_equal(df_stroke_recipe_replay(&r, from, N * N, 0, 2, b, &e), DF_OK);
    assert_memory_equal(a, b, 3 * N * N * 8);
    /* a 2D session refuses a field that moves z */
    r.brush.moving = 0;
    assert_int_equal(df_stroke_recipe_replay(&r, from, N * N, 1, 1, b, &e), DF_EINVAL);
    free(from);
    free(a);
    free(b);
}

static void test_blob_round_trip(void **st)
{
    (void)st;
    df_stroke_recipe r = grab_recipe(), back;
    double pins[3] = {0.1, 0.2, 0.3};
    r.n_pins = 1;
    r.pins = pins;
    r.pin_flags = DF_KELVINLET_PIN_DISPLACEMENT;
    r.brush.nu = -INFINITY;
    uint8_t *b = NULL;
    size_t len = 0;
    df_error e;
    assert_int_equal(df_stroke_recipe_encode(&r, &b, &len, &e), DF_OK);
    assert_int_equal(len, DF_STROKE_RECIPE_FIXED + 24);
    assert_int_equal(df_stroke_recipe_decode(b, len, &back, &e), DF_OK);
    assert_memory_equal(&back.brush.radius, &r.brush.radius, 8);
    assert_true(isinf(back.brush.nu) && back.brush.nu < 0);
    assert_int_equal(back.brush.order, 3);
    assert_memory_equal(back.load, r.load, sizeof r.load);
    assert_int_equal(back.n_pins, 1);
    assert_memory_equal(back.pins, pins, 24);
    df_stroke_recipe_free(&back);
    /* every truncation and one extra byte refused, the output zeroed */
    for (size_t k = 0; k < len; k++) {
        assert_int_equal(df_stroke_recipe_decode(b, k, &back, &e), DF_EFORMAT);
        assert_null(back.pins);
    }
    uint8_t *longer = malloc(len + 1);
    memcpy(longer, b, len);
    longer[len] = 0;
    assert_int_equal(df_stroke_recipe_decode(longer, len + 1, &back, &e), DF_EFORMAT);
    /* wrong magic, a NaN load */
    longer[0] ^= 1;
    assert_int_equal(df_stroke_recipe_decode(longer, len, &back, &e), DF_EFORMAT);
    longer[0] ^= 1;
    double nan = NAN;
    memcpy(longer + DF_STROKE_RECIPE_FIXED - 8 - 8 * DF_STROKE_LOAD_N, &nan, 8);
    assert_int_equal(df_stroke_recipe_decode(longer, len, &back, &e), DF_EFORMAT);
    free(longer);
    free(b);
}

static void test_checksum_sees_every_bit(void **st)
{
    (void)st;
    double *p = grid();
    size_t n = 3 * N * N;
    uint64_t h = df_positions_checksum(p, n);
    assert_int_equal(h, df_positions_checksum(p, n));
    for (size_t i = 0; i < n; i += 97)
        for (int bit = 0; bit < 64; bit += 7) {
            uint64_t u;
            memcpy(&u, p + i, 8);
            u ^= 1ULL << bit;
            double old = p[i];
            memcpy(p + i, &u, 8);
            assert_true(df_positions_checksum(p, n) != h);
            p[i] = old;
        }
    double z[5] = {0.0, 0, 0, 0, 0}, mz[5] = {-0.0, 0, 0, 0, 0};
    assert_true(df_positions_checksum(z, 5) != df_positions_checksum(mz, 5));
    assert_true(df_positions_checksum(z, 4) != df_positions_checksum(z, 5));
    free(p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_replay_matches_live),
        cmocka_unit_test(test_pinned_and_moving),
        cmocka_unit_test(test_blob_round_trip),
        cmocka_unit_test(test_checksum_sees_every_bit),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
