/* admm_seed.h — starting df_admm_run from a proposed deformation (e.g. the Kelvinlet initial
 * guess of core/kelvinlet/kelvinlet_guess.h) without starting it worse than the plain start.
 *
 * The plain start of a handle move is the current positions V0 (df_admm_set_positions(V0)); the
 * handles jump to their targets in the first global step. A proposal G (nv x 3, e.g. V0 plus the
 * Kelvinlet field) is applied as the candidate family
 *     X(alpha)_i = V0_i + alpha (G_i - V0_i)   (free vertices),   X_h = target_h   (handles),
 * alpha in [0, 1], and alpha is the minimizer of the solver's objective (elastic + SC-L1
 * locality, df_admm_evaluate) along it: DF_ADMM_SEED_GRID + 1 evenly spaced alphas, then
 * DF_ADMM_SEED_REFINE golden-section steps in the grid cell pair around the best one. The chosen
 * X(alpha) is used only when its objective is strictly below E(X(0)) (the plain start with the
 * handles already on their targets, which the first global step reaches anyway); otherwise the
 * seed is the plain start itself, bit for bit: df_admm_set_positions(V0), alpha = 0.
 * Support restriction (shrink): before the search, the proposal's displacement u_i = G_i - V0_i
 * of every vertex is soft-thresholded, u_i -> u_i max(0, 1 - tau / |u_i|), with tau = shrink x
 * the largest handle displacement |target_h - V0_h|: vertices the field moves by less than tau
 * stay where they are. Why: the SC-L1 term is flat beyond its threshold s, so free vertices the
 * whole field moves by more than s (a Kelvinlet decays like 1/r: most of the mesh) feel no pull
 * back to rest, and the run settles in another, higher local minimum (pig ARAP, 500 iterations:
 * +31% with the whole field, with or without the line search, which picks alpha ~ 1 there). The
 * start's objective does not predict that basin (the whole field starts lowest), so shrink is a
 * fixed fraction, DF_ADMM_SEED_SHRINK by default. Measured (tests/bench/bench_kguess.c, 500
 * iterations, the plain start's objective as the quality): see DF_ADMM_SEED_SHRINK. */
#ifndef DF_ADMM_SEED_H
#define DF_ADMM_SEED_H

#include <stdint.h>

#include "core/admm/admm.h"
#include "core/common/df_error.h"

#define DF_ADMM_SEED_GRID 8     /* grid cells over [0, 1]: alphas 0, 1/8, ..., 1 */
#define DF_ADMM_SEED_REFINE 6   /* golden-section steps after the grid */
/* Default shrink: tau = 0.25 x the largest handle displacement. Iterations to the plain start's
 * 500-iteration objective with the Kelvinlet guess for shrink 0 / 0.1 / 0.15 / 0.2 / 0.25 / 0.3
 * (never: final objective higher than the plain start's): pig ARAP never / never / never / 169 /
 * 294 / 363, bar3 ARAP 155 / 408 / - / 472 / - / 490, table ARAP (bench_table.h) plain start kept
 * (alpha 0) / 297 / - / 439 / - / 474. No single fraction is best everywhere; 0.25 keeps a margin
 * from pig's cliff between 0.15 and 0.2. */
#define DF_ADMM_SEED_SHRINK 0.25

typedef struct df_admm_seed_report {
    double alpha;        /* the scale used, in [0, 1]; 0: the plain start (V0) */
    double tau;          /* the shrink threshold used (mesh units) */
    double e_plain;      /* objective of X(0) (V0 with the handles on their targets) */
    double e_full;       /* objective of X(1) (the whole proposal); +inf if it inverts (Neo-Hookean) */
    double e_seed;       /* objective of X(alpha) (= e_plain when alpha is 0) */
    int evaluations;     /* objective evaluations made */
} df_admm_seed_report;

/* Computes X(alpha) for one alpha (header comment): X = V0 + alpha (G - V0) on free vertices and
 * the solver's targets (df_admm_set_targets) on its handles. In: s, V0 and G (nv x 3, nv =
 * df_admm_num_vertices), alpha (any finite value). Out: X (nv x 3; may not alias V0 or G).
 * Errors: DF_EINVAL (NULL, alpha not finite). Reads the solver only; any thread that owns it. */
int df_admm_seed_point(const df_admm *s, const double *V0, const double *G, double alpha,
                       double *X, df_error *err);

/* Shrinks the proposal and chooses alpha by the line search of the header comment, then sets the
 * solver's positions to X(alpha) (df_admm_set_positions), or to V0 when no alpha > 0 lowers the
 * objective below E(X(0)). Call after df_admm_set_targets (the handles' X are those targets).
 * In:  s (the solver of the move), V0 (nv x 3: the plain start, mesh units), G (nv x 3: the
 *      proposal, e.g. df_kelvinlet_guess's V_out from V0; not modified), shrink (in [0, 1]: the
 *      fraction of the largest handle displacement below which the proposal's displacement is
 *      soft-thresholded away; 0: none; DF_ADMM_SEED_SHRINK is the measured default).
 * Out: rep (may be NULL): the choice and its objectives. The solver's positions and warm start
 *      as df_admm_set_positions leaves them.
 * Errors: DF_EINVAL (NULL s/V0/G, NaN/Inf in V0 or G, shrink not in [0, 1]), DF_ENOMEM; the
 * solver is unchanged on error. Cost: about DF_ADMM_SEED_GRID + DF_ADMM_SEED_REFINE + 1
 * objective evaluations (one local step's worth each) and two nv x 3 buffers. Thread: the caller owning the solver. */
int df_admm_seed(df_admm *s, const double *V0, const double *G, double shrink,
                 df_admm_seed_report *rep, df_error *err);

#endif
