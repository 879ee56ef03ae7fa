/* Unit tests for the vectorized float32 kernels of every falloff order (issue 14 item 6):
 * orders 4-8 (double sums inside SIMD loops) and the 2D path (vectorized double sums and
 * logarithm) agree with the double reference to float rounding for every brush type, give
 * bit-identical displacements on 1 and 2 threads (the server's stroke replay relies on it),
 * and a point's result does not depend on its SIMD lane or block (evaluated alone or among
 * 10k others: same bits). */
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

#define NPTS 10007   /* not a multiple of any SIMD width or block */

static float *points(int dim)
{
    float *x = malloc(3 * NPTS * sizeof *x);
    assert_non_null(x);
    for (size_t k = 0; k < NPTS; k++) {
        double r = 1.6 * (double)k / NPTS;     /* from the centre out to ~6 radii */
        x[3 * k] = (float)(0.1 + r * sin(1.3 * (double)k));
        x[3 * k + 1] = (float)(-0.05 + r * cos(0.7 * (double)k));
        x[3 * k + 2] = dim == 3 ? (float)(0.02 + r * sin(0.31 * (double)k)) : 0.0f;
    }
    return x;
}

/* Every type, dimension and order: float vs double within 1e-6 of max |u|, 1 vs 2 threads
 * bit-identical, and the first and last points evaluated alone give the batch's bits. */
static void check(int dim, double ratio, double nu)
{
    float *x = points(dim), *d1 = malloc(3 * NPTS * sizeof *d1), *d2 = malloc(3 * NPTS * sizeof *d2);
    assert_non_null(d1);
    assert_non_null(d2);
    for (int t = DF_KELVINLET_GRAB; t <= DF_KELVINLET_AFFINE; t++)
        for (int order = 1; order <= DF_KELVINLET_MAX_ORDER; order++) {
            if (t == DF_KELVINLET_SCALE && nu == 0.5)
                continue;   /* singular by design */
            df_kelvinlet_brush b = tk_brush(t, dim, order, ratio, nu, 0.25);
            df_kelvinlet_prepared p;
            df_error e;
            if (df_kelvinlet_prepare(&b, &p, &e) != DF_OK)
                fail_msg("dim %d type %d order %d: %s", dim, t, order, e.msg);
            p.threads = 1;
            assert_int_equal(df_kelvinlet_displacements(&p, x, NPTS, d1, &e), DF_OK);
            p.threads = 2;
            assert_int_equal(df_kelvinlet_displacements(&p, x, NPTS, d2, &e), DF_OK);
            if (memcmp(d1, d2, 3 * NPTS * sizeof *d1) != 0)
                fail_msg("dim %d type %d order %d: 1 and 2 threads differ", dim, t, order);
            const size_t one[2] = {0, NPTS - 1};
            for (int k = 0; k < 2; k++) {
                float a[3];
                assert_int_equal(df_kelvinlet_displacements(&p, x + 3 * one[k], 1, a, &e), DF_OK);
                if (memcmp(a, d1 + 3 * one[k], sizeof a) != 0)
                    fail_msg("dim %d type %d order %d: point %zu alone differs", dim, t, order,
                             one[k]);
            }
            double worst = 0.0, umax = 0.0;
            for (size_t k = 0; k < NPTS; k++) {
                double xd[3] = {x[3 * k], x[3 * k + 1], x[3 * k + 2]}, u[3];
                assert_int_equal(df_kelvinlet_eval_ref(&p, xd, u, &e), DF_OK);
                for (int i = 0; i < 3; i++) {
                    worst = fmax(worst, fabs(d1[3 * k + i] - u[i]));
                    umax = fmax(umax, fabs(u[i]));
                }
                if (dim == 2)
                    assert_true(d1[3 * k + 2] == 0.0f);
            }
            if (!(worst <= 1e-6 * umax))
                fail_msg("dim %d type %d order %d ratio %g nu %g: max |float - double| = %.2e "
                         "of max |u|", dim, t, order, ratio, nu, worst / umax);
        }
    free(x);
    free(d1);
    free(d2);
}

static void test_3d_every_order(void **state)
{
    (void)state;
    check(3, 1.1, 0.3);
    check(3, 1.5, 0.5);
}

static void test_2d_every_order(void **state)
{
    (void)state;
    check(2, 1.1, 0.3);
    check(2, 1.5, 0.5);
    check(2, 2.0, INFINITY);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_3d_every_order),
        cmocka_unit_test(test_2d_every_order),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
