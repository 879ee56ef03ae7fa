/* Unit tests for core/kelvinlet bad input: NaN/Inf in every brush field, radius <= 0,
 * ratio <= 1, order 0 or > 8, nu out of range, bad dim / type / steps, out-of-range values,
 * NaN points, NULLs and uninitialized prepared brushes -> an error code and a message, with
 * the outputs left untouched. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "core/kelvinlet/kelvinlet.h"

static df_kelvinlet_brush good(void)
{
    df_kelvinlet_brush b;
    df_kelvinlet_brush_defaults(&b);
    b.order = 3;
    b.radius = 0.3;
    b.nu = 0.4;
    b.tip[0] = 0.1;
    b.mirror_normal[2] = 1.0;
    return b;
}

/* prepare must fail with `code`, a non-empty message, and leave `out` untouched. */
static void expect_fail(const df_kelvinlet_brush *b, int code, const char *what)
{
    df_kelvinlet_prepared out, copy;
    memset(&out, 0xA5, sizeof out);
    memcpy(&copy, &out, sizeof out);
    df_error e;
    df_error_clear(&e);
    int rc = df_kelvinlet_prepare(b, &out, &e);
    if (rc != code)
        printf("# %s: got %d (%s)\n", what, rc, e.msg);
    assert_int_equal(rc, code);
    assert_int_equal(e.code, code);
    assert_true(strlen(e.msg) > 10);
    assert_memory_equal(&out, &copy, sizeof out);
}

static void test_non_finite_fields(void **state)
{
    (void)state;
    const double bad[] = {NAN, INFINITY, -INFINITY};
    int n = 0;
    for (int k = 0; k < 3; k++)
        for (size_t f = 0; f < 11; f++) {
            df_kelvinlet_brush b = good();
            double *fl[11] = {&b.radius, &b.ratio, &b.centre[0], &b.centre[2], &b.tip[1],
                              &b.omega[2], &b.s, &b.grad[4], &b.grad[8], &b.mirror_point[1],
                              &b.mirror_normal[0]};
            *fl[f] = bad[k];
            expect_fail(&b, DF_EINVAL, "non-finite");
            n++;
        }
    df_kelvinlet_brush b = good();
    b.nu = NAN;
    expect_fail(&b, DF_EINVAL, "nu NaN");
    printf("# %d non-finite field cases rejected\n", n + 1);
}

static void test_range_errors(void **state)
{
    (void)state;
    df_kelvinlet_brush b;
    b = good(); b.radius = 0.0;       expect_fail(&b, DF_EINVAL, "radius 0");
    b = good(); b.radius = -0.2;      expect_fail(&b, DF_EINVAL, "radius < 0");
    b = good(); b.radius = 1e-9;      expect_fail(&b, DF_EINVAL, "radius tiny");
    b = good(); b.ratio = 1.0;        expect_fail(&b, DF_EINVAL, "ratio 1");
    b = good(); b.ratio = 0.9;        expect_fail(&b, DF_EINVAL, "ratio < 1");
    b = good(); b.order = 0;          expect_fail(&b, DF_EINVAL, "order 0");
    b = good(); b.order = 9;          expect_fail(&b, DF_EINVAL, "order 9");
    b = good(); b.order = -3;         expect_fail(&b, DF_EINVAL, "order < 0");
    b = good(); b.nu = 0.6;           expect_fail(&b, DF_EINVAL, "nu 0.6");
    b = good(); b.nu = 1.0;           expect_fail(&b, DF_EINVAL, "nu 1");
    b = good(); b.nu = -1.5;          expect_fail(&b, DF_EINVAL, "nu -1.5");
    b = good(); b.dim = 4;            expect_fail(&b, DF_EINVAL, "dim 4");
    b = good(); b.type = (df_kelvinlet_type)7;         expect_fail(&b, DF_EINVAL, "type");
    b = good(); b.integrator = (df_kelvinlet_integrator)3; expect_fail(&b, DF_EINVAL, "integ");
    b = good(); b.steps = 0;          expect_fail(&b, DF_EINVAL, "steps 0");
    b = good(); b.steps = DF_KELVINLET_MAX_STEPS + 1; expect_fail(&b, DF_EINVAL, "steps big");
    b = good(); b.moving = 2;         expect_fail(&b, DF_EINVAL, "moving 2");
    b = good(); b.tip[0] = 2e9;       expect_fail(&b, DF_EINVAL, "tip huge");
    b = good(); b.mirror = 1; b.mirror_normal[2] = 0.0; expect_fail(&b, DF_EINVAL, "normal 0");
    b = good(); b.type = DF_KELVINLET_SCALE; b.s = 0.1; b.nu = 0.5;
    expect_fail(&b, DF_ESINGULAR, "scale at 0.5");
    assert_int_equal(df_kelvinlet_prepare(NULL, NULL, NULL), DF_EINVAL);
    /* weights API */
    double eps[8] = {0}, w[8] = {0}, z[8] = {0};
    df_error e;
    assert_int_equal(df_kelvinlet_weights(0, 1.1, 1.0, eps, w, &e), DF_EINVAL);
    assert_int_equal(df_kelvinlet_weights(9, 1.1, 1.0, eps, w, &e), DF_EINVAL);
    assert_int_equal(df_kelvinlet_weights(3, 1.0, 1.0, eps, w, &e), DF_EINVAL);
    assert_int_equal(df_kelvinlet_weights(3, 1.1, 0.0, eps, w, &e), DF_EINVAL);
    assert_int_equal(df_kelvinlet_weights(3, NAN, 1.0, eps, w, &e), DF_EINVAL);
    assert_memory_equal(eps, z, sizeof z);
    assert_memory_equal(w, z, sizeof z);
}

/* A ratio so close to 1 that the multi-scale weights cancel is blamed on the ratio (named with
 * its digits, with the range that works), never on the radius, for every brush type. */
static void test_ratio_near_one_names_the_ratio(void **state)
{
    (void)state;
    for (int t = DF_KELVINLET_GRAB; t <= DF_KELVINLET_AFFINE; t++) {
        df_kelvinlet_brush b = good();
        b.type = (df_kelvinlet_type)t;
        b.ratio = 1.0000001;
        if (t == DF_KELVINLET_TWIST)
            b.omega[1] = 0.3;
        else if (t == DF_KELVINLET_SCALE)
            b.s = 0.1;
        else if (t != DF_KELVINLET_GRAB)
            b.grad[0] = 0.1, b.grad[4] = -0.1;
        df_kelvinlet_prepared out;
        df_error e;
        df_error_clear(&e);
        assert_int_equal(df_kelvinlet_prepare(&b, &out, &e), DF_ESINGULAR);
        assert_non_null(strstr(e.msg, "ratio 1.0000001 is too close to 1 for falloff order 3"));
        assert_non_null(strstr(e.msg, "1.05 or more"));
        assert_null(strstr(e.msg, "radius"));
        b.ratio = 1.05;
        assert_int_equal(df_kelvinlet_prepare(&b, &out, &e), DF_OK);
        df_kelvinlet_prepared_free(&out);
    }
}

static void test_bad_points_leave_outputs_untouched(void **state)
{
    (void)state;
    df_kelvinlet_brush b = good();
    df_kelvinlet_prepared p;
    assert_int_equal(df_kelvinlet_prepare(&b, &p, NULL), DF_OK);
    enum { N = 3000 };
    static float x[3 * N], keep[3 * N], out[3 * N], out0[3 * N];
    for (int i = 0; i < 3 * N; i++)
        x[i] = (float)(0.001 * i);
    const float bad[] = {NAN, INFINITY, -INFINITY, 3e9f};
    for (int k = 0; k < 4; k++) {
        x[3 * 2000 + 1] = bad[k];
        memcpy(keep, x, sizeof x);
        memset(out, 0x5A, sizeof out);
        memcpy(out0, out, sizeof out);
        df_error e;
        assert_int_equal(df_kelvinlet_apply(&p, x, N, &e), DF_EINVAL);
        assert_non_null(strstr(e.msg, "point 2000"));
        assert_memory_equal(x, keep, sizeof x);
        assert_int_equal(df_kelvinlet_displacements(&p, x, N, out, &e), DF_EINVAL);
        assert_memory_equal(out, out0, sizeof out);
        double xd[3] = {0.1, bad[k], 0.2}, u[3] = {7, 7, 7};
        assert_int_equal(df_kelvinlet_eval_ref(&p, xd, u, &e), DF_EINVAL);
        assert_true(u[0] == 7 && u[1] == 7 && u[2] == 7);
        double g[9] = {0};
        assert_int_equal(df_kelvinlet_gradient_ref(&p, xd, g, &e), DF_EINVAL);
        double pts[6] = {0.1, 0.2, 0.3, 0.1, bad[k], 0.3}, pk[6];
        memcpy(pk, pts, sizeof pk);
        assert_int_equal(df_kelvinlet_apply_ref(&p, pts, 2, &e), DF_EINVAL);
        assert_memory_equal(pts, pk, sizeof pk);
    }
    x[3 * 2000 + 1] = 0.5f;
    assert_int_equal(df_kelvinlet_apply(&p, NULL, 5, NULL), DF_EINVAL);
    assert_int_equal(df_kelvinlet_apply(&p, x, 0, NULL), DF_OK);          /* nothing to do */
    df_kelvinlet_prepared zero;
    memset(&zero, 0, sizeof zero);
    df_error e;
    assert_int_equal(df_kelvinlet_apply(&zero, x, N, &e), DF_EINVAL);
    assert_true(strlen(e.msg) > 10);
    assert_int_equal(df_kelvinlet_apply(NULL, x, N, &e), DF_EINVAL);
    double u[3];
    assert_int_equal(df_kelvinlet_eval_ref(&zero, (double[]){0, 0, 0}, u, &e), DF_EINVAL);
    df_kelvinlet_prepared_free(NULL);
    df_kelvinlet_constraints_free(NULL);
    assert_int_equal((int)df_kelvinlet_constraints_factorizations(NULL), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_non_finite_fields),
        cmocka_unit_test(test_range_errors),
        cmocka_unit_test(test_bad_points_leave_outputs_untouched),
        cmocka_unit_test(test_ratio_near_one_names_the_ratio),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
