/* admm_anderson.c — Anderson acceleration of the ADMM fixed-point map (type II, Walker & Ni 2011)
 * with the safeguard of Zhang et al. 2019: an extrapolated state is kept only if the fixed-point
 * residual |G(x) - x| it produces is not larger than the last accepted one; otherwise the solver
 * reverts to the plain ADMM iterate and restarts the history. */
#include <lapacke.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/admm/admm_internal.h"

int admm_aa_init(admm_anderson *aa, int m, int64_t n)
{
    memset(aa, 0, sizeof(*aa));
    aa->m = m;
    aa->n = n;
    aa->dF = malloc((size_t)m * n * sizeof(double));
    aa->dG = malloc((size_t)m * n * sizeof(double));
    aa->f_prev = malloc((size_t)n * sizeof(double));
    aa->g_prev = malloc((size_t)n * sizeof(double));
    aa->g_fallback = malloc((size_t)n * sizeof(double));
    aa->gram = calloc((size_t)m * m, sizeof(double));
    if (!aa->dF || !aa->dG || !aa->f_prev || !aa->g_prev || !aa->g_fallback || !aa->gram) {
        admm_aa_free(aa);
        return -1;
    }
    admm_aa_reset(aa);
    return 0;
}

void admm_aa_free(admm_anderson *aa)
{
    free(aa->dF); free(aa->dG); free(aa->f_prev); free(aa->g_prev); free(aa->g_fallback); free(aa->gram);
    memset(aa, 0, sizeof(*aa));
}

void admm_aa_reset(admm_anderson *aa)
{
    aa->count = 0;
    aa->head = 0;
    aa->have_prev = 0;
    aa->pending = 0;
    aa->r_prev = INFINITY;
}

static double dot(const double *a, const double *b, int64_t n, int nt)
{
    (void)nt; /* used only by the OpenMP clause */
    double s = 0;
    #pragma omp parallel for schedule(static) num_threads(nt) reduction(+ : s)
    for (int64_t i = 0; i < n; i++) s += a[i] * b[i];
    return s;
}

/* x_before: the state G was applied to; state: G(x_before) on entry, the next state on exit.
 * Returns 1 when the step was accepted (state extrapolated or plain), 0 when it was rejected
 * (state reverted to the last plain iterate). */
int admm_aa_step(admm_anderson *aa, const double *x_before, double *state)
{
    const int64_t n = aa->n;
    const int nt = aa->nthreads;
    double *f = malloc((size_t)n * sizeof(double));
    if (!f) { aa->pending = 0; return 1; } /* no memory: plain ADMM */
    #pragma omp parallel for schedule(static) num_threads(nt)
    for (int64_t i = 0; i < n; i++) f[i] = state[i] - x_before[i];
    double r = sqrt(dot(f, f, n, nt));
    if (aa->pending && !(r <= aa->r_prev)) {
        memcpy(state, aa->g_fallback, (size_t)n * sizeof(double));
        free(f);
        admm_aa_reset(aa);
        return 0;
    }
    aa->r_prev = r;
    if (aa->have_prev) {
        int slot = aa->head;
        double *df = aa->dF + (size_t)slot * n, *dg = aa->dG + (size_t)slot * n;
        #pragma omp parallel for schedule(static) num_threads(nt)
        for (int64_t i = 0; i < n; i++) { df[i] = f[i] - aa->f_prev[i]; dg[i] = state[i] - aa->g_prev[i]; }
        aa->head = (aa->head + 1) % aa->m;
        if (aa->count < aa->m) aa->count++;
        for (int j = 0; j < aa->count; j++) {
            double d = dot(df, aa->dF + (size_t)j * n, n, nt);
            aa->gram[slot * aa->m + j] = d;
            aa->gram[j * aa->m + slot] = d;
        }
    }
    memcpy(aa->f_prev, f, (size_t)n * sizeof(double));
    memcpy(aa->g_prev, state, (size_t)n * sizeof(double));
    memcpy(aa->g_fallback, state, (size_t)n * sizeof(double));
    aa->have_prev = 1;
    int k = aa->count;
    if (k == 0) { free(f); aa->pending = 0; return 1; }
    double A[DF_ADMM_MAX_ANDERSON * DF_ADMM_MAX_ANDERSON], b[DF_ADMM_MAX_ANDERSON];
    double trace = 0;
    for (int i = 0; i < k; i++) trace += aa->gram[i * aa->m + i];
    for (int i = 0; i < k; i++) {
        for (int j = 0; j < k; j++) A[i * k + j] = aa->gram[i * aa->m + j];
        A[i * k + i] += 1e-10 * trace / k + 1e-300;
        b[i] = dot(aa->dF + (size_t)i * n, f, n, nt);
    }
    free(f);
    if (LAPACKE_dposv(LAPACK_ROW_MAJOR, 'L', k, 1, A, k, b, 1) != 0) {
        admm_aa_reset(aa);
        return 1;
    }
    for (int j = 0; j < k; j++) {
        const double *dg = aa->dG + (size_t)j * n;
        double t = b[j];
        #pragma omp parallel for schedule(static) num_threads(nt)
        for (int64_t i = 0; i < n; i++) state[i] -= t * dg[i];
    }
    aa->pending = 1;
    return 1;
}
