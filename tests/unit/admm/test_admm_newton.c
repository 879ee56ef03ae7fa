/* Unit tests of the second-order polish df_admm_polish (core/admm/admm_newton.c): the analytic
 * gradient of the objective and the density Hessians against finite differences; full-space
 * (w = 0) Neo-Hookean and ARAP on a small tet bar reach a KKT residual < 1e-9 with an objective
 * <= ADMM's (and <= a 20x longer ADMM run's), no inverted element ever accepted; with w > 0 the
 * vertices left at rest satisfy the subgradient condition |grad E_elastic,i| <= w a_i (checked by
 * finite differences of df_admm_evaluate); affine constraints keep holding; the symbolic analysis
 * is reused for an unchanged support; the inversion-safe step bound matches a dense scan of
 * det(F + t D); df_admm_kkt agrees with the polish; a rough Neo-Hookean start (10 ADMM iterations,
 * strong locality) reaches the same optimum as a 300-iteration one; a follower (duplicated vertex
 * in a zero-volume tet) ends on its twin at the clean mesh's optimum; unsupported energies and bad
 * states are refused with the solver unchanged. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include "core/admm/admm.h"
#include "core/admm/admm_newton.h"
#include "tests/unit/admm/admm_test_util.h"

/* objective of V through the public evaluation (elastic + locality) */
static double eval(const df_admm *s, const double *V)
{
    double el, lo;
    df_error err;
    if (df_admm_evaluate(s, V, &el, &lo, &err)) return INFINITY;
    return el + lo;
}

static double det3(const double *a, const double *b, const double *c, const double *d)
{
    double u[3], v[3], w[3];
    for (int k = 0; k < 3; k++) { u[k] = b[k] - a[k]; v[k] = c[k] - a[k]; w[k] = d[k] - a[k]; }
    return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0]);
}

static int count_inverted(const df_mesh *m, const double *V)
{
    int n = 0;
    for (int32_t e = 0; e < m->ne; e++) {
        const int32_t *el = m->E + 4 * e;
        double d0 = det3(m->V + 3 * el[0], m->V + 3 * el[1], m->V + 3 * el[2], m->V + 3 * el[3]);
        double d1 = det3(V + 3 * el[0], V + 3 * el[1], V + 3 * el[2], V + 3 * el[3]);
        if (!(d0 * d1 > 0)) n++;
    }
    return n;
}

static df_admm *make(const df_mesh *m, df_admm_energy en, double w, double s_thr, double rho,
                     const int32_t *h, int nh, const double *tg)
{
    df_admm_params p;
    df_admm_params_default(&p, en);
    p.threads = 1;
    p.w = w; p.s = s_thr; p.rho = rho;
    df_admm *s = NULL;
    df_error err;
    assert_int_equal(df_admm_create(m, &p, h, nh, NULL, 0, &s, &err), DF_OK);
    assert_int_equal(df_admm_set_targets(s, tg, &err), DF_OK);
    return s;
}

/* analytic gradient (admm_newton_gradient) vs central differences of df_admm_evaluate at a
 * perturbed shape where some vertices are within s of rest and some beyond */
static void gradient_check(df_admm_energy en)
{
    tu_bar bh = tu_bar_load();
    df_admm *s = make(&bh.m, en, en == DF_ADMM_NEOHOOKEAN ? 3e5 : 1e-2, 0.05, en == DF_ADMM_NEOHOOKEAN ? 5e7 : 1.0,
                      bh.h, bh.nh, bh.tg);
    double *V = malloc((size_t)bh.m.nv * 24), *g = malloc((size_t)bh.m.nv * 24);
    srand(7);
    for (int32_t i = 0; i < bh.m.nv; i++)
        for (int k = 0; k < 3; k++) {
            double amp = (i % 3 == 0) ? 0.0 : (i % 3 == 1 ? 0.02 : 0.08); /* rest, inside s, beyond s */
            V[3 * i + k] = bh.m.V[3 * i + k] + amp * (2.0 * rand() / RAND_MAX - 1.0) + (i % 3 == 1 ? 0.005 : 0.0);
        }
    assert_int_equal(count_inverted(&bh.m, V), 0);
    assert_int_equal(admm_newton_gradient((const struct df_admm *)s, V, g, NULL, NULL), 0);
    double worst = 0, gmax = 0;
    for (int32_t i = 0; i < bh.m.nv; i++) {
        if (i % 3 == 0) continue; /* SC-L1 is not differentiable at rest */
        for (int k = 0; k < 3; k++) {
            double h0 = 1e-6, x = V[3 * i + k];
            V[3 * i + k] = x + h0;
            double ep = eval(s, V);
            V[3 * i + k] = x - h0;
            double em = eval(s, V);
            V[3 * i + k] = x;
            double fd = (ep - em) / (2 * h0);
            worst = fmax(worst, fabs(fd - g[3 * i + k]));
            gmax = fmax(gmax, fabs(g[3 * i + k]));
        }
    }
    assert_true(gmax > 0);
    assert_true(worst <= 1e-6 * gmax);
    free(V); free(g);
    df_admm_free(s);
    tu_bar_free(&bh);
}

static void test_gradient_nh(void **st) { (void)st; gradient_check(DF_ADMM_NEOHOOKEAN); }
static void test_gradient_arap(void **st) { (void)st; gradient_check(DF_ADMM_ARAP); }
static void test_gradient_acap(void **st) { (void)st; gradient_check(DF_ADMM_ACAP); }

/* exact density Hessians vs differences of P; projected ones are PSD and equal the exact one
 * where that is PD */
static void test_density_hessian(void **st)
{
    (void)st;
    const df_admm_energy ens[3] = {DF_ADMM_NEOHOOKEAN, DF_ADMM_ARAP, DF_ADMM_ACAP};
    const double Fs[3][9] = {{1.1, 0.2, -0.1, 0.05, 0.9, 0.3, -0.2, 0.1, 1.2},
                             {0.6, -0.3, 0.1, 0.2, 0.5, 0.0, 0.1, 0.1, 0.7},   /* compressed: twist modes negative */
                             {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0}};
    for (int ei = 0; ei < 3; ei++)
        for (int fi = 0; fi < 3; fi++) {
            double P[9], H[81], Hp[81];
            assert_true(admm_newton_density(ens[ei], 2.0, 5.0, Fs[fi], P, H, 0) >= 0);
            admm_newton_density(ens[ei], 2.0, 5.0, Fs[fi], P, Hp, 1);
            double worst = 0, hmax = 0;
            for (int c = 0; c < 9; c++) {
                double F1[9], F2[9], P1[9], P2[9], hh = 1e-6;
                memcpy(F1, Fs[fi], sizeof(F1)); memcpy(F2, Fs[fi], sizeof(F2));
                F1[c] += hh; F2[c] -= hh;
                admm_newton_density(ens[ei], 2.0, 5.0, F1, P1, NULL, 0);
                admm_newton_density(ens[ei], 2.0, 5.0, F2, P2, NULL, 0);
                for (int r = 0; r < 9; r++) {
                    worst = fmax(worst, fabs((P1[r] - P2[r]) / (2 * hh) - H[9 * r + c]));
                    hmax = fmax(hmax, fabs(H[9 * r + c]));
                }
            }
            assert_true(worst <= 1e-6 * hmax);
            /* PSD: x^T Hp x >= 0 for the unit vectors and random directions */
            srand(3);
            for (int t = 0; t < 50; t++) {
                double x[9], q = 0, nx = 0;
                for (int k = 0; k < 9; k++) { x[k] = 2.0 * rand() / RAND_MAX - 1.0; nx += x[k] * x[k]; }
                for (int r = 0; r < 9; r++)
                    for (int c = 0; c < 9; c++) q += x[r] * Hp[9 * r + c] * x[c];
                assert_true(q >= -1e-12 * hmax * nx);
            }
        }
}

static double mdet(const double F[9])
{
    return F[0] * (F[4] * F[8] - F[5] * F[7]) - F[1] * (F[3] * F[8] - F[5] * F[6]) + F[2] * (F[3] * F[7] - F[4] * F[6]);
}

/* the inversion-safe step bound against a dense scan of det(F + t D) */
static void test_det_step(void **st)
{
    (void)st;
    srand(11);
    int finite = 0;
    for (int trial = 0; trial < 200; trial++) {
        double F[9], D[9];
        do {
            for (int k = 0; k < 9; k++) F[k] = (k % 4 == 0 ? 1.0 : 0.0) + 0.4 * (2.0 * rand() / RAND_MAX - 1.0);
        } while (!(mdet(F) > 0.05));
        for (int k = 0; k < 9; k++) D[k] = 1.5 * (2.0 * rand() / RAND_MAX - 1.0);
        double t = admm_newton_det_step(F, D, 2.0);
        double end = isfinite(t) ? t : 2.0, G[9];
        for (int q = 0; q < 2000; q++) { /* positive everywhere before t */
            double a = end * q / 2000.0 * (1 - 1e-9);
            for (int k = 0; k < 9; k++) G[k] = F[k] + a * D[k];
            assert_true(mdet(G) > 0);
        }
        if (isfinite(t)) { /* a root: det vanishes at t and is not positive just past it */
            finite++;
            assert_true(t > 0 && t <= 2.0);
            for (int k = 0; k < 9; k++) G[k] = F[k] + t * D[k];
            assert_true(fabs(mdet(G)) <= 1e-9 * (1 + fabs(mdet(F))));
            for (int k = 0; k < 9; k++) G[k] = F[k] + t * (1 + 1e-6) * D[k];
            assert_true(mdet(G) <= 1e-12);
        }
    }
    assert_true(finite > 20 && finite < 200); /* both cases were exercised */
}

/* df_admm_kkt: above the target at ADMM's positions, below after the polish; refusals */
static void test_kkt_function(void **st)
{
    (void)st;
    tu_bar bh = tu_bar_load();
    df_admm *s = make(&bh.m, DF_ADMM_NEOHOOKEAN, 0.0, 0.01, 5e5, bh.h, bh.nh, bh.tg);
    df_error err;
    assert_int_equal(df_admm_run(s, &(df_admm_budget){30, 0, 0, NULL, NULL}, NULL, &err), DF_OK);
    double k0 = -1, k1 = -1;
    assert_int_equal(df_admm_kkt(s, df_admm_positions(s), &k0, &err), DF_OK);
    df_admm_polish_result pr;
    assert_int_equal(df_admm_polish(s, NULL, &pr, &err), DF_OK);
    assert_int_equal(df_admm_kkt(s, df_admm_positions(s), &k1, &err), DF_OK);
    assert_true(k0 > 1e-6);
    assert_true(k1 < 1e-9);
    assert_true(fabs(k1 - pr.kkt) <= 1e-3 * pr.kkt + 1e-15);
    double *V = malloc((size_t)bh.m.nv * 24);
    memcpy(V, df_admm_positions(s), (size_t)bh.m.nv * 24);
    V[3 * 20] = NAN;
    assert_int_equal(df_admm_kkt(s, V, &k1, &err), DF_EINVAL);
    assert_int_equal(df_admm_kkt(s, NULL, &k1, &err), DF_EINVAL);
    free(V);
    df_admm_free(s);
    tu_bar_free(&bh);
}

/* Neo-Hookean with a strong locality weight from a rough ADMM start (10 iterations: V off Z by a
 * large primal residual): converges, nothing inverted, and to the
 * objective reached from a 300-iteration start */
static void test_rough_start_nh(void **st)
{
    (void)st;
    df_mesh m = tu_bar3d(12, 2, 2, 6.0, 1.0, 1.0);
    int32_t h[64];
    double tg[64 * 3];
    int nh = 0;
    for (int32_t i = 0; i < m.nv; i++)
        if (m.V[3 * i] == 6.0 || m.V[3 * i] == 0.0) {
            h[nh] = i;
            memcpy(tg + 3 * nh, m.V + 3 * i, 24);
            if (m.V[3 * i] == 6.0) tg[3 * nh + 1] += 0.4;
            nh++;
        }
    double E[2];
    for (int pass = 0; pass < 2; pass++) {
        df_admm *s = make(&m, DF_ADMM_NEOHOOKEAN, 2e4, 0.01, 5e6, h, nh, tg);
        df_error err;
        assert_int_equal(df_admm_run(s, &(df_admm_budget){pass ? 300 : 10, 0, 0, NULL, NULL}, NULL, &err), DF_OK);
        df_admm_polish_result pr;
        assert_int_equal(df_admm_polish(s, &(df_admm_polish_params){200, 0, 0, 0}, &pr, &err), DF_OK);
        assert_true(pr.converged && pr.kkt < 1e-9);
        assert_int_equal(count_inverted(&m, df_admm_positions(s)), 0);
        for (int k = 0; k < pr.hist_n; k++) assert_true(isfinite(pr.hist_objective[k]));
        E[pass] = pr.objective;
        df_admm_free(s);
    }
    assert_true(fabs(E[0] - E[1]) <= 1e-9 * E[1]);
    tu_free(&m);
}

/* a duplicated vertex in a zero-volume tet (a follower): polished with the rest, placed on its
 * twin, the optimum that of the mesh without them */
static void test_follower(void **st)
{
    (void)st;
    tu_bar bh = tu_bar_load();
    int32_t c = -1, n1 = -1, n2 = -1;
    for (int32_t i = 0; i < bh.m.nv; i++) {
        const double *x = bh.m.V + 3 * i;
        if (x[0] == 1.5 && x[1] == 0.5 && x[2] == 0.5) c = i;
        if (x[0] == 2.0 && x[1] == 0.5 && x[2] == 0.5) n1 = i;
        if (x[0] == 1.5 && x[1] == 1.0 && x[2] == 0.5) n2 = i;
    }
    assert_true(c >= 0 && n1 >= 0 && n2 >= 0);
    df_mesh d = bh.m;
    d.nv = bh.m.nv + 1;
    d.ne = bh.m.ne + 1;
    d.V = malloc((size_t)d.nv * 24);
    d.E = malloc((size_t)d.ne * 16);
    memcpy(d.V, bh.m.V, (size_t)bh.m.nv * 24);
    memcpy(d.V + 3 * bh.m.nv, bh.m.V + 3 * c, 24);
    memcpy(d.E, bh.m.E, (size_t)bh.m.ne * 16);
    int32_t ex[4] = {bh.m.nv, c, n1, n2};
    memcpy(d.E + 4 * bh.m.ne, ex, 16);
    double E[2];
    for (int k = 0; k < 2; k++) {
        df_admm *s = make(k ? &d : &bh.m, DF_ADMM_NEOHOOKEAN, 0.0, 0.01, 5e5, bh.h, bh.nh, bh.tg);
        df_error err;
        df_admm_degenerate dg;
        df_admm_get_degenerate(s, &dg);
        assert_int_equal(dg.followers, k ? 1 : 0);
        assert_int_equal(df_admm_run(s, &(df_admm_budget){60, 0, 0, NULL, NULL}, NULL, &err), DF_OK);
        df_admm_polish_result pr;
        assert_int_equal(df_admm_polish(s, NULL, &pr, &err), DF_OK);
        assert_true(pr.converged);
        E[k] = pr.objective;
        const double *V = df_admm_positions(s);
        if (k) {
            assert_true(tu_dist(V + 3 * bh.m.nv, V + 3 * c) <= 1e-12);
            assert_true(tu_dist(V + 3 * c, bh.m.V + 3 * c) > 1e-3); /* the twin did move */
        }
        df_admm_free(s);
    }
    assert_true(fabs(E[0] - E[1]) <= 1e-10 * E[0]);
    free(d.V); free(d.E);
    tu_bar_free(&bh);
}

/* w = 0: every non-handle vertex free */
static void full_space(df_admm_energy en, double rho)
{
    tu_bar bh = tu_bar_load();
    df_admm *s = make(&bh.m, en, 0.0, 0.01, rho, bh.h, bh.nh, bh.tg);
    df_error err;
    df_admm_result ar;
    assert_int_equal(df_admm_run(s, &(df_admm_budget){100, 0, 0, NULL, NULL}, &ar, &err), DF_OK);
    df_admm_polish_result pr;
    assert_int_equal(df_admm_polish(s, NULL, &pr, &err), DF_OK);
    assert_true(pr.converged);
    assert_true(pr.kkt < 1e-9);
    assert_true(pr.iterations >= 1);
    assert_true(pr.objective <= ar.objective);
    assert_true(fabs(pr.objective_admm - ar.objective) <= 1e-12 * ar.objective);
    assert_int_equal(pr.support, bh.m.nv - bh.nh);
    assert_int_equal(pr.violations, 0);
    /* every accepted iterate had a finite (uninverted) energy, the history is non-increasing up to
     * roundoff */
    for (int k = 0; k < pr.hist_n; k++) {
        assert_true(isfinite(pr.hist_objective[k]));
        if (k > 0) assert_true(pr.hist_objective[k] <= pr.hist_objective[k - 1] * (1 + 1e-12));
    }
    const double *V = df_admm_positions(s);
    assert_int_equal(count_inverted(&bh.m, V), 0);
    assert_true(fabs(eval(s, V) - pr.objective) <= 1e-12 * pr.objective);
    for (int k = 0; k < bh.nh; k++) assert_memory_equal(V + 3 * bh.h[k], bh.tg + 3 * k, 24);
    /* an independent reference: 20x more ADMM iterations from the same start do not beat it */
    df_admm *s2 = make(&bh.m, en, 0.0, 0.01, rho, bh.h, bh.nh, bh.tg);
    df_admm_result ar2;
    assert_int_equal(df_admm_run(s2, &(df_admm_budget){2000, 0, 0, NULL, NULL}, &ar2, &err), DF_OK);
    assert_true(pr.objective <= ar2.objective * (1 + 1e-12));
    /* a second polish: same support, analysis reused, already converged */
    df_admm_polish_result pr2;
    assert_int_equal(df_admm_polish(s, NULL, &pr2, &err), DF_OK);
    assert_true(pr2.converged);
    assert_int_equal(pr2.analyses, 0);
    df_admm_free(s2);
    df_admm_free(s);
    tu_bar_free(&bh);
}

static void test_full_space_nh(void **st) { (void)st; full_space(DF_ADMM_NEOHOOKEAN, 5e5); }
static void test_full_space_arap(void **st) { (void)st; full_space(DF_ADMM_ARAP, 0.1); }
static void test_full_space_acap(void **st) { (void)st; full_space(DF_ADMM_ACAP, 0.1); }

/* w > 0 on a longer bar pulled at one end: part of it stays at rest; the subgradient condition
 * holds there (finite differences of the elastic energy) */
static void locality_case(df_admm_energy en, double w, double s_thr, double rho)
{
    df_mesh m = tu_bar3d(12, 2, 2, 6.0, 1.0, 1.0);
    int32_t h[64];
    double tg[64 * 3];
    int nh = 0;
    for (int32_t i = 0; i < m.nv; i++) {
        double x = m.V[3 * i];
        if (x == 6.0) {
            h[nh] = i;
            memcpy(tg + 3 * nh, m.V + 3 * i, 24);
            tg[3 * nh + 1] += 0.3;
            nh++;
        }
    }
    df_admm *s = make(&m, en, w, s_thr, rho, h, nh, tg);
    df_error err;
    assert_int_equal(df_admm_run(s, &(df_admm_budget){300, 0, 0, NULL, NULL}, NULL, &err), DF_OK);
    df_admm_polish_result pr;
    assert_int_equal(df_admm_polish(s, NULL, &pr, &err), DF_OK);
    assert_true(pr.converged);
    assert_true(pr.kkt < 1e-9);
    assert_int_equal(pr.violations, 0);
    const double *V0 = df_admm_positions(s);
    double *V = malloc((size_t)m.nv * 24);
    memcpy(V, V0, (size_t)m.nv * 24);
    int rest = 0, moved = 0;
    double worst = 0;
    for (int32_t i = 0; i < m.nv; i++) {
        if (m.V[3 * i] == 6.0) continue;
        if (memcmp(V + 3 * i, m.V + 3 * i, 24)) { moved++; continue; }
        rest++;
        double g[3];
        for (int k = 0; k < 3; k++) {
            double hh = 1e-6, el_p, el_m;
            V[3 * i + k] = m.V[3 * i + k] + hh;
            assert_int_equal(df_admm_evaluate(s, V, &el_p, NULL, &err), DF_OK);
            V[3 * i + k] = m.V[3 * i + k] - hh;
            assert_int_equal(df_admm_evaluate(s, V, &el_m, NULL, &err), DF_OK);
            V[3 * i + k] = m.V[3 * i + k];
            g[k] = (el_p - el_m) / (2 * hh);
        }
        worst = fmax(worst, sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]) / w); /* a_i = 1 */
    }
    assert_true(rest > 0 && moved > 0);
    assert_true(pr.support == moved);
    assert_true(worst <= 1.0 + 1e-5);
    assert_int_equal(count_inverted(&m, V), 0);
    free(V);
    df_admm_free(s);
    tu_free(&m);
}

static void test_locality_nh(void **st) { (void)st; locality_case(DF_ADMM_NEOHOOKEAN, 2e4, 0.01, 5e6); }
static void test_locality_arap(void **st) { (void)st; locality_case(DF_ADMM_ARAP, 2e-3, 0.01, 0.5); }

/* affine sets: polished in their null space, constraints still hold */
static void test_affine_kept(void **st)
{
    (void)st;
    tu_bar bh = tu_bar_load();
    int32_t line[64];
    int nl = 0;
    for (int32_t i = 0; i < bh.m.nv; i++)
        if (bh.m.V[3 * i] > 0 && bh.m.V[3 * i] < 3.0 && bh.m.V[3 * i + 1] == 0.0 && bh.m.V[3 * i + 2] == 0.0)
            line[nl++] = i;
    df_admm_affine aff = {nl, line, 1, {0, 0, 1, 0, 0, 0, 0, 0, 0}, {0.0, 0, 0}}; /* z = 0 */
    df_admm_params p;
    df_admm_params_default(&p, DF_ADMM_NEOHOOKEAN);
    p.threads = 1;
    p.w = 0.0;
    df_admm *s = NULL;
    df_error err;
    assert_int_equal(df_admm_create(&bh.m, &p, bh.h, bh.nh, &aff, 1, &s, &err), DF_OK);
    assert_int_equal(df_admm_set_targets(s, bh.tg, &err), DF_OK);
    assert_int_equal(df_admm_run(s, &(df_admm_budget){100, 0, 0, NULL, NULL}, NULL, &err), DF_OK);
    double before = eval(s, df_admm_positions(s));
    df_admm_polish_result pr;
    assert_int_equal(df_admm_polish(s, NULL, &pr, &err), DF_OK);
    assert_true(pr.converged);
    assert_true(pr.objective <= before);
    const double *V = df_admm_positions(s);
    for (int k = 0; k < nl; k++) assert_true(fabs(V[3 * line[k] + 2]) <= 1e-12);
    double ymove = 0;
    for (int k = 0; k < nl; k++) ymove = fmax(ymove, fabs(V[3 * line[k] + 1]));
    assert_true(ymove > 1e-3); /* they did move, in the plane */
    df_admm_free(s);
    tu_bar_free(&bh);
}

static void test_refusals(void **st)
{
    (void)st;
    df_error err;
    /* triangles (spokes and rims): unsupported */
    df_mesh g = tu_grid2d(4, 4, 1.0, 1.0);
    int32_t hg[2] = {0, 24};
    double tgg[6] = {0, 0, 0, 1.2, 1.0, 0};
    df_admm *sg = make(&g, DF_ADMM_ARAP, 1e-4, 0.01, 0.1, hg, 2, tgg);
    assert_int_equal(df_admm_run(sg, &(df_admm_budget){5, 0, 0, NULL, NULL}, NULL, &err), DF_OK);
    assert_int_equal(df_admm_polish(sg, NULL, NULL, &err), DF_EUNSUPPORTED);
    assert_non_null(strstr(err.msg, "tet"));
    df_admm_free(sg);
    tu_free(&g);
    /* targets set but never run: handles not at their targets */
    tu_bar bh = tu_bar_load();
    df_admm *s = make(&bh.m, DF_ADMM_ARAP, 1e-4, 0.01, 0.1, bh.h, bh.nh, bh.tg);
    double *V0 = malloc((size_t)bh.m.nv * 24);
    memcpy(V0, df_admm_positions(s), (size_t)bh.m.nv * 24);
    assert_int_equal(df_admm_polish(s, NULL, NULL, &err), DF_ESTATE);
    assert_non_null(strstr(err.msg, "target"));
    assert_memory_equal(V0, df_admm_positions(s), (size_t)bh.m.nv * 24);
    df_admm_polish_params bad = {DF_ADMM_POLISH_MAX_ITERS + 1, 0, 0, 0};
    assert_int_equal(df_admm_polish(s, &bad, NULL, &err), DF_EINVAL);
    bad = (df_admm_polish_params){10, NAN, 0, 0};
    assert_int_equal(df_admm_polish(s, &bad, NULL, &err), DF_EINVAL);
    bad = (df_admm_polish_params){10, 0, -1.0, 0};
    assert_int_equal(df_admm_polish(s, &bad, NULL, &err), DF_EINVAL);
    assert_int_equal(df_admm_polish(NULL, NULL, NULL, &err), DF_EINVAL);
    assert_memory_equal(V0, df_admm_positions(s), (size_t)bh.m.nv * 24);
    free(V0);
    df_admm_free(s);
    tu_bar_free(&bh);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gradient_nh),
        cmocka_unit_test(test_gradient_arap),
        cmocka_unit_test(test_gradient_acap),
        cmocka_unit_test(test_density_hessian),
        cmocka_unit_test(test_full_space_nh),
        cmocka_unit_test(test_full_space_arap),
        cmocka_unit_test(test_full_space_acap),
        cmocka_unit_test(test_locality_nh),
        cmocka_unit_test(test_locality_arap),
        cmocka_unit_test(test_affine_kept),
        cmocka_unit_test(test_refusals),
        cmocka_unit_test(test_det_step),
        cmocka_unit_test(test_kkt_function),
        cmocka_unit_test(test_rough_start_nh),
        cmocka_unit_test(test_follower),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
