/* stream_enc.c — quantized and zstd stream variants per subscriber encoding (stream_enc.h). */
#include "server/session/stream_enc.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <zstd.h>

#include "proto/buf.h"
#include "proto/frame_codec.h"
#include "proto/messages.h"
#include "server/log.h"
#include "server/net/reply.h"
#include "server/server.h"

#define ZSTD_STREAM_LEVEL 1       /* fast; the loop thread compresses each frame */
#define ZFRAME_HEADER 12         /* zframe body bytes before the zstd frame */
#define ZSTD_MIN_PAYLOAD 256      /* smaller frames are never worth a ZFRAME header */
#define K_LIMIT 4503599627370495.0 /* 2^52 - 1: K stays exact in double and in the wire's range */

/* floor(u / q + 0.5) in double, clamped to +-K_LIMIT (PROTOCOL.md 4.40: clients compute the same) */
static inline int64_t quantize(float u, double q)
{
    double k = floor((double)u / q + 0.5);
    if (k > K_LIMIT) k = K_LIMIT;
    if (k < -K_LIMIT) k = -K_LIMIT;
    return (int64_t)k;
}

/* quantize(u, q) with r = 1 / q (rounded): the same K, a multiply instead of a division where
 * that provably gives it. For |y| < 2^20, y = u * r differs from the u / q of quantize by less than
 * 3 * 2^-53 * 2^20 < 2^-31, and y + 0.5 from its counterpart by less than 2^-31 + 2 * 2^-33 <
 * 1e-9; so when y + 0.5 lies more than 1e-6 from every integer both have the same floor. Anything
 * else (near a step boundary, large, NaN): quantize's division. */
static inline int64_t quantize_r(float u, double q, double r)
{
    double y = (double)u * r;
    if (fabs(y) < 1048576.0) {
        double z = y + 0.5, k = floor(z), f = z - k; /* f exact: the fraction bits of z */
        if (f > 1e-6 && f < 1 - 1e-6) return (int64_t)k;
    }
    return quantize(u, q);
}

static df_qgroup *find_group(df_session *s, double err)
{
    for (int i = 0; i < s->nqg; i++)
        if (s->qg[i].err == err) return &s->qg[i];
    return NULL;
}

/* returns one group's charge (3 nv int64) */
static void release_group(df_session *s)
{
    if (s->srv)
        df_mem_release(df_server_mem(s->srv), DF_MEM_STREAM, 3 * (size_t)s->nv * sizeof(int64_t));
}

int df_stream_enc_join(df_session *s, const df_conn *c, df_error *err)
{
    if (!(c->stream_enc & DF_STREAM_ENC_QUANTIZED) || find_group(s, c->stream_err)) return DF_OK;
    if (s->nqg >= DF_QGROUP_MAX)
        return df_error_set(err, DF_ELIMIT, "subscribe: session %llu already streams %d "
                            "distinct quantized error bounds (at most %d); connect with one of "
                            "theirs", (unsigned long long)s->id, s->nqg, DF_QGROUP_MAX);
    size_t m = 3 * (size_t)s->nv;
    /* charged to memory_max_mb (membudget.h); a bare session (bench) has no server */
    if (s->srv && df_session_mem_charge(s->srv, DF_MEM_STREAM, m * sizeof(int64_t), "subscribe "
                                        "(quantized stream group)", err) != DF_OK)
        return DF_ELIMIT;
    int64_t *K = malloc(m * sizeof *K);
    df_qgroup *g = realloc(s->qg, (size_t)(s->nqg + 1) * sizeof *g);
    if (!K || !g) {
        free(K);
        if (g) s->qg = g;
        if (s->srv) df_mem_release(df_server_mem(s->srv), DF_MEM_STREAM, m * sizeof(int64_t));
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
        if (used) {
            s->qg[w++] = s->qg[i];
        } else {
            free(s->qg[i].K);
            release_group(s);
        }
    }
    s->nqg = w;
    if (w == 0) {
        free(s->qg);
        s->qg = NULL;
    }
}

void df_stream_enc_free(df_session *s)
{
    for (int i = 0; i < s->nqg; i++) {
        free(s->qg[i].K);
        release_group(s);
    }
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

/* One compression context per thread, kept across frames (ZSTD_compress would create and free
 * one per call, its tables page-faulted afresh) and freed when the thread exits: the same bytes
 * as ZSTD_compress. NULL when out of memory (the caller then uses ZSTD_compress). */
static pthread_key_t cctx_key;
static pthread_once_t cctx_once = PTHREAD_ONCE_INIT;

static void cctx_free(void *p)
{
    ZSTD_freeCCtx(p);
}

static void cctx_key_make(void)
{
    (void)pthread_key_create(&cctx_key, cctx_free);
}

static ZSTD_CCtx *thread_cctx(void)
{
    pthread_once(&cctx_once, cctx_key_make);
    ZSTD_CCtx *cx = pthread_getspecific(cctx_key);
    if (!cx && (cx = ZSTD_createCCtx()) != NULL && pthread_setspecific(cctx_key, cx) != 0) {
        ZSTD_freeCCtx(cx);
        cx = NULL;
    }
    return cx;
}

df_sbuf *df_stream_enc_zstd(df_sbuf *frame)
{
    size_t raw = frame->len - DF_FRAME_HEADER_SIZE;
    if (raw < ZSTD_MIN_PAYLOAD) return df_sbuf_ref(frame);
    size_t bound = ZSTD_compressBound(raw);
    df_sbuf *z = df_sbuf_new(DF_FRAME_HEADER_SIZE + ZFRAME_HEADER + bound);
    if (!z) return NULL;
    ZSTD_CCtx *cx = thread_cctx();
    size_t zn = cx ? ZSTD_compressCCtx(cx, z->data + DF_FRAME_HEADER_SIZE + ZFRAME_HEADER, bound,
                                       frame->data + DF_FRAME_HEADER_SIZE, raw, ZSTD_STREAM_LEVEL)
                   : ZSTD_compress(z->data + DF_FRAME_HEADER_SIZE + ZFRAME_HEADER, bound,
                                   frame->data + DF_FRAME_HEADER_SIZE, raw, ZSTD_STREAM_LEVEL);
    if (ZSTD_isError(zn) || zn + ZFRAME_HEADER >= raw) { /* incompressible: the frame itself */
        df_sbuf_unref(z);
        return df_sbuf_ref(frame);
    }
    memcpy(z->data, frame->data, DF_FRAME_HEADER_SIZE);
    df_le16_store(z->data + 6, DF_MSG_ZFRAME);
    df_le32_store(z->data + 20, (uint32_t)(zn + ZFRAME_HEADER));
    uint8_t *p = z->data + DF_FRAME_HEADER_SIZE; /* zframe body (PROTOCOL.md 4.41) */
    df_le16_store(p, df_le16_load(frame->data + 6)); /* inner_type */
    df_le16_store(p + 2, 0);
    df_le32_store(p + 4, (uint32_t)raw);
    df_le32_store(p + 8, (uint32_t)zn);
    z->len = DF_FRAME_HEADER_SIZE + ZFRAME_HEADER + zn;
    return z;
}

static inline uint8_t *put_varint(uint8_t *q, uint64_t v)
{
    while (v >= 0x80) {
        *q++ = (uint8_t)(v | 0x80);
        v >>= 7;
    }
    *q++ = (uint8_t)v;
    return q;
}

#define QDISP_HEADER 48  /* qdisp body bytes before the rows (PROTOCOL.md 4.40) */
#define QDISP_ROW_MAX 29 /* varint gap + 3 zigzag varints of |dq| < 2^53 */
#define DISP_HEADER 44   /* disp body bytes before the rows (4.21) */
#define PROGRESS_HEADER 32

/* The QDISP frame of `frame` (a DISPLACEMENT or PROGRESS chunk the daemon built: read in place,
 * bounds checked) for group `g`, updating g->K. One pass: each row's new K, its change written
 * as varints straight into the frame. */
static df_sbuf *quantize_frame(df_session *s, df_qgroup *g, df_sbuf *frame)
{
    const uint8_t *h = frame->data, *p = h + DF_FRAME_HEADER_SIZE;
    size_t n = frame->len - DF_FRAME_HEADER_SIZE;
    uint16_t type = df_le16_load(h + 6);
    const uint8_t *prog = type == DF_MSG_PROGRESS && n >= PROGRESS_HEADER ? p : NULL;
    if (type == DF_MSG_PROGRESS) {
        p += PROGRESS_HEADER;
        n -= n >= PROGRESS_HEADER ? PROGRESS_HEADER : n;
    }
    uint32_t nv = n >= DISP_HEADER ? df_le32_load(p + 28) : 0;
    uint32_t count = n >= DISP_HEADER ? df_le32_load(p + 40) : 0;
    uint32_t offset = n >= DISP_HEADER ? df_le32_load(p + 36) : 0;
    uint8_t enc = n >= DISP_HEADER ? p[25] : 0;
    size_t row = enc == DF_DISP_SPARSE ? 16 : 12;
    if (n < DISP_HEADER || nv != (uint32_t)s->nv || (enc != DF_DISP_SPARSE && enc != DF_DISP_DENSE) ||
        n != DISP_HEADER + row * (size_t)count ||
        (enc == DF_DISP_DENSE && (uint64_t)offset + count > nv)) {
        df_log(DF_LOG_ERROR, "session %llu: quantized stream: a broadcast frame does not parse",
               (unsigned long long)s->id);
        return NULL;
    }
    size_t cap = DF_FRAME_HEADER_SIZE + QDISP_HEADER + QDISP_ROW_MAX * (size_t)count +
                 PROGRESS_HEADER;
    /* built in place: a df_sbuf of the worst-case size (sbuf.c keeps such blocks for reuse, so
     * the pages written are not faulted afresh every version) */
    df_sbuf *b = df_sbuf_new(cap);
    if (!b) return NULL;
    uint8_t *out = b->data;
    uint8_t *o = out + DF_FRAME_HEADER_SIZE, *q = o + QDISP_HEADER;
    const uint8_t *rows = p + DISP_HEADER;
    int64_t prev = -1;
    uint32_t sent = 0;
    const double rstep = 1.0 / g->step;
    for (uint32_t r = 0; r < count; r++, rows += row) {
        uint32_t i = enc == DF_DISP_SPARSE ? df_le32_load(rows) : offset + r;
        if (i >= nv) {
            df_sbuf_unref(b);
            return NULL;
        }
        float u[3];
        memcpy(u, rows + (enc == DF_DISP_SPARSE ? 4 : 0), 12);
        int64_t *K = g->K + 3 * (size_t)i, dq[3];
        for (int k = 0; k < 3; k++) dq[k] = quantize_r(u[k], g->step, rstep) - K[k];
        if ((dq[0] | dq[1] | dq[2]) == 0) continue; /* unchanged row: K not written (no dirty line) */
        for (int k = 0; k < 3; k++) K[k] += dq[k];
        q = put_varint(q, (uint64_t)((int64_t)i - prev - 1));
        prev = i;
        for (int k = 0; k < 3; k++)
            q = put_varint(q, ((uint64_t)dq[k] << 1) ^ (uint64_t)(dq[k] >> 63));
        sent++;
    }
    uint32_t rows_bytes = (uint32_t)(q - (o + QDISP_HEADER));
    if (prog) { /* the progress trailer (4.40): the iterate's status .. elapsed_ms, as sent */
        memcpy(q, prog, PROGRESS_HEADER);
        q += PROGRESS_HEADER;
    }
    size_t len = (size_t)(q - out);
    memcpy(out, h, DF_FRAME_HEADER_SIZE); /* same flags and request id */
    df_le16_store(out + 6, DF_MSG_QDISP);
    df_le32_store(out + 20, (uint32_t)(len - DF_FRAME_HEADER_SIZE));
    memcpy(o, p, 24);                     /* session_id, version, base_version */
    o[24] = p[24];                        /* kind */
    o[25] = prog ? 1 : 0;                 /* flags: bit 0 the progress trailer */
    df_le16_store(o + 26, 0);
    df_le32_store(o + 28, nv);
    df_le32_store(o + 32, sent);
    df_le32_store(o + 36, rows_bytes);
    uint64_t step;
    memcpy(&step, &g->step, 8);
    df_le64_store(o + 40, step);
    b->len = len;
    return b;
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

df_sbuf *df_stream_enc_get(df_session *s, uint8_t enc, double e, df_sbuf *frame,
                           df_enc_variants *vs)
{
    enc &= DF_STREAM_ENC_ALL;
    if (!enc) return df_sbuf_ref(frame);
    df_enc_variant *v = build(s, frame, vs, enc, enc & DF_STREAM_ENC_QUANTIZED ? e : 0);
    return v ? df_sbuf_ref(v->frame) : NULL;
}

df_sbuf *df_stream_enc_frame(df_session *s, const df_conn *c, df_sbuf *frame, df_enc_variants *vs)
{
    return df_stream_enc_get(s, c->stream_enc, c->stream_err, frame, vs);
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
