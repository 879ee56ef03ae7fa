/* stream.c — displacement stream encoding (see stream.h). */
#include "server/session/stream.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "proto/buf.h"
#include "proto/frame_codec.h"
#include "server/net/reply.h"

#define DF_STREAM_DISP_HEADER 44 /* bytes of a disp body before its rows (proto/msg_disp.c) */

int df_frames_push(df_frames *f, df_sbuf *b)
{
    if (f->n == f->cap) {
        size_t nc = f->cap ? 2 * f->cap : 4;
        df_sbuf **n = realloc(f->v, nc * sizeof *n);
        if (!n) {
            df_sbuf_unref(b);
            return DF_ENOMEM;
        }
        f->v = n;
        f->cap = nc;
    }
    f->v[f->n++] = b;
    return DF_OK;
}

void df_frames_clear(df_frames *f)
{
    for (size_t i = 0; i < f->n; i++) df_sbuf_unref(f->v[i]);
    free(f->v);
    f->v = NULL;
    f->n = f->cap = 0;
}

/* One displacement frame built in a single exact-size allocation: the bytes df_out_disp
 * produces for the same arguments, without its validation passes (the rows come from
 * df_stream_publish / the published state, already checked finite and in range). */
static df_sbuf *disp_frame(const df_msg_disp *d, uint16_t type, uint16_t flags, uint64_t req_id,
                           df_error *err)
{
    size_t row = df_msg_disp_row_bytes(d->encoding);
    size_t payload = DF_STREAM_DISP_HEADER + row * (size_t)d->count;
    df_sbuf *b = df_sbuf_new(DF_FRAME_HEADER_SIZE + payload);
    if (!b) {
        df_error_set(err, DF_ENOMEM, "out of memory for a %zu-byte frame", payload);
        return NULL;
    }
    df_frame_header h = {.magic = DF_FRAME_MAGIC, .version = DF_PROTO_VERSION, .type = type,
                         .flags = flags, .request_id = req_id, .payload_len = (uint32_t)payload};
    int rc = df_frame_header_encode(&h, b->data, err);
    if (rc != DF_OK) {
        df_sbuf_unref(b);
        return NULL;
    }
    uint8_t *q = b->data + DF_FRAME_HEADER_SIZE;
    df_le64_store(q, d->session_id);
    df_le64_store(q + 8, d->version);
    df_le64_store(q + 16, d->base_version);
    q[24] = d->kind;
    q[25] = d->encoding;
    df_le16_store(q + 26, 0);
    df_le32_store(q + 28, d->nv);
    df_le32_store(q + 32, d->total);
    df_le32_store(q + 36, d->offset);
    df_le32_store(q + 40, d->count);
    q += DF_STREAM_DISP_HEADER;
    if (d->encoding == DF_DISP_DENSE) {
        memcpy(q, d->xyz, 12 * (size_t)d->count);
    } else {
        for (uint32_t i = 0; i < d->count; i++, q += 16) {
            df_le32_store(q, (uint32_t)d->idx[i]);
            memcpy(q + 4, d->xyz + 3 * (size_t)i, 12);
        }
    }
    b->len = DF_FRAME_HEADER_SIZE + payload;
    return b;
}

/* Splits `d` (total rows in d->total, arrays for all of them) into chunk frames. */
static int emit_chunks(df_msg_disp *d, const df_msg_progress *progress, uint16_t type,
                       uint16_t flags, uint64_t req_id, df_frames *out, df_error *err)
{
    uint32_t per = df_msg_disp_rows_per_chunk(d->encoding, DF_STREAM_CHUNK_BYTES);
    int32_t *idx0 = d->idx;
    float *xyz0 = d->xyz;
    size_t first = out->n;
    uint32_t off = 0;
    do {
        uint32_t cnt = d->total - off < per ? d->total - off : per;
        d->offset = off;
        d->count = cnt;
        d->idx = idx0 ? idx0 + off : NULL;
        d->xyz = xyz0 + (size_t)off * 3;
        int last = off + cnt >= d->total;
        uint16_t fl = (uint16_t)(flags | (last ? 0 : DF_FLAG_MORE));
        df_sbuf *f;
        if (progress) {
            df_msg_progress p = *progress;
            p.disp = *d;
            f = df_out_progress(DF_MSG_PROGRESS, fl, req_id, &p, err);
        } else {
            f = disp_frame(d, type, fl, req_id, err);
        }
        if (!f || df_frames_push(out, f) != DF_OK) {
            while (out->n > first) df_sbuf_unref(out->v[--out->n]);
            d->idx = idx0;
            d->xyz = xyz0;
            return f ? df_error_set(err, DF_ENOMEM, "out of memory") : err->code;
        }
        off += cnt;
    } while (off < d->total);
    d->idx = idx0;
    d->xyz = xyz0;
    return DF_OK;
}

int df_stream_scratch(df_session *s, df_error *err)
{
    size_t nv = (size_t)(s->nv > 0 ? s->nv : 1);
    if (!s->scratch_u) s->scratch_u = malloc(3 * nv * sizeof(float));
    if (!s->scratch_idx) s->scratch_idx = malloc(nv * sizeof(int32_t));
    if (!s->scratch_rows) s->scratch_rows = malloc(3 * nv * sizeof(float));
    if (!s->scratch_pos) s->scratch_pos = malloc(3 * nv * sizeof(double));
    if (!s->scratch_disp) s->scratch_disp = malloc(3 * nv * sizeof(float));
    if (!s->scratch_u || !s->scratch_idx || !s->scratch_rows || !s->scratch_pos ||
        !s->scratch_disp)
        return df_error_set(err, DF_ENOMEM, "out of memory for %zu vertices", nv);
    return DF_OK;
}

/* 1 when the bits of row u differ from row v (3 floats each). */
static inline uint32_t row_changed(const float *u, const float *v)
{
    uint64_t a, b;
    uint32_t c, d;
    memcpy(&a, u, 8);
    memcpy(&b, v, 8);
    memcpy(&c, u + 2, 4);
    memcpy(&d, v + 2, 4);
    return (a != b) | (c != d);
}

int df_stream_encode(const df_session *s, const float *prev, uint64_t version,
                     const double *pos, uint8_t kind, const df_msg_progress *progress,
                     uint64_t req_id, float *newu, df_frames *out, uint32_t *changed,
                     df_error *err)
{
    size_t nv = (size_t)s->nv;
    const double *X = s->mesh.V;
    const float *uf = prev ? prev : s->uf;
    int32_t *idx = s->scratch_idx;
    /* Pass 1: new displacements, their finiteness, changed components. `omp simd` because
     * gcc's -O2 cost model will not add the alias checks needed to vectorize it on its own. */
    size_t m = 3 * nv;
    int bad = 0;
    uint32_t ne = 0;
#pragma omp simd reduction(| : bad) reduction(+ : ne)
    for (size_t i = 0; i < m; i++) {
        float u = (float)(pos[i] - X[i]);
        uint32_t a, b;
        memcpy(&a, &u, 4);
        memcpy(&b, uf + i, 4);
        newu[i] = u;
        /* NaN or infinite: the float32 displacement, or the float32 position a client gets
         * (load-time float32 position fl32(X) = s->basef + displacement, as GET_MESH and
         * replicas compute it) */
        bad |= !(fabsf(u) <= FLT_MAX) | !(fabsf((float)X[i] + u) <= FLT_MAX);
        ne += a != b;
    }
    if (bad) {
        for (size_t i = 0; i < m; i++)
            if (!isfinite(newu[i]) || !isfinite((float)X[i] + newu[i]))
                return df_error_set(err, DF_EINVAL, "the result is refused: vertex %zu "
                                    "component %zu would be %g, not finite in float32 "
                                    "(|x| <= 3.4e38); nothing changed", i / 3, i % 3, pos[i]);
    }
    /* Pass 2: rows whose bits changed, their indices when the frame will be sparse. Skipped
     * when the ne changed components (>= ne / 3 rows) already make it dense and the caller does
     * not ask for the row count (a brush stroke moving every vertex). */
    uint32_t k = (ne + 2) / 3;
    if (changed || df_msg_disp_choose(k, (uint32_t)nv) == DF_DISP_SPARSE) {
        k = 0;
        for (size_t i = 0; i < nv; i++) {
            idx[k] = (int32_t)i;
            k += row_changed(newu + 3 * i, uf + 3 * i);
        }
    }
    if (!version) version = atomic_load(&s->version) + 1;
    df_msg_disp d;
    memset(&d, 0, sizeof d);
    d.session_id = s->id;
    d.version = version;
    d.base_version = version - 1;
    d.kind = kind;
    d.nv = (uint32_t)nv;
    d.encoding = df_msg_disp_choose(k, (uint32_t)nv);
    if (d.encoding == DF_DISP_SPARSE) {
        float *rows = s->scratch_rows;
        for (uint32_t r = 0; r < k; r++) memcpy(rows + 3 * r, newu + 3 * (size_t)idx[r], 12);
        d.total = k;
        d.idx = idx;
        d.xyz = rows;
    } else {
        d.total = (uint32_t)nv;
        d.xyz = newu;
    }
    int rc = emit_chunks(&d, progress, DF_MSG_DISPLACEMENT, DF_FLAG_EVENT,
                         progress ? req_id : 0, out, err);
    if (rc == DF_OK && changed) *changed = k;
    return rc;
}

int df_stream_publish(df_session *s, const double *pos, uint8_t kind,
                      const df_msg_progress *progress, uint64_t req_id, df_frames *out,
                      uint32_t *changed, df_error *err)
{
    if (df_stream_scratch(s, err) != DF_OK) return err ? err->code : DF_ENOMEM;
    int rc = df_stream_encode(s, NULL, 0, pos, kind, progress, req_id, s->scratch_u, out,
                              changed, err);
    if (rc == DF_OK) {
        float *newu = s->scratch_u; /* swap: newu becomes the published state */
        s->scratch_u = s->uf;
        s->uf = newu;
        atomic_store(&s->version, atomic_load(&s->version) + 1);
    }
    return rc;
}

int df_stream_snapshot(df_session *s, uint16_t type, uint64_t req_id, df_frames *out,
                       df_error *err)
{
    df_msg_disp d;
    memset(&d, 0, sizeof d);
    d.session_id = s->id;
    d.version = atomic_load(&s->version);
    d.base_version = 0;
    d.kind = DF_CHANGE_SNAPSHOT;
    d.encoding = DF_DISP_DENSE;
    d.nv = (uint32_t)s->nv;
    d.total = (uint32_t)s->nv;
    d.xyz = s->uf;
    int reply = type != DF_MSG_DISPLACEMENT;
    return emit_chunks(&d, NULL, type, reply ? DF_FLAG_REPLY : DF_FLAG_EVENT, req_id, out, err);
}

void df_stream_positions(const df_session *s, float *xyz)
{
    for (size_t i = 0; i < 3 * (size_t)s->nv; i++) xyz[i] = s->basef[i] + s->uf[i];
}
