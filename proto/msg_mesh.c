/* msg_mesh.c — get-mesh reply chunk body (messages.h).
 * u64 session_id, u64 version, u8 kind, u8 planar, u8 section, u8 reserved, u32 nv, u32 ne,
 * u32 nf, u32 offset, u32 count (40 bytes), then count rows:
 *   POSITIONS / BASE / REST: f32 x, y, z;  ELEMENTS: elem_size x u32;  FACES: 3 x u32 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/mesh/mesh.h"
#include "proto/codec_util.h"
#include "proto/messages.h"

#define CHUNK_HEADER 40u

static int is_xyz(uint8_t section)
{
    return section == DF_SECTION_POSITIONS || section == DF_SECTION_BASE ||
           section == DF_SECTION_REST;
}

/* Indices per row of an index section (0 for xyz sections). */
static unsigned idx_per_row(const df_msg_mesh_chunk *m)
{
    if (m->section == DF_SECTION_ELEMENTS)
        return (unsigned)df_mesh_elem_size((df_mesh_kind)m->kind);
    return m->section == DF_SECTION_FACES ? 3u : 0u;
}

static uint32_t section_rows(const df_msg_mesh_chunk *m)
{
    return is_xyz(m->section) ? m->nv : m->section == DF_SECTION_ELEMENTS ? m->ne : m->nf;
}

static int head_check(const df_msg_mesh_chunk *m, df_error *err)
{
    const char *M = "mesh_chunk";
    if (m->session_id == 0)
        return df_error_set(err, DF_EINVAL, "%s: session_id 0 is not a session", M);
    if (m->kind < 1 || m->kind > 3)
        return df_error_set(err, DF_EINVAL, "%s: mesh kind %u not in 1..3", M, m->kind);
    if (m->planar > 1)
        return df_error_set(err, DF_EINVAL, "%s: planar %u not 0/1", M, m->planar);
    if (m->section < 1 || m->section > DF_SECTION_MAX)
        return df_error_set(err, DF_EINVAL, "%s: section %u not in 1..%u", M, m->section,
                            DF_SECTION_MAX);
    if (m->nv < 1 || m->nv > DF_MAX_MESH_VERTICES || m->ne > DF_MAX_MESH_ELEMENTS ||
        m->nf > DF_MAX_MESH_ELEMENTS)
        return df_error_set(err, DF_ELIMIT, "%s: counts nv %u, ne %u, nf %u outside limits "
                            "(nv 1..%u, ne/nf <= %u)", M, m->nv, m->ne, m->nf,
                            DF_MAX_MESH_VERTICES, DF_MAX_MESH_ELEMENTS);
    if (m->nf && m->kind != DF_MESH_TET)
        return df_error_set(err, DF_EINVAL, "%s: nf %u boundary faces on a non-tet mesh", M,
                            m->nf);
    uint32_t rows = section_rows(m);
    if (m->offset > rows || m->count > rows - m->offset)
        return df_error_set(err, DF_EINVAL, "%s: chunk rows [%u, +%u) outside section of %u", M,
                            m->offset, m->count, rows);
    return DF_OK;
}

static int rows_check(const df_msg_mesh_chunk *m, df_error *err)
{
    const char *M = "mesh_chunk";
    if (is_xyz(m->section)) {
        if (m->count && !m->xyz)
            return df_error_set(err, DF_EINVAL, "%s: xyz is NULL with count %u", M, m->count);
        for (size_t i = 0; i < 3 * (size_t)m->count; i++)
            if (!isfinite(m->xyz[i]))
                return df_error_set(err, DF_EINVAL, "%s: vertex %zu component %zu is %g", M,
                                    i / 3 + m->offset, i % 3, (double)m->xyz[i]);
        return DF_OK;
    }
    size_t k = idx_per_row(m), n = k * (size_t)m->count;
    if (n && !m->idx)
        return df_error_set(err, DF_EINVAL, "%s: idx is NULL with count %u", M, m->count);
    for (size_t i = 0; i < n; i++)
        if (m->idx[i] < 0 || (uint32_t)m->idx[i] >= m->nv)
            return df_error_set(err, DF_EINVAL, "%s: row %zu index %d out of range (nv %u)", M,
                                i / k + m->offset, m->idx[i], m->nv);
    return DF_OK;
}

static size_t row_bytes(const df_msg_mesh_chunk *m)
{
    return is_xyz(m->section) ? 12 : 4 * (size_t)idx_per_row(m);
}

int df_msg_mesh_chunk_encode(const df_msg_mesh_chunk *m, df_buf *out, df_error *err)
{
    int rc = head_check(m, err);
    if (!rc)
        rc = rows_check(m, err);
    size_t size = CHUNK_HEADER + row_bytes(m) * (size_t)m->count;
    if (rc || (rc = df_enc_reserve(out, size, "mesh_chunk", err)))
        return rc;
    df_buf_put_u64(out, m->session_id);
    df_buf_put_u64(out, m->version);
    df_buf_put_u8(out, m->kind);
    df_buf_put_u8(out, m->planar);
    df_buf_put_u8(out, m->section);
    df_buf_put_u8(out, 0);
    df_buf_put_u32(out, m->nv);
    df_buf_put_u32(out, m->ne);
    df_buf_put_u32(out, m->nf);
    df_buf_put_u32(out, m->offset);
    df_buf_put_u32(out, m->count);
    if (is_xyz(m->section)) {
        for (size_t i = 0; i < 3 * (size_t)m->count; i++)
            df_buf_put_f32(out, m->xyz[i]);
    } else {
        for (size_t i = 0; i < idx_per_row(m) * (size_t)m->count; i++)
            df_buf_put_u32(out, (uint32_t)m->idx[i]);
    }
    return DF_OK;
}

int df_msg_mesh_chunk_decode(const uint8_t *p, size_t n, df_msg_mesh_chunk *m, df_error *err)
{
    df_rd r;
    df_msg_mesh_chunk t = {0};
    df_rd_init(&r, p, n, "mesh_chunk", err);
    t.session_id = df_rd_u64(&r, "session_id");
    t.version = df_rd_u64(&r, "version");
    t.kind = df_rd_u8(&r, "kind");
    t.planar = df_rd_u8(&r, "planar");
    t.section = df_rd_u8(&r, "section");
    df_rd_reserved8(&r, "reserved");
    t.nv = df_rd_u32(&r, "nv");
    t.ne = df_rd_u32(&r, "ne");
    t.nf = df_rd_u32(&r, "nf");
    t.offset = df_rd_u32(&r, "offset");
    t.count = df_rd_u32(&r, "count");
    if (!r.rc)
        r.rc = head_check(&t, err);
    if (!r.rc && df_rd_need_rows(&r, t.count, row_bytes(&t), "count")) {
        if (is_xyz(t.section)) {
            t.xyz = df_rd_alloc(&r, 3 * (size_t)t.count, sizeof(float), "xyz");
            for (size_t i = 0; !r.rc && i < 3 * (size_t)t.count; i++)
                t.xyz[i] = df_rd_f32(&r, "xyz");
        } else {
            size_t k = idx_per_row(&t) * (size_t)t.count;
            t.idx = df_rd_alloc(&r, k, sizeof(int32_t), "idx");
            for (size_t i = 0; !r.rc && i < k; i++) {
                uint32_t v = df_rd_u32(&r, "idx");
                t.idx[i] = v > INT32_MAX ? -1 : (int32_t)v;
            }
        }
        if (!r.rc)
            r.rc = rows_check(&t, err);
    }
    int rc = df_rd_end(&r);
    if (rc) {
        df_msg_mesh_chunk_free(&t);
        return rc;
    }
    *m = t;
    return DF_OK;
}

void df_msg_mesh_chunk_free(df_msg_mesh_chunk *m)
{
    if (!m)
        return;
    free(m->xyz);
    free(m->idx);
    m->xyz = NULL;
    m->idx = NULL;
    m->count = 0;
}
