/* msg_brush_state.c — session brush state bodies (messages.h, PROTOCOL.md 4.14a-4.14c).
 * values (86 bytes): u8 type, u8 falloff, u8 integrator, u8 has_mirror, u16 steps,
 *   f64 radius, nu, strength, ratio, mirror_point[3], mirror_normal[3]
 * brush_state_set: u64 session_id, u16 mask, values                              (96 bytes)
 * brush_state: u64 session_id, u64 seq, u16 changed, u8 origin_kind, u64 origin_id,
 *   str origin_name, values                                     (115 + name bytes)
 * brush_cursor: u64 session_id, u8 origin_kind, u64 origin_id, u8 flags, f64 center[3],
 *   f64 radius                                                                   (50 bytes) */
#include <math.h>
#include <string.h>

#include "proto/codec_util.h"
#include "proto/messages.h"

#define VALUES_BYTES 86u

int df_msg_brush_values_check(const df_msg_brush_values *v, unsigned mask, const char *M,
                              df_error *err)
{
    if (mask & ~DF_BS_ALL)
        return df_error_set(err, DF_EPROTO_RESERVED, "%s: field bits 0x%x are not defined "
                            "(known: 0x%x)", M, mask & ~DF_BS_ALL, DF_BS_ALL);
    if ((mask & DF_BS_TYPE) && (v->type < 1 || v->type > DF_BRUSH_TYPE_MAX))
        return df_error_set(err, DF_EINVAL, "%s: type %u not in 1..%u", M, v->type,
                            DF_BRUSH_TYPE_MAX);
    if ((mask & DF_BS_RADIUS) && (!isfinite(v->radius) || !(v->radius > 0)))
        return df_error_set(err, DF_EINVAL, "%s: radius %g must be finite and > 0", M,
                            v->radius);
    if ((mask & DF_BS_NU) && isnan(v->nu))
        return df_error_set(err, DF_EINVAL, "%s: nu is NaN (use a number or +-inf)", M);
    if ((mask & DF_BS_STRENGTH) && !isfinite(v->strength))
        return df_error_set(err, DF_EINVAL, "%s: strength %g must be finite", M, v->strength);
    if ((mask & DF_BS_FALLOFF) && (v->falloff < 1 || v->falloff > DF_MAX_FALLOFF))
        return df_error_set(err, DF_EINVAL, "%s: falloff %u not in 1..%u", M, v->falloff,
                            DF_MAX_FALLOFF);
    if ((mask & DF_BS_RATIO) && (!isfinite(v->ratio) || !(v->ratio > 1)))
        return df_error_set(err, DF_EINVAL, "%s: ratio %g must be finite and > 1", M, v->ratio);
    if (mask & DF_BS_INTEGRATOR) {
        if (v->integrator != DF_INTEG_EULER && v->integrator != DF_INTEG_RK4)
            return df_error_set(err, DF_EINVAL, "%s: integrator %u not 1 (euler) or 2 (rk4)", M,
                                v->integrator);
        if (v->steps < 1 || v->steps > DF_MAX_BRUSH_STEPS)
            return df_error_set(err, DF_EINVAL, "%s: steps %u not in 1..%u", M, v->steps,
                                DF_MAX_BRUSH_STEPS);
    }
    if (mask & DF_BS_MIRROR) {
        if (v->has_mirror > 1)
            return df_error_set(err, DF_EINVAL, "%s: has_mirror %u not 0/1", M, v->has_mirror);
        int rc = df_check_finite(v->mirror_point, 3, M, "mirror_point", err);
        if (!rc)
            rc = df_check_finite(v->mirror_normal, 3, M, "mirror_normal", err);
        if (rc)
            return rc;
        const double *nn = v->mirror_normal;
        if (v->has_mirror && nn[0] == 0 && nn[1] == 0 && nn[2] == 0)
            return df_error_set(err, DF_EINVAL, "%s: mirror_normal is the zero vector", M);
    }
    return DF_OK;
}

void df_msg_brush_values_defaults(df_msg_brush_values *v)
{
    df_msg_brush b;
    df_msg_brush_defaults(&b);
    memset(v, 0, sizeof *v);
    v->type = b.type;
    v->falloff = b.falloff;
    v->integrator = b.integrator;
    v->has_mirror = b.has_mirror;
    v->steps = b.steps;
    v->radius = b.radius;
    v->nu = b.nu;
    v->strength = b.strength;
    v->ratio = b.ratio;
    memcpy(v->mirror_point, b.mirror_point, sizeof v->mirror_point);
    memcpy(v->mirror_normal, b.mirror_normal, sizeof v->mirror_normal);
}

static void put_values(df_buf *out, const df_msg_brush_values *v)
{
    df_buf_put_u8(out, v->type);
    df_buf_put_u8(out, v->falloff);
    df_buf_put_u8(out, v->integrator);
    df_buf_put_u8(out, v->has_mirror);
    df_buf_put_u16(out, v->steps);
    df_buf_put_f64(out, v->radius);
    df_buf_put_f64(out, v->nu);
    df_buf_put_f64(out, v->strength);
    df_buf_put_f64(out, v->ratio);
    for (int i = 0; i < 3; i++)
        df_buf_put_f64(out, v->mirror_point[i]);
    for (int i = 0; i < 3; i++)
        df_buf_put_f64(out, v->mirror_normal[i]);
}

static void get_values(df_rd *r, df_msg_brush_values *v)
{
    v->type = df_rd_u8(r, "type");
    v->falloff = df_rd_u8(r, "falloff");
    v->integrator = df_rd_u8(r, "integrator");
    v->has_mirror = df_rd_u8(r, "has_mirror");
    v->steps = df_rd_u16(r, "steps");
    v->radius = df_rd_f64(r, "radius");
    v->nu = df_rd_f64(r, "nu");
    v->strength = df_rd_f64(r, "strength");
    v->ratio = df_rd_f64(r, "ratio");
    for (int i = 0; i < 3; i++)
        v->mirror_point[i] = df_rd_f64(r, "mirror_point");
    for (int i = 0; i < 3; i++)
        v->mirror_normal[i] = df_rd_f64(r, "mirror_normal");
}

/* ---------------------------------------------------------------- brush_state_set */
static int set_check(const df_msg_brush_state_set *m, df_error *err)
{
    const char *M = "brush_state_set";
    if (m->session_id == 0)
        return df_error_set(err, DF_EINVAL, "%s: session_id 0 is not a session", M);
    if (m->mask == 0)
        return df_error_set(err, DF_EINVAL, "%s: mask 0 sets nothing", M);
    return df_msg_brush_values_check(&m->v, m->mask, M, err);
}

int df_msg_brush_state_set_encode(const df_msg_brush_state_set *m, df_buf *out, df_error *err)
{
    int rc = set_check(m, err);
    if (rc || (rc = df_enc_reserve(out, 10 + VALUES_BYTES, "brush_state_set", err)))
        return rc;
    df_buf_put_u64(out, m->session_id);
    df_buf_put_u16(out, m->mask);
    put_values(out, &m->v);
    return DF_OK;
}

int df_msg_brush_state_set_decode(const uint8_t *p, size_t n, df_msg_brush_state_set *m,
                                  df_error *err)
{
    df_rd r;
    df_msg_brush_state_set t;
    df_rd_init(&r, p, n, "brush_state_set", err);
    t.session_id = df_rd_u64(&r, "session_id");
    t.mask = df_rd_u16(&r, "mask");
    get_values(&r, &t.v);
    int rc = df_rd_end(&r);
    if (rc || (rc = set_check(&t, err)))
        return rc;
    *m = t;
    return DF_OK;
}

/* ---------------------------------------------------------------- brush_state */
static int state_check(const df_msg_brush_state *m, df_error *err)
{
    const char *M = "brush_state";
    if (m->session_id == 0)
        return df_error_set(err, DF_EINVAL, "%s: session_id 0 is not a session", M);
    if (m->changed & ~DF_BS_ALL)
        return df_error_set(err, DF_EPROTO_RESERVED, "%s: changed bits 0x%x are not defined",
                            M, m->changed & ~DF_BS_ALL);
    if (m->origin_kind > DF_ORIGIN_MAX)
        return df_error_set(err, DF_EINVAL, "%s: origin_kind %u not in 0..%d", M,
                            m->origin_kind, DF_ORIGIN_MAX);
    int rc = df_check_str(m->origin_name, DF_MAX_NAME_LEN, M, "origin_name", err);
    return rc ? rc : df_msg_brush_values_check(&m->v, DF_BS_ALL, M, err);
}

int df_msg_brush_state_encode(const df_msg_brush_state *m, df_buf *out, df_error *err)
{
    int rc = state_check(m, err);
    size_t size = 27 + df_str_size(m->origin_name) + VALUES_BYTES;
    if (rc || (rc = df_enc_reserve(out, size, "brush_state", err)))
        return rc;
    df_buf_put_u64(out, m->session_id);
    df_buf_put_u64(out, m->seq);
    df_buf_put_u16(out, m->changed);
    df_buf_put_u8(out, m->origin_kind);
    df_buf_put_u64(out, m->origin_id);
    df_put_str(out, m->origin_name);
    put_values(out, &m->v);
    return DF_OK;
}

int df_msg_brush_state_decode(const uint8_t *p, size_t n, df_msg_brush_state *m, df_error *err)
{
    df_rd r;
    df_msg_brush_state t;
    df_rd_init(&r, p, n, "brush_state", err);
    t.session_id = df_rd_u64(&r, "session_id");
    t.seq = df_rd_u64(&r, "seq");
    t.changed = df_rd_u16(&r, "changed");
    t.origin_kind = df_rd_u8(&r, "origin_kind");
    t.origin_id = df_rd_u64(&r, "origin_id");
    df_rd_str(&r, t.origin_name, DF_MAX_NAME_LEN, "origin_name");
    get_values(&r, &t.v);
    int rc = df_rd_end(&r);
    if (rc || (rc = state_check(&t, err)))
        return rc;
    *m = t;
    return DF_OK;
}

/* ---------------------------------------------------------------- brush_cursor */
static int cursor_check(const df_msg_brush_cursor *m, df_error *err)
{
    const char *M = "brush_cursor";
    if (m->session_id == 0)
        return df_error_set(err, DF_EINVAL, "%s: session_id 0 is not a session", M);
    if (m->origin_kind > DF_ORIGIN_MAX)
        return df_error_set(err, DF_EINVAL, "%s: origin_kind %u not in 0..%d", M,
                            m->origin_kind, DF_ORIGIN_MAX);
    if (m->flags & ~DF_CURSOR_FLAGS_ALL)
        return df_error_set(err, DF_EPROTO_RESERVED, "%s: flags bits 0x%x are not defined", M,
                            m->flags & ~DF_CURSOR_FLAGS_ALL);
    int rc = df_check_finite(m->center, 3, M, "center", err);
    if (rc)
        return rc;
    if (!isfinite(m->radius) || !(m->radius > 0))
        return df_error_set(err, DF_EINVAL, "%s: radius %g must be finite and > 0", M,
                            m->radius);
    return DF_OK;
}

int df_msg_brush_cursor_encode(const df_msg_brush_cursor *m, df_buf *out, df_error *err)
{
    int rc = cursor_check(m, err);
    if (rc || (rc = df_enc_reserve(out, 50, "brush_cursor", err)))
        return rc;
    df_buf_put_u64(out, m->session_id);
    df_buf_put_u8(out, m->origin_kind);
    df_buf_put_u64(out, m->origin_id);
    df_buf_put_u8(out, m->flags);
    for (int i = 0; i < 3; i++)
        df_buf_put_f64(out, m->center[i]);
    df_buf_put_f64(out, m->radius);
    return DF_OK;
}

int df_msg_brush_cursor_decode(const uint8_t *p, size_t n, df_msg_brush_cursor *m,
                               df_error *err)
{
    df_rd r;
    df_msg_brush_cursor t;
    df_rd_init(&r, p, n, "brush_cursor", err);
    t.session_id = df_rd_u64(&r, "session_id");
    t.origin_kind = df_rd_u8(&r, "origin_kind");
    t.origin_id = df_rd_u64(&r, "origin_id");
    t.flags = df_rd_u8(&r, "flags");
    for (int i = 0; i < 3; i++)
        t.center[i] = df_rd_f64(&r, "center");
    t.radius = df_rd_f64(&r, "radius");
    int rc = df_rd_end(&r);
    if (rc || (rc = cursor_check(&t, err)))
        return rc;
    *m = t;
    return DF_OK;
}
