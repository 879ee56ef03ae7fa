/* kelvinlet_guess.h — a Kelvinlet initial guess for handle moves (de Goes & James 2017 suggest
 * seeding a nonlinear solver with the Kelvinlet field of the handles' displacement).
 *
 * Given the current positions V of a mesh, its handle vertices and their new targets, the guess
 * is V + u(V), where u is the superposition of one single-scale grab Kelvinlet per handle,
 * centred at the handle's current position, with forces f fitted so that u reaches every
 * handle's displacement d_h = target_h - V_h: the dense 3nh x 3nh system of handle-to-handle
 * kernel blocks K_hk = A(s) I + B(s) r r^T (r = V_h - V_k, s = |r|^2) is solved with LAPACKE
 * dgesv, like the pinned points of kelvinlet_constraints.c. Handles that do not move are part
 * of the fit (u = 0 there), so fixed handles hold the field down around them.
 * Choice of radius: the caller's, or (radius <= 0) DF_KGUESS_SPREAD_FRACTION times the RMS
 * distance of the handles from their centroid (the handle spread), at least 1% of the mesh's
 * bounding-box diagonal. Measured (tests/bench/bench_kguess.c, to tol 1e-11, 5000 cap, default
 * radius): bar3 ARAP 3518 -> 2808 iterations, bar3 Neo-Hookean 3689 -> 3263, same objective
 * (1e-12); pig ARAP 1212 -> cap, objective +5e-4 relative (+4e-5 with the whole spread as
 * radius); pig Neo-Hookean 2067 -> cap, objective -17% (another, lower local minimum, not
 * converged). The SC-L1 locality term is flat beyond its threshold s: free vertices the guess
 * displaced by more than s feel no pull back to rest, so on pig the solve settles elsewhere.
 * The guess suits moves whose result is smooth over the handles' region
 * and is an option, never the default. Handle moves do not use it raw: core/admm/admm_seed.h
 * restricts it to the vertices it moves by more than a fraction of the handle move and scales it,
 * both chosen by the solver's objective (pig ARAP then reaches the plain start's 500-iteration
 * objective in 83 iterations; bench_kguess). Near handles have close to equal kernel blocks, so K is
 * nearly singular: a ridge of
 * DF_KGUESS_RIDGE * A(0) is added to its diagonal, which leaves the fit residual at the handles
 * (reported) small but not zero; the guess then snaps the handles exactly onto their targets.
 * Math only: no I/O, no global state. */
#ifndef DF_KELVINLET_GUESS_H
#define DF_KELVINLET_GUESS_H

#include <stdint.h>

#include "core/common/df_error.h"

#define DF_KGUESS_MAX_HANDLES 1536   /* largest handle count: the dense 3nh square system takes
                                        72 nh^2 bytes (170 MB here; pig, 1016 handles: 74 MB) */
#define DF_KGUESS_RIDGE 1e-10        /* Tikhonov ridge of the fit, relative to K's diagonal */
#define DF_KGUESS_SPREAD_FRACTION 0.1 /* default radius / RMS handle spread */

/* The default radius: DF_KGUESS_SPREAD_FRACTION x the RMS distance of V's handle vertices from
 * their centroid, at least 1% of
 * the bounding-box diagonal of V (nv x 3), and within the Kelvinlet radius bounds. Returns 0
 * for bad input (NULL, nv or nh < 1, index out of range). Reentrant. */
double df_kelvinlet_guess_radius(const double *V, int32_t nv, const int32_t *handles, int32_t nh);

/* Computes the guess.
 * In:  V (nv x 3 row-major, mesh units; the current positions), handles[nh] (distinct vertex
 *      indices in [0, nv)), targets (nh x 3, same order), radius (> 0 mesh units; <= 0: the
 *      default df_kelvinlet_guess_radius), nu (Poisson ratio of the kernel, [-1, 0.5]).
 * Out: V_out (nv x 3, may equal V): V + u(V) with the handles set exactly to their targets;
 *      *fit_residual (may be NULL): the largest |u(V_h) - d_h| over the handles before the snap
 *      (mesh units); *radius_used (may be NULL): the radius of the kernel.
 * Errors: DF_EINVAL (NULL, nv/nh < 1, nh > DF_KGUESS_MAX_HANDLES, handle out of range or
 * repeated, NaN/Inf in V or targets, radius or nu out of the Kelvinlet bounds), DF_ENOMEM,
 * DF_ESINGULAR (dgesv found the ridged system singular); V_out untouched on error.
 * Threads: OpenMP over vertices for the field evaluation; OpenBLAS/LAPACK for the solve. */
int df_kelvinlet_guess(const double *V, int32_t nv, const int32_t *handles, int32_t nh,
                       const double *targets, double radius, double nu, double *V_out,
                       double *fit_residual, double *radius_used, df_error *err);

#endif
