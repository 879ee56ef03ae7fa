/* admm_seed.h — starting df_admm_run from a proposed deformation (e.g. the Kelvinlet initial
 * guess of core/kelvinlet/kelvinlet_guess.h) without starting it worse than the plain start.
 *
 * The plain start of a handle move is the current positions V0 (df_admm_set_positions(V0)); the
 * handles jump to their targets in the first global step. A proposal G (nv x 3, e.g. V0 plus the
 * Kelvinlet field) is applied as the two-parameter family
 *     X(shrink, alpha)_i = V0_i + alpha S_tau(G_i - V0_i)   (free vertices),
 *     X_h = target_h                                        (handles),
 * alpha in [0, 1], where S_tau is the support restriction: with dmax the largest handle
 * displacement |target_h - V0_h| and tau = shrink x dmax,
 *     S_tau(u) = u max(0, |u| - tau) / |u| x dmax / (dmax - tau),
 * i.e. vertices the field moves by less than tau stay where they are and displacements between
 * tau and dmax are mapped linearly onto 0..dmax (continuous, and vertices beside a moved handle
 * keep its displacement: a plain soft threshold left a gap of tau there, and pig ARAP at shrink
 * 0.25 took 294 iterations instead of 85). (shrink, alpha) minimizes the solver's objective
 * (elastic + SC-L1 locality, df_admm_evaluate) over shrink in {0.05, 0.1, ...,
 * DF_ADMM_SEED_SHRINK_MAX} (or one given shrink, 0 allowed) and, for each, alpha over the grid
 * 1/4, ..., 1 followed by golden-section steps beside the best grid point. The chosen X is used
 * only when its objective is strictly below that of X(., 0) (V0 with the handles on their
 * targets, which the first global step reaches anyway); otherwise the seed is the plain start
 * itself, bit for bit: df_admm_set_positions(V0), alpha = 0. Inverted Neo-Hookean candidates
 * count as +inf. When the plain start itself inverts with the handles on their targets
 * (E(X(., 0)) = +inf: Neo-Hookean moves whose handles must be damped) there is no finite
 * reference, and only alpha = 1 is accepted (the restricted field carries the handles'
 * neighbourhoods the whole way; partial alphas leave them strained as the jump does): on the
 * apple Neo-Hookean every alpha-1 candidate inverts, and the best partial one (shrink 0.5, alpha
 * 0.75) had ended 1e-4 above the plain start after 500 iterations (0.4 and below: 1e-4 to 5e-4
 * above); the plain start is kept there now.
 * Why the support restriction: the SC-L1 term is flat beyond its threshold s, so free vertices
 * the whole field moves by more than s (a Kelvinlet decays like 1/r: most of the mesh) feel no
 * pull back to rest, and the run settles in another, higher local minimum (pig ARAP after 500
 * iterations: +31% with the whole field). The unrestricted field (shrink 0) is therefore never
 * a candidate of the search: its start objective does not show that trap (pig ARAP: 0.0113, near
 * the candidates' 0.008-0.011; pig teaser Neo-Hookean: the only uninverted candidate, +41% after
 * 500 iterations, while every restricted one inverts, so the plain start is kept there).
 * Why choose shrink by the start's objective: on pig ARAP the start's objective for shrink 0.1 /
 * 0.15 / 0.2 / 0.25 / 0.3 / 0.35 was 0.0109 / 0.0094 / 0.0083 / 0.0081 / 0.0082 / 0.0086 and the
 * iterations to the plain start's 500-iteration objective never / never / 235 / 85 / 239 / 302:
 * the minimum picks the best. On bar3 ARAP (shrink 0 / 0.05 / 0.1 / 0.2 / 0.25: 155 / 287 / 384
 * / 459 / 474 iterations) and the table (0: no alpha helps / 0.05: 467 / 0.1: 193 / 0.2: 410 /
 * 0.25: 439) it picks 0.15 and 0.2: not the best, but ending below the plain start.
 * With the search (500 iterations; iterations to the plain start's final objective): pig ARAP 83
 * (shrink 0.25), bar3 ARAP 433 (0.15), table ARAP 409 (0.2), pig Neo-Hookean 219 (0.2), bar3
 * Neo-Hookean 388 (0.1), each ending below the plain start's final objective; apple and pig
 * teaser Neo-Hookean: the plain start (no uninverted candidate), the same result. Measured in
 * tests/bench/bench_kguess.c; nothing guarantees the final objective in general (a start only
 * chooses the basin ADMM runs in). */
#ifndef DF_ADMM_SEED_H
#define DF_ADMM_SEED_H

#include <stdint.h>

#include "core/admm/admm.h"
#include "core/common/df_error.h"

#define DF_ADMM_SEED_GRID 4          /* alpha grid cells over [0, 1]: alphas 1/4, ..., 1 */
#define DF_ADMM_SEED_REFINE 5        /* golden-section evaluations after the alpha grid */
#define DF_ADMM_SEED_SHRINK_MAX 0.5  /* largest shrink (the support restriction's tau / dmax) */
#define DF_ADMM_SEED_SHRINK_STEPS 10 /* shrink candidates: k x MAX / STEPS, k = 1..STEPS */
#define DF_ADMM_SEED_SHRINK_AUTO -1.0 /* df_admm_seed's shrink: search the candidates */

typedef struct df_admm_seed_report {
    double alpha;        /* the scale used, in [0, 1]; 0: the plain start (V0) */
    double shrink;       /* the shrink used (0 with alpha 0) */
    double tau;          /* its threshold, shrink x dmax (mesh units) */
    double e_plain;      /* objective of X(., 0) (V0 with the handles on their targets) */
    double e_one;        /* objective at alpha 1 of the chosen shrink (the only one when given;
                            the first candidate when none lowers the objective) */
    double e_seed;       /* objective of the start (= e_plain when alpha is 0); +inf: inverted */
    int evaluations;     /* objective evaluations made */
} df_admm_seed_report;

/* Computes X for one alpha and no shrink (header comment): X = V0 + alpha (G - V0) on free vertices
 * and the solver's targets (df_admm_set_targets) on its handles. In: s, V0 and G (nv x 3, nv =
 * df_admm_num_vertices), alpha (any finite value). Out: X (nv x 3; may not alias V0 or G).
 * Errors: DF_EINVAL (NULL, alpha not finite). Reads the solver only; any thread that owns it. */
int df_admm_seed_point(const df_admm *s, const double *V0, const double *G, double alpha,
                       double *X, df_error *err);

/* Chooses (shrink, alpha) by the search of the header comment, then sets the solver's positions to
 * X(shrink, alpha) (df_admm_set_positions), or to V0 when no candidate lowers the objective below
 * E(X(., 0)). Call after df_admm_set_targets (the handles' X are those targets).
 * In:  s (the solver of the move), V0 (nv x 3: the plain start, mesh units), G (nv x 3: the
 *      proposal, e.g. df_kelvinlet_guess's V_out from V0; not modified), shrink
 *      (DF_ADMM_SEED_SHRINK_AUTO: search the candidates; or one value in [0,
 *      DF_ADMM_SEED_SHRINK_MAX], 0: the proposal unrestricted).
 * Out: rep (may be NULL): the choice and its objectives. The solver's positions and warm start
 *      as df_admm_set_positions leaves them.
 * Errors: DF_EINVAL (NULL s/V0/G, NaN/Inf in V0 or G, shrink neither AUTO nor in range),
 * DF_ENOMEM; the solver is unchanged on error. Cost: 1 + (DF_ADMM_SEED_GRID +
 * DF_ADMM_SEED_REFINE) per shrink candidate objective evaluations (each about one local step:
 * 91 with AUTO, ~7 ms each on pig's 44k tets under load; 1 per candidate without a finite
 * reference) and three nv x 3 buffers. Thread: the
 * caller owning the solver. */
int df_admm_seed(df_admm *s, const double *V0, const double *G, double shrink,
                 df_admm_seed_report *rep, df_error *err);

#endif
