/* admm_local.c — the per-iteration kernels of the three-block ADMM: local step 1 (per-element
 * X_e with the polar rotation, or per-vertex rotations), local step 2 (SC-L1 prox on Z), the global
 * right-hand side (gathered per vertex, no atomics) and the dual updates. OpenMP over elements and
 * vertices. */
#include <math.h>
#include <string.h>

#include "core/admm/admm_internal.h"
#include "core/admm/nh_prox.h"
#include "core/admm/nh_spectral.h"
#include "core/admm/scl1.h"
#include "core/admm/svd3.h"

/* relative deviatoric size |S - tr S / 3 I| / (tr S / 3) below which the Neo-Hookean local step
 * uses the isotropic expansion instead of an eigen-decomposition */
#define ADMM_NH_ISO_REL 1e-8
/* elements per work item of the 4-lane tet kernels (admm_tet4.c) */
#define TET4_CHUNK 256

/* per-element right-hand side contributions C_{e,a} = gam_e (R_e X_e - W_e) g_{e,a}, gathered per
 * vertex by admm_assemble_rhs (element-ordered writes, no atomics) */
static inline void element_contrib(df_admm *s, int32_t e, const double *RX, const double *W)
{
    double P[9];
    for (int k = 0; k < 9; k++) P[k] = s->gam[e] * (RX[k] - W[k]);
    const double *g = s->grad + (size_t)e * s->esz * 3;
    double *C = s->Ce + (size_t)e * s->esz * 3;
    if (s->esz == 4 && s->q == 3) { /* tets: the same sums with constant bounds (unrolled) */
        for (int a = 0; a < 4; a++)
            for (int r = 0; r < 3; r++) {
                double acc = 0;
                for (int c = 0; c < 3; c++) acc += P[3 * r + c] * g[3 * a + c];
                C[3 * a + r] = acc;
            }
        return;
    }
    for (int a = 0; a < s->esz; a++)
        for (int r = 0; r < 3; r++) {
            double acc = 0;
            for (int c = 0; c < s->q; c++) acc += P[3 * r + c] * g[3 * a + c];
            C[3 * a + r] = acc;
        }
}

static void local_x_element_G(df_admm *s, int32_t e, double G[9]);

static void local_x_element_one(df_admm *s, int32_t e)
{
    double G[9];
    const double *W = s->W + 9 * (size_t)e;
    admm_element_F(s, s->V, e, G);
    for (int k = 0; k < 9; k++) G[k] += W[k];
    local_x_element_G(s, e, G);
}

/* ARAP / ACAP tets: the 4-lane kernels of admm_tet4.c (the same bits as the per-element code) */
static int tet4(const df_admm *s)
{
    return s->esz == 4 && s->q == 3 && (s->p.energy == DF_ADMM_ARAP || s->p.energy == DF_ADMM_ACAP);
}

/* local step 1 of elements e0 .. e0 + n (n <= TET4_CHUNK) by admm_local_tet4 */
static void local_x_tet4(df_admm *s, int32_t e0, int32_t n)
{
    int32_t idx[TET4_CHUNK] = {0};
    double fb[9 * TET4_CHUNK], s2 = 0, z2 = 0;
    for (int32_t k = 0; k < n; k++) {
        idx[k] = e0 + k;
        admm_element_F(s, s->V, e0 + k, fb + 9 * (size_t)k);
    }
    admm_local_tet4(s, idx, fb, n, &s2, &z2); /* the residual sums are not needed here */
}

static void local_x_element(df_admm *s)
{
    if (tet4(s)) {
        #pragma omp parallel for schedule(dynamic, 1) num_threads(s->nthreads)
        for (int32_t e = 0; e < s->ne; e += TET4_CHUNK) local_x_tet4(s, e, s->ne - e < TET4_CHUNK ? s->ne - e : TET4_CHUNK);
        return;
    }
    /* dynamic chunks: inverted / badly conditioned elements take the slower SVD path */
    #pragma omp parallel for schedule(dynamic, 1024) num_threads(s->nthreads)
    for (int32_t e = 0; e < s->ne; e++) {
        local_x_element_one(s, e);
        element_contrib(s, e, s->RX + 9 * (size_t)e, s->W + 9 * (size_t)e);
    }
}

void admm_local_x_one(df_admm *s, int32_t e)
{
    local_x_element_one(s, e);
    element_contrib(s, e, s->RX + 9 * (size_t)e, s->W + 9 * (size_t)e);
}

void admm_local_x_one_G(df_admm *s, int32_t e, double G[9])
{
    local_x_element_G(s, e, G);
    element_contrib(s, e, s->RX + 9 * (size_t)e, s->W + 9 * (size_t)e);
}

/* local step 1 of element e from G = F_e(V) + W_e (G is scratch afterwards) */
static void local_x_element_G(df_admm *s, int32_t e, double G[9])
{
    const df_admm_energy en = s->p.energy;
    {
        double *RX = s->RX + 9 * (size_t)e;
        double vol = s->vol[e], gam = s->gam[e];
        if (s->q == 2) {
            double Fc[6] = {G[0], G[1], G[3], G[4], G[6], G[7]}, U[6], sg[2], Vm[4];
            df_admm_svd32(Fc, U, sg, Vm);
            for (int i = 0; i < 2; i++) {
                double x = (vol + gam * sg[i]) / (vol + gam);
                sg[i] = x < s->p.strain_min ? s->p.strain_min : x > s->p.strain_max ? s->p.strain_max : x;
            }
            memset(RX, 0, 9 * sizeof(double));
            for (int r = 0; r < 3; r++)
                for (int c = 0; c < 2; c++)
                    RX[3 * r + c] = U[2 * r] * sg[0] * Vm[2 * c] + U[2 * r + 1] * sg[1] * Vm[2 * c + 1];
            return;
        }
        if (en != DF_ADMM_NEOHOOKEAN) {
            /* ARAP: R X = (vol R + gam G) / (vol + gam); ACAP: R X = (1 - f) (tr S / 3) R + f G,
             * f = gam / (vol + gam); only the polar rotation R and tr S are needed */
            double R[9], tS;
            if (df_admm_polar3(G, R) == 0) {
                tS = 0;
                for (int r = 0; r < 3; r++)
                    for (int c = 0; c < 3; c++) tS += R[3 * r + c] * G[3 * r + c];
            } else {
                double U[9], sg[3], Vm[9];
                df_admm_svd3(G, U, sg, Vm);
                for (int r = 0; r < 3; r++)
                    for (int c = 0; c < 3; c++)
                        R[3 * r + c] = U[3 * r] * Vm[3 * c] + U[3 * r + 1] * Vm[3 * c + 1] + U[3 * r + 2] * Vm[3 * c + 2];
                tS = sg[0] + sg[1] + sg[2];
            }
            double f = gam / (vol + gam);
            double cr = en == DF_ADMM_ARAP ? 1.0 - f : (1.0 - f) * tS / 3.0;
            for (int k = 0; k < 9; k++) RX[k] = cr * R[k] + f * G[k];
            return;
        }
        /* Neo-Hookean: X = Q diag(prox(eig S)) Q^T with S = R^T G. Well-conditioned G: closed-form
         * polar R and an eigen-decomposition of S warm-started from the element's previous
         * eigenvectors (1-2 Jacobi sweeps), Newton warm-started from the previous singular values;
         * otherwise (inverted or nearly singular G) the full signed SVD. */
        double *Q = s->nhQ + 9 * (size_t)e, *xp = s->nhx + 3 * (size_t)e;
        double R[9], x[3];
        if (df_admm_polar3(G, R) == 0) {
            double S[9];
            for (int i = 0; i < 3; i++)
                for (int j = 0; j < 3; j++)
                    S[3 * i + j] = R[i] * G[j] + R[3 + i] * G[3 + j] + R[6 + i] * G[6 + j];
            double m = (S[0] + S[4] + S[8]) / 3.0, dn = 0;
            for (int i = 0; i < 3; i++)
                for (int j = 0; j < 3; j++) {
                    double d = 0.5 * (S[3 * i + j] + S[3 * j + i]) - (i == j ? m : 0.0);
                    dn += d * d;
                }
            if (m > 0 && dn <= ADMM_NH_ISO_REL * ADMM_NH_ISO_REL * m * m) {
                /* nearly isotropic S = m I + D (the bulk far from the handles): the prox is an
                 * isotropic matrix function, so X = x(m) I + a D + O(|D|^2) with x(m) the prox at
                 * (m, m, m) and a = gam / (vol alpha + gam) its derivative along deviatoric
                 * directions (alpha = mu + mu / x^2 - lambda ln J / x^2, J = x^3); the neglected
                 * term is ~1e-16 relative at ADMM_NH_ISO_REL = 1e-8 */
                double sm[3] = {m, m, m};
                if (df_admm_nh_prox(sm, xp, vol, s->mu, s->lambda, gam, x) < 0) { x[0] = x[1] = x[2] = m; }
                double xm = (x[0] + x[1] + x[2]) / 3.0, x2 = xm * xm;
                double alpha = s->mu + s->mu / x2 - s->lambda * log(x2 * xm) / x2;
                double a = gam / (vol * alpha + gam);
                double X[9];
                for (int i = 0; i < 3; i++)
                    for (int j = 0; j < 3; j++)
                        X[3 * i + j] = a * (0.5 * (S[3 * i + j] + S[3 * j + i]) - (i == j ? m : 0.0)) + (i == j ? xm : 0.0);
                for (int r = 0; r < 3; r++)
                    for (int c = 0; c < 3; c++)
                        RX[3 * r + c] = R[3 * r] * X[c] + R[3 * r + 1] * X[3 + c] + R[3 * r + 2] * X[6 + c];
                xp[0] = xp[1] = xp[2] = xm;
                return;
            }
            /* warm-started Jacobi to DF_ADMM_NH_SPECTRAL_OFF plus the first-order correction */
            double X[9];
            if (df_admm_nh_prox_sym(S, Q, xp, vol, s->mu, s->lambda, gam, X) < 0) {
                memcpy(RX, R, sizeof(R)); /* invalid input cannot happen for finite G; identity X */
                return;
            }
            for (int r = 0; r < 3; r++)
                for (int c = 0; c < 3; c++)
                    RX[3 * r + c] = R[3 * r] * X[c] + R[3 * r + 1] * X[3 + c] + R[3 * r + 2] * X[6 + c];
            return;
        }
        double U[9], sg[3], Vm[9];
        df_admm_svd3(G, U, sg, Vm);
        if (df_admm_nh_prox(sg, NULL, vol, s->mu, s->lambda, gam, x) < 0) { x[0] = x[1] = x[2] = 1.0; }
        memcpy(Q, Vm, sizeof(Vm));
        memcpy(xp, x, sizeof(x));
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++)
                RX[3 * r + c] = U[3 * r] * x[0] * Vm[3 * c] + U[3 * r + 1] * x[1] * Vm[3 * c + 1] +
                                U[3 * r + 2] * x[2] * Vm[3 * c + 2];
    }
}

void admm_fit_vertex(const df_admm *s, const double *V, int32_t i, double SR[9])
{
    double M[9] = {0}, den = 0;
    for (int32_t t = s->sr_ptr[i]; t < s->sr_ptr[i + 1]; t++) {
        const double *xa = V + 3 * (size_t)s->sr_a[t], *xb = V + 3 * (size_t)s->sr_b[t];
        const double *dr = s->sr_d + 3 * (size_t)t;
        double w = s->sr_w[t], d[3] = {xb[0] - xa[0], xb[1] - xa[1], xb[2] - xa[2]};
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++) M[3 * r + c] += w * d[r] * dr[c];
        den += w * (dr[0] * dr[0] + dr[1] * dr[1] + dr[2] * dr[2]);
    }
    double tr;
    memset(SR, 0, 9 * sizeof(double));
    if (s->planar) {
        double a = M[0] + M[4], b = M[3] - M[1], n = sqrt(a * a + b * b);
        double c = n > 0 ? a / n : 1.0, sn = n > 0 ? b / n : 0.0;
        SR[0] = c; SR[1] = -sn; SR[3] = sn; SR[4] = c; SR[8] = 1.0;
        tr = n;
    } else {
        double U[9], sg[3], Vm[9];
        df_admm_svd3(M, U, sg, Vm);
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++)
                SR[3 * r + c] = U[3 * r] * Vm[3 * c] + U[3 * r + 1] * Vm[3 * c + 1] + U[3 * r + 2] * Vm[3 * c + 2];
        tr = sg[0] + sg[1] + sg[2];
    }
    if (s->p.energy == DF_ADMM_ACAP && den > 0) {
        double sc = tr / den;
        for (int k = 0; k < 9; k++) SR[k] *= sc;
    }
}

void admm_local_x(df_admm *s)
{
    if (s->family == ADMM_FAM_ELEMENT) {
        local_x_element(s);
        return;
    }
    #pragma omp parallel for schedule(static) num_threads(s->nthreads)
    for (int32_t i = 0; i < s->nv; i++) admm_fit_vertex(s, s->V, i, s->Rv + 9 * (size_t)i);
}

void admm_local_z(df_admm *s)
{
    const double w = s->p.w, sth = s->p.s, rho = s->p.rho;
    /* serial: ~20 flops per vertex, cheaper than an OpenMP fork/join on a shared machine */
    for (int32_t i = 0; i < s->nv; i++) {
        double x[3];
        for (int k = 0; k < 3; k++) x[k] = s->V[3 * (size_t)i + k] - s->Vrest[3 * (size_t)i + k] + s->U[3 * (size_t)i + k];
        df_admm_scl1_prox(x, w * s->a[i], sth, rho, s->Z + 3 * (size_t)i);
    }
}

void admm_rhs_row(const df_admm *s, const int32_t *verts, int32_t nf, const double *sub, double *rhs, int32_t f)
{
    const double rho = s->p.rho;
    int32_t v = verts[f];
    double b[3] = {0, 0, 0};
    if (s->family == ADMM_FAM_ELEMENT) {
        for (int32_t p = s->ve_ptr[v]; p < s->ve_ptr[v + 1]; p++) {
            const double *C = s->Ce + 3 * (size_t)s->ve_ent[p];
            b[0] += C[0]; b[1] += C[1]; b[2] += C[2];
        }
    } else {
        for (int32_t p = s->in_ptr[v]; p < s->in_ptr[v + 1]; p++) {
            int32_t se = s->in_ent[p];
            int32_t t = (se > 0 ? se : -se) - 1;
            double sign = se > 0 ? 1.0 : -1.0;
            const double *R = s->Rv + 9 * (size_t)s->sr_own[t], *dr = s->sr_d + 3 * (size_t)t;
            double w = sign * s->sr_w[t];
            for (int r = 0; r < 3; r++) b[r] += w * (R[3 * r] * dr[0] + R[3 * r + 1] * dr[1] + R[3 * r + 2] * dr[2]);
        }
    }
    for (int k = 0; k < 3; k++) {
        size_t o = 3 * (size_t)v + k;
        rhs[f + (size_t)k * nf] = b[k] + rho * (s->Vrest[o] + s->Z[o] - s->U[o]) - sub[f + (size_t)k * nf];
    }
}

void admm_rhs_rows(const df_admm *s, const int32_t *verts, int32_t nf, const double *sub, double *rhs,
                   int par)
{
    (void)par; /* read only by the OpenMP pragma (unused in serial builds: make tsan) */
    #pragma omp parallel for schedule(static) num_threads(s->nthreads) if (par)
    for (int32_t f = 0; f < nf; f++) admm_rhs_row(s, verts, nf, sub, rhs, f);
}

void admm_assemble_rhs(df_admm *s) { admm_rhs_rows(s, s->fvert, s->nfree, s->KfhP, s->rhs->x, 1); }

/* the dual update and energies of elements e0 .. e0 + n (n <= TET4_CHUNK) by admm_dual_tet4 (W
 * as below, the same bits); returns their energy summed in element order */
static double dual_tet4(df_admm *s, int32_t e0, int32_t n)
{
    int32_t idx[TET4_CHUNK] = {0};
    double fb[9 * TET4_CHUNK], t[4 * TET4_CHUNK], E = 0;
    for (int32_t k = 0; k < n; k++) idx[k] = e0 + k;
    admm_dual_tet4(s, idx, fb, n, 0, t);
    for (int32_t k = 0; k < n; k++) E += t[4 * k + 3];
    return E;
}

double admm_dual_update(df_admm *s)
{
    double E = 0;
    if (s->family == ADMM_FAM_ELEMENT && tet4(s)) {
        #pragma omp parallel for schedule(static) num_threads(s->nthreads) reduction(+ : E)
        for (int32_t e = 0; e < s->ne; e += TET4_CHUNK) E += dual_tet4(s, e, s->ne - e < TET4_CHUNK ? s->ne - e : TET4_CHUNK);
    } else if (s->family == ADMM_FAM_ELEMENT) {
        #pragma omp parallel for schedule(static) num_threads(s->nthreads) reduction(+ : E)
        for (int32_t e = 0; e < s->ne; e++) {
            double F[9];
            admm_element_F(s, s->V, e, F);
            double *W = s->W + 9 * (size_t)e;
            const double *RX = s->RX + 9 * (size_t)e;
            for (int k = 0; k < 9; k++) W[k] += F[k] - RX[k];
            E += admm_element_energy_F(s, e, F);
        }
    }
    for (int64_t o = 0; o < 3 * (int64_t)s->nv; o++) s->U[o] += s->V[o] - s->Vrest[o] - s->Z[o];
    return E;
}
