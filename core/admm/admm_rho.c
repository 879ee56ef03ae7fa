/* admm_rho.c — the adaptive ADMM penalty (admm.h, DF_ADMM_RHO_RULE): the initial rho from the
 * problem's scales, the refactorization-cost gap between two changes, and relative residual
 * balancing of the Z = V - Vrest block and of the element block (Boyd et al. 2011 sec. 3.4.1 with
 * the scale-invariant relative residuals of Wohlberg 2017) with the scaled duals U, W rescaled at
 * each change; the element penalties start at DF_ADMM_GAMMA_INIT (energies finite everywhere, on
 * trial) or DF_ADMM_GAMMA_INIT_NH (Neo-Hookean); lowered element penalties go back to 1 for good
 * when they produce inverted
 * (Neo-Hookean) iterates, fail their trial (too little progress) or stall. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/admm/admm_internal.h"
#include "core/admm/admm_resid.h"

/* median of x[0..n-1] (reorders x); 0 for n = 0 */
static double median(double *x, int32_t n)
{
    if (n <= 0) return 0.0;
    int32_t k = n / 2, lo = 0, hi = n - 1;
    while (lo < hi) { /* quickselect */
        double piv = x[(lo + hi) / 2];
        int32_t i = lo, j = hi;
        while (i <= j) {
            while (x[i] < piv) i++;
            while (x[j] > piv) j--;
            if (i <= j) { double t = x[i]; x[i] = x[j]; x[j] = t; i++; j--; }
        }
        if (k <= j) hi = j;
        else if (k >= i) lo = i;
        else break;
    }
    return x[k];
}

/* the elastic stiffness scale: the median over vertices with an energy term of the diagonal of
 * the elastic part of the global matrix (sum_e gamma_e |g_e,a|^2, or the spokes-and-rims weights
 * at the vertex); 0 when there is none */
static double elastic_scale(const df_admm *s)
{
    double *d = malloc((size_t)s->nv * sizeof(double));
    if (!d) return 0.0;
    int32_t n = 0;
    for (int32_t v = 0; v < s->nv; v++) {
        double k = 0.0;
        if (s->family == ADMM_FAM_ELEMENT) {
            for (int32_t p = s->ve_ptr[v]; p < s->ve_ptr[v + 1]; p++) {
                int32_t ent = s->ve_ent[p], e = ent / s->esz;
                const double *g = s->grad + 3 * (size_t)ent;
                double g2 = 0;
                for (int c = 0; c < s->q; c++) g2 += g[c] * g[c];
                k += s->gam[e] * g2;
            }
        } else {
            for (int32_t p = s->in_ptr[v]; p < s->in_ptr[v + 1]; p++) {
                int32_t se = s->in_ent[p], t = (se > 0 ? se : -se) - 1;
                k += s->sr_w[t];
            }
        }
        if (k > 0 && isfinite(k)) d[n++] = k;
    }
    double m = median(d, n);
    free(d);
    return m;
}

void admm_rho_init(df_admm *s)
{
    s->rho_req = s->p.rho;
    s->gscale = 1.0;
    s->rho_adaptive = !(s->p.rho > 0);
    if (!s->rho_adaptive) return;
    double conv = s->p.w * s->max_a / s->p.s; /* the SC-L1 prox is convex for rho > conv */
    double kel = elastic_scale(s);
    double rho0 = conv > 0 ? DF_ADMM_RHO_INIT_LOC * conv : DF_ADMM_RHO_INIT_EL * kel;
    if (!(rho0 > 0) || !isfinite(rho0)) rho0 = 1.0; /* w = 0 and no elastic term: any rho works */
    s->p.rho = rho0;
    s->rho_floor = conv > 0 ? DF_ADMM_RHO_FLOOR * conv : rho0 / DF_ADMM_RHO_RANGE;
    s->rho_ceil = rho0 * DF_ADMM_RHO_RANGE;
    s->win_prev = -1.0;
    s->held_run = 0;
    s->gam_locked = 0;
    s->g_trial = 0;
    s->best_since_change = INFINITY;
    /* the element penalties' start (admm.h DF_ADMM_RHO_RULE): energies finite for every V at
     * DF_ADMM_GAMMA_INIT (below 1: on trial like any lowering, its first window against
     * nothing), Neo-Hookean at DF_ADMM_GAMMA_INIT_NH */
    if (s->family == ADMM_FAM_ELEMENT) {
        double g0 = s->p.energy == DF_ADMM_NEOHOOKEAN ? DF_ADMM_GAMMA_INIT_NH : DF_ADMM_GAMMA_INIT;
        for (int32_t e = 0; e < s->ne; e++) s->gam[e] *= g0;
        s->gscale = g0;
        if (g0 < 1.0) {
            s->g_trial = DF_ADMM_GAMMA_TRIAL;
            s->g_trial_ref = INFINITY;
            s->g_trial_best = INFINITY;
        }
    }
}

void admm_rho_set_gap(df_admm *s)
{
    if (!s->rho_adaptive) return;
    /* one refactorization costs cc.fl flops; an iteration about 12 lnz (3 right-hand sides,
     * forward + back) plus its local steps: a change at most every
     * DF_ADMM_RHO_COST x (factorization / iteration) iterations, and at least DF_ADMM_RHO_MIN_GAP */
    double lnz = s->cc.lnz > 0 ? s->cc.lnz : (double)s->nfree;
    double local = s->family == ADMM_FAM_ELEMENT ? 500.0 * s->ne : 200.0 * (double)s->sr_ptr[s->nv];
    double it = 12.0 * lnz + local + 50.0 * s->nv;
    double g = ceil(DF_ADMM_RHO_COST * (s->cc.fl > 0 ? s->cc.fl : 0.0) / it);
    s->rho_gap = g > DF_ADMM_RHO_MIN_GAP ? (g < 1e6 ? (int)g : 1000000) : DF_ADMM_RHO_MIN_GAP;
    s->rho_wait = s->rho_gap;
}

/* the balancing factor for a block with relative residuals pri, dual: > 1 raises its penalty,
 * < 1 lowers it, 1 leaves it */
static double balance(double pri, double dual)
{
    if (!(pri >= 0) || !(dual >= 0) || !isfinite(pri) || !isfinite(dual) || (pri == 0 && dual == 0)) return 1.0;
    /* one residual exactly 0 and the other not: the largest imbalance there is (e.g. pri 1,
     * dual 0: the splitting variable has not moved at all while the constraint is violated) */
    if (dual == 0) return DF_ADMM_RHO_MAX_STEP;
    if (pri == 0) return 1.0 / DF_ADMM_RHO_MAX_STEP;
    double ratio = pri / dual;
    if (ratio > DF_ADMM_RHO_IMBALANCE) return fmin(sqrt(ratio), DF_ADMM_RHO_MAX_STEP);
    if (ratio * DF_ADMM_RHO_IMBALANCE < 1.0) return 1.0 / fmin(sqrt(1.0 / ratio), DF_ADMM_RHO_MAX_STEP);
    return 1.0;
}

/* stall watch: the best stop residual of each window of DF_ADMM_RHO_STALL_WINDOW iterations; 1
 * when a window ended no better than the one before (the iteration cycles instead of converging) */
static int stalled(df_admm *s, double resid)
{
    if (!(resid >= 0) || !isfinite(resid)) return 0;
    if (s->win_n == 0 || resid < s->win_best) s->win_best = resid;
    if (++s->win_n < DF_ADMM_RHO_STALL_WINDOW) return 0;
    /* residuals at round-off level (or below tol) are no stall: the run is converged */
    int st = s->win_prev >= 0 && s->win_best >= s->win_prev && s->win_best > DF_ADMM_RHO_STALL_MIN &&
             s->win_best >= s->p.tol;
    s->win_prev = s->win_best;
    s->win_n = 0;
    return st;
}

/* multiplies every gamma_e by fg (one numeric refactorization at the current rho) and rescales
 * the scaled element duals W so that the multipliers lambda = gamma W stay */
static int scale_gamma(df_admm *s, double fg, df_error *err)
{
    int rc = admm_system_refactor(s, s->p.rho, fg, err);
    if (rc) return rc;
    for (int64_t o = 0; o < 9 * (int64_t)s->ne; o++) s->W[o] /= fg;
    s->gscale *= fg;
    return DF_OK;
}

/* 1 when the element penalties may be balanced: while no lowering has been undone (gam_locked),
 * and for Neo-Hookean only with no damped handle step pending (the handles at their targets:
 * while they are on their way, iterates invert easily) */
static int gamma_free(const df_admm *s)
{
    return !s->gam_locked && (s->p.energy != DF_ADMM_NEOHOOKEAN || !s->tgt_pending);
}

int admm_rho_adapt(df_admm *s, const admm_resid *rs, int held, double resid, int *changed, df_error *err)
{
    *changed = 0;
    if (!s->rho_adaptive) return DF_OK;
    s->held_run = held ? s->held_run + 1 : 0;
    int trial_failed = 0;
    if (!held && isfinite(resid)) {
        if (resid < s->best_since_change) s->best_since_change = resid;
        if (s->g_trial > 0 && s->gscale < 1.0) {
            /* lowered element penalties stay on trial: each window of DF_ADMM_GAMMA_TRIAL
             * iterations must lower the best stop residual by DF_ADMM_GAMMA_GAIN against the window
             * before (the first: against the iterations before the lowering); else they cycle */
            if (resid < s->g_trial_best) s->g_trial_best = resid;
            if (--s->g_trial == 0) {
                if (!(s->g_trial_best * DF_ADMM_GAMMA_GAIN <= s->g_trial_ref) && s->g_trial_best >= s->p.tol)
                    trial_failed = 1;
                s->g_trial = DF_ADMM_GAMMA_TRIAL;
                s->g_trial_ref = s->g_trial_best;
                s->g_trial_best = INFINITY;
            }
        }
    }
    if (s->gscale < 1.0 && (s->held_run >= DF_ADMM_GAMMA_HELD || trial_failed)) {
        /* inverted iterates after the element penalties were lowered (Neo-Hookean: only it
         * holds iterates), or a failed trial: back to g = 1 at once, no gap, and no element
         * balancing again */
        int rc = scale_gamma(s, 1.0 / s->gscale, err);
        if (rc) return rc;
        s->gscale = 1.0;
        s->gam_locked = 1;
        s->held_run = 0;
        goto done;
    }
    int stall = !held && stalled(s, resid);
    if (stall) s->stall_pending = 1;
    if (s->rho_wait > 0) { s->rho_wait--; return DF_OK; }
    double rho = s->p.rho, fr = 1.0, fg = 1.0;
    if (s->stall_pending && s->gscale < 1.0) {
        /* cycling with lowered element penalties (a Neo-Hookean bar moved twice the unit tests'
         * move cycled at g = 0.25 while the stall watch doubled rho 14 times, 1.3% above the
         * reference after 6000 iterations): back to g = 1 for good, rho kept */
        fg = 1.0 / s->gscale;
        s->gam_locked = 1;
        s->stall_pending = 0;
        s->win_prev = -1.0;
        s->win_n = 0;
    } else if (s->stall_pending) {
        /* no progress over a whole window: a stiffer Z block, and the floor follows (the balancing
         * would otherwise lower it again) */
        fr = DF_ADMM_RHO_STALL_STEP;
        double f = rho * fr < s->rho_ceil ? rho * fr : s->rho_ceil;
        if (f > s->rho_floor) s->rho_floor = f;
        s->stall_pending = 0;
        s->win_prev = -1.0; /* the next window starts a fresh comparison */
        s->win_n = 0;
    } else if (!held) { /* an inverted (held) Neo-Hookean iterate's residuals say nothing about balance */
        fr = balance(rs->pri_z, rs->dual_z);
        /* element penalties; Neo-Hookean only once its handles are at their targets (with
         * g = 0.25 from the start the pig teaser never reached them); a lowering can still
         * invert iterates (the pig teaser, lowered at its 100th iteration, stayed inverted at
         * g = 0.25 without the held rule above) */
        if (s->family == ADMM_FAM_ELEMENT && gamma_free(s)) {
            fg = balance(rs->pri_e, rs->dual_e);
            if (fg > DF_ADMM_GAMMA_MAX_STEP) fg = DF_ADMM_GAMMA_MAX_STEP;
            if (fg < 1.0 / DF_ADMM_GAMMA_MAX_STEP) fg = 1.0 / DF_ADMM_GAMMA_MAX_STEP;
            double g = s->gscale * fg;
            if (g < DF_ADMM_GAMMA_MIN) fg = DF_ADMM_GAMMA_MIN / s->gscale;
            if (g > DF_ADMM_GAMMA_MAX) fg = DF_ADMM_GAMMA_MAX / s->gscale;
            if (fabs(fg - 1.0) < 1e-12) fg = 1.0;
        }
    }
    double rho_new = rho * fr;
    if (rho_new < s->rho_floor) rho_new = s->rho_floor;
    if (rho_new > s->rho_ceil) rho_new = s->rho_ceil;
    if (!(rho_new > s->p.w * s->max_a / s->p.s) || !isfinite(rho_new)) rho_new = rho;
    if (rho_new == rho && fg == 1.0) return DF_OK;
    int rc = admm_system_refactor(s, rho_new, fg, err);
    if (rc) return rc;
    /* scaled duals: U = y / rho and W = lambda / gamma keep the unscaled multipliers */
    double f = rho / rho_new;
    if (f != 1.0)
        for (int64_t o = 0; o < 3 * (int64_t)s->nv; o++) s->U[o] *= f;
    if (fg != 1.0) {
        for (int64_t o = 0; o < 9 * (int64_t)s->ne; o++) s->W[o] /= fg;
        s->gscale *= fg;
        if (fg < 1.0) { /* a lowering: on trial */
            s->g_trial = DF_ADMM_GAMMA_TRIAL;
            s->g_trial_ref = s->best_since_change;
            s->g_trial_best = INFINITY;
        }
    }
done:
    s->best_since_change = INFINITY;
    if (s->p.accelerate) admm_aa_reset(&s->aa);
    s->st.rho_changes++;
    s->rho_wait = s->rho_gap;
    *changed = 1;
    return DF_OK;
}
