/* kelvinlet_simd2d.h — arithmetic version 2 of the 2D grab load for falloff orders 1-3: float32
 * SIMD loop bodies (not a public API; included by kelvinlet_apply.c, whose target_clones compile
 * them once per instruction set, and by nothing else). Version 1 (kelvinlet_simd.h grab2) sums
 * the scales in double with a double logarithm: five double divisions and two double logs a
 * point at order 3, 2-2.3x the 3D cost. Version 2 stays in float and keeps the accuracy where
 * float sums would lose it:
 *   - the tip: A(s) = A0 + lc (L(s) - L0) - kA3 s Q(s), with A0 = A(0) of the double kernel and
 *     L0 the float L(s) of this very code at s = 0, so at the centre A is A0 rounded once (the
 *     centre moves by `tip` to float rounding even where lc L0 and kA3 cancel in A0);
 *   - the scale sums: Q = sum w q (q = 1/(s + eps^2)) is a divided difference of 1/p, in closed
 *     form without cancellation (order 2: -w2 del2 q1 q2, order 3: w1 del2 del3 q1 q2 q3), and
 *     X = sum w eps^2 q = X(0) - s Q (X(0) = 1 at order 1, 0 above);
 *   - L = sum w ln(s + eps^2) - ln(eps_1^2): order 1 log1p(s / eps_1^2), order 2
 *     w2 log1p(y2), order 3 sum_i w_i (log1p(y_i) - y_i) (y_i = del_i q1; the y_i terms sum to
 *     zero as sum w del = 0, and what remains no longer cancels ~1/del-fold at close ratios),
 *     with log1p(y) - y from the atanh series when y <= 1 (h_small) and directly above (h_any:
 *     order 3 with eps_3^2 > 2 eps_1^2, where some y_i exceed 1 near the centre).
 * Everything is computed on s / eps_1^2 (in [0, ~1e30] within the radius and coordinate bounds
 * of kelvinlet.h: no float overflow) and on eps_i^2 / eps_1^2. The functions are pure IEEE
 * float operations (no contraction, no libm): every clone, lane and thread count gives the same
 * bits, as for version 1. */
#ifndef DF_KELVINLET_SIMD2D_H
#define DF_KELVINLET_SIMD2D_H

#include <stdint.h>
#include <string.h>

#include "core/kelvinlet/kelvinlet_internal.h"
#include "core/kelvinlet/kelvinlet_simd.h"

/* ln(u) for a normal float u >= 1 (fdlibm's logf: m in [sqrt(1/2), sqrt(2)), ln m =
 * 2 atanh(f / (2 + f)) with its degree-8 minimax tail; < 1 ulp). */
DFK_AI float vlogf1(float u)
{
    int32_t bits, eb, mb;
    memcpy(&bits, &u, sizeof bits);
    const int32_t mant = bits & 0x007fffff;
    const int32_t up = (mant + (0x00800000 - 0x003504f3)) >> 23;  /* mantissa >= sqrt 2 */
    eb = (bits >> 23) - 127 + up;
    mb = mant | ((127 - up) << 23);
    float m, e = (float)eb;
    memcpy(&m, &mb, sizeof m);
    float f = m - 1.0f, hf = 0.5f * f * f, t = f / (2.0f + f), z = t * t, w = z * z;
    float t1 = w * (0x1.999c26p-2f + w * 0x1.f13c4cp-3f);           /* Lg2, Lg4 */
    float t2 = z * (0x1.555554p-1f + w * 0x1.23d3dcp-2f);           /* Lg1, Lg3 */
    float R = t2 + t1;
    const float ln2_hi = 0x1.62e300p-1f, ln2_lo = 0x1.2fefa2p-17f;
    return e * ln2_hi - ((hf - (t * (hf + R) + e * ln2_lo)) - f);
}

/* log1p(y), y >= 0, given inv ~= 1/(1 + y): ln of the rounded u = 1 + y plus the correction
 * (y - (u - 1)) / u of that rounding (u - 1 is exact). */
DFK_AI float vlog1pf(float y, float inv)
{
    float u = 1.0f + y;
    return vlogf1(u) + (y - (u - 1.0f)) * inv;
}

/* log1p(y) - y for 0 <= y <= 1 without cancellation: with t = y / (2 + y) (<= 1/3),
 * log1p(y) = 2 atanh(t) = 2t + 2t^3 S(t^2), S(z) = sum_k z^k / (2k + 3), and 2t - y = -y t,
 * so log1p(y) - y = t (2 t^2 S - y), 2 t^2 S <= y / 6. S to z^7 (remainder < 2^-25 S). */
DFK_AI float h_small(float y)
{
    float t = y / (2.0f + y), z = t * t;
    float S = 1.0f / 3.0f + z * (1.0f / 5.0f + z * (1.0f / 7.0f + z * (1.0f / 9.0f +
              z * (1.0f / 11.0f + z * (1.0f / 13.0f + z * (1.0f / 15.0f + z * (1.0f / 17.0f)))))));
    return t * (2.0f * z * S - y);
}

/* log1p(y) - y for any y >= 0: h_small up to 1, directly above (cancellation at most 3.3-fold
 * there); both are evaluated and one selected (no branch in the SIMD loop). */
DFK_AI float h_any(float y, float inv)
{
    float a = h_small(y < 1.0f ? y : 1.0f), b = vlog1pf(y, inv) - y;
    return y <= 1.0f ? a : b;
}

/* Version-2 2D grab load, orders 1-3 (`close`: order 3 with every y_i <= 1, i.e.
 * eps_3^2 <= 2 eps_1^2, so h_small alone serves): u += A f + B (r.f) r as in grab2 of
 * kelvinlet_simd.h. */
DFK_AI void grab2f(const fsrc *S, const int order, const int close, blk *restrict p,
                   blk *restrict u)
{
    const float cx = S->c[0], cy = S->c[1], fx = S->f[0], fy = S->f[1];
    const float ie2 = S->ie2, lc = S->lcoef, kA3 = S->kA3, A0 = S->A0, L0 = S->L0;
    const float kB = S->kBq, kQs = S->kQs;
    const float eh2 = S->eh[1], eh3 = S->eh[2], dh2 = S->dh[1], dh3 = S->dh[2];
    const float w2 = S->w[1], w3 = S->w[2];
#pragma omp simd
    for (int j = 0; j < BLOCK; j++) {
        float rx = p[0][j] - cx, ry = p[1][j] - cy;
        float sh = (rx * rx + ry * ry) * ie2;          /* s / eps_1^2 */
        float q1 = 1.0f / (sh + 1.0f), qq, L;          /* qq: q1 q2 (q3) scaled */
        if (order == 1) {
            qq = q1;
            L = vlog1pf(sh, q1);
        } else if (order == 2) {
            float q2 = 1.0f / (sh + eh2), y2 = dh2 * q1;
            qq = q1 * q2;
            L = w2 * vlog1pf(y2, (sh + 1.0f) * q2);
        } else {
            float q2 = 1.0f / (sh + eh2), q3 = 1.0f / (sh + eh3);
            float y2 = dh2 * q1, y3 = dh3 * q1;
            qq = q1 * q2 * q3;
            if (close)
                L = w2 * h_small(y2) + w3 * h_small(y3);
            else
                L = w2 * h_any(y2, (sh + 1.0f) * q2) + w3 * h_any(y3, (sh + 1.0f) * q3);
        }
        float A = A0 + (lc * (L - L0) - kA3 * (kQs * sh * qq));
        float rf = (kB * qq) * (rx * fx + ry * fy);
        u[0][j] += A * fx + rf * rx;
        u[1][j] += A * fy + rf * ry;
    }
}

/* The float L of grab2f at s = 0 (its L0: A(0) is then exactly A0). */
DFK_AI float grab2f_L0(const fsrc *S, int order, int close)
{
    const float q1 = 1.0f / (0.0f + 1.0f);
    if (order == 1)
        return vlog1pf(0.0f, q1);
    float q2 = 1.0f / (0.0f + S->eh[1]), y2 = S->dh[1] * q1;
    if (order == 2)
        return S->w[1] * vlog1pf(y2, (0.0f + 1.0f) * q2);
    float q3 = 1.0f / (0.0f + S->eh[2]), y3 = S->dh[2] * q1;
    if (close)
        return S->w[1] * h_small(y2) + S->w[2] * h_small(y3);
    return S->w[1] * h_any(y2, (0.0f + 1.0f) * q2) + S->w[2] * h_any(y3, (0.0f + 1.0f) * q3);
}

/* The per-load constants of grab2f for kernel k (2D, order 1-3): the closed-form scale
 * products' coefficients (Q = W q1..qn, W in double, then scaled to q / eps_1^2), A0 from the
 * double kernel and L0 from grab2f_L0; sets o->v2. Plan construction, not the SIMD loop. */
static void dfk2_build(const df_kelvinlet_kernel *k, fsrc *o)
{
    double x1 = k->eps[0] * k->eps[0], W;
    for (int i = 0; i < k->order; i++)
        o->dh[i] = (float)(k->eps[i] * k->eps[i] / x1 - 1.0);
    if (k->order == 1)
        W = 1.0;                                             /* Q = q1               */
    else if (k->order == 2)
        W = -k->w[1] * (k->eps[1] * k->eps[1] / x1 - 1.0);   /* Q = -w2 del2 q1 q2   */
    else
        W = k->w[0] * (k->eps[1] * k->eps[1] / x1 - 1.0)     /* Q = w1 del2 del3 q1 q2 q3 */
            * (k->eps[2] * k->eps[2] / x1 - 1.0);
    o->v2 = 1;
    o->v2close = k->order == 3 && k->eps[2] * k->eps[2] <= 2.0 * x1;
    o->kQs = (float)W;
    o->kBq = (float)(2.0 * k->b * W / x1);
    o->A0 = (float)dfk_grab_tip_scale(k);
    o->L0 = grab2f_L0(o, k->order, o->v2close);
}

#endif
