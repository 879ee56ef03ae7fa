/* kelvinlet_weights.c — multi-scale extrapolation radii and weights (paper section 5). */
#include <math.h>

#include "core/kelvinlet/kelvinlet_internal.h"

int df_kelvinlet_weights(int order, double ratio, double radius, double *eps, double *w,
                         df_error *err)
{
    if (!eps || !w)
        return df_error_set(err, DF_EINVAL, "kelvinlet weights: NULL output");
    if (order < 1 || order > DF_KELVINLET_MAX_ORDER)
        return df_error_set(err, DF_EINVAL, "kelvinlet falloff order %d outside [1, %d]", order,
                            DF_KELVINLET_MAX_ORDER);
    if (!dfk_finite(ratio) || ratio <= 1.0)
        return df_error_set(err, DF_EINVAL, "kelvinlet radius ratio %g must be finite and > 1",
                            ratio);
    if (!dfk_finite(radius) || radius <= 0.0)
        return df_error_set(err, DF_EINVAL, "kelvinlet radius %g must be finite and > 0", radius);

    /* Normalized nodes x_i = (eps_i / eps_1)^2 = ratio^(2i): the weights are scale-free. */
    double x[DF_KELVINLET_MAX_ORDER], ww[DF_KELVINLET_MAX_ORDER], e[DF_KELVINLET_MAX_ORDER];
    for (int i = 0; i < order; i++) {
        e[i] = radius * pow(ratio, i);
        x[i] = pow(ratio, 2.0 * i);
    }
    if (order == 1) {
        ww[0] = 1.0;
    } else if (order == 2) {           /* bi-scale, eq. 9 */
        ww[0] = 1.0;
        ww[1] = -1.0;
    } else if (order == 3) {           /* tri-scale, paper's closed form */
        ww[0] = 1.0;
        ww[1] = -(x[2] - x[0]) / (x[2] - x[1]);
        ww[2] = (x[1] - x[0]) / (x[2] - x[1]);
    } else {
        /* The Vandermonde system sum_i w_i x_i^k = 0 (k = 0..n-2) with w_0 = 1 has the exact
         * (Cramer / Lagrange divided-difference) solution w_i = c / prod_{j != i}(x_i - x_j),
         * c chosen so that w_0 = 1. Products of differences of distinct positive nodes are
         * accurate to rounding, unlike Gaussian elimination on the ill-conditioned matrix. */
        double p0 = 1.0;
        for (int j = 1; j < order; j++)
            p0 *= x[0] - x[j];
        for (int i = 0; i < order; i++) {
            double pi = 1.0;
            for (int j = 0; j < order; j++)
                if (j != i)
                    pi *= x[i] - x[j];
            ww[i] = p0 / pi;
        }
    }
    for (int i = 0; i < order; i++) {
        if (!dfk_finite(ww[i]) || !dfk_finite(e[i]))
            return df_error_set(err, DF_EINVAL,
                                "kelvinlet weights overflow (order %d, ratio %g, radius %g)",
                                order, ratio, radius);
    }
    for (int i = 0; i < order; i++) {
        eps[i] = e[i];
        w[i] = ww[i];
    }
    return DF_OK;
}
