/* msg_load.c — load mesh request body (messages.h).
 * u8 source, u8 format, u16 flags, u64 total_size, u64 part2_offset, u64 offset,
 * str name, str path (u16 length <= DF_MAX_PATH_LEN), u32 data_len, data bytes */
#include <stdlib.h>
#include <string.h>

#include "proto/codec_util.h"
#include "proto/messages.h"

static int load_check(const df_msg_load_mesh *m, df_error *err)
{
    const char *M = "load_mesh";
    if (m->format > DF_FMT_MAX)
        return df_error_set(err, DF_EINVAL, "%s: format %u not in 0..%u", M, m->format,
                            DF_FMT_MAX);
    if (m->flags & ~DF_LOAD_FLAGS_ALL)
        return df_error_set(err, DF_EINVAL, "%s: flags 0x%x has unknown bits (only 0x%x)", M,
                            m->flags, DF_LOAD_FLAGS_ALL);
    int rc = df_check_str(m->name, DF_MAX_NAME_LEN, M, "name", err);
    if (rc)
        return rc;
    if (m->source == DF_LOAD_PATH) {
        size_t len = m->path ? strnlen(m->path, DF_MAX_PATH_LEN + 1) : 0;
        if (len == 0 || len > DF_MAX_PATH_LEN)
            return df_error_set(err, len ? DF_ELIMIT : DF_EINVAL,
                                "%s: path length %zu not in 1..%u", M, len, DF_MAX_PATH_LEN);
        if (m->total_size || m->part2_offset || m->offset || m->data_len)
            return df_error_set(err, DF_EINVAL,
                                "%s: a path load must have total_size, part2_offset, offset and "
                                "data_len 0", M);
        return DF_OK;
    }
    if (m->source != DF_LOAD_INLINE)
        return df_error_set(err, DF_EINVAL, "%s: source %u not 0 (inline) or 1 (path)", M,
                            m->source);
    if (m->path && m->path[0])
        return df_error_set(err, DF_EINVAL, "%s: inline load must not carry a path", M);
    if (m->total_size < 1 || m->total_size > DF_MAX_MESH_BYTES)
        return df_error_set(err, DF_ELIMIT, "%s: total_size %llu not in 1..%llu", M,
                            (unsigned long long)m->total_size, (unsigned long long)DF_MAX_MESH_BYTES);
    if (m->data_len < 1 || m->offset > m->total_size || m->data_len > m->total_size - m->offset)
        return df_error_set(err, DF_EINVAL,
                            "%s: chunk [%llu, +%u) not a non-empty range inside total_size %llu", M,
                            (unsigned long long)m->offset, m->data_len,
                            (unsigned long long)m->total_size);
    if (m->data_len && !m->data)
        return df_error_set(err, DF_EINVAL, "%s: data is NULL with data_len %u", M, m->data_len);
    if (m->format == DF_FMT_TETGEN) {
        if (m->part2_offset == 0 || m->part2_offset >= m->total_size)
            return df_error_set(err, DF_EINVAL,
                                "%s: tetgen part2_offset %llu not in 1..total_size-1 (%llu)", M,
                                (unsigned long long)m->part2_offset,
                                (unsigned long long)m->total_size - 1);
    } else if (m->part2_offset) {
        return df_error_set(err, DF_EINVAL, "%s: part2_offset %llu set for a one-file format", M,
                            (unsigned long long)m->part2_offset);
    }
    return DF_OK;
}

int df_msg_load_mesh_encode(const df_msg_load_mesh *m, df_buf *out, df_error *err)
{
    int rc = load_check(m, err);
    size_t size = 28 + df_str_size(m->name) + df_str_size(m->path) + 4 + (size_t)m->data_len;
    if (rc || (rc = df_enc_reserve(out, size, "load_mesh", err)))
        return rc;
    df_buf_put_u8(out, m->source);
    df_buf_put_u8(out, m->format);
    df_buf_put_u16(out, m->flags);
    df_buf_put_u64(out, m->total_size);
    df_buf_put_u64(out, m->part2_offset);
    df_buf_put_u64(out, m->offset);
    df_put_str(out, m->name);
    df_put_str(out, m->source == DF_LOAD_PATH ? m->path : NULL);
    df_buf_put_u32(out, m->data_len);
    df_buf_put_bytes(out, m->data, m->data_len);
    return DF_OK;
}

int df_msg_load_mesh_decode(const uint8_t *p, size_t n, df_msg_load_mesh *m, df_error *err)
{
    df_rd r;
    df_msg_load_mesh t;
    df_rd_init(&r, p, n, "load_mesh", err);
    t.source = df_rd_u8(&r, "source");
    t.format = df_rd_u8(&r, "format");
    t.flags = df_rd_u16(&r, "flags");
    t.total_size = df_rd_u64(&r, "total_size");
    t.part2_offset = df_rd_u64(&r, "part2_offset");
    t.offset = df_rd_u64(&r, "offset");
    df_rd_str(&r, t.name, DF_MAX_NAME_LEN, "name");
    df_rd_str_alloc(&r, &t.path, DF_MAX_PATH_LEN, "path");
    t.data_len = df_rd_u32(&r, "data_len");
    t.data = df_rd_bytes(&r, t.data_len, "data");
    int rc = df_rd_end(&r);
    if (rc || (rc = load_check(&t, err))) {
        free(t.path);
        return rc;
    }
    if (t.data_len == 0)
        t.data = NULL;
    *m = t;
    return DF_OK;
}

void df_msg_load_mesh_free(df_msg_load_mesh *m)
{
    if (!m)
        return;
    free(m->path);
    m->path = NULL;
}
