/* admm_newton.c — df_admm_polish (admm.h): projected Newton on the support ADMM found, with an
 * inversion-safe backtracking line search on the true objective, the KKT residual with the
 * subgradient condition on the vertices at rest, and support growth / shrinking. The sparse system
 * is in admm_newton_sys.c, the per-element derivatives in admm_newton_elem.c. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/admm/admm_newton.h"

#define PN_DEFAULT_ITERS 50
#define PN_DEFAULT_TOL 1e-9
#define PN_TAU 0.9           /* fraction to the boundary (first inverting step) */
#define PN_ARMIJO 1e-4
#define PN_ROUNDOFF 1e-12    /* changes below this relative to |E| are roundoff */
#define PN_SNAP_REL 1e-1     /* free vertices within this times s of rest may snap back */
#define PN_SNAP_MIN 1e-7     /* (smallest threshold tried) */
#define PN_REAIM_REL 1e-3    /* free violators this close to rest (times s) may be re-aimed */
#define PN_REAIM_COS 0.99    /* ... unless already pointing along -g_el within this cosine */
#define PN_GROW_FRAC 0.1     /* grow by the violators within this fraction of the worst */
#define PN_VIOL_REL 1e-3     /* a violation counts when above this times tol * scale */

enum { CLS_FIXED = 0, CLS_FREE = 1, CLS_REST = 2 };

typedef struct pn {
    df_admm *s;
    double tol;
    double *V, *Vt, *g, *gl, *fmag, *D, *b, *x, *viol;
    uint8_t *cls;
    int32_t *sup, nsup;
    double f;                 /* objective at V */
    double rf, rr, scale, kkt, maxviol;
    int32_t nviol;
} pn;

static double objective(const df_admm *s, const double *V, double *el, double *lo)
{
    double e = admm_elastic(s, V), l = admm_locality(s, V);
    if (el) *el = e;
    if (lo) *lo = l;
    return e + l;
}

static int rest_feasible(const df_admm *s, int32_t i)
{
    const admm_polish_cache *c = s->polish;
    return c->pidx[i] < 0 || c->Pres[c->pidx[i]] <= 1e-9 * s->p.s;
}

static void collect_support(pn *P)
{
    P->nsup = 0;
    for (int32_t i = 0; i < P->s->nv; i++)
        if (P->cls[i] == CLS_FREE) P->sup[P->nsup++] = i;
}

/* gradient at V (projected per affine vertex) and the KKT measures */
static int measure(pn *P, df_error *err)
{
    df_admm *s = P->s;
    int rc = admm_newton_gradient(s, P->V, P->g, P->gl, P->fmag);
    if (rc == -2) return df_error_set(err, DF_ENOMEM, "admm_polish: out of memory");
    if (rc) return df_error_set(err, DF_EINTERNAL, "admm_polish: inverted element in an accepted iterate");
    double rf = 0, rr = 0, sc = 0, mv = 0;
    for (int32_t i = 0; i < s->nv; i++) {
        P->viol[i] = 0;
        if (P->cls[i] == CLS_FIXED) continue;
        double *g = P->g + 3 * (size_t)i, *gl = P->gl + 3 * (size_t)i;
        admm_pn_project(s, i, g);
        admm_pn_project(s, i, gl);
        sc += P->fmag[i] * P->fmag[i];
        if (P->cls[i] == CLS_FREE) {
            for (int k = 0; k < 3; k++) rf += (g[k] + gl[k]) * (g[k] + gl[k]);
        } else {
            double v = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]) - s->p.w * s->a[i];
            if (v > 0) { P->viol[i] = v; rr += v * v; if (v > mv) mv = v; }
        }
    }
    P->rf = sqrt(rf);
    P->rr = sqrt(rr);
    P->scale = sqrt(sc);
    P->maxviol = mv;
    double r = sqrt(rf + rr);
    P->kkt = r == 0 ? 0.0 : P->scale > 0 ? r / P->scale : INFINITY;
    P->nviol = 0;
    for (int32_t i = 0; i < s->nv; i++)
        if (P->viol[i] > PN_VIOL_REL * P->tol * P->scale) P->nviol++;
    return DF_OK;
}

/* stiffness estimate of vertex i along one direction (for the first step off rest) */
static double vertex_stiffness(const df_admm *s, int32_t i)
{
    double kap = s->p.energy == DF_ADMM_NEOHOOKEAN ? 2.0 * s->mu + s->lambda : 1.0, k = 0;
    for (int32_t p = s->ve_ptr[i]; p < s->ve_ptr[i + 1]; p++) {
        int32_t e = s->ve_ent[p] / 4, a = s->ve_ent[p] % 4;
        const double *ga = s->grad + (size_t)e * 12 + 3 * a;
        k += s->vol[e] * kap * (ga[0] * ga[0] + ga[1] * ga[1] + ga[2] * ga[2]);
    }
    return k;
}

/* V += a D for the first a in 1, 1/2, ..., 2^-(halvings - 1) with a finite objective below P->f
 * (P->f updated; P->Vt scratch); 0 when none */
static int halving_step(pn *P, int halvings)
{
    size_t nv3 = 3 * (size_t)P->s->nv;
    for (int h = 0; h < halvings; h++) {
        double a = ldexp(1.0, -h);
        for (size_t q = 0; q < nv3; q++) P->Vt[q] = P->V[q] + a * P->D[q];
        double ft = objective(P->s, P->Vt, NULL, NULL);
        if (isfinite(ft) && ft < P->f) {
            memcpy(P->V, P->Vt, nv3 * sizeof(double));
            P->f = ft;
            return 1;
        }
    }
    return 0;
}

/* moves the worst subgradient violators off rest along -g_el (first-order step, halved until E
 * decreases); returns the number added (0: none could decrease E) */
static int32_t grow(pn *P)
{
    df_admm *s = P->s;
    size_t nv3 = 3 * (size_t)s->nv;
    memset(P->D, 0, nv3 * sizeof(double));
    int32_t n = 0;
    for (int32_t i = 0; i < s->nv; i++) {
        double v = P->viol[i];
        if (!(v > 0) || v < PN_GROW_FRAC * P->maxviol || v <= PN_VIOL_REL * P->tol * P->scale) continue;
        const double *g = P->g + 3 * (size_t)i;
        double ng = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]), k = vertex_stiffness(s, i);
        double t = k > 0 ? v / k : s->p.s;
        if (t > s->p.s) t = s->p.s;
        for (int q = 0; q < 3; q++) P->D[3 * (size_t)i + q] = -t * g[q] / ng;
        n++;
    }
    if (n == 0 || !halving_step(P, 40)) return 0;
    for (int32_t i = 0; i < s->nv; i++)
        if (P->D[3 * (size_t)i] != 0 || P->D[3 * (size_t)i + 1] != 0 || P->D[3 * (size_t)i + 2] != 0)
            P->cls[i] = CLS_FREE;
    collect_support(P);
    return n;
}

/* snaps free vertices back to rest that are within PN_SNAP_REL s of it and satisfy the subgradient
 * condition there by the current elastic gradient (|g_el,i| <= w a_i: they would stay), when that
 * does not raise E; on a rise, tries again with the threshold / 10 (down to PN_SNAP_MIN s) */
static int32_t shrink(pn *P)
{
    df_admm *s = P->s;
    size_t nv3 = 3 * (size_t)s->nv;
    for (double thr = PN_SNAP_REL; thr >= PN_SNAP_MIN; thr *= 0.1) {
        int32_t n = 0;
        memcpy(P->Vt, P->V, nv3 * sizeof(double));
        for (int32_t i = 0; i < s->nv; i++) {
            double wa = s->p.w * s->a[i];
            if (P->cls[i] != CLS_FREE || !(wa > 0) || !rest_feasible(s, i)) continue;
            const double *g = P->g + 3 * (size_t)i;
            if (sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]) > wa) continue;
            double r2 = 0;
            for (int k = 0; k < 3; k++) {
                double d = P->V[3 * (size_t)i + k] - s->Vrest[3 * (size_t)i + k];
                r2 += d * d;
            }
            if (sqrt(r2) >= thr * s->p.s) continue;
            memcpy(P->Vt + 3 * (size_t)i, s->Vrest + 3 * (size_t)i, 3 * sizeof(double));
            n++;
        }
        if (n == 0) return 0;
        double ft = objective(s, P->Vt, NULL, NULL);
        if (!(ft <= P->f)) continue;
        for (int32_t i = 0; i < s->nv; i++)
            if (P->cls[i] == CLS_FREE && memcmp(P->Vt + 3 * (size_t)i, P->V + 3 * (size_t)i, 3 * sizeof(double)))
                P->cls[i] = CLS_REST;
        memcpy(P->V, P->Vt, nv3 * sizeof(double));
        P->f = ft;
        collect_support(P);
        return n;
    }
    return 0;
}

/* re-aims free vertices stuck next to rest: within PN_REAIM_REL s of it, violating the subgradient
 * condition there (|g_el,i| > w a_i: they want out) but not pointing along -g_el (the SC-L1
 * term's tangential curvature w a_i (1 - r/s) / r makes turning them a crawl): they jump to rest -
 * t g_el / |g_el| (t as for a new support vertex, at least their distance), halved until E
 * decreases; returns the number moved */
static int32_t reaim(pn *P)
{
    df_admm *s = P->s;
    size_t nv3 = 3 * (size_t)s->nv;
    memset(P->D, 0, nv3 * sizeof(double));
    int32_t n = 0;
    for (int32_t i = 0; i < s->nv; i++) {
        double wa = s->p.w * s->a[i];
        if (P->cls[i] != CLS_FREE || !(wa > 0)) continue;
        const double *g = P->g + 3 * (size_t)i, *x = P->V + 3 * (size_t)i, *x0 = s->Vrest + 3 * (size_t)i;
        double ng = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]), d[3], r = 0, dg = 0;
        if (!(ng > wa)) continue;
        for (int k = 0; k < 3; k++) { d[k] = x[k] - x0[k]; r += d[k] * d[k]; dg += d[k] * g[k]; }
        r = sqrt(r);
        if (r >= PN_REAIM_REL * s->p.s || (r > 0 && -dg >= PN_REAIM_COS * r * ng)) continue;
        double k = vertex_stiffness(s, i), t = k > 0 ? (ng - wa) / k : s->p.s;
        if (t > s->p.s) t = s->p.s;
        if (t < r) t = r;
        for (int q = 0; q < 3; q++) P->D[3 * (size_t)i + q] = x0[q] - t * g[q] / ng - x[q];
        n++;
    }
    return n > 0 && halving_step(P, 30) ? n : 0;
}

/* the Newton matrix: exact, else projected, else projected + growing shift */
static int model(pn *P, df_admm_polish_result *r, df_error *err)
{
    df_admm *s = P->s;
    admm_polish_cache *c = s->polish;
    int pd = 0, rc;
    for (int attempt = 0; attempt < 14 && !pd; attempt++) {
        int project = attempt > 0;
        double shift = 0;
        if (attempt >= 2) {
            double dmax = 0;
            const int *Hp = c->H->p;
            for (size_t d = 0; d < c->H->ncol; d++) {
                double v = fabs(((double *)c->H->x)[Hp[d + 1] - 1]);
                if (v > dmax) dmax = v;
            }
            shift = (dmax > 0 ? dmax : 1.0) * 1e-10 * pow(10.0, attempt - 2);
        }
        double ta = admm_now();
        if (admm_pn_assemble(s, P->V, project, shift))
            return df_error_set(err, DF_ENOMEM, "admm_polish: out of memory (Hessian assembly)");
        r->t_assemble += admm_now() - ta;
        ta = admm_now();
        rc = admm_pn_factor(s, &pd, err);
        r->t_factor += admm_now() - ta;
        r->factorizations++;
        if (rc) return rc;
        if (!pd && attempt == 0) r->projected++;
        if (!pd && attempt == 1) r->shifted++;
    }
    if (!pd) return df_error_set(err, DF_EINTERNAL, "admm_polish: Newton matrix not positive definite even with a shift");
    return DF_OK;
}

/* largest step along D that keeps every element touching the support uninverted, capped */
static double max_step(const pn *P, double cap)
{
    const df_admm *s = P->s;
    if (s->p.energy != DF_ADMM_NEOHOOKEAN) return INFINITY;
    double amin = INFINITY;
    #pragma omp parallel for schedule(static) num_threads(s->nthreads) reduction(min : amin)
    for (int32_t e = 0; e < s->ne; e++) {
        const int32_t *el = s->E + (size_t)e * 4;
        if (P->cls[el[0]] != CLS_FREE && P->cls[el[1]] != CLS_FREE && P->cls[el[2]] != CLS_FREE &&
            P->cls[el[3]] != CLS_FREE)
            continue;
        double F[9], Dm[9];
        admm_newton_element_F(s, P->V, e, F);
        admm_newton_element_F(s, P->D, e, Dm);
        double t = admm_newton_det_step(F, Dm, cap);
        if (t < amin) amin = t;
    }
    return amin;
}

static void record(pn *P, df_admm_polish_result *r, int k, double t0)
{
    if (k >= DF_ADMM_POLISH_HIST) return;
    r->hist_objective[k] = P->f;
    r->hist_kkt[k] = P->kkt;
    r->hist_time[k] = admm_now() - t0;
    r->hist_n = k + 1;
}

static int newton(pn *P, const df_admm_polish_params *prm, df_admm_polish_result *r, double t0, df_error *err)
{
    df_admm *s = P->s;
    size_t nv3 = 3 * (size_t)s->nv;
    int maxit = prm->max_iters, rounds = 0;
    for (;;) {
        int rc = measure(P, err);
        if (rc) return rc;
        int32_t snapped = shrink(P);
        if (snapped > 0) {
            r->removed += snapped;
            rc = measure(P, err);
            if (rc) return rc;
        }
        if (reaim(P) > 0) {
            rc = measure(P, err);
            if (rc) return rc;
        }
        record(P, r, r->iterations, t0);
        if (P->kkt < P->tol) { r->converged = 1; break; }
        if (!prm->no_grow && P->nviol > 0 && (P->rr >= P->rf || P->rf < P->tol * P->scale) && rounds < maxit) {
            rounds++;
            int32_t n = grow(P);
            r->added += n;
            if (n > 0) continue;
        }
        if (r->iterations >= maxit) break;
        if (P->nsup == 0) break; /* nothing to polish and no violator could move */
        long an = 0;
        rc = admm_pn_prepare(s, P->sup, P->nsup, &an, err);
        r->analyses += an;
        if (rc) return rc;
        rc = model(P, r, err);
        if (rc) return rc;
        for (int32_t j = 0; j < P->nsup; j++)
            for (int k = 0; k < 3; k++) {
                size_t q = 3 * (size_t)P->sup[j] + k;
                P->b[3 * (size_t)j + k] = -(P->g[q] + P->gl[q]);
            }
        double ta = admm_now();
        rc = admm_pn_solve(s, P->b, P->x, err);
        r->t_factor += admm_now() - ta;
        if (rc) return rc;
        memset(P->D, 0, nv3 * sizeof(double));
        double gd = 0;
        for (int32_t j = 0; j < P->nsup; j++) {
            int32_t i = P->sup[j];
            double *d = P->D + 3 * (size_t)i;
            memcpy(d, P->x + 3 * (size_t)j, 3 * sizeof(double));
            admm_pn_project(s, i, d);
            for (int k = 0; k < 3; k++) gd += (P->g[3 * (size_t)i + k] + P->gl[3 * (size_t)i + k]) * d[k];
        }
        if (!(gd < 0)) { r->line_search_fail = 1; break; }
        ta = admm_now();
        double amax = max_step(P, 1.0 / PN_TAU), alpha = amax * PN_TAU < 1.0 ? amax * PN_TAU : 1.0;
        int ok = 0;
        double ft = NAN;
        for (int h = 0; h < 60 && !ok; h++, alpha *= 0.5) {
            for (size_t q = 0; q < nv3; q++) P->Vt[q] = P->V[q] + alpha * P->D[q];
            ft = objective(s, P->Vt, NULL, NULL);
            if (!isfinite(ft)) continue;
            double roff = PN_ROUNDOFF * fabs(P->f);
            ok = ft <= P->f + PN_ARMIJO * alpha * gd || (-alpha * gd <= roff && ft - P->f <= roff);
        }
        r->t_line += admm_now() - ta;
        if (!ok) { r->line_search_fail = 1; break; }
        memcpy(P->V, P->Vt, nv3 * sizeof(double));
        P->f = ft;
        r->iterations++;
    }
    return DF_OK;
}

static void pn_free(pn *P)
{
    free(P->V); free(P->Vt); free(P->g); free(P->gl); free(P->fmag); free(P->D);
    free(P->b); free(P->x); free(P->viol); free(P->cls); free(P->sup);
}

/* classification of the start: fixed (handles, followers), free (support), rest (snapped) */
static void classify(pn *P, double support_tol)
{
    df_admm *s = P->s;
    for (int32_t i = 0; i < s->nv; i++) {
        P->cls[i] = CLS_REST;
        if (s->fo_flag && s->fo_flag[i]) { P->cls[i] = CLS_FIXED; continue; }
        const double *z = s->Z + 3 * (size_t)i;
        double zn = sqrt(z[0] * z[0] + z[1] * z[1] + z[2] * z[2]);
        if (!(s->p.w * s->a[i] > 0) || !rest_feasible(s, i) || (support_tol > 0 ? zn > support_tol : zn != 0))
            P->cls[i] = CLS_FREE;
    }
    for (int32_t h = 0; h < s->nh; h++) P->cls[s->hidx[h]] = CLS_FIXED;
    for (int32_t i = 0; i < s->nv; i++)
        if (P->cls[i] == CLS_REST) memcpy(P->V + 3 * (size_t)i, s->Vrest + 3 * (size_t)i, 3 * sizeof(double));
    /* Neo-Hookean: snapping may invert an element next to the support (an unconverged ADMM's V is
     * off Z by its primal residual): such elements' snapped vertices go back to ADMM's positions
     * and into the support, until no element is inverted (ADMM's own V is uninverted) */
    for (int changed = s->p.energy == DF_ADMM_NEOHOOKEAN; changed;) {
        changed = 0;
        for (int32_t e = 0; e < s->ne; e++) {
            const int32_t *el = s->E + (size_t)e * 4;
            double F[9];
            admm_newton_element_F(s, P->V, e, F);
            if (admm_det3(F) > 0) continue;
            for (int a = 0; a < 4; a++)
                if (P->cls[el[a]] == CLS_REST) {
                    P->cls[el[a]] = CLS_FREE;
                    memcpy(P->V + 3 * (size_t)el[a], s->Vout + 3 * (size_t)el[a], 3 * sizeof(double));
                    changed = 1;
                }
        }
    }
    collect_support(P);
}

static int check_supported(const df_admm *s, df_error *err)
{
    if (s->kind != DF_MESH_TET || (s->p.energy != DF_ADMM_NEOHOOKEAN && s->p.energy != DF_ADMM_ARAP &&
                                   s->p.energy != DF_ADMM_ACAP))
        return df_error_set(err, DF_EUNSUPPORTED, "admm_polish: only tet meshes with the arap, acap or "
                            "neohookean energy are supported (spokes-and-rims triangle energies, cloth "
                            "and polylines are not)");
    return DF_OK;
}

int df_admm_kkt(df_admm *s, const double *V, double *kkt, df_error *err)
{
    if (!s || !V || !kkt) return df_error_set(err, DF_EINVAL, "admm_kkt: NULL argument");
    int rc = check_supported(s, err);
    if (rc) return rc;
    for (int64_t i = 0; i < 3 * (int64_t)s->nv; i++)
        if (!isfinite(V[i])) return df_error_set(err, DF_EINVAL, "admm_kkt: vertex %d is not finite", (int)(i / 3));
    rc = admm_pn_cache(s, err);
    if (rc) return rc;
    pn P;
    memset(&P, 0, sizeof(P));
    P.s = s;
    P.tol = PN_DEFAULT_TOL;
    size_t nv3 = 3 * (size_t)s->nv;
    P.V = malloc(nv3 * sizeof(double));
    P.g = malloc(nv3 * sizeof(double));
    P.gl = malloc(nv3 * sizeof(double));
    P.fmag = malloc((size_t)s->nv * sizeof(double));
    P.viol = malloc((size_t)s->nv * sizeof(double));
    P.cls = malloc((size_t)s->nv);
    if (!P.V || !P.g || !P.gl || !P.fmag || !P.viol || !P.cls) {
        pn_free(&P);
        return df_error_set(err, DF_ENOMEM, "admm_kkt: out of memory");
    }
    memcpy(P.V, V, nv3 * sizeof(double));
    for (int32_t i = 0; i < s->nv; i++)
        P.cls[i] = (s->fo_flag && s->fo_flag[i]) ? CLS_FIXED
                   : (!(s->p.w * s->a[i] > 0) || memcmp(V + 3 * (size_t)i, s->Vrest + 3 * (size_t)i, 3 * sizeof(double)))
                   ? CLS_FREE : CLS_REST;
    for (int32_t h = 0; h < s->nh; h++) P.cls[s->hidx[h]] = CLS_FIXED;
    rc = measure(&P, err);
    if (rc == DF_EINTERNAL) rc = df_error_set(err, DF_ESTATE, "admm_kkt: inverted element at V");
    if (!rc) *kkt = P.kkt;
    pn_free(&P);
    return rc;
}

int df_admm_polish(df_admm *s, const df_admm_polish_params *params, df_admm_polish_result *res, df_error *err)
{
    if (!s) return df_error_set(err, DF_EINVAL, "admm_polish: NULL solver");
    df_admm_polish_params prm = {0};
    if (params) prm = *params;
    if (prm.max_iters > DF_ADMM_POLISH_MAX_ITERS)
        return df_error_set(err, DF_EINVAL, "admm_polish: max_iters %d exceeds %d", prm.max_iters, DF_ADMM_POLISH_MAX_ITERS);
    if (isnan(prm.tol) || isnan(prm.support_tol) || prm.support_tol < 0 || !isfinite(prm.support_tol))
        return df_error_set(err, DF_EINVAL, "admm_polish: tol and support_tol must be finite, support_tol >= 0");
    if (prm.max_iters <= 0) prm.max_iters = PN_DEFAULT_ITERS;
    if (!(prm.tol > 0)) prm.tol = PN_DEFAULT_TOL;
    int rc = check_supported(s, err);
    if (rc) return rc;
    for (int32_t h = 0; h < s->nh; h++)
        if (memcmp(s->Vout + 3 * (size_t)s->hidx[h], s->target_req + 3 * (size_t)h, 3 * sizeof(double)))
            return df_error_set(err, DF_ESTATE, "admm_polish: handle %d (vertex %d) is not at its target "
                                "(targets set but not yet reached, e.g. damped Neo-Hookean steps pending): "
                                "run ADMM further first", (int)h, (int)s->hidx[h]);
    rc = admm_pn_cache(s, err);
    if (rc) return rc;
    double t0 = admm_now();
    df_admm_polish_result r;
    memset(&r, 0, sizeof(r));
    pn P;
    memset(&P, 0, sizeof(P));
    P.s = s;
    P.tol = prm.tol;
    size_t nv3 = 3 * (size_t)s->nv;
    P.V = malloc(nv3 * sizeof(double));
    P.Vt = malloc(nv3 * sizeof(double));
    P.g = malloc(nv3 * sizeof(double));
    P.gl = malloc(nv3 * sizeof(double));
    P.D = malloc(nv3 * sizeof(double));
    P.b = malloc(nv3 * sizeof(double));
    P.x = malloc(nv3 * sizeof(double));
    P.fmag = malloc((size_t)s->nv * sizeof(double));
    P.viol = malloc((size_t)s->nv * sizeof(double));
    P.cls = malloc((size_t)s->nv);
    P.sup = malloc((size_t)s->nv * sizeof(int32_t));
    if (!P.V || !P.Vt || !P.g || !P.gl || !P.D || !P.b || !P.x || !P.fmag || !P.viol || !P.cls || !P.sup) {
        pn_free(&P);
        return df_error_set(err, DF_ENOMEM, "admm_polish: out of memory");
    }
    memcpy(P.V, s->Vout, nv3 * sizeof(double));
    r.objective_admm = objective(s, P.V, NULL, NULL);
    classify(&P, prm.support_tol);
    P.f = objective(s, P.V, NULL, NULL);
    if (!isfinite(P.f)) {
        pn_free(&P);
        return df_error_set(err, DF_ESTATE, "admm_polish: the start shape has an inverted element");
    }
    rc = newton(&P, &prm, &r, t0, err);
    if (rc) { pn_free(&P); return rc; }
    admm_place_followers(s, P.V);
    r.objective = objective(s, P.V, &r.elastic, &r.locality);
    r.kkt = P.kkt;
    r.kkt_free = P.scale > 0 ? P.rf / P.scale : (P.rf > 0 ? INFINITY : 0);
    r.kkt_rest = P.scale > 0 ? P.rr / P.scale : (P.rr > 0 ? INFINITY : 0);
    r.scale = P.scale;
    r.support = P.nsup;
    r.violations = P.nviol;
    rc = df_admm_set_positions(s, P.V, NULL, err);
    pn_free(&P);
    if (rc) return rc;
    r.t_total = admm_now() - t0;
    if (res) *res = r;
    return DF_OK;
}
