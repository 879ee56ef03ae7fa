/* kelvinlet_prepare.c — brush validation and force normalization: grab force from the tip
 * displacement (eq. 7, 10, 12, 2D eq. 25), affine force matrix from the wanted centre gradient
 * (inverse of the map F -> grad u(0) of eq. 14 / 26), symmetrization (eq. 21-22). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/kelvinlet/kelvinlet_internal.h"

#define REL_SINGULAR 1e-12  /* a normalization factor below this fraction of its scale is 0 */
#define PINCH_TOL 1e-9      /* pinch gradient: asymmetry and trace below this x max|G|     */

void df_kelvinlet_brush_defaults(df_kelvinlet_brush *b)
{
    if (!b)
        return;
    memset(b, 0, sizeof *b);
    b->type = DF_KELVINLET_GRAB;
    b->dim = 3;
    b->order = 1;
    b->ratio = DF_KELVINLET_DEFAULT_RATIO;
    b->radius = 1.0;
    b->nu = 0.5;
    b->integrator = DF_KELVINLET_EULER;
    b->steps = 1;
}

void df_kelvinlet_brush_advance(df_kelvinlet_brush *b)
{
    if (!b || b->type != DF_KELVINLET_GRAB)
        return;
    for (int i = 0; i < b->dim; i++)
        b->centre[i] += b->tip[i];
}

void df_kelvinlet_prepared_free(df_kelvinlet_prepared *p)
{
    if (!p)
        return;
    free(p->ext);
    p->ext = NULL;
    p->nsrc = 0;
}

static int validate(const df_kelvinlet_brush *b, df_error *err)
{
    if ((int)b->type < DF_KELVINLET_GRAB || (int)b->type > DF_KELVINLET_AFFINE)
        return df_error_set(err, DF_EINVAL, "kelvinlet brush type %d unknown", (int)b->type);
    if (b->dim != 2 && b->dim != 3)
        return df_error_set(err, DF_EINVAL, "kelvinlet dim %d must be 2 or 3", b->dim);
    struct { const char *name; const double *v; size_t n; } f[] = {
        {"radius", &b->radius, 1}, {"ratio", &b->ratio, 1}, {"centre", b->centre, 3},
        {"tip", b->tip, 3}, {"omega", b->omega, 3}, {"s", &b->s, 1}, {"grad", b->grad, 9},
        {"mirror_point", b->mirror_point, 3}, {"mirror_normal", b->mirror_normal, 3}};
    for (size_t i = 0; i < sizeof f / sizeof f[0]; i++)
        if (!dfk_all_finite(f[i].v, f[i].n))
            return df_error_set(err, DF_EINVAL, "kelvinlet brush %s is NaN or infinite",
                                f[i].name);
    for (size_t i = 2; i < sizeof f / sizeof f[0]; i++)
        for (size_t j = 0; j < f[i].n; j++)
            if (fabs(f[i].v[j]) > DF_KELVINLET_MAX_VALUE)
                return df_error_set(err, DF_EINVAL, "kelvinlet brush %s[%zu] = %g exceeds %g",
                                    f[i].name, j, f[i].v[j], DF_KELVINLET_MAX_VALUE);
    if (b->mirror != 0 && b->mirror != 1)
        return df_error_set(err, DF_EINVAL, "kelvinlet mirror flag %d must be 0 or 1", b->mirror);
    if (b->moving != 0 && b->moving != 1)
        return df_error_set(err, DF_EINVAL, "kelvinlet moving flag %d must be 0 or 1", b->moving);
    if (b->arith < 0 || b->arith > DF_KELVINLET_ARITH_CURRENT)
        return df_error_set(err, DF_EINVAL, "kelvinlet arithmetic version %d unknown (0..%d)",
                            b->arith, DF_KELVINLET_ARITH_CURRENT);
    if (b->surface != 0 && b->surface != 1)
        return df_error_set(err, DF_EINVAL, "kelvinlet surface flag %d must be 0 or 1",
                            b->surface);
    if (b->integrator != DF_KELVINLET_EULER && b->integrator != DF_KELVINLET_RK4)
        return df_error_set(err, DF_EINVAL, "kelvinlet integrator %d unknown", (int)b->integrator);
    if (b->steps < 1 || b->steps > DF_KELVINLET_MAX_STEPS)
        return df_error_set(err, DF_EINVAL, "kelvinlet steps %d outside [1, %d]", b->steps,
                            DF_KELVINLET_MAX_STEPS);
    if (b->mirror) {
        const double *n = b->mirror_normal;
        double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!(len > 0.0) || !isfinite(len))
            return df_error_set(err, DF_EINVAL, "kelvinlet mirror normal has zero length");
        if (b->dim == 2 && fabs(n[2]) > 1e-12 * len)
            return df_error_set(err, DF_EINVAL, "kelvinlet 2D mirror normal must lie in the "
                                "xy plane (z = %g)", n[2]);
    }
    if (b->type == DF_KELVINLET_PINCH) {
        const double *g = b->grad;
        int d = b->dim;
        double gmax = 0.0, asym = 0.0, tr = 0.0;
        for (int i = 0; i < d; i++) {
            tr += g[4 * i];
            for (int j = 0; j < d; j++) {
                gmax = fmax(gmax, fabs(g[3 * i + j]));
                asym = fmax(asym, fabs(g[3 * i + j] - g[3 * j + i]));
            }
        }
        if (asym > PINCH_TOL * gmax || fabs(tr) > PINCH_TOL * gmax)
            return df_error_set(err, DF_EINVAL, "kelvinlet pinch gradient must be symmetric and "
                                "traceless (asymmetry %g, trace %g)", asym, tr);
    }
    return DF_OK;
}

static void mirror_matrix(const double *normal, double *M)
{
    double len = sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
    double n[3] = {normal[0] / len, normal[1] / len, normal[2] / len};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            M[3 * i + j] = (i == j ? 1.0 : 0.0) - 2.0 * n[i] * n[j];
}

/* The multi-scale normalization vanished: the order's radii are so close (ratio near 1) that
 * their weights cancel. Names the ratio and the range that works (every order, both dims and
 * every brush type prepare at ratios from 1.05 up to where the largest radius leaves
 * [DF_KELVINLET_MIN_RADIUS, DF_KELVINLET_MAX_RADIUS]). */
static int ratio_error(const df_kelvinlet_brush *b, df_error *err)
{
    static const char *const names[] = {"grab", "twist", "scale", "pinch", "affine"};
    int t = (int)b->type - (int)DF_KELVINLET_GRAB;
    const char *what = t >= 0 && t < 5 ? names[t] : "brush";
    return df_error_set(err, DF_ESINGULAR, "kelvinlet %s: ratio %.10g is too close to 1 for falloff "
                        "order %d: its %d radii nearly coincide and their weights cancel; use a "
                        "ratio of 1.05 or more (default %g)", what, b->ratio, b->order, b->order,
                        DF_KELVINLET_DEFAULT_RATIO);
}

/* Grab force (and its mirror image when b->mirror). */
static int grab_force(const df_kelvinlet_brush *b, const df_kelvinlet_kernel *k,
                      df_kelvinlet_source *src, size_t *nsrc, df_error *err)
{
    int d = b->dim;
    double kappa = dfk_grab_tip_scale(k), scale = 0.0;
    for (int i = 0; i < k->order; i++)
        scale += fabs(k->w[i]) * (d == 3 ? 1.5 / k->eps[i]
                                         : 2.0 * fabs(log(k->eps[i])) + 1.0);
    if (!(fabs(kappa) > REL_SINGULAR * scale) && b->order >= 2)
        return ratio_error(b, err);
    if (!(fabs(kappa) > REL_SINGULAR * scale))
        return df_error_set(err, DF_ESINGULAR, "kelvinlet grab: the tip normalization vanishes "
                            "for radius %g (dim %d, order %d, nu %g); pick another radius or "
                            "order >= 2", b->radius, d, b->order, b->nu);
    double tip[3] = {b->tip[0], b->tip[1], d == 3 ? b->tip[2] : 0.0};
    double f[3] = {tip[0] / kappa, tip[1] / kappa, tip[2] / kappa};
    if (b->mirror) {
        double M[9], c1[3], dv[3];
        mirror_matrix(b->mirror_normal, M);
        for (int i = 0; i < 3; i++)
            dv[i] = b->centre[i] - b->mirror_point[i];
        for (int i = 0; i < 3; i++)
            c1[i] = b->mirror_point[i] + M[3 * i] * dv[0] + M[3 * i + 1] * dv[1]
                    + M[3 * i + 2] * dv[2];
        double r[3] = {b->centre[0] - c1[0], b->centre[1] - c1[1],
                       d == 3 ? b->centre[2] - c1[2] : 0.0};
        double s = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
        if (sqrt(s) <= 1e-12 * b->radius) {
            /* Centre on the plane: both loads coincide, u(x0) = kappa (I + M) f. */
            double nn[3], len = sqrt(b->mirror_normal[0] * b->mirror_normal[0]
                                     + b->mirror_normal[1] * b->mirror_normal[1]
                                     + b->mirror_normal[2] * b->mirror_normal[2]);
            for (int i = 0; i < 3; i++)
                nn[i] = b->mirror_normal[i] / len;
            double tn = tip[0] * nn[0] + tip[1] * nn[1] + tip[2] * nn[2];
            double tl = sqrt(tip[0] * tip[0] + tip[1] * tip[1] + tip[2] * tip[2]);
            if (fabs(tn) > 1e-12 * tl)
                return df_error_set(err, DF_ESINGULAR, "kelvinlet mirrored grab: the centre "
                                    "lies on the mirror plane, so it cannot move across it "
                                    "(tip normal component %g)", tn);
            for (int i = 0; i < 3; i++)
                f[i] = (tip[i] - tn * nn[i]) / (2.0 * kappa);
        } else {
            double A, B, Kd[9], rhs[3] = {tip[0], tip[1], tip[2]};
            dfk_grab_coeffs(k, s, &A, &B);
            for (int i = 0; i < 3; i++)
                for (int j = 0; j < 3; j++)
                    Kd[3 * i + j] = (i == j ? A : 0.0) + B * r[i] * r[j];
            double sub[9];
            for (int i = 0; i < d; i++)
                for (int j = 0; j < d; j++) {
                    double km = 0.0;
                    for (int l = 0; l < 3; l++)
                        km += Kd[3 * i + l] * M[3 * l + j];
                    sub[d * i + j] = (i == j ? kappa : 0.0) + km;
                }
            if (dfk_small_solve(d, sub, rhs, 1e-13) != DF_OK)
                return df_error_set(err, DF_ESINGULAR, "kelvinlet mirrored grab: tip "
                                    "normalization singular");
            f[0] = rhs[0];
            f[1] = rhs[1];
            f[2] = d == 3 ? rhs[2] : 0.0;
        }
        memset(&src[1], 0, sizeof src[1]);
        memcpy(src[1].centre, c1, sizeof c1);
        if (d == 2)
            src[1].centre[2] = b->centre[2];
        for (int i = 0; i < 3; i++)
            src[1].f[i] = M[3 * i] * f[0] + M[3 * i + 1] * f[1] + M[3 * i + 2] * f[2];
        *nsrc = 2;
    } else {
        *nsrc = 1;
    }
    memset(&src[0], 0, sizeof src[0]);
    memcpy(src[0].centre, b->centre, sizeof src[0].centre);
    memcpy(src[0].f, f, sizeof f);
    return DF_OK;
}

/* The wanted centre gradient G (row-major 3x3, zero outside the dim x dim block). */
static void wanted_gradient(const df_kelvinlet_brush *b, double *G)
{
    int d = b->dim;
    memset(G, 0, 9 * sizeof *G);
    const double *w = b->omega;
    switch (b->type) {
    case DF_KELVINLET_TWIST:
        if (d == 3) {
            G[1] = -w[2]; G[2] = w[1];
            G[3] = w[2];  G[5] = -w[0];
            G[6] = -w[1]; G[7] = w[0];
        } else {
            G[1] = -w[2];
            G[3] = w[2];
        }
        break;
    case DF_KELVINLET_SCALE:
        for (int i = 0; i < d; i++)
            G[4 * i] = b->s;
        break;
    default:
        for (int i = 0; i < d; i++)
            for (int j = 0; j < d; j++)
                G[3 * i + j] = b->grad[3 * i + j];
        break;
    }
}

static int affine_force(const df_kelvinlet_brush *b, const df_kelvinlet_kernel *k,
                        df_kelvinlet_source *src, size_t *nsrc, df_error *err)
{
    int d = b->dim;
    double G[9], F[9], alpha, beta, sigma, sscale = 0.0;
    wanted_gradient(b, G);
    dfk_affine_gradient_map(k, &alpha, &beta, &sigma);
    for (int i = 0; i < k->order; i++)
        sscale += fabs(k->w[i]) / pow(k->eps[i], d);
    if (!(fabs(sigma) > REL_SINGULAR * sscale))
        return ratio_error(b, err);
    double tr = 0.0, gmax = 0.0;
    for (int i = 0; i < d; i++)
        tr += G[4 * i];
    for (int i = 0; i < 9; i++)
        gmax = fmax(gmax, fabs(G[i]));
    /* grad u(0) = sigma (alpha F + beta (F + F^T + tr(F) I)) acts diagonally on the skew,
     * symmetric-traceless and trace parts of F. */
    double l_skew = sigma * alpha, l_dev = sigma * (alpha + 2.0 * beta);
    double l_tr = sigma * (alpha + (d + 2) * beta);
    double ref = fabs(sigma) * (fabs(alpha) + (d + 2) * fabs(beta));
    int tr_singular = !(fabs(l_tr) > REL_SINGULAR * ref);
    if (tr_singular && b->type == DF_KELVINLET_SCALE)
        return df_error_set(err, DF_ESINGULAR, "kelvinlet scale brush is singular at nu = %g: "
                            "the scaling Kelvinlet vanishes for incompressible materials", b->nu);
    if (tr_singular && fabs(tr) > 1e-12 * gmax)
        return df_error_set(err, DF_ESINGULAR, "kelvinlet affine: gradient trace %g is "
                            "unreachable at nu = %g (volume cannot change)", tr, b->nu);
    if (!(fabs(l_skew) > REL_SINGULAR * ref) || !(fabs(l_dev) > REL_SINGULAR * ref))
        return df_error_set(err, DF_ESINGULAR, "kelvinlet affine: gradient map singular at "
                            "nu = %g", b->nu);
    memset(F, 0, sizeof F);
    for (int i = 0; i < d; i++)
        for (int j = 0; j < d; j++) {
            double sk = 0.5 * (G[3 * i + j] - G[3 * j + i]);
            double sy = 0.5 * (G[3 * i + j] + G[3 * j + i]) - (i == j ? tr / d : 0.0);
            double t = i == j ? tr / d : 0.0;
            F[3 * i + j] = sk / l_skew + sy / l_dev + (tr_singular ? 0.0 : t / l_tr);
        }
    memset(&src[0], 0, sizeof src[0]);
    memcpy(src[0].centre, b->centre, sizeof src[0].centre);
    src[0].affine = 1;
    memcpy(src[0].F, F, sizeof F);
    *nsrc = 1;
    if (b->mirror) {
        double M[9], dv[3], MF[9];
        mirror_matrix(b->mirror_normal, M);
        for (int i = 0; i < 3; i++)
            dv[i] = b->centre[i] - b->mirror_point[i];
        memset(&src[1], 0, sizeof src[1]);
        src[1].affine = 1;
        for (int i = 0; i < 3; i++) {
            src[1].centre[i] = b->mirror_point[i] + M[3 * i] * dv[0] + M[3 * i + 1] * dv[1]
                               + M[3 * i + 2] * dv[2];
            for (int j = 0; j < 3; j++)
                MF[3 * i + j] = M[3 * i] * F[j] + M[3 * i + 1] * F[3 + j] + M[3 * i + 2] * F[6 + j];
        }
        if (d == 2)
            src[1].centre[2] = b->centre[2];
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                src[1].F[3 * i + j] = MF[3 * i] * M[j] + MF[3 * i + 1] * M[3 + j]
                                      + MF[3 * i + 2] * M[6 + j];
        *nsrc = 2;
    }
    return DF_OK;
}

int df_kelvinlet_prepare(const df_kelvinlet_brush *b, df_kelvinlet_prepared *out, df_error *err)
{
    if (!b || !out)
        return df_error_set(err, DF_EINVAL, "kelvinlet prepare: NULL argument");
    int rc = validate(b, err);
    if (rc != DF_OK)
        return rc;
    df_kelvinlet_prepared p;
    memset(&p, 0, sizeof p);
    rc = dfk_kernel_init(&p.kernel[0], b->dim, b->order, b->radius, b->ratio, b->nu, err);
    if (rc != DF_OK)
        return rc;
    p.brush = *b;
    if (b->type == DF_KELVINLET_GRAB)
        rc = grab_force(b, &p.kernel[0], p.src, &p.nsrc, err);
    else
        rc = affine_force(b, &p.kernel[0], p.src, &p.nsrc, err);
    if (rc != DF_OK)
        return rc;
    *out = p;
    return DF_OK;
}
