/* kelvinlet_guess.c — the Kelvinlet initial guess of a handle move (kelvinlet_guess.h). */
#include "core/kelvinlet/kelvinlet_guess.h"

#include <lapacke.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/kelvinlet/kelvinlet_internal.h"

double df_kelvinlet_guess_radius(const double *V, int32_t nv, const int32_t *handles, int32_t nh)
{
    if (!V || !handles || nv < 1 || nh < 1)
        return 0.0;
    double c[3] = {0, 0, 0}, lo[3], hi[3];
    for (int d = 0; d < 3; d++)
        lo[d] = hi[d] = V[d];
    for (int32_t i = 0; i < nv; i++)
        for (int d = 0; d < 3; d++) {
            double x = V[3 * (size_t)i + d];
            lo[d] = x < lo[d] ? x : lo[d];
            hi[d] = x > hi[d] ? x : hi[d];
        }
    for (int32_t k = 0; k < nh; k++) {
        if (handles[k] < 0 || handles[k] >= nv)
            return 0.0;
        for (int d = 0; d < 3; d++)
            c[d] += V[3 * (size_t)handles[k] + d] / nh;
    }
    double ss = 0.0, diag = 0.0;
    for (int32_t k = 0; k < nh; k++)
        for (int d = 0; d < 3; d++) {
            double e = V[3 * (size_t)handles[k] + d] - c[d];
            ss += e * e;
        }
    for (int d = 0; d < 3; d++)
        diag += (hi[d] - lo[d]) * (hi[d] - lo[d]);
    double r = DF_KGUESS_SPREAD_FRACTION * sqrt(ss / nh), floor_r = 0.01 * sqrt(diag);
    r = r > floor_r ? r : floor_r;
    if (r < DF_KELVINLET_MIN_RADIUS)
        r = DF_KELVINLET_MIN_RADIUS;
    if (r > DF_KELVINLET_MAX_RADIUS)
        r = DF_KELVINLET_MAX_RADIUS;
    return r;
}

static int check_input(const double *V, int32_t nv, const int32_t *handles, int32_t nh,
                       const double *targets, const double *V_out, df_error *err)
{
    if (!V || !handles || !targets || !V_out)
        return df_error_set(err, DF_EINVAL, "kelvinlet guess: NULL argument");
    if (nv < 1 || nh < 1)
        return df_error_set(err, DF_EINVAL, "kelvinlet guess: %d vertices, %d handles (need >= 1)",
                            (int)nv, (int)nh);
    if (nh > DF_KGUESS_MAX_HANDLES)
        return df_error_set(err, DF_EINVAL, "kelvinlet guess: %d handles (at most %d)", (int)nh,
                            DF_KGUESS_MAX_HANDLES);
    if (!dfk_all_finite(V, 3 * (size_t)nv) || !dfk_all_finite(targets, 3 * (size_t)nh))
        return df_error_set(err, DF_EINVAL, "kelvinlet guess: NaN/Inf in positions or targets");
    unsigned char *seen = calloc((size_t)nv, 1);
    if (!seen)
        return df_error_set(err, DF_ENOMEM, "kelvinlet guess: out of memory");
    for (int32_t k = 0; k < nh; k++) {
        int32_t h = handles[k];
        if (h < 0 || h >= nv || seen[h]) {
            free(seen);
            return df_error_set(err, DF_EINVAL, "kelvinlet guess: handle %d (vertex %d) %s",
                                (int)k, (int)h, h < 0 || h >= nv ? "out of range" : "repeated");
        }
        seen[h] = 1;
    }
    free(seen);
    return DF_OK;
}

/* u(x) of the fitted loads f (nh x 3) centred at the handles' positions */
static void field(const df_kelvinlet_kernel *k, const double *C, int32_t nh, const double *f,
                  const double *x, double *u)
{
    u[0] = u[1] = u[2] = 0.0;
    for (int32_t j = 0; j < nh; j++) {
        double r[3] = {x[0] - C[3 * j], x[1] - C[3 * j + 1], x[2] - C[3 * j + 2]};
        double A, B, s = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
        dfk_grab_coeffs(k, s, &A, &B);
        const double *fj = f + 3 * (size_t)j;
        double rf = B * (r[0] * fj[0] + r[1] * fj[1] + r[2] * fj[2]);
        for (int d = 0; d < 3; d++)
            u[d] += A * fj[d] + rf * r[d];
    }
}

int df_kelvinlet_guess(const double *V, int32_t nv, const int32_t *handles, int32_t nh,
                       const double *targets, double radius, double nu, double *V_out,
                       double *fit_residual, double *radius_used, df_error *err)
{
    int rc = check_input(V, nv, handles, nh, targets, V_out, err);
    if (rc != DF_OK)
        return rc;
    if (!(radius > 0.0))
        radius = df_kelvinlet_guess_radius(V, nv, handles, nh);
    df_kelvinlet_kernel k;
    rc = dfk_kernel_init(&k, 3, 1, radius, DF_KELVINLET_DEFAULT_RATIO, nu, err);
    if (rc != DF_OK)
        return rc;
    size_t m = 3 * (size_t)nh;
    double *K = malloc(m * m * sizeof *K), *f = malloc(m * sizeof *f), *C = malloc(m * sizeof *C);
    lapack_int *ipiv = malloc(m * sizeof *ipiv);
    if (!K || !f || !C || !ipiv) {
        free(K); free(f); free(C); free(ipiv);
        return df_error_set(err, DF_ENOMEM, "kelvinlet guess: out of memory (%d handles)", (int)nh);
    }
    for (int32_t h = 0; h < nh; h++)
        for (int d = 0; d < 3; d++) {
            C[3 * h + d] = V[3 * (size_t)handles[h] + d];
            f[3 * h + d] = targets[3 * h + d] - C[3 * h + d];
        }
    double A0 = dfk_grab_tip_scale(&k), ridge = DF_KGUESS_RIDGE * A0;
    for (int32_t h = 0; h < nh; h++)
        for (int32_t j = 0; j < nh; j++) {
            double r[3] = {C[3 * h] - C[3 * j], C[3 * h + 1] - C[3 * j + 1], C[3 * h + 2] - C[3 * j + 2]};
            double A, B;
            dfk_grab_coeffs(&k, r[0] * r[0] + r[1] * r[1] + r[2] * r[2], &A, &B);
            for (int a = 0; a < 3; a++)
                for (int b = 0; b < 3; b++)
                    K[(3 * (size_t)h + a) * m + 3 * (size_t)j + b] =
                        (a == b ? A + (h == j ? ridge : 0.0) : 0.0) + B * r[a] * r[b];
        }
    dfk_blas_serial_begin();
    lapack_int info = LAPACKE_dgesv(LAPACK_ROW_MAJOR, (lapack_int)m, 1, K, (lapack_int)m, ipiv, f, 1);
    dfk_blas_serial_end();
    free(K);
    free(ipiv);
    if (info != 0) {
        free(f); free(C);
        return df_error_set(err, info > 0 ? DF_ESINGULAR : DF_EINTERNAL,
                            "kelvinlet guess: dgesv info %d on the %zu x %zu handle system",
                            (int)info, m, m);
    }
    double worst = 0.0;
    for (int32_t h = 0; h < nh; h++) {
        double u[3], e = 0.0;
        field(&k, C, nh, f, C + 3 * (size_t)h, u);
        for (int d = 0; d < 3; d++) {
            double t = u[d] - (targets[3 * h + d] - C[3 * h + d]);
            e += t * t;
        }
        worst = sqrt(e) > worst ? sqrt(e) : worst;
    }
    #pragma omp parallel for schedule(static)
    for (int32_t i = 0; i < nv; i++) {
        double u[3];
        field(&k, C, nh, f, V + 3 * (size_t)i, u);
        for (int d = 0; d < 3; d++)
            V_out[3 * (size_t)i + d] = V[3 * (size_t)i + d] + u[d];
    }
    for (int32_t h = 0; h < nh; h++)
        memcpy(V_out + 3 * (size_t)handles[h], targets + 3 * h, 3 * sizeof(double));
    free(f);
    free(C);
    if (fit_residual)
        *fit_residual = worst;
    if (radius_used)
        *radius_used = radius;
    return DF_OK;
}
