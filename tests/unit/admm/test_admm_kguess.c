/* Unit tests of the Kelvinlet initial guess of a handle move (core/kelvinlet/kelvinlet_guess.h)
 * and of seeding ADMM with it (df_admm_set_positions): on the tet bar of admm_test_util.h (the
 * x = 0 face fixed, the x = 3 face moved), the fitted field reaches the handles' displacements
 * to 1e-9 before the snap and the guess puts them exactly on their targets; ADMM started from
 * the guess reaches the objective of the plain start within the solver tolerance in no more
 * iterations; bad input is refused with the output untouched. */
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include "core/admm/admm.h"
#include "core/kelvinlet/kelvinlet_guess.h"
#include "tests/unit/admm/admm_test_util.h"

#define TOL 1e-12

static void test_guess_reaches_targets(void **state)
{
    (void)state;
    tu_bar bh = tu_bar_load();
    double *G = malloc(3 * (size_t)bh.m.nv * sizeof *G), fit = -1, rad = -1;
    df_error err;
    assert_int_equal(df_kelvinlet_guess(bh.m.V, bh.m.nv, bh.h, bh.nh, bh.tg,
                                        0.0, 0.5, G, &fit, &rad, &err), DF_OK);
    assert_true(fit >= 0 && fit < 1e-9);
    assert_true(rad == df_kelvinlet_guess_radius(bh.m.V, bh.m.nv, bh.h, bh.nh) && rad > 0);
    for (int k = 0; k < bh.nh; k++)
        assert_true(tu_dist(G + 3 * (size_t)bh.h[k], bh.tg + 3 * k) <= 1e-9);
    /* the field moves the free vertices next to the moved face, and less at mid-bar */
    double near = 0, mid = 0;
    for (int32_t i = 0; i < bh.m.nv; i++) {
        double d = tu_dist(G + 3 * (size_t)i, bh.m.V + 3 * (size_t)i), x = bh.m.V[3 * (size_t)i];
        if (fabs(x - 2.5) < 1e-12) near = fmax(near, d);
        if (fabs(x - 1.5) < 1e-12) mid = fmax(mid, d);
    }
    assert_true(near > 1e-3);
    assert_true(mid < near);
    free(G); tu_bar_free(&bh);
}

static df_admm *make(const df_mesh *m, const int32_t *h, int nh, const double *tg)
{
    df_admm_params p;
    df_admm_params_default(&p, DF_ADMM_ARAP);
    p.threads = 1;
    p.w = 1e-3;
    p.s = 0.01;
    p.rho = 0.2;
    p.tol = TOL;
    p.max_iters = 20000;
    df_admm *s = NULL;
    df_error err;
    assert_int_equal(df_admm_create(m, &p, h, nh, NULL, 0, &s, &err), DF_OK);
    assert_int_equal(df_admm_set_targets(s, tg, &err), DF_OK);
    return s;
}

static void test_admm_from_guess(void **state)
{
    (void)state;
    tu_bar bh = tu_bar_load();
    df_error err;
    df_admm_result plain, seeded;
    df_admm *a = make(&bh.m, bh.h, bh.nh, bh.tg), *b = make(&bh.m, bh.h, bh.nh, bh.tg);
    assert_int_equal(df_admm_run(a, NULL, &plain, &err), DF_OK);
    double *G = malloc(3 * (size_t)bh.m.nv * sizeof *G);
    assert_int_equal(df_kelvinlet_guess(df_admm_positions(b), bh.m.nv, bh.h, bh.nh, bh.tg, 0.0, 0.5, G, NULL,
                                        NULL, &err), DF_OK);
    assert_int_equal(df_admm_set_positions(b, G, NULL, &err), DF_OK);
    assert_int_equal(df_admm_run(b, NULL, &seeded, &err), DF_OK);
    print_message("plain %d iterations E %.12g, guess %d iterations E %.12g\n", plain.iterations,
                  plain.objective, seeded.iterations, seeded.objective);
    assert_true(plain.converged && seeded.converged);
    assert_true(fabs(seeded.objective - plain.objective) / (plain.objective + 1.0) < 1e3 * TOL);
    assert_true(seeded.iterations <= plain.iterations);
    assert_true(tu_handles_on_target(df_admm_positions(b), &bh, 1e-9));
    df_admm_free(a); df_admm_free(b);
    free(G); tu_bar_free(&bh);
}

static void test_bad_input(void **state)
{
    (void)state;
    tu_bar bh = tu_bar_load();
    size_t n = 3 * (size_t)bh.m.nv;
    double *G = malloc(n * sizeof *G);
    for (size_t i = 0; i < n; i++) G[i] = -7.0;
    df_error err;
    int32_t keep = bh.h[1];
    bh.h[1] = bh.h[0]; /* repeated handle */
    assert_int_equal(df_kelvinlet_guess(bh.m.V, bh.m.nv, bh.h, bh.nh, bh.tg,
                                        0.0, 0.5, G, NULL, NULL, &err), DF_EINVAL);
    bh.h[1] = bh.m.nv; /* out of range */
    assert_int_equal(df_kelvinlet_guess(bh.m.V, bh.m.nv, bh.h, bh.nh, bh.tg,
                                        0.0, 0.5, G, NULL, NULL, &err), DF_EINVAL);
    bh.h[1] = keep;
    double t0 = bh.tg[4];
    bh.tg[4] = NAN;
    assert_int_equal(df_kelvinlet_guess(bh.m.V, bh.m.nv, bh.h, bh.nh, bh.tg,
                                        0.0, 0.5, G, NULL, NULL, &err), DF_EINVAL);
    bh.tg[4] = t0;
    assert_int_equal(df_kelvinlet_guess(bh.m.V, bh.m.nv, bh.h, bh.nh, bh.tg,
                                        0.0, 0.7, G, NULL, NULL, &err), DF_EINVAL);
    assert_int_equal(df_kelvinlet_guess(NULL, bh.m.nv, bh.h, bh.nh, bh.tg,
                                        0.0, 0.5, G, NULL, NULL, &err), DF_EINVAL);
    assert_int_equal(df_kelvinlet_guess(bh.m.V, bh.m.nv, bh.h, 0, bh.tg,
                                        0.0, 0.5, G, NULL, NULL, &err), DF_EINVAL);
    for (size_t i = 0; i < n; i++) assert_true(G[i] == -7.0);
    free(G); tu_bar_free(&bh);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_guess_reaches_targets),
        cmocka_unit_test(test_admm_from_guess),
        cmocka_unit_test(test_bad_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
