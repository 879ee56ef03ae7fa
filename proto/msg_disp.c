/* msg_disp.c — displacement stream and handle-move progress bodies (messages.h).
 * disp: u64 session_id, u64 version, u64 base_version, u8 kind, u8 encoding, u16 reserved,
 *   u32 nv, u32 total, u32 offset, u32 count (44 bytes), then count rows:
 *   DENSE f32 x, y, z (12 bytes) / SPARSE u32 index, f32 x, y, z (16 bytes)
 * progress: u8 status, u8 final, u16 reserved, u32 iteration, f64 objective, f64 residual,
 *   f64 elapsed_ms (32 bytes), then a disp body */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "proto/codec_util.h"
#include "proto/messages.h"

#define DISP_HEADER 44u
#define PROGRESS_HEADER 32u

size_t df_msg_disp_row_bytes(uint8_t encoding)
{
    return encoding == DF_DISP_DENSE ? 12 : encoding == DF_DISP_SPARSE ? 16 : 0;
}

uint32_t df_msg_disp_rows_per_chunk(uint8_t encoding, size_t max_payload)
{
    size_t row = df_msg_disp_row_bytes(encoding);
    if (!row || max_payload <= DISP_HEADER + PROGRESS_HEADER + row)
        return 1;
    size_t rows = (max_payload - DISP_HEADER - PROGRESS_HEADER) / row;
    return rows > DF_MAX_MESH_VERTICES ? DF_MAX_MESH_VERTICES : (uint32_t)rows;
}

uint8_t df_msg_disp_choose(uint32_t changed, uint32_t nv)
{
    return (uint64_t)changed * 16 < (uint64_t)nv * 12 ? DF_DISP_SPARSE : DF_DISP_DENSE;
}

/* Checks the header fields (not the rows). */
static int disp_head_check(const df_msg_disp *m, const char *M, df_error *err)
{
    if (m->session_id == 0)
        return df_error_set(err, DF_EINVAL, "%s: session_id 0 is not a session", M);
    if (m->kind < 1 || m->kind > DF_CHANGE_MAX)
        return df_error_set(err, DF_EINVAL, "%s: kind %u not in 1..%u", M, m->kind, DF_CHANGE_MAX);
    if (m->encoding != DF_DISP_DENSE && m->encoding != DF_DISP_SPARSE)
        return df_error_set(err, DF_EINVAL, "%s: encoding %u not 1 (dense) or 2 (sparse)", M,
                            m->encoding);
    if (m->kind == DF_CHANGE_SNAPSHOT ? m->base_version != 0 : m->version <= m->base_version)
        return df_error_set(err, DF_EINVAL, "%s: version %llu / base_version %llu inconsistent "
                            "(need version > base, or base 0 for a snapshot)", M,
                            (unsigned long long)m->version, (unsigned long long)m->base_version);
    if (m->nv < 1 || m->nv > DF_MAX_MESH_VERTICES)
        return df_error_set(err, DF_ELIMIT, "%s: nv %u not in 1..%u", M, m->nv,
                            DF_MAX_MESH_VERTICES);
    if (m->encoding == DF_DISP_DENSE ? m->total != m->nv : m->total > m->nv)
        return df_error_set(err, DF_EINVAL, "%s: total %u rows inconsistent with nv %u (%s)", M,
                            m->total, m->nv, m->encoding == DF_DISP_DENSE ? "dense" : "sparse");
    if (m->offset > m->total || m->count > m->total - m->offset)
        return df_error_set(err, DF_EINVAL, "%s: chunk rows [%u, +%u) outside total %u", M,
                            m->offset, m->count, m->total);
    return DF_OK;
}

static int disp_rows_check(const df_msg_disp *m, const char *M, df_error *err)
{
    if (m->count && (!m->xyz || (m->encoding == DF_DISP_SPARSE && !m->idx)))
        return df_error_set(err, DF_EINVAL, "%s: row arrays are NULL with count %u", M, m->count);
    for (size_t i = 0; i < 3 * (size_t)m->count; i++)
        if (!isfinite(m->xyz[i]))
            return df_error_set(err, DF_EINVAL, "%s: row %zu component %zu is %g (must be "
                                "finite)", M, i / 3 + m->offset, i % 3, (double)m->xyz[i]);
    if (m->encoding == DF_DISP_SPARSE)
        for (uint32_t i = 0; i < m->count; i++) {
            if (m->idx[i] < 0 || (uint32_t)m->idx[i] >= m->nv)
                return df_error_set(err, DF_EINVAL, "%s: vertex index %d out of range (nv %u)",
                                    M, m->idx[i], m->nv);
            if (i && m->idx[i] <= m->idx[i - 1])
                return df_error_set(err, DF_EINVAL, "%s: vertex indices not increasing (%d after "
                                    "%d)", M, m->idx[i], m->idx[i - 1]);
        }
    return DF_OK;
}

static size_t disp_size(const df_msg_disp *m)
{
    return DISP_HEADER + df_msg_disp_row_bytes(m->encoding) * (size_t)m->count;
}

static void disp_put(df_buf *out, const df_msg_disp *m)
{
    df_buf_put_u64(out, m->session_id);
    df_buf_put_u64(out, m->version);
    df_buf_put_u64(out, m->base_version);
    df_buf_put_u8(out, m->kind);
    df_buf_put_u8(out, m->encoding);
    df_buf_put_u16(out, 0);
    df_buf_put_u32(out, m->nv);
    df_buf_put_u32(out, m->total);
    df_buf_put_u32(out, m->offset);
    df_buf_put_u32(out, m->count);
    if (m->encoding == DF_DISP_DENSE) {
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
        df_buf_put_bytes(out, m->xyz, 12 * (size_t)m->count);
#else
        for (size_t i = 0; i < 3 * (size_t)m->count; i++)
            df_buf_put_f32(out, m->xyz[i]);
#endif
        return;
    }
    for (uint32_t i = 0; i < m->count; i++) {
        df_buf_put_u32(out, (uint32_t)m->idx[i]);
        df_buf_put_f32(out, m->xyz[3 * (size_t)i]);
        df_buf_put_f32(out, m->xyz[3 * (size_t)i + 1]);
        df_buf_put_f32(out, m->xyz[3 * (size_t)i + 2]);
    }
}

/* Reads a disp body from r into t (arrays allocated), validates everything. */
static void disp_get(df_rd *r, df_msg_disp *t, const char *M)
{
    *t = (df_msg_disp){0};
    t->session_id = df_rd_u64(r, "session_id");
    t->version = df_rd_u64(r, "version");
    t->base_version = df_rd_u64(r, "base_version");
    t->kind = df_rd_u8(r, "kind");
    t->encoding = df_rd_u8(r, "encoding");
    df_rd_reserved16(r, "reserved");
    t->nv = df_rd_u32(r, "nv");
    t->total = df_rd_u32(r, "total");
    t->offset = df_rd_u32(r, "offset");
    t->count = df_rd_u32(r, "count");
    if (r->rc)
        return;
    int rc = disp_head_check(t, M, r->err);
    if (rc) {
        r->rc = rc;
        return;
    }
    size_t row = df_msg_disp_row_bytes(t->encoding);
    if (!df_rd_need_rows(r, t->count, row, "count"))
        return;
    t->xyz = df_rd_alloc(r, 3 * (size_t)t->count, sizeof(float), "xyz");
    if (t->encoding == DF_DISP_SPARSE)
        t->idx = df_rd_alloc(r, t->count, sizeof(int32_t), "idx");
    if (r->rc)
        return;
    const uint8_t *q = r->p + r->off;
    if (t->encoding == DF_DISP_DENSE) {
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
        if (t->count)
            memcpy(t->xyz, q, 12 * (size_t)t->count);
#else
        for (size_t i = 0; i < 3 * (size_t)t->count; i++) {
            uint32_t u = df_le32_load(q + 4 * i);
            memcpy(&t->xyz[i], &u, 4);
        }
#endif
    } else {
        for (uint32_t i = 0; i < t->count; i++) {
            const uint8_t *e = q + 16 * (size_t)i;
            uint32_t v = df_le32_load(e);
            t->idx[i] = v > INT32_MAX ? -1 : (int32_t)v;
            for (int k = 0; k < 3; k++) {
                uint32_t u = df_le32_load(e + 4 + 4 * k);
                memcpy(&t->xyz[3 * (size_t)i + k], &u, 4);
            }
        }
    }
    r->off += row * (size_t)t->count;
    rc = disp_rows_check(t, M, r->err);
    if (rc)
        r->rc = rc;
}

int df_msg_disp_encode(const df_msg_disp *m, df_buf *out, df_error *err)
{
    int rc = disp_head_check(m, "disp", err);
    if (!rc)
        rc = disp_rows_check(m, "disp", err);
    if (rc || (rc = df_enc_reserve(out, disp_size(m), "disp", err)))
        return rc;
    disp_put(out, m);
    return DF_OK;
}

int df_msg_disp_decode(const uint8_t *p, size_t n, df_msg_disp *m, df_error *err)
{
    df_rd r;
    df_msg_disp t;
    df_rd_init(&r, p, n, "disp", err);
    disp_get(&r, &t, "disp");
    int rc = df_rd_end(&r);
    if (rc) {
        df_msg_disp_free(&t);
        return rc;
    }
    *m = t;
    return DF_OK;
}

void df_msg_disp_free(df_msg_disp *m)
{
    if (!m)
        return;
    free(m->xyz);
    free(m->idx);
    m->xyz = NULL;
    m->idx = NULL;
    m->count = 0;
}

static int progress_check(const df_msg_progress *m, df_error *err)
{
    const char *M = "progress";
    if (m->status > DF_MOVE_STATUS_MAX)
        return df_error_set(err, DF_EINVAL, "%s: status %u not in 0..%u", M, m->status,
                            DF_MOVE_STATUS_MAX);
    if (m->final > 1 || (m->final == 1) != (m->status != DF_MOVE_RUNNING))
        return df_error_set(err, DF_EINVAL, "%s: final %u inconsistent with status %u (final "
                            "iff status != running)", M, m->final, m->status);
    if (!isfinite(m->objective) || !isfinite(m->residual) || m->residual < 0 ||
        !isfinite(m->elapsed_ms) || m->elapsed_ms < 0)
        return df_error_set(err, DF_EINVAL, "%s: objective %g, residual %g, elapsed_ms %g must "
                            "be finite (residual, elapsed >= 0)", M, m->objective, m->residual,
                            m->elapsed_ms);
    if (m->disp.kind != DF_CHANGE_HANDLE_MOVE)
        return df_error_set(err, DF_EINVAL, "%s: disp kind %u is not handle_move (%u)", M,
                            m->disp.kind, DF_CHANGE_HANDLE_MOVE);
    return DF_OK;
}

int df_msg_progress_encode(const df_msg_progress *m, df_buf *out, df_error *err)
{
    int rc = progress_check(m, err);
    if (!rc)
        rc = disp_head_check(&m->disp, "progress", err);
    if (!rc)
        rc = disp_rows_check(&m->disp, "progress", err);
    if (rc || (rc = df_enc_reserve(out, PROGRESS_HEADER + disp_size(&m->disp), "progress", err)))
        return rc;
    df_buf_put_u8(out, m->status);
    df_buf_put_u8(out, m->final);
    df_buf_put_u16(out, 0);
    df_buf_put_u32(out, m->iteration);
    df_buf_put_f64(out, m->objective);
    df_buf_put_f64(out, m->residual);
    df_buf_put_f64(out, m->elapsed_ms);
    disp_put(out, &m->disp);
    return DF_OK;
}

int df_msg_progress_decode(const uint8_t *p, size_t n, df_msg_progress *m, df_error *err)
{
    df_rd r;
    df_msg_progress t;
    df_rd_init(&r, p, n, "progress", err);
    t.status = df_rd_u8(&r, "status");
    t.final = df_rd_u8(&r, "final");
    df_rd_reserved16(&r, "reserved");
    t.iteration = df_rd_u32(&r, "iteration");
    t.objective = df_rd_f64(&r, "objective");
    t.residual = df_rd_f64(&r, "residual");
    t.elapsed_ms = df_rd_f64(&r, "elapsed_ms");
    disp_get(&r, &t.disp, "progress");
    int rc = df_rd_end(&r);
    if (!rc)
        rc = progress_check(&t, err);
    if (rc) {
        df_msg_disp_free(&t.disp);
        return rc;
    }
    *m = t;
    return DF_OK;
}

void df_msg_progress_free(df_msg_progress *m)
{
    if (m)
        df_msg_disp_free(&m->disp);
}
