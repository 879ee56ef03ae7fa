/* kelvinlet_kernel.c — the multi-scale regularized Kelvinlet kernels in double precision:
 * grab (eq. 6, 2D eq. 25) and locally affine (eq. 14, 2D eq. 26) coefficient functions, the
 * tip normalization and the centre-gradient map. a = 1 (the shear modulus drops out). */
#include <math.h>
#include <string.h>

#include "core/kelvinlet/kelvinlet_internal.h"

int dfk_finite(double x) { return isfinite(x) ? 1 : 0; }

int dfk_all_finite(const double *v, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (!isfinite(v[i]))
            return 0;
    return 1;
}

int dfk_kernel_init(df_kelvinlet_kernel *k, int dim, int order, double radius, double ratio,
                    double nu, df_error *err)
{
    if (dim != 2 && dim != 3)
        return df_error_set(err, DF_EINVAL, "kelvinlet dim %d must be 2 or 3", dim);
    if (isnan(nu) || (isfinite(nu) && (nu < DF_KELVINLET_NU_MIN || nu > DF_KELVINLET_NU_MAX)))
        return df_error_set(err, DF_EINVAL, "kelvinlet Poisson ratio nu %g outside [%g, %g] "
                            "and not +-inf", nu, DF_KELVINLET_NU_MIN, DF_KELVINLET_NU_MAX);
    df_kelvinlet_kernel t;
    memset(&t, 0, sizeof t);
    int rc = df_kelvinlet_weights(order, ratio, radius, t.eps, t.w, err);
    if (rc != DF_OK)
        return rc;
    if (t.eps[0] < DF_KELVINLET_MIN_RADIUS || t.eps[order - 1] > DF_KELVINLET_MAX_RADIUS)
        return df_error_set(err, DF_EINVAL, "kelvinlet radii [%g, %g] outside [%g, %g]",
                            t.eps[0], t.eps[order - 1], DF_KELVINLET_MIN_RADIUS,
                            DF_KELVINLET_MAX_RADIUS);
    t.dim = dim;
    t.order = order;
    t.radius = radius;
    t.ratio = ratio;
    t.nu = nu;
    t.a = 1.0;
    t.b = isfinite(nu) ? t.a / (4.0 * (1.0 - nu)) : 0.0;
    *k = t;
    return DF_OK;
}

/* 0.5 * sum_i w_i ln(s + eps_i^2), written without the O(ln s) cancellation for n >= 2. */
static double weighted_half_log(const df_kelvinlet_kernel *k, double s)
{
    double x0 = k->eps[0] * k->eps[0];
    if (k->order == 1)
        return 0.5 * log(s + x0);
    double acc = 0.0;
    for (int i = 1; i < k->order; i++) {
        double xi = k->eps[i] * k->eps[i];
        acc += k->w[i] * log1p((xi - x0) / (s + x0));
    }
    return 0.5 * acc;
}

void dfk_grab_coeffs(const df_kelvinlet_kernel *k, double s, double *A, double *B)
{
    double a = k->a, b = k->b, sa = 0.0, sb = 0.0;
    if (k->dim == 3 && k->order == 1) {
        double e2 = k->eps[0] * k->eps[0];
        double ir = 1.0 / sqrt(s + e2), ir3 = ir * ir * ir;
        sa = (a - b) * ir + 0.5 * a * e2 * ir3;
        sb = b * ir3;
    } else if (k->dim == 3) {
        /* sum_i w_i = 0 (and sum_i w_i del_i = 0 from order 3): sum over the differences
         * ir_i^m - ir_1^m in closed form, as the float path does, so the large weights of
         * close radii (ratio 1.1, order 8) cancel without losing digits to rounding. */
        double x0 = k->eps[0] * k->eps[0], p0 = s + x0, i0 = 1.0 / sqrt(p0);
        double i0s = i0 * i0, rho0 = p0 * i0, s1 = 0.0, s3 = 0.0, t3 = 0.0;
        for (int i = 1; i < k->order; i++) {
            double xi = k->eps[i] * k->eps[i], del = xi - x0, pi = s + xi;
            double ii = 1.0 / sqrt(pi), iis = ii * ii;
            double d1 = -del * i0 * ii / (rho0 + pi * ii);      /* ir_i - ir_1     */
            double d3 = d1 * (iis + ii * i0 + i0s);              /* ir_i^3 - ir_1^3 */
            s1 += k->w[i] * d1;
            s3 += k->w[i] * d3;
            t3 += k->w[i] * del * (k->order >= 3 ? d3 : iis * ii);
        }
        sa = (a - b) * s1 + 0.5 * a * (x0 * s3 + t3);
        sb = b * s3;
    } else if (k->order == 1) {
        double e2 = k->eps[0] * k->eps[0], q = 1.0 / (s + e2);
        sa = 2.0 * (b - a) * weighted_half_log(k, s) + a * e2 * q;
        sb = 2.0 * b * q;
    } else {
        /* The same difference form in 2D: q_i - q_1 = -del_i q_i q_1 with q = 1/(s + eps^2). */
        double x0 = k->eps[0] * k->eps[0], q0 = 1.0 / (s + x0), a1 = 0.0, t1 = 0.0;
        for (int i = 1; i < k->order; i++) {
            double xi = k->eps[i] * k->eps[i], del = xi - x0, qi = 1.0 / (s + xi);
            double d1 = -del * qi * q0;
            a1 += k->w[i] * d1;
            t1 += k->w[i] * del * (k->order >= 3 ? d1 : qi);
        }
        sa = 2.0 * (b - a) * weighted_half_log(k, s) + a * (x0 * a1 + t1);
        sb = 2.0 * b * a1;
    }
    *A = sa;
    *B = sb;
}

void dfk_affine_coeffs(const df_kelvinlet_kernel *k, double s, double *C, double *dC)
{
    double a = k->a, b = k->b;
    double c1 = 0, c2 = 0, c3 = 0, d1 = 0, d2 = 0, d3 = 0;
    for (int i = 0; i < k->order; i++) {
        double w = k->w[i], e2 = k->eps[i] * k->eps[i];
        if (k->dim == 3) {
            double ir = 1.0 / sqrt(s + e2), ir2 = ir * ir, ir3 = ir2 * ir, ir5 = ir3 * ir2;
            double ir7 = ir5 * ir2;
            c1 += -w * a * (ir3 + 1.5 * e2 * ir5);
            c2 += w * b * ir3;
            c3 += -3.0 * w * b * ir5;
            d1 += -w * a * (-1.5 * ir5 - 3.75 * e2 * ir7);
            d2 += -1.5 * w * b * ir5;
            d3 += 7.5 * w * b * ir7;
        } else {
            double ir2 = 1.0 / (s + e2), ir4 = ir2 * ir2, ir6 = ir4 * ir2;
            c1 += -2.0 * w * a * (ir2 + e2 * ir4);
            c2 += 2.0 * w * b * ir2;
            c3 += -4.0 * w * b * ir4;
            d1 += -2.0 * w * a * (-ir4 - 2.0 * e2 * ir6);
            d2 += -2.0 * w * b * ir4;
            d3 += 8.0 * w * b * ir6;
        }
    }
    C[0] = c1; C[1] = c2; C[2] = c3;
    if (dC) {
        dC[0] = d1; dC[1] = d2; dC[2] = d3;
    }
}

double dfk_grab_tip_scale(const df_kelvinlet_kernel *k)
{
    /* A(0) of the very sums the field is evaluated with (3D: sum_i w_i (3a - 2b) / (2 eps_i);
     * 2D: sum_i w_i (2 (b - a) ln eps_i + a)): u(centre) = kappa f then matches the tip to
     * rounding however much the multi-scale weights cancel (issue 9 item 19). */
    double A, B;
    dfk_grab_coeffs(k, 0.0, &A, &B);
    return A;
}

void dfk_affine_gradient_map(const df_kelvinlet_kernel *k, double *alpha, double *beta,
                             double *sigma)
{
    double sg = 0.0;
    for (int i = 0; i < k->order; i++)
        sg += k->w[i] / pow(k->eps[i], k->dim);
    if (k->dim == 3) {
        *alpha = -2.5 * k->a;
        *beta = k->b;
    } else {
        *alpha = -4.0 * k->a;
        *beta = 2.0 * k->b;
    }
    *sigma = sg;
}
