/* admm_resid.h — primal and dual residuals of the SC-L1 ADMM (Boyd et al. 2011, sec. 3.3) for the
 * stop test of df_admm_run. Private to core/admm (see admm.h for the stop rule). */
#ifndef DF_ADMM_RESID_H
#define DF_ADMM_RESID_H

#include <stdint.h>

#include "core/admm/admm_internal.h"

/* Copies of U, Z (and W, R_e X_e for the element family) taken before an iteration. */
typedef struct admm_resid {
    double *U, *Z;           /* nv x 3 each */
    double *W, *RX;          /* ne x 9 each; NULL for the vertex family */
    double pri_e, dual_e;    /* the same for the element block (gamma_e metric); element family only */
    double pri_z, dual_z;    /* set by admm_resid_measure: the Z-block's own relative residuals
                                ||dU|| / max(||Z + dU||, ||Z||) and ||dZ|| / ||U|| */
} admm_resid;

/* Allocates the copies for solver s. Errors: DF_ENOMEM (rs left empty). Caller frees with
 * admm_resid_free. */
int admm_resid_init(admm_resid *rs, const df_admm *s, df_error *err);

/* Frees the copies. NULL-safe, idempotent. */
void admm_resid_free(admm_resid *rs);

/* Records U, Z, W, R_e X_e of s: call right before an iteration. */
void admm_resid_snapshot(admm_resid *rs, const df_admm *s);

/* After the iteration's dual update, before any Anderson extrapolation: the relative primal and
 * dual residuals, both in the penalty metric (rho on the Z = V - Vrest block, gamma_e on the
 * F_e(V) = R_e X_e block):
 *   *pri  = ||r|| / max(||A x||, ||z||), r = (V - Vrest - Z, F_e(V) - R_e X_e) = (dU, dW),
 *           A x = (V - Vrest, F_e(V)) = (Z + dU, RX + dW), z = (Z, RX);
 *   *dual = ||s|| / max(||y||, ||z||), s = (dZ, dRX) (the change of the splitting variables,
 *           measured in the constraint space: Boyd's rho A^T B dz without the A^T factor),
 *           y = (U, W) (the scaled duals, in the same space); ||z|| in the denominator because y
 *           vanishes where the objective is locally flat (all moved vertices beyond s).
 * A zero numerator gives 0; a nonzero one over a zero scale gives +inf. */
void admm_resid_measure(admm_resid *rs, const df_admm *s, double *pri, double *dual);

/* The stop residual of one iteration (admm.h DF_ADMM_RESIDUAL), for the full and the active-set
 * run: max(|E - E_prev| / |E|, sqrt(tol) max(pri, dual)) from the objective E of the new iterate,
 * the previous one E_prev and the relative residuals pri, dual; +inf when hold (the iterate was
 * held back), when E or E_prev is not finite, or when the value is NaN. */
double admm_stop_residual(const df_admm *s, int hold, double E, double E_prev, double pri, double dual);

#endif
