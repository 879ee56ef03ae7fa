/* buf.c — growable byte buffer and little-endian scalar codecs (see buf.h). */
#include "proto/buf.h"

#include <stdlib.h>
#include <string.h>

void df_buf_init(df_buf *b)
{
    b->data = NULL;
    b->len = 0;
    b->cap = 0;
}

void df_buf_free(df_buf *b)
{
    if (!b)
        return;
    free(b->data);
    df_buf_init(b);
}

void df_buf_reset(df_buf *b)
{
    b->len = 0;
}

int df_buf_reserve(df_buf *b, size_t extra, df_error *err)
{
    if (extra > SIZE_MAX - b->len)
        return df_error_set(err, DF_ELIMIT, "buffer size overflow (%zu + %zu bytes)", b->len, extra);
    size_t need = b->len + extra;
    if (need <= b->cap)
        return DF_OK;
    size_t cap = b->cap ? b->cap : 256;
    while (cap < need)
        cap = cap > SIZE_MAX / 2 ? need : cap * 2;
    uint8_t *d = realloc(b->data, cap);
    if (!d)
        return df_error_set(err, DF_ENOMEM, "out of memory growing a buffer to %zu bytes", cap);
    b->data = d;
    b->cap = cap;
    return DF_OK;
}

int df_buf_append(df_buf *b, const void *p, size_t n, df_error *err)
{
    int rc = df_buf_reserve(b, n, err);
    if (rc)
        return rc;
    df_buf_put_bytes(b, p, n);
    return DF_OK;
}

void df_buf_put_bytes(df_buf *b, const void *p, size_t n)
{
    if (n)
        memcpy(b->data + b->len, p, n);
    b->len += n;
}

void df_buf_put_u8(df_buf *b, uint8_t v)
{
    b->data[b->len++] = v;
}

void df_buf_put_u16(df_buf *b, uint16_t v)
{
    df_le16_store(b->data + b->len, v);
    b->len += 2;
}

void df_buf_put_u32(df_buf *b, uint32_t v)
{
    df_le32_store(b->data + b->len, v);
    b->len += 4;
}

void df_buf_put_u64(df_buf *b, uint64_t v)
{
    df_le64_store(b->data + b->len, v);
    b->len += 8;
}

void df_buf_put_i32(df_buf *b, int32_t v)
{
    df_buf_put_u32(b, (uint32_t)v);
}

void df_buf_put_f32(df_buf *b, float v)
{
    uint32_t u;
    memcpy(&u, &v, 4);
    df_buf_put_u32(b, u);
}

void df_buf_put_f64(df_buf *b, double v)
{
    uint64_t u;
    memcpy(&u, &v, 8);
    df_buf_put_u64(b, u);
}

uint16_t df_le16_load(const uint8_t *p)
{
    return (uint16_t)(p[0] | (uint16_t)p[1] << 8);
}

uint32_t df_le32_load(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

uint64_t df_le64_load(const uint8_t *p)
{
    return (uint64_t)df_le32_load(p) | (uint64_t)df_le32_load(p + 4) << 32;
}

void df_le16_store(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}

void df_le32_store(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}

void df_le64_store(uint8_t *p, uint64_t v)
{
    df_le32_store(p, (uint32_t)v);
    df_le32_store(p + 4, (uint32_t)(v >> 32));
}
