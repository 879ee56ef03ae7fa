/* svd3.c — signed 3x3 SVD, 3x2 SVD and symmetric 3x3 eigen-decomposition (see svd3.h).
 *
 * Eigen: cyclic Jacobi rotations (robust for repeated eigenvalues, converges quadratically; at most
 * 12 sweeps, typically 3-4). SVD: eigenvectors V of A^T A, then B = A V = U T orthogonalized by
 * Gram-Schmidt on the two largest columns and a cross product for the third, which gives det U = +1
 * and the sign of the smallest singular value for free. */
#include "core/admm/svd3.h"

#include <math.h>
#include <string.h>

#define SVD3_MAX_SWEEPS 12

/* cyclic Jacobi on the symmetric a (in place), accumulating the rotations into v */
static void jacobi3(double a[3][3], double v[3][3], double tol2)
{
    for (int sweep = 0; sweep < SVD3_MAX_SWEEPS; sweep++) {
        double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        double dia = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        /* off-diagonal below sqrt(tol2) of the diagonal (relative, in norm): converged */
        if (off <= tol2 * dia || off == 0.0) break;
        for (int p = 0; p < 2; p++) {
            for (int q = p + 1; q < 3; q++) {
                double apq = a[p][q];
                if (apq == 0.0) continue;
                double theta = (a[q][q] - a[p][p]) / (2.0 * apq);
                double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
                double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
                for (int k = 0; k < 3; k++) { /* A <- J^T A J */
                    double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < 3; k++) {
                    double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                a[p][q] = a[q][p] = 0.0; /* exactly annihilated by construction */
                for (int k = 0; k < 3; k++) {
                    double vkp = v[k][p], vkq = v[k][q];
                    v[k][p] = c * vkp - s * vkq;
                    v[k][q] = s * vkp + c * vkq;
                }
            }
        }
    }
}

void df_admm_sym3_eig_warm(const double C[9], double lam[3], double Q[9])
{
    double a[3][3], v[3][3], T[3][3];
    /* a = Q^T C Q */
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            T[i][j] = C[3 * i] * Q[j] + C[3 * i + 1] * Q[3 + j] + C[3 * i + 2] * Q[6 + j];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            a[i][j] = Q[i] * T[0][j] + Q[3 + i] * T[1][j] + Q[6 + i] * T[2][j];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) v[i][j] = Q[3 * i + j];
    a[1][0] = a[0][1] = 0.5 * (a[0][1] + a[1][0]);
    a[2][0] = a[0][2] = 0.5 * (a[0][2] + a[2][0]);
    a[2][1] = a[1][2] = 0.5 * (a[1][2] + a[2][1]);
    jacobi3(a, v, 1e-30);
    for (int i = 0; i < 3; i++) lam[i] = a[i][i];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) Q[3 * i + j] = v[i][j];
}

void df_admm_sym3_eig(const double C[9], double lam[3], double Q[9])
{
    double a[3][3] = {{C[0], C[1], C[2]}, {C[1], C[4], C[5]}, {C[2], C[5], C[8]}};
    double v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    jacobi3(a, v, 1e-30);
    int idx[3] = {0, 1, 2};
    double d[3] = {a[0][0], a[1][1], a[2][2]};
    for (int i = 0; i < 2; i++)
        for (int j = i + 1; j < 3; j++)
            if (d[idx[j]] > d[idx[i]]) { int t = idx[i]; idx[i] = idx[j]; idx[j] = t; }
    for (int i = 0; i < 3; i++) lam[i] = d[idx[i]];
    if (Q) {
        for (int k = 0; k < 3; k++)
            for (int i = 0; i < 3; i++) Q[3 * k + i] = v[k][idx[i]];
        double det = Q[0] * (Q[4] * Q[8] - Q[5] * Q[7]) - Q[1] * (Q[3] * Q[8] - Q[5] * Q[6]) +
                     Q[2] * (Q[3] * Q[7] - Q[4] * Q[6]);
        if (det < 0) { Q[2] = -Q[2]; Q[5] = -Q[5]; Q[8] = -Q[8]; }
    }
}

/* any unit vector perpendicular to unit u */
static void perp_unit(const double u[3], double out[3])
{
    double ax = fabs(u[0]), ay = fabs(u[1]), az = fabs(u[2]);
    double e[3] = {0, 0, 0};
    if (ax <= ay && ax <= az) e[0] = 1; else if (ay <= az) e[1] = 1; else e[2] = 1;
    out[0] = u[1] * e[2] - u[2] * e[1];
    out[1] = u[2] * e[0] - u[0] * e[2];
    out[2] = u[0] * e[1] - u[1] * e[0];
    double n = sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2]);
    out[0] /= n; out[1] /= n; out[2] /= n;
}

void df_admm_svd3(const double A[9], double U[9], double sig[3], double V[9])
{
    double C[9];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            C[3 * i + j] = A[i] * A[j] + A[3 + i] * A[3 + j] + A[6 + i] * A[6 + j];
    double lam[3], Q[9];
    df_admm_sym3_eig(C, lam, Q);
    double B[9]; /* B = A Q */
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            B[3 * i + j] = A[3 * i] * Q[j] + A[3 * i + 1] * Q[3 + j] + A[3 * i + 2] * Q[6 + j];
    double u1[3] = {B[0], B[3], B[6]}, b2[3] = {B[1], B[4], B[7]}, b3[3] = {B[2], B[5], B[8]};
    double n1 = sqrt(u1[0] * u1[0] + u1[1] * u1[1] + u1[2] * u1[2]);
    double scale = n1 > 0 ? n1 : 1.0;
    if (n1 <= 1e-300) { u1[0] = 1; u1[1] = 0; u1[2] = 0; n1 = 0.0; }
    else { u1[0] /= n1; u1[1] /= n1; u1[2] /= n1; }
    double d12 = u1[0] * b2[0] + u1[1] * b2[1] + u1[2] * b2[2];
    double u2[3] = {b2[0] - d12 * u1[0], b2[1] - d12 * u1[1], b2[2] - d12 * u1[2]};
    double n2 = sqrt(u2[0] * u2[0] + u2[1] * u2[1] + u2[2] * u2[2]);
    if (n2 <= 1e-15 * scale) perp_unit(u1, u2);
    else { u2[0] /= n2; u2[1] /= n2; u2[2] /= n2; }
    double u3[3] = {u1[1] * u2[2] - u1[2] * u2[1], u1[2] * u2[0] - u1[0] * u2[2],
                    u1[0] * u2[1] - u1[1] * u2[0]};
    sig[0] = n1;
    sig[1] = u2[0] * b2[0] + u2[1] * b2[1] + u2[2] * b2[2];
    sig[2] = u3[0] * b3[0] + u3[1] * b3[1] + u3[2] * b3[2];
    if (U) {
        for (int k = 0; k < 3; k++) { U[3 * k] = u1[k]; U[3 * k + 1] = u2[k]; U[3 * k + 2] = u3[k]; }
    }
    if (V)
        for (int k = 0; k < 9; k++) V[k] = Q[k];
}

void df_admm_svd32(const double F[6], double U[6], double sig[2], double V[4])
{
    /* C = F^T F (2x2) */
    double a = F[0] * F[0] + F[2] * F[2] + F[4] * F[4];
    double b = F[0] * F[1] + F[2] * F[3] + F[4] * F[5];
    double d = F[1] * F[1] + F[3] * F[3] + F[5] * F[5];
    double th = 0.5 * atan2(2.0 * b, a - d); /* eigenvector angle of the largest eigenvalue */
    double c = cos(th), s = sin(th);
    double v1[2] = {c, s}, v2[2] = {-s, c};
    double b1[3], bb2[3];
    for (int k = 0; k < 3; k++) {
        b1[k] = F[2 * k] * v1[0] + F[2 * k + 1] * v1[1];
        bb2[k] = F[2 * k] * v2[0] + F[2 * k + 1] * v2[1];
    }
    double n1 = sqrt(b1[0] * b1[0] + b1[1] * b1[1] + b1[2] * b1[2]);
    double u1[3], u2[3];
    if (n1 <= 1e-300) { u1[0] = 1; u1[1] = 0; u1[2] = 0; n1 = 0; }
    else for (int k = 0; k < 3; k++) u1[k] = b1[k] / n1;
    double dd = u1[0] * bb2[0] + u1[1] * bb2[1] + u1[2] * bb2[2];
    for (int k = 0; k < 3; k++) u2[k] = bb2[k] - dd * u1[k];
    double n2 = sqrt(u2[0] * u2[0] + u2[1] * u2[1] + u2[2] * u2[2]);
    if (n2 <= 1e-15 * (n1 > 0 ? n1 : 1.0)) { perp_unit(u1, u2); n2 = 0; }
    else for (int k = 0; k < 3; k++) u2[k] /= n2;
    sig[0] = n1;
    sig[1] = n2;
    if (U)
        for (int k = 0; k < 3; k++) { U[2 * k] = u1[k]; U[2 * k + 1] = u2[k]; }
    if (V) { V[0] = v1[0]; V[1] = v2[0]; V[2] = v1[1]; V[3] = v2[1]; }
}

/* largest root t of (t^2 - I1)^2 - 4 I2 - 8 J t (Newton from sqrt(3 I1)); C = A^T A packed */
static double trace_root(const double A[9], double C[6], double *I1o, double *Jo)
{
    C[0] = A[0] * A[0] + A[3] * A[3] + A[6] * A[6];
    C[1] = A[0] * A[1] + A[3] * A[4] + A[6] * A[7];
    C[2] = A[0] * A[2] + A[3] * A[5] + A[6] * A[8];
    C[3] = A[1] * A[1] + A[4] * A[4] + A[7] * A[7];
    C[4] = A[1] * A[2] + A[4] * A[5] + A[7] * A[8];
    C[5] = A[2] * A[2] + A[5] * A[5] + A[8] * A[8];
    double I1 = C[0] + C[3] + C[5];
    double I2 = C[0] * C[3] + C[0] * C[5] + C[3] * C[5] - C[1] * C[1] - C[2] * C[2] - C[4] * C[4];
    double J = A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) +
               A[2] * (A[3] * A[7] - A[4] * A[6]);
    *I1o = I1;
    *Jo = J;
    if (!(I1 > 0)) return 0.0;
    double t = sqrt(3.0 * I1);
    for (int it = 0; it < 60; it++) {
        double q = t * t - I1;
        double f = q * q - 4.0 * I2 - 8.0 * J * t;
        double fp = 4.0 * t * q - 8.0 * J;
        if (!(fp > 0)) break;
        double dt = f / fp;
        t -= dt;
        /* quadratic convergence from above: after a step of 1e-9 t the error is ~1e-18 t */
        if (fabs(dt) <= 1e-9 * t) break;
    }
    return t;
}

/* the invariant formulas lose accuracy near rank deficiency; use them only when well conditioned */
#define TRACE_MIN_DET_REL 0.05

double df_admm_trace_sym3(const double A[9])
{
    double C[6], I1, J;
    double t = trace_root(A, C, &I1, &J);
    if (J >= TRACE_MIN_DET_REL * (I1 / 3.0) * sqrt(I1 / 3.0) && I1 > 0) return t;
    double sg[3];
    df_admm_svd3(A, NULL, sg, NULL);
    return sg[0] + sg[1] + sg[2];
}

int df_admm_polar3(const double A[9], double R[9])
{
    double C[6], I1, J;
    double t = trace_root(A, C, &I1, &J);
    if (!(I1 > 0) || !(J >= TRACE_MIN_DET_REL * (I1 / 3.0) * sqrt(I1 / 3.0))) return -1;
    /* Cayley-Hamilton for S = sqrt(C): S (C + i2 I) = i1 C + i3 I, so R = A (C + i2 I) (t C + J I)^-1 */
    double i2 = 0.5 * (t * t - I1);
    double P[9] = {C[0] + i2, C[1], C[2], C[1], C[3] + i2, C[4], C[2], C[4], C[5] + i2};
    double Q[9] = {t * C[0] + J, t * C[1], t * C[2], t * C[1], t * C[3] + J, t * C[4], t * C[2], t * C[4], t * C[5] + J};
    double c0 = Q[4] * Q[8] - Q[5] * Q[7], c1 = Q[5] * Q[6] - Q[3] * Q[8], c2 = Q[3] * Q[7] - Q[4] * Q[6];
    double det = Q[0] * c0 + Q[1] * c1 + Q[2] * c2;
    if (!(det > 0)) return -1;
    double Qi[9] = {c0, Q[2] * Q[7] - Q[1] * Q[8], Q[1] * Q[5] - Q[2] * Q[4],
                    c1, Q[0] * Q[8] - Q[2] * Q[6], Q[2] * Q[3] - Q[0] * Q[5],
                    c2, Q[1] * Q[6] - Q[0] * Q[7], Q[0] * Q[4] - Q[1] * Q[3]};
    double M[9]; /* P Q^-1 */
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            M[3 * i + j] = (P[3 * i] * Qi[j] + P[3 * i + 1] * Qi[3 + j] + P[3 * i + 2] * Qi[6 + j]) / det;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            R[3 * i + j] = A[3 * i] * M[j] + A[3 * i + 1] * M[3 + j] + A[3 * i + 2] * M[6 + j];
    return 0;
}
