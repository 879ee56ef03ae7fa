/* kelvinlet_constraints.c — constrained deformations (paper section 7): pinned points with
 * zero displacement (grab loads) and/or zero gradient (affine loads) plus one live brush.
 *
 *   [ 0    ]   [ K_pp  K_pl ] [ f_p ]      K_pp: pins on pins (cached LU, dgetrf/dgetrs),
 *   [ t_l  ] = [ K_lp  K_ll ] [ f_l ]      S = K_ll - K_lp K_pp^-1 K_pl (Schur complement),
 *                                          f_l = S^-1 t_l, f_p = -K_pp^-1 K_pl f_l.
 * X = K_pp^-1 K_pl and S are cached per live centre/kernel/type, so a new tip or gradient
 * costs one q x q solve (q = 3 grab, 3 twist, 1 scale, 5 pinch, 9 affine).
 * Gradient functionals and affine loads use the orthonormal basis skew(3) / deviatoric(5) /
 * trace(1); at nu = 0.5 the trace load vanishes (divergence-free field), so it is dropped. */
#include <lapacke.h>
#include <math.h>
#ifdef _OPENMP
#include <omp.h>
#endif
#include <stdlib.h>
#include <string.h>

#include "core/kelvinlet/kelvinlet_internal.h"

#define DUP_TOL 1e-9        /* pins closer than DUP_TOL * radius are duplicates             */
#define RCOND_MIN 1e-13     /* K_pp with a smaller reciprocal condition number is singular */
#define SCHUR_TOL 1e-12     /* relative pivot threshold of the live Schur complement      */

typedef struct live_key {
    df_kelvinlet_kernel kern;
    int type;
    double centre[3];
} live_key;

struct df_kelvinlet_constraints {
    df_kelvinlet_kernel kern;          /* pinned loads */
    size_t n;
    double *pts;
    int flags, nb;                     /* nb: gradient basis size (9, or 8 at nu = 0.5)  */
    int dpp, m;                        /* DoF per pin, system size                       */
    double *lu;
    lapack_int *ipiv;
    unsigned long nfact;
    int live_ok, q;
    live_key key;
    double *X;                         /* m x q, column-major (LAPACK)                   */
    double S[81];                      /* q x q row-major                                */
};

static const double R2 = 0.70710678118654752440, R6 = 0.40824829046386301637,
                    R3 = 0.57735026918962576451;
/* Orthonormal (Frobenius) basis of 3x3 matrices: skew 0-2, deviatoric 3-7, trace 8. */
static const double BASIS[9][9] = {
    {0, R2, 0, -R2, 0, 0, 0, 0, 0}, {0, 0, R2, 0, 0, 0, -R2, 0, 0},
    {0, 0, 0, 0, 0, R2, 0, -R2, 0}, {0, R2, 0, R2, 0, 0, 0, 0, 0},
    {0, 0, R2, 0, 0, 0, R2, 0, 0},  {0, 0, 0, 0, 0, R2, 0, R2, 0},
    {R2, 0, 0, 0, -R2, 0, 0, 0, 0}, {R6, 0, 0, 0, R6, 0, 0, 0, -2 * R6},
    {R3, 0, 0, 0, R3, 0, 0, 0, R3}};

/* Unit load `c` of a pin / live brush: grab (c < 3 of kind 0) or affine basis matrix. */
static void unit_source(const double *centre, int affine, int c, df_kelvinlet_source *s)
{
    memset(s, 0, sizeof *s);
    memcpy(s->centre, centre, 3 * sizeof *centre);
    s->affine = affine;
    if (affine)
        memcpy(s->F, BASIS[c], sizeof s->F);
    else
        s->f[c] = 1.0;
}

/* Functionals at x of the field of one unit load: writes disp (3) and/or gradient
 * coordinates (basis rows b0..b0+nbr-1) into out. */
static void functionals(const df_kelvinlet_kernel *k, const df_kelvinlet_source *s,
                        const double *x, int want_u, int b0, int nbr, double *out)
{
    int o = 0;
    if (want_u) {
        double u[3] = {0, 0, 0};
        dfk_source_eval_add(k, s, x, u);
        out[o++] = u[0];
        out[o++] = u[1];
        out[o++] = u[2];
    }
    if (nbr > 0) {
        double g[9] = {0};
        dfk_source_grad_add(k, s, x, g);
        for (int r = 0; r < nbr; r++) {
            double acc = 0.0;
            for (int i = 0; i < 9; i++)
                acc += BASIS[b0 + r][i] * g[i];
            out[o++] = acc;
        }
    }
}

/* The loads of pin p, in DoF order: (grab e0..e2) then (affine basis 0..nb-1). */
static void pin_source(const df_kelvinlet_constraints *cs, size_t p, int dof,
                       df_kelvinlet_source *s)
{
    int disp = (cs->flags & DF_KELVINLET_PIN_DISPLACEMENT) ? 3 : 0;
    if (dof < disp)
        unit_source(cs->pts + 3 * p, 0, dof, s);
    else
        unit_source(cs->pts + 3 * p, 1, dof - disp, s);
}

static void pin_functionals(const df_kelvinlet_constraints *cs, const df_kelvinlet_kernel *k,
                            const df_kelvinlet_source *s, size_t p, double *out)
{
    functionals(k, s, cs->pts + 3 * p, (cs->flags & DF_KELVINLET_PIN_DISPLACEMENT) != 0, 0,
                (cs->flags & DF_KELVINLET_PIN_GRADIENT) ? cs->nb : 0, out);
}

static int trace_load_ok(const df_kelvinlet_kernel *k)
{
    double al, be, sg;
    dfk_affine_gradient_map(k, &al, &be, &sg);
    return fabs(al + 5.0 * be) > 1e-12 * (fabs(al) + 5.0 * fabs(be));
}

static int check_pins(const df_kelvinlet_pins *pins, df_kelvinlet_kernel *k, df_error *err)
{
    if (!pins)
        return df_error_set(err, DF_EINVAL, "kelvinlet constraints: NULL pins");
    if (pins->n == 0 || !pins->points)
        return df_error_set(err, DF_EINVAL, "kelvinlet constraints: no pinned points");
    if (pins->n > DF_KELVINLET_MAX_PINS)
        return df_error_set(err, DF_ELIMIT, "kelvinlet constraints: %zu pins exceed %d",
                            pins->n, DF_KELVINLET_MAX_PINS);
    if (pins->flags <= 0 || pins->flags > 3)
        return df_error_set(err, DF_EINVAL, "kelvinlet constraints: flags %d must be a non-empty "
                            "set of DF_KELVINLET_PIN_*", pins->flags);
    for (size_t i = 0; i < 3 * pins->n; i++)
        if (!isfinite(pins->points[i]) || fabs(pins->points[i]) > DF_KELVINLET_MAX_VALUE)
            return df_error_set(err, DF_EINVAL, "kelvinlet constraints: pin %zu coordinate is "
                                "not finite or beyond %g", i / 3, DF_KELVINLET_MAX_VALUE);
    int rc = dfk_kernel_init(k, 3, pins->order, pins->radius, pins->ratio, pins->nu, err);
    if (rc != DF_OK)
        return rc;
    double tol = DUP_TOL * pins->radius;
    for (size_t i = 0; i < pins->n; i++)
        for (size_t j = i + 1; j < pins->n; j++) {
            const double *a = pins->points + 3 * i, *b = pins->points + 3 * j;
            double d = sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1])
                            + (a[2] - b[2]) * (a[2] - b[2]));
            if (d <= tol)
                return df_error_set(err, DF_ESINGULAR, "kelvinlet constraints: pins %zu and %zu "
                                    "coincide (distance %g): K_pp is singular", i, j, d);
        }
    return DF_OK;
}

/* Builds and factorizes K_pp for `pins` into fresh buffers of `t`. */
/* OpenMP threads of the K_pp assembly: pins->threads, or OpenMP's default when 0. */
static int assembly_threads(const df_kelvinlet_pins *pins)
{
#ifdef _OPENMP
    return pins->threads > 0 ? pins->threads : omp_get_max_threads();
#else
    (void)pins;
    return 1;
#endif
}

static int factorize(const df_kelvinlet_pins *pins, const df_kelvinlet_kernel *k,
                     df_kelvinlet_constraints *t, df_error *err)
{
    t->kern = *k;
    t->n = pins->n;
    t->flags = pins->flags;
    t->nb = trace_load_ok(k) ? 9 : 8;
    t->dpp = ((pins->flags & DF_KELVINLET_PIN_DISPLACEMENT) ? 3 : 0)
             + ((pins->flags & DF_KELVINLET_PIN_GRADIENT) ? t->nb : 0);
    t->m = (int)(t->dpp * pins->n);
    size_t m = (size_t)t->m;
    t->pts = malloc(3 * pins->n * sizeof *t->pts);
    t->lu = malloc(m * m * sizeof *t->lu);
    t->ipiv = malloc(m * sizeof *t->ipiv);
    if (!t->pts || !t->lu || !t->ipiv)
        return df_error_set(err, DF_ENOMEM, "kelvinlet constraints: out of memory (%zu DoF)", m);
    memcpy(t->pts, pins->points, 3 * pins->n * sizeof *t->pts);
    /* Column-major: column (pin q, dof c) holds the functionals at every pin p. The assembly
     * and the LU let OpenMP trim their team on an oversubscribed machine (dynamic adjustment,
     * this thread's setting only, restored below): a team member waiting for a core made the
     * 2-thread set-up slower than the 1-thread one under load. The bits do not depend on it. */
#ifdef _OPENMP
    const int dyn = omp_get_dynamic();
    omp_set_dynamic(1);
#endif
    const int nt = assembly_threads(pins);
#pragma omp parallel for schedule(dynamic, 4) if (pins->n >= 32 && nt > 1) num_threads(nt)
    for (size_t col = 0; col < m; col++) {
        df_kelvinlet_source s;
        double buf[12];
        pin_source(t, col / (size_t)t->dpp, (int)(col % (size_t)t->dpp), &s);
        for (size_t p = 0; p < t->n; p++) {
            pin_functionals(t, k, &s, p, buf);
            memcpy(t->lu + col * m + p * (size_t)t->dpp, buf, (size_t)t->dpp * sizeof *buf);
        }
    }
    double anorm = LAPACKE_dlange(LAPACK_COL_MAJOR, '1', t->m, t->m, t->lu, t->m);
    /* the LU on the assembly's team, OpenBLAS on one thread (kelvinlet_lu.c) */
    lapack_int info = dfk_lu_factor(t->m, t->lu, t->ipiv, nt);
#ifdef _OPENMP
    omp_set_dynamic(dyn);
#endif
    t->nfact++;
    double rcond = 0.0;
    dfk_blas_serial_begin();
    lapack_int cinfo = info == 0 ? LAPACKE_dgecon(LAPACK_COL_MAJOR, '1', t->m, t->lu, t->m, anorm,
                                                  &rcond) : 0;
    dfk_blas_serial_end();
    if (info > 0)
        return df_error_set(err, DF_ESINGULAR, "kelvinlet constraints: K_pp is singular "
                            "(zero pivot %d of %d)", (int)info, t->m);
    if (info < 0)
        return df_error_set(err, DF_EINTERNAL, "kelvinlet constraints: dgetrf argument %d",
                            (int)-info);
    if (cinfo != 0)
        return df_error_set(err, DF_EINTERNAL, "kelvinlet constraints: dgecon failed (%d)",
                            (int)cinfo);
    if (!(rcond >= RCOND_MIN))
        return df_error_set(err, DF_ESINGULAR, "kelvinlet constraints: K_pp is numerically "
                            "singular (rcond %.3g): pins too close for radius %g", rcond,
                            k->radius);
    return DF_OK;
}

static void release(df_kelvinlet_constraints *t)
{
    free(t->pts);
    free(t->lu);
    free(t->ipiv);
    free(t->X);
    t->pts = t->lu = t->X = NULL;
    t->ipiv = NULL;
}

int df_kelvinlet_constraints_create(const df_kelvinlet_pins *pins, df_kelvinlet_constraints **out,
                                    df_error *err)
{
    if (!out)
        return df_error_set(err, DF_EINVAL, "kelvinlet constraints: NULL output");
    df_kelvinlet_kernel k;
    int rc = check_pins(pins, &k, err);
    if (rc != DF_OK)
        return rc;
    df_kelvinlet_constraints *t = calloc(1, sizeof *t);
    if (!t)
        return df_error_set(err, DF_ENOMEM, "kelvinlet constraints: out of memory");
    rc = factorize(pins, &k, t, err);
    if (rc != DF_OK) {
        release(t);
        free(t);
        return rc;
    }
    *out = t;
    return DF_OK;
}

static int same_pins(const df_kelvinlet_constraints *cs, const df_kelvinlet_pins *pins,
                     const df_kelvinlet_kernel *k)
{
    return cs->n == pins->n && cs->flags == pins->flags && cs->kern.order == k->order
           && cs->kern.radius == k->radius && cs->kern.ratio == k->ratio
           && (cs->kern.nu == k->nu || (isinf(cs->kern.nu) && isinf(k->nu)))
           && memcmp(cs->pts, pins->points, 3 * pins->n * sizeof *cs->pts) == 0;
}

int df_kelvinlet_constraints_update(df_kelvinlet_constraints *cs, const df_kelvinlet_pins *pins,
                                    df_error *err)
{
    if (!cs)
        return df_error_set(err, DF_EINVAL, "kelvinlet constraints: NULL solver");
    df_kelvinlet_kernel k;
    int rc = check_pins(pins, &k, err);
    if (rc != DF_OK)
        return rc;
    if (same_pins(cs, pins, &k))
        return DF_OK;
    df_kelvinlet_constraints t;
    memset(&t, 0, sizeof t);
    t.nfact = cs->nfact;
    rc = factorize(pins, &k, &t, err);
    if (rc != DF_OK) {
        cs->nfact = t.nfact;        /* the failed attempt still counts as a factorization */
        release(&t);
        return rc;
    }
    release(cs);
    *cs = t;
    return DF_OK;
}

unsigned long df_kelvinlet_constraints_factorizations(const df_kelvinlet_constraints *cs)
{
    return cs ? cs->nfact : 0;
}

void df_kelvinlet_constraints_free(df_kelvinlet_constraints *cs)
{
    if (!cs)
        return;
    release(cs);
    free(cs);
}

/* Live DoF basis: grab e0..e2 or a range [b0, b0 + q) of BASIS. */
static void live_basis(const df_kelvinlet_brush *b, int nb, int *affine, int *b0, int *q)
{
    *affine = b->type != DF_KELVINLET_GRAB;
    switch (b->type) {
    case DF_KELVINLET_GRAB: *b0 = 0; *q = 3; break;
    case DF_KELVINLET_TWIST: *b0 = 0; *q = 3; break;
    case DF_KELVINLET_PINCH: *b0 = 3; *q = 5; break;
    case DF_KELVINLET_SCALE: *b0 = 8; *q = 1; break;
    default: *b0 = 0; *q = nb; break;
    }
}

/* Builds X = K_pp^-1 K_pl and S = K_ll - K_lp X for the live brush. */
static int build_live(df_kelvinlet_constraints *cs, const df_kelvinlet_kernel *lk,
                      const df_kelvinlet_brush *b, df_error *err)
{
    int affine, b0, q;
    live_basis(b, trace_load_ok(lk) ? 9 : 8, &affine, &b0, &q);
    size_t m = (size_t)cs->m;
    double *X = malloc(m * (size_t)q * sizeof *X);
    if (!X)
        return df_error_set(err, DF_ENOMEM, "kelvinlet constraints: out of memory");
    double Kll[81], Klp_col[9];
    for (int c = 0; c < q; c++) {
        df_kelvinlet_source s;
        unit_source(b->centre, affine, affine ? b0 + c : c, &s);
        double buf[12];
        for (size_t p = 0; p < cs->n; p++) {
            pin_functionals(cs, lk, &s, p, buf);
            memcpy(X + c * m + p * (size_t)cs->dpp, buf, (size_t)cs->dpp * sizeof *buf);
        }
        functionals(lk, &s, b->centre, !affine, b0, affine ? q : 0, Klp_col);
        for (int r = 0; r < q; r++)
            Kll[r * q + c] = Klp_col[r];
    }
    lapack_int info = LAPACKE_dgetrs(LAPACK_COL_MAJOR, 'N', cs->m, q, cs->lu, cs->m, cs->ipiv,
                                     X, cs->m);
    if (info != 0) {
        free(X);
        return df_error_set(err, DF_EINTERNAL, "kelvinlet constraints: dgetrs failed (%d)",
                            (int)info);
    }
    /* S = K_ll - K_lp X, K_lp column (pin dof j) = functionals at the live centre. */
    double Sm[81];
    memcpy(Sm, Kll, sizeof Sm);
    for (size_t j = 0; j < m; j++) {
        df_kelvinlet_source s;
        pin_source(cs, j / (size_t)cs->dpp, (int)(j % (size_t)cs->dpp), &s);
        functionals(&cs->kern, &s, b->centre, !affine, b0, affine ? q : 0, Klp_col);
        for (int r = 0; r < q; r++)
            for (int c = 0; c < q; c++)
                Sm[r * q + c] -= Klp_col[r] * X[c * m + j];
    }
    free(cs->X);
    cs->X = X;
    cs->q = q;
    memcpy(cs->S, Sm, sizeof Sm);
    return DF_OK;
}

int df_kelvinlet_constraints_solve(df_kelvinlet_constraints *cs, const df_kelvinlet_brush *live,
                                   df_kelvinlet_prepared *out, df_error *err)
{
    if (!cs || !live || !out)
        return df_error_set(err, DF_EINVAL, "kelvinlet constraints solve: NULL argument");
    if (live->dim != 3 || live->mirror || live->moving)
        return df_error_set(err, DF_EUNSUPPORTED, "kelvinlet constraints: the live brush must be "
                            "3D, not mirrored and not moving (dim %d, mirror %d, moving %d)",
                            live->dim, live->mirror, live->moving);
    df_kelvinlet_prepared free_b;
    int rc = df_kelvinlet_prepare(live, &free_b, err);
    if (rc != DF_OK)
        return rc;
    const df_kelvinlet_kernel *lk = &free_b.kernel[0];
    int affine, b0, q;
    live_basis(live, trace_load_ok(lk) ? 9 : 8, &affine, &b0, &q);
    for (size_t p = 0; p < cs->n; p++) {
        const double *x = cs->pts + 3 * p;
        double d = sqrt((x[0] - live->centre[0]) * (x[0] - live->centre[0])
                        + (x[1] - live->centre[1]) * (x[1] - live->centre[1])
                        + (x[2] - live->centre[2]) * (x[2] - live->centre[2]));
        if (d <= DUP_TOL * fmin(live->radius, cs->kern.radius))
            return df_error_set(err, DF_ESINGULAR, "kelvinlet constraints: the live brush centre "
                                "coincides with pin %zu", p);
    }
    live_key key;
    memset(&key, 0, sizeof key);
    key.kern = *lk;
    key.type = (int)live->type;
    memcpy(key.centre, live->centre, sizeof key.centre);
    if (!cs->live_ok || memcmp(&key, &cs->key, sizeof key) != 0) {
        cs->live_ok = 0;
        rc = build_live(cs, lk, live, err);
        if (rc != DF_OK)
            return rc;
        cs->key = key;
        cs->live_ok = 1;
    }
    /* Target: the free brush's own tip / centre gradient coordinates. */
    double t[9];
    if (!affine) {
        double u[3];
        df_kelvinlet_eval_ref(&free_b, live->centre, u, NULL);
        memcpy(t, u, sizeof u);
    } else {
        double g[9];
        df_kelvinlet_gradient_ref(&free_b, live->centre, g, NULL);
        for (int r = 0; r < q; r++) {
            t[r] = 0.0;
            for (int i = 0; i < 9; i++)
                t[r] += BASIS[b0 + r][i] * g[i];
        }
    }
    double Sm[81];
    memcpy(Sm, cs->S, sizeof Sm);
    if (dfk_small_solve(q, Sm, t, SCHUR_TOL) != DF_OK)
        return df_error_set(err, DF_ESINGULAR, "kelvinlet constraints: Schur complement of the "
                            "live brush is singular (pins cancel the brush)");
    int disp = (cs->flags & DF_KELVINLET_PIN_DISPLACEMENT) != 0;
    int grad = (cs->flags & DF_KELVINLET_PIN_GRADIENT) != 0;
    size_t m = (size_t)cs->m, per = (size_t)(disp + grad), nsrc = 1 + cs->n * per;
    df_kelvinlet_source *src = calloc(nsrc, sizeof *src);
    if (!src)
        return df_error_set(err, DF_ENOMEM, "kelvinlet constraints: out of memory");
    memcpy(src[0].centre, live->centre, sizeof src[0].centre);
    src[0].affine = affine;
    for (int c = 0; c < q; c++) {
        if (affine)
            for (int i = 0; i < 9; i++)
                src[0].F[i] += t[c] * BASIS[b0 + c][i];
        else
            src[0].f[c] = t[c];
    }
    /* One grab and/or one affine load per pin, f_p = -X f_l. */
    for (size_t p = 0; p < cs->n; p++) {
        df_kelvinlet_source *g = &src[1 + p * per], *a = &src[1 + p * per + (size_t)disp];
        for (size_t l = 0; l < per; l++) {
            memcpy(src[1 + p * per + l].centre, cs->pts + 3 * p, 3 * sizeof(double));
            src[1 + p * per + l].kernel = 1;
        }
        if (grad)
            a->affine = 1;
        for (int dof = 0; dof < cs->dpp; dof++) {
            size_t j = p * (size_t)cs->dpp + (size_t)dof;
            double fp = 0.0;
            for (int c = 0; c < q; c++)
                fp -= cs->X[c * m + j] * t[c];
            if (disp && dof < 3)
                g->f[dof] = fp;
            else
                for (int i = 0; i < 9; i++)
                    a->F[i] += fp * BASIS[dof - 3 * disp][i];
        }
    }
    df_kelvinlet_prepared p;
    memset(&p, 0, sizeof p);
    p.brush = *live;
    p.kernel[0] = *lk;
    p.kernel[1] = cs->kern;
    p.nsrc = nsrc;
    p.ext = src;
    *out = p;
    return DF_OK;
}
