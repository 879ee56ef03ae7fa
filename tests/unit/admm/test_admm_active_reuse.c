/* Unit tests of the active-set run's reuse paths (core/admm/admm_active_run.c): the F_e(V) buffer
 * the dual update leaves for the next local step and the lazy elastic energy (summed only when
 * something needs it) must give bitwise the same iterates, objectives and stop residuals as
 * gathering F_e and summing the energy in every iteration. The reference is the same solver run so
 * that the reuse cannot happen: one-iteration runs (every run's first iteration gathers) and a
 * progress report every iteration (which needs the energy every iteration). And the element sums
 * threaded with their terms summed in element order (admm_active_elem.c) against one thread.
 * Scene: active_scene.h's tet grid, bottom face pinned, a 3 x 3 top patch dragged up. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include "core/admm/admm.h"
#include "core/admm/admm_active.h" /* ACT_PAR_HEAVY, ACT_PAR_LIGHT */
#include "tests/unit/admm/admm_test_util.h"
#include "tests/unit/admm/active_scene.h"


/* the active run keeps each element's F_e(V) from its dual update for the next iteration's local
 * step (G = F + W); every run's first iteration gathers F_e from V itself. So 20 runs of one
 * iteration (no reuse) and one run of 20 (reuse in 19) must give bitwise the same positions,
 * objective and stop residual, when both take the same region decisions: the far-field check
 * after every iteration (active_check_every 1: also what a one-iteration run does at its end) and
 * a region that does not grow during the compared iterations (checked). ARAP and Neo-Hookean (its
 * local step also starts from G). */
static void split_vs_one_run(df_admm_energy en)
{
    scene sc;
    tet_scene(&sc, 10);
    df_admm_params p = arap_params(&sc, 1);
    if (en == DF_ADMM_NEOHOOKEAN) { /* as test_tet_neohookean_equals_full */
        df_admm_params_default(&p, DF_ADMM_NEOHOOKEAN);
        double h = sc.hsp, E = p.youngs, nu = p.poisson;
        double stiff = E / (2 * (1 + nu)) + E * nu / ((1 + nu) * (1 - 2 * nu));
        p.w = 1.0 * h * h * stiff;
        p.s = 0.25 * h;
        p.rho = 10.0 * h * stiff;
        p.tol = 1e-13;
        p.threads = 1;
        p.active = 1;
    }
    p.active_band = 6;
    p.active_check_every = 1;
    df_admm *split = make(&sc, &p), *one = make(&sc, &p);
    /* the same first update on both builds their regions */
    set_drag(split, &sc, 0.3);
    set_drag(one, &sc, 0.3);
    df_admm_result r = run(split, 20), r1 = run(one, 20);
    assert_memory_equal(df_admm_positions(split), df_admm_positions(one), (size_t)sc.m.nv * 3 * sizeof(double));
    df_admm_active_stats a0, b0, a1, b1;
    df_admm_get_active_stats(split, &a0);
    df_admm_get_active_stats(one, &b0);
    set_drag(split, &sc, 0.45);
    set_drag(one, &sc, 0.45);
    for (int k = 0; k < 20; k++) {
        r = run(split, 1);
        assert_int_equal(r.iterations, 1);
    }
    r1 = run(one, 20);
    assert_int_equal(r1.iterations, 20);
    df_admm_get_active_stats(split, &a1);
    df_admm_get_active_stats(one, &b1);
    assert_int_equal(a1.grows + a1.rebuilds, a0.grows + a0.rebuilds);
    assert_int_equal(b1.grows + b1.rebuilds, b0.grows + b0.rebuilds);
    assert_int_equal(a1.fallbacks, 0);
    assert_int_equal(b1.fallbacks, 0);
    assert_true(count_moved(one, &sc.m) > 0);
    assert_memory_equal(df_admm_positions(split), df_admm_positions(one), (size_t)sc.m.nv * 3 * sizeof(double));
    assert_memory_equal(&r.objective, &r1.objective, sizeof(double));
    assert_memory_equal(&r.elastic, &r1.elastic, sizeof(double));
    assert_memory_equal(&r.residual, &r1.residual, sizeof(double));
    df_admm_free(split);
    df_admm_free(one);
    scene_free(&sc);
}

/* progress callback of test_lazy_energy_matches_eager: counts the reports */
static int count_reports(void *user, const df_admm_progress *p)
{
    (void)p;
    (*(int *)user)++;
    return 0;
}

/* The active run sums the elastic energy of an iteration only when something needs it (the stop
 * test when it can pass, a progress report, the tail test when the locality alone does not decide
 * it, a region growth, the last iteration); a progress report every iteration needs it in every
 * iteration. The same drag with and without reports must give bitwise the same positions,
 * objectives, stop residuals and region decisions (tail test on, so it grows the region). */
static void lazy_vs_eager(df_admm_energy en)
{
    scene sc;
    tet_scene(&sc, 16);
    df_admm_params p = arap_params(&sc, 1);
    p.energy = en;
    p.active_tail = DF_ADMM_ACTIVE_TAIL;
    df_admm *eager = make(&sc, &p), *lazy = make(&sc, &p);
    int reports = 0;
    for (int k = 1; k <= 4; k++) {
        set_drag(eager, &sc, 0.3 * k);
        set_drag(lazy, &sc, 0.3 * k);
        df_admm_budget be = {.max_iters = 20, .progress_every = 1, .progress = count_reports, .user = &reports};
        df_admm_result re, rl;
        df_error err;
        int before = reports;
        assert_int_equal(df_admm_run(eager, &be, &re, &err), DF_OK);
        assert_int_equal(reports - before, 20);
        rl = run(lazy, 20);
        assert_int_equal(re.iterations, rl.iterations);
        assert_memory_equal(df_admm_positions(eager), df_admm_positions(lazy), (size_t)sc.m.nv * 3 * sizeof(double));
        assert_memory_equal(&re.objective, &rl.objective, sizeof(double));
        assert_memory_equal(&re.elastic, &rl.elastic, sizeof(double));
        assert_memory_equal(&re.locality, &rl.locality, sizeof(double));
        assert_memory_equal(&re.residual, &rl.residual, sizeof(double));
    }
    df_admm_active_stats se, sl;
    df_admm_get_active_stats(eager, &se);
    df_admm_get_active_stats(lazy, &sl);
    assert_true(sl.tail_grows > 0);
    assert_int_equal(sl.fallbacks, 0);
    assert_int_equal(se.fallbacks, 0);
    assert_int_equal(se.tail_grows, sl.tail_grows);
    assert_int_equal(se.grows, sl.grows);
    assert_int_equal(se.region_vertices, sl.region_vertices);
    if (en == DF_ADMM_ARAP) { /* converged: the stop test passes at the same iteration (ACAP takes
                                 too long here) */
        df_admm_budget be = {.max_iters = 20000, .progress_every = 1, .progress = count_reports, .user = &reports};
        df_admm_result re, rl;
        df_error err;
        assert_int_equal(df_admm_run(eager, &be, &re, &err), DF_OK);
        rl = run(lazy, 20000);
        assert_true(re.converged);
        assert_true(rl.converged);
        assert_int_equal(re.iterations, rl.iterations);
        assert_memory_equal(&re.objective, &rl.objective, sizeof(double));
        assert_memory_equal(&re.residual, &rl.residual, sizeof(double));
        assert_memory_equal(df_admm_positions(eager), df_admm_positions(lazy), (size_t)sc.m.nv * 3 * sizeof(double));
    }
    df_admm_free(eager);
    df_admm_free(lazy);
    scene_free(&sc);
}

/* Regions of ACT_PAR_HEAVY to ACT_PAR_LIGHT elements run their element loops that end in sums
 * (dual update, elastic energy) on the team with the terms summed afterwards in element order
 * (admm_active_elem.c): 2 threads must give bitwise the positions, objectives, stop residuals and
 * region decisions of 1 thread, with the lazy energy and with a report every iteration (the
 * energy summed in every dual update). A drag of 4 updates with the tail test (it grows the
 * region; the region's size in that range checked). */
static void threads_vs_one(df_admm_energy en)
{
    scene sc;
    tet_scene(&sc, 16);
    df_admm_params p = arap_params(&sc, 1);
    p.energy = en;
    p.active_tail = DF_ADMM_ACTIVE_TAIL;
    p.threads = 1;
    df_admm *one = make(&sc, &p);
    p.threads = 2;
    df_admm *lazy = make(&sc, &p), *eager = make(&sc, &p);
    int reports = 0;
    for (int k = 1; k <= 4; k++) {
        set_drag(one, &sc, 0.3 * k);
        set_drag(lazy, &sc, 0.3 * k);
        set_drag(eager, &sc, 0.3 * k);
        df_admm_budget be = {.max_iters = 20, .progress_every = 1, .progress = count_reports, .user = &reports};
        df_admm_result r1, rl, re;
        df_error err;
        r1 = run(one, 20);
        rl = run(lazy, 20);
        assert_int_equal(df_admm_run(eager, &be, &re, &err), DF_OK);
        const df_admm_result *two[2] = {&rl, &re};
        const df_admm *s2[2] = {lazy, eager};
        for (int j = 0; j < 2; j++) {
            assert_int_equal(two[j]->iterations, r1.iterations);
            assert_memory_equal(df_admm_positions(s2[j]), df_admm_positions(one), (size_t)sc.m.nv * 3 * sizeof(double));
            assert_memory_equal(&two[j]->objective, &r1.objective, sizeof(double));
            assert_memory_equal(&two[j]->elastic, &r1.elastic, sizeof(double));
            assert_memory_equal(&two[j]->residual, &r1.residual, sizeof(double));
        }
    }
    assert_true(reports > 0);
    df_admm_active_stats s1, sl, se;
    df_admm_get_active_stats(one, &s1);
    df_admm_get_active_stats(lazy, &sl);
    df_admm_get_active_stats(eager, &se);
    assert_true(sl.region_elements >= ACT_PAR_HEAVY);
    assert_true(sl.region_elements < ACT_PAR_LIGHT);
    assert_true(sl.tail_grows > 0);
    assert_int_equal(sl.fallbacks, 0);
    assert_int_equal(sl.grows, s1.grows);
    assert_int_equal(se.grows, s1.grows);
    assert_int_equal(sl.region_vertices, s1.region_vertices);
    assert_int_equal(se.region_vertices, s1.region_vertices);
    df_admm_free(one);
    df_admm_free(lazy);
    df_admm_free(eager);
    scene_free(&sc);
}

static void test_threads_equal_one_thread_arap(void **state)
{
    (void)state;
    threads_vs_one(DF_ADMM_ARAP);
}

static void test_threads_equal_one_thread_acap(void **state)
{
    (void)state;
    threads_vs_one(DF_ADMM_ACAP);
}

static void test_lazy_energy_matches_eager_arap(void **state)
{
    (void)state;
    lazy_vs_eager(DF_ADMM_ARAP);
}

static void test_lazy_energy_matches_eager_acap(void **state)
{
    (void)state;
    lazy_vs_eager(DF_ADMM_ACAP);
}

static void test_split_runs_equal_one_run_arap(void **state)
{
    (void)state;
    split_vs_one_run(DF_ADMM_ARAP);
}

static void test_split_runs_equal_one_run_neohookean(void **state)
{
    (void)state;
    split_vs_one_run(DF_ADMM_NEOHOOKEAN);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_split_runs_equal_one_run_arap),
        cmocka_unit_test(test_split_runs_equal_one_run_neohookean),
        cmocka_unit_test(test_lazy_energy_matches_eager_arap),
        cmocka_unit_test(test_lazy_energy_matches_eager_acap),
        cmocka_unit_test(test_threads_equal_one_thread_arap),
        cmocka_unit_test(test_threads_equal_one_thread_acap),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
