/* view_ray.c — a viewport pixel to a ray in mesh space (see view_ray.h). */
#include "core/geom/view_ray.h"

#include <math.h>
#include <stddef.h>

int df_mat4_inverse(const double m[16], double inv[16])
{
    if (!m || !inv)
        return DF_EINVAL;
    double bound = 1;     /* Hadamard: |det| <= product of the rows' norms */
    for (int r = 0; r < 4; r++) {
        double n2 = 0;
        for (int c = 0; c < 4; c++) {
            if (!isfinite(m[4 * r + c]))
                return DF_EINVAL;
            n2 += m[4 * r + c] * m[4 * r + c];
        }
        bound *= sqrt(n2);
    }
    /* 2x2 minors of rows 0-1 (s) and rows 2-3 (c), then the adjugate (Laplace expansion). */
    double s0 = m[0] * m[5] - m[4] * m[1], s1 = m[0] * m[6] - m[4] * m[2];
    double s2 = m[0] * m[7] - m[4] * m[3], s3 = m[1] * m[6] - m[5] * m[2];
    double s4 = m[1] * m[7] - m[5] * m[3], s5 = m[2] * m[7] - m[6] * m[3];
    double c5 = m[10] * m[15] - m[14] * m[11], c4 = m[9] * m[15] - m[13] * m[11];
    double c3 = m[9] * m[14] - m[13] * m[10], c2 = m[8] * m[15] - m[12] * m[11];
    double c1 = m[8] * m[14] - m[12] * m[10], c0 = m[8] * m[13] - m[12] * m[9];
    double det = s0 * c5 - s1 * c4 + s2 * c3 + s3 * c2 - s4 * c1 + s5 * c0;
    if (!isfinite(det) || !(bound > 0) || !(fabs(det) >= 1e-12 * bound))
        return DF_EINVAL;
    double k = 1.0 / det, o[16];
    o[0] = (m[5] * c5 - m[6] * c4 + m[7] * c3) * k;
    o[1] = (-m[1] * c5 + m[2] * c4 - m[3] * c3) * k;
    o[2] = (m[13] * s5 - m[14] * s4 + m[15] * s3) * k;
    o[3] = (-m[9] * s5 + m[10] * s4 - m[11] * s3) * k;
    o[4] = (-m[4] * c5 + m[6] * c2 - m[7] * c1) * k;
    o[5] = (m[0] * c5 - m[2] * c2 + m[3] * c1) * k;
    o[6] = (-m[12] * s5 + m[14] * s2 - m[15] * s1) * k;
    o[7] = (m[8] * s5 - m[10] * s2 + m[11] * s1) * k;
    o[8] = (m[4] * c4 - m[5] * c2 + m[7] * c0) * k;
    o[9] = (-m[0] * c4 + m[1] * c2 - m[3] * c0) * k;
    o[10] = (m[12] * s4 - m[13] * s2 + m[15] * s0) * k;
    o[11] = (-m[8] * s4 + m[9] * s2 - m[11] * s0) * k;
    o[12] = (-m[4] * c3 + m[5] * c1 - m[6] * c0) * k;
    o[13] = (m[0] * c3 - m[1] * c1 + m[2] * c0) * k;
    o[14] = (-m[12] * s3 + m[13] * s1 - m[14] * s0) * k;
    o[15] = (m[8] * s3 - m[9] * s1 + m[10] * s0) * k;
    for (int i = 0; i < 16; i++)
        if (!isfinite(o[i]))
            return DF_EINVAL;
    for (int i = 0; i < 16; i++)
        inv[i] = o[i];
    return DF_OK;
}

/* inv * (x, y, z, 1) -> out (homogeneous, 4). */
static void unproject(const double inv[16], double x, double y, double z, double out[4])
{
    for (int r = 0; r < 4; r++)
        out[r] = inv[4 * r] * x + inv[4 * r + 1] * y + inv[4 * r + 2] * z + inv[4 * r + 3];
}

static int viewport_ok(const double vp[4])
{
    return isfinite(vp[0]) && isfinite(vp[1]) && isfinite(vp[2]) && isfinite(vp[3]) && vp[2] > 0
           && vp[3] > 0;
}

int df_view_pen_pixel(const double viewport[4], double nx, double ny, double *px, double *py,
                      df_error *err)
{
    if (!viewport || !px || !py)
        return df_error_set(err, DF_EINVAL, "pen pixel: NULL argument");
    if (!viewport_ok(viewport))
        return df_error_set(err, DF_EINVAL, "pen pixel: viewport (%g, %g, %g, %g) must be finite "
                            "with width and height > 0", viewport[0], viewport[1], viewport[2],
                            viewport[3]);
    if (!isfinite(nx) || !isfinite(ny))
        return df_error_set(err, DF_EINVAL, "pen pixel: position (%g, %g) is not finite", nx, ny);
    *px = viewport[0] + nx * viewport[2];
    *py = viewport[1] + ny * viewport[3];
    return DF_OK;
}

int df_view_ray(const double view_proj[16], const double viewport[4], double px, double py,
                double org[3], double dir[3], df_error *err)
{
    if (!view_proj || !viewport || !org || !dir)
        return df_error_set(err, DF_EINVAL, "view ray: NULL argument");
    if (!viewport_ok(viewport))
        return df_error_set(err, DF_EINVAL, "view ray: viewport (%g, %g, %g, %g) must be finite "
                            "with width and height > 0", viewport[0], viewport[1], viewport[2],
                            viewport[3]);
    if (!isfinite(px) || !isfinite(py))
        return df_error_set(err, DF_EINVAL, "view ray: pixel (%g, %g) is not finite", px, py);
    double inv[16];
    if (df_mat4_inverse(view_proj, inv) != DF_OK)
        return df_error_set(err, DF_EINVAL, "view ray: view_proj is singular or not finite "
                            "(no inverse: not a view-projection matrix)");
    double nx = 2 * (px - viewport[0]) / viewport[2] - 1;
    double ny = 1 - 2 * (py - viewport[1]) / viewport[3];
    /* The near-plane point (NDC z = -1) and a point behind it (NDC z = 0: finite also with an
     * infinite far plane, where NDC z = 1 is at infinity). */
    double a[4], b[4];
    unproject(inv, nx, ny, -1, a);
    unproject(inv, nx, ny, 0, b);
    double o[3], d[3], n2 = 0;
    for (int k = 0; k < 3; k++) {
        o[k] = a[k] / a[3];
        d[k] = b[k] / b[3] - o[k];
        n2 += d[k] * d[k];
    }
    double n = sqrt(n2);
    if (!(n > 0) || !isfinite(n) || !isfinite(o[0]) || !isfinite(o[1]) || !isfinite(o[2]))
        return df_error_set(err, DF_EINVAL, "view ray: pixel (%g, %g) maps to a point at "
                            "infinity through view_proj", px, py);
    for (int k = 0; k < 3; k++) {
        org[k] = o[k];
        dir[k] = d[k] / n;
    }
    return DF_OK;
}
