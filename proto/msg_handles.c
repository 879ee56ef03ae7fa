/* msg_handles.c — handle set, handle move and move result bodies (messages.h).
 * handles: u64 session_id, u8 energy, u8 area_weighting, u8 accelerate, u8 anderson_m, f64 w, s,
 *   rho, tol, youngs, poisson, strain_min, strain_max, bending, u32 max_iters, u32 n_handles
 *   (92 bytes), n_handles x u32 index, u32 n_affine, n_affine x { u8 rows, rows x 3 f64 A (row-major),
 *   rows x f64 b, u32 n_indices, n_indices x u32 index } [, u32 options]
 * [options]: optional trailing DF_WORK_OPT_* bits (written only when non-zero; a body without
 *   them decodes with options 0, as before the field existed)  * handle_move: u64 session_id, u32 max_iters, u32 max_ms, u32 progress_every, u32 n_targets,
 *   n_targets x f64[3] [, u32 options]
 * move_result: u64 session_id, u64 version, u8 status, u32 iterations, f64 objective,
 *   f64 residual, f64 elapsed_ms   (45 bytes) */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/admm/admm_defaults.h" /* constants only: the solver owns its defaults */
#include "proto/codec_util.h"
#include "proto/messages.h"

static int indices_check(const int32_t *idx, uint32_t n, const char *M, const char *field,
                         df_error *err)
{
    if (n && !idx)
        return df_error_set(err, DF_EINVAL, "%s: %s is NULL with count %u", M, field, n);
    for (uint32_t i = 0; i < n; i++)
        if (idx[i] < 0 || (uint32_t)idx[i] >= DF_MAX_MESH_VERTICES)
            return df_error_set(err, DF_EINVAL, "%s: %s[%u] = %d out of range 0..%u", M, field, i,
                                idx[i], DF_MAX_MESH_VERTICES - 1);
    return DF_OK;
}

/* The optional trailing `options` u32 (DF_WORK_OPT_*) of handles and handle_move: 0 when the
 * body ends here; 4 more bytes hold it (*present = 1; unknown bits: DF_EPROTO_RESERVED); 1..3
 * are a cut field (DF_EPROTO_TRUNCATED); more are left for df_rd_end (DF_EPROTO_TRAILING). */
static uint32_t read_options(df_rd *r, uint8_t *present, uint32_t allowed)
{
    size_t left = r->rc ? 0 : r->n - r->off;
    *present = 0;
    if (left == 0 || left > 4)
        return 0;
    *present = 1;
    uint32_t o = df_rd_u32(r, "options");
    if (o & ~allowed)
        df_rd_fail(r, DF_EPROTO_RESERVED, "options", "unknown bits 0x%x",
                   (unsigned)(o & ~allowed));
    return o;
}

static int options_check(uint32_t o, uint8_t field, uint32_t allowed, const char *M, df_error *err)
{
    if (field > 1)
        return df_error_set(err, DF_EINVAL, "%s: options_field %u not 0/1", M, field);
    if (o & ~allowed)
        return df_error_set(err, DF_EPROTO_RESERVED, "%s: options 0x%x has unknown bits 0x%x", M,
                            (unsigned)o, (unsigned)(o & ~allowed));
    return DF_OK;
}

static int handles_check(const df_msg_handles *m, df_error *err)
{
    const char *M = "handles";
    if (m->session_id == 0)
        return df_error_set(err, DF_EINVAL, "%s: session_id 0 is not a session", M);
    int orc = options_check(m->options, m->options_field, DF_WORK_OPTS_NOT_MOVE, M, err);
    if (orc)
        return orc;
    if (m->energy < 1 || m->energy > DF_ENERGY_MAX)
        return df_error_set(err, DF_EINVAL, "%s: energy %u not in 1..%u", M, m->energy,
                            DF_ENERGY_MAX);
    if (!isfinite(m->w) || m->w < 0)
        return df_error_set(err, DF_EINVAL, "%s: w %g must be finite and >= 0", M, m->w);
    if (!isfinite(m->s) || !(m->s > 0))
        return df_error_set(err, DF_EINVAL, "%s: s %g must be finite and > 0", M, m->s);
    if (!isfinite(m->rho) || m->rho < 0)
        return df_error_set(err, DF_EINVAL, "%s: rho %g must be finite and >= 0 (0: adaptive)", M, m->rho);
    if (!isfinite(m->tol) || m->tol < 0)
        return df_error_set(err, DF_EINVAL, "%s: tol %g must be finite and >= 0", M, m->tol);
    if (!isfinite(m->youngs) || !(m->youngs > 0))
        return df_error_set(err, DF_EINVAL, "%s: youngs %g must be finite and > 0", M, m->youngs);
    if (!(m->poisson > -1 && m->poisson < 0.5))
        return df_error_set(err, DF_EINVAL, "%s: poisson %g not in (-1, 0.5)", M, m->poisson);
    if (!(m->strain_min > 0 && m->strain_min <= 1) || !isfinite(m->strain_max) ||
        !(m->strain_max >= 1))
        return df_error_set(err, DF_EINVAL, "%s: strain limits [%g, %g] need 0 < min <= 1 <= max",
                            M, m->strain_min, m->strain_max);
    if (!isfinite(m->bending) || m->bending < 0)
        return df_error_set(err, DF_EINVAL, "%s: bending %g must be finite and >= 0", M,
                            m->bending);
    if (m->area_weighting > 1 || m->accelerate > 1)
        return df_error_set(err, DF_EINVAL, "%s: area_weighting %u / accelerate %u not 0/1", M,
                            m->area_weighting, m->accelerate);
    if (m->anderson_m < 1 || m->anderson_m > DF_MAX_ANDERSON)
        return df_error_set(err, DF_EINVAL, "%s: anderson_m %u not in 1..%u", M, m->anderson_m,
                            DF_MAX_ANDERSON);
    if (m->max_iters < 1 || m->max_iters > DF_MAX_MOVE_ITERS)
        return df_error_set(err, DF_EINVAL, "%s: max_iters %u not in 1..%u", M, m->max_iters,
                            DF_MAX_MOVE_ITERS);
    if (m->n_handles < 1 || m->n_handles > DF_MAX_HANDLES)
        return df_error_set(err, DF_ELIMIT, "%s: n_handles %u not in 1..%u", M, m->n_handles,
                            DF_MAX_HANDLES);
    int rc = indices_check(m->handles, m->n_handles, M, "handles", err);
    if (rc)
        return rc;
    if (m->n_affine > DF_MAX_AFFINE_SETS)
        return df_error_set(err, DF_ELIMIT, "%s: %u affine sets exceed limit %u", M, m->n_affine,
                            DF_MAX_AFFINE_SETS);
    if (m->n_affine && !m->affine)
        return df_error_set(err, DF_EINVAL, "%s: affine is NULL with n_affine %u", M,
                            m->n_affine);
    for (uint32_t k = 0; k < m->n_affine; k++) {
        const df_msg_affine_set *a = &m->affine[k];
        if (a->rows < 1 || a->rows > 3)
            return df_error_set(err, DF_EINVAL, "%s: affine[%u].rows %u not in 1..3", M, k,
                                a->rows);
        if ((rc = df_check_finite(a->A, 3 * (size_t)a->rows, M, "affine.A", err)) ||
            (rc = df_check_finite(a->b, a->rows, M, "affine.b", err)))
            return rc;
        if (a->n_indices < 1 || a->n_indices > DF_MAX_HANDLES)
            return df_error_set(err, DF_ELIMIT, "%s: affine[%u].n_indices %u not in 1..%u", M, k,
                                a->n_indices, DF_MAX_HANDLES);
        if ((rc = indices_check(a->indices, a->n_indices, M, "affine.indices", err)))
            return rc;
    }
    return DF_OK;
}

int df_msg_handles_encode(const df_msg_handles *m, df_buf *out, df_error *err)
{
    int rc = handles_check(m, err);
    if (rc)
        return rc;
    int with_options = m->options != 0 || m->options_field;
    size_t size = 92 + 4 * (size_t)m->n_handles + 4 + (with_options ? 4 : 0);
    for (uint32_t k = 0; k < m->n_affine; k++)
        size += 1 + 32 * (size_t)m->affine[k].rows + 4 + 4 * (size_t)m->affine[k].n_indices;
    if ((rc = df_enc_reserve(out, size, "handles", err)))
        return rc;
    df_buf_put_u64(out, m->session_id);
    df_buf_put_u8(out, m->energy);
    df_buf_put_u8(out, m->area_weighting);
    df_buf_put_u8(out, m->accelerate);
    df_buf_put_u8(out, m->anderson_m);
    df_buf_put_f64(out, m->w);
    df_buf_put_f64(out, m->s);
    df_buf_put_f64(out, m->rho);
    df_buf_put_f64(out, m->tol);
    df_buf_put_f64(out, m->youngs);
    df_buf_put_f64(out, m->poisson);
    df_buf_put_f64(out, m->strain_min);
    df_buf_put_f64(out, m->strain_max);
    df_buf_put_f64(out, m->bending);
    df_buf_put_u32(out, m->max_iters);
    df_buf_put_u32(out, m->n_handles);
    for (uint32_t i = 0; i < m->n_handles; i++)
        df_buf_put_u32(out, (uint32_t)m->handles[i]);
    df_buf_put_u32(out, m->n_affine);
    for (uint32_t k = 0; k < m->n_affine; k++) {
        const df_msg_affine_set *a = &m->affine[k];
        df_buf_put_u8(out, a->rows);
        for (unsigned i = 0; i < 3u * a->rows; i++)
            df_buf_put_f64(out, a->A[i]);
        for (unsigned i = 0; i < a->rows; i++)
            df_buf_put_f64(out, a->b[i]);
        df_buf_put_u32(out, a->n_indices);
        for (uint32_t i = 0; i < a->n_indices; i++)
            df_buf_put_u32(out, (uint32_t)a->indices[i]);
    }
    if (with_options)
        df_buf_put_u32(out, m->options);
    return DF_OK;
}

static void affine_read(df_rd *r, df_msg_affine_set *a)
{
    *a = (df_msg_affine_set){0};
    a->rows = df_rd_u8(r, "affine.rows");
    if (!r->rc && (a->rows < 1 || a->rows > 3)) {
        df_rd_fail(r, DF_EINVAL, "affine.rows", "%u not in 1..3", a->rows);
        return;
    }
    for (unsigned i = 0; i < 3u * a->rows; i++)
        a->A[i] = df_rd_f64(r, "affine.A");
    for (unsigned i = 0; i < a->rows; i++)
        a->b[i] = df_rd_f64(r, "affine.b");
    a->n_indices = df_rd_u32(r, "affine.n_indices");
    if (!r->rc && a->n_indices > DF_MAX_HANDLES)
        df_rd_fail(r, DF_ELIMIT, "affine.n_indices", "%u exceeds limit %u", a->n_indices,
                   DF_MAX_HANDLES);
    df_rd_indices(r, &a->indices, a->n_indices, DF_MAX_MESH_VERTICES, "affine.indices");
}

int df_msg_handles_decode(const uint8_t *p, size_t n, df_msg_handles *m, df_error *err)
{
    df_rd r;
    df_msg_handles t = {0};
    df_rd_init(&r, p, n, "handles", err);
    t.session_id = df_rd_u64(&r, "session_id");
    t.energy = df_rd_u8(&r, "energy");
    t.area_weighting = df_rd_u8(&r, "area_weighting");
    t.accelerate = df_rd_u8(&r, "accelerate");
    t.anderson_m = df_rd_u8(&r, "anderson_m");
    t.w = df_rd_f64(&r, "w");
    t.s = df_rd_f64(&r, "s");
    t.rho = df_rd_f64(&r, "rho");
    t.tol = df_rd_f64(&r, "tol");
    t.youngs = df_rd_f64(&r, "youngs");
    t.poisson = df_rd_f64(&r, "poisson");
    t.strain_min = df_rd_f64(&r, "strain_min");
    t.strain_max = df_rd_f64(&r, "strain_max");
    t.bending = df_rd_f64(&r, "bending");
    t.max_iters = df_rd_u32(&r, "max_iters");
    t.n_handles = df_rd_u32(&r, "n_handles");
    if (!r.rc && t.n_handles > DF_MAX_HANDLES)
        df_rd_fail(&r, DF_ELIMIT, "n_handles", "%u exceeds limit %u", t.n_handles,
                   DF_MAX_HANDLES);
    df_rd_indices(&r, &t.handles, t.n_handles, DF_MAX_MESH_VERTICES, "handles");
    t.n_affine = df_rd_u32(&r, "n_affine");
    if (!r.rc && t.n_affine > DF_MAX_AFFINE_SETS)
        df_rd_fail(&r, DF_ELIMIT, "n_affine", "%u sets exceed limit %u", t.n_affine,
                   DF_MAX_AFFINE_SETS);
    df_rd_need_rows(&r, t.n_affine, 1 + 32 + 4, "n_affine");
    t.affine = df_rd_alloc(&r, t.n_affine, sizeof *t.affine, "affine");
    uint32_t got = 0;
    for (; got < t.n_affine && !r.rc; got++)
        affine_read(&r, &t.affine[got]);
    t.options = read_options(&r, &t.options_field, DF_WORK_OPTS_NOT_MOVE);
    int rc = df_rd_end(&r);
    if (!rc)
        rc = handles_check(&t, err);
    if (rc) {
        t.n_affine = got;
        df_msg_handles_free(&t);
        return rc;
    }
    *m = t;
    return DF_OK;
}

void df_msg_handles_free(df_msg_handles *m)
{
    if (!m)
        return;
    for (uint32_t k = 0; m->affine && k < m->n_affine; k++)
        free(m->affine[k].indices);
    free(m->affine);
    free(m->handles);
    m->affine = NULL;
    m->handles = NULL;
    m->n_affine = 0;
    m->n_handles = 0;
}

static int move_check(const df_msg_handle_move *m, df_error *err)
{
    const char *M = "handle_move";
    if (m->session_id == 0)
        return df_error_set(err, DF_EINVAL, "%s: session_id 0 is not a session", M);
    int orc = options_check(m->options, m->options_field, DF_WORK_OPTS_ALL, M, err);
    if (orc)
        return orc;
    if (m->max_iters > DF_MAX_MOVE_ITERS)
        return df_error_set(err, DF_EINVAL, "%s: max_iters %u exceeds %u", M, m->max_iters,
                            DF_MAX_MOVE_ITERS);
    if (m->n_targets < 1 || m->n_targets > DF_MAX_HANDLES)
        return df_error_set(err, DF_ELIMIT, "%s: n_targets %u not in 1..%u", M, m->n_targets,
                            DF_MAX_HANDLES);
    if (!m->targets)
        return df_error_set(err, DF_EINVAL, "%s: targets is NULL", M);
    return df_check_finite(m->targets, 3 * (size_t)m->n_targets, M, "targets", err);
}

int df_msg_handle_move_encode(const df_msg_handle_move *m, df_buf *out, df_error *err)
{
    int rc = move_check(m, err);
    int with_options = m->options != 0 || m->options_field;
    if (rc || (rc = df_enc_reserve(out, 24 + 24 * (size_t)m->n_targets + (with_options ? 4 : 0),
                                   "handle_move", err)))
        return rc;
    df_buf_put_u64(out, m->session_id);
    df_buf_put_u32(out, m->max_iters);
    df_buf_put_u32(out, m->max_ms);
    df_buf_put_u32(out, m->progress_every);
    df_buf_put_u32(out, m->n_targets);
    for (size_t i = 0; i < 3 * (size_t)m->n_targets; i++)
        df_buf_put_f64(out, m->targets[i]);
    if (with_options)
        df_buf_put_u32(out, m->options);
    return DF_OK;
}

int df_msg_handle_move_decode(const uint8_t *p, size_t n, df_msg_handle_move *m, df_error *err)
{
    df_rd r;
    df_msg_handle_move t;
    df_rd_init(&r, p, n, "handle_move", err);
    t.session_id = df_rd_u64(&r, "session_id");
    t.max_iters = df_rd_u32(&r, "max_iters");
    t.max_ms = df_rd_u32(&r, "max_ms");
    t.progress_every = df_rd_u32(&r, "progress_every");
    t.n_targets = df_rd_u32(&r, "n_targets");
    if (!r.rc && t.n_targets > DF_MAX_HANDLES)
        df_rd_fail(&r, DF_ELIMIT, "n_targets", "%u exceeds limit %u", t.n_targets,
                   DF_MAX_HANDLES);
    df_rd_need_rows(&r, t.n_targets, 24, "n_targets");
    t.targets = df_rd_alloc(&r, 3 * (size_t)t.n_targets, sizeof(double), "targets");
    for (size_t i = 0; !r.rc && i < 3 * (size_t)t.n_targets; i++)
        t.targets[i] = df_rd_f64(&r, "targets");
    t.options = read_options(&r, &t.options_field, DF_WORK_OPTS_ALL);
    int rc = df_rd_end(&r);
    if (rc || (rc = move_check(&t, err))) {
        free(t.targets);
        return rc;
    }
    *m = t;
    return DF_OK;
}

void df_msg_handle_move_free(df_msg_handle_move *m)
{
    if (!m)
        return;
    free(m->targets);
    m->targets = NULL;
    m->n_targets = 0;
}

static int result_check(const df_msg_move_result *m, df_error *err)
{
    const char *M = "move_result";
    if (m->session_id == 0)
        return df_error_set(err, DF_EINVAL, "%s: session_id 0 is not a session", M);
    if (m->status < 1 || m->status > DF_MOVE_STATUS_MAX)
        return df_error_set(err, DF_EINVAL, "%s: status %u not in 1..%u", M, m->status,
                            DF_MOVE_STATUS_MAX);
    if (!isfinite(m->objective) || !isfinite(m->residual) || m->residual < 0 ||
        !isfinite(m->elapsed_ms) || m->elapsed_ms < 0)
        return df_error_set(err, DF_EINVAL,
                            "%s: objective %g, residual %g, elapsed_ms %g must be finite "
                            "(residual, elapsed >= 0)", M, m->objective, m->residual,
                            m->elapsed_ms);
    return DF_OK;
}

int df_msg_move_result_encode(const df_msg_move_result *m, df_buf *out, df_error *err)
{
    int rc = result_check(m, err);
    if (rc || (rc = df_enc_reserve(out, 45, "move_result", err)))
        return rc;
    df_buf_put_u64(out, m->session_id);
    df_buf_put_u64(out, m->version);
    df_buf_put_u8(out, m->status);
    df_buf_put_u32(out, m->iterations);
    df_buf_put_f64(out, m->objective);
    df_buf_put_f64(out, m->residual);
    df_buf_put_f64(out, m->elapsed_ms);
    return DF_OK;
}

int df_msg_move_result_decode(const uint8_t *p, size_t n, df_msg_move_result *m, df_error *err)
{
    df_rd r;
    df_msg_move_result t;
    df_rd_init(&r, p, n, "move_result", err);
    t.session_id = df_rd_u64(&r, "session_id");
    t.version = df_rd_u64(&r, "version");
    t.status = df_rd_u8(&r, "status");
    t.iterations = df_rd_u32(&r, "iterations");
    t.objective = df_rd_f64(&r, "objective");
    t.residual = df_rd_f64(&r, "residual");
    t.elapsed_ms = df_rd_f64(&r, "elapsed_ms");
    int rc = df_rd_end(&r);
    if (rc || (rc = result_check(&t, err)))
        return rc;
    *m = t;
    return DF_OK;
}

void df_msg_handles_defaults(df_msg_handles *m, uint8_t energy)
{
    memset(m, 0, sizeof *m);
    m->energy = energy >= 1 && energy <= DF_ENERGY_MAX ? energy : DF_ENERGY_ARAP;
#define DF_X_DEFAULT(field, value) m->field = (value);
    DF_ADMM_DEFAULTS(DF_X_DEFAULT)
    if (m->energy == DF_ENERGY_NEOHOOKEAN) {
        DF_ADMM_DEFAULTS_NEOHOOKEAN(DF_X_DEFAULT)
    }
#undef DF_X_DEFAULT
}
