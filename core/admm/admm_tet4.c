/* admm_tet4.c — the element kernels of ARAP / ACAP tets (4-node tetrahedra), four elements at a
 * time in 4-lane vectors (gcc vector extensions): local step 1 (admm_local_tet4: the closed-form
 * polar rotation of svd3.c's df_admm_polar3, Newton on the trace root and Cayley-Hamilton, then
 * local_x_element_G's ARAP / ACAP update and element_contrib's right-hand side pieces, admm_local.c),
 * the dual update with F_e(V) (admm_dual_tet4, as admm_active_elem.c's dual_one; any energy), the
 * element energies from F rows (admm_energy_tet4, as admm_element_energy_F) and the certificate's
 * force norm (admm_force_tet4, as admm_active.c's force_norm).
 * Bits: every lane performs the scalar code's operations in the scalar code's order (no FMA
 * contraction: -ffp-contract=off; a lane's Newton loop stops where the scalar one would), so the
 * results are bit-identical to the per-element code; an element whose matrix fails the closed
 * form's conditions (not well conditioned, inverted) takes the scalar path and its SVD fallback,
 * and so do the fewer than four elements at a block's end (test_admm_tet4).
 * SIMD: target_clones as in core/kelvinlet/kelvinlet_apply.c (AVX-512, AVX2 and the portable
 * build, picked at load; -DDF_NO_TARGET_CLONES drops them). An 8-lane variant (two blocks'
 * dependency chains interleaved) measured no faster on this machine. */
#include <math.h>
#include <string.h>

#include "core/admm/admm_internal.h"

#ifdef DF_NO_TARGET_CLONES
#define TET4_CLONES
#else
#define TET4_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#endif

/* the helpers pass 4-lane vectors by value and are always inlined into block4's clones: the
 * portable build's ABI note for 32-byte vectors does not apply */
#pragma GCC diagnostic ignored "-Wpsabi"

typedef double v4d __attribute__((vector_size(32)));
typedef long long v4m __attribute__((vector_size(32)));

#define TRACE_MIN_DET_REL 0.05 /* as svd3.c */

static inline __attribute__((always_inline)) v4d blend(v4m m, v4d a, v4d b) /* m ? a : b per lane (m all ones or zero) */
{
    return (v4d)(((v4m)a & m) | ((v4m)b & ~m));
}

static inline __attribute__((always_inline)) int any(v4m m) { return (m[0] | m[1] | m[2] | m[3]) != 0; }

/* columns c0 .. c0 + 3 of the four rows r[l] (unaligned) as 4 lane vectors: load, 4 x 4 transpose
 * in registers (lane inserts through memory would stall on store forwarding);
 * __builtin_shufflevector: gcc >= 12 and clang (the fuzzers' compiler) both have it */
static inline __attribute__((always_inline)) void load4x4(const double *const r[4], int c0, v4d out[4])
{
    v4d a, b, c, d;
    memcpy(&a, r[0] + c0, sizeof a);
    memcpy(&b, r[1] + c0, sizeof b);
    memcpy(&c, r[2] + c0, sizeof c);
    memcpy(&d, r[3] + c0, sizeof d);
    v4d t0 = __builtin_shufflevector(a, b, 0, 4, 2, 6), t1 = __builtin_shufflevector(a, b, 1, 5, 3, 7);
    v4d t2 = __builtin_shufflevector(c, d, 0, 4, 2, 6), t3 = __builtin_shufflevector(c, d, 1, 5, 3, 7);
    out[0] = __builtin_shufflevector(t0, t2, 0, 1, 4, 5);
    out[1] = __builtin_shufflevector(t1, t3, 0, 1, 4, 5);
    out[2] = __builtin_shufflevector(t0, t2, 2, 3, 6, 7);
    out[3] = __builtin_shufflevector(t1, t3, 2, 3, 6, 7);
}

/* the inverse: lane vectors in[0..3] to columns c0 .. c0 + 3 of the rows r[l] */
static inline __attribute__((always_inline)) void store4x4(double *const r[4], int c0, const v4d in[4])
{
    v4d t0 = __builtin_shufflevector(in[0], in[1], 0, 4, 2, 6), t1 = __builtin_shufflevector(in[0], in[1], 1, 5, 3, 7);
    v4d t2 = __builtin_shufflevector(in[2], in[3], 0, 4, 2, 6), t3 = __builtin_shufflevector(in[2], in[3], 1, 5, 3, 7);
    v4d a = __builtin_shufflevector(t0, t2, 0, 1, 4, 5), b = __builtin_shufflevector(t1, t3, 0, 1, 4, 5);
    v4d c = __builtin_shufflevector(t0, t2, 2, 3, 6, 7), d = __builtin_shufflevector(t1, t3, 2, 3, 6, 7);
    memcpy(r[0] + c0, &a, sizeof a);
    memcpy(r[1] + c0, &b, sizeof b);
    memcpy(r[2] + c0, &c, sizeof c);
    memcpy(r[3] + c0, &d, sizeof d);
}

/* rows of 9 (n = 9) or 12 (n = 12) doubles as n lane vectors */
static inline __attribute__((always_inline)) void load_rows(const double *const r[4], int n, v4d *out)
{
    load4x4(r, 0, out);
    load4x4(r, 4, out + 4);
    if (n == 12) load4x4(r, 8, out + 8);
    else out[8] = (v4d){r[0][8], r[1][8], r[2][8], r[3][8]};
}

static inline __attribute__((always_inline)) void store_rows(double *const r[4], int n, const v4d *in)
{
    store4x4(r, 0, in);
    store4x4(r, 4, in + 4);
    if (n == 12) store4x4(r, 8, in + 8);
    else for (int l = 0; l < 4; l++) r[l][8] = in[8][l];
}

/* the lanes' trace root t of df_admm_trace_sym3 / svd3.c's trace_root (Newton from sqrt(3 I1),
 * the scalar loop's stop per lane), with C = A^T A packed, I1 and J; *ok: lanes where the
 * closed form applies (I1 > 0 and J >= TRACE_MIN_DET_REL (I1 / 3)^(3/2)) */
static inline __attribute__((always_inline)) void trace4(const v4d A[9], v4d C[6], v4d *I1o, v4d *Jo, v4d *to, v4m *ok)
{
    C[0] = A[0] * A[0] + A[3] * A[3] + A[6] * A[6];
    C[1] = A[0] * A[1] + A[3] * A[4] + A[6] * A[7];
    C[2] = A[0] * A[2] + A[3] * A[5] + A[6] * A[8];
    C[3] = A[1] * A[1] + A[4] * A[4] + A[7] * A[7];
    C[4] = A[1] * A[2] + A[4] * A[5] + A[7] * A[8];
    C[5] = A[2] * A[2] + A[5] * A[5] + A[8] * A[8];
    v4d I1 = C[0] + C[3] + C[5];
    v4d I2 = C[0] * C[3] + C[0] * C[5] + C[3] * C[5] - C[1] * C[1] - C[2] * C[2] - C[4] * C[4];
    v4d J = A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) +
            A[2] * (A[3] * A[7] - A[4] * A[6]);
    const v4d zero = {0, 0, 0, 0};
    v4m pos = I1 > zero;
    v4d t, r3; /* sqrt(3 I1), sqrt(I1 / 3) where I1 > 0 (scalar sqrt per lane) */
    for (int l = 0; l < 4; l++) {
        t[l] = pos[l] ? sqrt(3.0 * I1[l]) : 0.0;
        r3[l] = pos[l] ? sqrt(I1[l] / 3.0) : 0.0;
    }
    v4m act = pos;
    for (int it = 0; it < 60 && any(act); it++) {
        v4d q = t * t - I1;
        v4d f = q * q - 4.0 * I2 - 8.0 * J * t;
        v4d fp = 4.0 * t * q - 8.0 * J;
        act &= fp > zero;
        v4d dt = f / blend(act, fp, zero + 1.0);
        t = blend(act, t - dt, t);
        v4d adt = blend(dt < zero, -dt, dt);
        act &= ~(adt <= 1e-9 * t);
    }
    *ok = pos & (J >= TRACE_MIN_DET_REL * (I1 / 3.0) * r3);
    *I1o = I1;
    *Jo = J;
    *to = t;
}

/* the lanes' polar rotations R of A (row-major 3 x 3, entry k in A[k]); *ok: lanes where
 * df_admm_polar3 would return 0 (R valid there) */
static inline __attribute__((always_inline)) void polar4(const v4d A[9], v4d R[9], v4m *ok)
{
    v4d Cp[6], I1, J, t;
    trace4(A, Cp, &I1, &J, &t, ok);
    const v4d zero = {0, 0, 0, 0};
    v4d C0 = Cp[0], C1 = Cp[1], C2 = Cp[2], C3 = Cp[3], C4 = Cp[4], C5 = Cp[5];
    v4d i2 = 0.5 * (t * t - I1);
    v4d P[9] = {C0 + i2, C1, C2, C1, C3 + i2, C4, C2, C4, C5 + i2};
    v4d Q[9] = {t * C0 + J, t * C1, t * C2, t * C1, t * C3 + J, t * C4, t * C2, t * C4, t * C5 + J};
    v4d c0 = Q[4] * Q[8] - Q[5] * Q[7], c1 = Q[5] * Q[6] - Q[3] * Q[8], c2 = Q[3] * Q[7] - Q[4] * Q[6];
    v4d det = Q[0] * c0 + Q[1] * c1 + Q[2] * c2;
    *ok &= det > zero;
    det = blend(*ok, det, zero + 1.0);
    v4d Qi[9] = {c0, Q[2] * Q[7] - Q[1] * Q[8], Q[1] * Q[5] - Q[2] * Q[4],
                 c1, Q[0] * Q[8] - Q[2] * Q[6], Q[2] * Q[3] - Q[0] * Q[5],
                 c2, Q[1] * Q[6] - Q[0] * Q[7], Q[0] * Q[4] - Q[1] * Q[3]};
    v4d M[9];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            M[3 * i + j] = (P[3 * i] * Qi[j] + P[3 * i + 1] * Qi[3 + j] + P[3 * i + 2] * Qi[6 + j]) / det;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            R[3 * i + j] = A[3 * i] * M[j] + A[3 * i + 1] * M[3 + j] + A[3 * i + 2] * M[6 + j];
}

/* elements ae[k0 .. k0 + 4) (all valid): the vector path, RX and Ce written and gam |RX new -
 * old|^2, gam |RX new|^2 into ds[l], dz[l] for the lanes that pass polar4; the others are
 * returned in the mask (bit l: element k0 + l) for the caller's scalar path, untouched */
TET4_CLONES
static unsigned block4(df_admm *s, const int32_t *ae, const double *fb, int32_t k0, double ds[4], double dz[4])
{
    v4d G[9], W[9], O[9], R[9], g[12], vol, gam;
    int32_t e[4];
    const double *rf[4], *rw[4], *ro[4], *rg[4];
    for (int l = 0; l < 4; l++) {
        e[l] = ae[k0 + l];
        rf[l] = fb + 9 * (size_t)(k0 + l);
        rw[l] = s->W + 9 * (size_t)e[l];
        ro[l] = s->RX + 9 * (size_t)e[l];
        rg[l] = s->grad + (size_t)e[l] * 12;
    }
    load_rows(rf, 9, G);
    load_rows(rw, 9, W);
    load_rows(ro, 9, O);
    load_rows(rg, 12, g);
    for (int c = 0; c < 9; c++) G[c] += W[c];
    vol = (v4d){s->vol[e[0]], s->vol[e[1]], s->vol[e[2]], s->vol[e[3]]};
    gam = (v4d){s->gam[e[0]], s->gam[e[1]], s->gam[e[2]], s->gam[e[3]]};
    v4m ok;
    polar4(G, R, &ok);
    v4d f = gam / (vol + gam), cr = 1.0 - f;
    if (s->p.energy == DF_ADMM_ACAP) {
        v4d tS = {0, 0, 0, 0};
        for (int k = 0; k < 9; k++) tS += R[k] * G[k];
        cr = (1.0 - f) * tS / 3.0;
    }
    v4d RX[9], P[9], C[12], sd = {0, 0, 0, 0}, sz = {0, 0, 0, 0};
    for (int k = 0; k < 9; k++) {
        RX[k] = cr * R[k] + f * G[k];
        P[k] = gam * (RX[k] - W[k]);
        v4d d = RX[k] - O[k];
        sd += d * d;
        sz += RX[k] * RX[k];
    }
    for (int a = 0; a < 4; a++)
        for (int r = 0; r < 3; r++) {
            v4d acc = {0, 0, 0, 0};
            for (int c = 0; c < 3; c++) acc += P[3 * r + c] * g[3 * a + c];
            C[3 * a + r] = acc;
        }
    sd *= gam;
    sz *= gam;
    unsigned bad = 0;
    for (int l = 0; l < 4; l++) bad |= ok[l] ? 0u : 1u << l;
    double *wx[4], *wc[4];
    for (int l = 0; l < 4; l++) {
        wx[l] = s->RX + 9 * (size_t)e[l];
        wc[l] = s->Ce + (size_t)e[l] * 12;
        ds[l] = sd[l];
        dz[l] = sz[l];
    }
    if (!bad) {
        store_rows(wx, 9, RX);
        store_rows(wc, 12, C);
    } else {
        for (int l = 0; l < 4; l++) {
            if (bad >> l & 1) continue;
            for (int k = 0; k < 9; k++) wx[l][k] = RX[k][l];
            for (int k = 0; k < 12; k++) wc[l][k] = C[k][l];
        }
    }
    return bad;
}

void admm_local_tet4(df_admm *s, const int32_t *ae, const double *fb, int32_t n, double *s2o, double *z2o)
{
    double s2 = 0, z2 = 0;
    for (int32_t k0 = 0; k0 < n; k0 += 4) {
        int m = n - k0 < 4 ? (int)(n - k0) : 4;
        double ds[4], dz[4];
        unsigned bad = m == 4 ? block4(s, ae, fb, k0, ds, dz) : (1u << m) - 1;
        for (int l = 0; l < m; l++) {
            if (bad >> l & 1) { /* the scalar path (SVD fallback, or the block's tail) */
                int32_t e = ae[k0 + l];
                double G[9], old[9];
                const double *F = fb + 9 * (size_t)(k0 + l), *W = s->W + 9 * (size_t)e, *RX = s->RX + 9 * (size_t)e;
                memcpy(old, RX, sizeof(old));
                for (int c = 0; c < 9; c++) G[c] = F[c] + W[c];
                admm_local_x_one_G(s, e, G);
                double d2 = 0, z = 0;
                for (int c = 0; c < 9; c++) {
                    double d = RX[c] - old[c];
                    d2 += d * d;
                    z += RX[c] * RX[c];
                }
                ds[l] = s->gam[e] * d2;
                dz[l] = s->gam[e] * z;
            }
            s2 += ds[l];
            z2 += dz[l];
        }
    }
    *s2o += s2;
    *z2o += z2;
}

/* the energies of the four elements e[l] (ARAP / ACAP) from their F rows rf[l] (lanes where the
 * closed-form trace fails: admm_element_energy_F) */
static inline __attribute__((always_inline)) void energy4(const df_admm *s, const int32_t e[4], const double *const rf[4], double out[4])
{
    v4d F[9], C[6], I1c, J, t;
    v4m ok;
    load_rows(rf, 9, F);
    trace4(F, C, &I1c, &J, &t, &ok);
    v4d I1 = {0, 0, 0, 0};
    for (int k = 0; k < 9; k++) I1 += F[k] * F[k];
    v4d d = s->p.energy == DF_ADMM_ACAP ? I1 - t * t / 3.0 : I1 - 2.0 * t + 3.0;
    v4d vol = {s->vol[e[0]], s->vol[e[1]], s->vol[e[2]], s->vol[e[3]]};
    v4d E = 0.5 * vol * d;
    for (int l = 0; l < 4; l++)
        out[l] = !ok[l] ? admm_element_energy_F(s, e[l], rf[l]) : d[l] > 0 ? E[l] : 0.5 * vol[l] * 0.0;
}

TET4_CLONES
static void energy_block4(const df_admm *s, const int32_t *ae, const double *fb, int32_t k0, double *out)
{
    const int32_t e[4] = {ae[k0], ae[k0 + 1], ae[k0 + 2], ae[k0 + 3]};
    const double *rf[4] = {fb + 9 * (size_t)k0, fb + 9 * (size_t)(k0 + 1), fb + 9 * (size_t)(k0 + 2), fb + 9 * (size_t)(k0 + 3)};
    energy4(s, e, rf, out + k0);
}

/* elements ae[k0 .. k0 + 4): F_e(V), W_e += F - R X, F rows into fb rows k0.., terms as dual_one */
TET4_CLONES
static void dual4(df_admm *s, const int32_t *ae, double *fb, int32_t k0, int lazy, double *t)
{
    v4d g[12], W[9], O[9], F[9], gam;
    int32_t e[4];
    const int32_t *el[4];
    const double *rg[4], *ro[4];
    double *rw[4];
    const double *rf[4];
    for (int l = 0; l < 4; l++) {
        e[l] = ae[k0 + l];
        el[l] = s->E + 4 * (size_t)e[l];
        rg[l] = s->grad + (size_t)e[l] * 12;
        ro[l] = s->RX + 9 * (size_t)e[l];
        rw[l] = s->W + 9 * (size_t)e[l];
        rf[l] = fb + 9 * (size_t)(k0 + l);
    }
    load_rows(rg, 12, g);
    load_rows((const double *const *)rw, 9, W);
    load_rows(ro, 9, O);
    gam = (v4d){s->gam[e[0]], s->gam[e[1]], s->gam[e[2]], s->gam[e[3]]};
    for (int k = 0; k < 9; k++) F[k] = (v4d){0, 0, 0, 0};
    for (int a = 0; a < 4; a++) {
        const double *x0 = s->V + 3 * (size_t)el[0][a], *x1 = s->V + 3 * (size_t)el[1][a];
        const double *x2 = s->V + 3 * (size_t)el[2][a], *x3 = s->V + 3 * (size_t)el[3][a];
        for (int r = 0; r < 3; r++) {
            v4d x = {x0[r], x1[r], x2[r], x3[r]};
            for (int c = 0; c < 3; c++) F[3 * r + c] += x * g[3 * a + c];
        }
    }
    v4d er = {0, 0, 0, 0}, ea = er, ey = er;
    for (int c = 0; c < 9; c++) {
        v4d dw = F[c] - O[c];
        W[c] += dw;
        er += dw * dw; ea += F[c] * F[c]; ey += W[c] * W[c];
    }
    er = gam * er; ea = gam * ea; ey = gam * ey;
    store_rows(rw, 9, W);
    store_rows((double *const *)rf, 9, F);
    double en[4] = {0, 0, 0, 0};
    if (!lazy && (s->p.energy == DF_ADMM_ARAP || s->p.energy == DF_ADMM_ACAP)) energy4(s, e, rf, en);
    else if (!lazy)
        for (int l = 0; l < 4; l++) en[l] = admm_element_energy_F(s, e[l], rf[l]);
    for (int l = 0; l < 4; l++) {
        double *tl = t + 4 * (size_t)(k0 + l);
        tl[0] = er[l]; tl[1] = ea[l]; tl[2] = ey[l];
        tl[3] = en[l];
    }
}

void admm_dual_tet4(df_admm *s, const int32_t *ae, double *fb, int32_t n, int lazy, double *t)
{
    int32_t k0 = 0;
    for (; k0 + 4 <= n; k0 += 4) dual4(s, ae, fb, k0, lazy, t);
    for (; k0 < n; k0++) { /* the tail: dual_one's operations, one element */
        int32_t e = ae[k0];
        double F[9], er = 0, ea = 0, ey = 0, *W = s->W + 9 * (size_t)e;
        const double *RX = s->RX + 9 * (size_t)e;
        admm_element_F(s, s->V, e, F);
        for (int c = 0; c < 9; c++) {
            double dw = F[c] - RX[c];
            W[c] += dw;
            er += dw * dw; ea += F[c] * F[c]; ey += W[c] * W[c];
        }
        double *tl = t + 4 * (size_t)k0;
        tl[0] = s->gam[e] * er; tl[1] = s->gam[e] * ea; tl[2] = s->gam[e] * ey;
        memcpy(fb + 9 * (size_t)k0, F, sizeof(F));
        tl[3] = lazy ? 0.0 : admm_element_energy_F(s, e, F);
    }
}

void admm_energy_tet4(const df_admm *s, const int32_t *ae, const double *fb, int32_t n, double *out)
{
    int32_t k0 = 0;
    for (; k0 + 4 <= n; k0 += 4) energy_block4(s, ae, fb, k0, out);
    for (; k0 < n; k0++) out[k0] = admm_element_energy_F(s, ae[k0], fb + 9 * (size_t)k0);
}

/* P = F - sc R (sc = 1 ARAP, tr(R^T F) / 3 ACAP; R the polar rotation of F, by the SVD where the
 * closed form fails) of m elements' F rows (m x 9): four lanes when m is 4, else per element */
TET4_CLONES
static void stress_block(const df_admm *s, const double (*Fr)[9], int m, double (*P)[9])
{
    unsigned bad = (1u << m) - 1;
    if (m == 4) {
        v4d F[9], R[9];
        v4m ok;
        const double *rf[4] = {Fr[0], Fr[1], Fr[2], Fr[3]};
        load_rows(rf, 9, F);
        polar4(F, R, &ok);
        v4d sc = {1.0, 1.0, 1.0, 1.0};
        if (s->p.energy == DF_ADMM_ACAP) {
            v4d tS = {0, 0, 0, 0};
            for (int k = 0; k < 9; k++) tS += R[k] * F[k];
            sc = tS / 3.0;
        }
        v4d Pv[9];
        for (int k = 0; k < 9; k++) Pv[k] = F[k] - sc * R[k];
        bad = 0;
        for (int l = 0; l < 4; l++) {
            if (!ok[l]) { bad |= 1u << l; continue; }
            for (int k = 0; k < 9; k++) P[l][k] = Pv[k][l];
        }
    }
    for (int l = 0; l < m; l++)
        if (bad >> l & 1) admm_rot_stress(s, Fr[l], P[l]);
}

static int moved4(const df_admm *s, const double *V, const int32_t *el)
{
    for (int c = 0; c < 4; c++) {
        const double *x = V + 3 * (size_t)el[c], *r = s->Vrest + 3 * (size_t)el[c];
        if (x[0] != r[0] || x[1] != r[1] || x[2] != r[2]) return 1;
    }
    return 0;
}

double admm_force_tet4(const df_admm *s, const double *V, int32_t i)
{
    double f[3] = {0, 0, 0};
    int32_t p = s->ve_ptr[i], pe = s->ve_ptr[i + 1];
    while (p < pe) {
        int32_t e[4], cor[4];
        double Fr[4][9], P[4][9];
        int m = 0;
        for (; p < pe && m < 4; p++) {
            int32_t ee = s->ve_ent[p] / 4;
            if (!moved4(s, V, s->E + 4 * (size_t)ee)) continue; /* exactly the rest element: zero gradient */
            e[m] = ee;
            cor[m] = s->ve_ent[p] % 4;
            admm_element_F(s, V, ee, Fr[m]);
            m++;
        }
        if (m == 0) break;
        stress_block(s, (const double (*)[9])Fr, m, P);
        for (int l = 0; l < m; l++) {
            const double *gc = s->grad + (size_t)e[l] * 12 + 3 * cor[l];
            for (int r = 0; r < 3; r++)
                f[r] += s->vol[e[l]] * (P[l][3 * r] * gc[0] + P[l][3 * r + 1] * gc[1] + P[l][3 * r + 2] * gc[2]);
        }
    }
    return sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
}
