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
        /* n-scale: solve the Vandermonde system sum_i z_i x_i^k = [k == n-1] (k = 0..n-1) with
         * the Bjorck-Pereyra algorithm (Golub & Van Loan, Alg. 4.6.2), accurate to rounding for
         * ordered positive nodes where Gaussian elimination would lose digits to the
         * conditioning; w = z / z_0 then cancels the first n-1 far-field terms (k <= n-2). */
        int n = order - 1;
        double z[DF_KELVINLET_MAX_ORDER];
        for (int i = 0; i <= n; i++)
            z[i] = i == n ? 1.0 : 0.0;
        for (int k = 0; k < n; k++)
            for (int i = n; i > k; i--)
                z[i] -= x[k] * z[i - 1];
        for (int k = n - 1; k >= 0; k--) {
            for (int i = k + 1; i <= n; i++)
                z[i] /= x[i] - x[i - k - 1];
            for (int i = k; i < n; i++)
                z[i] -= z[i + 1];
        }
        for (int i = 0; i <= n; i++)
            ww[i] = z[i] / z[0];
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
