/* nh_prox.h — proximal operator of the Neo-Hookean energy on singular values (local step 1 of the
 * Neo-Hookean ADMM, paper eqs. 11a, 12-15). */
#ifndef DF_ADMM_NH_PROX_H
#define DF_ADMM_NH_PROX_H

/* Lamé parameters from Young's modulus E (Pa) and Poisson ratio nu: mu = E / (2 (1 + nu)),
 * lambda = E nu / ((1 + nu)(1 - 2 nu)). */
void df_admm_lame(double youngs, double poisson, double *mu, double *lambda);

/* Neo-Hookean energy density psi(sigma) = mu/2 (sum sigma_i^2 - 3) - mu ln J + lambda/2 (ln J)^2,
 * J = sigma_0 sigma_1 sigma_2; +INFINITY when J <= 0. */
double df_admm_nh_psi(const double sig[3], double mu, double lambda);

/* out = argmin_x  vol psi(x) + gamma / 2 |x - sig|^2 over x in R^3 with all x_i > 0, for
 * vol > 0, gamma > 0, sig any finite 3-vector (signed singular values). Method: Newton's method
 * on the 3 unknowns (exact Hessian, plus a diagonal shift when it is not positive definite),
 * started from `start` when it is non-NULL with positive finite entries (warm start: the previous
 * ADMM iteration's answer), else from |sig_i| clamped below at 0.03 max(mean |sig|, 1) + 1e-3, with
 * a fraction-to-boundary rule that keeps x_i > 0. A full, unshifted Newton step that at least halves
 * the gradient norm is accepted at once (the Newton region: no objective evaluation, the gradient is
 * the next step's); any other step is safeguarded by Armijo backtracking on the objective (full
 * steps once the Newton decrement is at roundoff level), so it cannot diverge. At most DF_ADMM_NH_MAX_NEWTON steps; stops when the gradient
 * norm is below 1e-13 (vol mu + gamma) (1 + |x|). Returns the number of Newton steps taken, or -1
 * (out untouched) on invalid input. */
#define DF_ADMM_NH_MAX_NEWTON 30
int df_admm_nh_prox(const double sig[3], const double *start, double vol, double mu, double lambda,
                    double gamma, double out[3]);

#endif
