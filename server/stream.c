/* stream.c — displacement stream encoding (see stream.h). */
#include "server/stream.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "server/reply.h"

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
            f = df_out_disp(type, fl, req_id, d, err);
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

int df_stream_publish(df_session *s, const double *pos, uint8_t kind,
                      const df_msg_progress *progress, uint64_t req_id, df_frames *out,
                      uint32_t *changed, df_error *err)
{
    if (df_stream_scratch(s, err) != DF_OK) return err ? err->code : DF_ENOMEM;
    size_t nv = (size_t)s->nv;
    const double *X = s->mesh.V;
    const float *uf = s->uf;
    float *newu = s->scratch_u;
    int32_t *idx = s->scratch_idx;
    /* One pass: new displacements, finiteness, changed rows. */
    uint32_t k = 0;
    int bad = 0;
    for (size_t i = 0; i < nv; i++) {
        const double *p = pos + 3 * i, *x = X + 3 * i;
        float *u = newu + 3 * i;
        u[0] = (float)(p[0] - x[0]);
        u[1] = (float)(p[1] - x[1]);
        u[2] = (float)(p[2] - x[2]);
        bad |= !isfinite(u[0]) | !isfinite(u[1]) | !isfinite(u[2]);
        uint32_t a, b;
        uint64_t c, d;
        memcpy(&a, u + 2, 4);
        memcpy(&b, uf + 3 * i + 2, 4);
        memcpy(&c, u, 8);
        memcpy(&d, uf + 3 * i, 8);
        idx[k] = (int32_t)i;
        k += (a != b) | (c != d);
    }
    if (bad) {
        for (size_t i = 0; i < 3 * nv; i++)
            if (!isfinite(newu[i]))
                return df_error_set(err, DF_EINVAL, "vertex %zu: position not finite", i / 3);
    }
    uint64_t version = atomic_load(&s->version) + 1;
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
    if (rc == DF_OK) {
        s->scratch_u = s->uf; /* swap: newu becomes the published state */
        s->uf = newu;
        atomic_store(&s->version, version);
        if (changed) *changed = k;
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
