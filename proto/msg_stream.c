/* msg_stream.c — the bodies of the negotiated stream encodings (messages.h, PROTOCOL.md 4.40,
 * 4.41): qdisp (a quantized version delta, varint rows) and zframe (a zstd-compressed stream
 * event; this file only frames the compressed bytes, the codec itself lives with its users). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "proto/codec_util.h"
#include "proto/messages.h"

#define QDISP_HEADER 48       /* bytes before the rows */
#define QDISP_ROW_MAX 29      /* varint gap (<= 5 bytes) + 3 zigzag varints of |v| < 2^53 */
#define QDISP_PROGRESS 32     /* the optional progress trailer after the rows (4.40) */
#define QDISP_FLAG_PROGRESS 1 /* flags bit 0: the progress trailer follows the rows */
#define QDISP_DQ_LIMIT (1ll << 53)

static size_t put_varint(uint8_t *q, uint64_t v)
{
    size_t n = 0;
    while (v >= 0x80) {
        q[n++] = (uint8_t)(v | 0x80);
        v >>= 7;
    }
    q[n++] = (uint8_t)v;
    return n;
}

static uint64_t zigzag(int64_t v) { return ((uint64_t)v << 1) ^ (uint64_t)(v >> 63); }
static int64_t unzigzag(uint64_t u) { return (int64_t)(u >> 1) ^ -(int64_t)(u & 1); }

/* Reads one LEB128 varint of at most 10 bytes from p[*off .. n); 0 on truncation, more than
 * 10 bytes, or a non-canonical encoding (a last byte 0 after the first: every value has one
 * encoding, so a decoded body re-encodes to the same bytes). */
static int get_varint(const uint8_t *p, size_t n, size_t *off, uint64_t *v)
{
    uint64_t r = 0;
    for (int shift = 0; shift < 64 && *off < n; shift += 7) {
        uint8_t b = p[(*off)++];
        r |= (uint64_t)(b & 0x7f) << shift;
        if (!(b & 0x80)) {
            *v = r;
            return shift == 0 || b != 0;
        }
    }
    return 0;
}

static int qdisp_check(const df_msg_qdisp *m, df_error *err)
{
    const char *M = "qdisp";
    if (m->session_id == 0)
        return df_error_set(err, DF_EINVAL, "%s: session_id 0 is not a session", M);
    if (m->version <= m->base_version)
        return df_error_set(err, DF_EINVAL, "%s: version %llu must be > base_version %llu", M,
                            (unsigned long long)m->version, (unsigned long long)m->base_version);
    if (m->kind < 1 || m->kind >= DF_CHANGE_SNAPSHOT)
        return df_error_set(err, DF_EINVAL, "%s: kind %u not in 1..%u (a snapshot is always a "
                            "dense disp)", M, m->kind, DF_CHANGE_SNAPSHOT - 1);
    if (m->nv < 1 || m->nv > DF_MAX_MESH_VERTICES || m->count > m->nv)
        return df_error_set(err, DF_EINVAL, "%s: nv %u not in 1..%u or count %u > nv", M, m->nv,
                            DF_MAX_MESH_VERTICES, m->count);
    if (!(m->step > 0 && isfinite(m->step)))
        return df_error_set(err, DF_EINVAL, "%s: step %g must be finite and > 0", M, m->step);
    if (m->has_progress > 1)
        return df_error_set(err, DF_EINVAL, "%s: has_progress %u not 0 or 1", M, m->has_progress);
    if (!m->has_progress)
        return DF_OK;
    if (m->kind != DF_CHANGE_HANDLE_MOVE)
        return df_error_set(err, DF_EINVAL, "%s: a progress trailer on kind %u (only handle_move, "
                            "%u)", M, m->kind, DF_CHANGE_HANDLE_MOVE);
    if (m->status > DF_MOVE_STATUS_MAX || m->final > 1 ||
        (m->final == 1) != (m->status != DF_MOVE_RUNNING))
        return df_error_set(err, DF_EINVAL, "%s: progress status %u / final %u invalid (status "
                            "0..%u, final iff status != running)", M, m->status, m->final,
                            DF_MOVE_STATUS_MAX);
    if (!isfinite(m->objective) || !isfinite(m->residual) || m->residual < 0 ||
        !isfinite(m->elapsed_ms) || m->elapsed_ms < 0)
        return df_error_set(err, DF_EINVAL, "%s: progress objective %g, residual %g, elapsed_ms "
                            "%g must be finite (residual, elapsed >= 0)", M, m->objective,
                            m->residual, m->elapsed_ms);
    return DF_OK;
}

int df_msg_qdisp_encode(const df_msg_qdisp *m, df_buf *out, df_error *err)
{
    int rc = qdisp_check(m, err);
    for (uint32_t i = 0; !rc && i < m->count; i++) {
        if (m->idx[i] < 0 || (uint32_t)m->idx[i] >= m->nv || (i && m->idx[i] <= m->idx[i - 1]))
            rc = df_error_set(err, DF_EINVAL, "qdisp: row %u index %d not increasing in 0..%u", i,
                              m->idx[i], m->nv - 1);
        for (int k = 0; !rc && k < 3; k++)
            if (m->dq[3 * (size_t)i + k] <= -QDISP_DQ_LIMIT ||
                m->dq[3 * (size_t)i + k] >= QDISP_DQ_LIMIT)
                rc = df_error_set(err, DF_EINVAL, "qdisp: row %u change out of +-2^53 steps", i);
    }
    if (rc || (rc = df_enc_reserve(out, QDISP_HEADER + QDISP_ROW_MAX * (size_t)m->count +
                                   QDISP_PROGRESS, "qdisp", err)))
        return rc;
    size_t start = out->len;
    df_buf_put_u64(out, m->session_id);
    df_buf_put_u64(out, m->version);
    df_buf_put_u64(out, m->base_version);
    df_buf_put_u8(out, m->kind);
    df_buf_put_u8(out, m->has_progress ? QDISP_FLAG_PROGRESS : 0);
    df_buf_put_u16(out, 0);
    df_buf_put_u32(out, m->nv);
    df_buf_put_u32(out, m->count);
    df_buf_put_u32(out, 0); /* rows_bytes, patched below */
    df_buf_put_f64(out, m->step);
    uint8_t *q = out->data + out->len, *q0 = q;
    int64_t prev = -1;
    for (uint32_t i = 0; i < m->count; i++) {
        q += put_varint(q, (uint64_t)(m->idx[i] - prev - 1));
        prev = m->idx[i];
        for (int k = 0; k < 3; k++) q += put_varint(q, zigzag(m->dq[3 * (size_t)i + k]));
    }
    out->len += (size_t)(q - q0);
    df_le32_store(out->data + start + 36, (uint32_t)(q - q0));
    if (m->has_progress) { /* the progress trailer: progress's first 32 bytes (4.22) */
        df_buf_put_u8(out, m->status);
        df_buf_put_u8(out, m->final);
        df_buf_put_u16(out, 0);
        df_buf_put_u32(out, m->iteration);
        df_buf_put_f64(out, m->objective);
        df_buf_put_f64(out, m->residual);
        df_buf_put_f64(out, m->elapsed_ms);
    }
    return DF_OK;
}

int df_msg_qdisp_decode(const uint8_t *p, size_t n, df_msg_qdisp *m, df_error *err)
{
    df_rd r;
    df_msg_qdisp t;
    memset(&t, 0, sizeof t);
    df_rd_init(&r, p, n, "qdisp", err);
    t.session_id = df_rd_u64(&r, "session_id");
    t.version = df_rd_u64(&r, "version");
    t.base_version = df_rd_u64(&r, "base_version");
    t.kind = df_rd_u8(&r, "kind");
    uint8_t flags = df_rd_u8(&r, "flags");
    df_rd_reserved16(&r, "reserved");
    t.nv = df_rd_u32(&r, "nv");
    t.count = df_rd_u32(&r, "count");
    uint32_t rows_bytes = df_rd_u32(&r, "rows_bytes");
    t.step = df_rd_f64(&r, "step");
    if (r.rc)
        return r.rc;
    if (flags & ~QDISP_FLAG_PROGRESS)
        return df_error_set(err, DF_EINVAL, "qdisp: unknown flags 0x%x (known: 1 progress)",
                            (unsigned)flags);
    size_t rest = n - r.off, tail = flags ? QDISP_PROGRESS : 0;
    if (rows_bytes > rest || rest - rows_bytes != tail)
        return df_error_set(err, rest < (size_t)rows_bytes + tail ? DF_EPROTO_TRUNCATED
                                                                  : DF_EPROTO_TRAILING,
                            "qdisp: rows_bytes %u%s but %zu bytes follow the header", rows_bytes,
                            tail ? " and the 32-byte progress trailer" : "", rest);
    if (tail) { /* the progress trailer after the rows */
        df_rd tr;
        df_rd_init(&tr, p + r.off + rows_bytes, QDISP_PROGRESS, "qdisp", err);
        t.has_progress = 1;
        t.status = df_rd_u8(&tr, "status");
        t.final = df_rd_u8(&tr, "final");
        df_rd_reserved16(&tr, "reserved");
        t.iteration = df_rd_u32(&tr, "iteration");
        t.objective = df_rd_f64(&tr, "objective");
        t.residual = df_rd_f64(&tr, "residual");
        t.elapsed_ms = df_rd_f64(&tr, "elapsed_ms");
        if (tr.rc)
            return tr.rc;
        n -= QDISP_PROGRESS; /* the rows end where the trailer starts */
    }
    int rc = qdisp_check(&t, err);
    if (rc)
        return rc;
    if ((uint64_t)t.count * 4 > rows_bytes) /* a row takes >= 4 bytes: bound before allocating */
        return df_error_set(err, DF_EPROTO_TRUNCATED, "qdisp: %u rows cannot fit in %u bytes",
                            t.count, rows_bytes);
    t.idx = t.count ? malloc((size_t)t.count * sizeof *t.idx) : NULL;
    t.dq = t.count ? malloc((size_t)t.count * 3 * sizeof *t.dq) : NULL;
    if (t.count && (!t.idx || !t.dq)) {
        df_msg_qdisp_free(&t);
        return df_error_set(err, DF_ENOMEM, "qdisp: out of memory for %u rows", t.count);
    }
    size_t off = r.off;
    int64_t prev = -1;
    for (uint32_t i = 0; i < t.count; i++) {
        uint64_t gap, v[3];
        if (!get_varint(p, n, &off, &gap) || !get_varint(p, n, &off, &v[0]) ||
            !get_varint(p, n, &off, &v[1]) || !get_varint(p, n, &off, &v[2])) {
            df_msg_qdisp_free(&t);
            return df_error_set(err, DF_EPROTO_TRUNCATED, "qdisp: row %u truncated, or a varint "
                                "longer than 10 bytes or not in its shortest form", i);
        }
        if (gap >= (uint64_t)t.nv || prev + 1 + (int64_t)gap >= (int64_t)t.nv) {
            df_msg_qdisp_free(&t);
            return df_error_set(err, DF_EINVAL, "qdisp: row %u index beyond nv %u", i, t.nv);
        }
        prev += 1 + (int64_t)gap;
        t.idx[i] = (int32_t)prev;
        for (int k = 0; k < 3; k++) {
            int64_t d = unzigzag(v[k]);
            if (d <= -QDISP_DQ_LIMIT || d >= QDISP_DQ_LIMIT) {
                df_msg_qdisp_free(&t);
                return df_error_set(err, DF_EINVAL, "qdisp: row %u change out of +-2^53 steps", i);
            }
            t.dq[3 * (size_t)i + k] = d;
        }
    }
    if (off != n) {
        df_msg_qdisp_free(&t);
        return df_error_set(err, DF_EPROTO_TRAILING, "qdisp: %zu bytes after the %u rows",
                            n - off, t.count);
    }
    *m = t;
    return DF_OK;
}

void df_msg_qdisp_free(df_msg_qdisp *m)
{
    if (!m)
        return;
    free(m->idx);
    free(m->dq);
    m->idx = NULL;
    m->dq = NULL;
    m->count = 0;
}

/* ---- zframe: u16 inner_type, u16 reserved, u32 raw_len, u32 zlen, zlen zstd bytes */
static int zframe_check(const df_msg_zframe *m, df_error *err)
{
    if (m->inner_type != DF_MSG_DISPLACEMENT && m->inner_type != DF_MSG_PROGRESS &&
        m->inner_type != DF_MSG_QDISP)
        return df_error_set(err, DF_EINVAL, "zframe: inner_type 0x%04x is not displacement, "
                            "progress or qdisp", m->inner_type);
    if (m->raw_len > DF_MAX_FRAME_PAYLOAD || m->zlen < 1)
        return df_error_set(err, DF_EINVAL, "zframe: raw_len %u over %u or no compressed bytes",
                            m->raw_len, DF_MAX_FRAME_PAYLOAD);
    return DF_OK;
}

int df_msg_zframe_encode(const df_msg_zframe *m, df_buf *out, df_error *err)
{
    int rc = zframe_check(m, err);
    if (rc || (rc = df_enc_reserve(out, 12 + (size_t)m->zlen, "zframe", err)))
        return rc;
    df_buf_put_u16(out, m->inner_type);
    df_buf_put_u16(out, 0);
    df_buf_put_u32(out, m->raw_len);
    df_buf_put_u32(out, m->zlen);
    df_buf_put_bytes(out, m->z, m->zlen);
    return DF_OK;
}

int df_msg_zframe_decode(const uint8_t *p, size_t n, df_msg_zframe *m, df_error *err)
{
    df_rd r;
    df_msg_zframe t;
    df_rd_init(&r, p, n, "zframe", err);
    t.inner_type = df_rd_u16(&r, "inner_type");
    df_rd_reserved16(&r, "reserved");
    t.raw_len = df_rd_u32(&r, "raw_len");
    t.zlen = df_rd_u32(&r, "zlen");
    t.z = df_rd_bytes(&r, t.zlen, "data");
    int rc = df_rd_end(&r);
    if (!rc)
        rc = zframe_check(&t, err);
    if (rc)
        return rc;
    *m = t;
    return DF_OK;
}
