/* Unit tests of the line-searched seed of a handle move (core/admm/admm_seed.h) on the tet bar
 * of admm_test_util.h (the x = 0 face fixed, the x = 3 face moved), with the Kelvinlet guess
 * (core/kelvinlet/kelvinlet_guess.h) as the proposal: alpha = 0 is the plain start bit for bit
 * (a proposal that does not lower the objective is refused, and the run from it equals the plain
 * run); the searched shrink starts no higher than two of its candidates given alone; the chosen
 * start's objective, recomputed here with df_admm_evaluate, is no higher than
 * that of the rest state with the handles on their targets; the start is the soft-thresholded
 * proposal scaled by alpha, recomputed here from the proposal; the run from the seed reaches the
 * plain start's converged objective; Neo-Hookean with an inverted plain start takes alpha 1 or
 * nothing; bad input is refused with the solver unchanged. */
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "core/admm/admm.h"
#include "core/admm/admm_seed.h"
#include "core/kelvinlet/kelvinlet_guess.h"
#include "tests/unit/admm/admm_test_util.h"

#define TOL 1e-12

static df_admm *make(const tu_bar *bh)
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
    assert_int_equal(df_admm_create(&bh->m, &p, bh->h, bh->nh, NULL, 0, &s, &err), DF_OK);
    assert_int_equal(df_admm_set_targets(s, bh->tg, &err), DF_OK);
    return s;
}

/* the objective of V (elastic + locality) */
static double objective(const df_admm *s, const double *V)
{
    double el = NAN, lo = NAN;
    df_error err;
    assert_int_equal(df_admm_evaluate(s, V, &el, &lo, &err), DF_OK);
    return el + lo;
}

/* the Kelvinlet guess of the bar's move from V0 (malloc'd) */
static double *guess(const tu_bar *bh, const double *V0)
{
    double *G = malloc(3 * (size_t)bh->m.nv * sizeof *G);
    df_error err;
    assert_non_null(G);
    assert_int_equal(df_kelvinlet_guess(V0, bh->m.nv, bh->h, bh->nh, bh->tg, 0.0, 0.5, G, NULL, NULL,
                                        &err), DF_OK);
    return G;
}

static int is_handle(const tu_bar *bh, int32_t i)
{
    for (int k = 0; k < bh->nh; k++)
        if (bh->h[k] == i) return k;
    return -1;
}

/* A proposal that only raises the objective (the free vertices thrown 30 bar lengths about) and
 * one equal to the start (every alpha gives the same objective, none lower): alpha 0, and 40
 * iterations from there are bitwise those of the plain start. */
static void test_alpha_zero_is_the_plain_start(void **state)
{
    (void)state;
    tu_bar bh = tu_bar_load();
    size_t n = 3 * (size_t)bh.m.nv;
    double *V0 = malloc(n * sizeof *V0), *G = malloc(n * sizeof *G), *X = malloc(n * sizeof *X);
    memcpy(V0, bh.m.V, n * sizeof *V0);
    for (size_t i = 0; i < n; i++) G[i] = V0[i] + 90.0 * sin(7.0 * (double)i + 1.0);
    df_error err;
    /* seed_point at alpha 0: V0 with the handles on their targets */
    df_admm *probe = make(&bh);
    assert_int_equal(df_admm_seed_point(probe, V0, G, 0.0, X, &err), DF_OK);
    for (int32_t i = 0; i < bh.m.nv; i++) {
        int k = is_handle(&bh, i);
        assert_memory_equal(X + 3 * (size_t)i, k >= 0 ? bh.tg + 3 * k : V0 + 3 * (size_t)i, 3 * sizeof(double));
    }
    df_admm_free(probe);
    df_admm_budget b = {40, 0, 0, NULL, NULL};
    df_admm_result rp, rs;
    df_admm *a = make(&bh);
    assert_int_equal(df_admm_set_positions(a, V0, NULL, &err), DF_OK);
    assert_int_equal(df_admm_run(a, &b, &rp, &err), DF_OK);
    for (int pass = 0; pass < 2; pass++) {
        if (pass == 1) memcpy(G, V0, n * sizeof *G);
        df_admm *s = make(&bh);
        df_admm_seed_report rep;
        assert_int_equal(df_admm_seed(s, V0, G, pass ? 0.0 : DF_ADMM_SEED_SHRINK_AUTO, &rep, &err), DF_OK);
        assert_true(rep.alpha == 0.0);
        assert_true(rep.e_seed == rep.e_plain);
        assert_memory_equal(df_admm_positions(s), V0, n * sizeof *V0);
        assert_int_equal(df_admm_run(s, &b, &rs, &err), DF_OK);
        assert_memory_equal(df_admm_positions(s), df_admm_positions(a), n * sizeof *V0);
        assert_true(rs.objective == rp.objective);
        df_admm_free(s);
    }
    df_admm_free(a);
    free(V0); free(G); free(X); tu_bar_free(&bh);
}

/* The Kelvinlet guess on the bar, shrink 0 and the default: the start is X(alpha) of the
 * soft-thresholded proposal (recomputed here), its objective is the reported one and no higher
 * than the rest state's with the handles on target (both recomputed with df_admm_evaluate). */
static void test_seed_objective_not_above_the_rest_state(void **state)
{
    (void)state;
    tu_bar bh = tu_bar_load();
    size_t n = 3 * (size_t)bh.m.nv;
    double *V0 = malloc(n * sizeof *V0), *X0 = malloc(n * sizeof *X0);
    memcpy(V0, bh.m.V, n * sizeof *V0);
    memcpy(X0, V0, n * sizeof *X0);
    double dmax = 0;
    for (int k = 0; k < bh.nh; k++) {
        memcpy(X0 + 3 * (size_t)bh.h[k], bh.tg + 3 * k, 3 * sizeof(double));
        dmax = fmax(dmax, tu_dist(bh.tg + 3 * k, V0 + 3 * (size_t)bh.h[k]));
    }
    double *G = guess(&bh, V0);
    /* 0.1 and 0.3 are AUTO candidates (0.5 k / 10); 0 (the unrestricted field) is not */
    const double shrinks[4] = {0.0, 0.1, 0.3, DF_ADMM_SEED_SHRINK_AUTO};
    double e_fixed = INFINITY;
    for (int c = 0; c < 4; c++) {
        df_admm *s = make(&bh);
        df_admm_seed_report rep;
        df_error err;
        double e_rest = objective(s, X0);
        assert_int_equal(df_admm_seed(s, V0, G, shrinks[c], &rep, &err), DF_OK);
        print_message("shrink %g: used %g, alpha %.4f, start E %.9g, rest state E %.9g, alpha 1 E %.9g, "
                      "%d evaluations\n", shrinks[c], rep.shrink, rep.alpha, rep.e_seed, rep.e_plain, rep.e_one,
                      rep.evaluations);
        if (shrinks[c] >= 0) assert_true(rep.shrink == shrinks[c]);
        if (shrinks[c] > 0) e_fixed = fmin(e_fixed, rep.e_seed);
        if (shrinks[c] < 0) assert_true(rep.e_seed <= e_fixed && rep.shrink > 0); /* min over both */
        assert_true(fabs(rep.e_plain - e_rest) <= 1e-12 * e_rest);
        assert_true(rep.alpha > 0.0 && rep.alpha <= 1.0); /* the guess helps on the bar */
        const double *V = df_admm_positions(s);
        double e_start = objective(s, V);
        assert_true(fabs(rep.e_seed - e_start) <= 1e-12 * e_start);
        assert_true(e_start <= e_rest);
        assert_true(fabs(rep.tau - rep.shrink * dmax) <= 1e-15 * dmax);
        for (int32_t i = 0; i < bh.m.nv; i++) {
            int k = is_handle(&bh, i);
            const double *x = V + 3 * (size_t)i, *x0 = V0 + 3 * (size_t)i, *g = G + 3 * (size_t)i;
            if (k >= 0) {
                assert_memory_equal(x, bh.tg + 3 * k, 3 * sizeof(double));
                continue;
            }
            double m = tu_dist(g, x0);
            double f = rep.tau == 0.0 ? 1.0 : m > rep.tau ? (m - rep.tau) / m * dmax / (dmax - rep.tau) : 0.0;
            for (int d = 0; d < 3; d++)
                assert_true(fabs(x[d] - (x0[d] + rep.alpha * f * (g[d] - x0[d]))) <= 1e-14);
        }
        df_admm_free(s);
    }
    free(V0); free(X0); free(G); tu_bar_free(&bh);
}

/* From the seed (default shrink) the run converges to the plain start's objective. */
static void test_seeded_run_reaches_the_plain_objective(void **state)
{
    (void)state;
    tu_bar bh = tu_bar_load();
    df_error err;
    df_admm_result plain, seeded;
    df_admm *a = make(&bh), *b = make(&bh);
    assert_int_equal(df_admm_run(a, NULL, &plain, &err), DF_OK);
    double *G = guess(&bh, bh.m.V);
    df_admm_seed_report rep;
    assert_int_equal(df_admm_seed(b, bh.m.V, G, DF_ADMM_SEED_SHRINK_AUTO, &rep, &err), DF_OK);
    assert_int_equal(df_admm_run(b, NULL, &seeded, &err), DF_OK);
    print_message("plain %d iterations E %.12g, seeded (alpha %.3f) %d iterations E %.12g\n", plain.iterations,
                  plain.objective, rep.alpha, seeded.iterations, seeded.objective);
    assert_true(plain.converged && seeded.converged);
    assert_true(seeded.objective <= plain.objective * (1.0 + 1e3 * TOL));
    assert_true(tu_handles_on_target(df_admm_positions(b), &bh, 1e-9));
    df_admm_free(a); df_admm_free(b);
    free(G); tu_bar_free(&bh);
}

/* Neo-Hookean on the bar with the x = 3 face pushed by -0.6 in x as well, past the next vertex layer
 * at x = 2.5: the plain start with the handles on target inverts (+inf), so the candidates are
 * the alpha-1 points of the restricted fields (recomputed here): the lowest uninverted one, or
 * the plain start when every one inverts. */
static void test_neohookean_without_a_finite_reference(void **state)
{
    (void)state;
    tu_bar bh = tu_bar_load();
    for (int k = 0; k < bh.nh; k++)
        if (bh.m.V[3 * (size_t)bh.h[k]] == 3.0) bh.tg[3 * k] -= 0.6;
    size_t n = 3 * (size_t)bh.m.nv;
    df_admm_params p;
    df_admm_params_default(&p, DF_ADMM_NEOHOOKEAN);
    p.threads = 1;
    df_admm *s = NULL;
    df_error err;
    assert_int_equal(df_admm_create(&bh.m, &p, bh.h, bh.nh, NULL, 0, &s, &err), DF_OK);
    assert_int_equal(df_admm_set_targets(s, bh.tg, &err), DF_OK);
    double *G = guess(&bh, bh.m.V), *Y = malloc(n * sizeof *Y), e_g = INFINITY, dmax = 0;
    for (int k = 0; k < bh.nh; k++) dmax = fmax(dmax, tu_dist(bh.tg + 3 * k, bh.m.V + 3 * (size_t)bh.h[k]));
    for (int k = 1; k <= DF_ADMM_SEED_SHRINK_STEPS; k++) { /* the alpha-1 candidates, recomputed */
        double tau = DF_ADMM_SEED_SHRINK_MAX * k / DF_ADMM_SEED_SHRINK_STEPS * dmax, el, lo;
        for (int32_t i = 0; i < bh.m.nv; i++) {
            const double *g = G + 3 * (size_t)i, *x = bh.m.V + 3 * (size_t)i;
            double m = tu_dist(g, x), f = m > tau ? (m - tau) / m * dmax / (dmax - tau) : 0.0;
            for (int d = 0; d < 3; d++) Y[3 * (size_t)i + d] = x[d] + f * (g[d] - x[d]);
        }
        for (int h = 0; h < bh.nh; h++) memcpy(Y + 3 * (size_t)bh.h[h], bh.tg + 3 * h, 3 * sizeof(double));
        if (df_admm_evaluate(s, Y, &el, &lo, &err) == DF_OK) e_g = fmin(e_g, el + lo);
    }
    df_admm_seed_report rep;
    assert_int_equal(df_admm_seed(s, bh.m.V, G, DF_ADMM_SEED_SHRINK_AUTO, &rep, &err), DF_OK);
    print_message("NH: plain start E %g, best candidate E %g; alpha %g shrink %g start E %g, %d evaluations\n",
                  rep.e_plain, e_g, rep.alpha, rep.shrink, rep.e_seed, rep.evaluations);
    assert_false(isfinite(rep.e_plain));
    assert_int_equal(rep.evaluations, 1 + DF_ADMM_SEED_SHRINK_STEPS);
    if (isfinite(e_g)) {
        assert_true(rep.alpha == 1.0 && rep.shrink > 0);
        assert_true(fabs(rep.e_seed - e_g) <= 1e-12 * e_g);
        assert_true(fabs(objective(s, df_admm_positions(s)) - e_g) <= 1e-12 * e_g);
    } else {
        assert_true(rep.alpha == 0.0);
        assert_memory_equal(df_admm_positions(s), bh.m.V, n * sizeof(double));
    }
    df_admm_free(s);
    free(G); free(Y); tu_bar_free(&bh);
}

static void test_bad_input(void **state)
{
    (void)state;
    tu_bar bh = tu_bar_load();
    size_t n = 3 * (size_t)bh.m.nv;
    df_admm *s = make(&bh);
    double *G = guess(&bh, bh.m.V), *before = malloc(n * sizeof *before), *X = malloc(n * sizeof *X);
    memcpy(before, df_admm_positions(s), n * sizeof *before);
    df_error err;
    df_admm_seed_report rep = {-1, -1, -1, -1, -1, -1, -1};
    assert_int_equal(df_admm_seed(NULL, bh.m.V, G, 0.0, &rep, &err), DF_EINVAL);
    assert_int_equal(df_admm_seed(s, NULL, G, 0.0, &rep, &err), DF_EINVAL);
    assert_int_equal(df_admm_seed(s, bh.m.V, NULL, 0.0, &rep, &err), DF_EINVAL);
    assert_int_equal(df_admm_seed(s, bh.m.V, G, -0.1, &rep, &err), DF_EINVAL);
    assert_non_null(strstr(err.msg, "shrink"));
    assert_int_equal(df_admm_seed(s, bh.m.V, G, DF_ADMM_SEED_SHRINK_MAX + 0.01, &rep, &err), DF_EINVAL);
    assert_int_equal(df_admm_seed(s, bh.m.V, G, -0.5, &rep, &err), DF_EINVAL);
    assert_int_equal(df_admm_seed(s, bh.m.V, G, NAN, &rep, &err), DF_EINVAL);
    G[7] = NAN;
    assert_int_equal(df_admm_seed(s, bh.m.V, G, 0.0, &rep, &err), DF_EINVAL);
    assert_non_null(strstr(err.msg, "proposal"));
    assert_int_equal(df_admm_seed_point(s, bh.m.V, G, INFINITY, X, &err), DF_EINVAL);
    assert_int_equal(df_admm_seed_point(s, bh.m.V, G, 0.5, NULL, &err), DF_EINVAL);
    assert_true(rep.alpha == -1 && rep.evaluations == -1);
    assert_memory_equal(df_admm_positions(s), before, n * sizeof *before);
    df_admm_free(s);
    free(G); free(before); free(X); tu_bar_free(&bh);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_alpha_zero_is_the_plain_start),
        cmocka_unit_test(test_seed_objective_not_above_the_rest_state),
        cmocka_unit_test(test_seeded_run_reaches_the_plain_objective),
        cmocka_unit_test(test_neohookean_without_a_finite_reference),
        cmocka_unit_test(test_bad_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
