/* kelvinlet_surface.c — geodesic attenuation of a brush field (see kelvinlet_surface.h). */
#include "core/kelvinlet/kelvinlet_surface.h"

#include <math.h>

#include "core/kelvinlet/kelvinlet.h"

int df_kelvinlet_surface_weights(const double *xyz, int32_t nv, const double *dist, int32_t src,
                                 const double *centre, double radius, int order, float *w,
                                 df_error *err)
{
    if (!xyz || !dist || !centre || !w || nv <= 0)
        return df_error_set(err, DF_EINVAL, "surface brush: NULL argument or no vertices");
    if (src < 0 || src >= nv)
        return df_error_set(err, DF_EINVAL, "surface brush: centre vertex %d not in [0, %d)",
                            src, nv);
    if (!(radius > 0.0) || !isfinite(radius))
        return df_error_set(err, DF_EINVAL, "surface brush: radius %g must be finite and > 0",
                            radius);
    if (order < 1 || order > DF_KELVINLET_MAX_ORDER)
        return df_error_set(err, DF_EINVAL, "surface brush: order %d not in [1, %d]", order,
                            DF_KELVINLET_MAX_ORDER);
    if (!isfinite(centre[0]) || !isfinite(centre[1]) || !isfinite(centre[2]))
        return df_error_set(err, DF_EINVAL, "surface brush: centre is not finite");
    const double *s = xyz + 3 * (size_t)src, e2 = radius * radius, half = 0.5 * (2 * order - 1);
    double g0 = sqrt((s[0] - centre[0]) * (s[0] - centre[0]) + (s[1] - centre[1]) * (s[1] - centre[1])
                     + (s[2] - centre[2]) * (s[2] - centre[2]));
    for (int32_t v = 0; v < nv; v++) {
        if (!(dist[v] < INFINITY)) {
            w[v] = 0.0f;
            continue;
        }
        const double *x = xyz + 3 * (size_t)v;
        double r2 = (x[0] - centre[0]) * (x[0] - centre[0]) + (x[1] - centre[1]) * (x[1] - centre[1])
                    + (x[2] - centre[2]) * (x[2] - centre[2]);
        double g = (g0 + dist[v]) / DF_KELVINLET_SURFACE_SLACK, q = (r2 + e2) / (g * g + e2);
        w[v] = q >= 1.0 ? 1.0f : (float)pow(q, half);
    }
    return DF_OK;
}

void df_kelvinlet_surface_mask(float *disp, const float *w, size_t nv)
{
    for (size_t v = 0; v < nv; v++) {
        if (w[v] == 1.0f)
            continue;
        for (int k = 0; k < 3; k++)
            disp[3 * v + k] = w[v] == 0.0f ? 0.0f : disp[3 * v + k] * w[v];
    }
}
