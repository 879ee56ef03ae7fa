/* kelvinlet_apply.c — the float32 evaluation path: SoA blocks of BLOCK points, one fused
 * SIMD loop per load (every order 1-8, 3D and 2D, specialized at compile time so the scale
 * loop unrolls and vectorizes; the loop bodies live in kelvinlet_simd.h, and those of the 2D grab
 * of orders 1-3 under arithmetic version 2 in kelvinlet_simd2d.h: the brush's `arith` picks the
 * version, kelvinlet.h), Euler / RK4 per block, OpenMP over blocks when more than one thread may
 * run (a parallel region costs microseconds even with one thread: small meshes on a 1-thread
 * caller skip it).
 *
 * SIMD: the block integrator carries __attribute__((target_clones("arch=x86-64-v4",
 * "arch=x86-64-v3", "default"))): gcc emits AVX-512 and AVX2/FMA clones next to the portable
 * x86-64-v2 (SSE4.2) build and an ifunc picks one at load time from the running CPU. No FMA
 * contraction happens (-ffp-contract=off is global), so every clone rounds identically per
 * operation and results do not depend on the machine. -DDF_NO_TARGET_CLONES drops the clones
 * (sanitizer builds: the ifunc resolver runs before the ThreadSanitizer runtime is up).
 * Threads: p->threads (kelvinlet.h); built without OpenMP (_OPENMP undefined) everything is serial.
 * 1/sqrt is computed as the bit-level estimate plus three Newton steps (relative error at
 * float rounding level) and the 2D logarithm by bit-level range reduction and a series:
 * plain C that vectorizes, where sqrtf / log would not (errno semantics). */
#include <math.h>
#ifdef _OPENMP
#include <omp.h>
#endif
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "core/kelvinlet/kelvinlet_internal.h"
#include "core/kelvinlet/kelvinlet_simd.h"
#include "core/kelvinlet/kelvinlet_simd2d.h"

#define PAR_MIN_BLOCKS 4          /* below this many blocks run on one thread            */

#ifdef DF_NO_TARGET_CLONES
#define DF_SIMD_CLONES
#else
#define DF_SIMD_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#endif

/* OpenMP threads of one evaluation of p: p->threads, or OpenMP's default when 0. */
static int eval_threads(const df_kelvinlet_prepared *p)
{
#ifdef _OPENMP
    return p->threads > 0 ? p->threads : omp_get_max_threads();
#else
    (void)p;
    return 1;
#endif
}

typedef struct fplan {
    size_t n;
    fsrc *s;
} fplan;

/* ---- plan construction --------------------------------------------------------------- */

static void build_src(const df_kelvinlet_kernel *k, const df_kelvinlet_source *src, double h,
                      int arith, fsrc *o)
{
    memset(o, 0, sizeof *o);
    o->dim = k->dim;
    o->order = k->order;
    o->affine = src->affine;
    double a = k->a, b = k->b, x0 = k->eps[0] * k->eps[0];
    for (int i = 0; i < 3; i++) {
        o->c[i] = (float)src->centre[i];
        o->f[i] = (float)(h * (i < k->dim ? src->f[i] : 0.0));
    }
    double F[9];
    for (int i = 0; i < 9; i++)
        F[i] = (i / 3 < k->dim && i % 3 < k->dim) ? h * src->F[i] : 0.0;
    double tr = (F[0] + F[4] + F[8]) / k->dim;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            o->K[3 * i + j] = (float)(0.5 * (F[3 * i + j] - F[3 * j + i]));
            o->D[3 * i + j] = (float)(0.5 * (F[3 * i + j] + F[3 * j + i])
                                      - (i == j && i < k->dim ? tr : 0.0));
        }
    o->t = (float)tr;
    for (int i = 0; i < k->order; i++) {
        double e2 = k->eps[i] * k->eps[i];
        o->e2[i] = (float)e2;
        o->del[i] = (float)(e2 - x0);
        o->w[i] = (float)k->w[i];
        o->wd[i] = (float)(k->w[i] * (e2 - x0));
        o->eh[i] = (float)(e2 / x0);
        o->dx[i] = e2;
        o->ddel[i] = e2 - x0;
        o->dw[i] = k->w[i];
        o->dwd[i] = k->w[i] * (e2 - x0);
    }
    o->ie2 = (float)(1.0 / x0);
    o->ie1 = (float)(1.0 / k->eps[0]);
    o->ie3 = (float)(1.0 / (x0 * k->eps[0]));
    o->ie5 = (float)(1.0 / (x0 * x0 * k->eps[0]));
    if (k->order == 3)
        o->W3 = (float)((k->eps[1] * k->eps[1] / x0 - 1.0) * (k->eps[2] * k->eps[2] / x0 - 1.0));
    if (k->dim == 3) {
        o->kA1 = (float)(a - b);
        o->kA3 = (float)(0.5 * a);
        o->kB = (float)b;
        o->kK = (float)(-a);              /* skew:  -a (s3 + 1.5 x5) K r                   */
        o->kD1 = (float)(2.0 * b - a);    /* dev:   ((2b - a) s3 - 1.5 a x5) D r           */
        o->kD2 = (float)(-1.5 * a);       /*        - 3b s5 (r^T D r) r                    */
        o->kDq = (float)(-3.0 * b);
        o->kT = (float)(2.0 * b - a);     /* trace: (2b - a)(s3 + 1.5 x5) t r  (eq. 16)    */
    } else {
        o->kA3 = (float)a;            /* A = lcoef L + a sum w x q, B = 2b sum w q          */
        o->kB = (float)(2.0 * b);
        o->kK = (float)(-2.0 * a);        /* skew:  -2a (sq + xq2) K r                     */
        o->kD1 = (float)(4.0 * b - 2.0 * a); /* dev: ((4b - 2a) sq - 2a xq2) D r           */
        o->kD2 = (float)(-2.0 * a);       /*        - 4b sq2 (r^T D r) r                   */
        o->kDq = (float)(-4.0 * b);
        o->kT = (float)(4.0 * b - 2.0 * a); /* trace: (4b - 2a)(sq + xq2) t r              */
    }
    o->lcoef = (float)(b - a);
    if (k->dim == 2 && k->order <= 3 && !src->affine && arith >= DF_KELVINLET_ARITH_2)
        dfk2_build(k, o);
}

static int build_plan(const df_kelvinlet_prepared *p, double h, fplan *pl, df_error *err)
{
    pl->n = p->nsrc;
    pl->s = malloc(p->nsrc * sizeof *pl->s);
    if (!pl->s)
        return df_error_set(err, DF_ENOMEM, "kelvinlet: out of memory for %zu loads", p->nsrc);
    const df_kelvinlet_source *s = dfk_sources(p);
    for (size_t i = 0; i < p->nsrc; i++)
        build_src(&p->kernel[s[i].kernel], &s[i], h, dfk_arith(&p->brush), &pl->s[i]);
    return DF_OK;
}

/* ---- SIMD kernels ---------------------------------------------------------------------- */

/* Tri-scale sums in closed form. With q_i = (s + eps_i^2)^-1/2 the tri-scale weights make
 * sum_i w_i q_i^m = (x2 - x1)(x3 - x1) q^m[x1, x2, x3] (second divided difference in
 * x = s + eps^2), and for q^m = x^(-m/2) that divided difference is
 *   q1^2 q2^2 q3^2 P_m / ((q1 + q2)(q1 + q3)(q2 + q3)),
 *   P_m = sum_{i<j} q_i q_j h_{m-1}(q_i, q_j) + 2 q1 q2 q3 h_{m-2}(q1, q2, q3)
 * (h_k: complete homogeneous polynomials) — every term positive, so no cancellation at all.
 * Evaluated on q scaled by eps_1 (in (0, 1]) to stay far from float overflow. */
static inline __attribute__((always_inline)) void tri_sums(const fsrc *S, const int want5,
                                                           float s, float *o1, float *o3,
                                                           float *o5)
{
    float sh = s * S->ie2;
    float q1 = rsq(sh + S->eh[0]), q2 = rsq(sh + S->eh[1]), q3 = rsq(sh + S->eh[2]);
    float a12 = q1 * q2, a13 = q1 * q3, a23 = q2 * q3, e3 = a12 * q3;
    float s1q = q1 * q1, s2q = q2 * q2, s3q = q3 * q3;
    float C = S->W3 * e3 * e3 / ((q1 + q2) * (q1 + q3) * (q2 + q3));
    float h12 = s1q + a12 + s2q, h13 = s1q + a13 + s3q, h23 = s2q + a23 + s3q;
    float p1 = a12 + a13 + a23;
    float p3 = a12 * h12 + a13 * h13 + a23 * h23 + 2.0f * e3 * (q1 + q2 + q3);
    *o1 = C * p1 * S->ie1;
    *o3 = C * p3 * S->ie3;
    if (want5) {
        float g12 = s1q * s1q + s1q * a12 + s1q * s2q + a12 * s2q + s2q * s2q;
        float g13 = s1q * s1q + s1q * a13 + s1q * s3q + a13 * s3q + s3q * s3q;
        float g23 = s2q * s2q + s2q * a23 + s2q * s3q + a23 * s3q + s3q * s3q;
        float h3 = s1q * q1 + s1q * q2 + q1 * s2q + s2q * q2 + q3 * (h12 + q3 * (q1 + q2 + q3));
        float p5 = a12 * g12 + a13 * g13 + a23 * g23 + 2.0f * e3 * h3;
        *o5 = C * p5 * S->ie5;
    }
}

/* Orders >= 4: the same difference sums as below, taken in double. Their weights grow like
 * (ratio^2 - 1)^-(n-1) and cancel down to the O(1) result (at ratio 1.1, order 8: ~1e4-fold),
 * which float sums turned into 2e-4 relative errors at the brush centre (issue 9 item 19);
 * in double each output is rounded to float once, so the tip is exact to float rounding. */
static inline __attribute__((always_inline)) void sums_wide(const fsrc *S, const int order,
                                                            const int want5, float s, float *o1,
                                                            float *o3, float *o5, float *ox3,
                                                            float *ox5)
{
    double sd = s, x1 = S->dx[0], s1p = sd + x1;
    double i1 = rsqd(s1p), i1s = i1 * i1, i13 = i1s * i1, rho1 = s1p * i1;
    double s1 = 0.0, s3 = 0.0, s5 = 0.0, t3 = 0.0, t5 = 0.0;
#pragma GCC unroll 8
    for (int i = 1; i < order; i++) {
        double sp = sd + S->dx[i];
        double ii = rsqd(sp), iis = ii * ii, ii3 = iis * ii;
        double d1 = -S->ddel[i] * i1 * ii / (rho1 + sp * ii);      /* ir_i - ir_1 */
        double d3 = d1 * (iis + ii * i1 + i1s);                    /* ir_i^3 - ir_1^3 */
        s1 += S->dw[i] * d1;
        s3 += S->dw[i] * d3;
        t3 += S->dwd[i] * d3;
        if (want5) {
            double d5 = d1 * (iis * iis + ii3 * i1 + iis * i1s + ii * i13 + i1s * i1s);
            s5 += S->dw[i] * d5;
            t5 += S->dwd[i] * d5;
        }
    }
    *o1 = (float)s1;
    *o3 = (float)s3;
    *ox3 = (float)(x1 * s3 + t3);
    if (want5) {
        *o5 = (float)s5;
        *ox5 = (float)(x1 * s5 + t5);
    }
}

/* Multi-scale sums of one point, cancellation-aware. With ir_i = (s + eps_i^2)^-1/2:
 *   s1 = sum w_i ir_i, s3 = sum w_i ir_i^3, s5 = sum w_i ir_i^5,
 *   x3 = sum w_i eps_i^2 ir_i^3, x5 = sum w_i eps_i^2 ir_i^5.
 * Order 3 uses the closed forms above and eps^2 ir^m = ir^(m-2) - s ir^m. Other orders >= 2:
 * the weights sum to 0, so sum w_i f_i = sum_{i>=2} w_i (f_i - f_1) with the differences in
 * closed form (ir_i - ir_1 = -del_i ir_1 ir_i / (rho_1 + rho_i)); for order >= 3 also
 * sum w_i del_i = 0, used the same way for the eps^2-weighted sums. Orders >= 4 keep some
 * cancellation, so their sums run in double (sums_wide above). */
static inline __attribute__((always_inline)) void scale_sums3(const fsrc *S, const int order,
                                                              const int want5, float s,
                                                              float *o1, float *o3, float *o5,
                                                              float *ox3, float *ox5)
{
    if (order == 3) {
        float t1, t3, t5 = 0.0f;
        tri_sums(S, want5, s, &t1, &t3, &t5);
        *o1 = t1;
        *o3 = t3;
        *ox3 = t1 - s * t3;
        if (want5) {
            *o5 = t5;
            *ox5 = t3 - s * t5;
        }
        return;
    }
    float s1p = s + S->e2[0];
    float i1 = rsq(s1p), i1s = i1 * i1, i13 = i1s * i1, i15 = i13 * i1s, rho1 = s1p * i1;
    float x1 = S->e2[0];
    if (order == 1) {
        *o1 = i1;
        *o3 = i13;
        *ox3 = x1 * i13;
        if (want5) {
            *o5 = i15;
            *ox5 = x1 * i15;
        }
        return;
    }
    if (order >= 4) {
        sums_wide(S, order, want5, s, o1, o3, o5, ox3, ox5);
        return;
    }
    float s1 = 0.0f, s3 = 0.0f, s5 = 0.0f, t3 = 0.0f, t5 = 0.0f;
    for (int i = 1; i < order; i++) {
        float sp = s + S->e2[i];
        float ii = rsq(sp), iis = ii * ii, ii3 = iis * ii;
        float d1 = -S->del[i] * i1 * ii / (rho1 + sp * ii);        /* ir_i - ir_1 */
        float d3 = d1 * (iis + ii * i1 + i1s);                     /* ir_i^3 - ir_1^3 */
        s1 += S->w[i] * d1;
        s3 += S->w[i] * d3;
        t3 += S->wd[i] * (order >= 3 ? d3 : ii3);
        if (want5) {
            float d5 = d1 * (iis * iis + ii3 * i1 + iis * i1s + ii * i13 + i1s * i1s);
            s5 += S->w[i] * d5;
            t5 += S->wd[i] * (order >= 3 ? d5 : ii3 * iis);
        }
    }
    *o1 = s1;
    *o3 = s3;
    *ox3 = x1 * s3 + t3;
    if (want5) {
        *o5 = s5;
        *ox5 = x1 * s5 + t5;
    }
}

static inline __attribute__((always_inline)) void grab3(const fsrc *S, const int order,
                                                        blk *restrict p, blk *restrict u)
{
    const float cx = S->c[0], cy = S->c[1], cz = S->c[2];
    const float fx = S->f[0], fy = S->f[1], fz = S->f[2];
#pragma omp simd
    for (int j = 0; j < BLOCK; j++) {
        float rx = p[0][j] - cx, ry = p[1][j] - cy, rz = p[2][j] - cz;
        float s = rx * rx + ry * ry + rz * rz, s1, s3, s5, x3, x5;
        scale_sums3(S, order, 0, s, &s1, &s3, &s5, &x3, &x5);
        float A = S->kA1 * s1 + S->kA3 * x3;
        float rf = S->kB * s3 * (rx * fx + ry * fy + rz * fz);
        u[0][j] += A * fx + rf * rx;
        u[1][j] += A * fy + rf * ry;
        u[2][j] += A * fz + rf * rz;
    }
}

static inline __attribute__((always_inline)) void affine3(const fsrc *S, const int order,
                                                          blk *restrict p, blk *restrict u)
{
    const float cx = S->c[0], cy = S->c[1], cz = S->c[2];
    const float *K = S->K, *D = S->D, t = S->t;
#pragma omp simd
    for (int j = 0; j < BLOCK; j++) {
        float rx = p[0][j] - cx, ry = p[1][j] - cy, rz = p[2][j] - cz;
        float s = rx * rx + ry * ry + rz * rz, s1, s3, s5, x3, x5;
        scale_sums3(S, order, 1, s, &s1, &s3, &s5, &x3, &x5);
        float base = s3 + 1.5f * x5;
        float cK = S->kK * base, cT = S->kT * base * t;
        float cD = S->kD1 * s3 + S->kD2 * x5, cQ = S->kDq * s5;
        float Krx = K[0] * rx + K[1] * ry + K[2] * rz;
        float Kry = K[3] * rx + K[4] * ry + K[5] * rz;
        float Krz = K[6] * rx + K[7] * ry + K[8] * rz;
        float Drx = D[0] * rx + D[1] * ry + D[2] * rz;
        float Dry = D[3] * rx + D[4] * ry + D[5] * rz;
        float Drz = D[6] * rx + D[7] * ry + D[8] * rz;
        float q = cT + cQ * (rx * Drx + ry * Dry + rz * Drz);
        u[0][j] += cK * Krx + cD * Drx + q * rx;
        u[1][j] += cK * Kry + cD * Dry + q * ry;
        u[2][j] += cK * Krz + cD * Drz + q * rz;
    }
}

static inline __attribute__((always_inline)) void eval_block(const fplan *pl, blk *restrict p,
                                                             blk *restrict u)
{
    for (int c = 0; c < 3; c++)
        memset(u[c], 0, sizeof u[c]);
    for (size_t k = 0; k < pl->n; k++) {
        const fsrc *S = &pl->s[k];
        if (S->v2) {
            switch (S->order) {
            case 1: grab2f(S, 1, 0, p, u); break;
            case 2: grab2f(S, 2, 0, p, u); break;
            default:
                if (S->v2close)
                    grab2f(S, 3, 1, p, u);
                else
                    grab2f(S, 3, 0, p, u);
                break;
            }
            continue;
        }
        if (S->dim == 2) {
            if (!S->affine) {
                switch (S->order) {
                case 1: grab2(S, 1, p, u); break;
                case 2: grab2(S, 2, p, u); break;
                case 3: grab2(S, 3, p, u); break;
                case 4: grab2(S, 4, p, u); break;
                case 5: grab2(S, 5, p, u); break;
                case 6: grab2(S, 6, p, u); break;
                case 7: grab2(S, 7, p, u); break;
                default: grab2(S, 8, p, u); break;
                }
            } else {
                switch (S->order) {
                case 1: affine2(S, 1, p, u); break;
                case 2: affine2(S, 2, p, u); break;
                case 3: affine2(S, 3, p, u); break;
                case 4: affine2(S, 4, p, u); break;
                case 5: affine2(S, 5, p, u); break;
                case 6: affine2(S, 6, p, u); break;
                case 7: affine2(S, 7, p, u); break;
                default: affine2(S, 8, p, u); break;
                }
            }
            continue;
        }
        if (!S->affine) {
            switch (S->order) {
            case 1: grab3(S, 1, p, u); break;
            case 2: grab3(S, 2, p, u); break;
            case 3: grab3(S, 3, p, u); break;
            case 4: grab3(S, 4, p, u); break;
            case 5: grab3(S, 5, p, u); break;
            case 6: grab3(S, 6, p, u); break;
            case 7: grab3(S, 7, p, u); break;
            default: grab3(S, 8, p, u); break;
            }
        } else {
            switch (S->order) {
            case 1: affine3(S, 1, p, u); break;
            case 2: affine3(S, 2, p, u); break;
            case 3: affine3(S, 3, p, u); break;
            case 4: affine3(S, 4, p, u); break;
            case 5: affine3(S, 5, p, u); break;
            case 6: affine3(S, 6, p, u); break;
            case 7: affine3(S, 7, p, u); break;
            default: affine3(S, 8, p, u); break;
            }
        }
    }
}

/* pos = x0 + d + c * k (k == NULL: pos = x0 + d) */
static inline __attribute__((always_inline)) void stage(blk *restrict pos, blk *restrict x0,
                                                        blk *restrict d, blk *restrict k,
                                                        float c)
{
    for (int a = 0; a < 3; a++) {
        if (!k) {
#pragma omp simd
            for (int j = 0; j < BLOCK; j++)
                pos[a][j] = x0[a][j] + d[a][j];
        } else {
#pragma omp simd
            for (int j = 0; j < BLOCK; j++)
                pos[a][j] = x0[a][j] + d[a][j] + c * k[a][j];
        }
    }
}

/* Integrates one block of cnt <= BLOCK points (xyz interleaved) and writes positions
 * (want_disp = 0) or displacements (want_disp = 1) to out. plans[nplans]: one per step when
 * moving, else one reused for every step. */
DF_SIMD_CLONES
static void integrate_block(const fplan *plans, int moving, int steps, int rk4, const float *in,
                            int cnt, float *out, int want_disp)
{
    blk x0[3] __attribute__((aligned(64))), d[3] __attribute__((aligned(64)));
    blk pos[3] __attribute__((aligned(64))), k[3] __attribute__((aligned(64)));
    blk acc[3] __attribute__((aligned(64)));
    if (cnt == BLOCK) {                     /* full block: a vectorized transpose */
#pragma omp simd
        for (int j = 0; j < BLOCK; j++) {
            x0[0][j] = in[3 * j];
            x0[1][j] = in[3 * j + 1];
            x0[2][j] = in[3 * j + 2];
        }
    } else {
        for (int j = 0; j < BLOCK; j++) {
            int jj = j < cnt ? j : cnt - 1; /* pad with the last point */
            for (int a = 0; a < 3; a++)
                x0[a][j] = in[3 * jj + a];
        }
    }
    memset(d, 0, sizeof d);
    for (int st = 0; st < steps; st++) {
        const fplan *pl = moving ? &plans[st] : &plans[0];
        if (!rk4) {
            stage(pos, x0, d, NULL, 0.0f);
            eval_block(pl, pos, k);
            for (int a = 0; a < 3; a++) {
#pragma omp simd
                for (int j = 0; j < BLOCK; j++)
                    d[a][j] += k[a][j];
            }
            continue;
        }
        static const float cst[4] = {0.0f, 0.5f, 0.5f, 1.0f};
        static const float wgt[4] = {1.0f, 2.0f, 2.0f, 1.0f};
        for (int sg = 0; sg < 4; sg++) {
            stage(pos, x0, d, sg ? k : NULL, cst[sg]);   /* k: the previous stage */
            eval_block(pl, pos, k);
            for (int a = 0; a < 3; a++) {
                float wv = wgt[sg];
                if (sg == 0) {
#pragma omp simd
                    for (int j = 0; j < BLOCK; j++)
                        acc[a][j] = k[a][j];
                } else {
#pragma omp simd
                    for (int j = 0; j < BLOCK; j++)
                        acc[a][j] += wv * k[a][j];
                }
            }
        }
        for (int a = 0; a < 3; a++) {
#pragma omp simd
            for (int j = 0; j < BLOCK; j++)
                d[a][j] += acc[a][j] * (1.0f / 6.0f);
        }
    }
    if (!want_disp)
        for (int a = 0; a < 3; a++) {
#pragma omp simd
            for (int j = 0; j < BLOCK; j++)
                d[a][j] += x0[a][j];
        }
    if (cnt == BLOCK) {
#pragma omp simd
        for (int j = 0; j < BLOCK; j++) {
            out[3 * j] = d[0][j];
            out[3 * j + 1] = d[1][j];
            out[3 * j + 2] = d[2][j];
        }
    } else {
        for (int j = 0; j < cnt; j++)
            for (int a = 0; a < 3; a++)
                out[3 * j + a] = d[a][j];
    }
}

/* ---- drivers ---------------------------------------------------------------------------- */

/* 1 when xyz[lo..hi) holds a NaN, an infinity or a value beyond lim. */
static int chunk_bad(const float *xyz, size_t lo, size_t hi, float lim)
{
    int flag = 0;
#pragma omp simd reduction(| : flag)
    for (size_t i = lo; i < hi; i++)
        flag |= !(fabsf(xyz[i]) <= lim);              /* true for NaN, +-Inf, too large */
    return flag;
}

int dfk_points_ok_f(const float *xyz, size_t n, int nthreads, size_t *bad)
{
    const size_t m = 3 * n, chunk = 4096;
    const size_t nc = (m + chunk - 1) / chunk;
    const float lim = (float)DF_KELVINLET_MAX_VALUE;
    int any = 0;
    if (nc >= 16 && nthreads > 1) {
#pragma omp parallel for reduction(| : any) schedule(static) num_threads(nthreads)
        for (size_t c = 0; c < nc; c++)
            any |= chunk_bad(xyz, c * chunk, c * chunk + chunk < m ? c * chunk + chunk : m, lim);
    } else { /* no parallel region: it costs microseconds even with one thread */
        any = chunk_bad(xyz, 0, m, lim);
    }
    if (!any)
        return 1;
    for (size_t i = 0; i < m; i++)
        if (!(fabsf(xyz[i]) <= lim)) {
            if (bad)
                *bad = i / 3;
            break;
        }
    return 0;
}

static int run(const df_kelvinlet_prepared *p, const float *in, size_t n, float *out,
               int want_disp, df_error *err)
{
    int rc = dfk_check_prepared(p, err);
    if (rc != DF_OK)
        return rc;
    if (n == 0)
        return DF_OK;
    if (!in || !out)
        return df_error_set(err, DF_EINVAL, "kelvinlet apply: NULL points or output");
    size_t bad;
    const int nt = eval_threads(p);
    if (!dfk_points_ok_f(in, n, nt, &bad))
        return df_error_set(err, DF_EINVAL, "kelvinlet apply: point %zu not finite or beyond %g",
                            bad, DF_KELVINLET_MAX_VALUE);
    df_kelvinlet_prepared *mv;
    rc = dfk_moving_substeps(p, &mv, err);
    if (rc != DF_OK)
        return rc;
    int steps = p->brush.steps, nplans = mv ? steps : 1;
    fplan *plans = calloc((size_t)nplans, sizeof *plans);
    if (!plans) {
        free(mv);
        return df_error_set(err, DF_ENOMEM, "kelvinlet: out of memory for plans");
    }
    for (int i = 0; i < nplans && rc == DF_OK; i++)
        rc = build_plan(mv ? &mv[i] : p, mv ? 1.0 : 1.0 / steps, &plans[i], err);
    if (rc == DF_OK) {
        int rk4 = p->brush.integrator == DF_KELVINLET_RK4, moving = mv != NULL;
        size_t nb = (n + BLOCK - 1) / BLOCK;
        if (nb >= PAR_MIN_BLOCKS && nt > 1) {
#pragma omp parallel for schedule(dynamic, 8) num_threads(nt)
            for (size_t b = 0; b < nb; b++) {
                size_t lo = b * BLOCK, cnt = n - lo < BLOCK ? n - lo : BLOCK;
                integrate_block(plans, moving, steps, rk4, in + 3 * lo, (int)cnt, out + 3 * lo,
                                want_disp);
            }
        } else { /* one thread: skip the parallel region (microseconds even for 1 thread) */
            for (size_t lo = 0; lo < n; lo += BLOCK)
                integrate_block(plans, moving, steps, rk4, in + 3 * lo,
                                (int)(n - lo < BLOCK ? n - lo : BLOCK), out + 3 * lo, want_disp);
        }
    }
    for (int i = 0; i < nplans; i++)
        free(plans[i].s);
    free(plans);
    free(mv);
    return rc;
}

int df_kelvinlet_apply(const df_kelvinlet_prepared *p, float *xyz, size_t n, df_error *err)
{
    return run(p, xyz, n, xyz, 0, err);
}

int df_kelvinlet_displacements(const df_kelvinlet_prepared *p, const float *xyz, size_t n,
                               float *out, df_error *err)
{
    return run(p, xyz, n, out, 1, err);
}
