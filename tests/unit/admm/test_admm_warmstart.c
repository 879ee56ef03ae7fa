/* Unit tests of df_admm_set_positions (admm.h): a run after an outside change of the positions
 * (an undo, a brush edit) starts from those positions, not from the previous run's result; the
 * positions are taken exactly, unchanged positions leave the warm start untouched (bit-identical
 * runs), bad input changes nothing. Tet bar with its two end faces as handles (ARAP, w > 0, the
 * element family) and a 2D strip (spokes and rims, the vertex family). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include "core/admm/admm.h"
#include "tests/unit/admm/admm_test_util.h"

/* 2D strip [0,2]x[0,0.5]: left column fixed, right column lifted by 0.6 */
static void strip2d(df_mesh *m, int32_t **h, int *nh, double **tg)
{
    *m = tu_grid2d(12, 3, 2.0, 0.5);
    *nh = 0;
    *h = malloc(8 * sizeof(int32_t));
    *tg = malloc(8 * 3 * sizeof(double));
    for (int j = 0; j <= 3; j++) {
        int32_t l = j * 13, r = j * 13 + 12;
        (*h)[*nh] = l; memcpy(*tg + 3 * *nh, m->V + 3 * l, 24); (*nh)++;
        (*h)[*nh] = r; memcpy(*tg + 3 * *nh, m->V + 3 * r, 24); (*tg)[3 * *nh + 1] += 0.6; (*nh)++;
    }
}

static df_admm *make(const df_mesh *m, const int32_t *h, int nh, const double *tg)
{
    df_admm_params p;
    df_admm_params_default(&p, DF_ADMM_ARAP);
    p.threads = 1;
    p.w = 1e-3;
    p.s = 0.01;
    p.rho = 0.2;
    p.tol = 1e-12;
    p.max_iters = 2000;
    df_admm *s = NULL;
    df_error err;
    assert_int_equal(df_admm_create(m, &p, h, nh, NULL, 0, &s, &err), DF_OK);
    assert_int_equal(df_admm_set_targets(s, tg, &err), DF_OK);
    return s;
}

static double max_diff(const double *a, const double *b, int32_t nv)
{
    double d = 0;
    for (int32_t i = 0; i < nv; i++) d = fmax(d, tu_dist(a + 3 * i, b + 3 * i));
    return d;
}

static void run_iters(df_admm *s, int iters)
{
    df_admm_budget b = {.max_iters = iters};
    df_error err;
    assert_int_equal(df_admm_run(s, &b, NULL, &err), DF_OK);
}

/* Converge, "undo" to the rest shape, run one iteration: the result is the one-iteration result
 * of a fresh solver (which starts at rest), not the converged shape of the first run. */
static void undo_then_one_iteration(df_mesh *m, const int32_t *h, int nh, const double *tg,
                                    const char *label)
{
    df_admm *s = make(m, h, nh, tg), *fresh = make(m, h, nh, tg);
    df_error err;
    run_iters(s, 0);
    double *conv = malloc((size_t)m->nv * 3 * sizeof(double));
    memcpy(conv, df_admm_positions(s), (size_t)m->nv * 3 * sizeof(double));
    int32_t changed = -1;
    assert_int_equal(df_admm_set_positions(s, m->V, &changed, &err), DF_OK);
    assert_true(changed > 0);
    assert_memory_equal(df_admm_positions(s), m->V, (size_t)m->nv * 3 * sizeof(double));
    run_iters(s, 1);
    run_iters(fresh, 1);
    double to_fresh = max_diff(df_admm_positions(s), df_admm_positions(fresh), m->nv);
    double to_conv = max_diff(df_admm_positions(s), conv, m->nv);
    double fresh_to_conv = max_diff(df_admm_positions(fresh), conv, m->nv);
    printf("%s: after undo + 1 iteration: %.3g from a fresh solver's first iterate, %.3g from the "
           "converged shape (fresh first iterate: %.3g from it); %d vertices restarted\n",
           label, to_fresh, to_conv, fresh_to_conv, (int)changed);
    assert_true(fresh_to_conv > 0.05);
    assert_true(to_fresh < 1e-3 * fresh_to_conv);
    df_admm_free(s);
    df_admm_free(fresh);
    free(conv);
}

static void test_undo_restarts_from_the_given_positions_tets(void **st)
{
    (void)st;
    df_mesh m; int32_t *h; int nh; double *tg;
    tu_bar3d_handles(&m, &h, &nh, &tg);
    undo_then_one_iteration(&m, h, nh, tg, "tet bar");
    free(h); free(tg); tu_free(&m);
}

static void test_undo_restarts_from_the_given_positions_2d(void **st)
{
    (void)st;
    df_mesh m; int32_t *h; int nh; double *tg;
    strip2d(&m, &h, &nh, &tg);
    undo_then_one_iteration(&m, h, nh, tg, "2D strip");
    free(h); free(tg); tu_free(&m);
}

/* Setting the positions the solver already reports changes nothing: the next run is bit-identical
 * to a twin solver's that got no call. */
static void test_same_positions_keep_the_warm_start(void **st)
{
    (void)st;
    df_mesh m; int32_t *h; int nh; double *tg;
    tu_bar3d_handles(&m, &h, &nh, &tg);
    df_admm *a = make(&m, h, nh, tg), *b = make(&m, h, nh, tg);
    run_iters(a, 15);
    run_iters(b, 15);
    double *cur = malloc((size_t)m.nv * 3 * sizeof(double));
    memcpy(cur, df_admm_positions(a), (size_t)m.nv * 3 * sizeof(double));
    int32_t changed = -1;
    df_error err;
    assert_int_equal(df_admm_set_positions(a, cur, &changed, &err), DF_OK);
    assert_int_equal(changed, 0);
    run_iters(a, 10);
    run_iters(b, 10);
    assert_memory_equal(df_admm_positions(a), df_admm_positions(b), (size_t)m.nv * 3 * sizeof(double));
    df_admm_free(a); df_admm_free(b); free(cur);
    free(h); free(tg); tu_free(&m);
}

/* A local edit (a brush on a few free vertices) survives one iteration: the edited vertices start
 * where the edit put them instead of being reset to the previous run's result. */
static void test_local_edit_is_the_starting_point(void **st)
{
    (void)st;
    df_mesh m; int32_t *h; int nh; double *tg;
    tu_bar3d_handles(&m, &h, &nh, &tg);
    df_admm *s = make(&m, h, nh, tg);
    run_iters(s, 0);
    size_t n3 = (size_t)m.nv * 3;
    double *edit = malloc(n3 * sizeof(double));
    memcpy(edit, df_admm_positions(s), n3 * sizeof(double));
    int32_t moved = 0;
    for (int32_t i = 0; i < m.nv; i++)
        if (m.V[3 * i] == 1.5) { edit[3 * i + 2] += 0.2; moved++; } /* a middle slice, no handle */
    int32_t changed = -1;
    df_error err;
    assert_int_equal(df_admm_set_positions(s, edit, &changed, &err), DF_OK);
    assert_int_equal(changed, moved);
    run_iters(s, 1);
    double lift = 1e9;
    for (int32_t i = 0; i < m.nv; i++)
        if (m.V[3 * i] == 1.5) lift = fmin(lift, df_admm_positions(s)[3 * i + 2] - (edit[3 * i + 2] - 0.2));
    printf("local edit of 0.2 on %d vertices: at least %.3f left after one iteration\n", (int)moved, lift);
    assert_true(lift > 0.05);
    df_admm_free(s); free(edit);
    free(h); free(tg); tu_free(&m);
}

static void test_bad_input_changes_nothing(void **st)
{
    (void)st;
    df_mesh m; int32_t *h; int nh; double *tg;
    tu_bar3d_handles(&m, &h, &nh, &tg);
    df_admm *s = make(&m, h, nh, tg);
    run_iters(s, 5);
    size_t n3 = (size_t)m.nv * 3;
    double *before = malloc(n3 * sizeof(double)), *bad = malloc(n3 * sizeof(double));
    memcpy(before, df_admm_positions(s), n3 * sizeof(double));
    memcpy(bad, m.V, n3 * sizeof(double));
    bad[3 * (m.nv - 1) + 1] = NAN;
    df_error err;
    int32_t changed = -1;
    assert_int_equal(df_admm_set_positions(s, bad, &changed, &err), DF_EINVAL);
    assert_int_equal(changed, -1);
    assert_memory_equal(df_admm_positions(s), before, n3 * sizeof(double));
    assert_int_equal(df_admm_set_positions(NULL, bad, NULL, &err), DF_EINVAL);
    assert_int_equal(df_admm_set_positions(s, NULL, NULL, &err), DF_EINVAL);
    df_admm_free(s); free(before); free(bad);
    free(h); free(tg); tu_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_undo_restarts_from_the_given_positions_tets),
        cmocka_unit_test(test_undo_restarts_from_the_given_positions_2d),
        cmocka_unit_test(test_same_positions_keep_the_warm_start),
        cmocka_unit_test(test_local_edit_is_the_starting_point),
        cmocka_unit_test(test_bad_input_changes_nothing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
