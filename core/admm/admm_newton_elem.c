/* admm_newton_elem.c — per-element derivatives for the polish (admm_newton.h): first Piola stress
 * and Hessian of the tet energy densities, their PSD projection (Teran et al. 2005; Smith et al.
 * 2019's analytic eigensystems for ARAP/ACAP, a 9x9 Jacobi eigen-clamp for Neo-Hookean), the
 * inversion-safe step bound and the objective's gradient. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/admm/admm_newton.h"
#include "core/admm/svd3.h"

/* ---- dense helpers ---- */

/* in-place Cholesky test of a symmetric n x n matrix copy: 1 when positive definite */
static int is_pd(const double *A, int n)
{
    double L[144];
    for (int j = 0; j < n; j++) {
        double d = A[j * n + j];
        for (int k = 0; k < j; k++) d -= L[j * n + k] * L[j * n + k];
        if (!(d > 1e-14 * fabs(A[j * n + j])) || !(d > 0)) return 0;
        double r = sqrt(d);
        L[j * n + j] = r;
        for (int i = j + 1; i < n; i++) {
            double v = A[i * n + j];
            for (int k = 0; k < j; k++) v -= L[i * n + k] * L[j * n + k];
            L[i * n + j] = v / r;
        }
    }
    return 1;
}

int admm_newton_psd_project(double *A, int n)
{
    double Q[144], a[144];
    memcpy(a, A, (size_t)n * n * sizeof(double));
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) Q[i * n + j] = i == j;
    double fro = 0;
    for (int i = 0; i < n * n; i++) fro += a[i] * a[i];
    for (int sweep = 0; sweep < 30; sweep++) {
        double off = 0;
        for (int p = 0; p < n; p++)
            for (int q = p + 1; q < n; q++) off += a[p * n + q] * a[p * n + q];
        if (off <= 1e-32 * fro) break;
        for (int p = 0; p < n; p++)
            for (int q = p + 1; q < n; q++) {
                double apq = a[p * n + q];
                if (fabs(apq) < 1e-300) continue;
                double th = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
                double t = (th >= 0 ? 1.0 : -1.0) / (fabs(th) + sqrt(th * th + 1.0));
                double c = 1.0 / sqrt(t * t + 1.0), sn = t * c;
                for (int k = 0; k < n; k++) { /* columns p, q */
                    double akp = a[k * n + p], akq = a[k * n + q];
                    a[k * n + p] = c * akp - sn * akq;
                    a[k * n + q] = sn * akp + c * akq;
                }
                for (int k = 0; k < n; k++) { /* rows p, q */
                    double apk = a[p * n + k], aqk = a[q * n + k];
                    a[p * n + k] = c * apk - sn * aqk;
                    a[q * n + k] = sn * apk + c * aqk;
                }
                for (int k = 0; k < n; k++) {
                    double qkp = Q[k * n + p], qkq = Q[k * n + q];
                    Q[k * n + p] = c * qkp - sn * qkq;
                    Q[k * n + q] = sn * qkp + c * qkq;
                }
            }
    }
    int neg = 0;
    double lam[12];
    for (int k = 0; k < n; k++) {
        lam[k] = a[k * n + k];
        if (lam[k] < 0) { lam[k] = 0; neg = 1; }
    }
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            double v = 0;
            for (int k = 0; k < n; k++) v += Q[i * n + k] * lam[k] * Q[j * n + k];
            A[i * n + j] = v;
        }
    return neg;
}

/* ---- densities ---- */

/* cofactor matrix: cof(F)_ij = d det F / d F_ij */
static void cof3(const double F[9], double C[9])
{
    C[0] = F[4] * F[8] - F[5] * F[7];
    C[1] = F[5] * F[6] - F[3] * F[8];
    C[2] = F[3] * F[7] - F[4] * F[6];
    C[3] = F[2] * F[7] - F[1] * F[8];
    C[4] = F[0] * F[8] - F[2] * F[6];
    C[5] = F[1] * F[6] - F[0] * F[7];
    C[6] = F[1] * F[5] - F[2] * F[4];
    C[7] = F[2] * F[3] - F[0] * F[5];
    C[8] = F[0] * F[4] - F[1] * F[3];
}

static int neohookean(double mu, double lambda, const double F[9], double P[9], double *H, int project)
{
    double J = admm_det3(F);
    if (!(J > 0)) return -1;
    double C[9], Fit[9]; /* Fit = F^-T = cof(F) / J */
    cof3(F, C);
    for (int k = 0; k < 9; k++) Fit[k] = C[k] / J;
    double lJ = log(J);
    for (int k = 0; k < 9; k++) P[k] = mu * F[k] + (lambda * lJ - mu) * Fit[k];
    if (!H) return 0;
    /* H[(i,j),(l,k)] = mu d_il d_jk + lambda Fit_ij Fit_lk - (lambda ln J - mu) Fit_ik Fit_lj */
    double c = lambda * lJ - mu;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            for (int l = 0; l < 3; l++)
                for (int k = 0; k < 3; k++)
                    H[(3 * i + j) * 9 + 3 * l + k] = (i == l && j == k ? mu : 0.0) +
                        lambda * Fit[3 * i + j] * Fit[3 * l + k] - c * Fit[3 * i + k] * Fit[3 * l + j];
    if (project && !is_pd(H, 9)) return admm_newton_psd_project(H, 9);
    return 0;
}

/* ARAP (1/2 |S - I|^2) and ACAP (1/2 |S - tr S / 3 I|^2) from the signed SVD F = U diag(sg) V^T:
 * dR/dF has eigenvalue 2 / (sg_a + sg_b) on the three twist modes U (e_a e_b^T - e_b e_a^T) V^T /
 * sqrt 2 and 0 elsewhere; ACAP's (tr S)^2 / 6 adds vec(R) vec(R)^T / 3 (in the scaling modes). */
static int rotational(df_admm_energy energy, const double F[9], double P[9], double *H, int project)
{
    double U[9], sg[3], V[9];
    df_admm_svd3(F, U, sg, V);
    double R[9];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) R[3 * r + c] = U[3 * r] * V[3 * c] + U[3 * r + 1] * V[3 * c + 1] + U[3 * r + 2] * V[3 * c + 2];
    double k = energy == DF_ADMM_ACAP ? (sg[0] + sg[1] + sg[2]) / 3.0 : 1.0;
    for (int t = 0; t < 9; t++) P[t] = F[t] - k * R[t];
    if (!H) return 0;
    memset(H, 0, 81 * sizeof(double));
    for (int t = 0; t < 9; t++) H[10 * t] = 1.0;
    if (energy == DF_ADMM_ACAP)
        for (int i = 0; i < 9; i++)
            for (int j = 0; j < 9; j++) H[9 * i + j] -= R[i] * R[j] / 3.0;
    static const int pair[3][2] = {{1, 2}, {0, 2}, {0, 1}};
    int changed = 0;
    for (int t = 0; t < 3; t++) {
        int a = pair[t][0], b = pair[t][1];
        double den = sg[a] + sg[b];
        double lam = 1.0 - (fabs(den) > 1e-300 ? 2.0 * k / den : (k > 0 ? INFINITY : 0.0));
        if (project && lam < 0) { lam = 0; changed = 1; }
        double drop = 1.0 - lam; /* H = I - drop q q^T on this mode */
        if (!isfinite(drop)) drop = 1e300;
        double q[9];
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++)
                q[3 * r + c] = (U[3 * r + a] * V[3 * c + b] - U[3 * r + b] * V[3 * c + a]) * M_SQRT1_2;
        for (int i = 0; i < 9; i++)
            for (int j = 0; j < 9; j++) H[9 * i + j] -= drop * q[i] * q[j];
    }
    return changed;
}

int admm_newton_density(df_admm_energy energy, double mu, double lambda, const double F[9],
                        double P[9], double *H, int project)
{
    if (energy == DF_ADMM_NEOHOOKEAN) return neohookean(mu, lambda, F, P, H, project);
    return rotational(energy, F, P, H, project);
}

/* ---- inversion-safe step ---- */

static double cubic(const double c[4], double t) { return ((c[3] * t + c[2]) * t + c[1]) * t + c[0]; }

double admm_newton_det_step(const double F[9], const double D[9], double tmax)
{
    double CF[9], CD[9], c[4];
    cof3(F, CF);
    cof3(D, CD);
    c[0] = admm_det3(F);
    c[1] = c[2] = 0;
    for (int k = 0; k < 9; k++) { c[1] += CF[k] * D[k]; c[2] += CD[k] * F[k]; }
    c[3] = admm_det3(D);
    if (c[1] >= 0 && c[2] >= 0 && c[3] >= 0) return INFINITY;
    /* split [0, tmax] at the critical points (roots of 3 c3 t^2 + 2 c2 t + c1) */
    double br[4] = {0, tmax, tmax, tmax};
    int nb = 1;
    double A = 3 * c[3], B = 2 * c[2], Cc = c[1];
    double roots[2];
    int nr = 0;
    if (fabs(A) > 0) {
        double disc = B * B - 4 * A * Cc;
        if (disc >= 0) {
            double sq = sqrt(disc), qq = -0.5 * (B + (B >= 0 ? sq : -sq));
            roots[nr++] = qq / A;
            if (qq != 0) roots[nr++] = Cc / qq;
        }
    } else if (B != 0) {
        roots[nr++] = -Cc / B;
    }
    if (nr == 2 && roots[0] > roots[1]) { double x = roots[0]; roots[0] = roots[1]; roots[1] = x; }
    for (int r = 0; r < nr; r++)
        if (roots[r] > 0 && roots[r] < tmax) br[nb++] = roots[r];
    br[nb++] = tmax;
    for (int i = 0; i + 1 < nb; i++) {
        double lo = br[i], hi = br[i + 1];
        if (cubic(c, hi) > 0) continue;
        if (cubic(c, lo) <= 0) return lo; /* (only at a double root: det touches 0) */
        for (int it = 0; it < 200 && hi - lo > 1e-16 * hi; it++) {
            double mid = 0.5 * (lo + hi);
            if (cubic(c, mid) > 0) lo = mid; else hi = mid;
        }
        return lo > 0 ? lo : hi;
    }
    return INFINITY;
}

/* ---- assembly helpers ---- */

void admm_newton_element_F(const df_admm *s, const double *V, int32_t e, double F[9])
{
    const int32_t *el = s->E + (size_t)e * 4;
    const double *g = s->grad + (size_t)e * 12;
    memset(F, 0, 9 * sizeof(double));
    for (int a = 0; a < 4; a++) {
        const double *x = V + 3 * (size_t)el[a];
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++) F[3 * r + c] += x[r] * g[3 * a + c];
    }
}

int admm_newton_gradient(const df_admm *s, const double *V, double *g, double *gl, double *fmag)
{
    double *PE = malloc((size_t)s->ne * 9 * sizeof(double));
    if (!PE) return -2;
    int bad = 0;
    #pragma omp parallel for schedule(static) num_threads(s->nthreads) reduction(| : bad)
    for (int32_t e = 0; e < s->ne; e++) {
        double F[9], *P = PE + 9 * (size_t)e;
        admm_newton_element_F(s, V, e, F);
        if (admm_newton_density(s->p.energy, s->mu, s->lambda, F, P, NULL, 0) < 0) { bad = 1; continue; }
        for (int k = 0; k < 9; k++) P[k] *= s->vol[e];
    }
    if (bad) { free(PE); return -1; }
    double w = s->p.w, sc = s->p.s;
    #pragma omp parallel for schedule(static) num_threads(s->nthreads)
    for (int32_t i = 0; i < s->nv; i++) {
        double gi[3] = {0, 0, 0}, mag = 0;
        for (int32_t p = s->ve_ptr[i]; p < s->ve_ptr[i + 1]; p++) {
            int32_t e = s->ve_ent[p] / 4, a = s->ve_ent[p] % 4;
            const double *P = PE + 9 * (size_t)e, *ga = s->grad + (size_t)e * 12 + 3 * a;
            double t[3];
            for (int r = 0; r < 3; r++) t[r] = P[3 * r] * ga[0] + P[3 * r + 1] * ga[1] + P[3 * r + 2] * ga[2];
            for (int r = 0; r < 3; r++) gi[r] += t[r];
            mag += sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
        }
        double d[3], r2 = 0, lg[3] = {0, 0, 0};
        for (int k = 0; k < 3; k++) { d[k] = V[3 * (size_t)i + k] - s->Vrest[3 * (size_t)i + k]; r2 += d[k] * d[k]; }
        double r = sqrt(r2), wa = w * s->a[i];
        if (wa > 0 && r > 0 && r < sc) {
            double f = wa * (1.0 - r / sc) / r; /* d/dx of wa (r - r^2 / (2 s)) */
            for (int k = 0; k < 3; k++) lg[k] = f * d[k];
            mag += wa * (1.0 - r / sc);
        }
        for (int k = 0; k < 3; k++) {
            if (gl) { g[3 * (size_t)i + k] = gi[k]; gl[3 * (size_t)i + k] = lg[k]; }
            else g[3 * (size_t)i + k] = gi[k] + lg[k];
        }
        if (fmag) fmag[i] = mag;
    }
    free(PE);
    return 0;
}
