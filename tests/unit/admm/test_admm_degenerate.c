/* Unit tests for degenerate elements in ADMM (issue 14 item 3): a mesh with zero-area triangles
 * (a duplicated vertex), a zero-volume tet or a zero-length segment deforms like the same mesh
 * without those elements (built here) to 1e-9; a vertex of degenerate elements only follows the
 * mean displacement of its neighbours (its twin when duplicated; reset-rest keeps it degenerate);
 * a tiny island is degenerate by size and stays at rest; a
 * mesh of degenerate elements only is refused with a clear error. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include "admm_test_util.h"
#include "core/admm/admm.h"

/* m plus `extra_v` vertices (positions xv) and `extra_e` elements (ev) inserted before element
 * `at` (the kept elements keep their order); without_extra_e: the same mesh without them */
static df_mesh with_extra(const df_mesh *m, const double *xv, int extra_v, const int32_t *ev,
                          int extra_e, int at, int without_extra_e)
{
    int esz = df_mesh_elem_size(m->kind);
    df_mesh o = *m;
    o.nv = m->nv + extra_v;
    o.ne = m->ne + (without_extra_e ? 0 : extra_e);
    o.V = malloc((size_t)o.nv * 3 * sizeof(double));
    o.E = malloc((size_t)o.ne * esz * sizeof(int32_t));
    memcpy(o.V, m->V, (size_t)m->nv * 3 * sizeof(double));
    if (extra_v) memcpy(o.V + 3 * (size_t)m->nv, xv, (size_t)extra_v * 3 * sizeof(double));
    int32_t *p = o.E;
    memcpy(p, m->E, (size_t)at * esz * sizeof(int32_t));
    p += (size_t)at * esz;
    if (!without_extra_e) {
        memcpy(p, ev, (size_t)extra_e * esz * sizeof(int32_t));
        p += (size_t)extra_e * esz;
    }
    memcpy(p, m->E + (size_t)at * esz, (size_t)(m->ne - at) * esz * sizeof(int32_t));
    return o;
}

typedef struct run_out {
    double *V;
    double objective;
    df_admm_degenerate deg;
} run_out;

static run_out solve(const df_mesh *m, const df_admm_params *p, const int32_t *h, int nh,
                     const double *tg)
{
    df_admm *s = NULL;
    df_error err;
    int rc = df_admm_create(m, p, h, nh, NULL, 0, &s, &err);
    if (rc) fprintf(stderr, "create: %s\n", err.msg);
    assert_int_equal(rc, DF_OK);
    assert_int_equal(df_admm_set_targets(s, tg, &err), DF_OK);
    df_admm_result r;
    assert_int_equal(df_admm_run(s, NULL, &r, &err), DF_OK);
    /* both solves of a pair run the same iterations: exclusion is exact per iteration, so the
     * comparison holds whether or not the (strict, scale-invariant) stop test was met */
    printf("# %d iterations, residual %.3g, converged %d\n", r.iterations, r.residual, r.converged);
    assert_true(r.iterations > 0);
    run_out o;
    o.V = malloc((size_t)m->nv * 3 * sizeof(double));
    assert_int_equal(df_admm_get_positions(s, o.V, &err), DF_OK);
    o.objective = r.objective;
    df_admm_get_degenerate(s, &o.deg);
    df_admm_free(s);
    return o;
}

/* both solves agree on the first n vertices to 1e-9, and on the objective */
static void assert_same(const run_out *a, const run_out *b, int32_t n)
{
    double worst = 0;
    for (int64_t i = 0; i < 3 * (int64_t)n; i++) worst = fmax(worst, fabs(a->V[i] - b->V[i]));
    printf("# max |dV| %.3g, objectives %.12g %.12g\n", worst, a->objective, b->objective);
    assert_true(worst <= 1e-9);
    assert_true(fabs(a->objective - b->objective) <= 1e-9 * (1.0 + fabs(b->objective)));
}

/* V_f = Vrest_f + mean over `src` of (V - Vrest) */
static void assert_follows(const double *V, const double *Vr, int32_t f, const int32_t *src, int n)
{
    for (int k = 0; k < 3; k++) {
        double d = 0;
        for (int t = 0; t < n; t++) d += V[3 * src[t] + k] - Vr[3 * src[t] + k];
        assert_true(fabs(V[3 * f + k] - (Vr[3 * f + k] + d / n)) <= 1e-12);
    }
}

/* 8 x 8 grid, vertex 40 duplicated as vertex 81 with two zero-area triangles (40, 41, 81) and
 * (40, 81, 49) between the others; ARAP and ACAP (2D), cloth (flat 3D sheet, pulled up) */
static void tri_case(df_admm_energy en)
{
    df_mesh g = tu_grid2d(8, 8, 1.0, 1.0);
    g.planar = en != DF_ADMM_CLOTH; /* cloth: the same grid as a flat 3D sheet */
    const int32_t c = 4 * 9 + 4, D = 81;
    const int32_t ev[6] = {c, c + 1, D, c, D, c + 9};
    df_mesh deg = with_extra(&g, g.V + 3 * c, 1, ev, 2, 37, 0);
    df_mesh ref = with_extra(&g, g.V + 3 * c, 1, ev, 2, 37, 1);
    int32_t h[64];
    double tg[64 * 3];
    int nh = 0;
    for (int32_t i = 0; i < g.nv; i++) {
        double x = g.V[3 * i], y = g.V[3 * i + 1];
        if (x == 0 || (x == 1.0 && y == 1.0)) {
            h[nh] = i;
            memcpy(tg + 3 * nh, g.V + 3 * i, 24);
            if (x == 1.0) { tg[3 * nh] += 0.3; tg[3 * nh + 1] -= 0.2; }
            if (x == 1.0 && en == DF_ADMM_CLOTH) tg[3 * nh + 2] = 0.2;
            nh++;
        }
    }
    df_admm_params p;
    df_admm_params_default(&p, en);
    p.threads = 1;
    p.max_iters = 3000;
    if (en == DF_ADMM_CLOTH) {
        p.w = 1e-4; p.s = 0.05; p.rho = 5e-3;
        p.strain_min = 0.5; p.strain_max = 10.0; p.bending = 1e-4;
        p.tol = 1e-9;
    }
    run_out a = solve(&deg, &p, h, nh, tg), b = solve(&ref, &p, h, nh, tg);
    assert_int_equal(a.deg.elements, 2);
    assert_int_equal(a.deg.followers, 1);
    assert_int_equal(a.deg.at_rest, 0);
    assert_int_equal(b.deg.elements, 0);
    assert_same(&a, &b, g.nv);
    const int32_t src[1] = {c}; /* its twin: the same rest position */
    assert_follows(a.V, deg.V, D, src, 1);
    /* the followers' placement keeps the two triangles degenerate: a reset of the rest shape
     * classifies them again (no inverted or sliver triangle appears) */
    df_admm *s = NULL;
    df_error err;
    assert_int_equal(df_admm_create(&deg, &p, h, nh, NULL, 0, &s, &err), DF_OK);
    assert_int_equal(df_admm_set_targets(s, tg, &err), DF_OK);
    assert_int_equal(df_admm_run(s, NULL, NULL, &err), DF_OK);
    assert_int_equal(df_admm_reset_rest(s, &err), DF_OK);
    df_admm_degenerate dg;
    df_admm_get_degenerate(s, &dg);
    assert_int_equal(dg.elements, 2);
    assert_int_equal(dg.followers, 1);
    df_admm_free(s);
    double moved = tu_dist(a.V + 3 * c, g.V + 3 * c);
    assert_true(moved > 1e-3); /* the duplicate's twin did move: the check above is not vacuous */
    free(a.V); free(b.V);
    tu_free(&deg); tu_free(&ref); tu_free(&g);
}

static void test_triangles_arap(void **st) { (void)st; tri_case(DF_ADMM_ARAP); }
static void test_triangles_acap(void **st) { (void)st; tri_case(DF_ADMM_ACAP); }
static void test_triangles_cloth(void **st) { (void)st; tri_case(DF_ADMM_CLOTH); }

/* tet bar with a zero-volume tet on 4 coplanar corners of a cube face (no follower) */
static void test_tets_neohookean(void **st)
{
    (void)st;
    df_mesh g;
    int32_t *h;
    int nh;
    double *tg;
    tu_bar3d_handles(&g, &h, &nh, &tg);
    /* vertices (i, j, k) = (1,0,0), (2,0,0), (1,1,0), (2,1,0): the z = 0 face of a cube */
    const int32_t ev[4] = {1, 2, 1 + 7, 2 + 7};
    df_mesh deg = with_extra(&g, NULL, 0, ev, 1, 10, 0);
    df_mesh ref = with_extra(&g, NULL, 0, ev, 1, 10, 1);
    df_admm_params p;
    df_admm_params_default(&p, DF_ADMM_NEOHOOKEAN);
    p.threads = 1;
    p.max_iters = 4000;
    p.tol = 1e-13;
    run_out a = solve(&deg, &p, h, nh, tg), b = solve(&ref, &p, h, nh, tg);
    assert_int_equal(a.deg.elements, 1);
    assert_int_equal(a.deg.followers, 0);
    assert_same(&a, &b, g.nv);
    free(a.V); free(b.V); free(h); free(tg);
    tu_free(&deg); tu_free(&ref); tu_free(&g);
}

/* polyline of 10 segments along x, plus a zero-length segment to a duplicate of vertex 5 */
static void test_polyline(void **st)
{
    (void)st;
    df_mesh g;
    memset(&g, 0, sizeof g);
    g.kind = DF_MESH_POLYLINE;
    g.nv = 11;
    g.ne = 10;
    g.V = calloc(33, sizeof(double));
    g.E = malloc(20 * sizeof(int32_t));
    for (int i = 0; i <= 10; i++) g.V[3 * i] = 0.1 * i;
    for (int i = 0; i < 10; i++) { g.E[2 * i] = i; g.E[2 * i + 1] = i + 1; }
    const int32_t ev[2] = {5, 11};
    df_mesh deg = with_extra(&g, g.V + 15, 1, ev, 1, 4, 0);
    df_mesh ref = with_extra(&g, g.V + 15, 1, ev, 1, 4, 1);
    int32_t h[2] = {0, 10};
    double tg[6] = {0, 0, 0, 0.9, 0.3, 0.1};
    df_admm_params p;
    df_admm_params_default(&p, DF_ADMM_POLYLINE);
    p.threads = 1;
    p.max_iters = 20000;
    run_out a = solve(&deg, &p, h, 2, tg), b = solve(&ref, &p, h, 2, tg);
    assert_int_equal(a.deg.elements, 1);
    assert_int_equal(a.deg.followers, 1);
    assert_same(&a, &b, g.nv);
    const int32_t src[1] = {5};
    assert_follows(a.V, deg.V, 11, src, 1);
    free(a.V); free(b.V);
    tu_free(&deg); tu_free(&ref); tu_free(&g);
}

/* a well-shaped island 1e-6 the size of the grid's triangles is degenerate by size; its vertices
 * reach no kept element and stay at rest */
static void test_size_threshold_island(void **st)
{
    (void)st;
    df_mesh g = tu_grid2d(4, 4, 1.0, 1.0);
    double xv[9] = {2.0, 2.0, 0, 2.0 + 1e-6, 2.0, 0, 2.0, 2.0 + 1e-6, 0};
    const int32_t ev[3] = {25, 26, 27};
    df_mesh deg = with_extra(&g, xv, 3, ev, 1, g.ne, 0);
    df_admm_degenerate r;
    df_error err;
    uint8_t flags[64];
    assert_int_equal(df_admm_find_degenerate(&deg, flags, &r, &err), DF_OK);
    assert_int_equal(r.elements, 1);
    assert_int_equal(r.followers, 0);
    assert_int_equal(r.at_rest, 3);
    assert_int_equal(flags[deg.ne - 1], 1);
    for (int32_t e = 0; e + 1 < deg.ne; e++) assert_int_equal(flags[e], 0);
    int32_t h[2] = {0, 24};
    double tg[6] = {0, 0, 0, 1.2, 1.1, 0};
    df_admm_params p;
    df_admm_params_default(&p, DF_ADMM_ARAP);
    p.threads = 1;
    run_out a = solve(&deg, &p, h, 2, tg);
    assert_int_equal(a.deg.at_rest, 3);
    for (int i = 25 * 3; i < 28 * 3; i++) assert_true(a.V[i] == deg.V[i]);
    free(a.V);
    tu_free(&deg); tu_free(&g);
}

/* every element degenerate: refused, *out untouched */
static void test_all_degenerate_refused(void **st)
{
    (void)st;
    df_mesh g = tu_grid2d(2, 2, 1.0, 1.0);
    for (int32_t i = 0; i < g.nv; i++) g.V[3 * i + 1] = 0; /* everything collinear */
    int32_t h[1] = {0};
    df_admm_params p;
    df_admm_params_default(&p, DF_ADMM_ARAP);
    df_admm *s = (df_admm *)&g; /* sentinel */
    df_error err;
    assert_int_equal(df_admm_create(&g, &p, h, 1, NULL, 0, &s, &err), DF_EINVAL);
    assert_ptr_equal(s, (df_admm *)&g);
    assert_non_null(strstr(err.msg, "all 8 elements are degenerate"));
    tu_free(&g);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_triangles_arap),
        cmocka_unit_test(test_triangles_acap),
        cmocka_unit_test(test_triangles_cloth),
        cmocka_unit_test(test_tets_neohookean),
        cmocka_unit_test(test_polyline),
        cmocka_unit_test(test_size_threshold_island),
        cmocka_unit_test(test_all_degenerate_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
