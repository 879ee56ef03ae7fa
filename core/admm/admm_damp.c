/* admm_damp.c — the global step with damped handle steps for Neo-Hookean.
 *
 * When the handle targets jump (df_admm_set_targets during a drag, or the first run from rest), the
 * global step's V moves the handles at once while the screened response K^-1 (rho I + elasticity)
 * lags around them, and elements next to the handles invert: the Neo-Hookean energy of that
 * iterate is +inf, and with only one or two iterations per interactive update the reported shape
 * stays inverted. The global solution is affine in the applied targets p,
 *     V(t) = V_a + t delta,   V_a = K^-1 (b - K_fh p_applied),  delta = -K^-1 K_fh (p_req - p_applied),
 * so one extra solve gives the whole segment: the step takes the largest t in {1, 1/2, ..., 2^-7}
 * for which no element of V(t) is inverted and applies p_applied + t (p_req - p_applied). When even
 * the smallest t inverts an element but V_a does not, the handles hold still (t = 0) for at most
 * ADMM_DAMP_MAX_STALL iterations, after which the smallest step is taken anyway. When V_a itself
 * is inverted, damping cannot help and t = 1. Other energies (finite for any V) take t = 1 always. */
#include <math.h>
#include <string.h>

#include "core/admm/admm_internal.h"

#define ADMM_DAMP_MAX_STALL 2     /* iterations the handles may hold still before a forced step */

double admm_damp_choose(df_admm *s, double t_min, int va_bad)
{
    if (!va_bad && s->damp_stall < ADMM_DAMP_MAX_STALL) {
        s->damp_stall++;
        return 0.0;
    }
    s->damp_stall = 0;
    return va_bad ? 1.0 : t_min;
}

void admm_damp_apply(df_admm *s, double t)
{
    if (t == 1.0) {
        memcpy(s->target, s->target_req, (size_t)s->nh * 3 * sizeof(double));
        s->tgt_pending = 0;
    } else {
        for (int64_t i = 0; i < 3 * (int64_t)s->nh; i++) s->target[i] += t * s->damp_dp[i];
    }
}

/* 1 when some element of V has det F_e <= 0. Every thread stops scanning once any thread has
 * found one (a shared flag; the same answer): a trial step that inverts elements, the common case
 * while a damped step is searched (the pig teaser tries ~6 per damped iteration), then costs a
 * fraction of a pass (teaser, 2 threads: the trials 5.4 -> 2.7 ms per damped iteration, the run at
 * rho 1.25 w/s 4.43 -> 4.19 s CPU, the same iterates). */
static int any_inverted(const df_admm *s, const double *V)
{
    int bad = 0;
    #pragma omp parallel for schedule(static) num_threads(s->nthreads) shared(bad)
    for (int32_t e = 0; e < s->ne; e++) {
        int seen;
#ifdef _OPENMP /* (builds without OpenMP, e.g. make tsan's -fopenmp-simd, warn on these) */
        #pragma omp atomic read
#endif
        seen = bad;
        if (seen) continue;
        double F[9];
        admm_element_F(s, V, e, F); /* Neo-Hookean: tets, q = 3 */
        if (!(admm_det3(F) > 0)) {
#ifdef _OPENMP
            #pragma omp atomic write
#endif
            bad = 1;
        }
    }
    return bad;
}

/* V = V_a + t delta on the free vertices, handles at target + t dp */
static void place(df_admm *s, const double *x, double t)
{
    int32_t nf = s->nfree;
    for (int32_t f = 0; f < nf; f++) {
        double *v = s->V + 3 * (size_t)s->fvert[f];
        const double *va = s->damp_va + 3 * (size_t)s->fvert[f];
        for (int k = 0; k < 3; k++) v[k] = va[k] + t * x[f + (size_t)k * nf];
    }
    for (int32_t h = 0; h < s->nh; h++)
        for (int k = 0; k < 3; k++)
            s->V[3 * (size_t)s->hidx[h] + k] = s->target[3 * (size_t)h + k] + t * s->damp_dp[3 * (size_t)h + k];
}

int admm_global_step(df_admm *s, df_error *err)
{
    if (!s->damp || !s->tgt_pending) return admm_global_solve(s, err);
    int rc = admm_global_solve(s, err);
    if (rc) return rc;
    int32_t nf = s->nfree;
    memcpy(s->damp_va, s->V, (size_t)s->nv * 3 * sizeof(double));
    for (int64_t i = 0; i < 3 * (int64_t)s->nh; i++) s->damp_dp[i] = s->target_req[i] - s->target[i];
    /* delta = -K^-1 K_fh dp (affine rows homogeneous) */
    double *rhs = s->rhs->x;
    memset(rhs, 0, (size_t)nf * 3 * sizeof(double));
    for (int64_t t = 0; t < s->ncpl; t++) {
        const double *d = s->damp_dp + 3 * (size_t)s->cpl_h[t];
        for (int k = 0; k < 3; k++) rhs[s->cpl_f[t] + (size_t)k * nf] -= s->cpl_v[t] * d[k];
    }
    const double *x;
    rc = admm_solve_rhs(s, 0, &x, err);
    if (rc) { memcpy(s->V, s->damp_va, (size_t)s->nv * 3 * sizeof(double)); return rc; }
    double t = 1.0;
    int found = 0;
    for (int k = 0; k <= ADMM_DAMP_HALVINGS; k++, t *= 0.5) {
        place(s, x, t);
        if (!any_inverted(s, s->V)) { found = 1; break; }
    }
    if (!found) {
        t = admm_damp_choose(s, t * 2.0, any_inverted(s, s->damp_va)); /* the smallest trial step */
        place(s, x, t);
    } else {
        s->damp_stall = 0;
    }
    admm_damp_apply(s, t);
    admm_update_kfhp(s);
    return DF_OK;
}
