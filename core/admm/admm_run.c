/* admm_run.c — the ADMM iteration loop (Alg. 1): local step 1, local step 2, global step, dual
 * updates, objective, the scale-invariant stop test (relative energy change and relative primal and
 * dual residuals, admm.h), budgets, progress callback and the optional Anderson acceleration. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "core/admm/admm_internal.h"
#include "core/admm/admm_resid.h"

/* safety factor on the predicted cost of the next iteration when a time budget is set */
#define ADMM_BUDGET_MARGIN 1.05

double admm_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* one plain ADMM iteration on the state; accumulates phase times. *el_fused receives the elastic
 * energy of the new V computed during the dual update (element family), NAN otherwise. */
static int iterate(df_admm *s, df_admm_result *r, double *el_fused, df_error *err)
{
    double t0 = admm_now();
    admm_local_x(s);
    double t1 = admm_now();
    admm_local_z(s);
    double t2 = admm_now();
    admm_assemble_rhs(s);
    int rc = admm_global_step(s, err);
    if (rc) return rc;
    double ef = admm_dual_update(s);
    *el_fused = s->family == ADMM_FAM_ELEMENT ? ef : NAN;
    double t3 = admm_now();
    r->t_local1 += t1 - t0;
    r->t_local2 += t2 - t1;
    r->t_global += t3 - t2;
    return DF_OK;
}

int df_admm_run(df_admm *s, const df_admm_budget *budget, df_admm_result *res, df_error *err)
{
    if (!s) return df_error_set(err, DF_EINVAL, "admm_run: NULL solver");
    if (s->broken) return df_error_set(err, DF_EINTERNAL, "admm_run: the solver lost its affine system in a failed refactorization (out of memory); recreate it");
    if (s->p.active) { /* active-set mode (admm_active_run.c); 0 handled: full solve below */
        int handled = 0, arc = admm_active_run(s, budget, res, &handled, err);
        if (handled) return arc;
    }
    df_admm_result r;
    memset(&r, 0, sizeof(r));
    r.residual = INFINITY;
    double tstart = admm_now();
    int maxit = budget && budget->max_iters > 0 ? budget->max_iters : s->p.max_iters;
    double max_ms = budget ? budget->max_ms : 0;
    int every = budget && budget->progress ? budget->progress_every : 0;
    double *x_before = NULL;
    if (s->p.accelerate) {
        x_before = malloc((size_t)s->n_state * sizeof(double));
        if (!x_before) return df_error_set(err, DF_ENOMEM, "admm_run: out of memory");
    }
    admm_resid rs;
    if (admm_resid_init(&rs, s, err)) { free(x_before); return DF_ENOMEM; }
    /* primal and dual residuals must fall below sqrt(tol) (relative): near the optimum the
     * objective error is quadratic in them, so this matches the energy test's |dE| < tol |E| */
    double E_prev = s->E_last;
    if (!isfinite(E_prev)) {
        double el0 = admm_elastic(s, s->Vout), lo0 = admm_locality(s, s->Vout);
        E_prev = el0 + lo0;
        s->E_last = E_prev;
        s->el_last = el0;
        s->lo_last = lo0;
    }
    int rc = DF_OK;
    r.stop = DF_ADMM_STOP_ITERS;
    double t_loop = admm_now(), t_it = t_loop, last_ms = 0.0;
    for (int it = 0; it < maxit; it++) {
        if (it > 0 && max_ms > 0) {
            /* predictive stop: start the next iteration only if it ends within the budget at the
             * larger of the mean iteration cost of this run and the last iteration's cost (a slow
             * iteration on a loaded machine raises the estimate at once) */
            double tn = admm_now(), el_ms = (tn - tstart) * 1e3;
            double mean_ms = (tn - t_loop) * 1e3 / it, est = mean_ms > last_ms ? mean_ms : last_ms;
            if (el_ms + est * ADMM_BUDGET_MARGIN > max_ms) { r.stop = DF_ADMM_STOP_TIME; break; }
        }
        if (x_before) memcpy(x_before, s->state, (size_t)s->n_state * sizeof(double));
        double el_fused;
        admm_resid_snapshot(&rs, s);
        rc = iterate(s, &r, &el_fused, err);
        if (rc) break;
        double pri, dual;
        admm_resid_measure(&rs, s, &pri, &dual);
        /* Neo-Hookean: an inverted iterate (infinite energy) is not reported while the positions
         * reported so far are feasible; the ADMM state continues from it all the same */
        int hold = s->damp && !isfinite(el_fused) && isfinite(s->E_last) && isfinite(s->el_last);
        if (!hold) {
            memcpy(s->Vout, s->V, (size_t)s->nv * 3 * sizeof(double));
            admm_place_followers(s, s->Vout); /* vertices of degenerate elements only */
        }
        double ta = admm_now();
        if (x_before) r.anderson_accepted += admm_aa_step(&s->aa, x_before, s->state) && s->aa.pending;
        /* element family: the energy of Vout (= V before any Anderson extrapolation) came with the
         * dual update's F_e; only the bending part remains */
        double el, lo;
        if (hold) {
            el = s->el_last;
            lo = s->lo_last;
        } else {
            el = s->family == ADMM_FAM_ELEMENT ? el_fused + admm_bending(s, s->Vout) : admm_elastic(s, s->Vout);
            lo = admm_locality(s, s->Vout);
        }
        double E = hold ? s->E_last : el + lo;
        r.t_other += admm_now() - ta;
        r.iterations++;
        s->st.iterations++;
        double t_end = admm_now();
        last_ms = (t_end - t_it) * 1e3;
        t_it = t_end;
        r.elastic = el;
        r.locality = lo;
        r.objective = E;
        r.residual = admm_stop_residual(s, hold, E, E_prev, pri, dual);
        E_prev = E;
        s->E_last = E;
        s->el_last = el;
        s->lo_last = lo;
        int conv = r.residual < s->p.tol;
        if (every > 0 && (r.iterations % every == 0 || conv || it == maxit - 1)) {
            df_admm_progress pr = {r.iterations, E, r.residual, s->Vout, s->nv};
            if (budget->progress(budget->user, &pr)) { r.stop = DF_ADMM_STOP_CALLBACK; break; }
        }
        if (conv) { r.converged = 1; r.stop = DF_ADMM_STOP_CONVERGED; break; }
        if (s->rho_adaptive && it < maxit - 1) { /* adaptive penalty (admm_rho.c) */
            double tr = admm_now();
            int changed = 0;
            rc = admm_rho_adapt(s, &rs, hold, r.residual, &changed, err);
            if (rc) break;
            if (changed) { r.rho_changes++; r.t_refactor += admm_now() - tr; }
        }
    }
    free(x_before);
    admm_resid_free(&rs);
    if (r.iterations == 0 && rc == DF_OK) {
        r.objective = E_prev;
        r.elastic = admm_elastic(s, s->Vout);
        r.locality = admm_locality(s, s->Vout);
    }
    r.rho = s->p.rho;
    r.t_total = admm_now() - tstart;
    if (res) *res = r;
    return rc;
}
