/* admm_run.c — the ADMM iteration loop (Alg. 1): local step 1, local step 2, global step, dual
 * updates, objective and residual |E_k - E_k-1| / (E_k + 1), budgets, progress callback and the
 * optional Anderson acceleration. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "core/admm/admm_internal.h"

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
    int rc = admm_global_solve(s, err);
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
    double E_prev = s->E_last;
    if (!isfinite(E_prev)) E_prev = admm_elastic(s, s->Vout) + admm_locality(s, s->Vout);
    int rc = DF_OK;
    r.stop = DF_ADMM_STOP_ITERS;
    for (int it = 0; it < maxit; it++) {
        if (it > 0 && max_ms > 0) {
            /* stop when the next iteration (at the average cost so far) would overrun the budget */
            double el_ms = (admm_now() - tstart) * 1e3;
            if (el_ms + el_ms / it > max_ms) { r.stop = DF_ADMM_STOP_TIME; break; }
        }
        if (x_before) memcpy(x_before, s->state, (size_t)s->n_state * sizeof(double));
        double el_fused;
        rc = iterate(s, &r, &el_fused, err);
        if (rc) break;
        memcpy(s->Vout, s->V, (size_t)s->nv * 3 * sizeof(double));
        double ta = admm_now();
        if (x_before) r.anderson_accepted += admm_aa_step(&s->aa, x_before, s->state) && s->aa.pending;
        /* element family: the energy of Vout (= V before any Anderson extrapolation) came with the
         * dual update's F_e; only the bending part remains */
        double el = s->family == ADMM_FAM_ELEMENT ? el_fused + admm_bending(s, s->Vout) : admm_elastic(s, s->Vout);
        double lo = admm_locality(s, s->Vout);
        double E = el + lo;
        r.t_other += admm_now() - ta;
        r.iterations++;
        s->st.iterations++;
        r.elastic = el;
        r.locality = lo;
        r.objective = E;
        r.residual = (isfinite(E) && isfinite(E_prev)) ? fabs(E - E_prev) / (E + 1.0) : INFINITY;
        E_prev = E;
        s->E_last = E;
        int conv = r.residual < s->p.tol;
        if (every > 0 && (r.iterations % every == 0 || conv || it == maxit - 1)) {
            df_admm_progress pr = {r.iterations, E, r.residual, s->Vout, s->nv};
            if (budget->progress(budget->user, &pr)) { r.stop = DF_ADMM_STOP_CALLBACK; break; }
        }
        if (conv) { r.converged = 1; r.stop = DF_ADMM_STOP_CONVERGED; break; }
    }
    free(x_before);
    if (r.iterations == 0 && rc == DF_OK) {
        r.objective = E_prev;
        r.elastic = admm_elastic(s, s->Vout);
        r.locality = admm_locality(s, s->Vout);
    }
    r.t_total = admm_now() - tstart;
    if (res) *res = r;
    return rc;
}
