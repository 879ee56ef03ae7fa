/* admm_active_tail.c — the tail test of the active-set mode (admm.h DF_ADMM_ACTIVE, "Tail test"):
 * the SC-L1 charge of the region's edge, the rings each charged edge vertex needs (from the
 * charge's decay between depths 1 and 2), the growth lists; and the probe: a run that starts on a
 * freshly built region keeps a copy of the region's state (vertex rows of V, U, Z, Vout; element
 * rows of W and R X) and its objective; when its first iteration grows the region,
 * admm_active_run.c puts that state back (admm_act_probe_restore) and starts the run again on the
 * grown region, as if the region had been that large from the start. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/admm/admm_active.h"

/* The tail test's ring prediction. Near the region's edge the charge profile is that of a field
 * pinned at rest one ring further out, so its per-vertex decay between depths 2 and 1 (q) is
 * steeper than the free field's: measured on bench_local's 100k grid, each one-ring growth cut
 * the edge's summed charge by q^0.49 .. q^0.77 (q ~ 9); a vertex whose charge is c > share gets
 * ceil(log(c / share) / (ACT_TAIL_DECAY_EXP log q)) rings, at most ACT_TAIL_MAX_RINGS. */
#define ACT_TAIL_DECAY_EXP 0.7
#define ACT_TAIL_MAX_RINGS 8

/* SC-L1 slope charge w a_i |Vout_i - Vrest_i| of vertex i */
static double charge(const df_admm *s, int32_t i)
{
    const double *x = s->Vout + 3 * (size_t)i, *r = s->Vrest + 3 * (size_t)i;
    double d0 = x[0] - r[0], d1 = x[1] - r[1], d2 = x[2] - r[2];
    return s->p.w * s->a[i] * sqrt(d0 * d0 + d1 * d1 + d2 * d2);
}

int32_t admm_act_tail(df_admm *s, double E, double tol)
{
    admm_active *a = s->act;
    if (s->p.w == 0.0 || a->nedge == 0 || !(fabs(E) > 0)) return 0;
    double sum = 0, share = tol * fabs(E) / a->nedge;
    for (int32_t k = 0; k < a->nedge; k++) sum += charge(s, a->edge[k]);
    if (!(sum > tol * fabs(E))) return 0;
    double s2 = 0, lq = 0;
    int32_t n2 = 0;
    for (int32_t k = 0; k < a->nr; k++)
        if (a->depth[a->rv[k]] == 2) { s2 += charge(s, a->rv[k]); n2++; }
    if (n2 > 0 && sum > 0) {
        double q = (s2 / n2) / (sum / a->nedge);
        if (q > 1.0) lq = ACT_TAIL_DECAY_EXP * log(q);
    }
    /* seeds: the charged edge vertices with their ring budgets; then breadth first over the
     * outside, highest budget first, each vertex taking the largest budget that reaches it */
    uint32_t g = admm_act_stamp(a, a->stamp, (size_t)s->nv);
    int32_t nl = 0, n = 0, *lst = a->work;
    for (int32_t k = 0; k < a->nedge; k++) {
        int32_t i = a->edge[k];
        double c = charge(s, i);
        if (!(c > share)) continue;
        int m = 1;
        if (lq > 0) {
            double r = ceil(log(c / share) / lq);
            m = r < 1 ? 1 : r > ACT_TAIL_MAX_RINGS ? ACT_TAIL_MAX_RINGS : (int)r;
        }
        a->stamp[i] = g;
        a->tbud[i] = m;
        lst[nl++] = i;
    }
    for (int L = ACT_TAIL_MAX_RINGS; L >= 1; L--)
        for (int32_t k = 0; k < nl; k++) {
            int32_t v = lst[k];
            if (a->tbud[v] != L) continue;
            for (int32_t p = a->adj_ptr[v]; p < a->adj_ptr[v + 1]; p++) {
                int32_t u = a->adj[p];
                if (a->in[u] || a->stamp[u] == g) continue;
                a->stamp[u] = g;
                a->tbud[u] = L - 1;
                lst[nl++] = u;
                a->sup[a->nsup + n++] = u;
            }
        }
    return n;
}

void admm_act_probe_free(admm_active *a)
{
    free(a->pr_rv); free(a->pr_v); free(a->pr_ae); free(a->pr_e); free(a->pr_mark);
    a->pr_rv = a->pr_ae = NULL;
    a->pr_v = a->pr_e = NULL;
    a->pr_mark = NULL;
    a->pr_nr = a->pr_nae = 0;
    a->pr_cap_v = a->pr_cap_e = 0;
}

int admm_act_probe_save(df_admm *s, df_error *err)
{
    admm_active *a = s->act;
    int elem = s->family == ADMM_FAM_ELEMENT;
    if (a->nr > a->pr_cap_v) {
        free(a->pr_rv); free(a->pr_v);
        a->pr_rv = malloc((size_t)a->nr * sizeof(int32_t));
        a->pr_v = malloc((size_t)a->nr * 12 * sizeof(double));
        a->pr_cap_v = a->pr_rv && a->pr_v ? a->nr : 0;
        if (!a->pr_cap_v) return df_error_set(err, DF_ENOMEM, "admm_run: out of memory (tail probe)");
    }
    if (elem && a->nae > a->pr_cap_e) {
        free(a->pr_ae); free(a->pr_e);
        a->pr_ae = malloc((size_t)a->nae * sizeof(int32_t));
        a->pr_e = malloc((size_t)a->nae * 18 * sizeof(double));
        a->pr_cap_e = a->pr_ae && a->pr_e ? a->nae : 0;
        if (!a->pr_cap_e) return df_error_set(err, DF_ENOMEM, "admm_run: out of memory (tail probe)");
    }
    if (elem && !a->pr_mark && !(a->pr_mark = calloc((size_t)s->ne, 1)))
        return df_error_set(err, DF_ENOMEM, "admm_run: out of memory (tail probe)");
    a->pr_nr = a->nr;
    memcpy(a->pr_rv, a->rv, (size_t)a->nr * sizeof(int32_t));
    for (int32_t k = 0; k < a->nr; k++) {
        size_t o = 3 * (size_t)a->rv[k];
        double *d = a->pr_v + 12 * (size_t)k;
        memcpy(d, s->V + o, 3 * sizeof(double));
        memcpy(d + 3, s->U + o, 3 * sizeof(double));
        memcpy(d + 6, s->Z + o, 3 * sizeof(double));
        memcpy(d + 9, s->Vout + o, 3 * sizeof(double));
    }
    a->pr_nae = elem ? a->nae : 0;
    for (int32_t k = 0; k < a->pr_nae; k++) {
        int32_t e = a->ae[k];
        a->pr_ae[k] = e;
        memcpy(a->pr_e + 18 * (size_t)k, s->W + 9 * (size_t)e, 9 * sizeof(double));
        memcpy(a->pr_e + 18 * (size_t)k + 9, s->RX + 9 * (size_t)e, 9 * sizeof(double));
    }
    a->pr_E = s->E_last; a->pr_el = s->el_last; a->pr_lo = s->lo_last;
    return DF_OK;
}

void admm_act_probe_restore(df_admm *s)
{
    admm_active *a = s->act;
    for (int32_t k = 0; k < a->pr_nr; k++) {
        size_t o = 3 * (size_t)a->pr_rv[k];
        const double *d = a->pr_v + 12 * (size_t)k;
        memcpy(s->V + o, d, 3 * sizeof(double));
        memcpy(s->U + o, d + 3, 3 * sizeof(double));
        memcpy(s->Z + o, d + 6, 3 * sizeof(double));
        memcpy(s->Vout + o, d + 9, 3 * sizeof(double));
    }
    if (s->family == ADMM_FAM_ELEMENT) {
        for (int32_t k = 0; k < a->pr_nae; k++) {
            int32_t e = a->pr_ae[k];
            memcpy(s->W + 9 * (size_t)e, a->pr_e + 18 * (size_t)k, 9 * sizeof(double));
            memcpy(s->RX + 9 * (size_t)e, a->pr_e + 18 * (size_t)k + 9, 9 * sizeof(double));
            a->pr_mark[e] = 1;
        }
        /* elements that entered with the growth: their local step from the restored positions,
         * as a region built that large at the start would have given them (W = 0: they had no
         * vertex in the region) */
        for (int32_t k = 0; k < a->nae; k++)
            if (!a->pr_mark[a->ae[k]]) admm_local_x_one(s, a->ae[k]);
        for (int32_t k = 0; k < a->pr_nae; k++) a->pr_mark[a->pr_ae[k]] = 0;
    }
    s->E_last = a->pr_E; s->el_last = a->pr_el; s->lo_last = a->pr_lo;
}
