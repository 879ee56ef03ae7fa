/* The objective the ADMM solver reports, recomputed independently: on a tet bar under a smooth
 * non-inverting deformation, df_admm_evaluate must equal, to 1e-10 relative,
 *   ARAP:        sum_e 1/2 V_e ||S_e - I||_F^2,  S_e = (F_e^T F_e)^(1/2) (LAPACK dsyev here)
 *   Neo-Hookean: sum_e V_e (mu/2 (I_1 - 3) - mu ln J + lambda/2 (ln J)^2), E = 1e7 Pa, nu = 0.45
 *   locality:    sum_i w a_i ||V_i - Vrest_i||_SC-L1 with a_i = 1, and with a_i = the barycentric
 *                vertex volume (sum of V_e / 4 over incident tets) under area weighting,
 * with ||x||_SC-L1 = |x| - |x|^2/(2s) below s and s/2 beyond (paper eq. 1), written out here. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>
#include <lapacke.h>

#include "core/admm/admm.h"
#include "tests/unit/admm/admm_test_util.h"

static double det3(const double M[9])
{
    return M[0] * (M[4] * M[8] - M[5] * M[7]) - M[1] * (M[3] * M[8] - M[5] * M[6]) +
           M[2] * (M[3] * M[7] - M[4] * M[6]);
}

static void inv3(const double M[9], double out[9])
{
    double d = det3(M);
    out[0] = (M[4] * M[8] - M[5] * M[7]) / d; out[1] = (M[2] * M[7] - M[1] * M[8]) / d;
    out[2] = (M[1] * M[5] - M[2] * M[4]) / d; out[3] = (M[5] * M[6] - M[3] * M[8]) / d;
    out[4] = (M[0] * M[8] - M[2] * M[6]) / d; out[5] = (M[2] * M[3] - M[0] * M[5]) / d;
    out[6] = (M[3] * M[7] - M[4] * M[6]) / d; out[7] = (M[1] * M[6] - M[0] * M[7]) / d;
    out[8] = (M[0] * M[4] - M[1] * M[3]) / d;
}

/* Edge matrix [x1-x0, x2-x0, x3-x0] (columns) of tet `el` in positions X. */
static void edges(const double *X, const int32_t *el, double D[9])
{
    for (int c = 0; c < 3; c++)
        for (int r = 0; r < 3; r++) D[3 * r + c] = X[3 * el[c + 1] + r] - X[3 * el[0] + r];
}

/* ||S - I||_F^2 with S = sqrt(F^T F), from LAPACK's eigenvalues of C = F^T F. */
static double arap_density(const double F[9])
{
    double C[9] = {0}, ev[3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            for (int k = 0; k < 3; k++) C[3 * i + j] += F[3 * k + i] * F[3 * k + j];
    assert_int_equal(LAPACKE_dsyev(LAPACK_ROW_MAJOR, 'N', 'U', 3, C, 3, ev), 0);
    double sum = 0;
    for (int k = 0; k < 3; k++) sum += (sqrt(ev[k]) - 1) * (sqrt(ev[k]) - 1);
    return sum;
}

static double nh_density(const double F[9], double mu, double lambda)
{
    double I1 = 0, J = det3(F);
    for (int k = 0; k < 9; k++) I1 += F[k] * F[k];
    return mu / 2 * (I1 - 3) - mu * log(J) + lambda / 2 * log(J) * log(J);
}

static double scl1(const double *x, const double *x0, double s)
{
    double d = sqrt((x[0] - x0[0]) * (x[0] - x0[0]) + (x[1] - x0[1]) * (x[1] - x0[1]) +
                    (x[2] - x0[2]) * (x[2] - x0[2]));
    return d < s ? d - d * d / (2 * s) : s / 2;
}

/* Reference objective of mesh m (rest) at X for `energy`, weight w, threshold s. */
static void reference(const df_mesh *m, const double *X, int energy, int area_weighting, double w,
                      double s, double *elastic, double *locality)
{
    const double E = 1e7, nu = 0.45, mu = E / (2 * (1 + nu)), lambda = E * nu / ((1 + nu) * (1 - 2 * nu));
    double *a = calloc((size_t)m->nv, sizeof *a);
    *elastic = 0;
    for (int32_t e = 0; e < m->ne; e++) {
        const int32_t *el = m->E + 4 * (size_t)e;
        double Dm[9], Ds[9], Dminv[9], F[9] = {0};
        edges(m->V, el, Dm);
        edges(X, el, Ds);
        inv3(Dm, Dminv);
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                for (int k = 0; k < 3; k++) F[3 * i + j] += Ds[3 * i + k] * Dminv[3 * k + j];
        double vol = fabs(det3(Dm)) / 6;
        *elastic += energy == DF_ADMM_ARAP ? 0.5 * vol * arap_density(F) : vol * nh_density(F, mu, lambda);
        for (int c = 0; c < 4; c++) a[el[c]] += vol / 4;
    }
    *locality = 0;
    for (int32_t i = 0; i < m->nv; i++)
        *locality += w * (area_weighting ? a[i] : 1.0) * scl1(X + 3 * i, m->V + 3 * i, s);
    free(a);
}

static void check(int energy, int area_weighting, double w, double s, double rho)
{
    df_mesh m = tu_bar3d(4, 2, 2, 2.0, 1.0, 1.0);
    double *X = malloc((size_t)m.nv * 3 * sizeof *X);
    for (int32_t i = 0; i < m.nv; i++) { /* a smooth bend + twist, small enough not to invert */
        const double *p = m.V + 3 * i;
        X[3 * i + 0] = p[0] + 0.05 * sin(p[1] + 0.3 * p[2]);
        X[3 * i + 1] = p[1] + 0.08 * p[0] * p[0] * 0.25 - 0.03 * p[2] * p[0];
        X[3 * i + 2] = p[2] + 0.04 * cos(1.3 * p[0]) + 0.002 * (i % 3);
    }
    df_admm_params p;
    df_admm_params_default(&p, energy);
    p.w = w; p.s = s; p.rho = rho; p.area_weighting = area_weighting;
    int32_t handle = 0;
    df_admm *solver = NULL;
    df_error err;
    assert_int_equal(df_admm_create(&m, &p, &handle, 1, NULL, 0, &solver, &err), DF_OK);
    double el = NAN, lo = NAN, el_ref, lo_ref;
    assert_int_equal(df_admm_evaluate(solver, X, &el, &lo, &err), DF_OK);
    reference(&m, X, energy, area_weighting, w, s, &el_ref, &lo_ref);
    print_message("energy %d area %d: elastic %.12g (ref %.12g), locality %.12g (ref %.12g)\n",
                  energy, area_weighting, el, el_ref, lo, lo_ref);
    assert_true(el_ref > 0 && lo_ref > 0);
    assert_true(fabs(el - el_ref) <= 1e-10 * el_ref);
    assert_true(fabs(lo - lo_ref) <= 1e-10 * lo_ref);
    df_admm_free(solver);
    free(X);
    tu_free(&m);
}

static void test_arap_objective_matches_reference(void **state)
{
    (void)state;
    check(DF_ADMM_ARAP, 0, 1e-3, 0.05, 1.0);
}

static void test_arap_area_weighted_locality_matches_reference(void **state)
{
    (void)state;
    check(DF_ADMM_ARAP, 1, 1e-3, 0.05, 1.0);
}

static void test_neohookean_objective_matches_reference(void **state)
{
    (void)state;
    check(DF_ADMM_NEOHOOKEAN, 0, 500, 0.01, 5e5);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_arap_objective_matches_reference),
        cmocka_unit_test(test_arap_area_weighted_locality_matches_reference),
        cmocka_unit_test(test_neohookean_objective_matches_reference),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
