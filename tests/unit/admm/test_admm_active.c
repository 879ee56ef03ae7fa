/* Unit tests of the active-set mode (admm.h DF_ADMM_ACTIVE): on a tet grid (ARAP and Neo-Hookean,
 * the element family) and a planar triangle grid (ARAP, spokes and rims), a drag solved in active
 * mode and converged equals the full solve (params.active = 0) within 1e-8 relative objective and
 * 1e-8 positions; the vertices outside the region stay bitwise at rest; the region grows when the
 * handle drags further and shrinks when it comes back; with a band of one ring only the far-field certificate can grow the region
 * and it does; the tail test makes a 20-iteration update follow the full solve's iterate closely
 * (and converges to the same result), and its probe redoes a first iteration that grew the region
 * (one reported iteration is the full solve's first iterate); set_positions and reset_rest keep working in active mode (same result as the full
 * solve); affine constraints fall back to the full solve (bit-identical to it); bad parameters are
 * refused. Expected values come from the full solve of the same problem. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include "core/admm/admm.h"
#include "tests/unit/admm/admm_test_util.h"
#include "tests/unit/admm/active_scene.h"

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
    pa.active_tail = 3e-4;
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
 * (Dirichlet at rest on the fringe) does: the region grows, by the rings the charge's decay asks
 * for, wherever its edge still carries SC-L1 charge. Expected values: the full solve of the same update; converged, the result
 * is the full solve's as without the test. */
static void test_tail_test_follows_full(void **state)
{
    (void)state;
    scene sc;
    tet_scene(&sc, 16);
    df_admm_params pf = arap_params(&sc, 0), pa = arap_params(&sc, 1), pt = pa;
    pt.active_tail = 3e-4;
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
    pt.active_tail = 3e-4;
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

/* hops over the vertex graph (vertices sharing an element) from the dragged handles, into dist
 * (nv; -1: not reached) */
static void hops_from_drag(const scene *sc, int32_t *dist)
{
    const df_mesh *m = &sc->m;
    int32_t nv = m->nv, ne = m->ne, esz = 4;
    for (int32_t i = 0; i < nv; i++) dist[i] = -1;
    for (int k = 0; k < sc->nh; k++)
        if (sc->drag[k]) dist[sc->h[k]] = 0;
    for (int changed = 1, d = 0; changed; d++) { /* level by level over the elements */
        changed = 0;
        for (int32_t e = 0; e < ne; e++) {
            const int32_t *el = m->E + (size_t)e * esz;
            int touch = 0;
            for (int c = 0; c < esz; c++) touch |= dist[el[c]] == d;
            if (!touch) continue;
            for (int c = 0; c < esz; c++)
                if (dist[el[c]] < 0) { dist[el[c]] = d + 1; changed = 1; }
        }
    }
}

/* the tail test's probe (admm.h "Tail test"): a drag's first update starts on a region built
 * from the handles, and its first iteration shows the region too small; the region grows (several
 * rings at once where the edge carries charge) and the iteration is redone from the state before
 * it. Expected values: the full solve's first and second iterates of the same update. After one
 * reported iteration the tail-test solver is at the full solve's first iterate (far closer than
 * the plain band's first iterate, and not at the second iterate: the probe's iteration left no
 * trace); the region grew by several rings at once but not by whole rings (the moved vertices,
 * the region's, reach more than one ring beyond the first region, the handles + 3 rings, yet are
 * fewer than the vertices within that many rings of the handles), and converged the result is the
 * full solve's. */
static void test_tail_probe(void **state)
{
    (void)state;
    scene sc;
    tet_scene(&sc, 16);
    df_admm_params pf = arap_params(&sc, 0), pa = arap_params(&sc, 1), pt = pa;
    pt.active_tail = DF_ADMM_ACTIVE_TAIL;
    df_admm *full = make(&sc, &pf), *full2 = make(&sc, &pf), *band = make(&sc, &pa), *tail = make(&sc, &pt);
    set_drag2(full, full2, &sc, 0.3);
    set_drag2(band, tail, &sc, 0.3);
    df_admm_result r1, r2, rb, rt;
    run2(full, full2, 1, &r1, NULL);
    r2 = run(full2, 1); /* the full solve's second iterate */
    run2(band, tail, 1, &rb, &rt);
    assert_int_equal(rt.iterations, 1);
    df_admm_active_stats st, sb;
    df_admm_get_active_stats(tail, &st);
    df_admm_get_active_stats(band, &sb);
    double E1 = fabs(r1.objective);
    double d_tail = fabs(rt.objective - r1.objective) / E1, d_band = fabs(rb.objective - r1.objective) / E1;
    double d_12 = fabs(r2.objective - r1.objective) / E1;
    print_message("1 iteration: probes %ld, tail grows %ld, region %d (band %d) of %d; |E - E_full1| / E_full1: tail "
                  "%.2e, band %.2e; second full iterate %.2e away\n", st.tail_probes, st.tail_grows, st.region_vertices,
                  sb.region_vertices, sc.m.nv, d_tail, d_band, d_12);
    assert_true(st.tail_probes >= 1);
    assert_int_equal(st.tail_probes, st.tail_grows);
    assert_int_equal(sb.tail_probes, 0);
    assert_true(st.region_vertices > sb.region_vertices);
    assert_true(d_tail * 10.0 < d_band);
    assert_true(d_tail * 10.0 < d_12);
    assert_int_equal(st.fallbacks, 0);
    int32_t moved = count_moved(tail, &sc.m);
    assert_true(moved <= st.region_vertices);
    int32_t *dist = malloc((size_t)sc.m.nv * sizeof(int32_t)), dmax = 0, ball = 0;
    hops_from_drag(&sc, dist);
    const double *V = df_admm_positions(tail);
    for (int32_t i = 0; i < sc.m.nv; i++)
        if (memcmp(V + 3 * (size_t)i, sc.m.V + 3 * (size_t)i, 3 * sizeof(double)) && dist[i] > dmax) dmax = dist[i];
    for (int32_t i = 0; i < sc.m.nv; i++) ball += dist[i] >= 0 && dist[i] <= dmax;
    print_message("moved %d vertices, up to %d rings from the dragged handles; %d vertices within %d rings\n", moved,
                  dmax, ball, dmax);
    free(dist);
    assert_true(dmax > DF_ADMM_ACTIVE_BAND + 1);
    assert_true(moved < ball);
    df_admm_result rf, rc;
    run2(full, tail, 20000, &rf, &rc);
    assert_same(full, tail, &rf, &rc, sc.m.nv);
    df_admm_free(full2);
    df_admm_free(band);
    free_pair(full, tail, &sc);
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
        cmocka_unit_test(test_tail_probe),
        cmocka_unit_test(test_set_positions_and_reset_rest),
        cmocka_unit_test(test_affine_falls_back),
        cmocka_unit_test(test_bad_params),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
