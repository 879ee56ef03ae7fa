/* kelvinlet_simd.h — the float32 path's per-load data and the loop bodies it shares (not a
 * public API; included by kelvinlet_apply.c only, whose target_clones compile every function
 * here once per instruction set).
 *
 * Everything is plain C written so that gcc vectorizes it inside `#pragma omp simd` loops:
 * no libm calls (sqrtf/log set errno and stay scalar), bit-level estimates refined by Newton
 * steps, selects instead of branches, loops over scales unrolled at compile time. Every
 * operation is an IEEE operation without contraction (-ffp-contract=off), so scalar, SSE,
 * AVX2 and AVX-512 code round identically: results do not depend on the machine or on how a
 * point falls into a SIMD lane. */
#ifndef DF_KELVINLET_SIMD_H
#define DF_KELVINLET_SIMD_H

#include <stdint.h>
#include <string.h>

#include "core/kelvinlet/kelvinlet.h"

#define BLOCK 256                 /* points per SoA block (fits L1 with all temporaries) */
#define MO DF_KELVINLET_MAX_ORDER
#define DFK_AI static inline __attribute__((always_inline))

typedef float blk[BLOCK];

typedef struct fsrc {
    int dim, order, affine;
    float c[3], f[3];      /* centre and grab force (times the step h)                  */
    float e2[MO];          /* eps_i^2                                                   */
    float del[MO];         /* eps_i^2 - eps_1^2                                         */
    float w[MO], wd[MO];   /* w_i and w_i (eps_i^2 - eps_1^2)                           */
    float ie2, eh[MO];     /* tri-scale: 1 / eps_1^2 and eps_i^2 / eps_1^2              */
    float W3, ie1, ie3, ie5; /* (eps_2^2 - eps_1^2)(eps_3^2 - eps_1^2) / eps_1^4, eps_1^-k */
    float kA1, kA3, kB;    /* grab:   A = kA1 sum w ir + kA3 sum w x ir^3, B = kB sum w ir^3 */
    float K[9], D[9], t;   /* affine F split: skew K, symmetric traceless D, trace/dim t */
    float kK, kD1, kD2, kDq, kT; /* affine coefficients (see affine3 / grab2, affine2)   */
    float lcoef;           /* 2D: (b - a) sum_i w_i ln(s + eps_i^2)                     */
    double dx[MO], ddel[MO], dw[MO], dwd[MO]; /* the same in double (orders >= 4, 2D)    */
    int v2, v2close;       /* 2D grab, orders 1-3, arithmetic 2 (kelvinlet_simd2d.h); order 3
                              with eps_3^2 <= 2 eps_1^2                                       */
    float A0, L0;          /* v2: A(0) of the double kernel, the float L at s = 0            */
    float kBq, kQs;        /* v2: B = kBq qq, s Q = kQs (s / eps_1^2) qq (qq: scaled q products) */
    float dh[MO];          /* v2: eps_i^2 / eps_1^2 - 1                                        */
} fsrc;

/* 1/sqrt(x), x > 0 normal: bit-level estimate plus three Newton steps (float rounding level). */
DFK_AI float rsq(float x)
{
    int32_t i;
    float y, hx = 0.5f * x;
    memcpy(&i, &x, sizeof i);
    i = 0x5f375a86 - (i >> 1);
    memcpy(&y, &i, sizeof y);
    y = y * (1.5f - hx * y * y);
    y = y * (1.5f - hx * y * y);
    y = y * (1.5f - hx * y * y);
    return y;
}

/* 1/sqrt(x) in double: the float estimate plus two double Newton steps. */
DFK_AI double rsqd(double x)
{
    double y = (double)rsq((float)x);
    y = y * (1.5 - 0.5 * x * y * y);
    y = y * (1.5 - 0.5 * x * y * y);
    return y;
}

/* ln(x) for a positive normal double, within ~1 ulp: x = m 2^e with m in [sqrt(1/2), sqrt(2)),
 * ln m = 2 atanh(t), t = (m - 1)/(m + 1), |t| <= 0.1716, as in fdlibm's log (its degree-14
 * minimax polynomial); e ln 2 in two parts (ln2_hi has 11 trailing zero bits: e * ln2_hi is
 * exact). The exponent becomes a double through the 2^52 trick (integer ops only). */
DFK_AI double vlog(double x)
{
    uint64_t bits, eb, mb;
    memcpy(&bits, &x, sizeof bits);
    const uint64_t mant = bits & UINT64_C(0x000fffffffffffff);
    /* up = 1 when the mantissa is >= sqrt(2) - 1 (0x6a09e667f3bcd): halve m, bump e */
    const uint64_t up = (mant + (UINT64_C(0x0010000000000000) - UINT64_C(0x6a09e667f3bcd))) >> 52;
    eb = ((bits >> 52) + up) | UINT64_C(0x4330000000000000);    /* 2^52 + biased exponent */
    mb = mant | ((UINT64_C(0x3ff) - up) << 52);
    double m, e;
    memcpy(&m, &mb, sizeof m);
    memcpy(&e, &eb, sizeof e);
    e -= 4503599627370496.0 + 1023.0;                          /* the unbiased exponent */
    /* fdlibm's split: ln(1 + f) = f - f^2/2 + t (f^2/2 + R), t = f / (2 + f), R ~ 2 t^2/3 +
     * 2 t^4/5 + ...: f and f^2/2 carry the result, the rounded division only the small rest. */
    double f = m - 1.0, hf = 0.5 * f * f, t = f / (2.0 + f), z = t * t;
    /* fdlibm's minimax coefficients (e_log.c Lg1..Lg7): |error| < 2^-58.45 on this range */
    double R = z * (6.666666666666735130e-01 +
               z * (3.999999999940941908e-01 +
               z * (2.857142874366239149e-01 +
               z * (2.222219843214978396e-01 +
               z * (1.818357216161805012e-01 +
               z * (1.531383769920937332e-01 +
               z * 1.479819860511658591e-01))))));
    const double ln2_hi = 6.93147180369123816490e-01, ln2_lo = 1.90821492927058770002e-10;
    return e * ln2_hi - ((hf - (t * (hf + R) + e * ln2_lo)) - f);
}

/* ln(1 + y), y >= 0, given inv ~= 1/(1 + y): ln(u) of the rounded u = 1 + y plus the
 * correction (y - (u - 1)) / u of that rounding (u - 1 is exact), accurate for tiny y too. */
DFK_AI double vlog1p(double y, double inv)
{
    double u = 1.0 + y;
    return vlog(u) + (y - (u - 1.0)) * inv;
}

/* 2D multi-scale sums at squared distance s, in double, with q_i = 1/(s + eps_i^2):
 * sq = sum w q, sq2 = sum w q^2, xq = sum w eps^2 q, xq2 = sum w eps^2 q^2,
 * lg = sum w ln(s + eps^2). For order >= 2 the weights sum to 0 and the differences
 * q_i - q_1 = -del_i q_i q_1 are exact in form (as in 3D); ln terms become ln(1 + del_i q_1). */
DFK_AI void sums2(const fsrc *S, const int order, double s, double *sq, double *sq2, double *xq,
                  double *xq2, double *lg)
{
    const double x1 = S->dx[0], p1 = s + x1, q1 = 1.0 / p1;
    if (order == 1) {
        *sq = q1;
        *sq2 = q1 * q1;
        *xq = x1 * q1;
        *xq2 = x1 * (q1 * q1);
        *lg = vlog(p1);
        return;
    }
    double a1 = 0.0, a2 = 0.0, t1 = 0.0, t2 = 0.0, l = 0.0;
#pragma GCC unroll 8
    for (int i = 1; i < order; i++) {
        double qi = 1.0 / (s + S->dx[i]);
        double d1 = -S->ddel[i] * qi * q1, d2 = d1 * (qi + q1);
        a1 += S->dw[i] * d1;
        a2 += S->dw[i] * d2;
        t1 += S->dwd[i] * (order >= 3 ? d1 : qi);
        t2 += S->dwd[i] * (order >= 3 ? d2 : qi * qi);
        l += S->dw[i] * vlog1p(S->ddel[i] * q1, p1 * qi);
    }
    *sq = a1;
    *sq2 = a2;
    *xq = x1 * a1 + t1;
    *xq2 = x1 * a2 + t2;
    *lg = l;
}

/* 2D grab load (z untouched): u += (lcoef lg + kA3 xq) f + kB sq (r.f) r. */
DFK_AI void grab2(const fsrc *S, const int order, blk *restrict p, blk *restrict u)
{
    const float cx = S->c[0], cy = S->c[1], fx = S->f[0], fy = S->f[1];
    const double lc = S->lcoef, kA3 = S->kA3, kB = S->kB;
#pragma omp simd
    for (int j = 0; j < BLOCK; j++) {
        float rx = p[0][j] - cx, ry = p[1][j] - cy;
        double s = (double)rx * rx + (double)ry * ry, sq, sq2, xq, xq2, lg;
        sums2(S, order, s, &sq, &sq2, &xq, &xq2, &lg);
        float A = (float)(lc * lg + kA3 * xq);
        float rf = (float)(kB * sq) * (rx * fx + ry * fy);
        u[0][j] += A * fx + rf * rx;
        u[1][j] += A * fy + rf * ry;
    }
}

/* 2D affine load: skew, deviatoric and trace parts of F (see build_src in kelvinlet_apply.c). */
DFK_AI void affine2(const fsrc *S, const int order, blk *restrict p, blk *restrict u)
{
    const float cx = S->c[0], cy = S->c[1];
    const float K0 = S->K[0], K1 = S->K[1], K3 = S->K[3], K4 = S->K[4];
    const float D0 = S->D[0], D1 = S->D[1], D3 = S->D[3], D4 = S->D[4];
    const double kK = S->kK, kT = S->kT, kD1 = S->kD1, kD2 = S->kD2, kDq = S->kDq, t = S->t;
#pragma omp simd
    for (int j = 0; j < BLOCK; j++) {
        float rx = p[0][j] - cx, ry = p[1][j] - cy;
        double s = (double)rx * rx + (double)ry * ry, sq, sq2, xq, xq2, lg;
        sums2(S, order, s, &sq, &sq2, &xq, &xq2, &lg);
        double base = sq + xq2;
        float cK = (float)(kK * base), cT = (float)(kT * base * t);
        float cD = (float)(kD1 * sq + kD2 * xq2), cQ = (float)(kDq * sq2);
        float Krx = K0 * rx + K1 * ry, Kry = K3 * rx + K4 * ry;
        float Drx = D0 * rx + D1 * ry, Dry = D3 * rx + D4 * ry;
        float q = cT + cQ * (rx * Drx + ry * Dry);
        u[0][j] += cK * Krx + cD * Drx + q * rx;
        u[1][j] += cK * Kry + cD * Dry + q * ry;
    }
}

#endif
