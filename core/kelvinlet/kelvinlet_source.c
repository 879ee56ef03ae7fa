/* kelvinlet_source.c — double-precision evaluation of one load (displacement and analytic
 * gradient), the small dense solver and the prepared-field sanity check. */
#include <math.h>
#include <string.h>

#include "core/kelvinlet/kelvinlet_internal.h"

/* r = x - c (2D: z dropped) and s = r.r. */
static double rel(const df_kelvinlet_kernel *k, const double *c, const double *x, double *r)
{
    r[0] = x[0] - c[0];
    r[1] = x[1] - c[1];
    r[2] = k->dim == 3 ? x[2] - c[2] : 0.0;
    return r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
}

/* S = F + F^T + tr(F) I_d (F row-major, 2D: only the upper-left 2x2 of F is used). */
static void sym_part(int dim, const double *F, double *S)
{
    double tr = F[0] + F[4] + (dim == 3 ? F[8] : 0.0);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            S[3 * i + j] = F[3 * i + j] + F[3 * j + i] + (i == j && i < dim ? tr : 0.0);
}

static void mat_vec(const double *M, const double *v, double *o)
{
    for (int i = 0; i < 3; i++)
        o[i] = M[3 * i] * v[0] + M[3 * i + 1] * v[1] + M[3 * i + 2] * v[2];
}

/* Affine field of force matrix F at relative position r (s = r.r), added into u. */
static void affine_add(const df_kelvinlet_kernel *k, const double *F, const double *r, double s,
                       double *u)
{
    double Fm[9], S[9], Fr[3], Sr[3], C[3];
    memcpy(Fm, F, sizeof Fm);
    if (k->dim == 2)
        Fm[2] = Fm[5] = Fm[6] = Fm[7] = Fm[8] = 0.0;
    sym_part(k->dim, Fm, S);
    mat_vec(Fm, r, Fr);
    mat_vec(S, r, Sr);
    double q = r[0] * Fr[0] + r[1] * Fr[1] + r[2] * Fr[2];
    dfk_affine_coeffs(k, s, C, NULL);
    for (int i = 0; i < 3; i++)
        u[i] += C[0] * Fr[i] + C[1] * Sr[i] + C[2] * q * r[i];
}

/* Gradient of the affine field of F at r, added into g (row-major du_i/dx_j). */
static void affine_grad_add(const df_kelvinlet_kernel *k, const double *F, const double *r,
                            double s, double *g)
{
    double Fm[9], S[9], Fr[3], Sr[3], Ftr[3], C[3], dC[3];
    memcpy(Fm, F, sizeof Fm);
    if (k->dim == 2)
        Fm[2] = Fm[5] = Fm[6] = Fm[7] = Fm[8] = 0.0;
    sym_part(k->dim, Fm, S);
    mat_vec(Fm, r, Fr);
    mat_vec(S, r, Sr);
    for (int i = 0; i < 3; i++)       /* (F + F^T) r = grad of q = r^T F r */
        Ftr[i] = Fr[i] + Fm[i] * r[0] + Fm[3 + i] * r[1] + Fm[6 + i] * r[2];
    double q = r[0] * Fr[0] + r[1] * Fr[1] + r[2] * Fr[2];
    dfk_affine_coeffs(k, s, C, dC);
    for (int i = 0; i < 3; i++) {
        double v = 2.0 * (dC[0] * Fr[i] + dC[1] * Sr[i] + dC[2] * q * r[i]);
        for (int j = 0; j < 3; j++) {
            double idj = (i == j && i < k->dim) ? 1.0 : 0.0;
            g[3 * i + j] += v * r[j] + C[0] * Fm[3 * i + j] + C[1] * S[3 * i + j]
                            + C[2] * (r[i] * Ftr[j] + q * idj);
        }
    }
}

void dfk_source_eval_add(const df_kelvinlet_kernel *k, const df_kelvinlet_source *src,
                         const double *x, double *u)
{
    double r[3];
    double s = rel(k, src->centre, x, r);
    if (src->affine) {
        affine_add(k, src->F, r, s, u);
        return;
    }
    double A, B, f[3] = {src->f[0], src->f[1], k->dim == 3 ? src->f[2] : 0.0};
    dfk_grab_coeffs(k, s, &A, &B);
    double rf = r[0] * f[0] + r[1] * f[1] + r[2] * f[2];
    for (int i = 0; i < 3; i++)
        u[i] += A * f[i] + B * rf * r[i];
}

void dfk_source_grad_add(const df_kelvinlet_kernel *k, const df_kelvinlet_source *src,
                         const double *x, double *g)
{
    double r[3];
    double s = rel(k, src->centre, x, r);
    if (src->affine) {
        affine_grad_add(k, src->F, r, s, g);
        return;
    }
    /* Column j of grad(K f) is the affine field of F = f e_j^T (paper section 6). */
    for (int j = 0; j < k->dim; j++) {
        double F[9] = {0}, col[3] = {0, 0, 0};
        for (int i = 0; i < k->dim; i++)
            F[3 * i + j] = src->f[i];
        affine_add(k, F, r, s, col);
        for (int i = 0; i < 3; i++)
            g[3 * i + j] += col[i];
    }
}

const df_kelvinlet_source *dfk_sources(const df_kelvinlet_prepared *p)
{
    return p->ext ? p->ext : p->src;
}

int dfk_check_prepared(const df_kelvinlet_prepared *p, df_error *err)
{
    if (!p)
        return df_error_set(err, DF_EINVAL, "kelvinlet: NULL prepared brush");
    if (p->nsrc == 0 || (!p->ext && p->nsrc > 2))
        return df_error_set(err, DF_EINVAL, "kelvinlet: prepared brush has %zu loads", p->nsrc);
    for (int i = 0; i < 2; i++) {
        const df_kelvinlet_kernel *k = &p->kernel[i];
        if (i == 1 && !p->ext)
            break;
        if ((k->dim != 2 && k->dim != 3) || k->order < 1 || k->order > DF_KELVINLET_MAX_ORDER)
            return df_error_set(err, DF_EINVAL, "kelvinlet: prepared brush not initialized "
                                "(call df_kelvinlet_prepare)");
    }
    if (p->brush.steps < 1 || p->brush.steps > DF_KELVINLET_MAX_STEPS)
        return df_error_set(err, DF_EINVAL, "kelvinlet: %d integrator steps outside [1, %d]",
                            p->brush.steps, DF_KELVINLET_MAX_STEPS);
    const df_kelvinlet_source *s = dfk_sources(p);
    for (size_t i = 0; i < p->nsrc; i++)
        if (s[i].kernel < 0 || s[i].kernel > 1 || (s[i].kernel == 1 && !p->ext))
            return df_error_set(err, DF_EINVAL, "kelvinlet: load %zu has bad kernel index", i);
    return DF_OK;
}

int dfk_small_solve(int m, double *A, double *b, double tol)
{
    double amax = 0.0;
    for (int i = 0; i < m * m; i++)
        amax = fmax(amax, fabs(A[i]));
    if (!(amax > 0.0) || !isfinite(amax))
        return DF_ESINGULAR;
    for (int c = 0; c < m; c++) {
        int p = c;
        for (int r = c + 1; r < m; r++)
            if (fabs(A[r * m + c]) > fabs(A[p * m + c]))
                p = r;
        if (fabs(A[p * m + c]) <= tol * amax)
            return DF_ESINGULAR;
        if (p != c) {
            for (int j = 0; j < m; j++) {
                double t = A[c * m + j];
                A[c * m + j] = A[p * m + j];
                A[p * m + j] = t;
            }
            double t = b[c];
            b[c] = b[p];
            b[p] = t;
        }
        for (int r = c + 1; r < m; r++) {
            double f = A[r * m + c] / A[c * m + c];
            for (int j = c; j < m; j++)
                A[r * m + j] -= f * A[c * m + j];
            b[r] -= f * b[c];
        }
    }
    for (int c = m - 1; c >= 0; c--) {
        double acc = b[c];
        for (int j = c + 1; j < m; j++)
            acc -= A[c * m + j] * b[j];
        b[c] = acc / A[c * m + c];
    }
    return DF_OK;
}
