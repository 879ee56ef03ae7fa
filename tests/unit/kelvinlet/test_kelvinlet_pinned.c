/* Unit tests for the float32 evaluation of constrained (pinned) fields, the path a pinned brush
 * stroke runs in the daemon and in its replay (issue 14 item 6): every pin load is evaluated
 * at every point, so for random pin sets, several pin radii, falloff orders and pin kinds
 * (displacement, gradient, both) the float field is within the brush path's float error of
 * the double reference (2e-6 of max |u|, kelvinlet.h), the pins stay still to that tolerance,
 * 1 and 2 threads give the same bits, and a point's value does not depend on which block or
 * SIMD lane it falls in (the same point alone gives the same bits). */
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

#define NPIN 48
#define NPTS 6007       /* not a multiple of any SIMD width or block */
#define TOL 2e-6        /* of max |u|: the float path's error bound stated in kelvinlet.h */

static uint64_t rng = 0x9e3779b97f4a7c15ull;

static double urand(void)   /* [0, 1) */
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (double)(rng >> 11) * 0x1.0p-53;
}

/* NPIN random pins in the cube [-0.5, 0.5]^3 at least 1.5 radii apart (K_pp well conditioned). */
static void random_pins(double *pts, double radius)
{
    for (int i = 0; i < NPIN;) {
        double p[3] = {urand() - 0.5, urand() - 0.5, urand() - 0.5};
        int ok = 1;
        for (int j = 0; j < i && ok; j++) {
            double d = 0.0;
            for (int k = 0; k < 3; k++)
                d += (p[k] - pts[3 * j + k]) * (p[k] - pts[3 * j + k]);
            ok = sqrt(d) >= 1.5 * radius;
        }
        if (ok) {
            memcpy(pts + 3 * i, p, sizeof p);
            i++;
        }
    }
}

/* Points: every pin, points just beside the pins (within a pin radius) and the rest random in
 * a box a little larger than the pins'. */
static float *points(const double *pins, double radius)
{
    float *x = malloc(3 * NPTS * sizeof *x);
    assert_non_null(x);
    for (int i = 0; i < NPTS; i++)
        for (int k = 0; k < 3; k++) {
            double v;
            if (i < NPIN)
                v = pins[3 * i + k];
            else if (i < 4 * NPIN)
                v = pins[3 * (i % NPIN) + k] + radius * (urand() - 0.5);
            else
                v = 1.4 * (urand() - 0.5);
            x[3 * i + k] = (float)v;
        }
    return x;
}

static void check_case(int flags, int order, double radius, double nu)
{
    double pins_xyz[3 * NPIN];
    random_pins(pins_xyz, radius);
    df_kelvinlet_pins pins = {NPIN, pins_xyz, flags, radius, 1.2, nu, order, 0};
    df_kelvinlet_constraints *cs = NULL;
    df_error e;
    if (df_kelvinlet_constraints_create(&pins, &cs, &e) != DF_OK)
        fail_msg("flags %d order %d radius %g: %s", flags, order, radius, e.msg);
    df_kelvinlet_brush b;
    df_kelvinlet_brush_defaults(&b);
    b.order = 2;
    b.radius = 0.3;
    b.nu = nu;
    b.centre[0] = 0.61;
    b.centre[1] = -0.07;
    b.centre[2] = 0.13;
    b.tip[0] = -0.08;
    b.tip[1] = 0.05;
    b.tip[2] = 0.02;
    df_kelvinlet_prepared f;
    if (df_kelvinlet_constraints_solve(cs, &b, &f, &e) != DF_OK)
        fail_msg("solve: %s", e.msg);
    float *x = points(pins_xyz, radius);
    float *u1 = malloc(3 * NPTS * sizeof *u1), *u2 = malloc(3 * NPTS * sizeof *u2);
    assert_non_null(u1);
    assert_non_null(u2);
    f.threads = 1;
    assert_int_equal(df_kelvinlet_displacements(&f, x, NPTS, u1, &e), DF_OK);
    f.threads = 2;
    assert_int_equal(df_kelvinlet_displacements(&f, x, NPTS, u2, &e), DF_OK);
    if (memcmp(u1, u2, 3 * NPTS * sizeof *u1) != 0)
        fail_msg("flags %d order %d radius %g: 1 and 2 threads differ", flags, order, radius);
    /* the double reference, independently at every point */
    double umax = 0.0, dmax = 0.0, pinmax = 0.0;
    for (int i = 0; i < NPTS; i++) {
        double xi[3] = {x[3 * i], x[3 * i + 1], x[3 * i + 2]}, ur[3];
        assert_int_equal(df_kelvinlet_eval_ref(&f, xi, ur, NULL), DF_OK);
        for (int k = 0; k < 3; k++) {
            umax = fmax(umax, fabs(ur[k]));
            dmax = fmax(dmax, fabs((double)u1[3 * i + k] - ur[k]));
            if (i < NPIN && (flags & DF_KELVINLET_PIN_DISPLACEMENT))
                pinmax = fmax(pinmax, fabs((double)u1[3 * i + k]));
        }
    }
    printf("# flags %d order %d radius %.2f nu %.1f: max|u| %.3e, float error %.2e of it, "
           "pins %.2e of it\n", flags, order, radius, nu, umax, dmax / umax, pinmax / umax);
    assert_true(umax > 1e-3);
    if (dmax > TOL * umax)
        fail_msg("float error %.3e of max |u| above %.0e", dmax / umax, TOL);
    if (pinmax > TOL * umax)
        fail_msg("pins move by %.3e of max |u|", pinmax / umax);
    /* one point alone (first lane of its own block) gives the bits it got among the others */
    for (int i = 0; i < NPTS; i += 613) {
        float one[3];
        f.threads = 1;
        assert_int_equal(df_kelvinlet_displacements(&f, x + 3 * i, 1, one, &e), DF_OK);
        assert_memory_equal(one, u1 + 3 * i, sizeof one);
    }
    free(x);
    free(u1);
    free(u2);
    df_kelvinlet_prepared_free(&f);
    df_kelvinlet_constraints_free(cs);
}

static void test_displacement_pins(void **state)
{
    (void)state;
    static const int orders[] = {1, 2, 3, 5};
    static const double radii[] = {0.04, 0.1};
    for (size_t o = 0; o < sizeof orders / sizeof *orders; o++)
        for (size_t r = 0; r < sizeof radii / sizeof *radii; r++)
            check_case(DF_KELVINLET_PIN_DISPLACEMENT, orders[o], radii[r], 0.4);
}

static void test_gradient_and_both(void **state)
{
    (void)state;
    check_case(DF_KELVINLET_PIN_GRADIENT, 1, 0.06, 0.3);
    check_case(DF_KELVINLET_PIN_GRADIENT, 3, 0.06, 0.5);
    check_case(DF_KELVINLET_PIN_DISPLACEMENT | DF_KELVINLET_PIN_GRADIENT, 2, 0.08, 0.4);
    check_case(DF_KELVINLET_PIN_DISPLACEMENT | DF_KELVINLET_PIN_GRADIENT, 4, 0.05, 0.5);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_displacement_pins),
        cmocka_unit_test(test_gradient_and_both),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
