/* Unit tests of the non-ARAP energies: cloth (per-triangle ARAP in 3D + hard strain limits +
 * quadratic bending) respects its strain limit where plain ARAP does not, a 1D polyline returns
 * to its rest shape when its handle returns, ACAP reaches zero energy on a uniform scaling that ARAP
 * cannot follow (2D spokes-and-rims and tets), and Neo-Hookean on tets keeps every element
 * uninverted and reaches a lower Neo-Hookean energy than the ARAP solution. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include "core/admm/admm.h"
#include "core/admm/svd3.h"
#include "tests/unit/admm/admm_test_util.h"

/* largest / smallest singular value of the 3x2 deformation gradients of a triangle mesh */
static void cloth_strain(const df_mesh *m, const double *V, double *smax, double *smin)
{
    *smax = 0; *smin = INFINITY;
    for (int e = 0; e < m->ne; e++) {
        const int32_t *el = m->E + 3 * e;
        const double *X0 = m->V + 3 * el[0], *X1 = m->V + 3 * el[1], *X2 = m->V + 3 * el[2];
        /* rest edges in the plane (z = 0): Dm 2x2 */
        double a = X1[0] - X0[0], b = X2[0] - X0[0], c = X1[1] - X0[1], d = X2[1] - X0[1];
        double det = a * d - b * c, inv[4] = {d / det, -b / det, -c / det, a / det};
        double F[6];
        for (int r = 0; r < 3; r++) {
            double e1 = V[3 * el[1] + r] - V[3 * el[0] + r], e2 = V[3 * el[2] + r] - V[3 * el[0] + r];
            F[2 * r] = e1 * inv[0] + e2 * inv[2];
            F[2 * r + 1] = e1 * inv[1] + e2 * inv[3];
        }
        double sg[2];
        df_admm_svd32(F, NULL, sg, NULL);
        if (sg[0] > *smax) *smax = sg[0];
        if (sg[1] < *smin) *smin = sg[1];
    }
}

static double run_cloth(const df_mesh *m, const int32_t *h, int nh, const double *tg, double smax_lim, double *smax, double *smin)
{
    df_admm_params p;
    df_admm_params_default(&p, DF_ADMM_CLOTH);
    p.threads = 1; /* correctness tests: one thread (the machine may be shared) */
    p.w = 1e-4; p.s = 0.05; p.rho = 5e-3;
    p.strain_min = 0.5; p.strain_max = smax_lim;
    p.bending = 1e-4;
    p.tol = 1e-13; p.max_iters = 3000;
    df_admm *s = NULL;
    df_error err;
    assert_int_equal(df_admm_create(m, &p, h, nh, NULL, 0, &s, &err), DF_OK);
    assert_int_equal(df_admm_set_targets(s, tg, &err), DF_OK);
    df_admm_result r;
    assert_int_equal(df_admm_run(s, NULL, &r, &err), DF_OK);
    cloth_strain(m, df_admm_positions(s), smax, smin);
    printf("cloth limit %.2f: %d its, E %.6g (elastic %.4g), stretch in [%.4f, %.4f], center z %.4f\n", smax_lim,
           r.iterations, r.objective, r.elastic, *smin, *smax, df_admm_positions(s)[3 * h[nh - 1] + 2]);
    df_admm_free(s);
    return r.objective;
}

static void test_cloth_strain_limit(void **st)
{
    (void)st;
    df_mesh m = tu_grid2d(16, 16, 1.0, 1.0);
    m.planar = 0;   /* a flat 3D cloth: its centre is pulled out of the plane */
    int32_t h[128];
    double tg[128 * 3];
    int nh = 0;
    for (int32_t i = 0; i < m.nv; i++) {
        double x = m.V[3 * i], y = m.V[3 * i + 1];
        if (x == 0 || y == 0 || x == 1.0 || y == 1.0) { h[nh] = i; memcpy(tg + 3 * nh, m.V + 3 * i, 24); nh++; }
    }
    int32_t c = 8 * 17 + 8; /* center vertex, pulled out of the plane */
    h[nh] = c;
    memcpy(tg + 3 * nh, m.V + 3 * c, 24);
    tg[3 * nh + 2] = 0.18;
    nh++;
    double smax_free, smin_free, smax_lim, smin_lim;
    run_cloth(&m, h, nh, tg, 10.0, &smax_free, &smin_free);
    run_cloth(&m, h, nh, tg, 1.1, &smax_lim, &smin_lim);
    assert_true(smax_free > 1.15);        /* without the limit the pull stretches elements more */
    assert_true(smax_lim <= 1.1 + 2e-3);  /* with it, the stretch stays at the limit */
    assert_true(smin_lim >= 0.5 - 2e-3);
    tu_free(&m);
}

static void test_polyline_returns_to_rest(void **st)
{
    (void)st;
    df_mesh m;
    memset(&m, 0, sizeof(m));
    m.kind = DF_MESH_POLYLINE;
    m.planar = 1;
    m.nv = 40;
    m.ne = 39;
    m.V = calloc(120, sizeof(double));
    m.E = malloc(78 * sizeof(int32_t));
    for (int i = 0; i < 40; i++) { m.V[3 * i] = i / 39.0; m.V[3 * i + 1] = 0.1 * sin(6.0 * i / 39.0); }
    for (int i = 0; i < 39; i++) { m.E[2 * i] = i; m.E[2 * i + 1] = i + 1; }
    int32_t h[2] = {0, 25};
    double rest[6], moved[6];
    memcpy(rest, m.V, 24); memcpy(rest + 3, m.V + 75, 24);
    memcpy(moved, rest, sizeof(rest));
    moved[4] += 0.25; moved[3] -= 0.05;
    df_admm_params p;
    df_admm_params_default(&p, DF_ADMM_POLYLINE);
    p.threads = 1; /* correctness tests: one thread (the machine may be shared) */
    p.w = 1e-3; p.s = 0.1; p.rho = 0.05; p.tol = 1e-14; p.max_iters = 5000;
    df_admm *s = NULL;
    df_error err;
    assert_int_equal(df_admm_create(&m, &p, h, 2, NULL, 0, &s, &err), DF_OK);
    assert_int_equal(df_admm_set_targets(s, moved, &err), DF_OK);
    df_admm_result r1, r2;
    assert_int_equal(df_admm_run(s, NULL, &r1, &err), DF_OK);
    double maxmove = 0, farmove = 0;
    for (int i = 0; i < 40; i++) {
        double d = tu_dist(df_admm_positions(s) + 3 * i, m.V + 3 * i);
        maxmove = fmax(maxmove, d);
        if (i >= 33) farmove = fmax(farmove, d);
    }
    assert_int_equal(df_admm_set_targets(s, rest, &err), DF_OK);
    assert_int_equal(df_admm_run(s, NULL, &r2, &err), DF_OK);
    double back = 0;
    for (int i = 0; i < 40; i++) back = fmax(back, tu_dist(df_admm_positions(s) + 3 * i, m.V + 3 * i));
    printf("polyline: pulled: max move %.4f (free tail %.3f) in %d its; handle back: max deviation from rest %.2e in %d its, E %.2e\n",
           maxmove, farmove, r1.iterations, back, r2.iterations, r2.objective);
    assert_true(maxmove > 0.2);
    assert_true(back < 1e-6);
    assert_true(r2.objective < 1e-10);
    df_admm_free(s);
    tu_free(&m);
}

static void scaled_boundary(const df_mesh *m, double f, int32_t *h, double *tg, int *nh, int tet)
{
    *nh = 0;
    for (int32_t i = 0; i < m->nv; i++) {
        const double *x = m->V + 3 * i;
        int bd = tet ? (x[0] == 0.0 || x[0] == 2.0) : (x[0] == 0 || x[1] == 0 || x[0] == 1.0 || x[1] == 1.0);
        if (!bd) continue;
        h[*nh] = i;
        for (int d = 0; d < 3; d++) tg[3 * *nh + d] = f * x[d];
        (*nh)++;
    }
}

static double scale_run(const df_mesh *m, df_admm_energy en, const int32_t *h, int nh, const double *tg, double f, double *maxerr)
{
    df_admm_params p;
    df_admm_params_default(&p, en);
    p.threads = 1; /* correctness tests: one thread (the machine may be shared) */
    p.w = 0; p.rho = 1e-3; p.tol = 1e-15; p.max_iters = 4000;
    df_admm *s = NULL;
    df_error err;
    assert_int_equal(df_admm_create(m, &p, h, nh, NULL, 0, &s, &err), DF_OK);
    assert_int_equal(df_admm_set_targets(s, tg, &err), DF_OK);
    df_admm_result r;
    assert_int_equal(df_admm_run(s, NULL, &r, &err), DF_OK);
    *maxerr = 0;
    for (int i = 0; i < m->nv; i++) {
        double y[3] = {f * m->V[3 * i], f * m->V[3 * i + 1], f * m->V[3 * i + 2]};
        *maxerr = fmax(*maxerr, tu_dist(df_admm_positions(s) + 3 * i, y));
    }
    df_admm_free(s);
    return r.objective;
}

static void test_acap_scale(void **st)
{
    (void)st;
    int32_t h[512];
    double tg[512 * 3];
    int nh;
    double e1, e2;
    df_mesh g = tu_grid2d(10, 10, 1.0, 1.0);
    scaled_boundary(&g, 1.5, h, tg, &nh, 0);
    double Eacap = scale_run(&g, DF_ADMM_ACAP, h, nh, tg, 1.5, &e1);
    double Earap = scale_run(&g, DF_ADMM_ARAP, h, nh, tg, 1.5, &e2);
    printf("2D scale x1.5: ACAP E %.3e (max |V - 1.5 X| %.2e), ARAP E %.4g (%.3f)\n", Eacap, e1, Earap, e2);
    assert_true(Eacap < 1e-12 && e1 < 1e-6);
    assert_true(Earap > 1e-2); /* ARAP pays for the scaling (its minimizer may still be 1.5 X) */
    tu_free(&g);
    df_mesh b = tu_bar3d(4, 2, 2, 2.0, 1.0, 1.0);
    scaled_boundary(&b, 1.3, h, tg, &nh, 1);
    Eacap = scale_run(&b, DF_ADMM_ACAP, h, nh, tg, 1.3, &e1);
    Earap = scale_run(&b, DF_ADMM_ARAP, h, nh, tg, 1.3, &e2);
    printf("tet scale x1.3: ACAP E %.3e (max |V - 1.3 X| %.2e), ARAP E %.4g (%.3f)\n", Eacap, e1, Earap, e2);
    assert_true(Eacap < 1e-12 && e1 < 1e-6);
    assert_true(Earap > 1e-2); /* ARAP pays for the scaling (its minimizer may still be 1.5 X) */
    tu_free(&b);
}

static void test_neohookean_tets(void **st)
{
    (void)st;
    df_mesh m = tu_bar3d(6, 2, 2, 3.0, 1.0, 1.0);
    int32_t h[64];
    double tg[64 * 3];
    int nh = 0;
    for (int32_t i = 0; i < m.nv; i++) {
        double x = m.V[3 * i];
        if (x == 0.0 || x == 3.0) {
            h[nh] = i;
            memcpy(tg + 3 * nh, m.V + 3 * i, 24);
            if (x == 3.0) { tg[3 * nh] += 0.6; tg[3 * nh + 1] += 0.5; } /* stretch 20% and shear */
            nh++;
        }
    }
    df_admm_params p;
    df_admm_params_default(&p, DF_ADMM_NEOHOOKEAN);
    p.threads = 1; /* correctness tests: one thread (the machine may be shared) */
    p.rho = 1e5; p.s = 0.05; p.w = 0; p.max_iters = 400; p.tol = 1e-12;
    df_admm *nh_s = NULL, *ar_s = NULL;
    df_error err;
    assert_int_equal(df_admm_create(&m, &p, h, nh, NULL, 0, &nh_s, &err), DF_OK);
    assert_int_equal(df_admm_set_targets(nh_s, tg, &err), DF_OK);
    df_admm_result r1, r;
    assert_int_equal(df_admm_run(nh_s, &(df_admm_budget){1, 0, 0, NULL, NULL}, &r1, &err), DF_OK);
    assert_int_equal(df_admm_run(nh_s, NULL, &r, &err), DF_OK);
    df_admm_params pa;
    df_admm_params_default(&pa, DF_ADMM_ARAP);
    pa.threads = 1; /* correctness tests: one thread (the machine may be shared) */
    pa.w = 0; pa.rho = 1e-3; pa.max_iters = 2000; pa.tol = 1e-14;
    assert_int_equal(df_admm_create(&m, &pa, h, nh, NULL, 0, &ar_s, &err), DF_OK);
    assert_int_equal(df_admm_set_targets(ar_s, tg, &err), DF_OK);
    df_admm_result ra;
    assert_int_equal(df_admm_run(ar_s, NULL, &ra, &err), DF_OK);
    double e_nh_at_arap;
    assert_int_equal(df_admm_evaluate(nh_s, df_admm_positions(ar_s), &e_nh_at_arap, NULL, &err), DF_OK);
    printf("Neo-Hookean: E after 1 it %.6g, after %d more %.8g (residual %.1e); NH energy of the ARAP solution %.8g\n",
           r1.objective, r.iterations, r.objective, r.residual, e_nh_at_arap);
    assert_true(isfinite(r.objective) && r.objective > 0);
    assert_true(r.objective < r1.objective);
    assert_true(r.objective < e_nh_at_arap * (1 - 1e-4));
    /* w > 0 with the paper's scaling w = rho s / 10 runs, stays finite and uninverted */
    df_admm_free(nh_s);
    p.w = p.rho * p.s / 10;
    assert_int_equal(df_admm_create(&m, &p, h, nh, NULL, 0, &nh_s, &err), DF_OK);
    assert_int_equal(df_admm_set_targets(nh_s, tg, &err), DF_OK);
    assert_int_equal(df_admm_run(nh_s, &(df_admm_budget){150, 0, 0, NULL, NULL}, &r, &err), DF_OK);
    double el, lo;
    assert_int_equal(df_admm_evaluate(nh_s, df_admm_positions(nh_s), &el, &lo, &err), DF_OK);
    printf("Neo-Hookean w = %g: E %.8g = elastic %.8g + locality %.6g\n", p.w, r.objective, el, lo);
    assert_true(fabs(el + lo - r.objective) <= 1e-12 * r.objective);
    assert_true(lo > 0);
    df_admm_free(nh_s);
    df_admm_free(ar_s);
    tu_free(&m);
}

/* ARAP on a curved triangle surface in 3D (per-vertex spokes and rims, 3D rotations): rigidly
 * moved handles give a rigidly moved surface at zero energy; a bending pull gives E > 0 */
static void test_surface_arap_rigid(void **st)
{
    (void)st;
    df_mesh m = tu_grid2d(10, 6, 1.0, 0.6);
    m.planar = 0;
    for (int i = 0; i < m.nv; i++) m.V[3 * i + 2] = 0.2 * sin(3.0 * m.V[3 * i]) * cos(2.0 * m.V[3 * i + 1]);
    int32_t h[64];
    double tg[64 * 3];
    int nh = 0;
    /* rotation by 40 degrees about the axis (1, 1, 1)/sqrt(3), plus a translation */
    double c = cos(0.698), sn = sin(0.698), k = 1.0 / sqrt(3.0), R[9];
    double K[9] = {0, -k, k, k, 0, -k, -k, k, 0};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double k2 = 0;
            for (int q = 0; q < 3; q++) k2 += K[3 * i + q] * K[3 * q + j];
            R[3 * i + j] = (i == j) + sn * K[3 * i + j] + (1 - c) * k2;
        }
    for (int32_t i = 0; i < m.nv; i++) {
        double x = m.V[3 * i];
        if (x == 0.0 || x == 1.0) {
            h[nh] = i;
            for (int r = 0; r < 3; r++)
                tg[3 * nh + r] = R[3 * r] * m.V[3 * i] + R[3 * r + 1] * m.V[3 * i + 1] + R[3 * r + 2] * m.V[3 * i + 2] + 0.1 * (r + 1);
            nh++;
        }
    }
    df_admm_params p;
    df_admm_params_default(&p, DF_ADMM_ARAP);
    p.threads = 1;
    p.w = 0; p.rho = 1e-3; p.tol = 1e-15; p.max_iters = 3000;
    df_admm *s = NULL;
    df_error err;
    assert_int_equal(df_admm_create(&m, &p, h, nh, NULL, 0, &s, &err), DF_OK);
    assert_int_equal(df_admm_set_targets(s, tg, &err), DF_OK);
    df_admm_result r;
    assert_int_equal(df_admm_run(s, NULL, &r, &err), DF_OK);
    double maxd = 0;
    for (int i = 0; i < m.nv; i++) {
        double y[3];
        for (int q = 0; q < 3; q++)
            y[q] = R[3 * q] * m.V[3 * i] + R[3 * q + 1] * m.V[3 * i + 1] + R[3 * q + 2] * m.V[3 * i + 2] + 0.1 * (q + 1);
        maxd = fmax(maxd, tu_dist(df_admm_positions(s) + 3 * i, y));
    }
    printf("surface ARAP, rigid handles: %d its, E %.2e, max distance to the rigid motion %.2e\n", r.iterations, r.objective, maxd);
    assert_true(r.objective < 1e-12);
    assert_true(maxd < 1e-6);
    /* pull the x = 1 end up: real bending energy */
    for (int q = 0; q < nh; q++) {
        memcpy(tg + 3 * q, m.V + 3 * h[q], 24);
        if (m.V[3 * h[q]] == 1.0) tg[3 * q + 2] += 0.4;
    }
    assert_int_equal(df_admm_set_targets(s, tg, &err), DF_OK);
    assert_int_equal(df_admm_run(s, NULL, &r, &err), DF_OK);
    printf("surface ARAP, pulled end: %d its, E %.6g\n", r.iterations, r.objective);
    assert_true(r.objective > 1e-4 && isfinite(r.objective));
    df_admm_free(s);
    tu_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cloth_strain_limit),
        cmocka_unit_test(test_polyline_returns_to_rest),
        cmocka_unit_test(test_acap_scale),
        cmocka_unit_test(test_neohookean_tets),
        cmocka_unit_test(test_surface_arap_rigid),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
