/* admm_params.c — default parameters and their validation (see admm.h). */
#include <math.h>
#include <string.h>

#include "core/admm/admm_defaults.h"
#include "core/admm/admm_internal.h"

void df_admm_params_default(df_admm_params *p, df_admm_energy energy)
{
    if (!p) return;
    memset(p, 0, sizeof(*p));
    p->energy = energy;
#define DF_X_DEFAULT(field, value) p->field = (value);
    DF_ADMM_DEFAULTS(DF_X_DEFAULT)
    if (energy == DF_ADMM_NEOHOOKEAN) {
        DF_ADMM_DEFAULTS_NEOHOOKEAN(DF_X_DEFAULT)
    }
#undef DF_X_DEFAULT
}

int admm_validate_params(const df_admm_params *p, df_error *err)
{
    if (p->energy < DF_ADMM_ARAP || p->energy > DF_ADMM_POLYLINE)
        return df_error_set(err, DF_EINVAL, "admm: unknown energy %d", (int)p->energy);
    if (!(p->w >= 0) || !isfinite(p->w)) return df_error_set(err, DF_EINVAL, "admm: w = %g must be finite and >= 0", p->w);
    if (!(p->s > 0) || !isfinite(p->s)) return df_error_set(err, DF_EINVAL, "admm: s = %g must be finite and > 0", p->s);
    if (!isfinite(p->rho)) return df_error_set(err, DF_EINVAL, "admm: rho = %g must be finite (> 0, or <= 0 for the adaptive penalty)", p->rho);
    if (!(p->tol >= 0) || !isfinite(p->tol)) return df_error_set(err, DF_EINVAL, "admm: tol = %g must be finite and >= 0", p->tol);
    if (p->max_iters < 1 || p->max_iters > DF_ADMM_MAX_ITERS_LIMIT)
        return df_error_set(err, DF_EINVAL, "admm: max_iters = %d outside [1, %d]", p->max_iters, DF_ADMM_MAX_ITERS_LIMIT);
    if (p->energy == DF_ADMM_NEOHOOKEAN) {
        if (!(p->youngs > 0) || !isfinite(p->youngs)) return df_error_set(err, DF_EINVAL, "admm: Young's modulus %g must be > 0", p->youngs);
        if (!(p->poisson > -1.0 && p->poisson < 0.5)) return df_error_set(err, DF_EINVAL, "admm: Poisson ratio %g outside (-1, 0.5)", p->poisson);
    }
    if (p->threads < 0 || p->threads > 1024) return df_error_set(err, DF_EINVAL, "admm: threads = %d outside [0, 1024]", p->threads);
    if (p->active < 0 || p->active > 1) return df_error_set(err, DF_EINVAL, "admm: active = %d must be 0 or 1", p->active);
    if (p->active_band < 0 || p->active_band > 64)
        return df_error_set(err, DF_EINVAL, "admm: active_band = %d outside [0, 64] (0: default)", p->active_band);
    if (p->active_check_every < 0 || p->active_check_every > DF_ADMM_MAX_ITERS_LIMIT)
        return df_error_set(err, DF_EINVAL, "admm: active_check_every = %d outside [0, %d] (0: default)",
                            p->active_check_every, DF_ADMM_MAX_ITERS_LIMIT);
    if (!(p->active_tail >= 0) || !isfinite(p->active_tail))
        return df_error_set(err, DF_EINVAL, "admm: active_tail = %g must be finite and >= 0 (0: off)", p->active_tail);
    if (p->accelerate && (p->anderson_m < 1 || p->anderson_m > DF_ADMM_MAX_ANDERSON))
        return df_error_set(err, DF_EINVAL, "admm: anderson_m = %d outside [1, %d]", p->anderson_m, DF_ADMM_MAX_ANDERSON);
    if (p->energy == DF_ADMM_CLOTH) {
        if (!(p->strain_min > 0 && p->strain_min <= 1.0 && p->strain_max >= 1.0) || !isfinite(p->strain_max))
            return df_error_set(err, DF_EINVAL, "admm: strain limits [%g, %g] must satisfy 0 < min <= 1 <= max", p->strain_min, p->strain_max);
        if (!(p->bending >= 0) || !isfinite(p->bending)) return df_error_set(err, DF_EINVAL, "admm: bending %g must be >= 0", p->bending);
    }
    return DF_OK;
}
