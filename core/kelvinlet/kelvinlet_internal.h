/* kelvinlet_internal.h — helpers shared by the core/kelvinlet files (not a public API).
 *
 * Notation: r = x - centre, s = r.r (2D: only x, y), rho_i^2 = s + eps_i^2.
 * Grab load (per unit force f):      u = A(s) f + B(s) (r.f) r
 * Affine load (force matrix F):      u = C1(s) F r + C2(s) S r + C3(s) (r^T F r) r,
 *                                    S = F + F^T + tr(F) I (2D: 2x2 trace and identity).
 * The multi-scale weights are folded into A, B, C1..C3. */
#ifndef DF_KELVINLET_INTERNAL_H
#define DF_KELVINLET_INTERNAL_H

#include "core/kelvinlet/kelvinlet.h"

/* The arithmetic version brush b asks for (its arith, or DF_KELVINLET_ARITH_CURRENT for 0). */
static inline int dfk_arith(const df_kelvinlet_brush *b)
{
    return b->arith ? b->arith : DF_KELVINLET_ARITH_CURRENT;
}

/* 1 if x is finite. */
int dfk_finite(double x);

/* 1 if all n values are finite. */
int dfk_all_finite(const double *v, size_t n);

/* Checks nu (finite in [NU_MIN, NU_MAX] or +-inf) and fills k (a = 1, b, eps, w). Errors:
 * DF_EINVAL with a message; k untouched then. */
int dfk_kernel_init(df_kelvinlet_kernel *k, int dim, int order, double radius, double ratio,
                    double nu, df_error *err);

/* Grab coefficients A, B at squared distance s. */
void dfk_grab_coeffs(const df_kelvinlet_kernel *k, double s, double *A, double *B);

/* Affine coefficients C[3] at squared distance s and, if dC != NULL, their derivatives d/ds. */
void dfk_affine_coeffs(const df_kelvinlet_kernel *k, double s, double *C, double *dC);

/* u(centre) per unit force of a grab load: u(0) = kappa f (kappa may be ~0 in 2D). */
double dfk_grab_tip_scale(const df_kelvinlet_kernel *k);

/* grad u(centre) of an affine load: G = sigma (alpha F + beta S) with the returned
 * alpha, beta, sigma (3D: -5a/2, b, sum w/eps^3; 2D: -4a, 2b, sum w/eps^2). */
void dfk_affine_gradient_map(const df_kelvinlet_kernel *k, double *alpha, double *beta,
                             double *sigma);

/* Displacement at x of one load (adds into u[3]). */
void dfk_source_eval_add(const df_kelvinlet_kernel *k, const df_kelvinlet_source *src,
                         const double *x, double *u);

/* Gradient at x of one load (adds into g[9]). */
void dfk_source_grad_add(const df_kelvinlet_kernel *k, const df_kelvinlet_source *src,
                         const double *x, double *g);

/* The loads of a prepared field. */
const df_kelvinlet_source *dfk_sources(const df_kelvinlet_prepared *p);

/* Sanity check of a prepared field before evaluation (DF_EINVAL if malformed). */
int dfk_check_prepared(const df_kelvinlet_prepared *p, df_error *err);

/* Solves the m x m system A x = b (A row-major, destroyed; b overwritten by x) with partial
 * pivoting. Returns DF_ESINGULAR when a pivot is below tol * max|A|. */
int dfk_small_solve(int m, double *A, double *b, double tol);

/* Moving brushes: fills *fields (malloc'ed, p->brush.steps entries, free with free()) with the
 * substep fields (centre advected by k/N of the stroke, force of tip/N or gradient/N);
 * *fields = NULL for stationary brushes. Errors: DF_ENOMEM, DF_ESINGULAR, DF_EINVAL. */
int dfk_moving_substeps(const df_kelvinlet_prepared *p, df_kelvinlet_prepared **fields,
                        df_error *err);

/* 1 if all n*3 floats are finite and within DF_KELVINLET_MAX_VALUE (scan on up to nthreads
 * OpenMP threads). */
int dfk_points_ok_f(const float *xyz, size_t n, int nthreads, size_t *bad);

/* OpenBLAS on the calling thread between begin and end (nestable, thread-safe; the previous
 * process-wide OpenBLAS thread count is restored by the outermost end). */
void dfk_blas_serial_begin(void);
void dfk_blas_serial_end(void);

/* LU with partial pivoting of the m x m column-major matrix a (overwritten by L and U) into
 * ipiv[m] (1-based, LAPACK dgetrf's layout and meaning), on up to nthreads OpenMP threads with
 * OpenBLAS on one thread (kelvinlet_lu.c); the same bits for any nthreads. Returns 0, or i > 0
 * when U(i, i) is exactly zero (as dgetrf: the factorization is completed). */
int dfk_lu_factor(int m, double *a, int *ipiv, int nthreads);

#endif
