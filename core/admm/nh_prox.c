/* nh_prox.c — Neo-Hookean singular-value proximal operator (see nh_prox.h). */
#include "core/admm/nh_prox.h"

#include <math.h>
#include <string.h>

void df_admm_lame(double youngs, double poisson, double *mu, double *lambda)
{
    *mu = youngs / (2.0 * (1.0 + poisson));
    *lambda = youngs * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson));
}

double df_admm_nh_psi(const double sig[3], double mu, double lambda)
{
    double J = sig[0] * sig[1] * sig[2];
    if (!(J > 0.0) || sig[0] <= 0.0 || sig[1] <= 0.0 || sig[2] <= 0.0) return INFINITY;
    double L = log(J);
    return 0.5 * mu * (sig[0] * sig[0] + sig[1] * sig[1] + sig[2] * sig[2] - 3.0) - mu * L +
           0.5 * lambda * L * L;
}

static double prox_obj(const double x[3], const double sig[3], double vol, double mu, double lambda,
                       double gamma)
{
    double d0 = x[0] - sig[0], d1 = x[1] - sig[1], d2 = x[2] - sig[2];
    return vol * df_admm_nh_psi(x, mu, lambda) + 0.5 * gamma * (d0 * d0 + d1 * d1 + d2 * d2);
}

/* solves the SPD 3x3 system H d = -g by an LDL^T factorization (no square roots); returns 0, or -1
 * when H is not positive definite */
static int ldl_solve3(const double H[9], const double g[3], double d[3])
{
    double d0 = H[0];
    if (!(d0 > 0)) return -1;
    double l10 = H[3] / d0, l20 = H[6] / d0;
    double d1 = H[4] - l10 * l10 * d0;
    if (!(d1 > 0)) return -1;
    double l21 = (H[7] - l20 * l10 * d0) / d1;
    double d2 = H[8] - l20 * l20 * d0 - l21 * l21 * d1;
    if (!(d2 > 0)) return -1;
    double y0 = -g[0], y1 = -g[1] - l10 * y0, y2 = -g[2] - l20 * y0 - l21 * y1;
    d[2] = y2 / d2;
    d[1] = y1 / d1 - l21 * d[2];
    d[0] = y0 / d0 - l10 * d[1] - l20 * d[2];
    return 0;
}

/* gradient of the prox objective at x (all x_i > 0); *L = ln J; returns |g| */
static double grad(const double x[3], const double sig[3], double vol, double mu, double lambda,
                   double gamma, double g[3], double *L)
{
    *L = log(x[0] * x[1] * x[2]);
    double c = lambda * *L - mu;
    for (int i = 0; i < 3; i++) g[i] = vol * (mu * x[i] + c / x[i]) + gamma * (x[i] - sig[i]);
    return sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
}

int df_admm_nh_prox(const double sig[3], const double *start, double vol, double mu, double lambda,
                    double gamma, double out[3])
{
    if (!(vol > 0) || !(gamma > 0) || !(mu > 0) || !(lambda >= 0) || !isfinite(sig[0]) ||
        !isfinite(sig[1]) || !isfinite(sig[2]) || !isfinite(vol * mu) || !isfinite(gamma))
        return -1;
    double x[3];
    double m = (fabs(sig[0]) + fabs(sig[1]) + fabs(sig[2])) / 3.0;
    double floor_ = 0.03 * (m < 1.0 ? 1.0 : m) + 1e-3;
    for (int i = 0; i < 3; i++) x[i] = fabs(sig[i]) > floor_ ? fabs(sig[i]) : floor_;
    if (start && start[0] > 0 && start[1] > 0 && start[2] > 0 && isfinite(start[0] + start[1] + start[2])) {
        x[0] = start[0]; x[1] = start[1]; x[2] = start[2];
    }
    double scale = vol * mu + gamma;
    int it;
    double f = NAN; /* computed lazily: warm-started solves usually take full steps only */
    double g[3], L, gn = grad(x, sig, vol, mu, lambda, gamma, g, &L);
    for (it = 0; it < DF_ADMM_NH_MAX_NEWTON; it++) {
        double xn = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
        if (gn <= 1e-13 * scale * (1.0 + xn)) break;
        double H[9], ix[3] = {1.0 / x[0], 1.0 / x[1], 1.0 / x[2]};
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                H[3 * i + j] = (i == j)
                    ? vol * (mu + (mu + lambda * (1.0 - L)) * ix[i] * ix[i]) + gamma
                    : vol * lambda * ix[i] * ix[j];
        double d[3];
        double shift = 0.0;
        while (ldl_solve3(H, g, d) != 0) { /* not PD: shift the diagonal until it is */
            double add = shift == 0.0 ? 1e-8 * scale : shift;
            shift += add;
            H[0] += add; H[4] += add; H[8] += add;
            if (shift > 1e12 * scale) { d[0] = -g[0] / scale; d[1] = -g[1] / scale; d[2] = -g[2] / scale; break; }
        }
        /* fraction to boundary: keep every x_i > 0 */
        double t = 1.0;
        for (int i = 0; i < 3; i++)
            if (d[i] < 0 && x[i] + t * d[i] <= 0.0) t = 0.9 * x[i] / -d[i];
        double xt[3], gt[3], Lt;
        if (t == 1.0 && shift == 0.0) {
            /* Newton region test: a full step of the exact-Hessian Newton method that at least
             * halves the gradient is accepted without evaluating the objective (its gradient is
             * the next step's anyway) */
            for (int i = 0; i < 3; i++) xt[i] = x[i] + d[i];
            double gnt = grad(xt, sig, vol, mu, lambda, gamma, gt, &Lt);
            if (gnt <= 0.5 * gn) {
                memcpy(x, xt, sizeof(xt));
                memcpy(g, gt, sizeof(gt));
                L = Lt;
                gn = gnt;
                f = NAN;
                continue;
            }
        }
        double slope = g[0] * d[0] + g[1] * d[1] + g[2] * d[2];
        if (isnan(f) && !(-slope <= 1e-10 * scale)) f = prox_obj(x, sig, vol, mu, lambda, gamma);
        double ft = INFINITY;
        if (-slope <= 1e-10 * ((isnan(f) ? 0.0 : fabs(f)) + scale)) {
            /* quadratic-convergence region: objective differences are at roundoff level, so
             * Armijo cannot be tested; the full (boundary-safe) Newton step is taken */
            for (int i = 0; i < 3; i++) x[i] += t * d[i];
            f = NAN; /* recomputed only if a later step needs a line search */
            gn = grad(x, sig, vol, mu, lambda, gamma, g, &L);
            continue;
        }
        for (int ls = 0; ls < 40; ls++) {
            for (int i = 0; i < 3; i++) xt[i] = x[i] + t * d[i];
            ft = prox_obj(xt, sig, vol, mu, lambda, gamma);
            if (ft <= f + 1e-4 * t * slope || fabs(ft - f) <= 1e-15 * fabs(f)) break;
            t *= 0.5;
        }
        if (!(ft <= f) && !(fabs(ft - f) <= 1e-15 * fabs(f))) break;
        x[0] = xt[0]; x[1] = xt[1]; x[2] = xt[2];
        f = ft;
        gn = grad(x, sig, vol, mu, lambda, gamma, g, &L);
    }
    out[0] = x[0];
    out[1] = x[1];
    out[2] = x[2];
    return it;
}
