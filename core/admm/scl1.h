/* scl1.h — the SC-L1 ("smoothly clamped group l1") loss and its proximal operator
 * (Chen, Zheng & Wampler 2023, eq. 1 and supplement eqs. 7-9, with a weight). */
#ifndef DF_ADMM_SCL1_H
#define DF_ADMM_SCL1_H

/* ||x||_SC-L1 for a 3-vector x and threshold s > 0 (length units):
 * |x| - |x|^2 / (2 s) when |x| < s, s / 2 otherwise. Returns NaN for s <= 0. */
double df_admm_scl1_value(const double x[3], double s);

/* Proximal operator: out = argmin_z  wa ||z||_SC-L1 + rho / 2 |z - x|^2  (global minimizer), for
 * wa >= 0 (the weight w a_i), s > 0, rho > 0. Convex regime rho s > wa: the shrinkage of
 * supplement eq. 9, ((rho s - wa s / |x|) / (rho s - wa))_+ x for |x| <= s, x beyond. Nonconvex
 * regime rho s <= wa: the better of the two candidates 0 and max(s, |x|) x / |x| (ties -> 0, the
 * paper's preference for the origin). `out` may alias `x`. Returns 0, or -1 (out untouched) for
 * invalid wa, s or rho. */
int df_admm_scl1_prox(const double x[3], double wa, double s, double rho, double out[3]);

#endif
