/* Unit tests for df_admm_run's scale-invariant stop test (admm.h, DF_ADMM_RESIDUAL): the same
 * problem in metres and in millimetres-as-metres (every length times 1e-3, energies ~1e-6 of the
 * unscaled ones) stops at the same relative distance from the optimum; the old absolute test
 * |E_k - E_k-1| / (E_k + 1) < tol, replayed on the scaled run's objectives, stops far from it. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include "core/admm/admm.h"
#include "tests/unit/admm/admm_test_util.h"

#define SCALE 1e-3
#define MAXIT 20000

/* planar ARAP strip 12 x 3 over [0, 2L] x [0, L/2]: left column fixed, right column lifted by 0.3 L,
 * with the objective recorded at every iteration (for the old stop test's replay) */
typedef struct trace {
    double *E;
    int n;
} trace;

static int record(void *user, const df_admm_progress *pr)
{
    trace *t = user;
    if (t->n < MAXIT) t->E[t->n++] = pr->objective;
    return 0;
}

/* runs the strip scaled by c (lengths; w scaled by c and s by c so that the objective scales by c^2
 * exactly, rho unchanged) with tolerance tol; returns the result, *tr the objectives */
static df_admm_result run_strip(double c, double tol, trace *tr)
{
    df_mesh m = tu_grid2d(12, 3, 2.0 * c, 0.5 * c);
    int32_t h[8];
    double tg[24];
    int nh = 0;
    for (int j = 0; j <= 3; j++) {
        int32_t l = j * 13, r = j * 13 + 12;
        h[nh] = l; memcpy(tg + 3 * nh, m.V + 3 * l, 24); nh++;
        h[nh] = r; memcpy(tg + 3 * nh, m.V + 3 * r, 24); tg[3 * nh + 1] += 0.3 * c; nh++;
    }
    df_admm_params p;
    df_admm_params_default(&p, DF_ADMM_ARAP);
    p.threads = 1;
    p.w = 1e-2 * c; p.s = 0.05 * c; p.rho = 0.5; p.tol = tol; p.max_iters = MAXIT;
    df_admm *s = NULL;
    df_error err;
    assert_int_equal(df_admm_create(&m, &p, h, nh, NULL, 0, &s, &err), DF_OK);
    assert_int_equal(df_admm_set_targets(s, tg, &err), DF_OK);
    df_admm_result r;
    df_admm_budget b = {0, 0, tr ? 1 : 0, tr ? record : NULL, tr};
    assert_int_equal(df_admm_run(s, &b, &r, &err), DF_OK);
    df_admm_free(s);
    tu_free(&m);
    return r;
}

static void test_scaled_mesh_reaches_the_optimum(void **st)
{
    (void)st;
    /* the optimum: the unscaled problem run for MAXIT iterations with no early stop */
    df_admm_result ref = run_strip(1.0, 0.0, NULL);
    assert_int_equal(ref.iterations, MAXIT);
    double Eopt = ref.objective;
    assert_true(Eopt > 0 && isfinite(Eopt));
    /* the unscaled run with the default tolerance stops early, close to the optimum */
    df_admm_params d;
    df_admm_params_default(&d, DF_ADMM_ARAP);
    df_admm_result un = run_strip(1.0, d.tol, NULL);
    /* the scaled run with the default tolerance */
    trace tr = {calloc(MAXIT, sizeof(double)), 0};
    assert_non_null(tr.E);
    df_admm_result sc = run_strip(SCALE, d.tol, &tr);
    double c2 = SCALE * SCALE;
    double rel_un = (un.objective - Eopt) / Eopt, rel_sc = (sc.objective / c2 - Eopt) / Eopt;
    /* the old test replayed on the scaled run's objectives */
    int old_it = 0;
    for (int k = 1; k < tr.n; k++)
        if (fabs(tr.E[k] - tr.E[k - 1]) / (tr.E[k] + 1.0) < d.tol) { old_it = k + 1; break; }
    assert_true(old_it > 0);
    double rel_old = (tr.E[old_it - 1] / c2 - Eopt) / Eopt;
    printf("optimum E %.12g (%d its); unscaled: %d its, %.2e above; scaled by %g (E %.3g): %d its, %.2e above; "
           "old test on the scaled run: %d its, %.2e above\n", Eopt, ref.iterations, un.iterations, rel_un, SCALE,
           sc.objective, sc.iterations, rel_sc, old_it, rel_old);
    assert_true(un.converged && un.stop == DF_ADMM_STOP_CONVERGED && un.iterations < MAXIT);
    assert_true(sc.converged && sc.stop == DF_ADMM_STOP_CONVERGED && sc.iterations < MAXIT);
    assert_true(sc.residual < d.tol);
    assert_true(fabs(rel_un) <= 1e-6);
    assert_true(fabs(rel_sc) <= 1e-6);
    /* scale invariance: the scaled run stops within a few iterations of the unscaled one */
    assert_true(abs(sc.iterations - un.iterations) <= un.iterations / 20 + 2);
    /* the old test stopped the scaled run early, far from the optimum */
    assert_true(old_it < sc.iterations);
    assert_true(rel_old > 1e-6);
    free(tr.E);
}

/* tol 0 never stops early; the residual is still reported (finite once the duals are nonzero) */
static void test_tol_zero_runs_the_budget(void **st)
{
    (void)st;
    df_admm_result r = run_strip(1.0, 0.0, NULL);
    assert_int_equal(r.iterations, MAXIT);
    assert_false(r.converged);
    assert_int_equal(r.stop, DF_ADMM_STOP_ITERS);
    assert_true(r.residual >= 0);
}

/* ACAP on an 8 x 8 grid, left column fixed, top-right corner moved by (0.3, -0.2): nearly every
 * vertex moves beyond s, where the SC-L1 term is flat, so the scaled duals U vanish; the run
 * reaches an exact fixed point (the objective unchanged to 1e-15). The dual residual relative to
 * ||U|| alone was round-off over round-off there (the run went to its cap at residual 9.4e-6);
 * relative to max(||U||, ||Z||) it stops, at the fixed point's objective. */
static df_admm_result run_acap_grid(double tol, double *frac_beyond_s)
{
    df_mesh g = tu_grid2d(8, 8, 1.0, 1.0);
    int32_t h[16];
    double tg[48];
    int nh = 0;
    for (int32_t i = 0; i < g.nv; i++) {
        double x = g.V[3 * i], y = g.V[3 * i + 1];
        if (x == 0 || (x == 1.0 && y == 1.0)) {
            h[nh] = i;
            memcpy(tg + 3 * nh, g.V + 3 * i, 24);
            if (x == 1.0) { tg[3 * nh] += 0.3; tg[3 * nh + 1] -= 0.2; }
            nh++;
        }
    }
    df_admm_params p;
    df_admm_params_default(&p, DF_ADMM_ACAP);
    p.threads = 1;
    p.rho = 0.1; /* fixed: the stop test, not the adaptive penalty, is under test */
    p.tol = tol;
    df_admm *s = NULL;
    df_error err;
    assert_int_equal(df_admm_create(&g, &p, h, nh, NULL, 0, &s, &err), DF_OK);
    assert_int_equal(df_admm_set_targets(s, tg, &err), DF_OK);
    df_admm_result r;
    assert_int_equal(df_admm_run(s, &(df_admm_budget){3000, 0, 0, NULL, NULL}, &r, &err), DF_OK);
    const double *V = df_admm_positions(s);
    int beyond = 0;
    for (int32_t i = 0; i < g.nv; i++) {
        int handle = 0;
        for (int k = 0; k < nh; k++) handle |= h[k] == i;
        beyond += !handle && tu_dist(V + 3 * i, g.V + 3 * i) > p.s;
    }
    *frac_beyond_s = (double)beyond / (g.nv - nh);
    df_admm_free(s);
    tu_free(&g);
    return r;
}

static void test_flat_locality_fixed_point_stops(void **st)
{
    (void)st;
    double f0, f1;
    df_admm_result ref = run_acap_grid(0.0, &f0);
    df_admm_params d;
    df_admm_params_default(&d, DF_ADMM_ACAP);
    df_admm_result r = run_acap_grid(d.tol, &f1);
    printf("ACAP grid: %.0f%% of the free vertices beyond s; reference E %.15g (%d its), default tol: %d its, "
           "E %.15g, residual %.2e\n", 100 * f1, ref.objective, ref.iterations, r.iterations, r.objective, r.residual);
    assert_true(f1 > 0.9); /* the premise: the locality term is flat almost everywhere */
    assert_true(r.converged && r.stop == DF_ADMM_STOP_CONVERGED);
    assert_true(r.iterations < 3000);
    assert_true(fabs(r.objective - ref.objective) <= 1e-9 * ref.objective);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_scaled_mesh_reaches_the_optimum),
        cmocka_unit_test(test_tol_zero_runs_the_budget),
        cmocka_unit_test(test_flat_locality_fixed_point_stops),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
