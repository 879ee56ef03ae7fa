/* kelvinlet_ref.c — the double-precision scalar reference: field, gradient and integration
 * (Euler / RK4, stationary or moving brush). The oracle of the float path. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/kelvinlet/kelvinlet_internal.h"

int dfk_moving_substeps(const df_kelvinlet_prepared *p, df_kelvinlet_prepared **fields,
                        df_error *err)
{
    *fields = NULL;
    if (!p->brush.moving)
        return DF_OK;
    if (p->ext)
        return df_error_set(err, DF_EUNSUPPORTED, "kelvinlet: constrained fields cannot move");
    int n = p->brush.steps;
    df_kelvinlet_prepared *f = malloc((size_t)n * sizeof *f);
    if (!f)
        return df_error_set(err, DF_ENOMEM, "kelvinlet: out of memory for %d substeps", n);
    double inv = 1.0 / n;
    for (int k = 0; k < n; k++) {
        df_kelvinlet_brush b = p->brush;
        b.moving = 0;
        b.steps = 1;
        if (b.type == DF_KELVINLET_GRAB)
            for (int i = 0; i < b.dim; i++)
                b.centre[i] += k * inv * p->brush.tip[i];
        for (int i = 0; i < 3; i++) {
            b.tip[i] *= inv;
            b.omega[i] *= inv;
        }
        b.s *= inv;
        for (int i = 0; i < 9; i++)
            b.grad[i] *= inv;
        int rc = df_kelvinlet_prepare(&b, &f[k], err);
        if (rc != DF_OK) {
            free(f);
            return rc;
        }
    }
    *fields = f;
    return DF_OK;
}

static void field_at(const df_kelvinlet_prepared *p, const double *x, double *u)
{
    const df_kelvinlet_source *s = dfk_sources(p);
    u[0] = u[1] = u[2] = 0.0;
    for (size_t i = 0; i < p->nsrc; i++)
        dfk_source_eval_add(&p->kernel[s[i].kernel], &s[i], x, u);
}

static int point_ok(const double *x)
{
    for (int i = 0; i < 3; i++)
        if (!isfinite(x[i]) || fabs(x[i]) > DF_KELVINLET_MAX_VALUE)
            return 0;
    return 1;
}

int df_kelvinlet_eval_ref(const df_kelvinlet_prepared *p, const double *x, double *u,
                          df_error *err)
{
    int rc = dfk_check_prepared(p, err);
    if (rc != DF_OK)
        return rc;
    if (!x || !u)
        return df_error_set(err, DF_EINVAL, "kelvinlet eval: NULL point or output");
    if (!point_ok(x))
        return df_error_set(err, DF_EINVAL, "kelvinlet eval: point (%g, %g, %g) not finite or "
                            "beyond %g", x[0], x[1], x[2], DF_KELVINLET_MAX_VALUE);
    field_at(p, x, u);
    return DF_OK;
}

int df_kelvinlet_gradient_ref(const df_kelvinlet_prepared *p, const double *x, double *g,
                              df_error *err)
{
    int rc = dfk_check_prepared(p, err);
    if (rc != DF_OK)
        return rc;
    if (!x || !g)
        return df_error_set(err, DF_EINVAL, "kelvinlet gradient: NULL point or output");
    if (!point_ok(x))
        return df_error_set(err, DF_EINVAL, "kelvinlet gradient: point (%g, %g, %g) not finite "
                            "or beyond %g", x[0], x[1], x[2], DF_KELVINLET_MAX_VALUE);
    const df_kelvinlet_source *s = dfk_sources(p);
    double t[9] = {0};
    for (size_t i = 0; i < p->nsrc; i++)
        dfk_source_grad_add(&p->kernel[s[i].kernel], &s[i], x, t);
    memcpy(g, t, sizeof t);
    return DF_OK;
}

/* One integrator step of the field f scaled by h, in place on x[3]. */
static void step(const df_kelvinlet_prepared *f, int rk4, double h, double *x)
{
    double k1[3], k2[3], k3[3], k4[3], y[3];
    field_at(f, x, k1);
    if (!rk4) {
        for (int i = 0; i < 3; i++)
            x[i] += h * k1[i];
        return;
    }
    for (int i = 0; i < 3; i++)
        y[i] = x[i] + 0.5 * h * k1[i];
    field_at(f, y, k2);
    for (int i = 0; i < 3; i++)
        y[i] = x[i] + 0.5 * h * k2[i];
    field_at(f, y, k3);
    for (int i = 0; i < 3; i++)
        y[i] = x[i] + h * k3[i];
    field_at(f, y, k4);
    for (int i = 0; i < 3; i++)
        x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
}

int df_kelvinlet_apply_ref(const df_kelvinlet_prepared *p, double *xyz, size_t n, df_error *err)
{
    int rc = dfk_check_prepared(p, err);
    if (rc != DF_OK)
        return rc;
    if (n == 0)
        return DF_OK;
    if (!xyz)
        return df_error_set(err, DF_EINVAL, "kelvinlet apply_ref: NULL points");
    for (size_t i = 0; i < n; i++)
        if (!point_ok(xyz + 3 * i))
            return df_error_set(err, DF_EINVAL, "kelvinlet apply_ref: point %zu not finite or "
                                "beyond %g", i, DF_KELVINLET_MAX_VALUE);
    df_kelvinlet_prepared *mv;
    rc = dfk_moving_substeps(p, &mv, err);
    if (rc != DF_OK)
        return rc;
    int steps = p->brush.steps, rk4 = p->brush.integrator == DF_KELVINLET_RK4;
    double h = mv ? 1.0 : 1.0 / steps;
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < steps; k++)
            step(mv ? &mv[k] : p, rk4, h, xyz + 3 * i);
    free(mv);
    return DF_OK;
}
