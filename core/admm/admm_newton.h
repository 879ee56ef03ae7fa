/* admm_newton.h — private pieces of the second-order polish (df_admm_polish, admm.h): per-element
 * first and second derivatives of the tet energies with respect to the deformation gradient, their
 * projection to positive semi-definite, the inversion-safe step bound, and the objective's
 * gradient. Not part of the public API. Row-major 3x3 F; the 9-vector vec(F) is F's row-major
 * entries (index 3 r + c). Thread: pure functions, safe inside OpenMP loops. */
#ifndef DF_ADMM_NEWTON_H
#define DF_ADMM_NEWTON_H

#include "core/admm/admm_internal.h"

/* Energy density derivatives of element energy `energy` (DF_ADMM_NEOHOOKEAN, DF_ADMM_ARAP,
 * DF_ADMM_ACAP; per unit rest volume, i.e. without vol_e) at F: P (9) = dPsi/dF and, when H is
 * not NULL, H (9 x 9 row-major) = d2Psi/dF2, the exact Hessian (project = 0) or its projection to
 * the nearest PSD matrix (project = 1: eigenvalues clamped at 0). Neo-Hookean needs det F > 0
 * (returns -1 otherwise, P/H untouched); mu, lambda its Lame parameters. Returns 0, or 1 when the
 * projection changed H (some eigenvalue was negative), -1 on an inverted Neo-Hookean F. */
int admm_newton_density(df_admm_energy energy, double mu, double lambda, const double F[9],
                        double P[9], double *H, int project);

/* Given det F > 0: the smallest t in (0, tmax] with det(F + t D) = 0 (the first step length that
 * inverts the element along D), or +INFINITY when det(F + t D) > 0 on all of [0, tmax]. Exact
 * cubic det F + t tr(adj F D) + t^2 tr(adj D F) + t^3 det D, root by bisection on its monotone
 * pieces (relative accuracy ~1e-15). */
double admm_newton_det_step(const double F[9], const double D[9], double tmax);

/* Symmetric n x n (n <= 12, row-major) eigen-decomposition by cyclic Jacobi: A is overwritten by
 * the clamped reconstruction Q diag(max(lam, 0)) Q^T. Returns 1 when an eigenvalue was negative. */
int admm_newton_psd_project(double *A, int n);

/* Deformation gradient of kept element e at positions V (tets: F = sum_a x_a g_a^T). */
void admm_newton_element_F(const df_admm *s, const double *V, int32_t e, double F[9]);

/* Gradient of the polish objective (elastic + locality, admm.h) at V: g (nv x 3) receives the
 * elastic gradient plus, when gl is NULL, the locality gradient (0 at V_i = Vrest_i); when gl is not
 * NULL the locality gradient goes there instead (nv x 3). fmag (nv, may be NULL) receives per vertex
 * the sum of the magnitudes of the per-term gradient contributions (element terms and the locality
 * term): the scale of the KKT residual. Returns 0, -1 when a Neo-Hookean element is inverted, -2 when out
 * of memory (an ne x 9 work buffer). Handles and followers get their gradient like any vertex. */
int admm_newton_gradient(const df_admm *s, const double *V, double *g, double *gl, double *fmag);

/* ---- the polish's sparse Newton system (admm_newton_sys.c) ---- */

/* Cache kept in the solver across polishes (s->polish): CHOLMOD state, the support it was
 * analyzed for, the upper-triangle pattern of the 3n x 3n Hessian on it and its symbolic factor,
 * and the per-vertex projectors onto the null space of the affine rows. */
typedef struct admm_polish_cache {
    cholmod_common cc;
    int started;
    int32_t n;               /* support vertices of the cached pattern */
    int32_t *sup;            /* n: support vertex ids (ascending) */
    int32_t *sidx;           /* nv: support index or -1 */
    cholmod_sparse *H;       /* 3n x 3n, stype 1 (upper), sorted columns */
    cholmod_factor *L;
    int32_t *pidx;           /* nv: index into Pv of the vertex's projector, -1 when unconstrained */
    double *Pv;              /* 9 per affine vertex: I - sum of q q^T over its orthonormalized rows */
    double *Pres;            /* per affine vertex: |A Vrest - b| max over its rows (rest feasible?) */
    int32_t npv;
} admm_polish_cache;

/* Creates s->polish when missing (CHOLMOD started, affine projectors built). DF_ENOMEM. */
int admm_pn_cache(df_admm *s, df_error *err);

/* Makes the cached pattern and symbolic factor those of support sup[0..n-1] (ascending); reuses
 * them when the support is unchanged. *analyses is incremented when it analyzes. */
int admm_pn_prepare(df_admm *s, const int32_t *sup, int32_t n, long *analyses, df_error *err);

/* Assembles the Newton matrix on the prepared support at V (the model of df_admm_polish:
 * project = 0 exact, 1 projected), affine blocks projected, plus shift * I. Returns 0, or -1 when
 * out of memory (a work buffer). */
int admm_pn_assemble(df_admm *s, const double *V, int project, double shift);

/* Numeric factorization: *pd = 1 when positive definite. DF_EINTERNAL on a CHOLMOD failure. */
int admm_pn_factor(df_admm *s, int *pd, df_error *err);

/* Solves H x = b (3n) with the current factor. DF_EINTERNAL / DF_ENOMEM. */
int admm_pn_solve(df_admm *s, const double *b, double *x, df_error *err);

/* Applies vertex i's affine projector to v (3) in place (nothing for unconstrained vertices). */
void admm_pn_project(const df_admm *s, int32_t i, double v[3]);

#endif
