/* delta.c — the packed / raw position delta codec (see delta.h). Moved here from
 * server/store/codec.c unchanged, so the undo history (session/) and the store share it. */
#include "server/session/delta.h"
#include "server/session/blob_io.h"

#include <stdlib.h>
#include <string.h>
#include <zstd.h>

/* ---- delta ---- */
/* The raw (v1) layout's size for `count` changed vertices of nv. */
static size_t raw_size(uint32_t count, int32_t nv)
{
    return 8 + (count == (uint32_t)nv ? 0 : 4 * (size_t)count) + 24 * (size_t)count;
}

static int count_changed(const double *old, const double *now, int32_t nv)
{
    uint32_t count = 0;
    for (int32_t i = 0; i < nv; i++)
        if (memcmp(old + 3 * (size_t)i, now + 3 * (size_t)i, 3 * sizeof(double)) != 0) count++;
    return (int)count;
}

static int encode_raw(const double *old, const double *now, int32_t nv, uint32_t count,
                      uint8_t **out, size_t *len, df_error *err)
{
    int dense = count == (uint32_t)nv;
    size_t n = raw_size(count, nv);
    df_wbuf w = {malloc(n ? n : 1), 0};
    if (!w.p) return df_error_set(err, DF_ENOMEM, "store: out of memory encoding a change");
    df_wput(&w, &count, 4);
    df_wput_i32(&w, nv);
    if (!dense)
        for (int32_t i = 0; i < nv; i++)
            if (memcmp(old + 3 * (size_t)i, now + 3 * (size_t)i, 3 * sizeof(double)) != 0) {
                uint32_t u = (uint32_t)i;
                df_wput(&w, &u, 4);
            }
    for (int32_t i = 0; i < nv; i++)
        if (dense || memcmp(old + 3 * (size_t)i, now + 3 * (size_t)i, 3 * sizeof(double)) != 0)
            df_wput(&w, now + 3 * (size_t)i, 3 * sizeof(double));
    *out = w.p;
    *len = w.n;
    return DF_OK;
}

/* The packed (v2) payload of `count` changed vertices: gap-coded indices as 4 byte planes,
 * then the 3 * count XOR words as 8 byte planes (plane b holds byte b of every word). */
static uint8_t *packed_payload(const double *old, const double *now, int32_t nv, uint32_t count)
{
    size_t nw = 3 * (size_t)count, psize = 28 * (size_t)count;
    uint8_t *pl = malloc(psize ? psize : 1);
    if (!pl) return NULL;
    uint8_t *gaps = pl, *xw = pl + 4 * (size_t)count;
    size_t k = 0;
    int64_t prev = -1;
    for (int32_t i = 0; i < nv; i++) {
        const double *a = old + 3 * (size_t)i, *b = now + 3 * (size_t)i;
        if (memcmp(a, b, 3 * sizeof(double)) == 0) continue;
        uint32_t gap = (uint32_t)((int64_t)i - prev - 1);
        prev = i;
        for (int byte = 0; byte < 4; byte++)
            gaps[(size_t)byte * count + k] = (uint8_t)(gap >> (8 * byte));
        for (int c = 0; c < 3; c++) {
            uint64_t ua, ub;
            memcpy(&ua, a + c, 8);
            memcpy(&ub, b + c, 8);
            uint64_t x = ua ^ ub;
            size_t word = 3 * k + (size_t)c;
            for (int byte = 0; byte < 8; byte++)
                xw[(size_t)byte * nw + word] = (uint8_t)(x >> (8 * byte));
        }
        k++;
    }
    return pl;
}

int df_codec_delta_encode(const double *old, const double *now, int32_t nv, uint8_t **out,
                          size_t *len, df_error *err)
{
    uint32_t count = (uint32_t)count_changed(old, now, nv);
    size_t raw = raw_size(count, nv);
    if (count < DF_CODEC_PACK_MIN_VERTICES) return encode_raw(old, now, nv, count, out, len, err);
    size_t psize = 28 * (size_t)count, bound = ZSTD_compressBound(psize);
    uint8_t *pl = packed_payload(old, now, nv, count);
    uint8_t *blob = malloc(DF_CODEC_PACKED_HEADER + bound);
    ZSTD_CCtx *cx = ZSTD_createCCtx();
    if (!pl || !blob || !cx) {
        free(pl);
        free(blob);
        ZSTD_freeCCtx(cx);
        return df_error_set(err, DF_ENOMEM, "store: out of memory encoding a change");
    }
    size_t z = ZSTD_CCtx_setParameter(cx, ZSTD_c_compressionLevel, DF_CODEC_ZSTD_LEVEL);
    if (!ZSTD_isError(z)) z = ZSTD_CCtx_setParameter(cx, ZSTD_c_checksumFlag, 1);
    if (!ZSTD_isError(z))
        z = ZSTD_compress2(cx, blob + DF_CODEC_PACKED_HEADER, bound, pl, psize);
    ZSTD_freeCCtx(cx);
    free(pl);
    if (ZSTD_isError(z)) {
        free(blob);
        return df_error_set(err, DF_EINTERNAL, "store: compressing a change: %s",
                            ZSTD_getErrorName(z));
    }
    if (DF_CODEC_PACKED_HEADER + z >= raw) { /* no gain: the raw layout */
        free(blob);
        return encode_raw(old, now, nv, count, out, len, err);
    }
    uint32_t marker = DF_CODEC_PACKED_MARKER;
    memcpy(blob, &marker, 4);
    memcpy(blob + 4, &nv, 4);
    memcpy(blob + 8, &count, 4);
    *out = blob;
    *len = DF_CODEC_PACKED_HEADER + z;
    return DF_OK;
}

/* Applies a packed (v2) blob: decompressed and checked in full before `pos` is written. */
static int apply_packed(const uint8_t *b, size_t len, double *pos, int32_t nv,
                        uint32_t *changed, df_error *err)
{
    uint32_t count;
    int32_t bnv;
    if (len < DF_CODEC_PACKED_HEADER)
        return df_error_set(err, DF_EFORMAT, "store: compressed change delta of %zu bytes is "
                            "truncated", len);
    memcpy(&bnv, b + 4, 4);
    memcpy(&count, b + 8, 4);
    if (bnv != nv || count > (uint32_t)nv || count == 0)
        return df_error_set(err, DF_EFORMAT, "store: compressed change delta of %d vertices "
                            "(count %u) on a %d-vertex session", bnv, count, nv);
    const uint8_t *zb = b + DF_CODEC_PACKED_HEADER;
    size_t zlen = len - DF_CODEC_PACKED_HEADER, psize = 28 * (size_t)count;
    unsigned long long csize = ZSTD_getFrameContentSize(zb, zlen);
    if (csize != (unsigned long long)psize)
        return df_error_set(err, DF_EFORMAT, "store: compressed change delta is corrupt (frame "
                            "content size %llu, %zu expected)", csize, psize);
    uint8_t *pl = malloc(psize);
    if (!pl) return df_error_set(err, DF_ENOMEM, "store: out of memory reading a change");
    size_t z = ZSTD_decompress(pl, psize, zb, zlen);
    if (ZSTD_isError(z) || z != psize) {
        free(pl);
        return df_error_set(err, DF_EFORMAT, "store: compressed change delta is corrupt (%s)",
                            ZSTD_isError(z) ? ZSTD_getErrorName(z) : "short payload");
    }
    const uint8_t *gaps = pl, *xw = pl + 4 * (size_t)count;
    size_t nw = 3 * (size_t)count;
    int64_t at = -1;
    for (uint32_t k = 0; k < count; k++) { /* every index first: nothing written on error */
        uint32_t gap = 0;
        for (int byte = 0; byte < 4; byte++)
            gap |= (uint32_t)gaps[(size_t)byte * count + k] << (8 * byte);
        at += (int64_t)gap + 1;
        if (at >= nv) {
            free(pl);
            return df_error_set(err, DF_EFORMAT, "store: compressed change delta index %lld "
                                "out of range (nv %d)", (long long)at, nv);
        }
    }
    at = -1;
    for (uint32_t k = 0; k < count; k++) {
        uint32_t gap = 0;
        for (int byte = 0; byte < 4; byte++)
            gap |= (uint32_t)gaps[(size_t)byte * count + k] << (8 * byte);
        at += (int64_t)gap + 1;
        for (int c = 0; c < 3; c++) {
            size_t word = 3 * (size_t)k + (size_t)c;
            uint64_t x = 0, u;
            for (int byte = 0; byte < 8; byte++)
                x |= (uint64_t)xw[(size_t)byte * nw + word] << (8 * byte);
            double *d = pos + 3 * (size_t)at + c;
            memcpy(&u, d, 8);
            u ^= x;
            memcpy(d, &u, 8);
        }
    }
    free(pl);
    if (changed) *changed = count;
    return DF_OK;
}

int df_codec_delta_apply(const uint8_t *b, size_t len, double *pos, int32_t nv,
                         uint32_t *changed, df_error *err)
{
    df_rbuf r = {b, len, 0, 0};
    uint32_t count;
    df_rget(&r, &count, 4);
    if (!r.bad && count == DF_CODEC_PACKED_MARKER)
        return apply_packed(b, len, pos, nv, changed, err);
    int32_t bnv = df_rget_i32(&r);
    if (r.bad || bnv != nv || count > (uint32_t)nv)
        return df_error_set(err, DF_EFORMAT, "store: change delta of %d vertices (count %u) on "
                            "a %d-vertex session", bnv, count, nv);
    int dense = count == (uint32_t)nv;
    size_t need = raw_size(count, nv);
    if (len != need)
        return df_error_set(err, DF_EFORMAT, "store: change delta of %zu bytes, %zu expected",
                            len, need);
    const uint8_t *idx = b + 8, *vals = b + 8 + (dense ? 0 : 4 * (size_t)count);
    int64_t prev = -1;
    for (uint32_t k = 0; k < count; k++) {
        uint32_t i = k;
        if (!dense) {
            memcpy(&i, idx + 4 * (size_t)k, 4);
            if (i >= (uint32_t)nv || (int64_t)i <= prev)
                return df_error_set(err, DF_EFORMAT, "store: change delta index %u bad "
                                    "(nv %d, previous %lld)", i, nv, (long long)prev);
            prev = i;
        }
    }
    for (uint32_t k = 0; k < count; k++) {
        uint32_t i = k;
        if (!dense) memcpy(&i, idx + 4 * (size_t)k, 4);
        memcpy(pos + 3 * (size_t)i, vals + 24 * (size_t)k, 24);
    }
    if (changed) *changed = count;
    return DF_OK;
}
