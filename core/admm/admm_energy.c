/* admm_energy.c — the objective the solver reports: elastic energy (definitions in admm.h) and
 * the locality term sum_i w a_i ||V_i - Vrest_i||_SC-L1, both at arbitrary positions V. */
#include <math.h>
#include <string.h>

#include "core/admm/admm_internal.h"
#include "core/admm/nh_prox.h"
#include "core/admm/scl1.h"
#include "core/admm/svd3.h"

double admm_element_energy_F(const df_admm *s, int32_t e, const double F[9])
{
    double vol = s->vol[e];
    if (s->q == 2) {
        double Fc[6] = {F[0], F[1], F[3], F[4], F[6], F[7]}, sg[2];
        df_admm_svd32(Fc, NULL, sg, NULL);
        return 0.5 * vol * ((sg[0] - 1) * (sg[0] - 1) + (sg[1] - 1) * (sg[1] - 1));
    }
    if (s->p.energy == DF_ADMM_NEOHOOKEAN) {
        double J = admm_det3(F);
        if (!(J > 0)) return INFINITY;
        double I1 = 0;
        for (int k = 0; k < 9; k++) I1 += F[k] * F[k];
        double lJ = log(J);
        return vol * (0.5 * s->mu * (I1 - 3.0) - s->mu * lJ + 0.5 * s->lambda * lJ * lJ);
    }
    /* |S - I|^2 = |F|^2 - 2 tr S + 3 and |S - tr S / 3 I|^2 = |F|^2 - (tr S)^2 / 3 (signed tr S) */
    double I1 = 0;
    for (int k = 0; k < 9; k++) I1 += F[k] * F[k];
    double t = df_admm_trace_sym3(F);
    double d = s->p.energy == DF_ADMM_ACAP ? I1 - t * t / 3.0 : I1 - 2.0 * t + 3.0;
    return 0.5 * vol * (d > 0 ? d : 0.0);
}

void admm_rot_stress(const df_admm *s, const double F[9], double P[9])
{
    double R[9];
    if (df_admm_polar3(F, R) != 0) {
        double U[9], sg[3], Vm[9];
        df_admm_svd3(F, U, sg, Vm);
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++)
                R[3 * r + c] = U[3 * r] * Vm[3 * c] + U[3 * r + 1] * Vm[3 * c + 1] + U[3 * r + 2] * Vm[3 * c + 2];
    }
    double sc = 1.0;
    if (s->p.energy == DF_ADMM_ACAP) {
        double tS = 0;
        for (int k = 0; k < 9; k++) tS += R[k] * F[k];
        sc = tS / 3.0;
    }
    for (int k = 0; k < 9; k++) P[k] = F[k] - sc * R[k];
}

static double element_energy(const df_admm *s, const double *V, int32_t e)
{
    double F[9];
    admm_element_F(s, V, e, F);
    return admm_element_energy_F(s, e, F);
}

double admm_vertex_energy(const df_admm *s, const double *V, int32_t i)
{
    double R[9];
    admm_fit_vertex(s, V, i, R);
    double E = 0;
    for (int32_t t = s->sr_ptr[i]; t < s->sr_ptr[i + 1]; t++) {
        const double *xa = V + 3 * (size_t)s->sr_a[t], *xb = V + 3 * (size_t)s->sr_b[t];
        const double *dr = s->sr_d + 3 * (size_t)t;
        double r2 = 0;
        for (int r = 0; r < 3; r++) {
            double d = R[3 * r] * dr[0] + R[3 * r + 1] * dr[1] + R[3 * r + 2] * dr[2] - (xb[r] - xa[r]);
            r2 += d * d;
        }
        E += 0.5 * s->sr_w[t] * r2;
    }
    return E;
}

double admm_elastic(const df_admm *s, const double *V)
{
    double E = 0;
    if (s->family == ADMM_FAM_ELEMENT) {
        #pragma omp parallel for schedule(static) num_threads(s->nthreads) reduction(+ : E)
        for (int32_t e = 0; e < s->ne; e++) E += element_energy(s, V, e);
    } else {
        #pragma omp parallel for schedule(static) num_threads(s->nthreads) reduction(+ : E)
        for (int32_t i = 0; i < s->nv; i++) E += admm_vertex_energy(s, V, i);
    }
    return E + admm_bending(s, V);
}

double admm_bending(const df_admm *s, const double *V)
{
    double E = 0;
    if (s->bl_ptr) {
        double B = 0;
        #pragma omp parallel for schedule(static) num_threads(s->nthreads) reduction(+ : B)
        for (int32_t k = 0; k < s->nv; k++) {
            double y[3] = {0, 0, 0};
            for (int32_t p = s->bl_ptr[k]; p < s->bl_ptr[k + 1]; p++)
                for (int r = 0; r < 3; r++) y[r] += s->bl_val[p] * V[3 * (size_t)s->bl_idx[p] + r];
            B += y[0] * y[0] + y[1] * y[1] + y[2] * y[2];
        }
        E += 0.5 * s->p.bending * B;
    }
    return E;
}

double admm_locality(const df_admm *s, const double *V)
{
    if (s->p.w == 0.0) return 0.0;
    double L = 0;
    for (int32_t i = 0; i < s->nv; i++) {
        double d[3];
        for (int k = 0; k < 3; k++) d[k] = V[3 * (size_t)i + k] - s->Vrest[3 * (size_t)i + k];
        L += s->a[i] * df_admm_scl1_value(d, s->p.s);
    }
    return s->p.w * L;
}
