/* Unit tests for core/kelvinlet constrained deformations (section 7): displacement and
 * gradient pins hold to 1e-9 while the live brush keeps its tip / centre gradient; the LU of
 * K_pp is cached (factorization counter) and invalidated only by pins / radius / nu / falloff;
 * duplicated or coincident pins are reported as singular. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>
#include <cblas.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "core/kelvinlet/kelvinlet.h"

/* n points on a Fibonacci sphere of radius R around (0, 0, 0). */
static double *sphere(size_t n, double R)
{
    double *p = malloc(3 * n * sizeof *p);
    assert_non_null(p);
    for (size_t i = 0; i < n; i++) {
        double z = 1.0 - (2.0 * i + 1.0) / n, r = sqrt(1.0 - z * z), a = 2.399963229728653 * i;
        p[3 * i] = R * r * cos(a);
        p[3 * i + 1] = R * r * sin(a);
        p[3 * i + 2] = R * z;
    }
    return p;
}

static df_kelvinlet_pins pins_of(const double *pts, size_t n, int flags, double nu)
{
    df_kelvinlet_pins p = {n, pts, flags, 0.12, 1.1, nu, 1, 0};
    return p;
}

static df_kelvinlet_brush live(df_kelvinlet_type t, double nu)
{
    df_kelvinlet_brush b;
    df_kelvinlet_brush_defaults(&b);
    b.type = t;
    b.order = 2;
    b.nu = nu;
    b.radius = 0.2;
    b.centre[0] = 0.62; b.centre[1] = 0.1; b.centre[2] = -0.05;
    b.tip[0] = -0.1; b.tip[1] = 0.04; b.tip[2] = 0.03;
    b.omega[0] = 0.2; b.omega[1] = -0.4; b.omega[2] = 0.3;
    return b;
}

static double max_pin_disp(const df_kelvinlet_prepared *f, const double *pts, size_t n)
{
    double m = 0.0;
    for (size_t i = 0; i < n; i++) {
        double u[3];
        assert_int_equal(df_kelvinlet_eval_ref(f, pts + 3 * i, u, NULL), DF_OK);
        for (int k = 0; k < 3; k++)
            m = fmax(m, fabs(u[k]));
    }
    return m;
}

static double max_pin_grad(const df_kelvinlet_prepared *f, const double *pts, size_t n)
{
    double m = 0.0;
    for (size_t i = 0; i < n; i++) {
        double g[9];
        assert_int_equal(df_kelvinlet_gradient_ref(f, pts + 3 * i, g, NULL), DF_OK);
        for (int k = 0; k < 9; k++)
            m = fmax(m, fabs(g[k]));
    }
    return m;
}

static void test_160_displacement_pins(void **state)
{
    (void)state;
    size_t n = 160;
    double *pts = sphere(n, 0.45);
    df_kelvinlet_pins pins = pins_of(pts, n, DF_KELVINLET_PIN_DISPLACEMENT, 0.5);
    df_kelvinlet_constraints *cs = NULL;
    df_error e;
    assert_int_equal(df_kelvinlet_constraints_create(&pins, &cs, &e), DF_OK);
    df_kelvinlet_brush b = live(DF_KELVINLET_GRAB, 0.5);
    df_kelvinlet_prepared f, free_b;
    assert_int_equal(df_kelvinlet_constraints_solve(cs, &b, &f, &e), DF_OK);
    assert_int_equal((int)f.nsrc, 161);
    double pin = max_pin_disp(&f, pts, n), u[3];
    df_kelvinlet_eval_ref(&f, b.centre, u, NULL);
    double tip = fmax(fabs(u[0] - b.tip[0]), fmax(fabs(u[1] - b.tip[1]), fabs(u[2] - b.tip[2])));
    /* without the pins they would move */
    assert_int_equal(df_kelvinlet_prepare(&b, &free_b, NULL), DF_OK);
    double unpinned = max_pin_disp(&free_b, pts, n);
    printf("# 160 pins: max |u(pin)| %.2e (unconstrained %.2e), tip error %.2e\n", pin, unpinned,
           tip);
    assert_true(pin < 1e-9);
    assert_true(tip < 1e-9);
    assert_true(unpinned > 1e-3);
    /* the float path keeps the pins still too */
    float fp[3 * 160];
    for (size_t i = 0; i < 3 * n; i++)
        fp[i] = (float)pts[i];
    assert_int_equal(df_kelvinlet_displacements(&f, fp, n, fp, &e), DF_OK);
    double fmaxd = 0.0;
    for (size_t i = 0; i < 3 * n; i++)
        fmaxd = fmax(fmaxd, fabs(fp[i]));
    printf("# float path: max |u(pin)| %.2e\n", fmaxd);
    assert_true(fmaxd < 1e-5);
    df_kelvinlet_prepared_free(&f);
    df_kelvinlet_constraints_free(cs);
    free(pts);
}

static void test_gradient_pins(void **state)
{
    (void)state;
    size_t n = 24;
    double *pts = sphere(n, 0.4);
    const double nus[] = {0.3, 0.5};
    const int flags[] = {DF_KELVINLET_PIN_GRADIENT,
                         DF_KELVINLET_PIN_GRADIENT | DF_KELVINLET_PIN_DISPLACEMENT};
    const df_kelvinlet_type types[] = {DF_KELVINLET_GRAB, DF_KELVINLET_TWIST, DF_KELVINLET_PINCH,
                                       DF_KELVINLET_AFFINE};
    for (int a = 0; a < 2; a++)
        for (int fl = 0; fl < 2; fl++) {
            df_kelvinlet_pins pins = pins_of(pts, n, flags[fl], nus[a]);
            df_kelvinlet_constraints *cs = NULL;
            df_error e;
            assert_int_equal(df_kelvinlet_constraints_create(&pins, &cs, &e), DF_OK);
            for (int t = 0; t < 4; t++) {
                df_kelvinlet_brush b = live(types[t], nus[a]);
                static const double PIN[9] = {0.2, 0.1, -0.05, 0.1, -0.15, 0.07, -0.05, 0.07, -0.05};
                memcpy(b.grad, PIN, sizeof PIN);
                if (types[t] == DF_KELVINLET_AFFINE)
                    b.grad[1] = 0.3;      /* non-symmetric, traceless (nu = 0.5 allows it) */
                df_kelvinlet_prepared f;
                assert_int_equal(df_kelvinlet_constraints_solve(cs, &b, &f, &e), DF_OK);
                double g = max_pin_grad(&f, pts, n);
                double d = (flags[fl] & DF_KELVINLET_PIN_DISPLACEMENT) ? max_pin_disp(&f, pts, n)
                                                                       : 0.0;
                double G[9], err = 0.0;
                df_kelvinlet_gradient_ref(&f, b.centre, G, NULL);
                if (types[t] == DF_KELVINLET_GRAB) {
                    double u[3];
                    df_kelvinlet_eval_ref(&f, b.centre, u, NULL);
                    for (int i = 0; i < 3; i++)
                        err = fmax(err, fabs(u[i] - b.tip[i]));
                } else if (types[t] == DF_KELVINLET_TWIST) {
                    /* the skew part is the requested rotation */
                    err = fmax(fabs(0.5 * (G[7] - G[5]) - b.omega[0]),
                               fmax(fabs(0.5 * (G[2] - G[6]) - b.omega[1]),
                                    fabs(0.5 * (G[3] - G[1]) - b.omega[2])));
                } else if (types[t] == DF_KELVINLET_PINCH) {
                    for (int i = 0; i < 3; i++)
                        for (int j = 0; j < 3; j++) {
                            double sym = 0.5 * (G[3 * i + j] + G[3 * j + i]);
                            double tr = (G[0] + G[4] + G[8]) / 3.0;
                            err = fmax(err, fabs(sym - (i == j ? tr : 0.0) - b.grad[3 * i + j]));
                        }
                } else {
                    for (int i = 0; i < 9; i++)
                        err = fmax(err, fabs(G[i] - b.grad[i]));
                }
                printf("# nu %.1f flags %d live type %d: max |grad u(pin)| %.1e, |u(pin)| %.1e, "
                       "live error %.1e\n", nus[a], flags[fl], (int)types[t], g, d, err);
                assert_true(g < 1e-9 && d < 1e-9 && err < 1e-9);
                df_kelvinlet_prepared_free(&f);
            }
            assert_int_equal((int)df_kelvinlet_constraints_factorizations(cs), 1);
            df_kelvinlet_constraints_free(cs);
        }
    free(pts);
}

static void test_cache_counts_and_invalidation(void **state)
{
    (void)state;
    size_t n = 40;
    double *pts = sphere(n, 0.5);
    df_kelvinlet_pins pins = pins_of(pts, n, DF_KELVINLET_PIN_DISPLACEMENT, 0.4);
    df_kelvinlet_constraints *cs = NULL;
    df_error e;
    assert_int_equal(df_kelvinlet_constraints_create(&pins, &cs, &e), DF_OK);
    assert_int_equal((int)df_kelvinlet_constraints_factorizations(cs), 1);
    df_kelvinlet_brush b = live(DF_KELVINLET_GRAB, 0.4);
    df_kelvinlet_prepared f;
    for (int k = 0; k < 5; k++) {          /* new tips, new centres, other live kernels */
        b.tip[0] = 0.02 * k;
        b.centre[1] = 0.1 + 0.01 * k;
        b.order = 1 + k % 3;
        b.nu = k == 4 ? 0.1 : 0.4;
        assert_int_equal(df_kelvinlet_constraints_solve(cs, &b, &f, &e), DF_OK);
        df_kelvinlet_prepared_free(&f);
    }
    assert_int_equal(df_kelvinlet_constraints_update(cs, &pins, &e), DF_OK);   /* same set */
    assert_int_equal((int)df_kelvinlet_constraints_factorizations(cs), 1);
    pins.radius = 0.13;
    assert_int_equal(df_kelvinlet_constraints_update(cs, &pins, &e), DF_OK);
    assert_int_equal((int)df_kelvinlet_constraints_factorizations(cs), 2);
    pins.nu = 0.45;
    assert_int_equal(df_kelvinlet_constraints_update(cs, &pins, &e), DF_OK);
    assert_int_equal((int)df_kelvinlet_constraints_factorizations(cs), 3);
    pins.order = 2;
    assert_int_equal(df_kelvinlet_constraints_update(cs, &pins, &e), DF_OK);
    assert_int_equal((int)df_kelvinlet_constraints_factorizations(cs), 4);
    pins.ratio = 1.3;
    assert_int_equal(df_kelvinlet_constraints_update(cs, &pins, &e), DF_OK);
    assert_int_equal((int)df_kelvinlet_constraints_factorizations(cs), 5);
    pts[7] += 0.01;
    assert_int_equal(df_kelvinlet_constraints_update(cs, &pins, &e), DF_OK);
    assert_int_equal((int)df_kelvinlet_constraints_factorizations(cs), 6);
    /* the new set is in force */
    b.tip[0] = 0.1;
    assert_int_equal(df_kelvinlet_constraints_solve(cs, &b, &f, &e), DF_OK);
    assert_true(max_pin_disp(&f, pts, n) < 1e-9);
    df_kelvinlet_prepared_free(&f);
    /* a failed update (duplicate pin) keeps the previous state */
    double saved[3] = {pts[3], pts[4], pts[5]};
    pts[3] = pts[0]; pts[4] = pts[1]; pts[5] = pts[2];
    assert_int_equal(df_kelvinlet_constraints_update(cs, &pins, &e), DF_ESINGULAR);
    assert_non_null(strstr(e.msg, "coincide"));
    pts[3] = saved[0]; pts[4] = saved[1]; pts[5] = saved[2];
    assert_int_equal(df_kelvinlet_constraints_solve(cs, &b, &f, &e), DF_OK);
    assert_true(max_pin_disp(&f, pts, n) < 1e-9);
    df_kelvinlet_prepared_free(&f);
    assert_int_equal((int)df_kelvinlet_constraints_factorizations(cs), 6);
    df_kelvinlet_constraints_free(cs);
    free(pts);
}

static void test_singular_and_unsupported(void **state)
{
    (void)state;
    double pts[9] = {0, 0, 0, 0.3, 0, 0, 0.3, 0, 1e-12};
    df_kelvinlet_pins pins = pins_of(pts, 3, DF_KELVINLET_PIN_DISPLACEMENT, 0.4);
    df_kelvinlet_constraints *cs = (df_kelvinlet_constraints *)&pins;   /* sentinel */
    df_error e;
    assert_int_equal(df_kelvinlet_constraints_create(&pins, &cs, &e), DF_ESINGULAR);
    assert_ptr_equal(cs, (df_kelvinlet_constraints *)&pins);
    printf("# duplicate pins: %s\n", e.msg);
    pts[8] = 1e-8;           /* distinct but numerically coincident for radius 0.12 */
    assert_int_equal(df_kelvinlet_constraints_create(&pins, &cs, &e), DF_ESINGULAR);
    printf("# near-coincident pins: %s\n", e.msg);
    pts[8] = 0.2;
    assert_int_equal(df_kelvinlet_constraints_create(&pins, &cs, &e), DF_OK);
    df_kelvinlet_brush b = live(DF_KELVINLET_GRAB, 0.4);
    df_kelvinlet_prepared f;
    f.nsrc = 5;
    b.centre[0] = 0.3; b.centre[1] = 0; b.centre[2] = 0;   /* on pin 1 */
    assert_int_equal(df_kelvinlet_constraints_solve(cs, &b, &f, &e), DF_ESINGULAR);
    b = live(DF_KELVINLET_GRAB, 0.4);
    b.dim = 2;
    assert_int_equal(df_kelvinlet_constraints_solve(cs, &b, &f, &e), DF_EUNSUPPORTED);
    b.dim = 3;
    b.moving = 1;
    assert_int_equal(df_kelvinlet_constraints_solve(cs, &b, &f, &e), DF_EUNSUPPORTED);
    b.moving = 0;
    b.tip[1] = NAN;
    assert_int_equal(df_kelvinlet_constraints_solve(cs, &b, &f, &e), DF_EINVAL);
    assert_int_equal((int)f.nsrc, 5);
    df_kelvinlet_constraints_free(cs);
    /* bad pin sets */
    pins.flags = 0;
    assert_int_equal(df_kelvinlet_constraints_create(&pins, &cs, &e), DF_EINVAL);
    pins.flags = DF_KELVINLET_PIN_DISPLACEMENT;
    pins.n = 0;
    assert_int_equal(df_kelvinlet_constraints_create(&pins, &cs, &e), DF_EINVAL);
    pins.n = DF_KELVINLET_MAX_PINS + 1;
    assert_int_equal(df_kelvinlet_constraints_create(&pins, &cs, &e), DF_ELIMIT);
    pins.n = 3;
    pts[4] = INFINITY;
    assert_int_equal(df_kelvinlet_constraints_create(&pins, &cs, &e), DF_EINVAL);
    pts[4] = 0.0;
    pins.radius = -1.0;
    assert_int_equal(df_kelvinlet_constraints_create(&pins, &cs, &e), DF_EINVAL);
}

/* pins.threads: the K_pp assembly on 1 thread (and on 2) gives the loads of the default team bit
 * for bit, and the call leaves the OpenMP settings (thread count, dynamic adjustment) and the
 * OpenBLAS thread count alone
 * (the LU runs with OpenBLAS on one thread and restores the count, also on a refused set). */
static void test_pin_threads_do_not_change_bits(void **state)
{
    (void)state;
    size_t n = 160;
    double *pts = sphere(n, 0.45);
    df_kelvinlet_brush b = live(DF_KELVINLET_GRAB, 0.4);
    df_kelvinlet_prepared ref, f;
    df_kelvinlet_constraints *cs = NULL;
    df_kelvinlet_pins pins = pins_of(pts, n, DF_KELVINLET_PIN_DISPLACEMENT, 0.4);
    assert_int_equal(df_kelvinlet_constraints_create(&pins, &cs, NULL), DF_OK);
    assert_int_equal(df_kelvinlet_constraints_solve(cs, &b, &ref, NULL), DF_OK);
    df_kelvinlet_constraints_free(cs);
#ifdef _OPENMP
    int nt = omp_get_max_threads();
    omp_set_dynamic(0);   /* create enables dynamic adjustment for its own call only */
#endif
    openblas_set_num_threads(2);
    int nb = openblas_get_num_threads();
    for (int threads = 1; threads <= 2; threads++) {
        pins.threads = threads;
        assert_int_equal(df_kelvinlet_constraints_create(&pins, &cs, NULL), DF_OK);
        assert_int_equal(df_kelvinlet_constraints_solve(cs, &b, &f, NULL), DF_OK);
        assert_int_equal(f.nsrc, ref.nsrc);
        assert_memory_equal(f.ext, ref.ext, ref.nsrc * sizeof *ref.ext);
#ifdef _OPENMP
        assert_int_equal(omp_get_max_threads(), nt);
        assert_int_equal(omp_get_dynamic(), 0);
#endif
        assert_int_equal(openblas_get_num_threads(), nb);
        df_kelvinlet_prepared_free(&f);
        df_kelvinlet_constraints_free(cs);
    }
    memcpy(pts + 3, pts, 3 * sizeof *pts);                /* two coincident pins */
    assert_int_equal(df_kelvinlet_constraints_create(&pins, &cs, NULL), DF_ESINGULAR);
    assert_int_equal(openblas_get_num_threads(), nb);
    df_kelvinlet_prepared_free(&ref);
    free(pts);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_160_displacement_pins),
        cmocka_unit_test(test_gradient_pins),
        cmocka_unit_test(test_cache_counts_and_invalidation),
        cmocka_unit_test(test_singular_and_unsupported),
        cmocka_unit_test(test_pin_threads_do_not_change_bits),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
