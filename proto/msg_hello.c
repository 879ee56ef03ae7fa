/* msg_hello.c — handshake, auth placeholder, ping, empty and error bodies (messages.h). */
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "proto/codec_util.h"
#include "proto/messages.h"

/* ---- optional stream-encoding trailer of hello and hello_reply: u8 stream_encoding,
 * u8 reserved, f64 error_bound (PROTOCOL.md 4.2); present iff bytes remain after the name */
#define STREAM_TRAILER 10

int df_msg_stream_enc_check(uint8_t has, uint8_t enc, double e, const char *msg, df_error *err)
{
    if (!has)
        return enc || e != 0 ? df_error_set(err, DF_EINVAL, "%s: stream_encoding set without "
                                            "has_stream", msg) : DF_OK;
    if (enc & ~DF_STREAM_ENC_ALL)
        return df_error_set(err, DF_EINVAL, "%s: unknown stream_encoding bits 0x%x (known: 1 "
                            "quantized, 2 zstd)", msg, (unsigned)(enc & ~DF_STREAM_ENC_ALL));
    if (enc & DF_STREAM_ENC_QUANTIZED) {
        if (!(e >= DF_STREAM_ERROR_LO && e <= DF_STREAM_ERROR_HI))
            return df_error_set(err, DF_EINVAL, "%s: error_bound %g of a quantized stream must "
                                "be finite and in [%g, %g] mesh units", msg, e,
                                DF_STREAM_ERROR_LO, DF_STREAM_ERROR_HI);
    } else if (e != 0) {
        return df_error_set(err, DF_EINVAL, "%s: error_bound %g without stream_encoding "
                            "QUANTIZED (must be 0)", msg, e);
    }
    return DF_OK;
}

static void stream_put(df_buf *out, uint8_t has, uint8_t enc, double e)
{
    if (!has)
        return;
    df_buf_put_u8(out, enc);
    df_buf_put_u8(out, 0);
    df_buf_put_f64(out, e);
}

static void stream_get(df_rd *r, uint8_t *has, uint8_t *enc, double *e)
{
    *has = r->rc == DF_OK && r->off < r->n;
    *enc = 0;
    *e = 0;
    if (!*has)
        return;
    *enc = df_rd_u8(r, "stream_encoding");
    df_rd_reserved8(r, "reserved");
    *e = df_rd_f64(r, "error_bound");
}

/* ---- hello: u16 min_version, u16 max_version, u32 features, str client_name */
static int hello_check(const df_msg_hello *m, df_error *err)
{
    if (m->min_version < 1 || m->max_version < m->min_version)
        return df_error_set(err, DF_EINVAL, "hello: versions %u..%u: need 1 <= min <= max",
                            m->min_version, m->max_version);
    int rc = df_check_str(m->client_name, DF_MAX_NAME_LEN, "hello", "client_name", err);
    return rc ? rc : df_msg_stream_enc_check(m->has_stream, m->stream_encoding, m->error_bound,
                                             "hello", err);
}

int df_msg_hello_encode(const df_msg_hello *m, df_buf *out, df_error *err)
{
    int rc = hello_check(m, err);
    if (rc || (rc = df_enc_reserve(out, 8 + df_str_size(m->client_name) +
                                           (m->has_stream ? STREAM_TRAILER : 0), "hello", err)))
        return rc;
    df_buf_put_u16(out, m->min_version);
    df_buf_put_u16(out, m->max_version);
    df_buf_put_u32(out, m->features);
    df_put_str(out, m->client_name);
    stream_put(out, m->has_stream, m->stream_encoding, m->error_bound);
    return DF_OK;
}

int df_msg_hello_decode(const uint8_t *p, size_t n, df_msg_hello *m, df_error *err)
{
    df_rd r;
    df_msg_hello t;
    df_rd_init(&r, p, n, "hello", err);
    t.min_version = df_rd_u16(&r, "min_version");
    t.max_version = df_rd_u16(&r, "max_version");
    t.features = df_rd_u32(&r, "features");
    df_rd_str(&r, t.client_name, DF_MAX_NAME_LEN, "client_name");
    stream_get(&r, &t.has_stream, &t.stream_encoding, &t.error_bound);
    int rc = df_rd_end(&r);
    if (rc || (rc = hello_check(&t, err)))
        return rc;
    *m = t;
    return DF_OK;
}

/* ---- hello reply: u16 version, u16 server_max_version, u32 features, u32 max_frame_payload,
 * u32 max_mesh_vertices, u32 max_mesh_elements, u32 max_pending_requests, u32 max_sessions,
 * u64 max_mesh_bytes, u64 max_client_queue_bytes, u8 auth_required, u8 reserved, str name */
static int hello_reply_check(const df_msg_hello_reply *m, df_error *err)
{
    if (m->version < 1 || m->version > m->server_max_version)
        return df_error_set(err, DF_EINVAL, "hello_reply: version %u not in 1..%u", m->version,
                            m->server_max_version);
    if (m->features & ~DF_FEAT_DECODE_MASK) /* the reserved bit 6 (future HID) is accepted */
        return df_error_set(err, DF_EINVAL, "hello_reply: unknown feature bits 0x%x",
                            m->features & ~DF_FEAT_DECODE_MASK);
    if (m->max_frame_payload < 1024 || m->max_frame_payload > DF_MAX_FRAME_PAYLOAD)
        return df_error_set(err, DF_EINVAL, "hello_reply: max_frame_payload %u not in 1024..%u",
                            m->max_frame_payload, DF_MAX_FRAME_PAYLOAD);
    if (m->max_mesh_vertices < 1 || m->max_mesh_vertices > DF_MAX_MESH_VERTICES ||
        m->max_mesh_elements > DF_MAX_MESH_ELEMENTS || m->max_pending_requests < 1 ||
        m->max_pending_requests > DF_MAX_PENDING_REQUESTS || m->max_sessions < 1 ||
        m->max_sessions > DF_MAX_SESSIONS || m->max_mesh_bytes > DF_MAX_MESH_BYTES)
        return df_error_set(err, DF_EINVAL, "hello_reply: a limit is 0 or above its protocol "
                            "maximum (vertices %u, elements %u, pending %u, sessions %u, "
                            "mesh bytes %llu)", m->max_mesh_vertices, m->max_mesh_elements,
                            m->max_pending_requests, m->max_sessions,
                            (unsigned long long)m->max_mesh_bytes);
    if (m->auth_required > 1)
        return df_error_set(err, DF_EINVAL, "hello_reply: auth_required %u not 0/1",
                            m->auth_required);
    int rc = df_check_str(m->server_name, DF_MAX_NAME_LEN, "hello_reply", "server_name", err);
    return rc ? rc : df_msg_stream_enc_check(m->has_stream, m->stream_encoding, m->error_bound,
                                             "hello_reply", err);
}

int df_msg_hello_reply_encode(const df_msg_hello_reply *m, df_buf *out, df_error *err)
{
    int rc = hello_reply_check(m, err);
    if (rc || (rc = df_enc_reserve(out, 46 + df_str_size(m->server_name) +
                                           (m->has_stream ? STREAM_TRAILER : 0), "hello_reply",
                                   err)))
        return rc;
    df_buf_put_u16(out, m->version);
    df_buf_put_u16(out, m->server_max_version);
    df_buf_put_u32(out, m->features);
    df_buf_put_u32(out, m->max_frame_payload);
    df_buf_put_u32(out, m->max_mesh_vertices);
    df_buf_put_u32(out, m->max_mesh_elements);
    df_buf_put_u32(out, m->max_pending_requests);
    df_buf_put_u32(out, m->max_sessions);
    df_buf_put_u64(out, m->max_mesh_bytes);
    df_buf_put_u64(out, m->max_client_queue_bytes);
    df_buf_put_u8(out, m->auth_required);
    df_buf_put_u8(out, 0);
    df_put_str(out, m->server_name);
    stream_put(out, m->has_stream, m->stream_encoding, m->error_bound);
    return DF_OK;
}

int df_msg_hello_reply_decode(const uint8_t *p, size_t n, df_msg_hello_reply *m, df_error *err)
{
    df_rd r;
    df_msg_hello_reply t;
    df_rd_init(&r, p, n, "hello_reply", err);
    t.version = df_rd_u16(&r, "version");
    t.server_max_version = df_rd_u16(&r, "server_max_version");
    t.features = df_rd_u32(&r, "features");
    t.max_frame_payload = df_rd_u32(&r, "max_frame_payload");
    t.max_mesh_vertices = df_rd_u32(&r, "max_mesh_vertices");
    t.max_mesh_elements = df_rd_u32(&r, "max_mesh_elements");
    t.max_pending_requests = df_rd_u32(&r, "max_pending_requests");
    t.max_sessions = df_rd_u32(&r, "max_sessions");
    t.max_mesh_bytes = df_rd_u64(&r, "max_mesh_bytes");
    t.max_client_queue_bytes = df_rd_u64(&r, "max_client_queue_bytes");
    t.auth_required = df_rd_u8(&r, "auth_required");
    df_rd_reserved8(&r, "reserved");
    df_rd_str(&r, t.server_name, DF_MAX_NAME_LEN, "server_name");
    stream_get(&r, &t.has_stream, &t.stream_encoding, &t.error_bound);
    int rc = df_rd_end(&r);
    if (rc || (rc = hello_reply_check(&t, err)))
        return rc;
    *m = t;
    return DF_OK;
}

/* ---- auth: u16 method, u16 reserved, u32 token_len, token bytes */
int df_msg_auth_encode(const df_msg_auth *m, df_buf *out, df_error *err)
{
    if (m->token_len > DF_MAX_AUTH_TOKEN)
        return df_error_set(err, DF_ELIMIT, "auth: token of %u bytes exceeds limit %u",
                            m->token_len, DF_MAX_AUTH_TOKEN);
    if (m->token_len && !m->token)
        return df_error_set(err, DF_EINVAL, "auth: token is NULL with token_len %u", m->token_len);
    int rc = df_enc_reserve(out, 8 + (size_t)m->token_len, "auth", err);
    if (rc)
        return rc;
    df_buf_put_u16(out, m->method);
    df_buf_put_u16(out, 0);
    df_buf_put_u32(out, m->token_len);
    df_buf_put_bytes(out, m->token, m->token_len);
    return DF_OK;
}

int df_msg_auth_decode(const uint8_t *p, size_t n, df_msg_auth *m, df_error *err)
{
    df_rd r;
    df_msg_auth t;
    df_rd_init(&r, p, n, "auth", err);
    t.method = df_rd_u16(&r, "method");
    df_rd_reserved16(&r, "reserved");
    t.token_len = df_rd_u32(&r, "token_len");
    if (!r.rc && t.token_len > DF_MAX_AUTH_TOKEN)
        df_rd_fail(&r, DF_ELIMIT, "token_len", "%u bytes exceeds limit %u", t.token_len,
                   DF_MAX_AUTH_TOKEN);
    t.token = df_rd_bytes(&r, t.token_len, "token");
    int rc = df_rd_end(&r);
    if (rc)
        return rc;
    *m = t;
    return DF_OK;
}

/* ---- ping: the payload is the opaque bytes themselves */
int df_msg_ping_encode(const df_msg_ping *m, df_buf *out, df_error *err)
{
    if (m->len > DF_MAX_PING_BYTES)
        return df_error_set(err, DF_ELIMIT, "ping: %u bytes exceeds limit %u", m->len,
                            DF_MAX_PING_BYTES);
    if (m->len && !m->data)
        return df_error_set(err, DF_EINVAL, "ping: data is NULL with len %u", m->len);
    return df_buf_append(out, m->data, m->len, err);
}

int df_msg_ping_decode(const uint8_t *p, size_t n, df_msg_ping *m, df_error *err)
{
    if (n > DF_MAX_PING_BYTES)
        return df_error_set(err, DF_ELIMIT, "ping: %zu bytes exceeds limit %u", n,
                            DF_MAX_PING_BYTES);
    m->len = (uint32_t)n;
    m->data = n ? p : NULL;
    return DF_OK;
}

int df_msg_empty_decode(const uint8_t *p, size_t n, df_error *err)
{
    (void)p;
    if (n)
        return df_error_set(err, DF_EPROTO_TRAILING, "empty body expected, got %zu bytes", n);
    return DF_OK;
}

/* ---- error: i32 code, u16 len, message bytes */
int df_msg_error_encode(const df_error *e, df_buf *out, df_error *err)
{
    if (!df_proto_error_valid(e->code))
        return df_error_set(err, DF_EINVAL, "error: code %d is not a wire error code", e->code);
    size_t len = strnlen(e->msg, DF_MAX_ERROR_MSG_LEN);
    int rc = df_enc_reserve(out, 6 + len, "error", err);
    if (rc)
        return rc;
    df_buf_put_i32(out, e->code);
    df_buf_put_u16(out, (uint16_t)len);
    df_buf_put_bytes(out, e->msg, len);
    return DF_OK;
}

int df_msg_error_decode(const uint8_t *p, size_t n, df_error *out, df_error *err)
{
    df_rd r;
    df_error t;
    df_rd_init(&r, p, n, "error", err);
    t.code = (int32_t)df_rd_u32(&r, "code");
    if (!r.rc && !df_proto_error_valid(t.code))
        df_rd_fail(&r, DF_EINVAL, "code", "%d is not a wire error code", t.code);
    df_rd_str(&r, t.msg, DF_MAX_ERROR_MSG_LEN, "message");
    int rc = df_rd_end(&r);
    if (rc)
        return rc;
    *out = t;
    return DF_OK;
}

int df_msg_error_frame(df_buf *out, uint16_t type, uint64_t request_id, int code,
                       df_error *err, const char *fmt, ...)
{
    df_error body;
    body.code = df_proto_error_valid(code) ? code : DF_EINTERNAL;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(body.msg, sizeof body.msg, fmt, ap);
    va_end(ap);
    /* Request id 0 is never a request's (PROTOCOL.md 1.3): connection-level ERROR event. Any
     * other error answers its request with the request's own type, known or not. */
    if (request_id == 0 || type == 0)
        type = DF_MSG_ERROR;
    uint16_t flags = DF_FLAG_ERROR;
    if (request_id != 0)
        flags |= DF_FLAG_REPLY;
    size_t start, len0 = out->len;
    int rc = df_frame_begin(out, type, flags, request_id, &start, err);
    if (!rc)
        rc = df_msg_error_encode(&body, out, err);
    if (!rc)
        rc = df_frame_end(out, start, err);
    if (rc)
        out->len = len0;
    return rc;
}
