/* Unit tests for the grab tip of every falloff order (issue 9 item 19): the brush centre moves
 * by exactly `tip` on the double path (relative error < 1e-9) and to float rounding on the
 * float32 path (< 6 ulps of |tip|), for orders 1-8, close and wide radius ratios, finite and
 * infinite nu, 3D and 2D. Orders 7 and 8 at ratio 1.1 used to move the centre by 1.00027 tip
 * on the float path (2.5e-4 relative): their multi-scale weights cancel ~1e4-fold. */
#include <float.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "core/kelvinlet/kelvinlet.h"

static const double RATIOS[] = {1.01, 1.05, 1.1, 1.25, 1.5, 2.0, 3.0};
static const double NUS[] = {0.0, 0.45, 0.5, -0.5, INFINITY, -INFINITY};
#define NR (sizeof RATIOS / sizeof RATIOS[0])
#define NN (sizeof NUS / sizeof NUS[0])

static df_kelvinlet_brush grab(int dim, int order, double ratio, double nu)
{
    df_kelvinlet_brush b;
    df_kelvinlet_brush_defaults(&b);
    b.dim = dim;
    b.order = order;
    b.ratio = ratio;
    b.nu = nu;
    b.radius = 0.25;
    b.centre[0] = 0.5;
    b.centre[1] = -0.25;
    b.centre[2] = dim == 3 ? 0.125 : 0.0;
    b.tip[0] = 0.003;
    b.tip[1] = 0.01;
    b.tip[2] = dim == 3 ? -0.006 : 0.0;
    return b;
}

/* Worst relative tip error over every order, ratio and nu; *fworst: the float path's. */
static void tip_errors(int dim, double *dworst, double *fworst, int order_lo, int order_hi)
{
    *dworst = *fworst = 0.0;
    for (int order = order_lo; order <= order_hi; order++)
        for (size_t r = 0; r < NR; r++)
            for (size_t k = 0; k < NN; k++) {
                df_kelvinlet_brush b = grab(dim, order, RATIOS[r], NUS[k]);
                double tl = sqrt(b.tip[0] * b.tip[0] + b.tip[1] * b.tip[1]
                                 + b.tip[2] * b.tip[2]);
                df_kelvinlet_prepared p;
                df_error e;
                int rc = df_kelvinlet_prepare(&b, &p, &e);
                if (rc == DF_ESINGULAR && dim == 2 && RATIOS[r] < 1.02)
                    continue;   /* 2D, ratio 1.01: the tip map is refused as singular */
                assert_int_equal(rc, DF_OK);
                double u[3];
                assert_int_equal(df_kelvinlet_eval_ref(&p, b.centre, u, &e), DF_OK);
                float x[3] = {(float)b.centre[0], (float)b.centre[1], (float)b.centre[2]};
                float d[3];
                /* the float path evaluates at the float centre: move the brush there */
                for (int i = 0; i < 3; i++)
                    b.centre[i] = x[i];
                assert_int_equal(df_kelvinlet_prepare(&b, &p, &e), DF_OK);
                assert_int_equal(df_kelvinlet_displacements(&p, x, 1, d, &e), DF_OK);
                for (int i = 0; i < 3; i++) {
                    double de = fabs(u[i] - b.tip[i]) / tl, fe = fabs(d[i] - b.tip[i]) / tl;
                    if (de > *dworst || fe > *fworst)
                        printf("# dim %d order %d ratio %g nu %g: double %.2e float %.2e\n",
                               dim, order, RATIOS[r], NUS[k], de, fe);
                    *dworst = fmax(*dworst, de);
                    *fworst = fmax(*fworst, fe);
                }
            }
}

#define FLOAT_TOL (6.0 * FLT_EPSILON)   /* ~7e-7: a few roundings of the float32 path */

static void test_tip_3d_every_order_ratio_nu(void **state)
{
    (void)state;
    double dw, fw;
    tip_errors(3, &dw, &fw, 1, DF_KELVINLET_MAX_ORDER);
    printf("# 3D tip, orders 1-8: worst relative error double %.2e, float %.2e\n", dw, fw);
    assert_true(dw < 1e-9);
    assert_true(fw < FLOAT_TOL);
}

static void test_tip_2d_every_order_ratio_nu(void **state)
{
    (void)state;
    double dw, fw;
    tip_errors(2, &dw, &fw, 1, DF_KELVINLET_MAX_ORDER);
    printf("# 2D tip, orders 1-8: worst relative error double %.2e, float %.2e\n", dw, fw);
    assert_true(dw < 1e-9);
    assert_true(fw < FLOAT_TOL);
}

/* The case: order 7 and 8 at the default ratio 1.1, nu 0.45 and inf, 0.01 upwards. */
static void test_tip_order_7_8_default_ratio(void **state)
{
    (void)state;
    const double nus[] = {0.45, INFINITY};
    for (int order = 7; order <= 8; order++)
        for (int k = 0; k < 2; k++) {
            df_kelvinlet_brush b;
            df_kelvinlet_brush_defaults(&b);
            b.order = order;
            b.radius = 0.25;
            b.nu = nus[k];
            b.centre[0] = 0.5f;
            b.tip[1] = 0.01;
            df_kelvinlet_prepared p;
            df_error e;
            assert_int_equal(df_kelvinlet_prepare(&b, &p, &e), DF_OK);
            float x[3] = {0.5f, 0.0f, 0.0f};
            assert_int_equal(df_kelvinlet_apply(&p, x, 1, &e), DF_OK);
            printf("# order %d nu %g: centre moves %.9g for 0.01\n", order, nus[k], x[1]);
            assert_true(fabs(x[1] - 0.01) < 0.01 * FLOAT_TOL);
            assert_true(x[0] == 0.5f && x[2] == 0.0f);
        }
}

/* The whole float32 field, not just its tip: every brush type at orders 4-8 agrees with the
 * double reference to float rounding (these orders sum in double on the float path; summed in
 * float they were off by ~1e-4 of the largest displacement at order 7). */
static void test_float_field_matches_double_orders_4_to_8(void **state)
{
    (void)state;
    const double g[9] = {0.1, 0.02, 0, 0.02, -0.05, 0.01, 0, 0.01, -0.05};
    for (int t = DF_KELVINLET_GRAB; t <= DF_KELVINLET_AFFINE; t++)
        for (int order = 4; order <= DF_KELVINLET_MAX_ORDER; order++) {
            df_kelvinlet_brush b;
            df_kelvinlet_brush_defaults(&b);
            b.type = (df_kelvinlet_type)t;
            b.order = order;
            b.radius = 0.25;
            b.nu = 0.3;
            b.tip[0] = 0.01;
            b.tip[2] = 0.02;
            b.omega[0] = 0.1;
            b.omega[2] = 0.3;
            b.s = 0.1;
            memcpy(b.grad, g, sizeof g);
            df_kelvinlet_prepared p;
            df_error e;
            assert_int_equal(df_kelvinlet_prepare(&b, &p, &e), DF_OK);
            double worst = 0.0, umax = 0.0;
            for (int k = 0; k < 500; k++) {
                float x[3] = {(float)(0.8 * sin(1.3 * k)), (float)(0.8 * cos(0.7 * k)),
                              (float)(0.8 * sin(0.31 * k))};
                double xd[3] = {x[0], x[1], x[2]}, u[3];
                float d[3];
                assert_int_equal(df_kelvinlet_displacements(&p, x, 1, d, &e), DF_OK);
                assert_int_equal(df_kelvinlet_eval_ref(&p, xd, u, &e), DF_OK);
                for (int i = 0; i < 3; i++) {
                    worst = fmax(worst, fabs(d[i] - u[i]));
                    umax = fmax(umax, fabs(u[i]));
                }
            }
            if (worst > 1e-6 * umax)
                fail_msg("type %d order %d: max |float - double| = %.2e of max |u|", t, order,
                         worst / umax);
        }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tip_3d_every_order_ratio_nu),
        cmocka_unit_test(test_tip_2d_every_order_ratio_nu),
        cmocka_unit_test(test_tip_order_7_8_default_ratio),
        cmocka_unit_test(test_float_field_matches_double_orders_4_to_8),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
