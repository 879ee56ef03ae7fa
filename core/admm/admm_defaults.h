/* admm_defaults.h — the one place of the SC-L1 ADMM defaults (the paper's settings): plain
 * macros, no includes, no code, so every layer may use them without linking the solver:
 * core/admm (df_admm_params_default), proto (df_msg_handles_defaults, the wire defaults every
 * client starts from), deformctl's help text; tests/integration/test_schema.py checks the Python
 * client's HandleParams against them.
 * DF_ADMM_DEFAULTS(X): X(field, value) for every field shared by df_admm_params,
 * df_msg_handles and Python HandleParams; DF_ADMM_DEFAULTS_NEOHOOKEAN(X): the overrides for the
 * Neo-Hookean energy (its stiffness is in Pa, so w scales with it). */
#ifndef DF_CORE_ADMM_DEFAULTS_H
#define DF_CORE_ADMM_DEFAULTS_H

#define DF_ADMM_DEFAULT_W 1e-4          /* SC-L1 locality weight */
#define DF_ADMM_DEFAULT_S 0.01          /* SC-L1 threshold, mesh units */
#define DF_ADMM_DEFAULT_RHO 0           /* ADMM penalty: 0 = adaptive (admm.h DF_ADMM_RHO_RULE) */
#define DF_ADMM_DEFAULT_TOL 1e-11       /* residual tolerance */
#define DF_ADMM_DEFAULT_MAX_ITERS 500   /* iteration budget of a move */
#define DF_ADMM_DEFAULT_YOUNGS 1e7      /* Neo-Hookean Young's modulus, Pa */
#define DF_ADMM_DEFAULT_POISSON 0.45    /* Neo-Hookean Poisson ratio */
#define DF_ADMM_DEFAULT_ANDERSON_M 5    /* Anderson history (when accelerated) */
#define DF_ADMM_DEFAULT_STRAIN_MIN 0.9  /* cloth stretch limits */
#define DF_ADMM_DEFAULT_STRAIN_MAX 1.1
#define DF_ADMM_DEFAULT_BENDING 1e-3    /* cloth bending stiffness */
#define DF_ADMM_DEFAULT_NH_W 500        /* Neo-Hookean: w (its rho is adaptive too) */

#define DF_ADMM_DEFAULTS(X)                                                                  \
    X(w, DF_ADMM_DEFAULT_W) X(s, DF_ADMM_DEFAULT_S) X(rho, DF_ADMM_DEFAULT_RHO)              \
    X(tol, DF_ADMM_DEFAULT_TOL) X(max_iters, DF_ADMM_DEFAULT_MAX_ITERS)                      \
    X(youngs, DF_ADMM_DEFAULT_YOUNGS) X(poisson, DF_ADMM_DEFAULT_POISSON)                    \
    X(area_weighting, 0) X(accelerate, 0) X(anderson_m, DF_ADMM_DEFAULT_ANDERSON_M)          \
    X(strain_min, DF_ADMM_DEFAULT_STRAIN_MIN) X(strain_max, DF_ADMM_DEFAULT_STRAIN_MAX)      \
    X(bending, DF_ADMM_DEFAULT_BENDING)
#define DF_ADMM_DEFAULTS_NEOHOOKEAN(X) X(w, DF_ADMM_DEFAULT_NH_W)

#endif
