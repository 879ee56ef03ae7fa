/* Unit tests for core/kelvinlet symmetrized brushes (eq. 21-22): u(Mx) = M u(x) to rounding for
 * grab / twist / pinch / affine, single and multi-scale, 3D and 2D; the mirrored grab keeps the
 * tip exact; a grab centred on the plane moves along it and cannot cross it. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "core/kelvinlet/kelvinlet.h"

static const double GEN[9] = {0.12, -0.3, 0.05, 0.2, -0.07, 0.11, -0.04, 0.09, 0.16};
static const double PIN[9] = {0.2, 0.1, -0.05, 0.1, -0.15, 0.07, -0.05, 0.07, -0.05};

static df_kelvinlet_brush mirrored(df_kelvinlet_type t, int dim, int order)
{
    df_kelvinlet_brush b;
    df_kelvinlet_brush_defaults(&b);
    b.type = t;
    b.dim = dim;
    b.order = order;
    b.nu = 0.45;
    b.radius = 0.15;
    b.centre[0] = 0.35; b.centre[1] = 0.1; b.centre[2] = dim == 3 ? -0.2 : 0.5;
    b.tip[0] = 0.04; b.tip[1] = 0.09; b.tip[2] = -0.03;
    b.omega[0] = 0.2; b.omega[1] = 0.5; b.omega[2] = -0.3;
    memcpy(b.grad, t == DF_KELVINLET_PINCH ? PIN : GEN, sizeof b.grad);
    if (dim == 2 && t == DF_KELVINLET_PINCH)
        b.grad[4] = -b.grad[0];
    b.mirror = 1;
    b.mirror_point[0] = 0.05; b.mirror_point[1] = -0.02; b.mirror_point[2] = 0.1;
    b.mirror_normal[0] = 2.0; b.mirror_normal[1] = 0.6; b.mirror_normal[2] = dim == 3 ? -0.9 : 0.0;
    return b;
}

static void reflect(const df_kelvinlet_brush *b, const double *x, double *y, int point)
{
    const double *n = b->mirror_normal, *c = b->mirror_point;
    double l2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2], d = 0.0, v[3];
    for (int i = 0; i < 3; i++) {
        v[i] = point ? x[i] - c[i] : x[i];
        d += v[i] * n[i];
    }
    for (int i = 0; i < 3; i++)
        y[i] = (point ? c[i] : 0.0) + v[i] - 2.0 * d * n[i] / l2;
}

static void test_symmetrized_identity(void **state)
{
    (void)state;
    double worst = 0.0;
    for (int dim = 2; dim <= 3; dim++)
        for (int t = DF_KELVINLET_GRAB; t <= DF_KELVINLET_AFFINE; t++)
            for (int order = 1; order <= 3; order++) {
                df_kelvinlet_brush b = mirrored((df_kelvinlet_type)t, dim, order);
                if (dim == 2 && order == 1 && t == DF_KELVINLET_GRAB)
                    b.radius = 0.15;
                df_kelvinlet_prepared p;
                df_error e;
                assert_int_equal(df_kelvinlet_prepare(&b, &p, &e), DF_OK);
                assert_int_equal((int)p.nsrc, 2);
                double umax = 0.0, dmax = 0.0;
                for (int q = 0; q < 40; q++) {
                    double x[3] = {0.4 * sin(1.7 * q), 0.5 * cos(0.9 * q), 0.3 * sin(q + 0.3)};
                    double mx[3], u[3], um[3], mu[3];
                    reflect(&b, x, mx, 1);
                    if (dim == 2)
                        mx[2] = x[2];
                    assert_int_equal(df_kelvinlet_eval_ref(&p, x, u, NULL), DF_OK);
                    assert_int_equal(df_kelvinlet_eval_ref(&p, mx, um, NULL), DF_OK);
                    reflect(&b, u, mu, 0);
                    for (int i = 0; i < 3; i++) {
                        umax = fmax(umax, fabs(u[i]));
                        dmax = fmax(dmax, fabs(um[i] - mu[i]));
                    }
                }
                worst = fmax(worst, dmax / umax);
                if (dmax > 1e-12 * umax)
                    printf("# dim %d type %d order %d: %.3e\n", dim, t, order, dmax / umax);
                assert_true(dmax <= 1e-12 * umax);   /* tri-scale cancels ~6 bits */
            }
    printf("# u(Mx) = M u(x): worst relative deviation %.2e over 30 brushes x 40 points\n",
           worst);
}

static void test_mirrored_grab_tip_exact(void **state)
{
    (void)state;
    for (int dim = 2; dim <= 3; dim++)
        for (int order = 1; order <= 3; order++) {
            df_kelvinlet_brush b = mirrored(DF_KELVINLET_GRAB, dim, order);
            df_kelvinlet_prepared p;
            assert_int_equal(df_kelvinlet_prepare(&b, &p, NULL), DF_OK);
            double u[3];
            df_kelvinlet_eval_ref(&p, b.centre, u, NULL);
            for (int i = 0; i < dim; i++)
                assert_true(fabs(u[i] - b.tip[i]) < 1e-13);
            /* the image centre moves by M tip */
            double mc[3], mt[3], ui[3];
            reflect(&b, b.centre, mc, 1);
            reflect(&b, b.tip, mt, 0);
            if (dim == 2) {
                mc[2] = b.centre[2];
                mt[2] = 0.0;
            }
            df_kelvinlet_eval_ref(&p, mc, ui, NULL);
            for (int i = 0; i < dim; i++)
                assert_true(fabs(ui[i] - mt[i]) < 1e-13);
        }
}

static void test_grab_centred_on_plane(void **state)
{
    (void)state;
    df_kelvinlet_brush b = mirrored(DF_KELVINLET_GRAB, 3, 3);
    b.mirror_normal[0] = 0; b.mirror_normal[1] = 0; b.mirror_normal[2] = 1;
    b.mirror_point[2] = b.centre[2];
    b.tip[2] = 0.0;                        /* along the plane: fine and exact */
    df_kelvinlet_prepared p;
    df_error e;
    assert_int_equal(df_kelvinlet_prepare(&b, &p, &e), DF_OK);
    double u[3];
    df_kelvinlet_eval_ref(&p, b.centre, u, NULL);
    for (int i = 0; i < 3; i++)
        assert_true(fabs(u[i] - b.tip[i]) < 1e-13);
    b.tip[2] = 0.01;                       /* across the plane: impossible for a symmetric field */
    p.nsrc = 9;
    assert_int_equal(df_kelvinlet_prepare(&b, &p, &e), DF_ESINGULAR);
    assert_int_equal((int)p.nsrc, 9);
    assert_non_null(strstr(e.msg, "mirror plane"));
}

static void test_mirror_normal_checks(void **state)
{
    (void)state;
    df_kelvinlet_brush b = mirrored(DF_KELVINLET_TWIST, 3, 1);
    df_kelvinlet_prepared p;
    df_error e;
    b.mirror_normal[0] = b.mirror_normal[1] = b.mirror_normal[2] = 0.0;
    assert_int_equal(df_kelvinlet_prepare(&b, &p, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "zero length"));
    b = mirrored(DF_KELVINLET_GRAB, 2, 2);
    b.mirror_normal[2] = 0.5;              /* a 2D mirror must be a line of the plane */
    assert_int_equal(df_kelvinlet_prepare(&b, &p, &e), DF_EINVAL);
    b.mirror = 2;
    assert_int_equal(df_kelvinlet_prepare(&b, &p, &e), DF_EINVAL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_symmetrized_identity),
        cmocka_unit_test(test_mirrored_grab_tip_exact),
        cmocka_unit_test(test_grab_centred_on_plane),
        cmocka_unit_test(test_mirror_normal_checks),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
