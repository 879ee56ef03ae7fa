/* nh_spectral.c — Neo-Hookean prox on a symmetric stretch matrix (see nh_spectral.h). */
#include "core/admm/nh_spectral.h"

#include <math.h>
#include <string.h>

#include "core/admm/nh_prox.h"

#define NH_SPECTRAL_MAX_SWEEPS 12
/* full-accuracy stopping rule (relative, squared) used when no correction can be applied */
#define NH_SPECTRAL_TIGHT2 1e-30

/* one Jacobi rotation annihilating a[p][q] of the symmetric a (both triangles kept), accumulated
 * into the columns p, q of v */
static inline void rotate(double a[3][3], double v[3][3], int p, int q, double skip2)
{
    double apq = a[p][q];
    if (apq * apq <= skip2) return;
    double theta = (a[q][q] - a[p][p]) / (2.0 * apq);
    double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
    double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
    int r = 3 - p - q; /* the third index */
    double arp = a[r][p], arq = a[r][q];
    a[p][p] -= t * apq;
    a[q][q] += t * apq;
    a[r][p] = a[p][r] = c * arp - s * arq;
    a[r][q] = a[q][r] = s * arp + c * arq;
    a[p][q] = a[q][p] = 0.0;
    for (int k = 0; k < 3; k++) {
        double vkp = v[k][p], vkq = v[k][q];
        v[k][p] = c * vkp - s * vkq;
        v[k][q] = s * vkp + c * vkq;
    }
}

static void sweeps(double a[3][3], double v[3][3], double tol2)
{
    for (int sw = 0; sw < NH_SPECTRAL_MAX_SWEEPS; sw++) {
        double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        double dia = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        if (off <= tol2 * dia || off == 0.0) return;
        /* pairs already far below the target are left alone (the sweep test above still decides) */
        double skip2 = 0.1 * tol2 * dia;
        rotate(a, v, 0, 1, skip2);
        rotate(a, v, 0, 2, skip2);
        rotate(a, v, 1, 2, skip2);
    }
}

int df_admm_nh_prox_sym(const double S[9], double Q[9], double xw[3], double vol, double mu,
                        double lambda, double gamma, double X[9])
{
    double a[3][3], v[3][3], T[3][3], Ss[9];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) Ss[3 * i + j] = 0.5 * (S[3 * i + j] + S[3 * j + i]);
    for (int k = 0; k < 9; k++)
        if (!isfinite(Ss[k]) || !isfinite(Q[k])) return -1;
    /* a = Q^T S Q */
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            T[i][j] = Ss[3 * i] * Q[j] + Ss[3 * i + 1] * Q[3 + j] + Ss[3 * i + 2] * Q[6 + j];
    for (int i = 0; i < 3; i++)
        for (int j = i; j < 3; j++)
            a[i][j] = a[j][i] = Q[i] * T[0][j] + Q[3 + i] * T[1][j] + Q[6 + i] * T[2][j];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) v[i][j] = Q[3 * i + j];
    sweeps(a, v, DF_ADMM_NH_SPECTRAL_OFF * DF_ADMM_NH_SPECTRAL_OFF);
    double l[3] = {a[0][0], a[1][1], a[2][2]}, x[3];
    int steps = df_admm_nh_prox(l, xw, vol, mu, lambda, gamma, x);
    if (steps < 0) return -1;
    double M[3][3] = {{x[0], 0, 0}, {0, x[1], 0}, {0, 0, x[2]}};
    double L = log(x[0] * x[1] * x[2]);
    int ok = 1;
    for (int i = 0; i < 2 && ok; i++)
        for (int j = i + 1; j < 3; j++) {
            if (a[i][j] == 0.0) continue;
            double g = gamma / (gamma + vol * (mu + (mu - lambda * L) / (x[i] * x[j])));
            if (!(g >= 0.0 && g <= 1.0)) { ok = 0; break; }
            M[i][j] = M[j][i] = g * a[i][j];
        }
    if (!ok) {
        /* non-convex prox: no first-order shortcut; converge the eigenvectors fully */
        sweeps(a, v, NH_SPECTRAL_TIGHT2);
        l[0] = a[0][0]; l[1] = a[1][1]; l[2] = a[2][2];
        steps = df_admm_nh_prox(l, x, vol, mu, lambda, gamma, x);
        if (steps < 0) return -1;
        memset(M, 0, sizeof(M));
        M[0][0] = x[0]; M[1][1] = x[1]; M[2][2] = x[2];
    }
    /* X = v M v^T */
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) T[i][j] = v[i][0] * M[0][j] + v[i][1] * M[1][j] + v[i][2] * M[2][j];
    for (int i = 0; i < 3; i++)
        for (int j = i; j < 3; j++)
            X[3 * i + j] = X[3 * j + i] = T[i][0] * v[j][0] + T[i][1] * v[j][1] + T[i][2] * v[j][2];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) Q[3 * i + j] = v[i][j];
    memcpy(xw, x, sizeof(x));
    return steps;
}
