/* Unit tests for core/kelvinlet grab brushes: exact tip displacement for every nu and falloff
 * order (3D and 2D), the multi-scale weights, far-field decay slopes from log-log fits, the
 * classic radial falloff at nu = +-inf and the 2D singular single-scale radius. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "core/kelvinlet/kelvinlet.h"

static const double NUS[] = {0.0, 0.25, 0.4, 0.49, 0.5, INFINITY, -INFINITY};
#define NNU (sizeof NUS / sizeof NUS[0])

static df_kelvinlet_brush grab(int dim, int order, double nu, double radius)
{
    df_kelvinlet_brush b;
    df_kelvinlet_brush_defaults(&b);
    b.dim = dim;
    b.order = order;
    b.nu = nu;
    b.radius = radius;
    b.centre[0] = 0.3;
    b.centre[1] = -0.2;
    b.centre[2] = 0.7;
    b.tip[0] = 0.05;
    b.tip[1] = -0.11;
    b.tip[2] = dim == 3 ? 0.07 : 0.0;
    return b;
}

static void test_tip_exact_3d_all_orders_and_nu(void **state)
{
    (void)state;
    double worst = 0.0;
    for (int order = 1; order <= DF_KELVINLET_MAX_ORDER; order++)
        for (size_t k = 0; k < NNU; k++) {
            df_kelvinlet_brush b = grab(3, order, NUS[k], 0.25);
            df_kelvinlet_prepared p;
            df_error e;
            assert_int_equal(df_kelvinlet_prepare(&b, &p, &e), DF_OK);
            double u[3];
            assert_int_equal(df_kelvinlet_eval_ref(&p, b.centre, u, &e), DF_OK);
            for (int i = 0; i < 3; i++) {
                double rel = fabs(u[i] - b.tip[i]) / 0.14;
                worst = fmax(worst, rel);
                assert_true(rel < 1e-11);
            }
        }
    printf("# 3D tip: worst relative error over orders 1-8 x 7 nu: %.2e\n", worst);
}

static void test_tip_exact_2d_all_orders_and_nu(void **state)
{
    (void)state;
    double worst = 0.0;
    for (int order = 1; order <= DF_KELVINLET_MAX_ORDER; order++)
        for (size_t k = 0; k < NNU; k++) {
            df_kelvinlet_brush b = grab(2, order, NUS[k], 0.25);
            df_kelvinlet_prepared p;
            df_error e;
            assert_int_equal(df_kelvinlet_prepare(&b, &p, &e), DF_OK);
            double u[3];
            assert_int_equal(df_kelvinlet_eval_ref(&p, b.centre, u, &e), DF_OK);
            for (int i = 0; i < 2; i++) {
                double rel = fabs(u[i] - b.tip[i]) / 0.11;
                worst = fmax(worst, rel);
                assert_true(rel < 1e-10);
            }
            assert_true(u[2] == 0.0);   /* z untouched */
        }
    printf("# 2D tip: worst relative error over orders 1-8 x 7 nu: %.2e\n", worst);
}

static void test_weights_match_paper_and_vandermonde(void **state)
{
    (void)state;
    double eps[8], w[8];
    df_error e;
    assert_int_equal(df_kelvinlet_weights(2, 1.1, 0.5, eps, w, &e), DF_OK);
    assert_true(w[0] == 1.0 && w[1] == -1.0);
    assert_true(fabs(eps[1] - 0.55) < 1e-15);
    assert_int_equal(df_kelvinlet_weights(3, 1.1, 0.5, eps, w, &e), DF_OK);
    double e1 = eps[0] * eps[0], e2 = eps[1] * eps[1], e3 = eps[2] * eps[2];
    assert_true(fabs(w[1] + (e3 - e1) / (e3 - e2)) < 1e-12);
    assert_true(fabs(w[2] - (e2 - e1) / (e3 - e2)) < 1e-12);
    assert_true(fabs(eps[2] - 0.5 * 1.21) < 1e-15);
    /* n-scale: moments sum_i w_i (eps_i/eps_1)^(2k) vanish for k < n - 1, not for k = n - 1. */
    for (int n = 2; n <= 8; n++)
        for (int r = 0; r < 3; r++) {
            double ratio = (double[]){1.1, 1.5, 3.0}[r];
            assert_int_equal(df_kelvinlet_weights(n, ratio, 0.5, eps, w, &e), DF_OK);
            assert_true(w[0] == 1.0);
            for (int k = 0; k < n; k++) {
                double m = 0.0, scale = 0.0;
                for (int i = 0; i < n; i++) {
                    double t = w[i] * pow(eps[i] / eps[0], 2.0 * k);
                    m += t;
                    scale += fabs(t);
                }
                if (k < n - 1)
                    assert_true(fabs(m) < 1e-12 * scale);
                else
                    assert_true(fabs(m) > 1e-6 * scale);
            }
        }
}

/* Least-squares slope of log|u| against log r along a fixed direction,
 * r = r0 eps, 2 r0 eps, ... (n points). */
static double decay_slope(int dim, int order, double nu, double r0, int n)
{
    df_kelvinlet_brush b = grab(dim, order, nu, 0.1);
    df_kelvinlet_prepared p;
    assert_int_equal(df_kelvinlet_prepare(&b, &p, NULL), DF_OK);
    double dir[3] = {0.48, 0.6, dim == 3 ? 0.64 : 0.0};
    double len = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (int k = 0; k < n; k++) {
        double r = 0.1 * r0 * pow(2.0, k), x[3], u[3];
        for (int i = 0; i < 3; i++)
            x[i] = b.centre[i] + r * dir[i] / len;
        assert_int_equal(df_kelvinlet_eval_ref(&p, x, u, NULL), DF_OK);
        double lx = log(r), ly = log(sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]));
        sx += lx; sy += ly; sxx += lx * lx; sxy += lx * ly;
    }
    return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

static void test_far_field_decay_3d(void **state)
{
    (void)state;
    const double want[3] = {-1.0, -3.0, -5.0};
    for (int order = 1; order <= 3; order++)
        for (size_t k = 0; k < 5; k++) {
            double s = decay_slope(3, order, NUS[k], 32.0, 6);
            printf("# 3D order %d nu %g decay slope %.4f (want %.0f)\n", order,
                   NUS[k], s, want[order - 1]);
            assert_true(fabs(s - want[order - 1]) < 0.01);
        }
    /* nu = +-inf (b = 0): the eps^2 / r^3 terms of 1/r_eps and eps^2 / (2 r_eps^3) cancel, so
     * the radial-falloff grab already decays like r^-5 at bi-scale. */
    double si = decay_slope(3, 2, INFINITY, 32.0, 6);
    printf("# 3D order 2 nu inf decay slope %.4f (want -5)\n", si);
    assert_true(fabs(si + 5.0) < 0.01);
    /* n-scale keeps going: order 4 decays like r^-7. */
    double s4 = decay_slope(3, 4, 0.4, 16.0, 4);
    printf("# 3D order 4 decay slope %.4f (want -7)\n", s4);
    assert_true(fabs(s4 + 7.0) < 0.1);
}

static void test_far_field_decay_2d(void **state)
{
    (void)state;
    double s2 = decay_slope(2, 2, 0.4, 32.0, 6), s3 = decay_slope(2, 3, 0.4, 32.0, 6);
    printf("# 2D bi-scale slope %.4f (want -2), tri-scale %.4f (want -4)\n", s2, s3);
    assert_true(fabs(s2 + 2.0) < 0.01);
    assert_true(fabs(s3 + 4.0) < 0.01);
}

static void test_nu_infinite_is_radial_falloff(void **state)
{
    (void)state;
    /* b = 0: u(r) = (1/r_eps + eps^2 / (2 r_eps^3)) / (1.5 / eps) * tip, parallel to tip. */
    for (int sgn = -1; sgn <= 1; sgn += 2) {
        df_kelvinlet_brush b = grab(3, 1, sgn * INFINITY, 0.3);
        df_kelvinlet_prepared p;
        assert_int_equal(df_kelvinlet_prepare(&b, &p, NULL), DF_OK);
        double x[3] = {0.9, 0.1, 0.2}, u[3];
        assert_int_equal(df_kelvinlet_eval_ref(&p, x, u, NULL), DF_OK);
        double r2 = 0, e = 0.3;
        for (int i = 0; i < 3; i++)
            r2 += (x[i] - b.centre[i]) * (x[i] - b.centre[i]);
        double re = sqrt(r2 + e * e);
        double fall = (1.0 / re + e * e / (2.0 * re * re * re)) / (1.5 / e);
        for (int i = 0; i < 3; i++)
            assert_true(fabs(u[i] - fall * b.tip[i]) < 1e-14);
    }
}

static void test_2d_single_scale_singular_radius(void **state)
{
    (void)state;
    /* 2D single-scale tip map 2 (b - a) ln eps + a vanishes at eps = exp(a / (2 (a - b))). */
    double nu = 0.4, b = 1.0 / (4.0 * (1.0 - nu));
    df_kelvinlet_brush br = grab(2, 1, nu, exp(1.0 / (2.0 * (1.0 - b))));
    df_kelvinlet_prepared p;
    p.nsrc = 77;
    df_error e;
    assert_int_equal(df_kelvinlet_prepare(&br, &p, &e), DF_ESINGULAR);
    assert_true(p.nsrc == 77);
    assert_non_null(strstr(e.msg, "tip normalization"));
    /* bi-scale at the same radius is fine and exact */
    br.order = 2;
    assert_int_equal(df_kelvinlet_prepare(&br, &p, &e), DF_OK);
    double u[3];
    df_kelvinlet_eval_ref(&p, br.centre, u, NULL);
    assert_true(fabs(u[0] - br.tip[0]) < 1e-12 && fabs(u[1] - br.tip[1]) < 1e-12);
}

static void test_nu_changes_bulge_not_tip(void **state)
{
    (void)state;
    /* Off-axis response along the tip direction grows with nu (more bulging at 0.5). */
    double prev = -1.0;
    for (size_t k = 0; k < 5; k++) {
        df_kelvinlet_brush b = grab(3, 1, NUS[k], 0.2);
        b.tip[0] = 0.1; b.tip[1] = 0; b.tip[2] = 0;
        df_kelvinlet_prepared p;
        assert_int_equal(df_kelvinlet_prepare(&b, &p, NULL), DF_OK);
        double x[3] = {b.centre[0] + 0.3, b.centre[1], b.centre[2]}, u[3];
        df_kelvinlet_eval_ref(&p, x, u, NULL);
        assert_true(u[0] > prev);
        prev = u[0];
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tip_exact_3d_all_orders_and_nu),
        cmocka_unit_test(test_tip_exact_2d_all_orders_and_nu),
        cmocka_unit_test(test_weights_match_paper_and_vandermonde),
        cmocka_unit_test(test_far_field_decay_3d),
        cmocka_unit_test(test_far_field_decay_2d),
        cmocka_unit_test(test_nu_infinite_is_radial_falloff),
        cmocka_unit_test(test_2d_single_scale_singular_radius),
        cmocka_unit_test(test_nu_changes_bulge_not_tip),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
