/* stream_lag.c — coalescing for subscribers that cannot keep up (stream_lag.h). */
#include "server/session/stream_lag.h"

#include <stdlib.h>
#include <string.h>

#include "proto/buf.h"
#include "proto/frame_codec.h"
#include "proto/messages.h"
#include "server/log.h"
#include "server/net/conn.h"
#include "server/net/reply.h"
#include "server/server.h"
#include "server/session/stream.h"

#define DISP_HEADER 44   /* disp body bytes before the rows (PROTOCOL.md 4.21) */
#define PROGRESS_HEADER 32

/* The view of a stream chunk (disp, progress or qdisp body) the accumulator needs. */
typedef struct chunk {
    uint64_t version, base;
    uint8_t kind;
    int last;
} chunk;

static int chunk_head(const df_sbuf *f, chunk *k)
{
    if (f->len < DF_FRAME_HEADER_SIZE + DISP_HEADER) return 0;
    const uint8_t *p = f->data + DF_FRAME_HEADER_SIZE;
    if (df_le16_load(f->data + 6) == DF_MSG_PROGRESS) {
        if (f->len < DF_FRAME_HEADER_SIZE + PROGRESS_HEADER + DISP_HEADER) return 0;
        p += PROGRESS_HEADER;
    }
    k->version = df_le64_load(p + 8);
    k->base = df_le64_load(p + 16);
    k->kind = p[24];
    k->last = !(df_le16_load(f->data + 8) & DF_FLAG_MORE);
    return 1;
}

static int lag_start(df_session *s, const df_conn *c, df_sublag *l, int quant, uint64_t held)
{
    size_t nv = (size_t)s->nv;
    uint64_t bytes = nv * (quant ? 1 + 3 * sizeof *l->dq : 1 + 3 * sizeof *l->u);
    df_error err;
    if (df_session_mem_charge(s->srv, DF_MEM_STREAM, bytes, "coalescing", &err) != DF_OK) {
        df_log(DF_LOG_WARN, "session %llu: client %llu cannot keep up and is not coalesced: %s",
               (unsigned long long)s->id, (unsigned long long)c->id, err.msg);
        return DF_ELIMIT;
    }
    l->touched = calloc(nv, 1);
    if (quant) l->dq = calloc(3 * nv, sizeof *l->dq);
    else l->u = malloc(3 * nv * sizeof *l->u);
    if (!l->touched || (quant ? !l->dq : !l->u)) {
        free(l->touched);
        free(l->dq);
        free(l->u);
        l->touched = NULL;
        l->dq = NULL;
        l->u = NULL;
        df_mem_release(df_server_mem(s->srv), DF_MEM_STREAM, bytes);
        return DF_ENOMEM;
    }
    l->charged = bytes;
    l->lagging = 1;
    l->held = held;
    s->srv->lagging_subs++;
    return DF_OK;
}

/* Folds the exact chunk `f` (DISPLACEMENT / PROGRESS) into l->u. */
static void fold_exact(df_session *s, df_sublag *l, const df_sbuf *f)
{
    const uint8_t *p = f->data + DF_FRAME_HEADER_SIZE;
    size_t n = f->len - DF_FRAME_HEADER_SIZE;
    if (df_le16_load(f->data + 6) == DF_MSG_PROGRESS) {
        p += PROGRESS_HEADER;
        n -= PROGRESS_HEADER;
    }
    uint32_t count = df_le32_load(p + 40), offset = df_le32_load(p + 36);
    int sparse = p[25] == DF_DISP_SPARSE;
    size_t row = sparse ? 16 : 12;
    if (n != DISP_HEADER + row * (size_t)count) return; /* built by the daemon: never */
    const uint8_t *r = p + DISP_HEADER;
    for (uint32_t j = 0; j < count; j++, r += row) {
        uint32_t i = sparse ? df_le32_load(r) : offset + j;
        if (i >= (uint32_t)s->nv) continue;
        memcpy(l->u + 3 * (size_t)i, r + (sparse ? 4 : 0), 12);
        l->touched[i] = 1;
    }
}

/* Folds the QDISP chunk `f` into l->dq. */
static void fold_quant(df_sublag *l, const df_sbuf *f)
{
    df_msg_qdisp q;
    if (df_msg_qdisp_decode(f->data + DF_FRAME_HEADER_SIZE, f->len - DF_FRAME_HEADER_SIZE, &q,
                            NULL) != DF_OK)
        return;
    for (uint32_t j = 0; j < q.count; j++) {
        size_t i = (size_t)q.idx[j];
        for (int k = 0; k < 3; k++) l->dq[3 * i + k] += q.dq[3 * (size_t)j + k];
        l->touched[i] = 1;
    }
    df_msg_qdisp_free(&q);
}

/* The coalesced version of subscription i: the touched rows, chunked. The state is released
 * before the frames are queued (a drop for a full queue unsubscribes the connection). */
static void catch_up(df_session *s, int i)
{
    df_conn *c = s->subs[i];
    df_sublag *l = &s->sub_lag[i];
    size_t nv = (size_t)s->nv;
    int quant = l->dq != NULL;
    uint32_t k = 0;
    for (size_t v = 0; v < nv; v++) k += l->touched[v];
    int32_t *idx = malloc(((size_t)k + 1) * sizeof *idx);
    float *xyz = quant ? NULL : malloc(((size_t)k + 1) * 3 * sizeof *xyz);
    int64_t *dq = quant ? malloc(((size_t)k + 1) * 3 * sizeof *dq) : NULL;
    uint32_t m = 0;
    if (idx && (xyz || dq))
        for (size_t v = 0; v < nv; v++) {
            if (!l->touched[v]) continue;
            if (quant && !(l->dq[3 * v] | l->dq[3 * v + 1] | l->dq[3 * v + 2])) continue;
            idx[m] = (int32_t)v;
            if (quant) memcpy(dq + 3 * (size_t)m, l->dq + 3 * v, 3 * sizeof *dq);
            else memcpy(xyz + 3 * (size_t)m, l->u + 3 * v, 12);
            m++;
        }
    int ok = idx && (xyz || dq);
    df_frames out = {0};
    /* chunks of at most DF_STREAM_CHUNK_BYTES (16 or 29 bytes a row) */
    uint32_t per = (uint32_t)(DF_STREAM_CHUNK_BYTES / (quant ? 29 : 16));
    for (uint32_t off = 0; ok && (off < m || off == 0);) {
        uint32_t cnt = m - off < per ? m - off : per;
        uint16_t fl = (uint16_t)(DF_FLAG_EVENT | (off + cnt < m ? DF_FLAG_MORE : 0));
        df_error err;
        df_sbuf *f = NULL;
        if (quant) {
            df_msg_qdisp q = {.session_id = s->id, .version = l->last, .base_version = l->held,
                              .kind = l->kind, .nv = (uint32_t)nv, .count = cnt,
                              .step = 2 * c->stream_err, .idx = idx + off,
                              .dq = dq + 3 * (size_t)off}; /* no progress trailer */
            df_buf b;
            df_buf_init(&b);
            size_t start;
            if (df_frame_begin(&b, DF_MSG_QDISP, fl, 0, &start, &err) == DF_OK &&
                df_msg_qdisp_encode(&q, &b, &err) == DF_OK && df_frame_end(&b, start, &err) == DF_OK)
                f = df_sbuf_from_buf(&b);
            df_buf_free(&b);
        } else {
            df_msg_disp d = {s->id, l->last, l->held, l->kind, DF_DISP_SPARSE, (uint32_t)nv, m,
                             off, cnt, idx + off, xyz + 3 * (size_t)off};
            f = df_out_disp(DF_MSG_DISPLACEMENT, fl, 0, &d, &err);
        }
        df_sbuf *z = f && (c->stream_enc & DF_STREAM_ENC_ZSTD) ? df_stream_enc_zstd(f) : df_sbuf_ref(f);
        df_sbuf_unref(f);
        ok = z && df_frames_push(&out, z) == DF_OK;
        off += cnt;
        if (cnt == 0) break;
    }
    free(idx);
    free(xyz);
    free(dq);
    df_stream_lag_release(s, i);
    if (!ok) {
        df_log(DF_LOG_ERROR, "session %llu: out of memory for client %llu's coalesced version; "
               "it will see a gap and resync", (unsigned long long)s->id,
               (unsigned long long)c->id);
        df_frames_clear(&out);
        return;
    }
    df_conn_ref(c);
    for (size_t j = 0; j < out.n && !c->closing; j++) df_conn_send(c, out.v[j]);
    df_conn_unref(c);
    df_frames_clear(&out);
}

void df_stream_lag_thresholds(size_t limit, int start, int resume, size_t *hi, size_t *lo)
{
    *hi = start > 0 ? (size_t)start : DF_LAG_HI(limit);
    if (*hi > limit) *hi = limit;
    *lo = resume > 0 ? (size_t)resume : DF_LAG_LO(limit);
    if (*lo > *hi) *lo = *hi;
}

/* the thresholds of connection c under the running config */
static void thresholds(const df_server *srv, const df_conn *c, size_t *hi, size_t *lo)
{
    df_stream_lag_thresholds(c->outq.limit, srv->cfg.stream_coalesce_start,
                             srv->cfg.stream_coalesce_resume, hi, lo);
}

int df_stream_lag_send(df_session *s, int i, df_sbuf *frame, df_enc_variants *vs)
{
    df_conn *c = s->subs[i];
    df_sublag *l = &s->sub_lag[i];
    df_sbuf *f = df_stream_enc_frame(s, c, frame, vs);
    if (!f) return DF_ENOMEM;
    chunk k;
    size_t hi, lo;
    thresholds(s->srv, c, &hi, &lo);
    int head = chunk_head(frame, &k);
    int quant = (c->stream_enc & DF_STREAM_ENC_QUANTIZED) != 0;
    if (!(c->stream_enc || c->stream_neg) || !head ||
        (!l->lagging && (l->mid || c->outq.bytes < hi)) ||
        (!l->lagging && lag_start(s, c, l, quant, k.base) != DF_OK)) {
        l->mid = head && !k.last; /* before the send: a drop unsubscribes (l then is gone) */
        int rc = df_conn_send(c, f);
        df_sbuf_unref(f);
        return rc;
    }
    df_sbuf_unref(f);
    if (quant) { /* the group's QDISP (the variant before compression) */
        df_sbuf *qf = df_stream_enc_get(s, DF_STREAM_ENC_QUANTIZED, c->stream_err, frame, vs);
        if (qf) fold_quant(l, qf);
        df_sbuf_unref(qf);
    } else {
        fold_exact(s, l, frame);
    }
    l->last = k.version;
    l->kind = k.kind;
    l->mid = 0;
    if (k.last) {
        c->coalesced++;
        s->srv->stats.stream_coalesced++;
        if (c->outq.bytes <= lo) catch_up(s, i);
    }
    return DF_OK;
}

void df_stream_lag_poll(df_server *srv)
{
    if (srv->lagging_subs == 0) return;
    for (df_session *s = srv->sessions; s; s = s->next)
        for (int i = 0; i < s->nsubs && s->sub_lag; i++) {
            df_sublag *l = &s->sub_lag[i];
            df_conn *c = s->subs[i];
            size_t hi, lo;
            thresholds(srv, c, &hi, &lo);
            if (l->lagging && l->last && !c->closing && c->outq.bytes <= lo) catch_up(s, i);
        }
}

void df_stream_lag_release(df_session *s, int i)
{
    df_sublag *l = &s->sub_lag[i];
    if (l->lagging) s->srv->lagging_subs--;
    if (l->charged) df_mem_release(df_server_mem(s->srv), DF_MEM_STREAM, l->charged);
    free(l->touched);
    free(l->u);
    free(l->dq);
    memset(l, 0, sizeof *l);
}
