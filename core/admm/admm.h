/* admm.h — SC-L1 local deformation engine: three-block ADMM (Chen, Zheng & Wampler 2023).
 *
 * Minimizes   E_elastic(V) + sum_i w a_i ||V_i - Vrest_i||_SC-L1
 * subject to  V_h = p_h for every handle h            (position constraints, eq. 2b)
 *             A_k V_t = b_k for every t in S_k          (affine constraints on vertex sets, eq. 2c)
 * with ||x||_SC-L1 = |x| - |x|^2 / (2 s) for |x| < s, s / 2 beyond (paper eq. 1).
 *
 * Energies (df_admm_energy) and the mesh kinds they accept:
 *   ARAP       triangles (2D or surface): per-vertex "spokes and rims" ARAP with cotangent weights,
 *              E = sum_i sum_(j,k) w_jk / 2 |R_i (Vrest_k - Vrest_j) - (V_k - V_j)|^2;
 *              tets: per element E = sum_e vol_e / 2 |S_e - I|_F^2, S_e the symmetric polar factor
 *              of the deformation gradient F_e (the paper's released code).
 *   ACAP       triangles: spokes-and-rims with a per-vertex analytic scale s_i (supplement sec. 5);
 *              tets: per element E = sum_e vol_e / 2 |S_e - (tr S_e / 3) I|_F^2 (analytic scale).
 *   NEOHOOKEAN tets only: E = sum_e vol_e (mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2).
 *   CLOTH      triangles in 3D: per-triangle ARAP (area_e / 2 |S_e - I|^2, F_e 3x2) with hard strain
 *              limits on the singular values of the element's symmetric factor, plus the quadratic
 *              bending energy bending / 2 tr(V^T Q V), Q = L^T M^-1 L (Bergou et al. 2006 for flat
 *              rest shapes; L cotangent Laplacian, M lumped areas of the rest mesh).
 *   POLYLINE   segment meshes: per-vertex ARAP over incident segments with uniform weights.
 * Per-element energies use the WRAPD splitting F_e(V) = R_e X_e (X_e symmetric) with the scaled dual
 * W_e and the element penalty weight gamma_e = vol_e (ARAP, ACAP, CLOTH: area) or
 * (2.0066 mu + 1.0122 lambda) vol_e (Neo-Hookean); the global matrix is
 * sum_e gamma_e D_e^T D_e + rho I (per-vertex energies: their spokes-and-rims Laplacian + rho I).
 * Local step 1 per element: polar rotation R of F_e + W_e (closed form, signed SVD fallback for
 * inverted or ill-conditioned elements); ARAP/ACAP/cloth then have closed-form X; Neo-Hookean solves
 * the prox of its energy on the 3 stretches by safeguarded Newton (core/admm/nh_prox.h: exact
 * Hessian, positivity kept by a fraction-to-boundary rule, Armijo backtracking when a full step does
 * not halve the gradient), warm-started from the element's previous stretches and eigenvectors;
 * the eigenvectors of S = R^T (F_e + W_e) come from warm-started Jacobi sweeps stopped at 1e-6
 * relative off-diagonal size plus the exact first-order (Daleckii-Krein) correction of the rest
 * (core/admm/nh_spectral.h; ~1e-12 relative error in X_e).
 * Neo-Hookean handle steps are damped (core/admm/admm_damp.c): when new targets would make the
 * global step's V invert an element, the targets applied to the handles move only by the largest
 * fraction 1, 1/2, ..., 1/128 of the jump that keeps V uninverted (one extra solve per damped
 * iteration); they reach the requested targets once that is feasible. Reported positions and
 * objective are those of the last iterate without an inverted element (see df_admm_run). Per-vertex energies fit R_i (s_i) in closed
 * form (2x2 for planar meshes, signed 3x3 SVD otherwise).
 *
 * The SC-L1 prox uses the penalty rho (true ADMM), so `w` is the true loss weight; rho > w max(a_i)/s
 * is required. (The paper's released code used 10 w / s instead of rho; its settings translate to
 * w = rho s / 10: pig ARAP 1e-4, pig Neo-Hookean 500, bar3 ARAP 1e-3, apple Neo-Hookean 1.)
 *
 * Degenerate elements (df_admm_find_degenerate: a repeated vertex, |measure| <=
 * DF_ADMM_DEGENERATE_SHAPE_REL (longest edge)^d, or |measure| <= DF_ADMM_DEGENERATE_SIZE_REL times
 * the median measure of the other elements) are excluded from every energy, as if the mesh did not
 * have them; their vertices still move with the elements they share with the rest. A vertex whose
 * every element is degenerate (a "follower", e.g. a duplicated vertex) has no energy term of its
 * own (a_i = 0): after every iteration it is placed at its rest offset from the mean displacement of
 * its neighbours through those elements (followers of followers in turn), or of those neighbours
 * alone that share its rest position when there are some (a duplicated vertex stays on its twin);
 * one that no kept element, handle or affine vertex reaches stays at rest (counted in `at_rest`).
 *
 * Threading: a solver object is used by one thread at a time (it owns its cholmod_common);
 * df_admm_run uses OpenMP over elements and vertices inside.
 * Errors follow core/common/df_error.h: on any error the solver state is unchanged. */
#ifndef DF_ADMM_H
#define DF_ADMM_H

#include <stdint.h>

#include "core/common/df_error.h"
#include "core/mesh/mesh.h"

/* Limits. */
#define DF_ADMM_MAX_VERTICES 5000000      /* largest mesh accepted by df_admm_create */
#define DF_ADMM_MAX_AFFINE_ROWS 2048      /* total scalar affine constraint rows (sum |S_k| m_k) */
#define DF_ADMM_MAX_ITERS_LIMIT 1000000   /* largest accepted max_iters */
#define DF_ADMM_MAX_ANDERSON 20           /* largest Anderson history */

/* Degenerate element thresholds (see the header comment): shape relative to the element's longest
 * edge (as core/mesh's DF_MESH_DEGENERATE_REL), size relative to the mesh's median element. */
#define DF_ADMM_DEGENERATE_SHAPE_REL 1e-12
#define DF_ADMM_DEGENERATE_SIZE_REL 1e-10

typedef enum df_admm_energy {
    DF_ADMM_ARAP = 1,
    DF_ADMM_ACAP = 2,
    DF_ADMM_NEOHOOKEAN = 3,
    DF_ADMM_CLOTH = 4,
    DF_ADMM_POLYLINE = 5
} df_admm_energy;

/* DF_ADMM_RESIDUAL — the scale-invariant stop test of df_admm_run (independent of the mesh's
 * length unit and of the energy's scale: the old |E_k - E_k-1| / (E_k + 1) was absolute when
 * E ~ 1e-6 and stopped early). After each iteration k:
 *   e_k   = |E_k - E_k-1| / |E_k|                      (relative objective change; 0 when equal)
 *   pri_k = ||r_k|| / max(||A x_k||, ||z_k||)          (relative primal residual)
 *   dua_k = ||s_k|| / max(||y_k||, ||z_k||)            (relative dual residual)
 *   residual = max(e_k, sqrt(tol) * max(pri_k, dua_k))
 * and the run has converged when residual < tol, i.e. the objective changed by less than tol
 * relative AND both ADMM residuals are below sqrt(tol) relative (near the optimum the objective
 * error is quadratic in them). The residuals are Boyd et al. (2011, sec. 3.3) for the blocks of this
 * splitting, in the penalty metric (rho on Z = V - Vrest, gamma_e on F_e(V) = R_e X_e):
 * r = (V - Vrest - Z, F_e(V) - R_e X_e), A x = (V - Vrest, F_e(V)), z = (Z, R_e X_e),
 * s = the change of (Z, R_e X_e) over the iteration and y = (U, W) the scaled duals (s and y both
 * measured in the constraint space, i.e. Boyd's rho A^T B dz and rho A^T u without the common A^T).
 * Per-vertex energies (spokes and rims) have only the Z block. ||z_k|| joins ||y_k|| in dua_k's
 * scale because the duals vanish where the objective is flat (every moved vertex beyond s: the
 * SC-L1 term is constant there), which left dua_k at round-off / round-off = O(1) at an exact fixed
 * point (an ACAP grid ran 3000 iterations at residual 9.4e-6 with the energy unchanged to 1e-16).
 * Boyd's absolute term eps_abs sqrt(n) is 0: a zero residual counts as 0 and a nonzero one over a zero scale as +inf. */
/* DF_ADMM_RHO_RULE — the adaptive penalties, used when params.rho <= 0 (an explicit rho > 0 is used
 * as given for the whole life of the solver, with the element penalties gamma_e as documented
 * above, exactly as before). With c = w max(a_i) / s (the SC-L1 prox is convex only for rho > c)
 * and k_el the median over vertices of the elastic part of the global matrix's diagonal
 * (sum_e gamma_e |g_e,a|^2, or the spokes-and-rims weights):
 *   initial rho = DF_ADMM_RHO_INIT_LOC c when c > 0, else DF_ADMM_RHO_INIT_EL k_el (1 when 0)
 *   (the balancing then takes it to the floor on every shared-mesh case; starting at the floor
 *   was measured slower on Neo-Hookean: 519 vs 144 iterations on the unit tests' bar);
 *   rho stays in [DF_ADMM_RHO_FLOOR c, initial x DF_ADMM_RHO_RANGE] (c = 0: initial / RANGE below),
 *   so rho > c always; the element penalties are gamma_e x g with one global g in
 *   [DF_ADMM_GAMMA_MIN, DF_ADMM_GAMMA_MAX], initially 1.
 * After every iteration, per block, the relative residuals (Wohlberg 2017; penalty-free, so the
 * rule does not depend on the length unit or the energy scale) of the Z block
 *     pri_z = ||V - Vrest - Z|| / max(||V - Vrest||, ||Z||),   dual_z = ||Z_k - Z_k-1|| / ||U||
 * and of the element block (gamma_e metric, F_e(V) = R_e X_e; element-family energies but
 * Neo-Hookean, whose gamma_e is tied to its prox's curvature: g = 1 there)
 *     pri_e = ||F(V) - RX|| / max(||F(V)||, ||RX||),            dual_e = ||RX_k - RX_k-1|| / ||W||
 * give a factor sqrt(pri / dual) when pri > DF_ADMM_RHO_IMBALANCE dual or
 * dual > DF_ADMM_RHO_IMBALANCE pri (then < 1), else 1, at most DF_ADMM_RHO_MAX_STEP either way
 * (DF_ADMM_GAMMA_MAX_STEP for g); rho and g are multiplied by their factors (Boyd et al. 2011
 * sec. 3.4.1 residual balancing). Neo-Hookean: no balancing after an inverted (held, see
 * df_admm_run) iterate. (Raising rho while iterates stay inverted was tried: on the pig teaser it
 * doubled rho 22 times and never reached the targets.) Stall watch: when the best stop residual
 * (DF_ADMM_RESIDUAL) of a window of DF_ADMM_RHO_STALL_WINDOW non-inverted iterations is no better
 * than the previous window's and above max(tol, DF_ADMM_RHO_STALL_MIN) (the iteration cycles: small penalties near c can, e.g. the table
 * case w 2e-7 oscillated at 1e-6 relative forever at 1.25 c), the next change multiplies rho by
 * DF_ADMM_RHO_STALL_STEP and raises the floor to it. A change is one numeric-only refactorization (the global
 * matrix is reassembled with the same pattern and factorized, supernodal, into a copy of the kept
 * symbolic analysis, then converted to the simplicial LL^T the solves use, as at create; no new
 * analysis; the affine Schur complement is rebuilt), the scaled duals are rescaled so that the multipliers stay
 * (U x rho_old / rho_new, W / g-factor) and the Anderson history is dropped. Changes are at least
 * G iterations apart (the first one too), G = max(DF_ADMM_RHO_MIN_GAP, ceil(DF_ADMM_RHO_COST x
 * the factorization's flops / an iteration's estimated flops)), so refactorizations cost at most
 * about 1 / DF_ADMM_RHO_COST of the iteration time. The rule is deterministic (no timing enters
 * it); the penalties persist across df_admm_run calls (a reset_rest starts over).
 * df_admm_result and df_admm_stats count the changes; df_admm_rho reports rho. */
#define DF_ADMM_RHO_INIT_LOC 1.5
#define DF_ADMM_RHO_INIT_EL 1.0
#define DF_ADMM_RHO_FLOOR 1.25
#define DF_ADMM_RHO_RANGE 1e6
#define DF_ADMM_RHO_IMBALANCE 10.0
#define DF_ADMM_RHO_MAX_STEP 10.0
#define DF_ADMM_RHO_COST 5.0
#define DF_ADMM_RHO_MIN_GAP 10
#define DF_ADMM_RHO_STALL_WINDOW 200
#define DF_ADMM_RHO_STALL_STEP 2.0
#define DF_ADMM_RHO_STALL_MIN 1e-12
#define DF_ADMM_GAMMA_MIN 0.25
#define DF_ADMM_GAMMA_MAX 4.0
#define DF_ADMM_GAMMA_MAX_STEP 4.0

typedef struct df_admm_params {
    df_admm_energy energy;
    double w;              /* SC-L1 weight (energy per unit a_i per unit length), >= 0 */
    double s;              /* SC-L1 threshold distance (mesh length unit), > 0 */
    double rho;            /* ADMM penalty of Z = V - Vrest; > 0: fixed, must be > w max(a_i) / s;
                              <= 0 (default): adaptive (DF_ADMM_RHO_RULE above) */
    double tol;            /* stop test (df_admm_run): residual < tol, see DF_ADMM_RESIDUAL below;
                              default 1e-11; 0: never stop early */
    int max_iters;         /* default iteration cap of df_admm_run; default 500 */
    double youngs;         /* Neo-Hookean Young's modulus E (Pa); default 1e7 */
    double poisson;        /* Neo-Hookean Poisson ratio nu in (-1, 0.5); default 0.45 */
    int area_weighting;    /* 0: a_i = 1 (paper's code, default); 1: a_i = barycentric vertex
                              measure (area for triangles, volume for tets, length for polylines) */
    int accelerate;        /* 1: Anderson-accelerated ADMM (Zhang et al. 2019) with a
                              fixed-point-residual safeguard; 0: plain ADMM (default) */
    int anderson_m;        /* Anderson history length, 1..DF_ADMM_MAX_ANDERSON; default 5 */
    double strain_min;     /* CLOTH: lower limit of the stretch singular values; default 0.9 */
    double strain_max;     /* CLOTH: upper limit of the stretch singular values; default 1.1 */
    double bending;        /* CLOTH: bending stiffness (energy units * length^2); default 1e-3 */
    int threads;           /* OpenMP threads of the solver's kernels; 0 (default): OpenMP's default */
} df_admm_params;

/* Fills `p` with the defaults for `energy` (w 1e-4, s 0.01, rho 0 = adaptive, tol 1e-11,
 * max_iters 500, E 1e7, nu 0.45, a_i = 1, no acceleration, Anderson m 5, cloth limits [0.9, 1.1],
 * bending 1e-3; NEOHOOKEAN: w 500). NULL-safe. */
void df_admm_params_default(df_admm_params *p, df_admm_energy energy);

/* One affine constraint set (eq. 2c): A V_t = b for every vertex t in verts[0..n-1]; A is m x 3
 * row-major (m = 1: plane, 2: line, 3: point), rows linearly independent; b has m entries. A vertex
 * may not be a handle; the total number of scalar rows is at most DF_ADMM_MAX_AFFINE_ROWS. */
typedef struct df_admm_affine {
    int32_t n;
    const int32_t *verts;
    int m;
    double A[9];
    double b[3];
} df_admm_affine;

typedef struct df_admm df_admm;

/* What the solver does with degenerate elements. */
typedef struct df_admm_degenerate {
    int32_t elements;      /* degenerate elements, excluded from the energies */
    int32_t followers;     /* vertices of degenerate elements only, moved with their neighbours */
    int32_t at_rest;       /* such vertices no other vertex reaches: kept at their rest position */
} df_admm_degenerate;

/* Classifies the elements of `mesh` as the solver does (header comment) without building a solver:
 * flags (may be NULL; else mesh->ne bytes) receives 1 per degenerate element, *rep the counts
 * (followers / at_rest as for a solver without handles or affine sets). O(ne log ne), any thread.
 * Errors: DF_EINVAL (NULL mesh/rep, empty mesh, unknown kind, index out of range), DF_ENOMEM;
 * *rep untouched on error. */
int df_admm_find_degenerate(const df_mesh *mesh, uint8_t *flags, df_admm_degenerate *rep,
                            df_error *err);

/* Creates a solver for `mesh` (copied: the caller keeps ownership), `params` (rho <= 0: adaptive), the nh handle vertex
 * indices `handles` (distinct, in [0, nv), nh >= 1) and n_affine affine sets (may be NULL/0).
 * Computes per-element/per-vertex operators, analyzes and factorizes the global matrix once
 * (CHOLMOD). Initial state: V = rest, Z = U = W = 0, handle targets = rest positions.
 * Errors: DF_EINVAL (NULL args, bad params, rho <= w max(a_i)/s, energy/mesh kind mismatch, handle
 * out of range or repeated, empty handle set, affine vertex out of range or also a handle, NaN/Inf
 * coordinates, every element degenerate, inverted elements), DF_ELIMIT, DF_ESINGULAR (matrix or affine system
 * singular), DF_ENOMEM, DF_EINTERNAL (CHOLMOD/LAPACK failure). *out untouched on error. */
int df_admm_create(const df_mesh *mesh, const df_admm_params *params, const int32_t *handles,
                   int32_t nh, const df_admm_affine *affine, int n_affine, df_admm **out,
                   df_error *err);

/* Sets the handle targets: `targets` is nh x 3 row-major (same order as `handles` at create), in
 * mesh units. Never refactors. The next df_admm_run warm-starts from the current V, Z, U, W.
 * Errors: DF_EINVAL (NULL, NaN/Inf; a target with z != 0 on a 2D mesh (mesh->planar), whose
 * 2D solve would drop it). Solver unchanged on error. */
int df_admm_set_targets(df_admm *s, const double *targets, df_error *err);

/* Replaces the solver's positions by V (nv x 3, e.g. the session's current shape after an undo or
 * a brush edit), so that the next df_admm_run starts from V and not from the previous run's result.
 * The warm start is kept only where it is still valid: for every vertex whose position differs
 * (bitwise) from df_admm_positions, its ADMM state is restarted (V_i = given, Z_i = V_i - Vrest_i,
 * U_i = 0), the dual W_e of every element touching such a vertex is zeroed, and the Anderson history
 * and the cached objective are dropped; unchanged vertices keep V, Z, U. Neo-Hookean: the applied
 * (damped) handle targets restart at the handles' new positions. Handle targets are otherwise
 * unchanged. V equal to df_admm_positions changes nothing. *n_changed (may be NULL) receives the
 * number of changed vertices. Errors: DF_EINVAL (NULL solver/V, NaN/Inf in V); solver unchanged. */
int df_admm_set_positions(df_admm *s, const double *V, int32_t *n_changed, df_error *err);

/* What df_admm_run reports to its progress callback. V is the current nv x 3 positions (valid only
 * during the call). */
typedef struct df_admm_progress {
    int iteration;         /* iterations done in this run */
    double objective;      /* elastic + locality at V */
    double residual;       /* the stop test's residual (DF_ADMM_RESIDUAL) */
    const double *V;
    int32_t nv;
} df_admm_progress;

/* Progress callback: return 0 to continue, nonzero to stop the run after this iteration. */
typedef int (*df_admm_progress_fn)(void *user, const df_admm_progress *p);

typedef struct df_admm_budget {
    int max_iters;         /* <= 0: params.max_iters */
    double max_ms;         /* wall-clock budget of this call in ms: no iteration is started that would
                              end past it at 1.05 x the larger of the run's mean iteration cost and
                              its last iteration's cost (the first always runs); <= 0: unlimited */
    int progress_every;    /* call `progress` every k iterations (and at the end); <= 0: never */
    df_admm_progress_fn progress;
    void *user;
} df_admm_budget;

typedef enum df_admm_stop {
    DF_ADMM_STOP_CONVERGED = 1,  /* residual < tol */
    DF_ADMM_STOP_ITERS = 2,      /* max_iters reached */
    DF_ADMM_STOP_TIME = 3,       /* max_ms reached */
    DF_ADMM_STOP_CALLBACK = 4    /* the progress callback asked to stop */
} df_admm_stop;

typedef struct df_admm_result {
    int iterations;        /* ADMM iterations done by this call */
    double objective;      /* elastic + locality of the final V (the paper's E) */
    double elastic;        /* elastic energy part of `objective` */
    double locality;       /* sum_i w a_i ||V_i - Vrest_i||_SC-L1 */
    double residual;       /* last residual (DF_ADMM_RESIDUAL); +inf when no iteration ran */
    int converged;         /* 1 when residual < tol */
    df_admm_stop stop;     /* why the run ended */
    int anderson_accepted; /* accelerated steps accepted (0 without acceleration) */
    double t_local1;       /* seconds in local step 1 (X / rotations) */
    double t_local2;       /* seconds in local step 2 (Z prox) */
    double t_global;       /* seconds in the global step (RHS + solve + dual updates; per-element
                              energies also evaluate the objective's element terms there, fused
                              with the dual update's F_e) */
    double t_other;        /* seconds in objective evaluation and acceleration */
    double t_total;        /* wall-clock seconds of the call */
    double rho;            /* the penalty in use at the end of the call */
    int rho_changes;       /* adaptive penalty changes in this call (each one numeric refactorization) */
    double t_refactor;     /* seconds in those refactorizations (part of t_total only) */
} df_admm_result;

/* Runs ADMM iterations from the current state until the residual drops below tol, the iteration or
 * time budget is spent, or the callback stops it. `budget` may be NULL (params.max_iters, no time
 * limit, no callback); `res` may be NULL. Neo-Hookean: intermediate ADMM iterates may invert an
 * element (infinite energy); such an iterate is not reported when the positions reported before it
 * are uninverted: df_admm_positions, the progress V and the result keep the last uninverted iterate
 * and its (finite) objective, the residual is +inf for that iteration and the run does not count as
 * converged; the ADMM state itself continues from the actual iterate. The objective is +inf only
 * when no uninverted iterate has been reported yet. While damped handle steps are pending (admm.h
 * header comment) the reported handles lag behind their targets. Errors: DF_EINVAL (NULL solver), DF_ENOMEM
 * (Anderson work buffer), DF_EINTERNAL (CHOLMOD solve failure; positions then keep their last
 * values). */
int df_admm_run(df_admm *s, const df_admm_budget *budget, df_admm_result *res, df_error *err);

/* Number of vertices of the solver's mesh. */
int32_t df_admm_num_vertices(const df_admm *s);

/* Read-only view of the current positions (nv x 3 row-major), valid until the next call that
 * changes the solver. */
const double *df_admm_positions(const df_admm *s);

/* Copies the current positions into V_out (nv x 3). Errors: DF_EINVAL (NULL). */
int df_admm_get_positions(const df_admm *s, double *V_out, df_error *err);

/* Evaluates the objective at arbitrary positions V (nv x 3) against the solver's rest shape:
 * *elastic and *locality (either may be NULL). Handles and affine constraints are not checked.
 * Errors: DF_EINVAL (NULL solver/V, NaN), DF_EINVAL for inverted elements under Neo-Hookean
 * (infinite energy). */
int df_admm_evaluate(const df_admm *s, const double *V, double *elastic, double *locality,
                     df_error *err);

/* Sculpting mode: makes the current V the new rest shape (recomputes operators and refactors:
 * one analysis + one factorization), resets Z, U, W to 0 and the handle targets to their current
 * positions; the elements are classified again on the new rest shape. Errors: DF_EINVAL (the
 * current shape has inverted elements or only degenerate ones), DF_ESINGULAR,
 * DF_ENOMEM, DF_EINTERNAL; solver unchanged on error. */
int df_admm_reset_rest(df_admm *s, df_error *err);

typedef struct df_admm_stats {
    long analyses;         /* cholmod_analyze calls */
    long factorizations;   /* cholmod_factorize calls */
    long solves;           /* cholmod_solve calls (each with an nv_free x 3 right-hand side) */
    long iterations;       /* ADMM iterations over the solver's lifetime */
    long refactorizations; /* numeric-only refactorizations for a penalty change (also counted in
                              factorizations) */
    long rho_changes;      /* adaptive penalty changes */
} df_admm_stats;

/* The ADMM penalty in use: params.rho when it was given (> 0), else the adaptive penalty's current
 * value (DF_ADMM_RHO_RULE). NULL-safe (0). */
double df_admm_rho(const df_admm *s);

/* Copies the lifetime counters. NULL-safe (zeroes `out` for a NULL solver). */
void df_admm_get_stats(const df_admm *s, df_admm_stats *out);

/* Copies the solver's degenerate-element counts (header comment). NULL-safe (zeroes `out`). */
void df_admm_get_degenerate(const df_admm *s, df_admm_degenerate *out);

/* Frees the solver. NULL-safe. */
void df_admm_free(df_admm *s);

#endif
