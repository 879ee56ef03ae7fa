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
 *   (INIT_LOC = FLOOR: the balancing took a higher start down to the floor on every shared-mesh
 *   case anyway, at the price of one refactorization and its slower first iterations; the Z block's
 *   dual residual stays far above its primal one near c);
 *   rho stays in [DF_ADMM_RHO_FLOOR c, initial x DF_ADMM_RHO_RANGE] (c = 0: initial / RANGE below),
 *   so rho > c always; the element penalties are gamma_e x g with one global g in
 *   [DF_ADMM_GAMMA_MIN, DF_ADMM_GAMMA_MAX], initially DF_ADMM_GAMMA_INIT for the energies that are
 *   finite for every V (ARAP, ACAP, cloth: every shared-mesh ARAP case balanced g to 0.25-0.31 at
 *   its first change; starting there saves that refactorization and the imbalanced iterations
 *   before it: to the bench's quality pig ARAP 54 iterations instead of 55 + 1 refactorization,
 *   bar3 60 instead of 70 + 1, 72 at g = 1; g0 0.3-0.4 all gave 53-55 and 59-63), on trial like a
 *   lowering (below; the first window passes); Neo-Hookean starts at DF_ADMM_GAMMA_INIT_NH (the
 *   top of the range; below 1 its iterates invert while the handles travel: the pig took 107
 *   iterations from g0 0.35). Its gamma_e sits below the energy's largest curvature at rest
 *   ((2 mu + 3 lambda) vol, 2.6 gamma_e at nu 0.45), and a stiffer element block keeps the global
 *   step's response to the handle move from inverting elements: the pig teaser's handles reach
 *   their targets by damped steps at iteration 65 instead of a forced jump at 44 followed by 55
 *   inverted iterates. To the bench's quality (iterations, g0 1 / 2 / 3 / 4 / 6): pig teaser
 *   120 / 125 / 116 / 108 / 96, pig 84 / 82 / 80 / 72 / 128, apple 12 / 9 / 6 / 4 / 3, unit apple
 *   (w 5) 58 / 53 / 48 / 44 / 39; the unit pig with the teaser's targets (w 5, inverted for ~1000
 *   iterations whatever the start) 1101 at g0 1, 1245 at 2, 1304 at 4 (1147 at rho 1.25 w/s).
 * After every iteration, per block, the relative residuals (Wohlberg 2017; penalty-free, so the
 * rule does not depend on the length unit or the energy scale) of the Z block
 *     pri_z = ||V - Vrest - Z|| / max(||V - Vrest||, ||Z||),   dual_z = ||Z_k - Z_k-1|| / ||U||
 * and of the element block (gamma_e metric, F_e(V) = R_e X_e; element-family energies;
 * Neo-Hookean only while no damped handle step is pending, see below)
 *     pri_e = ||F(V) - RX|| / max(||F(V)||, ||RX||),            dual_e = ||RX_k - RX_k-1|| / ||W||
 * give a factor sqrt(pri / dual) when pri > DF_ADMM_RHO_IMBALANCE dual or
 * dual > DF_ADMM_RHO_IMBALANCE pri (then < 1), else 1, at most DF_ADMM_RHO_MAX_STEP either way
 * (a residual exactly 0 with the other not: the full step, e.g. Z still 0 while V left rest: the
 * table-like tiny move raised rho at its first change instead of cycling at the floor)
 * (DF_ADMM_GAMMA_MAX_STEP for g); rho and g are multiplied by their factors (Boyd et al. 2011
 * sec. 3.4.1 residual balancing). Neo-Hookean: no balancing after an inverted (held, see
 * df_admm_run) iterate; its element penalties change only once the handles are at their targets
 * (with g = 0.25 from the start the pig teaser never reached them; lowered at its 100th
 * iteration, once they were there, its iterates stayed inverted),
 * and when DF_ADMM_GAMMA_HELD consecutive iterates are held while g < 1, g goes back to 1 at once
 * (one refactorization, no gap) and stays there for the solver's life (until a reset_rest); the
 * same happens after a failed trial (below). (Raising rho while iterates stay inverted was tried: on the pig teaser it
 * doubled rho 22 times and never reached the targets.) Stall watch: when the best stop residual
 * (DF_ADMM_RESIDUAL) of a window of DF_ADMM_RHO_STALL_WINDOW non-inverted iterations is no better
 * than the previous window's and above max(tol, DF_ADMM_RHO_STALL_MIN) (the iteration cycles: small penalties near c can, e.g. the table
 * case w 2e-7 oscillated at 1e-6 relative forever at 1.25 c), the next change multiplies rho by
 * DF_ADMM_RHO_STALL_STEP and raises the floor to it (with g < 1 the change instead takes g back to
 * 1 for good, rho kept). Lowered element penalties are on trial: each window of
 * DF_ADMM_GAMMA_TRIAL non-inverted iterations while g < 1 must lower the best stop residual by
 * DF_ADMM_GAMMA_GAIN against the window before (the first window: against the iterations since the
 * previous change), else g goes back to 1 at once (no gap) and the element penalties are not
 * balanced again (a table-like bar, ARAP w 2e-7 at 1/100 scale, cycled ~1e-3 above the reference
 * at g = 0.25 until the stall watch caught it at 400 iterations; 124 with the trial). A change is one numeric-only refactorization (the global
 * matrix is reassembled with the same pattern and factorized, supernodal, into a copy of the kept
 * symbolic analysis, then converted to the simplicial LL^T the solves use, as at create; no new
 * analysis; the affine Schur complement is rebuilt), the scaled duals are rescaled so that the multipliers stay
 * (U x rho_old / rho_new, W / g-factor) and the Anderson history is dropped. Changes are at least
 * G iterations apart (the first one too), G = max(DF_ADMM_RHO_MIN_GAP, ceil(DF_ADMM_RHO_COST x
 * the factorization's flops / an iteration's estimated flops)), so refactorizations cost at most
 * about 1 / DF_ADMM_RHO_COST of the iteration time. The rule is deterministic (no timing enters
 * it); the penalties persist across df_admm_run calls (a reset_rest starts over).
 * df_admm_result and df_admm_stats count the changes; df_admm_rho reports rho. */
#define DF_ADMM_RHO_INIT_LOC 1.25
#define DF_ADMM_RHO_INIT_EL 1.0
#define DF_ADMM_RHO_FLOOR 1.25
#define DF_ADMM_RHO_RANGE 1e6
#define DF_ADMM_RHO_IMBALANCE 10.0
#define DF_ADMM_RHO_MAX_STEP 10.0
#define DF_ADMM_RHO_COST 2.0
#define DF_ADMM_RHO_MIN_GAP 5
#define DF_ADMM_RHO_STALL_WINDOW 200
#define DF_ADMM_RHO_STALL_STEP 2.0
#define DF_ADMM_RHO_STALL_MIN 1e-12
#define DF_ADMM_GAMMA_INIT 0.35
#define DF_ADMM_GAMMA_INIT_NH 4.0
#define DF_ADMM_GAMMA_MIN 0.25
#define DF_ADMM_GAMMA_MAX 4.0
#define DF_ADMM_GAMMA_MAX_STEP 4.0
#define DF_ADMM_GAMMA_HELD 3
#define DF_ADMM_GAMMA_TRIAL 50
#define DF_ADMM_GAMMA_GAIN 2.0

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
    /* Active-set iterations (DF_ADMM_ACTIVE below); 0 fields mean the defaults. */
    int active;            /* 1: iterate on the active region only; 0: full solve (default) */
    int active_band;       /* rings of the band around the support, >= 1; 0: DF_ADMM_ACTIVE_BAND */
    int active_check_every;/* far-field certificate every k iterations; 0: DF_ADMM_ACTIVE_CHECK */
    double active_tail;    /* tail test tolerance (DF_ADMM_ACTIVE, "Tail test"), >= 0; 0 (default):
                              off */
} df_admm_params;

/* DF_ADMM_ACTIVE — active-set mode (params.active = 1; core/admm/admm_active*.c). SC-L1 leaves the
 * optimum exactly at rest away from the edit, so df_admm_run iterates only over the region
 * R = support grown by `active_band` rings of the mesh's vertex graph (support: vertices with
 * Z_i != 0, handles whose target or position differs from rest, vertices set by
 * df_admm_set_positions), with every vertex outside R held exactly (bitwise) at rest:
 * V = Vout = Vrest, Z = U = 0, W_e = 0 on elements with no vertex in R. Each iteration is the
 * ADMM iteration of the problem restricted to R (Dirichlet at rest on the outside vertices): local
 * steps on the elements (per-vertex energies: the cells) touching R, the SC-L1 prox and duals on R,
 * and the global step on R's free vertices with the principal submatrix of the global matrix,
 * analyzed and factorized by CHOLMOD when R changes (cached while R and rho are unchanged). Cost
 * per iteration: proportional to |R|, not to the mesh.
 * Growth: when a support vertex comes within active_band - 1 rings of R's edge, R grows to its
 * union with the support grown by active_band rings (refactor). Certificate (every
 * active_check_every iterations, before reporting convergence and at the end of every run): the
 * restricted optimum is the full one iff every outside vertex i satisfies the SC-L1 subgradient
 * condition |grad_i E_elastic(V)| <= w a_i (its rest position is optimal); only vertices next to R
 * can have a nonzero force (the elements of the others are exactly at rest), so those are checked;
 * the failing ones join the support and R grows. Convergence is reported only when certified.
 * Energies and features: ARAP / ACAP (tets and triangles), Neo-Hookean (with damped handle steps),
 * polylines. Fallback to the full solve (same results, full cost; counted in
 * df_admm_active_stats.fallbacks): cloth, affine constraints, Anderson acceleration, degenerate
 * elements with followers or isolated vertices, and a region above DF_ADMM_ACTIVE_MAX_FRAC of the
 * vertices (then the run finishes with full iterations). df_admm_set_positions and
 * df_admm_reset_rest work in both modes: after them (and after any full run) the next active run
 * takes the support from Z != 0 and puts every vertex outside the new region exactly at rest (a
 * change of the order of the full solve's far-field round-off). With params.active (and no
 * feature that falls back) df_admm_create builds no whole-mesh factorization; the first full run
 * builds it. df_admm_stats counts the region analyses, factorizations and solves too.
 * Tail test (params.active_tail = tol > 0; off by default; DF_ADMM_ACTIVE_TAIL recommended):
 * after every iteration, when the SC-L1 charge w sum a_i |Vout_i - Vrest_i| of the region's edge
 * (its vertices next to the outside) exceeds tol |E|, the region grows at the edge vertices whose
 * charge c exceeds their share tol |E| / (edge size), each by the rings its charge needs to decay
 * to that share: ceil(log(c / share) / (0.7 log q)), 1 to 8 rings, q the decay of the per-vertex
 * mean charge from depth 2 to depth 1 (admm_active_tail.c; counted in
 * df_admm_active_stats.tail_grows). Probe: in a run that starts on a freshly built region (a
 * drag's first update), when the first iteration grows the region, the region's state from before
 * it is put back and the run starts again on the grown region (up to 3 times per run; counted in
 * tail_probes; the redone iteration is not in df_admm_result.iterations; not with Neo-Hookean's
 * damped handle steps). The charge vanishes at convergence, so converged results are unchanged.
 * Exactness: converged results equal the full solve's (objective ~1e-14 relative in the tests).
 * A fixed number of iterations is not the same computation as the full solve's: there the global
 * step's decaying response (about 6x per ring on bench_local's grids) moves every vertex a little
 * in every iteration, and SC-L1 charges a small displacement linearly (w a_i |d_i|), so the full
 * iterate carries a far-field cost the active iterate (and the optimum) does not have. Measured
 * after 20 iterations on bench_local's 100k grid: the full objective is above the active one in
 * every update, by 1.6e-6 relative with the default band, of which the full iterate's own far
 * field outside the region costs 1.7e-6 (the full iterate with that far field put at rest is
 * within 1.3e-7 of the active one; 1.6e-9 with 6 rings). No region growth, penalty change or
 * stop happens in those updates, and both start from the same state: the difference is the
 * global step's response beyond the band alone. That gap comes mostly from the iterations run
 * while the region was too small: ADMM damps an early difference only ~0.6x per iteration. The
 * tail test follows the full iterate's far field instead: over the whole 10-update drag at 100k,
 * DF_ADMM_ACTIVE_TAIL (5e-5) stays within 7.1e-9 of the full solve's 20-iteration objective with
 * a region of ~2.1k vertices (4 builds in a drag's first two updates); 1e-4 gives 1.6e-8 (1.7k
 * vertices) and 3e-4 6.3e-8 (1.3k vertices, 6.4e-9 over the first two updates alone: the full
 * iterate's far-field drift, and so the gap, grows over a drag). The one-ring growth the
 * multi-ring growth replaced needed 3e-6 and ~2.8k vertices for 7.2e-9 over two updates. A region
 * fixed from the start to the vertices the full iterates of the first two updates move by more
 * than 3e-6 drag steps (known only after the full solve; 1275 vertices) gives 7.3e-9 there
 * (measured with a throw-away hook, not in the API). Where its time goes (bench_local's 1M grid):
 * the region is built and grown in the first two updates only and then kept (it never shrinks
 * back during a drag); later updates are the iterations on its vertices and elements. */
#define DF_ADMM_ACTIVE_BAND 3
#define DF_ADMM_ACTIVE_CHECK 10
#define DF_ADMM_ACTIVE_MAX_FRAC 0.5
#define DF_ADMM_ACTIVE_TAIL 5e-5   /* the recommended params.active_tail ("Tail test") */

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

/* Counters of the active-set mode (DF_ADMM_ACTIVE). */
typedef struct df_admm_active_stats {
    long runs;             /* df_admm_run calls done in active mode */
    long fallbacks;        /* df_admm_run calls (or their rest) done by the full solve instead */
    long grows;            /* region growths (each one refactorization) */
    long check_grows;      /* growths asked by the far-field certificate */
    long checks;           /* certificates evaluated */
    long rebuilds;         /* regions rebuilt from the support (first run, after set_positions,
                              reset_rest or a full run) */
    int32_t region_vertices;   /* |R| now (0 when no region) */
    int32_t region_elements;   /* elements (per-vertex energies: cells) iterated on */
    int32_t support;           /* support size at the end of the last active run */
    long tail_grows;           /* growths by the tail test (params.active_tail) */
    long tail_probes;          /* first iterations redone on a grown region (tail test probe) */
} df_admm_active_stats;

/* Copies the active-set counters. NULL-safe (zeroes `out` for a NULL solver). */
void df_admm_get_active_stats(const df_admm *s, df_admm_active_stats *out);

/* Copies the solver's degenerate-element counts (header comment). NULL-safe (zeroes `out`). */
void df_admm_get_degenerate(const df_admm *s, df_admm_degenerate *out);

/* ---- second-order polish (core/admm/admm_newton.c) ----
 *
 * df_admm_polish: after ADMM has found the support (the vertices that moved), minimizes the same
 * objective E(V) = E_elastic(V) + sum_i w a_i ||V_i - Vrest_i||_SC-L1 by projected Newton on the
 * moved set, to a tight KKT residual (ADMM alone converges only linearly and stalls for
 * Neo-Hookean). Covered: tet meshes with ARAP, ACAP or NEOHOOKEAN (per-element energies). Not
 * covered (DF_EUNSUPPORTED): triangle / polyline meshes (spokes-and-rims ARAP / ACAP, CLOTH,
 * POLYLINE).
 *
 * Variables. Handles stay at their targets. Vertices of degenerate elements only (followers, a_i
 * = 0 and no energy) are placed after the polish as df_admm_run does. Every other vertex is either
 *   free  (the support): V_i is polished; initially the vertices with |Z_i| > support_tol (ADMM's
 *         exactly sparse copy of V - Vrest; support_tol 0: Z_i != 0), every vertex when w a_i = 0
 *         (w = 0: full space), and affine vertices whose rest position violates their constraint;
 *   rest: V_i = Vrest_i exactly (the ADMM result's V_i, off rest by the primal residual only, is
 *         snapped back first; Neo-Hookean: the vertices of an element that snapping would invert
 *         keep ADMM's positions and join the support instead).
 * Affine-constrained vertices are polished in the null space of their constraint rows (Newton
 * steps projected per vertex), so A V_t = b holds as after ADMM (to roundoff).
 *
 * Newton model per iteration: the element Hessians d2E_e / dV2 = vol_e G_e^T (d2Psi/dF2) G_e plus
 * the SC-L1 term's 3x3 blocks w a_i [(1 - r/s)/r (I - n n^T) - (1/s) n n^T] (r = |V_i - Vrest_i|
 * < s, n the direction; 0 beyond s) on the free set. The exact Hessian is tried first (sparse
 * Cholesky, CHOLMOD, symbolic analysis cached in the solver for the same support); when it is not
 * positive definite the model is projected: each element's 9x9 d2Psi/dF2 with its negative
 * eigenvalues clamped to 0 (Neo-Hookean: Jacobi eigen-decomposition when its Cholesky fails;
 * ARAP / ACAP: the analytic twist-mode eigenvalues 1 - 2 k / (sg_a + sg_b), k = 1 or tr S / 3) and
 * the SC-L1 term's concave radial curvature -w a_i / s dropped (left to the line search); a still
 * singular model gets a growing diagonal shift. Step: Neo-Hookean steps stop short of inversion by
 * a fraction to the boundary (0.9 of the largest step keeping every det F_e > 0, exact cubic in
 * the step), then backtracking (halving, Armijo c = 1e-4) on the true objective; a step whose
 * predicted and actual changes are both below 1e-12 |E| (roundoff) is accepted as is.
 *
 * KKT residual (relative, DF_ADMM_POLISH_KKT): with g the gradient of E (elastic + SC-L1, projected
 * per affine vertex), g_el its elastic part,
 *   r_free = sqrt(sum_{i free} |g_i|^2),
 *   r_rest = sqrt(sum_{i rest} max(0, |g_el,i| - w a_i)^2)   (subgradient condition at V_i = Vrest_i),
 *   scale  = sqrt(sum_{i free or rest} m_i^2), m_i = sum over the terms touching i (each element
 *            with a corner at i, the SC-L1 term of i) of the magnitude of that term's gradient at i,
 *   kkt    = sqrt(r_free^2 + r_rest^2) / scale            (0 when both are 0)
 * i.e. the net force relative to the forces that balance there (invariant to the length unit and
 * the energy scale). A rest vertex violating the subgradient condition wants to move: the support
 * grows (the worst violators, >= 0.1 x the largest violation, get a first-order step off rest) and
 * Newton continues; free vertices within 0.1 s of rest whose elastic gradient satisfies the
 * subgradient condition (they would stay at rest) are snapped back to rest when that does not
 * raise E (else the same with the distance threshold / 10, down to 1e-7 s); free vertices within
 * 1e-3 s of rest that violate it (they want out) but do not point along -g_el,i are re-aimed: moved
 * to rest + t (-g_el,i / |g_el,i|) as a new support vertex (when E decreases). `violations` counts
 * the rest vertices with max(0, |g_el,i| - w a_i) > 1e-3 tol scale. */
#define DF_ADMM_POLISH_HIST 64       /* per-iteration history kept in df_admm_polish_result */
#define DF_ADMM_POLISH_MAX_ITERS 10000

typedef struct df_admm_polish_params {
    int max_iters;         /* Newton iterations; <= 0: 50 (at most DF_ADMM_POLISH_MAX_ITERS) */
    double tol;            /* stop when kkt < tol; <= 0: 1e-9 */
    double support_tol;    /* initial support: |Z_i| > support_tol (mesh units); 0 (default): Z_i != 0 */
    int no_grow;           /* 1: never add rest vertices (violations are only reported) */
} df_admm_polish_params;

typedef struct df_admm_polish_result {
    int iterations;        /* Newton steps taken */
    int converged;         /* 1 when kkt < tol at the end */
    double objective_admm; /* E at the solver's positions before the polish */
    double objective;      /* E after (elastic + locality) */
    double elastic, locality;
    double kkt;            /* final relative KKT residual (header comment) */
    double kkt_free, kkt_rest; /* r_free / scale, r_rest / scale */
    double scale;          /* the force scale (energy / length) */
    int32_t support;       /* free (polished) vertices at the end */
    int32_t added;         /* rest vertices moved into the support (subgradient violations) */
    int32_t removed;       /* free vertices snapped back to rest */
    int32_t violations;    /* rest vertices still violating the subgradient condition at the end */
    int projected;         /* iterations whose exact Hessian was not positive definite */
    int shifted;           /* iterations that needed a diagonal shift on top of the projection */
    int line_search_fail;  /* 1 when the last line search found no decrease (stopped there) */
    long analyses, factorizations; /* CHOLMOD calls of this polish */
    int hist_n;            /* entries in the history: min(iterations + 1, DF_ADMM_POLISH_HIST) */
    double hist_objective[DF_ADMM_POLISH_HIST]; /* [0]: start (after snapping), [k]: after step k */
    double hist_kkt[DF_ADMM_POLISH_HIST];
    double hist_time[DF_ADMM_POLISH_HIST];      /* seconds since the call began */
    double t_assemble, t_factor, t_line, t_total; /* seconds */
} df_admm_polish_result;

/* Polishes the solver's current positions (df_admm_positions) as described above and makes the
 * result the solver's positions as df_admm_set_positions does (ADMM state of the changed vertices
 * restarted; the next df_admm_run continues from the polished shape). `params` may be NULL
 * (defaults); `res` may be NULL. Not converging within max_iters is not an error (res->converged
 * 0). Errors: DF_EINVAL (NULL solver, max_iters > DF_ADMM_POLISH_MAX_ITERS, NaN or negative tol /
 * support_tol), DF_EUNSUPPORTED (not a tet mesh with ARAP, ACAP or NEOHOOKEAN), DF_ESTATE (handles
 * not at their requested targets, e.g. damped Neo-Hookean steps pending: run ADMM further first; or
 * an inverted element in the start shape), DF_ENOMEM, DF_EINTERNAL (CHOLMOD failure); the solver is
 * unchanged on error. Thread: as df_admm_run (OpenMP inside, the solver used by one thread). */
int df_admm_polish(df_admm *s, const df_admm_polish_params *params, df_admm_polish_result *res,
                   df_error *err);

/* The relative KKT residual of DF_ADMM_POLISH_KKT (above) at arbitrary positions V (nv x 3; handles
 * and affine rows are not checked), with the free set = the vertices off rest (V_i != Vrest_i) or
 * with w a_i = 0, the rest set = the others, handles and followers excluded: for comparing ADMM's
 * iterates with the polish. Errors: DF_EINVAL (NULL, NaN), DF_EUNSUPPORTED (as df_admm_polish),
 * DF_ESTATE (an inverted Neo-Hookean element at V), DF_ENOMEM. Positions unchanged. */
int df_admm_kkt(df_admm *s, const double *V, double *kkt, df_error *err);

/* Frees the solver. NULL-safe. */
void df_admm_free(df_admm *s);

#endif
