/* admm_active_run.c — df_admm_run in active-set mode (admm.h DF_ADMM_ACTIVE): the ADMM iteration
 * restricted to the active region (local steps on its elements or cells, SC-L1 prox and duals on
 * its vertices, the global step on its free vertices with the region's factor, Neo-Hookean damped
 * handle steps), the same scale-invariant stop test as the full solve (admm.h DF_ADMM_RESIDUAL;
 * the far field adds its constant share sum gam_e |I|^2 to the residual scales), region growth,
 * the far-field certificate, the tail test (params.active_tail) with its probe (a first
 * iteration that grew a fresh region is redone on the grown one) and the fallback to the full
 * solve. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/admm/admm_active.h"
#include "core/admm/admm_resid.h"
#include "core/admm/scl1.h"

#define ADMM_BUDGET_MARGIN 1.05 /* as admm_run.c */
/* a run starts from a fresh region when the current one is this many times larger than needed */
#define ACT_SHRINK 2
/* tail test: restarts of a run on a fresh region whose first iteration grew it (the probe) */
#define ACT_PROBES 3

/* The residuals of the stop test (admm_resid.c's, over the region) are summed inside the
 * kernels from each item's old and new values, without snapshots: squared norms of r, A x, z, s
 * and y in the penalty metric. */
typedef struct act_acc {
    double r2, ax2, z2, s2, y2;
} act_acc;

/* the two F buffers (admm_active.h) and the partial sums (admm_active_elem.c), one allocation of
 * cap_gc x (2 x 9 + 4) doubles: capacity for the region's elements; without memory the local step
 * gathers F_e itself (gc_ok stays 0), the energy is summed in every dual update and the element
 * sums run on one thread below ACT_PAR_LIGHT */
static void gc_reserve(admm_active *a)
{
    a->gc_ok = 0;
    if (a->nae <= a->cap_gc) return;
    int64_t c = a->nae + a->nae / 4;
    free(a->gc);
    a->gc = malloc((size_t)c * 22 * sizeof(double));
    a->cap_gc = a->gc ? c : 0;
}

/* F buffer b (0, 1) */
static double *fbuf(const admm_active *a, int b) { return a->gc + (size_t)b * 9 * (size_t)a->cap_gc; }

/* local step 2 on the region (SC-L1 prox) with its residual sums in vertex order; *sec its time */
static void act_local_z(df_admm *s, double *zs2, double *zz2, double *sec)
{
    const admm_active *a = s->act;
    const double w = s->p.w, sth = s->p.s, rho = s->p.rho;
    double t0 = admm_now(), s2 = 0, z2 = 0;
    for (int32_t k = 0; k < a->nr; k++) {
        size_t o = 3 * (size_t)a->rv[k];
        double x[3], old[3] = {s->Z[o], s->Z[o + 1], s->Z[o + 2]};
        for (int c = 0; c < 3; c++) x[c] = s->V[o + c] - s->Vrest[o + c] + s->U[o + c];
        df_admm_scl1_prox(x, w * s->a[a->rv[k]], sth, rho, s->Z + o);
        for (int c = 0; c < 3; c++) {
            double d = s->Z[o + c] - old[c];
            s2 += d * d;
            z2 += s->Z[o + c] * s->Z[o + c];
        }
    }
    *zs2 = rho * s2;
    *zz2 = rho * z2;
    *sec = admm_now() - t0;
}

/* The local phase of an iteration in one OpenMP region (one fork): local step 1 on the region's
 * elements (cells) with one thread doing local step 2 (the prox, independent of it) meanwhile,
 * then, after the barrier, the right-hand side rows of the region's free vertices (element
 * (cell) pieces, rho (Vrest + Z - U), minus the couplings to the outside at rest), and serially
 * the couplings to the handles at their applied targets. *t_x: seconds of the phase up to the
 * barrier less the prox's, *t_z: the prox's, *t_rhs: the rows' and couplings'. */
static void act_local(df_admm *s, act_acc *acc, double *t_x, double *t_z, double *t_rhs)
{
    admm_active *a = s->act;
    const int elem = s->family == ADMM_FAM_ELEMENT;
    const int32_t nf = a->nrf;
    double *rhs = a->rhs ? a->rhs->x : NULL;
    double s2 = 0, z2 = 0, zs2 = 0, zz2 = 0, tz = 0, t0 = admm_now(), t_mid = t0;
    /* elements in ae order, G from the dual update's F buffer when it is current */
    const double *fc = elem && a->gc_ok ? fbuf(a, a->gc_buf) : NULL;
    /* ARAP / ACAP tets from the F buffer: four elements at a time (admm_tet4.c, same bits) */
    const int tet4 = fc && s->q == 3 && s->esz == 4 && (s->p.energy == DF_ADMM_ARAP || s->p.energy == DF_ADMM_ACAP);
    #pragma omp parallel num_threads(s->nthreads) if (a->nae >= ACT_PAR_HEAVY)
    {
#ifdef _OPENMP /* (builds without OpenMP, e.g. make tsan's -fopenmp-simd, warn on these two) */
        #pragma omp single nowait
#endif
        act_local_z(s, &zs2, &zz2, &tz);
        if (tet4) {
            #pragma omp for schedule(dynamic, 1) reduction(+ : s2, z2)
            for (int32_t b = 0; b < a->nae; b += ACT_TET4_CHUNK)
                admm_local_tet4(s, a->ae + b, fc + 9 * (size_t)b, a->nae - b < ACT_TET4_CHUNK ? a->nae - b : ACT_TET4_CHUNK, &s2, &z2);
        } else if (elem) {
            #pragma omp for schedule(dynamic, 256) reduction(+ : s2, z2)
            for (int32_t k = 0; k < a->nae; k++) {
                int32_t e = a->ae[k];
                double *RX = s->RX + 9 * (size_t)e, old[9], ds = 0, dz = 0;
                memcpy(old, RX, sizeof(old));
                if (fc) { /* G = F_e(V) + W_e, as admm_local_x_one sums it */
                    double G[9];
                    const double *F = fc + 9 * (size_t)k, *W = s->W + 9 * (size_t)e;
                    for (int c = 0; c < 9; c++) G[c] = F[c] + W[c];
                    admm_local_x_one_G(s, e, G);
                } else {
                    admm_local_x_one(s, e);
                }
                for (int c = 0; c < 9; c++) {
                    double d = RX[c] - old[c];
                    ds += d * d;
                    dz += RX[c] * RX[c];
                }
                s2 += s->gam[e] * ds;
                z2 += s->gam[e] * dz;
            }
        } else {
            #pragma omp for schedule(static)
            for (int32_t k = 0; k < a->nae; k++) admm_fit_vertex(s, s->V, a->ae[k], s->Rv + 9 * (size_t)a->ae[k]);
        }
        /* the implicit barrier above also waits for the prox (Z) */
#ifdef _OPENMP
        #pragma omp master
#endif
        t_mid = admm_now();
        #pragma omp for schedule(static) nowait /* the region's end is the barrier */
        for (int32_t f = 0; f < nf; f++) admm_rhs_row(s, a->rfv, nf, a->kout, rhs, f);
    }
    if (elem) {
        acc->s2 += s2;
        acc->z2 += z2;
    }
    acc->s2 += zs2;
    acc->z2 += zz2;
    for (int64_t t = 0; nf > 0 && t < a->ncp; t++) {
        const double *p = s->target + 3 * (size_t)a->hmap[a->cp_v[t]];
        for (int k = 0; k < 3; k++) rhs[a->cp_f[t] + (size_t)k * nf] -= a->cp_val[t] * p[k];
    }
    double t_end = admm_now();
    *t_z = tz;
    *t_x = t_mid - t0 - tz;
    *t_rhs = t_end - t_mid;
}

static int any_inverted(const df_admm *s)
{
    const admm_active *a = s->act;
    int bad = 0;
    #pragma omp parallel for schedule(static) num_threads(s->nthreads) reduction(| : bad) if (a->nae >= ACT_PAR_LIGHT)
    for (int32_t k = 0; k < a->nae; k++) {
        double F[9];
        admm_element_F(s, s->V, a->ae[k], F);
        bad |= !(admm_det3(F) > 0);
    }
    return bad;
}

/* V = va + t x on the region's free vertices, handles at target + t dp (admm_damp.c) */
static void place(df_admm *s, const double *x, double t)
{
    admm_active *a = s->act;
    int32_t nf = a->nrf;
    for (int32_t k = 0; k < a->nr; k++) {
        int32_t v = a->rv[k], f = a->rfidx[v];
        if (f < 0) continue;
        for (int c = 0; c < 3; c++) s->V[3 * (size_t)v + c] = a->va[3 * (size_t)k + c] + t * x[f + (size_t)c * nf];
    }
    for (int32_t h = 0; h < s->nh; h++)
        for (int c = 0; c < 3; c++)
            s->V[3 * (size_t)s->hidx[h] + c] = s->target[3 * (size_t)h + c] + t * s->damp_dp[3 * (size_t)h + c];
}

/* the global step on the region (admm_damp.c's damped handle steps for Neo-Hookean) */
static int act_global(df_admm *s, df_error *err)
{
    admm_active *a = s->act;
    int32_t nf = a->nrf;
    const double *x = NULL;
    if (nf > 0) {
        int rc = admm_act_solve(s, &x, err);
        if (rc) return rc;
        for (int32_t f = 0; f < nf; f++) {
            double *v = s->V + 3 * (size_t)a->rfv[f];
            v[0] = x[f]; v[1] = x[f + nf]; v[2] = x[f + 2 * (size_t)nf];
        }
    }
    for (int32_t h = 0; h < s->nh; h++) memcpy(s->V + 3 * (size_t)s->hidx[h], s->target + 3 * (size_t)h, 3 * sizeof(double));
    if (!s->damp || !s->tgt_pending) return DF_OK;
    for (int32_t k = 0; k < a->nr; k++) memcpy(a->va + 3 * (size_t)k, s->V + 3 * (size_t)a->rv[k], 3 * sizeof(double));
    for (int64_t i = 0; i < 3 * (int64_t)s->nh; i++) s->damp_dp[i] = s->target_req[i] - s->target[i];
    if (nf > 0) {
        double *rhs = a->rhs->x;
        memset(rhs, 0, (size_t)nf * 3 * sizeof(double));
        for (int64_t t = 0; t < a->ncp; t++) {
            int32_t h = a->hmap[a->cp_v[t]];
            for (int k = 0; k < 3; k++) rhs[a->cp_f[t] + (size_t)k * nf] -= a->cp_val[t] * s->damp_dp[3 * (size_t)h + k];
        }
        int rc = admm_act_solve(s, &x, err);
        if (rc) { place(s, x ? x : rhs, 0.0); return rc; }
    }
    double t = 1.0;
    int found = 0;
    for (int k = 0; k <= ADMM_DAMP_HALVINGS; k++, t *= 0.5) {
        place(s, x, t);
        if (!any_inverted(s)) { found = 1; break; }
    }
    if (!found) {
        place(s, x, 0.0);
        t = admm_damp_choose(s, t * 2.0, any_inverted(s));
        place(s, x, t);
    } else {
        s->damp_stall = 0;
    }
    admm_damp_apply(s, t);
    a->kfhp_dirty = 1;
    return DF_OK;
}

/* duals on the region; element family: F_e(V) of the region's elements stored in F buffer buf
 * (nae x 9, ae order; when there is one) for the next local step and the lazy energy, and the
 * elastic energy of the new V over the region's elements (the outside is exactly at rest: zero
 * energy) returned, or 0 when lazy (then the buffer is there: lazy_ok) */
static double act_dual(df_admm *s, act_acc *acc, int buf, int lazy)
{
    admm_active *a = s->act;
    double E = 0;
    if (s->family == ADMM_FAM_ELEMENT) {
        double r2, ax2, y2;
        double *fb = a->gc && a->cap_gc >= a->nae ? fbuf(a, buf) : NULL;
        E = admm_act_dual_elems(s, fb, lazy, &r2, &ax2, &y2);
        acc->r2 += r2; acc->ax2 += ax2; acc->y2 += y2;
        a->gc_ok = fb != NULL;
        a->gc_buf = buf;
    }
    double r2 = 0, ax2 = 0, y2 = 0;
    for (int32_t k = 0; k < a->nr; k++) {
        size_t o = 3 * (size_t)a->rv[k];
        for (int c = 0; c < 3; c++) {
            double du = s->V[o + c] - s->Vrest[o + c] - s->Z[o + c], ax = s->Z[o + c] + du;
            s->U[o + c] += du;
            r2 += du * du; ax2 += ax * ax; y2 += s->U[o + c] * s->U[o + c];
        }
    }
    const double rho = s->p.rho;
    acc->r2 += rho * r2; acc->ax2 += rho * ax2; acc->y2 += rho * y2;
    return E;
}

/* The lazy energy (ARAP / ACAP tets, whose energy is finite and >= 0): the dual update stores
 * F_e(V) (act_dual's fb) and the elastic energy of an iteration is summed from it only when
 * something needs it: the stop test when it can pass (sqrt(tol) max(pri, dual) < tol; otherwise
 * it fails whatever the objective), the last iteration of the call, a progress report, the tail
 * test when the locality alone does not settle it (E >= lo), before a region growth (which
 * changes ae), and the run's result. fb_energy sums it with act_dual's loop (same partition and
 * order of the sum), so every reported value is bit-identical to summing it in every dual
 * update. Two buffers: the objective of the iteration before is needed with the current one
 * (the stop residual |E - E_prev| / |E|). */
typedef struct lazy_it {
    int pend;          /* el not summed yet: F_e in buffer buf */
    int buf;
    double el, lo, E;
} lazy_it;

static int lazy_ok(const df_admm *s)
{
    const admm_active *a = s->act;
    return s->family == ADMM_FAM_ELEMENT && s->q == 3 && (s->p.energy == DF_ADMM_ARAP || s->p.energy == DF_ADMM_ACAP) &&
           a->gc && a->cap_gc >= a->nae;
}

static void lazy_resolve(const df_admm *s, lazy_it *x)
{
    if (!x->pend) return;
    x->el = admm_act_energy(s, fbuf(s->act, x->buf), NULL);
    x->E = x->el + x->lo;
    x->pend = 0;
}

/* 1 when the stop test can pass with these residuals (admm_stop_residual's second term below tol) */
static int conv_possible(const df_admm *s, double pri, double dual)
{
    const double sq_tol = sqrt(s->p.tol);
    double pd = sq_tol > 0 ? sq_tol * (pri > dual ? pri : dual) : 0.0;
    return !(pd >= s->p.tol);
}

/* elastic energy of Vout over the region's elements or cells; locality over the region */
static double act_elastic(const df_admm *s)
{
    const admm_active *a = s->act;
    const double *V = s->Vout;
    double E = 0;
    if (s->family == ADMM_FAM_ELEMENT) return admm_act_energy(s, NULL, V);
    #pragma omp parallel for schedule(static) num_threads(s->nthreads) reduction(+ : E) if (a->nae >= ACT_PAR_HEAVY)
    for (int32_t k = 0; k < a->nae; k++) E += admm_vertex_energy(s, V, a->ae[k]);
    return E;
}

static double act_locality(const df_admm *s)
{
    const admm_active *a = s->act;
    if (s->p.w == 0.0) return 0.0;
    double L = 0;
    for (int32_t k = 0; k < a->nr; k++) {
        int32_t i = a->rv[k];
        double d[3];
        for (int c = 0; c < 3; c++) d[c] = s->Vout[3 * (size_t)i + c] - s->Vrest[3 * (size_t)i + c];
        L += s->a[i] * df_admm_scl1_value(d, s->p.s);
    }
    return s->p.w * L;
}

static double ratio(double num2, double den2)
{
    if (num2 == 0.0) return 0.0;
    if (!(den2 > 0.0)) return INFINITY;
    return sqrt(num2 / den2);
}

/* relative primal and dual residuals (admm.h DF_ADMM_RESIDUAL); the outside adds gam_e |I|^2 per
 * element to |A x|^2 and |z|^2 (R_e X_e = F_e = I there) and nothing else */
static void act_measure(const df_admm *s, const act_acc *acc, double *pri, double *dual)
{
    const admm_active *a = s->act;
    double far = s->family == ADMM_FAM_ELEMENT ? a->gam3_all - a->gam3_ae : 0.0;
    if (far < 0) far = 0;
    double ax2 = acc->ax2 + far, z2 = acc->z2 + far;
    *pri = ratio(acc->r2, ax2 > z2 ? ax2 : z2);
    *dual = ratio(acc->s2, acc->y2);
}

/* the features the active mode does not cover (admm.h DF_ADMM_ACTIVE) */
static int unsupported(const df_admm *s)
{
    return s->naff > 0 || s->p.accelerate || s->bl_ptr || s->p.energy == DF_ADMM_CLOTH ||
           (s->family == ADMM_FAM_ELEMENT && s->q != 3) || s->deg.followers > 0 || s->deg.at_rest > 0;
}

int admm_active_defers(const df_admm *s) { return s->p.active && !unsupported(s); }

/* the whole-mesh system for a full run (deferred by df_admm_create in active mode) */
static int full_system(df_admm *s, df_error *err)
{
    if (s->L) return DF_OK;
    return admm_build_system_affine(s, s->aff, s->naff, err);
}

static int too_big(const df_admm *s) { return s->act->nr > DF_ADMM_ACTIVE_MAX_FRAC * (double)s->nv; }

/* the rest of the call by the full solve (a region too large to pay off) */
static int finish_full(df_admm *s, const df_admm_budget *budget, double tstart, df_admm_result *r, df_error *err)
{
    admm_active *a = s->act;
    admm_active_stale(s);
    a->st.fallbacks++;
    int rc = full_system(s, err);
    if (rc) return rc;
    admm_update_kfhp(s);
    a->kfhp_dirty = 0;
    df_admm_budget b;
    memset(&b, 0, sizeof(b));
    if (budget) b = *budget;
    int maxit = budget && budget->max_iters > 0 ? budget->max_iters : s->p.max_iters;
    b.max_iters = maxit - r->iterations;
    if (b.max_iters <= 0) return DF_OK;
    if (b.max_ms > 0) {
        b.max_ms -= (admm_now() - tstart) * 1e3;
        if (b.max_ms <= 0) { r->stop = DF_ADMM_STOP_TIME; return DF_OK; }
    }
    df_admm_result r2;
    a->bypass = 1;
    rc = df_admm_run(s, &b, &r2, err);
    a->bypass = 0;
    if (rc) return rc;
    r->iterations += r2.iterations;
    r->objective = r2.objective; r->elastic = r2.elastic; r->locality = r2.locality;
    r->residual = r2.residual; r->converged = r2.converged; r->stop = r2.stop;
    r->t_local1 += r2.t_local1; r->t_local2 += r2.t_local2; r->t_global += r2.t_global; r->t_other += r2.t_other;
    return DF_OK;
}

/* grows the region by the support in act->sup (+ failing fringe vertices) and by the n_tail
 * vertices the tail test put after them; 1 when it got too big */
static int grow(df_admm *s, int by_check, int32_t n_tail, df_error *err, int *rc)
{
    admm_active *a = s->act;
    a->st.grows++;
    a->hs_ok = 0;
    if (by_check) a->st.check_grows++;
    if (n_tail > 0) a->st.tail_grows++;
    *rc = admm_act_build(s, 0, a->sup + a->nsup, n_tail, err);
    if (s->family == ADMM_FAM_ELEMENT) gc_reserve(a); /* ae changed */
    return !*rc && too_big(s);
}

int admm_active_run(df_admm *s, const df_admm_budget *budget, df_admm_result *res, int *handled, df_error *err)
{
    *handled = 0;
    if (s->act && s->act->bypass) return DF_OK;
    if (!s->act && !(s->act = calloc(1, sizeof(admm_active)))) { /* no memory: the full solve */
        int rc = full_system(s, err);
        *handled = rc != DF_OK;
        return rc;
    }
    admm_active *a = s->act;
    if (unsupported(s)) {
        a->st.fallbacks++;
        admm_active_stale(s);
        if (a->kfhp_dirty) { admm_update_kfhp(s); a->kfhp_dirty = 0; }
        return DF_OK;
    }
    *handled = 1;
    df_admm_result r;
    memset(&r, 0, sizeof(r));
    r.residual = INFINITY;
    r.stop = DF_ADMM_STOP_ITERS;
    r.rho = s->p.rho; /* the active-set iterations keep the penalty (no adaptive change) */
    double tstart = admm_now();
    int rc = admm_act_init(s, err);
    if (rc) return rc;
    a = s->act;
    int fresh_run = !a->valid;
    if (!a->valid) {
        admm_act_support(s, s->act_dirty, 0); /* pristine (at rest since create): the handles only */
        a->st.rebuilds++;
        rc = admm_act_build(s, 1, NULL, 0, err);
    } else {
        admm_act_support(s, 0, 0);
        if (admm_act_needs_grow(s)) { a->st.grows++; rc = admm_act_build(s, 0, NULL, 0, err); }
        else if ((int64_t)ACT_SHRINK * ((int64_t)admm_act_fresh_size(s) + a->tail_added) < a->nr) {
            /* the support shrank (a drag back): rebuild from it; the vertices leaving the region
             * go exactly to rest (they are off it by no more than the iterations' residual) */
            a->st.rebuilds++;
            fresh_run = 1;
            rc = admm_act_build(s, 1, NULL, 0, err);
        } else if (a->rho_fact != s->p.rho) rc = admm_act_build(s, 0, NULL, 0, err); /* rho changed: refactor */
    }
    if (rc) return rc;
    if (too_big(s)) {
        rc = finish_full(s, budget, tstart, &r, err);
        r.t_total = admm_now() - tstart;
        if (res) *res = r;
        return rc;
    }
    a->st.runs++;
    a->hs_ok = 0;
    if (s->family == ADMM_FAM_ELEMENT) gc_reserve(a);
    int maxit = budget && budget->max_iters > 0 ? budget->max_iters : s->p.max_iters;
    double max_ms = budget ? budget->max_ms : 0;
    int every = budget && budget->progress ? budget->progress_every : 0;
    double E_prev = s->E_last;
    if (!isfinite(E_prev)) {
        double el0 = act_elastic(s), lo0 = act_locality(s);
        E_prev = el0 + lo0;
        s->E_last = E_prev; s->el_last = el0; s->lo_last = lo0;
    }
    /* the tail test's probe (admm_active_tail.c; not with damped handle steps, whose applied
     * targets move during the iteration) */
    int probes = fresh_run && s->p.active_tail > 0 && !s->damp ? ACT_PROBES : 0;
    if (probes && (rc = admm_act_probe_save(s, err))) return rc;
    /* the last iteration (cur) and the one before (prv), for the lazy energy; res_done: the stop
     * residual and s->E_last are those of cur */
    lazy_it cur = {0, 0, s->el_last, s->lo_last, E_prev}, prv = cur;
    int res_done = 1;
    double pri = INFINITY, dual = INFINITY;
    double t_loop = admm_now(), t_it = t_loop, last_ms = 0.0;
    int certified = 0, fell_back = 0;
    for (int it = 0; it < maxit; it++) {
        if (it > 0 && max_ms > 0) {
            double tn = admm_now(), el_ms = (tn - tstart) * 1e3;
            double mean_ms = (tn - t_loop) * 1e3 / it, est = mean_ms > last_ms ? mean_ms : last_ms;
            if (el_ms + est * ADMM_BUDGET_MARGIN > max_ms) { r.stop = DF_ADMM_STOP_TIME; break; }
        }
        act_acc acc = {0, 0, 0, 0, 0};
        double t_x, t_z, t_rhs;
        act_local(s, &acc, &t_x, &t_z, &t_rhs);
        double t2 = admm_now();
        rc = act_global(s, err);
        if (rc) break;
        int lz = lazy_ok(s), buf = cur.buf ^ 1; /* cur's F stays in its buffer */
        double ef = act_dual(s, &acc, buf, lz);
        double t3 = admm_now();
        r.t_local1 += t_x; r.t_local2 += t_z; r.t_global += t_rhs + t3 - t2;
        act_measure(s, &acc, &pri, &dual);
        int hold = s->damp && !isfinite(ef) && isfinite(s->E_last) && isfinite(s->el_last);
        if (!hold)
            for (int32_t k = 0; k < a->nr; k++)
                memcpy(s->Vout + 3 * (size_t)a->rv[k], s->V + 3 * (size_t)a->rv[k], 3 * sizeof(double));
        double ta = admm_now();
        prv = cur;
        cur.pend = lz;
        cur.buf = buf;
        cur.el = hold ? s->el_last : lz ? NAN : s->family == ADMM_FAM_ELEMENT ? ef : act_elastic(s);
        cur.lo = hold ? s->lo_last : act_locality(s);
        cur.E = hold ? s->E_last : cur.el + cur.lo;
        r.iterations++;
        s->st.iterations++;
        int report = every > 0 && (r.iterations % every == 0 || it == maxit - 1);
        res_done = 0;
        int conv = 0;
        if (!lz || report || it == maxit - 1 || conv_possible(s, pri, dual)) {
            lazy_resolve(s, &prv);
            lazy_resolve(s, &cur);
            r.elastic = cur.el; r.locality = cur.lo; r.objective = cur.E;
            r.residual = admm_stop_residual(s, hold, cur.E, prv.E, pri, dual);
            s->E_last = cur.E; s->el_last = cur.el; s->lo_last = cur.lo;
            res_done = 1;
            conv = r.residual < s->p.tol;
        }
        E_prev = cur.E;
        /* region: grow when the support nears the edge; certify the far field periodically and
         * before reporting convergence */
        admm_act_support(s, 0, 1);
        int need = admm_act_needs_grow(s), by_check = 0;
        int32_t nt = 0;
        certified = 0;
        if (!need && (conv || r.iterations % a->check_every == 0)) {
            int32_t nf = admm_act_certify(s);
            if (nf > 0) { a->nsup += nf; need = by_check = 1; }
            else certified = 1;
        }
        if (!need && !conv && s->p.active_tail > 0) { /* tail test (admm.h): every iteration */
            /* E >= lo: an edge charge within tol lo is within tol E (lazy_it) */
            if (!cur.pend || !(cur.lo > 0) || admm_act_tail(s, cur.lo, s->p.active_tail) > 0) {
                lazy_resolve(s, &cur);
                nt = admm_act_tail(s, cur.E, s->p.active_tail);
            }
            need = nt > 0;
        }
        if (need) {
            conv = 0;
            lazy_resolve(s, &prv); /* their F buffers follow ae, which the growth changes */
            lazy_resolve(s, &cur);
            if (grow(s, by_check, nt, err, &rc)) { fell_back = 1; break; }
            if (rc) break;
            if (it == 0 && probes > 0) { /* the probe: start again on the grown region */
                probes--;
                a->st.tail_probes++;
                admm_act_probe_restore(s);
                a->hs_ok = 0;
                E_prev = s->E_last;
                /* the lazy energy and residuals start again from the restored state (the growth
                 * already invalidated the F buffers: gc_ok 0) */
                cur = (lazy_it){0, 0, s->el_last, s->lo_last, E_prev};
                prv = cur;
                res_done = 1;
                pri = dual = INFINITY;
                r.iterations = 0;
                r.t_other += admm_now() - ta;
                t_it = admm_now();
                it = -1;
                continue;
            }
        }
        r.t_other += admm_now() - ta;
        double t_end = admm_now();
        last_ms = (t_end - t_it) * 1e3;
        t_it = t_end;
        if (every > 0 && (report || conv)) {
            df_admm_progress pr = {r.iterations, cur.E, r.residual, s->Vout, s->nv};
            if (budget->progress(budget->user, &pr)) { r.stop = DF_ADMM_STOP_CALLBACK; break; }
        }
        if (conv) { r.converged = 1; r.stop = DF_ADMM_STOP_CONVERGED; break; }
    }
    if (!res_done) { /* the last iteration's objective and stop residual (lazy energy) */
        lazy_resolve(s, &prv);
        lazy_resolve(s, &cur);
        r.elastic = cur.el; r.locality = cur.lo; r.objective = cur.E;
        r.residual = admm_stop_residual(s, 0, cur.E, prv.E, pri, dual);
        s->E_last = cur.E; s->el_last = cur.el; s->lo_last = cur.lo;
        E_prev = cur.E;
    }
    if (!rc && fell_back) rc = finish_full(s, budget, tstart, &r, err);
    else if (!rc && !certified && r.iterations > 0) {
        /* certify the reported state; a failure grows the region for the next run */
        admm_act_support(s, 0, 0);
        int32_t nf = admm_act_certify(s);
        if (nf > 0 || admm_act_needs_grow(s)) {
            a->nsup += nf;
            (void)grow(s, nf > 0, 0, err, &rc); /* too big: the next run falls back at its start */
        }
    }
    if (r.iterations == 0 && rc == DF_OK) {
        r.objective = E_prev;
        r.elastic = s->el_last;
        r.locality = s->lo_last;
    }
    if (s->act) a->st.support = a->nsup;
    r.t_total = admm_now() - tstart;
    if (res) *res = r;
    return rc;
}
