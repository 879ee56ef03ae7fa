/* msg_brush.c — brush stroke bodies (messages.h).
 * brush (begin): u64 session_id, u8 type, u8 dim, u8 falloff, u8 integrator, u16 steps,
 *   u8 moving, u8 has_mirror, f64 radius, ratio, nu, strength, center[3], move[3], twist[3],
 *   scale, matrix[9], mirror_point[3], mirror_normal[3], u32 n_pinned, u8 pin_flags,
 *   n_pinned x f64[3]   (253 + 24 n_pinned bytes)
 *   [u16 use_session]   optional trailing field (DF_BS_* bits); absent = 0, so bodies of
 *                       clients that predate it decode unchanged (+2 bytes when present)
 *   [u32 options]       optional, only after use_session: DF_WORK_OPT_* bits (+4 bytes)
 *   [u8 surface]        optional, only after options: 0/1 (absent = 0; +7 bytes in all)
 * brush_update: u64 session_id, f64 move[3], twist[3], scale, matrix[9]   (136 bytes)
 * brush_param: u64 session_id, u8 param, f64 value                        (17 bytes) */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "proto/codec_util.h"
#include "proto/messages.h"

#define BRUSH_FIXED 253u

static int load_check(const double *move, const double *twist, double scale,
                      const double *matrix, const char *M, df_error *err)
{
    int rc = df_check_finite(move, 3, M, "move", err);
    if (!rc)
        rc = df_check_finite(twist, 3, M, "twist", err);
    if (!rc)
        rc = df_check_finite(&scale, 1, M, "scale", err);
    if (!rc)
        rc = df_check_finite(matrix, 9, M, "matrix", err);
    return rc;
}

static int brush_check(const df_msg_brush *m, df_error *err)
{
    const char *M = "brush";
    if (m->session_id == 0)
        return df_error_set(err, DF_EINVAL, "%s: session_id 0 is not a session", M);
    if (m->type < 1 || m->type > DF_BRUSH_TYPE_MAX)
        return df_error_set(err, DF_EINVAL, "%s: type %u not in 1..%u", M, m->type,
                            DF_BRUSH_TYPE_MAX);
    if (m->dim != 2 && m->dim != 3)
        return df_error_set(err, DF_EINVAL, "%s: dim %u not 2 or 3", M, m->dim);
    if (m->falloff < 1 || m->falloff > DF_MAX_FALLOFF)
        return df_error_set(err, DF_EINVAL, "%s: falloff %u not in 1..%u", M, m->falloff,
                            DF_MAX_FALLOFF);
    if (m->integrator != DF_INTEG_EULER && m->integrator != DF_INTEG_RK4)
        return df_error_set(err, DF_EINVAL, "%s: integrator %u not 1 (euler) or 2 (rk4)", M,
                            m->integrator);
    if (m->steps < 1 || m->steps > DF_MAX_BRUSH_STEPS)
        return df_error_set(err, DF_EINVAL, "%s: steps %u not in 1..%u", M, m->steps,
                            DF_MAX_BRUSH_STEPS);
    if (m->moving > 1 || m->has_mirror > 1)
        return df_error_set(err, DF_EINVAL, "%s: moving %u / has_mirror %u not 0/1", M, m->moving,
                            m->has_mirror);
    if (!isfinite(m->radius) || !(m->radius > 0))
        return df_error_set(err, DF_EINVAL, "%s: radius %g must be finite and > 0", M, m->radius);
    if (!isfinite(m->ratio) || !(m->ratio > 1))
        return df_error_set(err, DF_EINVAL, "%s: ratio %g must be finite and > 1", M, m->ratio);
    if (isnan(m->nu))
        return df_error_set(err, DF_EINVAL, "%s: nu is NaN (use a number or +-inf)", M);
    int rc = df_check_finite(&m->strength, 1, M, "strength", err);
    if (!rc)
        rc = df_check_finite(m->center, 3, M, "center", err);
    if (!rc)
        rc = load_check(m->move, m->twist, m->scale, m->matrix, M, err);
    if (!rc)
        rc = df_check_finite(m->mirror_point, 3, M, "mirror_point", err);
    if (!rc)
        rc = df_check_finite(m->mirror_normal, 3, M, "mirror_normal", err);
    if (rc)
        return rc;
    const double *nn = m->mirror_normal;
    if (m->has_mirror && nn[0] == 0 && nn[1] == 0 && nn[2] == 0)
        return df_error_set(err, DF_EINVAL, "%s: mirror_normal is the zero vector", M);
    if (m->n_pinned > DF_MAX_PINNED_POINTS)
        return df_error_set(err, DF_ELIMIT, "%s: %u pinned points exceed limit %u", M,
                            m->n_pinned, DF_MAX_PINNED_POINTS);
    if (m->n_pinned ? (m->pin_flags < 1 || m->pin_flags > 3) : m->pin_flags != 0)
        return df_error_set(err, DF_EINVAL, "%s: pin_flags %u invalid with %u pinned points "
                            "(need 0 without pins, else 1..3)", M, m->pin_flags, m->n_pinned);
    if (m->n_pinned && !m->pinned)
        return df_error_set(err, DF_EINVAL, "%s: pinned is NULL with n_pinned %u", M,
                            m->n_pinned);
    if (m->use_session & ~DF_BS_ALL)
        return df_error_set(err, DF_EPROTO_RESERVED, "%s: use_session bits 0x%x are not "
                            "defined (known: 0x%x)", M, m->use_session & ~DF_BS_ALL, DF_BS_ALL);
    if (m->use_session_field > 1)
        return df_error_set(err, DF_EINVAL, "%s: use_session_field %u not 0/1", M,
                            m->use_session_field);
    if (m->options & ~DF_WORK_OPTS_NOT_MOVE)
        return df_error_set(err, DF_EPROTO_RESERVED, "%s: options 0x%x has unknown bits 0x%x", M,
                            (unsigned)m->options, (unsigned)(m->options & ~DF_WORK_OPTS_NOT_MOVE));
    if (m->options_field > 1)
        return df_error_set(err, DF_EINVAL, "%s: options_field %u not 0/1", M, m->options_field);
    if (m->surface > 1)
        return df_error_set(err, DF_EINVAL, "%s: surface %u not 0 or 1", M, m->surface);
    return df_check_finite(m->pinned, 3 * (size_t)m->n_pinned, M, "pinned", err);
}

static void put_f64s(df_buf *out, const double *v, size_t n)
{
    for (size_t i = 0; i < n; i++)
        df_buf_put_f64(out, v[i]);
}

static void get_f64s(df_rd *r, double *v, size_t n, const char *field)
{
    for (size_t i = 0; i < n; i++)
        v[i] = df_rd_f64(r, field);
}

int df_msg_brush_encode(const df_msg_brush *m, df_buf *out, df_error *err)
{
    int rc = brush_check(m, err);
    int surf = m->surface != 0, opts = surf || m->options != 0 || m->options_field;
    int trailer = m->use_session != 0 || m->use_session_field || opts;
    size_t size = BRUSH_FIXED + 24 * (size_t)m->n_pinned + (trailer ? 2 : 0) + (opts ? 4 : 0) +
                  (surf ? 1 : 0);
    if (rc || (rc = df_enc_reserve(out, size, "brush", err)))
        return rc;
    df_buf_put_u64(out, m->session_id);
    df_buf_put_u8(out, m->type);
    df_buf_put_u8(out, m->dim);
    df_buf_put_u8(out, m->falloff);
    df_buf_put_u8(out, m->integrator);
    df_buf_put_u16(out, m->steps);
    df_buf_put_u8(out, m->moving);
    df_buf_put_u8(out, m->has_mirror);
    df_buf_put_f64(out, m->radius);
    df_buf_put_f64(out, m->ratio);
    df_buf_put_f64(out, m->nu);
    df_buf_put_f64(out, m->strength);
    put_f64s(out, m->center, 3);
    put_f64s(out, m->move, 3);
    put_f64s(out, m->twist, 3);
    df_buf_put_f64(out, m->scale);
    put_f64s(out, m->matrix, 9);
    put_f64s(out, m->mirror_point, 3);
    put_f64s(out, m->mirror_normal, 3);
    df_buf_put_u32(out, m->n_pinned);
    df_buf_put_u8(out, m->pin_flags);
    put_f64s(out, m->pinned, 3 * (size_t)m->n_pinned);
    if (trailer)
        df_buf_put_u16(out, m->use_session);
    if (opts)
        df_buf_put_u32(out, m->options);
    if (surf)
        df_buf_put_u8(out, m->surface);
    return DF_OK;
}

int df_msg_brush_decode(const uint8_t *p, size_t n, df_msg_brush *m, df_error *err)
{
    df_rd r;
    df_msg_brush t;
    df_rd_init(&r, p, n, "brush", err);
    t.session_id = df_rd_u64(&r, "session_id");
    t.type = df_rd_u8(&r, "type");
    t.dim = df_rd_u8(&r, "dim");
    t.falloff = df_rd_u8(&r, "falloff");
    t.integrator = df_rd_u8(&r, "integrator");
    t.steps = df_rd_u16(&r, "steps");
    t.moving = df_rd_u8(&r, "moving");
    t.has_mirror = df_rd_u8(&r, "has_mirror");
    t.radius = df_rd_f64(&r, "radius");
    t.ratio = df_rd_f64(&r, "ratio");
    t.nu = df_rd_f64(&r, "nu");
    t.strength = df_rd_f64(&r, "strength");
    get_f64s(&r, t.center, 3, "center");
    get_f64s(&r, t.move, 3, "move");
    get_f64s(&r, t.twist, 3, "twist");
    t.scale = df_rd_f64(&r, "scale");
    get_f64s(&r, t.matrix, 9, "matrix");
    get_f64s(&r, t.mirror_point, 3, "mirror_point");
    get_f64s(&r, t.mirror_normal, 3, "mirror_normal");
    t.n_pinned = df_rd_u32(&r, "n_pinned");
    if (!r.rc && t.n_pinned > DF_MAX_PINNED_POINTS)
        df_rd_fail(&r, DF_ELIMIT, "n_pinned", "%u pinned points exceed limit %u", t.n_pinned,
                   DF_MAX_PINNED_POINTS);
    t.pin_flags = df_rd_u8(&r, "pin_flags");
    df_rd_need_rows(&r, t.n_pinned, 24, "n_pinned");
    t.pinned = df_rd_alloc(&r, 3 * (size_t)t.n_pinned, sizeof(double), "pinned");
    if (!r.rc)
        get_f64s(&r, t.pinned, 3 * (size_t)t.n_pinned, "pinned");
    t.use_session = 0;
    t.use_session_field = !r.rc && r.off < r.n; /* the optional trailer (else: old layout) */
    if (t.use_session_field)
        t.use_session = df_rd_u16(&r, "use_session");
    t.options = 0;
    t.options_field = !r.rc && t.use_session_field && r.off < r.n && r.n - r.off <= 5;
    if (t.options_field) /* 1..3 bytes: a cut field (truncated); more than 5: trailing */
        t.options = df_rd_u32(&r, "options");
    t.surface = !r.rc && t.options_field && r.off < r.n ? df_rd_u8(&r, "surface") : 0;
    int rc = df_rd_end(&r);
    if (rc || (rc = brush_check(&t, err))) {
        free(t.pinned);
        return rc;
    }
    *m = t;
    return DF_OK;
}

void df_msg_brush_free(df_msg_brush *m)
{
    if (!m)
        return;
    free(m->pinned);
    m->pinned = NULL;
    m->n_pinned = 0;
}

static int update_check(const df_msg_brush_update *m, df_error *err)
{
    if (m->session_id == 0)
        return df_error_set(err, DF_EINVAL, "brush_update: session_id 0 is not a session");
    return load_check(m->move, m->twist, m->scale, m->matrix, "brush_update", err);
}

int df_msg_brush_update_encode(const df_msg_brush_update *m, df_buf *out, df_error *err)
{
    int rc = update_check(m, err);
    if (rc || (rc = df_enc_reserve(out, 136, "brush_update", err)))
        return rc;
    df_buf_put_u64(out, m->session_id);
    put_f64s(out, m->move, 3);
    put_f64s(out, m->twist, 3);
    df_buf_put_f64(out, m->scale);
    put_f64s(out, m->matrix, 9);
    return DF_OK;
}

int df_msg_brush_update_decode(const uint8_t *p, size_t n, df_msg_brush_update *m, df_error *err)
{
    df_rd r;
    df_msg_brush_update t;
    df_rd_init(&r, p, n, "brush_update", err);
    t.session_id = df_rd_u64(&r, "session_id");
    get_f64s(&r, t.move, 3, "move");
    get_f64s(&r, t.twist, 3, "twist");
    t.scale = df_rd_f64(&r, "scale");
    get_f64s(&r, t.matrix, 9, "matrix");
    int rc = df_rd_end(&r);
    if (rc || (rc = update_check(&t, err)))
        return rc;
    *m = t;
    return DF_OK;
}

static int param_check(const df_msg_brush_param *m, df_error *err)
{
    const char *M = "brush_param";
    double v = m->value;
    if (m->session_id == 0)
        return df_error_set(err, DF_EINVAL, "%s: session_id 0 is not a session", M);
    switch (m->param) {
    case DF_BP_RADIUS:
        if (!isfinite(v) || !(v > 0))
            return df_error_set(err, DF_EINVAL, "%s: radius %g must be finite and > 0", M, v);
        return DF_OK;
    case DF_BP_NU:
        if (isnan(v))
            return df_error_set(err, DF_EINVAL, "%s: nu is NaN", M);
        return DF_OK;
    case DF_BP_STRENGTH:
        if (!isfinite(v))
            return df_error_set(err, DF_EINVAL, "%s: strength %g must be finite", M, v);
        return DF_OK;
    case DF_BP_FALLOFF:
        if (!(v >= 1 && v <= DF_MAX_FALLOFF) || v != floor(v))
            return df_error_set(err, DF_EINVAL, "%s: falloff %g not an integer in 1..%u", M, v,
                                DF_MAX_FALLOFF);
        return DF_OK;
    case DF_BP_RATIO:
        if (!isfinite(v) || !(v > 1))
            return df_error_set(err, DF_EINVAL, "%s: ratio %g must be finite and > 1", M, v);
        return DF_OK;
    default:
        return df_error_set(err, DF_EINVAL, "%s: param %u not in 1..%u", M, m->param, DF_BP_MAX);
    }
}

int df_msg_brush_param_encode(const df_msg_brush_param *m, df_buf *out, df_error *err)
{
    int rc = param_check(m, err);
    if (rc || (rc = df_enc_reserve(out, 17, "brush_param", err)))
        return rc;
    df_buf_put_u64(out, m->session_id);
    df_buf_put_u8(out, m->param);
    df_buf_put_f64(out, m->value);
    return DF_OK;
}

int df_msg_brush_param_decode(const uint8_t *p, size_t n, df_msg_brush_param *m, df_error *err)
{
    df_rd r;
    df_msg_brush_param t;
    df_rd_init(&r, p, n, "brush_param", err);
    t.session_id = df_rd_u64(&r, "session_id");
    t.param = df_rd_u8(&r, "param");
    t.value = df_rd_f64(&r, "value");
    int rc = df_rd_end(&r);
    if (rc || (rc = param_check(&t, err)))
        return rc;
    *m = t;
    return DF_OK;
}

void df_msg_brush_defaults(df_msg_brush *m)
{
    memset(m, 0, sizeof *m);
#define DF_X_DEFAULT(field, value) m->field = (value);
    DF_WIRE_BRUSH_DEFAULTS(DF_X_DEFAULT)
#undef DF_X_DEFAULT
    m->mirror_normal[0] = 1;
}
