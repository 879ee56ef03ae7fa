/* admm_resid.c — primal and dual residuals of the ADMM iteration for the stop test (see
 * admm_resid.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/admm/admm_resid.h"

int admm_resid_init(admm_resid *rs, const df_admm *s, df_error *err)
{
    memset(rs, 0, sizeof(*rs));
    size_t n3 = 3 * (size_t)s->nv, n9 = s->family == ADMM_FAM_ELEMENT ? 9 * (size_t)s->ne : 0;
    rs->U = malloc((n3 ? n3 : 1) * sizeof(double));
    rs->Z = malloc((n3 ? n3 : 1) * sizeof(double));
    if (n9) {
        rs->W = malloc(n9 * sizeof(double));
        rs->RX = malloc(n9 * sizeof(double));
    }
    if (!rs->U || !rs->Z || (n9 && (!rs->W || !rs->RX))) {
        admm_resid_free(rs);
        return df_error_set(err, DF_ENOMEM, "admm_run: out of memory (residual buffers)");
    }
    return DF_OK;
}

void admm_resid_free(admm_resid *rs)
{
    if (!rs) return;
    free(rs->U); free(rs->Z); free(rs->W); free(rs->RX);
    memset(rs, 0, sizeof(*rs));
}

void admm_resid_snapshot(admm_resid *rs, const df_admm *s)
{
    size_t n3 = 3 * (size_t)s->nv;
    memcpy(rs->U, s->U, n3 * sizeof(double));
    memcpy(rs->Z, s->Z, n3 * sizeof(double));
    if (rs->W) {
        size_t n9 = 9 * (size_t)s->ne;
        memcpy(rs->W, s->W, n9 * sizeof(double));
        memcpy(rs->RX, s->RX, n9 * sizeof(double));
    }
}

static double ratio(double num2, double den2)
{
    if (num2 == 0.0) return 0.0;
    if (!(den2 > 0.0)) return INFINITY;
    return sqrt(num2 / den2);
}

void admm_resid_measure(admm_resid *rs, const df_admm *s, double *pri, double *dual)
{
    /* squared norms: r, A x, z, s, y */
    double r2 = 0, ax2 = 0, z2 = 0, s2 = 0, y2 = 0;
    const double rho = s->p.rho;
    {
        double a = 0, b = 0, c = 0, d = 0, e = 0;
        for (int64_t o = 0; o < 3 * (int64_t)s->nv; o++) {
            double du = s->U[o] - rs->U[o], dz = s->Z[o] - rs->Z[o], ax = s->Z[o] + du;
            a += du * du; b += ax * ax; c += s->Z[o] * s->Z[o]; d += dz * dz; e += s->U[o] * s->U[o];
        }
        r2 += rho * a; ax2 += rho * b; z2 += rho * c; s2 += rho * d; y2 += rho * e;
        rs->pri_z = ratio(a, b > c ? b : c);
        rs->dual_z = ratio(d, e);
    }
    if (rs->W) {
        double a = 0, b = 0, c = 0, d = 0, e = 0;
        #pragma omp parallel for schedule(static) num_threads(s->nthreads) reduction(+ : a, b, c, d, e)
        for (int32_t el = 0; el < s->ne; el++) {
            const double g = s->gam[el];
            const double *W = s->W + 9 * (size_t)el, *W0 = rs->W + 9 * (size_t)el;
            const double *RX = s->RX + 9 * (size_t)el, *RX0 = rs->RX + 9 * (size_t)el;
            double ea = 0, eb = 0, ec = 0, ed = 0, ee = 0;
            for (int k = 0; k < 9; k++) {
                double dw = W[k] - W0[k], drx = RX[k] - RX0[k], f = RX[k] + dw;
                ea += dw * dw; eb += f * f; ec += RX[k] * RX[k]; ed += drx * drx; ee += W[k] * W[k];
            }
            a += g * ea; b += g * eb; c += g * ec; d += g * ed; e += g * ee;
        }
        r2 += a; ax2 += b; z2 += c; s2 += d; y2 += e;
        rs->pri_e = ratio(a, b > c ? b : c);
        rs->dual_e = ratio(d, e);
    }
    *pri = ratio(r2, ax2 > z2 ? ax2 : z2);
    /* the duals vanish where the SC-L1 term is flat (every moved vertex beyond s) and an element
     * energy is at rest: relative to ||y|| alone the dual residual is then round-off over
     * round-off, O(1) at an exact fixed point; max(||y||, ||z||) keeps it relative */
    *dual = ratio(s2, y2 > z2 ? y2 : z2);
}

double admm_stop_residual(const df_admm *s, int hold, double E, double E_prev, double pri, double dual)
{
    if (hold || !isfinite(E) || !isfinite(E_prev)) return INFINITY;
    const double sq_tol = sqrt(s->p.tol);
    double dE = fabs(E - E_prev), rel = dE == 0.0 ? 0.0 : dE / fabs(E);
    double pd = sq_tol > 0 ? sq_tol * (pri > dual ? pri : dual) : 0.0;
    double r = rel > pd ? rel : pd;
    return isnan(r) ? INFINITY : r;
}
