/* Unit tests of the ADMM's per-vertex and per-element kernels: SC-L1 loss value and prox against a
 * brute-force 1D minimization in both rho regimes of the supplement (rho s > w a convex shrinkage,
 * rho s <= w a two-candidate choice), the signed 3x3 SVD / closed-form polar / trace of S, and the
 * Neo-Hookean singular-value prox (stationarity and brute-force neighbourhood check). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "core/admm/nh_prox.h"
#include "core/admm/scl1.h"
#include "core/admm/svd3.h"

static double urand(unsigned *seed) { return rand_r(seed) / (double)RAND_MAX; }

static void test_scl1_value(void **st)
{
    (void)st;
    double s = 0.5;
    double x0[3] = {0, 0, 0}, x1[3] = {0.3, 0, 0.4}, x2[3] = {0, 0.5, 0}, x3[3] = {3, 4, 0};
    assert_true(df_admm_scl1_value(x0, s) == 0.0);
    assert_true(fabs(df_admm_scl1_value(x1, s) - (0.5 - 0.25 / 1.0)) < 1e-15); /* |x| = s: s/2 */
    assert_true(fabs(df_admm_scl1_value(x2, s) - 0.25) < 1e-15);
    assert_true(fabs(df_admm_scl1_value(x3, s) - 0.25) < 1e-15);
    double x4[3] = {0.1, 0, 0};
    assert_true(fabs(df_admm_scl1_value(x4, s) - (0.1 - 0.01 / 1.0)) < 1e-15);
    assert_true(isnan(df_admm_scl1_value(x4, 0.0)));
}

/* g(r) = wa SC-L1(r) + rho/2 (r - |x|)^2 along the ray of x */
static double ray_obj(double r, double xn, double wa, double s, double rho)
{
    double f = r < s ? r - r * r / (2 * s) : 0.5 * s;
    return wa * f + 0.5 * rho * (r - xn) * (r - xn);
}

static void check_prox_regime(int convex)
{
    unsigned seed = convex ? 7u : 11u;
    int n_zero = 0, n_shrunk = 0, n_identity = 0;
    for (int t = 0; t < 1000; t++) {
        double s = 0.01 + urand(&seed);
        double wa = 0.01 + urand(&seed) * 2.0;
        /* convex: rho s > wa; nonconvex: rho s <= wa */
        double rho = convex ? (wa / s) * (1.05 + 3 * urand(&seed)) : (wa / s) * (0.1 + 0.9 * urand(&seed));
        double dir[3] = {urand(&seed) - 0.5, urand(&seed) - 0.5, urand(&seed) - 0.5};
        double dn = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
        double xn = urand(&seed) * 2.0 * s;
        double x[3] = {dir[0] / dn * xn, dir[1] / dn * xn, dir[2] / dn * xn}, z[3];
        assert_int_equal(df_admm_scl1_prox(x, wa, s, rho, z), 0);
        double zn = sqrt(z[0] * z[0] + z[1] * z[1] + z[2] * z[2]);
        /* z is parallel to x (or zero) */
        if (zn > 0) assert_true(fabs(z[0] * x[0] + z[1] * x[1] + z[2] * x[2] - zn * xn) < 1e-12 * (1 + zn * xn));
        /* brute force over r in [0, 3 max(s, |x|)] */
        double hi = 3 * fmax(s, xn), best = INFINITY, rbest = 0;
        for (int k = 0; k <= 100000; k++) {
            double r = hi * k / 100000.0, g = ray_obj(r, xn, wa, s, rho);
            if (g < best) { best = g; rbest = r; }
        }
        double gz = ray_obj(zn, xn, wa, s, rho);
        assert_true(gz <= best + 1e-12 * (1 + fabs(best)));
        if (convex) assert_true(fabs(zn - rbest) <= 2.5 * hi / 100000.0 + 1e-12);
        if (zn == 0) n_zero++;
        else if (fabs(zn - xn) < 1e-15) n_identity++;
        else n_shrunk++;
    }
    /* every branch was exercised */
    assert_true(n_zero > 30);
    assert_true(n_identity > 30);
    if (convex) assert_true(n_shrunk > 30);
    printf("prox %s regime: %d zero, %d shrunk, %d identity of 1000 (each checked against a 1e5-point search)\n", convex ? "convex" : "nonconvex", n_zero, n_shrunk, n_identity);
}

static void test_scl1_prox_convex(void **st) { (void)st; check_prox_regime(1); }
static void test_scl1_prox_nonconvex(void **st) { (void)st; check_prox_regime(0); }

static void test_scl1_prox_formula(void **st)
{
    (void)st;
    /* supplement eq. 9 with weight: ((rho s - wa s / |x|) / (rho s - wa)) x inside s */
    double x[3] = {0.03, 0.04, 0}, z[3]; /* |x| = 0.05 */
    double wa = 1.0, s = 0.1, rho = 20.0;   /* rho s = 2 > wa */
    assert_int_equal(df_admm_scl1_prox(x, wa, s, rho, z), 0);
    double f = (rho * s - wa * s / 0.05) / (rho * s - wa);
    assert_true(fabs(z[0] - f * 0.03) < 1e-15 && fabs(z[1] - f * 0.04) < 1e-15);
    /* below the threshold wa / rho = 0.05: exactly 0 */
    double x2[3] = {0.0, 0.049, 0.0};
    assert_int_equal(df_admm_scl1_prox(x2, wa, s, rho, z), 0);
    assert_true(z[0] == 0 && z[1] == 0 && z[2] == 0);
    /* w = 0: identity */
    assert_int_equal(df_admm_scl1_prox(x, 0.0, s, rho, z), 0);
    assert_true(z[0] == x[0] && z[1] == x[1]);
    /* invalid arguments leave out untouched */
    double keep[3] = {9, 9, 9};
    assert_int_equal(df_admm_scl1_prox(x, -1, s, rho, keep), -1);
    assert_int_equal(df_admm_scl1_prox(x, wa, 0, rho, keep), -1);
    assert_int_equal(df_admm_scl1_prox(x, wa, s, NAN, keep), -1);
    assert_true(keep[0] == 9 && keep[1] == 9 && keep[2] == 9);
}

static void matmul_usv(const double U[9], const double s[3], const double V[9], double A[9])
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            A[3 * i + j] = U[3 * i] * s[0] * V[3 * j] + U[3 * i + 1] * s[1] * V[3 * j + 1] + U[3 * i + 2] * s[2] * V[3 * j + 2];
}

static double det3(const double A[9])
{
    return A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) + A[2] * (A[3] * A[7] - A[4] * A[6]);
}

static void test_svd_polar(void **st)
{
    (void)st;
    unsigned seed = 5;
    double max_rec = 0, max_pol = 0, max_tr = 0;
    int inverted = 0, polar_ok = 0;
    for (int t = 0; t < 20000; t++) {
        double A[9], U[9], sg[3], V[9], B[9];
        double sc = (t % 3 == 0) ? 2.0 : 0.4;
        for (int k = 0; k < 9; k++) A[k] = (k % 4 == 0 ? 1.0 : 0.0) + sc * (urand(&seed) - 0.5);
        if (t % 5 == 0) for (int k = 0; k < 3; k++) A[k] = -A[k];             /* reflections */
        if (t % 7 == 0) for (int k = 0; k < 3; k++) A[6 + k] = A[k] + A[3 + k]; /* rank 2 */
        df_admm_svd3(A, U, sg, V);
        matmul_usv(U, sg, V, B);
        for (int k = 0; k < 9; k++) max_rec = fmax(max_rec, fabs(A[k] - B[k]));
        assert_true(fabs(det3(U) - 1) < 1e-12 && fabs(det3(V) - 1) < 1e-12);
        assert_true(sg[0] >= fabs(sg[1]) - 1e-15 && fabs(sg[1]) >= fabs(sg[2]) - 1e-12 && sg[1] >= 0);
        if (det3(A) < -1e-9) { assert_true(sg[2] < 0); inverted++; }
        double R[9], Rs[9], one[3] = {1, 1, 1};
        matmul_usv(U, one, V, Rs);
        if (df_admm_polar3(A, R) == 0) {
            polar_ok++;
            for (int k = 0; k < 9; k++) max_pol = fmax(max_pol, fabs(R[k] - Rs[k]));
        }
        max_tr = fmax(max_tr, fabs(df_admm_trace_sym3(A) - (sg[0] + sg[1] + sg[2])));
    }
    printf("svd3 max reconstruction error %.2e, polar3 vs svd %.2e (%d closed-form), trace %.2e, %d inverted\n",
           max_rec, max_pol, polar_ok, max_tr, inverted);
    assert_true(max_rec < 1e-13);
    assert_true(max_pol < 1e-12);
    assert_true(max_tr < 1e-12);
    assert_true(polar_ok > 5000 && inverted > 1000);
    /* 3x2 */
    for (int t = 0; t < 2000; t++) {
        double F[6], U[6], sg[2], V[4];
        for (int k = 0; k < 6; k++) F[k] = urand(&seed) - 0.5;
        df_admm_svd32(F, U, sg, V);
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 2; c++) {
                double v = U[2 * r] * sg[0] * V[2 * c] + U[2 * r + 1] * sg[1] * V[2 * c + 1];
                assert_true(fabs(v - F[2 * r + c]) < 1e-13);
            }
        assert_true(sg[0] >= sg[1] && sg[1] >= 0);
    }
}

static void test_sym3_eig_warm(void **st)
{
    (void)st;
    unsigned seed = 21;
    for (int t = 0; t < 2000; t++) {
        double A[9], C[9], lam[3], Q[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
        for (int k = 0; k < 9; k++) A[k] = urand(&seed) - 0.5;
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) C[3 * i + j] = A[3 * i] * A[3 * j] + A[3 * i + 1] * A[3 * j + 1] + A[3 * i + 2] * A[3 * j + 2];
        if (t % 2) df_admm_sym3_eig(C, lam, Q); /* odd cases: warm start from the exact answer of a nearby matrix */
        if (t % 2) for (int k = 0; k < 9; k++) C[k] += 1e-3 * (k / 3 == k % 3);
        df_admm_sym3_eig_warm(C, lam, Q);
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                double v = Q[3 * i] * lam[0] * Q[3 * j] + Q[3 * i + 1] * lam[1] * Q[3 * j + 1] + Q[3 * i + 2] * lam[2] * Q[3 * j + 2];
                assert_true(fabs(v - C[3 * i + j]) < 1e-13);
                double o = Q[i] * Q[j] + Q[3 + i] * Q[3 + j] + Q[6 + i] * Q[6 + j];
                assert_true(fabs(o - (i == j)) < 1e-13);
            }
    }
}

static double nh_obj(const double x[3], const double sig[3], double vol, double mu, double lam, double gam)
{
    double d = 0;
    for (int i = 0; i < 3; i++) d += (x[i] - sig[i]) * (x[i] - sig[i]);
    return vol * df_admm_nh_psi(x, mu, lam) + 0.5 * gam * d;
}

static void test_nh_prox(void **st)
{
    (void)st;
    double mu, lam;
    df_admm_lame(1e7, 0.45, &mu, &lam);
    assert_true(fabs(mu - 1e7 / 2.9) < 1e-6 && fabs(lam - 1e7 * 0.45 / (1.45 * 0.1)) < 1e-3);
    unsigned seed = 9;
    int max_steps = 0;
    double x_prev[3] = {1.0, 1.0, 1.0}; /* warm start from another problem's answer every 3rd case */
    for (int t = 0; t < 3000; t++) {
        double vol = 1e-6 * (0.1 + urand(&seed));
        double gam = (2.0066 * mu + 1.0122 * lam) * vol * (t % 2 ? 1.0 : 0.01 + urand(&seed));
        double sig[3] = {0.3 + 1.5 * urand(&seed), 0.3 + 1.5 * urand(&seed), 0.3 + 1.5 * urand(&seed)};
        if (t % 4 == 0) sig[2] = -0.5 * urand(&seed); /* inverted input */
        double x[3];
        int steps = df_admm_nh_prox(sig, (t % 3 == 0) ? x_prev : NULL, vol, mu, lam, gam, x);
        assert_true(steps >= 0 && steps <= DF_ADMM_NH_MAX_NEWTON);
        if (steps > max_steps) max_steps = steps;
        assert_true(x[0] > 0 && x[1] > 0 && x[2] > 0);
        memcpy(x_prev, x, sizeof(x));
        /* stationarity */
        double L = log(x[0]) + log(x[1]) + log(x[2]), gn = 0;
        for (int i = 0; i < 3; i++) {
            double g = vol * (mu * x[i] - mu / x[i] + lam * L / x[i]) + gam * (x[i] - sig[i]);
            gn += g * g;
        }
        if (!(sqrt(gn) < 1e-9 * (vol * mu + gam))) printf("t %d steps %d sig %g %g %g x %g %g %g g %g scale %g\n", t, steps, sig[0], sig[1], sig[2], x[0], x[1], x[2], sqrt(gn), vol * mu + gam);
        assert_true(sqrt(gn) < 1e-9 * (vol * mu + gam));
        /* brute force: no nearby point is better */
        double f0 = nh_obj(x, sig, vol, mu, lam, gam);
        for (int k = 0; k < 50; k++) {
            double y[3];
            for (int i = 0; i < 3; i++) y[i] = x[i] * (1 + 0.02 * (urand(&seed) - 0.5));
            assert_true(nh_obj(y, sig, vol, mu, lam, gam) >= f0 - 1e-12 * fabs(f0));
        }
    }
    printf("nh prox: at most %d Newton steps\n", max_steps);
    double keep[3] = {7, 7, 7}, sig[3] = {1, 1, 1};
    assert_int_equal(df_admm_nh_prox(sig, NULL, -1.0, mu, lam, 1.0, keep), -1);
    assert_true(keep[0] == 7);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_scl1_value),
        cmocka_unit_test(test_scl1_prox_convex),
        cmocka_unit_test(test_scl1_prox_nonconvex),
        cmocka_unit_test(test_scl1_prox_formula),
        cmocka_unit_test(test_svd_polar),
        cmocka_unit_test(test_sym3_eig_warm),
        cmocka_unit_test(test_nh_prox),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
