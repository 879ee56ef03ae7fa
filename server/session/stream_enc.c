/* stream_enc.c — quantized and zstd stream variants per subscriber encoding (stream_enc.h). */
#include "server/session/stream_enc.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <zstd.h>

#include "proto/buf.h"
#include "proto/frame_codec.h"
#include "proto/messages.h"
#include "server/log.h"
#include "server/net/reply.h"

#define ZSTD_STREAM_LEVEL 1       /* fast: a 12 MB dense frame compresses in tens of ms */
#define ZFRAME_HEADER 12         /* zframe body bytes before the zstd frame */
#define ZSTD_MIN_PAYLOAD 256      /* smaller frames are never worth a ZFRAME header */
#define K_LIMIT 4503599627370495.0 /* 2^52 - 1: K stays exact in double and in the wire's range */

/* floor(u / q + 0.5) in double, clamped to +-K_LIMIT (PROTOCOL.md 4.38: clients compute the same) */
static inline int64_t quantize(float u, double q)
{
    double k = floor((double)u / q + 0.5);
    if (k > K_LIMIT) k = K_LIMIT;
    if (k < -K_LIMIT) k = -K_LIMIT;
    return (int64_t)k;
}

static df_qgroup *find_group(df_session *s, double err)
{
    for (int i = 0; i < s->nqg; i++)
        if (s->qg[i].err == err) return &s->qg[i];
    return NULL;
}

int df_stream_enc_join(df_session *s, const df_conn *c, df_error *err)
{
    if (!(c->stream_enc & DF_STREAM_ENC_QUANTIZED) || find_group(s, c->stream_err)) return DF_OK;
    size_t m = 3 * (size_t)s->nv;
    int64_t *K = malloc(m * sizeof *K);
    df_qgroup *g = realloc(s->qg, (size_t)(s->nqg + 1) * sizeof *g);
    if (!K || !g) {
        free(K);
        if (g) s->qg = g;
        return df_error_set(err, DF_ENOMEM, "subscribe: out of memory for the quantized stream "
                            "of %d vertices", s->nv);
    }
    s->qg = g;
    double q = 2 * c->stream_err;
    for (size_t i = 0; i < m; i++) K[i] = quantize(s->uf[i], q);
    s->qg[s->nqg++] = (df_qgroup){.err = c->stream_err, .step = q, .K = K};
    df_log(DF_LOG_DEBUG, "session %llu: quantized stream group error %g (%d groups)",
           (unsigned long long)s->id, c->stream_err, s->nqg);
    return DF_OK;
}

void df_stream_enc_prune(df_session *s)
{
    int w = 0;
    for (int i = 0; i < s->nqg; i++) {
        int used = 0;
        for (int j = 0; j < s->nsubs && !used; j++)
            used = (s->subs[j]->stream_enc & DF_STREAM_ENC_QUANTIZED) &&
                   s->subs[j]->stream_err == s->qg[i].err;
        if (used) s->qg[w++] = s->qg[i];
        else free(s->qg[i].K);
    }
    s->nqg = w;
    if (w == 0) {
        free(s->qg);
        s->qg = NULL;
    }
}

void df_stream_enc_free(df_session *s)
{
    for (int i = 0; i < s->nqg; i++) free(s->qg[i].K);
    free(s->qg);
    s->qg = NULL;
    s->nqg = 0;
}

int df_stream_enc_applies(const df_sbuf *frame)
{
    if (frame->len < DF_FRAME_HEADER_SIZE) return 0;
    uint16_t type = df_le16_load(frame->data + 6), flags = df_le16_load(frame->data + 8);
    return (type == DF_MSG_DISPLACEMENT || type == DF_MSG_PROGRESS) && (flags & DF_FLAG_EVENT);
}

df_sbuf *df_stream_enc_zstd(df_sbuf *frame)
{
    size_t raw = frame->len - DF_FRAME_HEADER_SIZE;
    if (raw < ZSTD_MIN_PAYLOAD) return df_sbuf_ref(frame);
    size_t bound = ZSTD_compressBound(raw);
    df_sbuf *z = df_sbuf_new(DF_FRAME_HEADER_SIZE + ZFRAME_HEADER + bound);
    if (!z) return NULL;
    size_t zn = ZSTD_compress(z->data + DF_FRAME_HEADER_SIZE + ZFRAME_HEADER, bound,
                              frame->data + DF_FRAME_HEADER_SIZE, raw, ZSTD_STREAM_LEVEL);
    if (ZSTD_isError(zn) || zn + ZFRAME_HEADER >= raw) { /* incompressible: the frame itself */
        df_sbuf_unref(z);
        return df_sbuf_ref(frame);
    }
    memcpy(z->data, frame->data, DF_FRAME_HEADER_SIZE);
    df_le16_store(z->data + 6, DF_MSG_ZFRAME);
    df_le32_store(z->data + 20, (uint32_t)(zn + ZFRAME_HEADER));
    uint8_t *p = z->data + DF_FRAME_HEADER_SIZE; /* zframe body (PROTOCOL.md 4.39) */
    df_le16_store(p, df_le16_load(frame->data + 6)); /* inner_type */
    df_le16_store(p + 2, 0);
    df_le32_store(p + 4, (uint32_t)raw);
    df_le32_store(p + 8, (uint32_t)zn);
    z->len = DF_FRAME_HEADER_SIZE + ZFRAME_HEADER + zn;
    return z;
}

/* The QDISP frame of `frame` (a DISPLACEMENT or PROGRESS chunk) for group `g`, updating g->K. */
static df_sbuf *quantize_frame(df_session *s, df_qgroup *g, df_sbuf *frame)
{
    df_error err;
    df_frame_header h;
    if (df_frame_header_decode(frame->data, frame->len, &h, &err) != DF_OK) return NULL;
    const uint8_t *pl = frame->data + DF_FRAME_HEADER_SIZE;
    df_msg_progress pr;
    df_msg_disp *d = &pr.disp;
    memset(&pr, 0, sizeof pr);
    int rc = h.type == DF_MSG_PROGRESS ? df_msg_progress_decode(pl, h.payload_len, &pr, &err)
                                       : df_msg_disp_decode(pl, h.payload_len, d, &err);
    if (rc != DF_OK || d->nv != (uint32_t)s->nv) {
        df_log(DF_LOG_ERROR, "session %llu: quantized stream: a broadcast frame does not decode "
               "(%s)", (unsigned long long)s->id, rc ? err.msg : "vertex count");
        df_msg_disp_free(d);
        return NULL;
    }
    df_msg_qdisp qd = {.session_id = d->session_id, .version = d->version,
                       .base_version = d->base_version, .kind = d->kind, .nv = d->nv,
                       .step = g->step};
    qd.idx = malloc(((size_t)d->count + 1) * sizeof *qd.idx);
    qd.dq = malloc(((size_t)d->count + 1) * 3 * sizeof *qd.dq);
    df_sbuf *out = NULL;
    if (qd.idx && qd.dq) {
        for (uint32_t r = 0; r < d->count; r++) {
            size_t i = d->encoding == DF_DISP_SPARSE ? (size_t)d->idx[r] : d->offset + (size_t)r;
            int64_t *K = g->K + 3 * i, *dq = qd.dq + 3 * (size_t)qd.count;
            const float *u = d->xyz + 3 * (size_t)r;
            int nz = 0;
            for (int k = 0; k < 3; k++) {
                int64_t kn = quantize(u[k], g->step);
                dq[k] = kn - K[k];
                nz |= dq[k] != 0;
                K[k] = kn;
            }
            if (nz) qd.idx[qd.count++] = (int32_t)i;
        }
        df_buf b;
        df_buf_init(&b);
        size_t start;
        if (df_frame_begin(&b, DF_MSG_QDISP, h.flags, h.request_id, &start, &err) == DF_OK &&
            df_msg_qdisp_encode(&qd, &b, &err) == DF_OK && df_frame_end(&b, start, &err) == DF_OK)
            out = df_sbuf_from_buf(&b);
        df_buf_free(&b);
    }
    free(qd.idx);
    free(qd.dq);
    df_msg_disp_free(d);
    if (!out)
        df_log(DF_LOG_ERROR, "session %llu: quantized stream frame of version %llu failed",
               (unsigned long long)s->id, (unsigned long long)qd.version);
    return out;
}

static df_enc_variant *variant(df_enc_variants *vs, uint8_t enc, double e)
{
    for (int i = 0; i < vs->n; i++)
        if (vs->v[i].enc == enc && vs->v[i].err == e) return &vs->v[i];
    return NULL;
}

/* Builds variant (enc, e) into vs (the quantized one first when zstd needs it). */
static df_enc_variant *build(df_session *s, df_sbuf *frame, df_enc_variants *vs, uint8_t enc,
                             double e)
{
    df_enc_variant *v = variant(vs, enc, e);
    if (v) return v;
    if (vs->n == (int)(sizeof vs->v / sizeof vs->v[0])) return NULL;
    df_sbuf *f = NULL;
    if (enc == DF_STREAM_ENC_QUANTIZED) {
        df_qgroup *g = find_group(s, e);
        f = g ? quantize_frame(s, g, frame) : NULL;
    } else if (enc == DF_STREAM_ENC_ZSTD) {
        f = df_stream_enc_zstd(frame);
    } else { /* QUANTIZED | ZSTD: compress the group's QDISP */
        df_enc_variant *qv = build(s, frame, vs, DF_STREAM_ENC_QUANTIZED, e);
        if (qv && qv->frame) f = df_stream_enc_zstd(qv->frame);
    }
    if (vs->n == (int)(sizeof vs->v / sizeof vs->v[0])) {
        df_sbuf_unref(f);
        return NULL;
    }
    v = &vs->v[vs->n++];
    *v = (df_enc_variant){.enc = enc, .err = e, .frame = f};
    return v;
}

df_sbuf *df_stream_enc_frame(df_session *s, const df_conn *c, df_sbuf *frame, df_enc_variants *vs)
{
    uint8_t enc = c->stream_enc & DF_STREAM_ENC_ALL;
    if (!enc) return df_sbuf_ref(frame);
    double e = enc & DF_STREAM_ENC_QUANTIZED ? c->stream_err : 0;
    df_enc_variant *v = build(s, frame, vs, enc, e);
    return v ? df_sbuf_ref(v->frame) : NULL;
}

void df_stream_enc_follow(df_session *s, df_sbuf *frame, df_enc_variants *vs)
{
    for (int g = 0; g < s->nqg; g++) build(s, frame, vs, DF_STREAM_ENC_QUANTIZED, s->qg[g].err);
}

void df_stream_enc_variants_clear(df_enc_variants *vs)
{
    for (int i = 0; i < vs->n; i++) df_sbuf_unref(vs->v[i].frame);
    vs->n = 0;
}
