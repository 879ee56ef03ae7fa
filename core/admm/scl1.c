/* scl1.c — SC-L1 loss value and proximal operator (see scl1.h). */
#include "core/admm/scl1.h"

#include <math.h>

double df_admm_scl1_value(const double x[3], double s)
{
    if (!(s > 0.0)) return NAN;
    double r = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    return r < s ? r - r * r / (2.0 * s) : 0.5 * s;
}

int df_admm_scl1_prox(const double x[3], double wa, double s, double rho, double out[3])
{
    if (!(wa >= 0.0) || !(s > 0.0) || !(rho > 0.0) || !isfinite(wa) || !isfinite(s) ||
        !isfinite(rho))
        return -1;
    double r = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    double f;
    if (wa == 0.0) {
        f = 1.0;
    } else if (rho * s > wa) {
        /* convex: unique minimizer, shrink towards 0 and clamp at 0 (identity beyond s) */
        if (r > s) f = 1.0;
        else f = r > 0.0 ? (rho * s - wa * s / r) / (rho * s - wa) : 0.0;
        if (f < 0.0) f = 0.0;
    } else {
        /* nonconvex: the inner piece is concave along the ray, so the minimum is at 0 or at the
         * start of the flat region, max(s, r) along x */
        double rs = r > s ? r : s;
        double g0 = 0.5 * rho * r * r;
        double gs = 0.5 * wa * s + 0.5 * rho * (rs - r) * (rs - r);
        f = (g0 <= gs || r == 0.0) ? 0.0 : rs / r;
    }
    out[0] = f * x[0];
    out[1] = f * x[1];
    out[2] = f * x[2];
    return 0;
}
