/* svd3.h — small dense decompositions for the per-element local steps: signed 3x3 SVD (polar
 * rotation and stretches), 3x2 SVD (cloth), symmetric 3x3 eigenvalues. Closed-form / fixed-cost
 * routines (cyclic Jacobi on 3x3), no LAPACK call, safe to run inside OpenMP loops. All matrices
 * are row-major. */
#ifndef DF_ADMM_SVD3_H
#define DF_ADMM_SVD3_H

/* Warm-started eigen-decomposition of a symmetric 3x3 C: on entry Q is a rotation close to C's
 * eigenvectors (e.g. the previous call's), on exit C = Q diag(lam) Q^T (columns of Q, unsorted,
 * order kept from the warm start). Cyclic Jacobi on Q^T C Q: one or two sweeps when the start is
 * good, at most 12. */
void df_admm_sym3_eig_warm(const double C[9], double lam[3], double Q[9]);

/* Signed SVD A = U diag(sig) V^T of a 3x3 matrix with det U = det V = +1 (proper rotations),
 * |sig[0]| >= |sig[1]| >= |sig[2]|, sig[0], sig[1] >= 0 and sig[2] < 0 exactly when det A < 0.
 * The polar rotation of A is R = U V^T and its symmetric factor S = V diag(sig) V^T (A = R S).
 * Any of U, V may be NULL when not needed. Accuracy ~1e-15 relative to |A|. */
void df_admm_svd3(const double A[9], double U[9], double sig[3], double V[9]);

/* SVD of a 3x2 matrix F (3 rows, 2 columns, row-major): F = U diag(sig) V^T with U 3x2
 * orthonormal columns (row-major 3x2), V 2x2 rotation (row-major), sig[0] >= sig[1] >= 0. */
void df_admm_svd32(const double F[6], double U[6], double sig[2], double V[4]);

/* Eigen-decomposition of a symmetric 3x3 matrix C (upper triangle read): C = Q diag(lam) Q^T,
 * lam descending, Q a proper rotation (columns = eigenvectors). Q may be NULL. */
void df_admm_sym3_eig(const double C[9], double lam[3], double Q[9]);

/* Sum of the signed singular values of A (tr S, S its symmetric polar factor; the smallest singular
 * value counts negative when det A < 0) from the invariants of A^T A: the largest root of
 * (t^2 - I1)^2 - 4 I2 - 8 J t = 0, found by Newton's method from sqrt(3 I1) (monotone, quadratic),
 * ~40 flops; falls back to df_admm_svd3 when det A < 0.05 (|A|_F^2 / 3)^(3/2). */
double df_admm_trace_sym3(const double A[9]);

/* Polar rotation R of a well-conditioned 3x3 matrix A (A = R S, S symmetric positive definite)
 * in closed form: S's trace t from df_admm_trace_sym3's quartic, then by Cayley-Hamilton
 * R = A (C + i2 I) (t C + det A I)^-1 with C = A^T A, i2 = (t^2 - |A|^2) / 2. ~150 flops, accuracy
 * ~1e-15. Returns 0 with R filled, or -1 (R untouched) when det A < 0.05 (|A|_F^2 / 3)^(3/2)
 * (inverted, nearly singular or strongly anisotropic: callers then use df_admm_svd3). */
int df_admm_polar3(const double A[9], double R[9]);

#endif
