/* nh_spectral.h — Neo-Hookean proximal operator on a symmetric stretch matrix (local step 1 of the
 * Neo-Hookean ADMM for a well-conditioned element), by a warm-started, loosely converged Jacobi
 * eigen-decomposition plus the exact first-order (Daleckii-Krein) correction of the remaining
 * off-diagonal part. */
#ifndef DF_ADMM_NH_SPECTRAL_H
#define DF_ADMM_NH_SPECTRAL_H

/* Jacobi stops once the off-diagonal part of Q^T S Q is below this fraction of its diagonal (norms);
 * the first-order correction then leaves an error of order DF_ADMM_NH_SPECTRAL_OFF^2 relative. */
#define DF_ADMM_NH_SPECTRAL_OFF 1e-6

/* X = argmin over symmetric positive definite X of vol psi(eig X) + gamma / 2 |X - S|_F^2 (psi the
 * Neo-Hookean density of nh_prox.h on the eigenvalues), for S symmetric 3x3 row-major (the
 * symmetric part is used) with vol, gamma, mu > 0, lambda >= 0. X = Q (diag(x) + G o E) Q^T where
 * Q^T S Q = diag(l) + E after cyclic Jacobi sweeps from the warm start Q until
 * |E| <= DF_ADMM_NH_SPECTRAL_OFF |diag(l)|, x = df_admm_nh_prox(l) warm-started from xw, and
 * G_ij = (x_i - x_j) / (l_i - l_j) in the closed form gamma / (gamma + vol (mu + (mu - lambda ln J)
 * / (x_i x_j))) (J = x_0 x_1 x_2; exact for the prox, also when l_i = l_j). When a G_ij falls outside
 * [0, 1] (non-convex prox) the sweeps continue to full accuracy and no correction is applied.
 * In/out: Q (3x3 rotation, columns = eigenvectors; any rotation, e.g. identity, on the first call),
 * xw (3 warm-start stretches, ignored unless all positive and finite; the answer's x on exit).
 * Out: X (3x3 row-major, symmetric). Returns the Newton steps of the prox, or -1 (X, Q, xw
 * untouched) on invalid input. */
int df_admm_nh_prox_sym(const double S[9], double Q[9], double xw[3], double vol, double mu,
                        double lambda, double gamma, double X[9]);

#endif
