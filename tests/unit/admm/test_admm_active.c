/* Unit tests of the active-set mode (admm.h DF_ADMM_ACTIVE): on a tet grid (ARAP and Neo-Hookean,
 * the element family) and a planar triangle grid (ARAP, spokes and rims), a drag solved in active
 * mode and converged equals the full solve (params.active = 0) within 1e-8 relative objective and
 * 1e-8 positions; the vertices outside the region stay bitwise at rest; the region grows when the
 * handle drags further and shrinks when it comes back; with a band of one ring only the far-field certificate can grow the region
 * and it does; the tail test makes a 20-iteration update follow the full solve's iterate closely
 * (and converges to the same result); set_positions and reset_rest keep working in active mode (same result as the full
 * solve); affine constraints fall back to the full solve (bit-identical to it); bad parameters are
 * refused. Expected values come from the full solve of the same problem. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include "core/admm/admm.h"
#include "tests/unit/admm/admm_test_util.h"

typedef struct scene {
    df_mesh m;
    int32_t *h;
    int nh;
    double *tg;     /* rest positions of the handles */
    uint8_t *drag;  /* per handle: 1 when dragged */
    double hsp;     /* grid spacing */
    double dir[3];  /* drag direction per unit of `amount` */
} scene;

/* tet grid n^3 over [0,1]^3: bottom face pinned, 3 x 3 patch at the top centre dragged up */
static void tet_scene(scene *sc, int n)
{
    memset(sc, 0, sizeof(*sc));
    sc->m = tu_bar3d(n, n, n, 1.0, 1.0, 1.0);
    sc->hsp = 1.0 / n;
    sc->h = malloc((size_t)sc->m.nv * sizeof(int32_t));
    sc->tg = malloc((size_t)sc->m.nv * 3 * sizeof(double));
    sc->drag = calloc((size_t)sc->m.nv, 1);
    for (int32_t i = 0; i < sc->m.nv; i++) {
        const double *x = sc->m.V + 3 * (size_t)i;
        long ii = lround(x[0] * n), jj = lround(x[1] * n);
        int top = x[2] == 1.0 && labs(ii - n / 2) <= 1 && labs(jj - n / 2) <= 1;
        if (top || x[2] == 0.0) {
            sc->drag[sc->nh] = (uint8_t)top;
            memcpy(sc->tg + 3 * (size_t)sc->nh, x, 3 * sizeof(double));
            sc->h[sc->nh++] = i;
        }
    }
    sc->dir[2] = 1.0;
}

/* planar triangle grid n x n over [0,1]^2: left column pinned, 3 x 3 centre patch dragged in x, y */
static void tri_scene(scene *sc, int n)
{
    memset(sc, 0, sizeof(*sc));
    sc->m = tu_grid2d(n, n, 1.0, 1.0);
    sc->hsp = 1.0 / n;
    sc->h = malloc((size_t)sc->m.nv * sizeof(int32_t));
    sc->tg = malloc((size_t)sc->m.nv * 3 * sizeof(double));
    sc->drag = calloc((size_t)sc->m.nv, 1);
    for (int32_t i = 0; i < sc->m.nv; i++) {
        const double *x = sc->m.V + 3 * (size_t)i;
        long ii = lround(x[0] * n), jj = lround(x[1] * n);
        int mid = labs(ii - n / 2) <= 1 && labs(jj - n / 2) <= 1;
        if (mid || ii == 0) {
            sc->drag[sc->nh] = (uint8_t)mid;
            memcpy(sc->tg + 3 * (size_t)sc->nh, x, 3 * sizeof(double));
            sc->h[sc->nh++] = i;
        }
    }
    sc->dir[0] = 0.8;
    sc->dir[1] = 0.6;
}

static void scene_free(scene *sc)
{
    tu_free(&sc->m);
    free(sc->h); free(sc->tg); free(sc->drag);
}

/* ARAP with w, s, rho scaled by the grid spacing (a support of a few rings) */
static df_admm_params arap_params(const scene *sc, int active)
{
    df_admm_params p;
    df_admm_params_default(&p, DF_ADMM_ARAP);
    double h = sc->hsp;
    if (sc->m.kind == DF_MESH_TET) { /* per-vertex stiffness ~ h: w ~ h^2 keeps the support in rings */
        p.w = 0.5 * h * h;
        p.rho = 6.0 * h;
    } else { /* spokes and rims: stiffness ~ 1, w ~ h */
        p.w = 0.5 * h;
        p.rho = 6.0;
    }
    p.s = 0.25 * h;
    p.tol = 1e-13;
    p.max_iters = 20000;
    p.threads = 1;
    p.active = active;
    return p;
}

static df_admm *make(const scene *sc, const df_admm_params *p)
{
    df_admm *s = NULL;
    df_error err;
    assert_int_equal(df_admm_create(&sc->m, p, sc->h, sc->nh, NULL, 0, &s, &err), DF_OK);
    return s;
}

/* targets: dragged handles moved by amount * hsp along dir */
static void set_drag(df_admm *s, const scene *sc, double amount)
{
    double *t = malloc((size_t)sc->nh * 3 * sizeof(double));
    memcpy(t, sc->tg, (size_t)sc->nh * 3 * sizeof(double));
    for (int k = 0; k < sc->nh; k++)
        if (sc->drag[k])
            for (int c = 0; c < 3; c++) t[3 * k + c] += amount * sc->hsp * sc->dir[c];
    df_error err;
    assert_int_equal(df_admm_set_targets(s, t, &err), DF_OK);
    free(t);
}

static df_admm_result run(df_admm *s, int iters)
{
    df_admm_budget b = {.max_iters = iters};
    df_admm_result r;
    df_error err;
    assert_int_equal(df_admm_run(s, &b, &r, &err), DF_OK);
    return r;
}

/* the same drag on both solvers (set_drag) */
static void set_drag2(df_admm *full, df_admm *act, const scene *sc, double amount)
{
    set_drag(full, sc, amount);
    set_drag(act, sc, amount);
}

/* iters on both solvers (run), full first; their results in *rf, *ra when not NULL */
static void run2(df_admm *full, df_admm *act, int iters, df_admm_result *rf, df_admm_result *ra)
{
    df_admm_result a = run(full, iters), b = run(act, iters);
    if (rf) *rf = a;
    if (ra) *ra = b;
}

/* frees both solvers and the scene */
static void free_pair(df_admm *full, df_admm *act, scene *sc)
{
    df_admm_free(full);
    df_admm_free(act);
    scene_free(sc);
}

/* the n = 10 tet scene in *sc, ARAP full and active solvers on it, dragged by amount and run
 * 20000 iterations each (caller frees with free_pair) */
static void tet_arap_pair(scene *sc, double amount, df_admm **full, df_admm **act)
{
    tet_scene(sc, 10);
    df_admm_params pf = arap_params(sc, 0), pa = arap_params(sc, 1);
    *full = make(sc, &pf);
    *act = make(sc, &pa);
    set_drag2(*full, *act, sc, amount);
    run2(*full, *act, 20000, NULL, NULL);
}

static double max_diff(const double *a, const double *b, int32_t nv)
{
    double d = 0;
    for (int32_t i = 0; i < nv; i++) d = fmax(d, tu_dist(a + 3 * (size_t)i, b + 3 * (size_t)i));
    return d;
}

static int32_t count_moved(const df_admm *s, const df_mesh *m)
{
    const double *V = df_admm_positions(s);
    int32_t n = 0;
    for (int32_t i = 0; i < m->nv; i++)
        if (memcmp(V + 3 * (size_t)i, m->V + 3 * (size_t)i, 3 * sizeof(double))) n++;
    return n;
}

/* both converged: equal objectives (1e-8 relative, also re-evaluated from the positions) and
 * positions (1e-8, mesh size 1) */
static void assert_same(df_admm *full, df_admm *act, const df_admm_result *rf, const df_admm_result *ra, int32_t nv)
{
    assert_true(rf->converged);
    assert_true(ra->converged);
    assert_true(fabs(ra->objective - rf->objective) <= 1e-8 * fabs(rf->objective));
    double el, lo;
    df_error err;
    assert_int_equal(df_admm_evaluate(act, df_admm_positions(act), &el, &lo, &err), DF_OK);
    assert_true(fabs(el + lo - rf->objective) <= 1e-8 * fabs(rf->objective));
    assert_true(max_diff(df_admm_positions(full), df_admm_positions(act), nv) <= 1e-8);
}

/* a drag of `steps` warm updates of 20 iterations, then converged, in both modes */
static void drag_pair(const scene *sc, const df_admm_params *pf, const df_admm_params *pa, int steps, double step,
                      df_admm **full, df_admm **act)
{
    *full = make(sc, pf);
    *act = make(sc, pa);
    for (int k = 1; k <= steps; k++) {
        set_drag2(*full, *act, sc, step * k);
        run2(*full, *act, 20, NULL, NULL);
    }
    df_admm_result rf, ra;
    run2(*full, *act, 20000, &rf, &ra);
    assert_same(*full, *act, &rf, &ra, sc->m.nv);
}

static void check_far_field(const df_admm *act, const scene *sc)
{
    df_admm_active_stats st;
    df_admm_get_active_stats(act, &st);
    assert_true(st.runs > 0);
    assert_int_equal(st.fallbacks, 0);
    /* only region vertices may differ from rest; the rest of the mesh is bitwise at rest */
    int32_t moved = count_moved(act, &sc->m);
    assert_true(moved > 0);
    assert_true(moved <= st.region_vertices);
    assert_true(st.region_vertices < sc->m.nv / 2);
}

static void test_tet_arap_equals_full(void **state)
{
    (void)state;
    scene sc;
    tet_scene(&sc, 10);
    df_admm_params pf = arap_params(&sc, 0), pa = arap_params(&sc, 1);
    df_admm *full, *act;
    drag_pair(&sc, &pf, &pa, 4, 0.3, &full, &act);
    check_far_field(act, &sc);
    /* the full solve's far field is at rest up to round-off only: more vertices differ there */
    assert_true(count_moved(full, &sc.m) > count_moved(act, &sc.m));
    free_pair(full, act, &sc);
}

static void test_tri_arap_equals_full(void **state)
{
    (void)state;
    scene sc;
    tri_scene(&sc, 30);
    df_admm_params pf = arap_params(&sc, 0), pa = arap_params(&sc, 1);
    df_admm *full, *act;
    drag_pair(&sc, &pf, &pa, 4, 0.3, &full, &act);
    check_far_field(act, &sc);
    free_pair(full, act, &sc);
}

/* the tail test on spokes-and-rims cells: the drag converges to the full solve's result */
static void test_tri_tail_equals_full(void **state)
{
    (void)state;
    scene sc;
    tri_scene(&sc, 40);
    df_admm_params pf = arap_params(&sc, 0), pa = arap_params(&sc, 1);
    pa.active_tail = 1e-6;
    df_admm *full, *act;
    drag_pair(&sc, &pf, &pa, 4, 0.3, &full, &act);
    df_admm_active_stats st;
    df_admm_get_active_stats(act, &st);
    print_message("tail grows %ld, region %d of %d vertices, fallbacks %ld\n", st.tail_grows, st.region_vertices, sc.m.nv,
                  st.fallbacks);
    assert_true(st.tail_grows > 0);
    check_far_field(act, &sc);
    free_pair(full, act, &sc);
}

static void test_tet_neohookean_equals_full(void **state)
{
    (void)state;
    scene sc;
    tet_scene(&sc, 10);
    df_admm_params pf, pa;
    df_admm_params_default(&pf, DF_ADMM_NEOHOOKEAN);
    double h = sc.hsp;
    /* the ARAP scaling times the Neo-Hookean stiffness scale mu + lambda */
    double E = pf.youngs, nu = pf.poisson, stiff = E / (2 * (1 + nu)) + E * nu / ((1 + nu) * (1 - 2 * nu));
    pf.w = 1.0 * h * h * stiff;
    pf.s = 0.25 * h;
    pf.rho = 10.0 * h * stiff;
    pf.tol = 1e-13;
    pf.max_iters = 20000;
    pf.threads = 1;
    pa = pf;
    pa.active = 1;
    df_admm *full, *act;
    drag_pair(&sc, &pf, &pa, 3, 0.3, &full, &act);
    check_far_field(act, &sc);
    free_pair(full, act, &sc);
}

static void test_region_grows_with_drag(void **state)
{
    (void)state;
    scene sc;
    df_admm *full, *act;
    tet_arap_pair(&sc, 0.2, &full, &act);
    df_admm_active_stats st1, st2;
    df_admm_get_active_stats(act, &st1);
    set_drag2(full, act, &sc, 2.0); /* drag further: the support spreads into the band */
    df_admm_result rf, ra;
    run2(full, act, 20000, &rf, &ra);
    df_admm_get_active_stats(act, &st2);
    assert_true(st2.grows > st1.grows);
    assert_true(st2.region_vertices > st1.region_vertices);
    assert_true(st2.support > st1.support);
    assert_same(full, act, &rf, &ra, sc.m.nv);
    check_far_field(act, &sc);
    /* and back: the support shrinks, the next run rebuilds a smaller region from it */
    set_drag2(full, act, &sc, 0.2);
    run2(full, act, 20000, NULL, NULL);
    run2(full, act, 20000, &rf, &ra); /* the first run's end shows the shrunk support, the next shrinks */
    df_admm_active_stats st3;
    df_admm_get_active_stats(act, &st3);
    assert_true(st3.rebuilds > st2.rebuilds);
    assert_true(st3.region_vertices < st2.region_vertices);
    assert_same(full, act, &rf, &ra, sc.m.nv);
    check_far_field(act, &sc);
    free_pair(full, act, &sc);
}

/* band 1: a support vertex is always >= 1 ring from the edge, so the depth rule never grows the
 * region; the support spreading from the handles must be caught by the certificate */
static void test_certificate_grows_region(void **state)
{
    (void)state;
    scene sc;
    tet_scene(&sc, 10);
    df_admm_params pf = arap_params(&sc, 0), pa = arap_params(&sc, 1);
    pa.active_band = 1;
    pa.active_check_every = 5;
    df_admm *full = make(&sc, &pf), *act = make(&sc, &pa);
    set_drag2(full, act, &sc, 2.0);
    df_admm_result rf, ra;
    run2(full, act, 20000, &rf, &ra);
    df_admm_active_stats st;
    df_admm_get_active_stats(act, &st);
    assert_true(st.check_grows > 0);
    assert_int_equal(st.grows, st.check_grows);
    assert_true(st.checks > st.check_grows); /* the last certificate passed */
    assert_same(full, act, &rf, &ra, sc.m.nv);
    check_far_field(act, &sc);
    free_pair(full, act, &sc);
}

/* the tail test (params.active_tail): an unconverged 20-iteration update follows the full solve's
 * iterate, whose global step moves every vertex a little, far more closely than the plain band
 * (Dirichlet at rest on the fringe) does: the region grows one ring wherever its edge still
 * carries SC-L1 charge. Expected values: the full solve of the same update; converged, the result
 * is the full solve's as without the test. */
static void test_tail_test_follows_full(void **state)
{
    (void)state;
    scene sc;
    tet_scene(&sc, 16);
    df_admm_params pf = arap_params(&sc, 0), pa = arap_params(&sc, 1), pt = pa;
    pt.active_tail = 1e-6;
    df_admm *full = make(&sc, &pf), *act = make(&sc, &pa), *tail = make(&sc, &pt);
    set_drag2(full, act, &sc, 0.3);
    set_drag(tail, &sc, 0.3);
    df_admm_result rf, ra;
    run2(full, act, 20, &rf, &ra);
    df_admm_result rt = run(tail, 20);
    double d_band = fabs(ra.objective - rf.objective) / fabs(rf.objective);
    double d_tail = fabs(rt.objective - rf.objective) / fabs(rf.objective);
    print_message("20 iterations: |E_active - E_full| / E_full: band %.2e, band + tail test %.2e\n", d_band, d_tail);
    assert_true(d_tail * 10.0 < d_band);
    df_admm_active_stats sa, st;
    df_admm_get_active_stats(act, &sa);
    df_admm_get_active_stats(tail, &st);
    assert_int_equal(sa.tail_grows, 0);
    assert_true(st.tail_grows > 0);
    assert_true(st.region_vertices > sa.region_vertices);
    print_message("region %d vertices (plain band %d), %d moved, of %d\n", st.region_vertices, sa.region_vertices,
                  count_moved(tail, &sc.m), sc.m.nv);
    assert_int_equal(st.fallbacks, 0);
    assert_true(count_moved(tail, &sc.m) <= st.region_vertices); /* the rest still bitwise at rest */
    run2(full, tail, 20000, &rf, &rt);
    assert_same(full, tail, &rf, &rt, sc.m.nv);
    df_admm_free(act);
    free_pair(full, tail, &sc);
}

/* the tail test over the warm updates of one drag: the region is built once and kept (it never
 * shrinks back, so later updates do not re-grow it), every CHOLMOD analysis / factorization
 * belongs to a region build or growth (none per update otherwise), and the final result equals both
 * the full solve's and that of a region grown from scratch for the last update (a new solver per
 * update, at rest, given that update's targets: its region is built from the handles and grown
 * again by the tail test). Expected values: the full solve of the same targets. */
static void test_tail_region_kept(void **state)
{
    (void)state;
    scene sc;
    tet_scene(&sc, 16);
    df_admm_params pf = arap_params(&sc, 0), pt = arap_params(&sc, 1);
    pt.active_tail = 1e-6;
    df_admm *full = make(&sc, &pf), *kept = make(&sc, &pt), *regrown = NULL;
    int32_t prev_region = 0;
    for (int k = 1; k <= 4; k++) {
        set_drag2(full, kept, &sc, 0.3 * k);
        df_admm_stats s0, s1;
        df_admm_active_stats a0, a1, r1;
        df_admm_get_stats(kept, &s0);
        df_admm_get_active_stats(kept, &a0);
        run2(full, kept, 20, NULL, NULL);
        df_admm_get_stats(kept, &s1);
        df_admm_get_active_stats(kept, &a1);
        assert_int_equal(a1.rebuilds, 1);
        assert_int_equal(a1.fallbacks, 0);
        assert_true(a1.region_vertices >= prev_region);
        prev_region = a1.region_vertices;
        long builds = (a1.grows - a0.grows) + (a1.rebuilds - a0.rebuilds);
        assert_int_equal(s1.analyses - s0.analyses, builds);
        assert_int_equal(s1.factorizations - s0.factorizations, builds);
        /* the re-grown region: a new solver at rest given this update's targets */
        df_admm_free(regrown);
        regrown = make(&sc, &pt);
        set_drag(regrown, &sc, 0.3 * k);
        (void)run(regrown, 20);
        df_admm_get_active_stats(regrown, &r1);
        assert_int_equal(r1.rebuilds, 1);
        assert_int_equal(r1.fallbacks, 0);
    }
    df_admm_active_stats st;
    df_admm_get_active_stats(kept, &st);
    assert_true(st.tail_grows > 0);
    df_admm_result rf, rk, rr;
    run2(full, kept, 20000, &rf, &rk);
    rr = run(regrown, 20000);
    assert_same(full, kept, &rf, &rk, sc.m.nv);
    assert_same(full, regrown, &rf, &rr, sc.m.nv);
    df_admm_free(regrown);
    free_pair(full, kept, &sc);
}

/* set_positions (e.g. an undo or a brush edit somewhere else) and reset_rest in active mode give the
 * full solve's results */
static void test_set_positions_and_reset_rest(void **state)
{
    (void)state;
    scene sc;
    df_admm *full, *act;
    tet_arap_pair(&sc, 0.5, &full, &act);
    /* an outside edit far from the region: a corner vertex of the top face pushed down */
    double *V = malloc((size_t)sc.m.nv * 3 * sizeof(double));
    memcpy(V, df_admm_positions(act), (size_t)sc.m.nv * 3 * sizeof(double));
    int32_t corner = sc.m.nv - 1;
    V[3 * (size_t)corner + 2] -= 0.5 * sc.hsp;
    df_error err;
    int32_t nch = 0;
    assert_int_equal(df_admm_set_positions(full, V, NULL, &err), DF_OK);
    assert_int_equal(df_admm_set_positions(act, V, &nch, &err), DF_OK);
    assert_int_equal(nch, 1);
    df_admm_active_stats st0, st1;
    df_admm_get_active_stats(act, &st0);
    df_admm_result rf, ra;
    run2(full, act, 20000, &rf, &ra);
    df_admm_get_active_stats(act, &st1);
    assert_true(st1.rebuilds > st0.rebuilds);
    assert_same(full, act, &rf, &ra, sc.m.nv);
    /* sculpting: the current shape becomes the rest shape, then a new drag */
    assert_int_equal(df_admm_reset_rest(full, &err), DF_OK);
    assert_int_equal(df_admm_reset_rest(act, &err), DF_OK);
    double *t = malloc((size_t)sc.nh * 3 * sizeof(double));
    const double *P = df_admm_positions(act);
    for (int k = 0; k < sc.nh; k++) {
        memcpy(t + 3 * k, P + 3 * (size_t)sc.h[k], 3 * sizeof(double));
        if (sc.drag[k]) t[3 * k + 2] += 0.4 * sc.hsp;
    }
    assert_int_equal(df_admm_set_targets(full, t, &err), DF_OK);
    assert_int_equal(df_admm_set_targets(act, t, &err), DF_OK);
    run2(full, act, 20000, &rf, &ra);
    assert_same(full, act, &rf, &ra, sc.m.nv);
    df_admm_active_stats st2;
    df_admm_get_active_stats(act, &st2);
    assert_true(st2.runs > 0);
    free(t);
    free(V);
    free_pair(full, act, &sc);
}

/* affine constraints: the active mode falls back to the full solve, bit for bit */
static void test_affine_falls_back(void **state)
{
    (void)state;
    scene sc;
    tet_scene(&sc, 6);
    df_admm_params pf = arap_params(&sc, 0), pa = arap_params(&sc, 1);
    int32_t av[2];
    int na = 0;
    for (int32_t i = 0; i < sc.m.nv && na < 2; i++) /* two free vertices of the top face on x = 0 */
        if (sc.m.V[3 * (size_t)i] == 0.0 && sc.m.V[3 * (size_t)i + 2] == 1.0) av[na++] = i;
    df_admm_affine aff = {.n = 2, .verts = av, .m = 1, .A = {0, 0, 1}, .b = {1.0}};
    df_admm *full = NULL, *act = NULL;
    df_error err;
    assert_int_equal(df_admm_create(&sc.m, &pf, sc.h, sc.nh, &aff, 1, &full, &err), DF_OK);
    assert_int_equal(df_admm_create(&sc.m, &pa, sc.h, sc.nh, &aff, 1, &act, &err), DF_OK);
    set_drag2(full, act, &sc, 0.5);
    df_admm_result rf, ra;
    run2(full, act, 50, &rf, &ra);
    assert_int_equal(rf.iterations, ra.iterations);
    assert_memory_equal(&rf.objective, &ra.objective, sizeof(double));
    assert_memory_equal(df_admm_positions(full), df_admm_positions(act), (size_t)sc.m.nv * 3 * sizeof(double));
    df_admm_active_stats st;
    df_admm_get_active_stats(act, &st);
    assert_int_equal(st.runs, 0);
    assert_int_equal(st.fallbacks, 1);
    free_pair(full, act, &sc);
}

static void test_bad_params(void **state)
{
    (void)state;
    scene sc;
    tet_scene(&sc, 4);
    df_admm_params p = arap_params(&sc, 1);
    df_admm *s = NULL;
    df_error err;
    p.active = 2;
    assert_int_equal(df_admm_create(&sc.m, &p, sc.h, sc.nh, NULL, 0, &s, &err), DF_EINVAL);
    assert_non_null(strstr(err.msg, "active"));
    p.active = 1;
    p.active_band = -1;
    assert_int_equal(df_admm_create(&sc.m, &p, sc.h, sc.nh, NULL, 0, &s, &err), DF_EINVAL);
    assert_non_null(strstr(err.msg, "active_band"));
    p.active_band = 0;
    p.active_check_every = -3;
    assert_int_equal(df_admm_create(&sc.m, &p, sc.h, sc.nh, NULL, 0, &s, &err), DF_EINVAL);
    p.active_check_every = 0;
    p.active_tail = -1e-6;
    assert_int_equal(df_admm_create(&sc.m, &p, sc.h, sc.nh, NULL, 0, &s, &err), DF_EINVAL);
    assert_non_null(strstr(err.msg, "active_tail"));
    p.active_tail = NAN;
    assert_int_equal(df_admm_create(&sc.m, &p, sc.h, sc.nh, NULL, 0, &s, &err), DF_EINVAL);
    assert_non_null(strstr(err.msg, "active_tail"));
    assert_null(s);
    df_admm_active_stats st;
    df_admm_get_active_stats(NULL, &st);
    assert_int_equal(st.runs, 0);
    scene_free(&sc);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tet_arap_equals_full),
        cmocka_unit_test(test_tri_arap_equals_full),
        cmocka_unit_test(test_tet_neohookean_equals_full),
        cmocka_unit_test(test_tri_tail_equals_full),
        cmocka_unit_test(test_region_grows_with_drag),
        cmocka_unit_test(test_certificate_grows_region),
        cmocka_unit_test(test_tail_test_follows_full),
        cmocka_unit_test(test_tail_region_kept),
        cmocka_unit_test(test_set_positions_and_reset_rest),
        cmocka_unit_test(test_affine_falls_back),
        cmocka_unit_test(test_bad_params),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
