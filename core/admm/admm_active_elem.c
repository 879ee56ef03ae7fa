/* admm_active_elem.c — the element loops of the active-set iterations (admm_active_run.c) that
 * end in sums: the dual update of the region's elements (W, the residual sums, F_e(V) kept for the
 * next local step and the lazy energy) and the elastic energy of the region's elements from F
 * buffers or from positions. Threads (admm_active.h ACT_PAR_*): from ACT_PAR_LIGHT elements an
 * OpenMP reduction (as since the active mode's start); from ACT_PAR_HEAVY elements up to that, the
 * items in parallel with each element's terms stored in a partial-sum buffer (act->gc's tail) and
 * summed afterwards on the calling thread in element order, so every sum is bit-identical to one
 * thread's (the serial loop below ACT_PAR_HEAVY). Tets with an F buffer: the dual update four
 * elements at a time (admm_tet4.c; the same terms bit for bit, summed in the same order). */
#include <string.h>

#include "core/admm/admm_active.h"

/* 1 when the ordered parallel path applies: a team, a region between the thresholds, the
 * partial-sum buffer (nparts doubles per element) present */
static double *parts(const df_admm *s)
{
    const admm_active *a = s->act;
    if (s->nthreads < 2 || a->nae < ACT_PAR_HEAVY || a->nae >= ACT_PAR_LIGHT || !a->gc || a->cap_gc < a->nae) return NULL;
    return a->gc + (size_t)18 * (size_t)a->cap_gc;
}

/* element k of ae: W += F - R X; its residual terms gam |dW|^2, gam |F|^2, gam |W|^2 into t[0..2],
 * its energy (unless lazy) into t[3]; F into fb row k when fb */
static void dual_one(df_admm *s, int32_t k, double *fb, int lazy, double t[4])
{
    const admm_active *a = s->act;
    int32_t e = a->ae[k];
    double F[9], er = 0, ea = 0, ey = 0;
    admm_element_F(s, s->V, e, F);
    double *W = s->W + 9 * (size_t)e;
    const double *RX = s->RX + 9 * (size_t)e;
    for (int c = 0; c < 9; c++) {
        double dw = F[c] - RX[c];
        W[c] += dw;
        er += dw * dw; ea += F[c] * F[c]; ey += W[c] * W[c]; /* R X + dW = F */
    }
    t[0] = s->gam[e] * er; t[1] = s->gam[e] * ea; t[2] = s->gam[e] * ey;
    if (fb) memcpy(fb + 9 * (size_t)k, F, sizeof(F));
    t[3] = lazy ? 0.0 : admm_element_energy_F(s, e, F);
}

double admm_act_dual_elems(df_admm *s, double *fb, int lazy, double *r2o, double *ax2o, double *y2o)
{
    admm_active *a = s->act;
    double E = 0, r2 = 0, ax2 = 0, y2 = 0;
    double *pt = parts(s);
    const int tet4 = fb && s->esz == 4 && s->q == 3; /* admm_tet4.c: same bits, 4 at a time */
    if (pt) {
        if (tet4) {
            #pragma omp parallel for schedule(static) num_threads(s->nthreads)
            for (int32_t b = 0; b < a->nae; b += ACT_TET4_CHUNK)
                admm_dual_tet4(s, a->ae + b, fb + 9 * (size_t)b, a->nae - b < ACT_TET4_CHUNK ? a->nae - b : ACT_TET4_CHUNK, lazy,
                               pt + 4 * (size_t)b);
        } else {
            #pragma omp parallel for schedule(static) num_threads(s->nthreads)
            for (int32_t k = 0; k < a->nae; k++) dual_one(s, k, fb, lazy, pt + 4 * (size_t)k);
        }
        for (int32_t k = 0; k < a->nae; k++) {
            const double *t = pt + 4 * (size_t)k;
            r2 += t[0]; ax2 += t[1]; y2 += t[2];
            if (!lazy) E += t[3];
        }
    } else if (tet4) {
        #pragma omp parallel for schedule(static) num_threads(s->nthreads) reduction(+ : E, r2, ax2, y2) if (a->nae >= ACT_PAR_LIGHT)
        for (int32_t b = 0; b < a->nae; b += ACT_TET4_CHUNK) {
            double t[4 * ACT_TET4_CHUNK];
            int32_t m = a->nae - b < ACT_TET4_CHUNK ? a->nae - b : ACT_TET4_CHUNK;
            admm_dual_tet4(s, a->ae + b, fb + 9 * (size_t)b, m, lazy, t);
            for (int32_t k = 0; k < m; k++) {
                r2 += t[4 * k]; ax2 += t[4 * k + 1]; y2 += t[4 * k + 2];
                if (!lazy) E += t[4 * k + 3];
            }
        }
    } else {
        #pragma omp parallel for schedule(static) num_threads(s->nthreads) reduction(+ : E, r2, ax2, y2) if (a->nae >= ACT_PAR_LIGHT)
        for (int32_t k = 0; k < a->nae; k++) {
            double t[4];
            dual_one(s, k, fb, lazy, t);
            r2 += t[0]; ax2 += t[1]; y2 += t[2];
            if (!lazy) E += t[3];
        }
    }
    *r2o = r2; *ax2o = ax2; *y2o = y2;
    return E;
}

/* energy of element k of ae: from fb row k, or from F_e(V) */
static double energy_one(const df_admm *s, int32_t k, const double *fb, const double *V)
{
    int32_t e = s->act->ae[k];
    if (fb) return admm_element_energy_F(s, e, fb + 9 * (size_t)k);
    double F[9];
    admm_element_F(s, V, e, F);
    return admm_element_energy_F(s, e, F);
}

double admm_act_energy(const df_admm *s, const double *fb, const double *V)
{
    const admm_active *a = s->act;
    double E = 0;
    double *pt = parts(s);
    /* ARAP / ACAP tets from an F buffer: four at a time (admm_tet4.c, the same bits) */
    const int tet4 = fb && s->esz == 4 && s->q == 3 && (s->p.energy == DF_ADMM_ARAP || s->p.energy == DF_ADMM_ACAP);
    if (pt) {
        if (tet4) {
            #pragma omp parallel for schedule(static) num_threads(s->nthreads)
            for (int32_t b = 0; b < a->nae; b += ACT_TET4_CHUNK)
                admm_energy_tet4(s, a->ae + b, fb + 9 * (size_t)b, a->nae - b < ACT_TET4_CHUNK ? a->nae - b : ACT_TET4_CHUNK, pt + b);
        } else {
            #pragma omp parallel for schedule(static) num_threads(s->nthreads)
            for (int32_t k = 0; k < a->nae; k++) pt[k] = energy_one(s, k, fb, V);
        }
        for (int32_t k = 0; k < a->nae; k++) E += pt[k];
        return E;
    }
    if (tet4) {
        #pragma omp parallel for schedule(static) num_threads(s->nthreads) reduction(+ : E) if (a->nae >= ACT_PAR_LIGHT)
        for (int32_t b = 0; b < a->nae; b += ACT_TET4_CHUNK) {
            double t[ACT_TET4_CHUNK];
            int32_t m = a->nae - b < ACT_TET4_CHUNK ? a->nae - b : ACT_TET4_CHUNK;
            admm_energy_tet4(s, a->ae + b, fb + 9 * (size_t)b, m, t);
            for (int32_t k = 0; k < m; k++) E += t[k];
        }
        return E;
    }
    #pragma omp parallel for schedule(static) num_threads(s->nthreads) reduction(+ : E) if (a->nae >= ACT_PAR_LIGHT)
    for (int32_t k = 0; k < a->nae; k++) E += energy_one(s, k, fb, V);
    return E;
}
