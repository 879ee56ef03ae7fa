/* admm_seed.c — the line-searched start of a handle move from a proposal (admm_seed.h). */
#include "core/admm/admm_seed.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/admm/admm_internal.h"

int df_admm_seed_point(const df_admm *s, const double *V0, const double *G, double alpha,
                       double *X, df_error *err)
{
    if (!s || !V0 || !G || !X)
        return df_error_set(err, DF_EINVAL, "admm_seed: NULL argument");
    if (!isfinite(alpha))
        return df_error_set(err, DF_EINVAL, "admm_seed: alpha %g is not finite", alpha);
    size_t n = 3 * (size_t)s->nv;
    for (size_t i = 0; i < n; i++)
        X[i] = V0[i] + alpha * (G[i] - V0[i]);
    for (int32_t h = 0; h < s->nh; h++)
        memcpy(X + 3 * (size_t)s->hidx[h], s->target_req + 3 * (size_t)h, 3 * sizeof(double));
    return DF_OK;
}

/* objective of X(alpha) (into the work buffer X); +inf when it cannot be evaluated (an inverted
 * Neo-Hookean element) */
static double objective_at(const df_admm *s, const double *V0, const double *G, double alpha,
                           double *X, int *count)
{
    (*count)++;
    df_admm_seed_point(s, V0, G, alpha, X, NULL);
    double el = admm_elastic(s, X);
    if (!isfinite(el))
        return INFINITY;
    double E = el + admm_locality(s, X);
    return isfinite(E) ? E : INFINITY;
}

/* Gs = V0 + the proposal's displacements u_i = G_i - V0_i shrunk (admm_seed.h): u_i x
 * max(0, |u_i| - tau) / |u_i| x dmax / (dmax - tau), tau = shrink x dmax, dmax the largest handle
 * displacement |target_h - V0_h|; returns tau */
static double shrink_proposal(const df_admm *s, const double *V0, const double *G, double shrink,
                              double *Gs)
{
    double dmax = 0.0;
    for (int32_t h = 0; h < s->nh; h++) {
        const double *t = s->target_req + 3 * (size_t)h, *x = V0 + 3 * (size_t)s->hidx[h];
        double d = sqrt((t[0] - x[0]) * (t[0] - x[0]) + (t[1] - x[1]) * (t[1] - x[1]) +
                        (t[2] - x[2]) * (t[2] - x[2]));
        dmax = d > dmax ? d : dmax;
    }
    double tau = shrink * dmax;
    if (!(tau > 0.0)) {
        memcpy(Gs, G, 3 * (size_t)s->nv * sizeof *Gs);
        return 0.0;
    }
    double gain = dmax / (dmax - tau);
    for (int32_t i = 0; i < s->nv; i++) {
        const double *g = G + 3 * (size_t)i, *x = V0 + 3 * (size_t)i;
        double u[3] = {g[0] - x[0], g[1] - x[1], g[2] - x[2]};
        double m = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
        double f = m > tau ? (m - tau) / m * gain : 0.0;
        for (int c = 0; c < 3; c++)
            Gs[3 * (size_t)i + c] = x[c] + f * u[c];
    }
    return tau;
}

/* The best alpha in (0, 1] for the (shrunk) proposal G: the grid alphas k / DF_ADMM_SEED_GRID,
 * k >= 1, then golden section over the cells beside the best one. Returns its objective
 * (+inf when every candidate inverts), *alpha the alpha; *e_one the objective at alpha 1. */
static double search_alpha(const df_admm *s, const double *V0, const double *G, double *X,
                           double *alpha, double *e_one, int *count)
{
    double Eg[DF_ADMM_SEED_GRID + 1];
    int best = 1;
    Eg[0] = INFINITY;
    for (int k = 1; k <= DF_ADMM_SEED_GRID; k++) {
        Eg[k] = objective_at(s, V0, G, (double)k / DF_ADMM_SEED_GRID, X, count);
        if (Eg[k] < Eg[best])
            best = k;
    }
    *e_one = Eg[DF_ADMM_SEED_GRID];
    double a_best = (double)best / DF_ADMM_SEED_GRID, e_best = Eg[best];
    if (isfinite(e_best)) {
        const double g = 0.5 * (sqrt(5.0) - 1.0);
        double lo = (double)(best - 1) / DF_ADMM_SEED_GRID;
        double hi = (double)(best < DF_ADMM_SEED_GRID ? best + 1 : best) / DF_ADMM_SEED_GRID;
        double c = hi - g * (hi - lo), d = lo + g * (hi - lo);
        double ec = objective_at(s, V0, G, c, X, count);
        double ed = objective_at(s, V0, G, d, X, count);
        for (int it = 2; it < DF_ADMM_SEED_REFINE; it++) {
            if (ec < ed) {
                hi = d; d = c; ed = ec;
                c = hi - g * (hi - lo);
                ec = objective_at(s, V0, G, c, X, count);
            } else {
                lo = c; c = d; ec = ed;
                d = lo + g * (hi - lo);
                ed = objective_at(s, V0, G, d, X, count);
            }
        }
        if (ec < e_best) { e_best = ec; a_best = c; }
        if (ed < e_best) { e_best = ed; a_best = d; }
    }
    *alpha = a_best;
    return e_best;
}

int df_admm_seed(df_admm *s, const double *V0, const double *G0, double shrink,
                 df_admm_seed_report *rep, df_error *err)
{
    if (!s || !V0 || !G0)
        return df_error_set(err, DF_EINVAL, "admm_seed: NULL argument");
    if (!(shrink == DF_ADMM_SEED_SHRINK_AUTO || (shrink >= 0.0 && shrink <= DF_ADMM_SEED_SHRINK_MAX)))
        return df_error_set(err, DF_EINVAL, "admm_seed: shrink %g is neither in [0, %g] nor "
                            "DF_ADMM_SEED_SHRINK_AUTO (%g)", shrink, DF_ADMM_SEED_SHRINK_MAX,
                            DF_ADMM_SEED_SHRINK_AUTO);
    size_t n = 3 * (size_t)s->nv;
    for (size_t i = 0; i < n; i++)
        if (!isfinite(V0[i]) || !isfinite(G0[i]))
            return df_error_set(err, DF_EINVAL, "admm_seed: vertex %d of the %s is not finite",
                                (int)(i / 3), isfinite(V0[i]) ? "proposal" : "start");
    double *X = malloc(n * sizeof *X), *G = malloc(n * sizeof *G), *Gb = malloc(n * sizeof *Gb);
    if (!X || !G || !Gb) {
        free(X); free(G); free(Gb);
        return df_error_set(err, DF_ENOMEM, "admm_seed: out of memory (%d vertices)", (int)s->nv);
    }
    df_admm_seed_report r = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0};
    r.e_plain = objective_at(s, V0, G0, 0.0, X, &r.evaluations);
    int auto_shrink = shrink == DF_ADMM_SEED_SHRINK_AUTO;
    int k0 = auto_shrink ? 1 : 0, steps = auto_shrink ? DF_ADMM_SEED_SHRINK_STEPS : 0;
    double e_best = INFINITY, a_best = 0.0, s_best = 0.0, t_best = 0.0;
    for (int k = k0; k <= steps; k++) {
        double sh = auto_shrink ? DF_ADMM_SEED_SHRINK_MAX * k / steps : shrink, a, e_one;
        double tau = shrink_proposal(s, V0, G0, sh, G);
        double e;
        if (isfinite(r.e_plain)) {
            e = search_alpha(s, V0, G, X, &a, &e_one, &r.evaluations);
        } else { /* no finite reference: the whole (shrunk) field or nothing (admm_seed.h) */
            a = 1.0;
            e = e_one = objective_at(s, V0, G, 1.0, X, &r.evaluations);
        }
        if (k == k0 || e < e_best)
            r.e_one = e_one;
        if (e < e_best) {
            e_best = e; a_best = a; s_best = sh; t_best = tau;
            double *t = Gb; Gb = G; G = t;   /* keep the best shrunk proposal */
        }
    }
    int rc;
    if (e_best < r.e_plain) {
        df_admm_seed_point(s, V0, Gb, a_best, X, NULL);
        rc = df_admm_set_positions(s, X, NULL, err);
        r.alpha = a_best;
        r.shrink = s_best;
        r.tau = t_best;
        r.e_seed = e_best;
    } else {
        rc = df_admm_set_positions(s, V0, NULL, err);
        r.e_seed = r.e_plain;
    }
    free(X); free(G); free(Gb);
    if (rc == DF_OK && rep)
        *rep = r;
    return rc;
}
