/* codec_util.c — bounds-checked payload reading and shared encoder helpers (codec_util.h). */
#include "proto/codec_util.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "proto/wire_error.h"

void df_rd_init(df_rd *r, const uint8_t *p, size_t n, const char *msg, df_error *err)
{
    static const uint8_t none[1] = {0};
    r->p = p ? p : none; /* never do arithmetic on a NULL payload */
    r->n = p ? n : 0;
    r->off = 0;
    r->msg = msg;
    r->err = err;
    r->rc = DF_OK;
}

int df_rd_fail(df_rd *r, int code, const char *field, const char *fmt, ...)
{
    if (r->rc)
        return r->rc;
    r->rc = code;
    if (r->err) {
        char detail[192];
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(detail, sizeof detail, fmt, ap);
        va_end(ap);
        df_error_set(r->err, code, "%s: %s: %s", r->msg, field, detail);
    }
    return code;
}

int df_rd_need(df_rd *r, size_t k, const char *field)
{
    if (r->rc)
        return 0;
    if (r->n - r->off < k) {
        df_rd_fail(r, DF_EPROTO_TRUNCATED, field, "truncated at byte %zu (need %zu, %zu left)",
                   r->off, k, r->n - r->off);
        return 0;
    }
    return 1;
}

int df_rd_need_rows(df_rd *r, uint64_t count, size_t row_bytes, const char *field)
{
    if (r->rc)
        return 0;
    uint64_t left = r->n - r->off;
    if (row_bytes && count > left / row_bytes) {
        df_rd_fail(r, DF_EPROTO_TRUNCATED, field,
                   "count %llu needs %llu bytes but only %llu remain",
                   (unsigned long long)count, (unsigned long long)count * row_bytes,
                   (unsigned long long)left);
        return 0;
    }
    return 1;
}

uint8_t df_rd_u8(df_rd *r, const char *field)
{
    if (!df_rd_need(r, 1, field))
        return 0;
    return r->p[r->off++];
}

uint16_t df_rd_u16(df_rd *r, const char *field)
{
    if (!df_rd_need(r, 2, field))
        return 0;
    uint16_t v = df_le16_load(r->p + r->off);
    r->off += 2;
    return v;
}

uint32_t df_rd_u32(df_rd *r, const char *field)
{
    if (!df_rd_need(r, 4, field))
        return 0;
    uint32_t v = df_le32_load(r->p + r->off);
    r->off += 4;
    return v;
}

uint64_t df_rd_u64(df_rd *r, const char *field)
{
    if (!df_rd_need(r, 8, field))
        return 0;
    uint64_t v = df_le64_load(r->p + r->off);
    r->off += 8;
    return v;
}

float df_rd_f32(df_rd *r, const char *field)
{
    uint32_t u = df_rd_u32(r, field);
    float f;
    memcpy(&f, &u, 4);
    return f;
}

double df_rd_f64(df_rd *r, const char *field)
{
    uint64_t u = df_rd_u64(r, field);
    double d;
    memcpy(&d, &u, 8);
    return d;
}

void df_rd_reserved16(df_rd *r, const char *field)
{
    uint16_t v = df_rd_u16(r, field);
    if (v)
        df_rd_fail(r, DF_EPROTO_RESERVED, field, "reserved field is %u, must be 0", v);
}

void df_rd_reserved8(df_rd *r, const char *field)
{
    uint8_t v = df_rd_u8(r, field);
    if (v)
        df_rd_fail(r, DF_EPROTO_RESERVED, field, "reserved field is %u, must be 0", v);
}

static size_t read_str_len(df_rd *r, size_t max, const char *field)
{
    uint16_t len = df_rd_u16(r, field);
    if (r->rc)
        return 0;
    if (len > max) {
        df_rd_fail(r, DF_ELIMIT, field, "string of %u bytes exceeds limit %zu", len, max);
        return 0;
    }
    if (!df_rd_need(r, len, field))
        return 0;
    if (memchr(r->p + r->off, 0, len)) {
        df_rd_fail(r, DF_EINVAL, field, "string contains a NUL byte");
        return 0;
    }
    return len;
}

void df_rd_str(df_rd *r, char *dst, size_t max, const char *field)
{
    size_t len = read_str_len(r, max, field);
    if (r->rc) {
        dst[0] = '\0';
        return;
    }
    memcpy(dst, r->p + r->off, len);
    dst[len] = '\0';
    r->off += len;
}

void df_rd_str_alloc(df_rd *r, char **dst, size_t max, const char *field)
{
    *dst = NULL;
    size_t len = read_str_len(r, max, field);
    if (r->rc || len == 0)
        return;
    char *s = malloc(len + 1);
    if (!s) {
        df_rd_fail(r, DF_ENOMEM, field, "out of memory for %zu bytes", len + 1);
        return;
    }
    memcpy(s, r->p + r->off, len);
    s[len] = '\0';
    r->off += len;
    *dst = s;
}

const uint8_t *df_rd_bytes(df_rd *r, size_t k, const char *field)
{
    if (!df_rd_need(r, k, field))
        return NULL;
    const uint8_t *q = r->p + r->off;
    r->off += k;
    return q;
}

int df_rd_end(df_rd *r)
{
    if (!r->rc && r->off != r->n)
        df_rd_fail(r, DF_EPROTO_TRAILING, "end", "%zu trailing bytes after %zu-byte body",
                   r->n - r->off, r->off);
    return r->rc;
}

void *df_rd_alloc(df_rd *r, size_t count, size_t size, const char *field)
{
    if (r->rc || count == 0)
        return NULL;
    if (size && count > SIZE_MAX / size) {
        df_rd_fail(r, DF_ELIMIT, field, "array of %zu x %zu bytes overflows", count, size);
        return NULL;
    }
    void *q = malloc(count * size);
    if (!q)
        df_rd_fail(r, DF_ENOMEM, field, "out of memory for %zu bytes", count * size);
    return q;
}

void df_rd_indices(df_rd *r, int32_t **dst, uint32_t count, uint32_t bound, const char *field)
{
    *dst = NULL;
    if (!df_rd_need_rows(r, count, 4, field))
        return;
    int32_t *a = df_rd_alloc(r, count, sizeof *a, field);
    if (r->rc)
        return;
    for (uint32_t i = 0; i < count; i++) {
        uint32_t v = df_le32_load(r->p + r->off + 4 * (size_t)i);
        if (v >= bound) {
            df_rd_fail(r, DF_EINVAL, field, "index %u at position %u out of range (bound %u)", v,
                       i, bound);
            free(a);
            return;
        }
        a[i] = (int32_t)v;
    }
    r->off += 4 * (size_t)count;
    *dst = a;
}

size_t df_str_size(const char *s)
{
    return 2 + (s ? strlen(s) : 0);
}

void df_put_str(df_buf *b, const char *s)
{
    size_t len = s ? strlen(s) : 0;
    df_buf_put_u16(b, (uint16_t)len);
    df_buf_put_bytes(b, s, len);
}

int df_check_finite(const double *v, size_t n, const char *msg, const char *field, df_error *err)
{
    for (size_t i = 0; i < n; i++)
        if (!isfinite(v[i]))
            return df_error_set(err, DF_EINVAL, "%s: %s: component %zu is %g (must be finite)",
                                msg, field, i, v[i]);
    return DF_OK;
}

int df_check_str(const char *s, size_t max, const char *msg, const char *field, df_error *err)
{
    size_t len = s ? strnlen(s, max + 1) : 0;
    if (len > max)
        return df_error_set(err, DF_ELIMIT, "%s: %s: string longer than %zu bytes", msg, field,
                            max);
    return DF_OK;
}

int df_enc_reserve(df_buf *out, size_t size, const char *msg, df_error *err)
{
    int rc = df_buf_reserve(out, size, err);
    if (rc && err)
        df_error_set(err, rc, "%s: cannot reserve %zu bytes", msg, size);
    return rc;
}

int df_list_encode(const df_list_codec *c, uint32_t count, const void *items, df_buf *out,
                   df_error *err)
{
    if (count > c->limit)
        return df_error_set(err, DF_ELIMIT, "%s: %u %s exceed limit %u", c->msg, count, c->noun,
                            c->limit);
    if (count && !items)
        return df_error_set(err, DF_EINVAL, "%s: items is NULL with count %u", c->msg, count);
    const char *it = items;
    size_t size = 4;
    for (uint32_t i = 0; i < count; i++) {
        int rc = c->check(it + i * c->item_size, i, err);
        if (rc)
            return rc;
        size += c->size(it + i * c->item_size);
    }
    int rc = df_enc_reserve(out, size, c->msg, err);
    if (rc)
        return rc;
    df_buf_put_u32(out, count);
    for (uint32_t i = 0; i < count; i++)
        c->put(out, it + i * c->item_size);
    return DF_OK;
}

int df_list_decode(const df_list_codec *c, const uint8_t *p, size_t n, uint32_t *count,
                   void **items, df_error *err)
{
    df_rd r;
    df_rd_init(&r, p, n, c->msg, err);
    uint32_t k = df_rd_u32(&r, "count");
    if (!r.rc && k > c->limit)
        df_rd_fail(&r, DF_ELIMIT, "count", "%u %s exceed limit %u", k, c->noun, c->limit);
    df_rd_need_rows(&r, k, c->min_row, "count");
    char *a = df_rd_alloc(&r, k, c->item_size, "items");
    for (uint32_t i = 0; i < k && !r.rc; i++) {
        c->get(&r, a + i * c->item_size);
        if (!r.rc)
            r.rc = c->check(a + i * c->item_size, i, err);
    }
    int rc = df_rd_end(&r);
    if (rc) {
        free(a);
        return rc;
    }
    *count = k;
    *items = a;
    return DF_OK;
}
