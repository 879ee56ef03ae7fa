/* Unit tests for the float32 path's arithmetic versions (kelvinlet.h DF_KELVINLET_ARITH_*,
 * issue 14 item 6): version 2 evaluates the 2D grab of orders 1-3 in float
 * (kelvinlet_simd2d.h) and leaves every other load as version 1 does.
 *  - version 2 against the double reference, 2D grab orders 1-3, over close to wide radius
 *    ratios, every kind of nu and radii up to near the single-scale singular one (where the
 *    tip map A(0) nearly cancels): within 1e-6 of max |u|, and the centre moves by the tip to
 *    6 float epsilons (the same bounds as test_kelvinlet_simd / test_kelvinlet_tip);
 *  - version 1 is still what it was: equal to version 2 bit for bit wherever version 2 did not
 *    change the arithmetic (3D, 2D orders 4-8, 2D affine loads), different bits but the same
 *    field to float rounding for the 2D grab of orders 1-3 (bit-exactness of version 1 against
 *    a build before version 2: tests/unit/server/test_recipe_arith.c);
 *  - arith 0 is the current version; an unknown version is refused with nothing written. */
#include <float.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "core/kelvinlet/kelvinlet.h"
#include "tests/unit/kelvinlet/kelvinlet_test_brush.h"

#define NPTS 4099

/* NPTS points from the centre out to ~8 radii (z = 0 in 2D), the first exactly at the centre. */
static float *points(int dim, double radius)
{
    float *x = malloc(3 * NPTS * sizeof *x);
    assert_non_null(x);
    for (size_t k = 0; k < NPTS; k++) {
        double r = 8.0 * radius * (double)k / NPTS;
        x[3 * k] = (float)(0.1 + r * sin(1.3 * (double)k));
        x[3 * k + 1] = (float)(-0.05 + r * cos(0.7 * (double)k));
        x[3 * k + 2] = dim == 3 ? (float)(0.02 + r * sin(0.31 * (double)k)) : 0.0f;
    }
    return x;
}

/* Displacements of brush b (its arith as given) at x, into d; DF_OK or the error. */
static int disp(df_kelvinlet_brush b, const float *x, size_t n, float *d)
{
    df_kelvinlet_prepared p;
    int rc = df_kelvinlet_prepare(&b, &p, NULL);
    if (rc == DF_OK) {
        p.threads = 1;
        rc = df_kelvinlet_displacements(&p, x, n, d, NULL);
    }
    return rc;
}

static void test_v2_2d_grab_accuracy(void **st)
{
    (void)st;
    static const double ratios[] = {1.01, 1.05, 1.1, 1.19, 1.25, 1.5, 2.0, 3.0};
    static const double nus[] = {0.0, 0.3, 0.5, -1.0, INFINITY};
    static const double radii[] = {0.25, 1.0, 2.5};   /* 2.5: A(0) of order 1 ~ 0 at nu 0.5 */
    float *d = malloc(3 * NPTS * sizeof *d);
    assert_non_null(d);
    double worst = 0.0, worst_tip = 0.0;
    for (size_t ri = 0; ri < sizeof radii / sizeof radii[0]; ri++) {
        float *x = points(2, radii[ri]);
        for (int order = 1; order <= 3; order++)
            for (size_t q = 0; q < sizeof ratios / sizeof ratios[0]; q++)
                for (size_t k = 0; k < sizeof nus / sizeof nus[0]; k++) {
                    df_kelvinlet_brush b = tk_brush(DF_KELVINLET_GRAB, 2, order, ratios[q], nus[k],
                                                radii[ri]);
                    b.centre[0] = x[0];               /* the first point: the float centre */
                    b.centre[1] = x[1];
                    df_kelvinlet_prepared p;
                    int rc = df_kelvinlet_prepare(&b, &p, NULL);
                    if (rc == DF_ESINGULAR)
                        continue;                     /* a vanishing tip map (ratio 1.01) */
                    assert_int_equal(rc, DF_OK);
                    assert_int_equal(disp(b, x, NPTS, d), DF_OK);
                    double err = 0.0, umax = 0.0;
                    for (size_t j = 0; j < NPTS; j++) {
                        double xd[3] = {x[3 * j], x[3 * j + 1], x[3 * j + 2]}, u[3];
                        assert_int_equal(df_kelvinlet_eval_ref(&p, xd, u, NULL), DF_OK);
                        for (int i = 0; i < 3; i++) {
                            err = fmax(err, fabs(d[3 * j + i] - u[i]));
                            umax = fmax(umax, fabs(u[i]));
                        }
                        assert_true(d[3 * j + 2] == 0.0f);
                    }
                    double tl = hypot(b.tip[0], b.tip[1]);
                    double tip = fmax(fabs(d[0] - b.tip[0]), fabs(d[1] - b.tip[1])) / tl;
                    if (err / umax > 1e-6 || tip > 6.0 * FLT_EPSILON)
                        fail_msg("order %d ratio %g nu %g radius %g: max |float - double| "
                                 "%.2e of max |u|, tip error %.2e", order, ratios[q], nus[k],
                                 radii[ri], err / umax, tip);
                    worst = fmax(worst, err / umax);
                    worst_tip = fmax(worst_tip, tip);
                }
        free(x);
    }
    printf("# arith 2, 2D grab orders 1-3: worst |float - double| %.2e of max |u|, worst tip "
           "error %.2e of |tip|\n", worst, worst_tip);
    free(d);
}

/* Version 1 and 2 give the same bits wherever version 2 did not change the arithmetic, and
 * other bits (the same field to float rounding) where it did. */
static void test_versions_differ_only_in_2d_grab_1_3(void **st)
{
    (void)st;
    float *x2 = points(2, 0.25), *x3 = points(3, 0.25);
    float *d1 = malloc(3 * NPTS * sizeof *d1), *d2 = malloc(3 * NPTS * sizeof *d2);
    float *d0 = malloc(3 * NPTS * sizeof *d0);
    assert_non_null(d0);
    assert_non_null(d1);
    assert_non_null(d2);
    for (int dim = 2; dim <= 3; dim++)
        for (int type = DF_KELVINLET_GRAB; type <= DF_KELVINLET_TWIST; type++)
            for (int order = 1; order <= DF_KELVINLET_MAX_ORDER; order++) {
                df_kelvinlet_brush b = tk_brush(type, dim, order, 1.1, 0.3, 0.25);
                const float *x = dim == 2 ? x2 : x3;
                b.arith = DF_KELVINLET_ARITH_1;
                assert_int_equal(disp(b, x, NPTS, d1), DF_OK);
                b.arith = DF_KELVINLET_ARITH_2;
                assert_int_equal(disp(b, x, NPTS, d2), DF_OK);
                b.arith = 0;
                assert_int_equal(disp(b, x, NPTS, d0), DF_OK);
                assert_memory_equal(d0, DF_KELVINLET_ARITH_CURRENT == 2 ? d2 : d1,
                                    3 * NPTS * sizeof *d0);
                int changed = dim == 2 && type == DF_KELVINLET_GRAB && order <= 3;
                int same = memcmp(d1, d2, 3 * NPTS * sizeof *d1) == 0;
                if (same == changed)
                    fail_msg("dim %d type %d order %d: versions 1 and 2 %s", dim, type, order,
                             same ? "give the same bits" : "differ");
                double dmax = 0.0, umax = 0.0;
                for (size_t i = 0; i < 3 * NPTS; i++) {
                    dmax = fmax(dmax, fabs((double)d1[i] - d2[i]));
                    umax = fmax(umax, fabs((double)d1[i]));
                }
                assert_true(dmax <= 2e-6 * umax);
            }
    free(x2);
    free(x3);
    free(d0);
    free(d1);
    free(d2);
}

static void test_unknown_version_refused(void **st)
{
    (void)st;
    const int bad[] = {-1, DF_KELVINLET_ARITH_CURRENT + 1, 1000};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        df_kelvinlet_brush b = tk_brush(DF_KELVINLET_GRAB, 2, 1, 1.1, 0.3, 0.25);
        b.arith = bad[i];
        df_kelvinlet_prepared p;
        p.nsrc = 77;
        df_error e;
        assert_int_equal(df_kelvinlet_prepare(&b, &p, &e), DF_EINVAL);
        assert_true(p.nsrc == 77);
        assert_non_null(strstr(e.msg, "arithmetic version"));
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_v2_2d_grab_accuracy),
        cmocka_unit_test(test_versions_differ_only_in_2d_grab_1_3),
        cmocka_unit_test(test_unknown_version_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
