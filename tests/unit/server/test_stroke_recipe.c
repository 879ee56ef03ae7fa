/* test_stroke_recipe — a stroke kept as its request (server/session/stroke_recipe.h): a replay
 * reproduces the live stroke's arithmetic bit for bit (computed here independently from the
 * Kelvinlet engine, the way h_brush.c publishes), does not depend on the thread count, covers
 * pinned and moving brushes and surface-aware strokes (issue 14 item 7: the part not connected
 * to the brush stays exactly at rest, the replay matches a longhand masked live stroke on 1 and
 * 2 threads); the blob round-trips (version 3 carries `arith`, version 2 `surface`; version 2
 * and 1 blobs still decode, as arithmetic 1)
 * and malformed blobs are refused; the checksum sees every bit. */
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "core/kelvinlet/kelvinlet_surface.h"
#include "core/mesh/geodesic.h"
#include "core/mesh/mesh.h"
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

/* The grid as two sheets: columns i < N/2 and i >= N/2 share no triangle (disconnected, 1/39
 * apart). Returns the vertex adjacency. */
static df_mesh_sparse split_adjacency(double *from)
{
    df_mesh m;
    memset(&m, 0, sizeof m);
    m.kind = DF_MESH_TRIANGLE;
    m.nv = N * N;
    m.V = from;
    m.E = malloc(6 * (size_t)N * N * sizeof *m.E);
    int32_t t = 0;
    for (int j = 0; j + 1 < N; j++)
        for (int i = 0; i + 1 < N; i++) {
            if (i + 1 == N / 2) continue; /* the gap between the sheets */
            int32_t a = j * N + i, b = a + 1, c = a + N, d = c + 1;
            int32_t tri[6] = {a, b, d, a, d, c};
            memcpy(m.E + 3 * (size_t)t, tri, sizeof tri);
            t += 2;
        }
    m.ne = t;
    df_mesh_sparse A;
    assert_int_equal(df_mesh_vertex_adjacency(&m, &A, NULL), DF_OK);
    free(m.E);
    return A;
}

/* The masked live stroke, longhand from the core functions: field at x0, weights from the
 * edge-graph distances over (double)x0 from the vertex nearest the centre, d *= w, motion. */
static void live_surface(const df_stroke_recipe *r, const df_mesh_sparse *A, const double *from,
                         double *to)
{
    size_t n = 3 * N * N;
    float *x0 = malloc(n * sizeof *x0), *d = malloc(n * sizeof *d), *w = malloc(N * N * 4);
    double *xd = malloc(n * 8), *dist = malloc(N * N * 8), *x0d = malloc(n * 8);
    for (size_t i = 0; i < n; i++) {
        x0[i] = (float)from[i];
        x0d[i] = x0[i];
        xd[i] = from[i];          /* the rest shape: `from` itself in this test */
    }
    df_kelvinlet_brush b = r->brush;
    for (int i = 0; i < 3; i++) b.tip[i] = r->strength * r->load[i];
    df_kelvinlet_prepared prep;
    assert_int_equal(df_kelvinlet_prepare(&b, &prep, NULL), DF_OK);
    prep.threads = 1;
    assert_int_equal(df_kelvinlet_displacements(&prep, x0, N * N, d, NULL), DF_OK);
    int32_t src = df_mesh_nearest_vertex(x0d, N * N, b.centre);
    assert_int_equal(df_mesh_geodesic_from(A, xd, src, dist, NULL), DF_OK);
    assert_int_equal(df_kelvinlet_surface_weights(x0d, N * N, dist, src, b.centre, b.radius,
                                                  b.order, w, NULL), DF_OK);
    for (size_t v = 0; v < N * N; v++)
        for (int k = 0; k < 3; k++) d[3 * v + k] = w[v] == 0.0f ? 0.0f : d[3 * v + k] * w[v];
    for (size_t i = 0; i < n; i++) {
        volatile float s = x0[i] + d[i];
        float m = s - x0[i];
        to[i] = from[i] + (double)m;
    }
    free(x0);
    free(d);
    free(w);
    free(xd);
    free(x0d);
    free(dist);
}

static void test_surface_replay(void **st)
{
    (void)st;
    double *from = grid(), *a = malloc(3 * N * N * 8), *b = malloc(3 * N * N * 8);
    df_mesh_sparse A = split_adjacency(from);
    df_stroke_recipe r = grab_recipe();
    r.brush.radius = 0.3;           /* reaches well into the other sheet */
    r.brush.centre[0] = 0.45;
    r.brush.surface = 1;
    df_error e;
    assert_int_equal(df_stroke_recipe_replay(&r, from, N * N, 0, 1, b, &e), DF_EINVAL);
    live_surface(&r, &A, from, a);
    assert_int_equal(df_stroke_recipe_replay_mesh(&r, from, N * N, &A, from, 0, 1, b, &e),
                     DF_OK);
    assert_memory_equal(a, b, 3 * N * N * 8);
    assert_int_equal(df_stroke_recipe_replay_mesh(&r, from, N * N, &A, from, 0, 2, b, &e),
                     DF_OK);
    assert_memory_equal(a, b, 3 * N * N * 8);
    size_t other_moved = 0, own_moved = 0;
    for (int j = 0; j < N; j++)
        for (int i = 0; i < N; i++)
            for (int k = 0; k < 3; k++) {
                size_t q = 3 * (size_t)(j * N + i) + k;
                if (i >= N / 2) assert_memory_equal(&b[q], &from[q], 8); /* exactly at rest */
                else own_moved += b[q] != from[q];
            }
    assert_true(own_moved > 100);
    r.brush.surface = 0;            /* without the mask the other sheet moves */
    assert_int_equal(df_stroke_recipe_replay_mesh(&r, from, N * N, &A, from, 0, 1, b, &e),
                     DF_OK);
    for (int j = 0; j < N; j++)
        for (int i = N / 2; i < N; i++) other_moved += b[3 * (j * N + i)] != from[3 * (j * N + i)];
    assert_true(other_moved > 100);
    df_mesh_sparse_free(&A);
    free(from);
    free(a);
    free(b);
}

/* Version 3 carries `arith`, version 2 `surface`; version 2 and 1 blobs (no arith, no surface
 * field) still decode, as arithmetic version 1 (what the builds that wrote them evaluated). */
static void test_blob_versions(void **st)
{
    (void)st;
    df_stroke_recipe r = grab_recipe(), back;
    r.brush.surface = 1;
    uint8_t *b = NULL;
    size_t len = 0;
    assert_int_equal(df_stroke_recipe_encode(&r, &b, &len, NULL), DF_OK);
    assert_int_equal(len, DF_STROKE_RECIPE_FIXED);
    assert_memory_equal(b, "DSR3", 4);
    assert_int_equal(df_stroke_recipe_decode(b, len, &back, NULL), DF_OK);
    assert_int_equal(back.brush.surface, 1);
    assert_int_equal(back.brush.arith, DF_KELVINLET_ARITH_CURRENT); /* arith 0 is written resolved */
    r.brush.arith = DF_KELVINLET_ARITH_1;
    uint8_t *b1 = NULL;
    assert_int_equal(df_stroke_recipe_encode(&r, &b1, &len, NULL), DF_OK);
    assert_int_equal(df_stroke_recipe_decode(b1, len, &back, NULL), DF_OK);
    assert_int_equal(back.brush.arith, DF_KELVINLET_ARITH_1);
    free(b1);
    const int bad_arith[] = {0, -1, DF_KELVINLET_ARITH_CURRENT + 1};
    for (size_t i = 0; i < sizeof bad_arith / sizeof bad_arith[0]; i++) {
        int32_t v = bad_arith[i], keep;
        memcpy(&keep, b + 36, 4);
        memcpy(b + 36, &v, 4);                  /* arith (i32 at offset 36) unknown */
        df_error e;
        assert_int_equal(df_stroke_recipe_decode(b, len, &back, &e), DF_EFORMAT);
        assert_non_null(strstr(e.msg, "arithmetic version"));
        assert_int_equal(back.brush.arith, 0);  /* zeroed */
        memcpy(b + 36, &keep, 4);
        if (bad_arith[i] != 0) {                /* 0 (current) is legal in a brush */
            r.brush.arith = bad_arith[i];
            uint8_t *nb = NULL;
            size_t nl = 0;
            assert_int_equal(df_stroke_recipe_encode(&r, &nb, &nl, &e), DF_EINVAL);
            assert_null(nb);
        }
    }
    r.brush.arith = DF_KELVINLET_ARITH_1;
    b[32] = 2;                                  /* surface (i32 at offset 32) not 0/1 */
    assert_int_equal(df_stroke_recipe_decode(b, len, &back, NULL), DF_EFORMAT);
    b[32] = 1;
    /* the version 2 layout of the same recipe: magic DSR2, no arith field */
    uint8_t v2[DF_STROKE_RECIPE_FIXED_V2];
    memcpy(v2, "DSR2", 4);
    memcpy(v2 + 4, b + 4, 32);
    memcpy(v2 + 36, b + 40, DF_STROKE_RECIPE_FIXED - 40);
    assert_int_equal(df_stroke_recipe_decode(v2, sizeof v2, &back, NULL), DF_OK);
    assert_int_equal(back.brush.surface, 1);
    assert_int_equal(back.brush.arith, DF_KELVINLET_ARITH_1);
    assert_memory_equal(back.load, r.load, sizeof r.load);
    assert_int_equal(df_stroke_recipe_decode(v2, sizeof v2 - 1, &back, NULL), DF_EFORMAT);
    /* the version 1 layout: magic DSR1, no surface field either */
    uint8_t v1[DF_STROKE_RECIPE_FIXED_V1];
    memcpy(v1, "DSR1", 4);
    memcpy(v1 + 4, v2 + 4, 28);
    memcpy(v1 + 32, v2 + 36, DF_STROKE_RECIPE_FIXED_V2 - 36);
    assert_int_equal(df_stroke_recipe_decode(v1, sizeof v1, &back, NULL), DF_OK);
    assert_int_equal(back.brush.surface, 0);
    assert_int_equal(back.brush.arith, DF_KELVINLET_ARITH_1);
    assert_memory_equal(back.load, r.load, sizeof r.load);
    assert_memory_equal(&back.brush.radius, &r.brush.radius, 8);
    assert_int_equal(df_stroke_recipe_decode(v1, sizeof v1 - 1, &back, NULL), DF_EFORMAT);
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
        cmocka_unit_test(test_surface_replay),
        cmocka_unit_test(test_blob_versions),
        cmocka_unit_test(test_checksum_sees_every_bit),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
