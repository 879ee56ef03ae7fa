/* msg_load.c — load mesh request and reply bodies (messages.h).
 * load_mesh: u8 source, u8 format, u16 options (DF_LOAD_OPT_EXT | DF_LOAD_OPT_2D),
 *            u64 total_size, u64 part2_offset, u64 offset,
 *            str name, str path (u16 length <= DF_MAX_PATH_LEN), u32 data_len, data bytes,
 *            [options & DF_LOAD_OPT_EXT: str file_name]
 * load_reply: session_info [+ load_report: u8 format, u8 index_base, u16 reserved,
 *            11 x u32 counts (48 bytes)] */
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
    if (m->options & ~DF_LOAD_OPTS_ALL)
        return df_error_set(err, DF_EPROTO_RESERVED,
                            "%s: options 0x%x has unknown bits 0x%x (known: 0x1 EXT, 0x2 2D)", M,
                            (unsigned)m->options, (unsigned)(m->options & ~DF_LOAD_OPTS_ALL));
    int rc = df_check_str(m->name, DF_MAX_NAME_LEN, M, "name", err);
    if (!rc)
        rc = df_check_str(m->file_name, DF_MAX_NAME_LEN, M, "file_name", err);
    if (rc)
        return rc;
    if (m->file_name[0] && !(m->options & DF_LOAD_OPT_EXT))
        return df_error_set(err, DF_EINVAL, "%s: file_name needs the EXT option", M);
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
    int ext = (m->options & DF_LOAD_OPT_EXT) != 0;
    size_t size = 28 + df_str_size(m->name) + df_str_size(m->path) + 4 + (size_t)m->data_len +
                  (ext ? df_str_size(m->file_name) : 0);
    if (rc || (rc = df_enc_reserve(out, size, "load_mesh", err)))
        return rc;
    df_buf_put_u8(out, m->source);
    df_buf_put_u8(out, m->format);
    df_buf_put_u16(out, m->options);
    df_buf_put_u64(out, m->total_size);
    df_buf_put_u64(out, m->part2_offset);
    df_buf_put_u64(out, m->offset);
    df_put_str(out, m->name);
    df_put_str(out, m->source == DF_LOAD_PATH ? m->path : NULL);
    df_buf_put_u32(out, m->data_len);
    df_buf_put_bytes(out, m->data, m->data_len);
    if (ext)
        df_put_str(out, m->file_name);
    return DF_OK;
}

int df_msg_load_mesh_decode(const uint8_t *p, size_t n, df_msg_load_mesh *m, df_error *err)
{
    df_rd r;
    df_msg_load_mesh t;
    df_rd_init(&r, p, n, "load_mesh", err);
    t.source = df_rd_u8(&r, "source");
    t.format = df_rd_u8(&r, "format");
    t.options = df_rd_u16(&r, "options");
    t.file_name[0] = '\0';
    if (r.rc == DF_OK && (t.options & ~DF_LOAD_OPTS_ALL))
        return df_error_set(err, DF_EPROTO_RESERVED,
                            "load_mesh: options 0x%x has unknown bits 0x%x (known: 0x1 EXT, 0x2 2D)",
                            (unsigned)t.options, (unsigned)(t.options & ~DF_LOAD_OPTS_ALL));
    t.total_size = df_rd_u64(&r, "total_size");
    t.part2_offset = df_rd_u64(&r, "part2_offset");
    t.offset = df_rd_u64(&r, "offset");
    df_rd_str(&r, t.name, DF_MAX_NAME_LEN, "name");
    df_rd_str_alloc(&r, &t.path, DF_MAX_PATH_LEN, "path");
    t.data_len = df_rd_u32(&r, "data_len");
    t.data = df_rd_bytes(&r, t.data_len, "data");
    if (t.options & DF_LOAD_OPT_EXT)
        df_rd_str(&r, t.file_name, DF_MAX_NAME_LEN, "file_name");
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

/* ---- load_reply: session_info [+ 48-byte load_report] */
#define REPORT_SIZE 48u

static int report_check(const df_msg_load_report *r, df_error *err)
{
    if (r->format < 1 || r->format > DF_FMT_MAX)
        return df_error_set(err, DF_EINVAL, "load_reply: format %u not in 1..%u", r->format,
                            DF_FMT_MAX);
    if (r->index_base > 1)
        return df_error_set(err, DF_EINVAL, "load_reply: index_base %u not 0/1", r->index_base);
    return DF_OK;
}

int df_msg_load_reply_encode(const df_msg_load_reply *m, df_buf *out, df_error *err)
{
    int rc = m->has_report ? report_check(&m->report, err) : DF_OK;
    size_t before = out->len;
    if (rc || (rc = df_msg_session_info_encode(&m->info, out, err)))
        return rc;
    if (!m->has_report)
        return DF_OK;
    if ((rc = df_enc_reserve(out, REPORT_SIZE, "load_reply", err))) {
        out->len = before;
        return rc;
    }
    const df_msg_load_report *r = &m->report;
    df_buf_put_u8(out, r->format);
    df_buf_put_u8(out, r->index_base);
    df_buf_put_u16(out, 0);
    const uint32_t v[11] = {r->input_polygons, r->polygons_triangulated, r->dropped_elements,
                            r->duplicate_elements, r->degenerate_elements, r->inverted_elements,
                            r->nonmanifold_edges, r->nonmanifold_faces, r->boundary_edges,
                            r->boundary_faces, r->unused_vertices};
    for (int i = 0; i < 11; i++)
        df_buf_put_u32(out, v[i]);
    return DF_OK;
}

int df_msg_load_reply_decode(const uint8_t *p, size_t n, df_msg_load_reply *m, df_error *err)
{
    df_msg_load_reply t;
    memset(&t, 0, sizeof t);
    size_t info_len = n; /* session_info is 36 bytes + u16 name length + name */
    if (n >= 38) {
        size_t l = 38 + (size_t)(p[36] | (p[37] << 8));
        if (l < n)
            info_len = l;
    }
    int rc = df_msg_session_info_decode(p, info_len, &t.info, err);
    if (rc || info_len == n) {
        if (!rc)
            *m = t;
        return rc;
    }
    df_rd r;
    df_rd_init(&r, p + info_len, n - info_len, "load_reply", err);
    t.has_report = 1;
    t.report.format = df_rd_u8(&r, "format");
    t.report.index_base = df_rd_u8(&r, "index_base");
    df_rd_reserved16(&r, "reserved");
    uint32_t *v[11] = {&t.report.input_polygons, &t.report.polygons_triangulated,
                       &t.report.dropped_elements, &t.report.duplicate_elements,
                       &t.report.degenerate_elements, &t.report.inverted_elements,
                       &t.report.nonmanifold_edges, &t.report.nonmanifold_faces,
                       &t.report.boundary_edges, &t.report.boundary_faces,
                       &t.report.unused_vertices};
    static const char *names[11] = {"input_polygons", "polygons_triangulated",
                                    "dropped_elements", "duplicate_elements",
                                    "degenerate_elements", "inverted_elements",
                                    "nonmanifold_edges", "nonmanifold_faces", "boundary_edges",
                                    "boundary_faces", "unused_vertices"};
    for (int i = 0; i < 11; i++)
        *v[i] = df_rd_u32(&r, names[i]);
    rc = df_rd_end(&r);
    if (rc || (rc = report_check(&t.report, err)))
        return rc;
    *m = t;
    return DF_OK;
}
