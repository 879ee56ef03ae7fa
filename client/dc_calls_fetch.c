/* dc_calls_fetch.c — libdeformclient calls that read state: get mesh (chunk reassembly),
 * displacement snapshot, stats, the session's handle set. */
#include "client/dc_client.h"

#include <stdlib.h>
#include <string.h>

#include "core/mesh/mesh.h"

void df_client_mesh_free(df_client_mesh *m)
{
    if (!m)
        return;
    free(m->positions);
    free(m->base);
    free(m->rest);
    free(m->elements);
    free(m->faces);
    memset(m, 0, sizeof *m);
}

/* Reassembly state of a get-mesh reply. */
typedef struct mesh_acc {
    df_client_mesh m;
    int started;
    uint32_t got[DF_SECTION_MAX + 1]; /* rows received per section */
} mesh_acc;

static uint32_t section_rows(const df_client_mesh *m, uint8_t section)
{
    return section == DF_SECTION_ELEMENTS ? m->ne : section == DF_SECTION_FACES ? m->nf : m->nv;
}

static int alloc_mesh(mesh_acc *a, const df_msg_mesh_chunk *k, uint32_t flags, df_error *err)
{
    df_client_mesh *m = &a->m;
    m->session_id = k->session_id;
    m->version = k->version;
    m->kind = k->kind;
    m->planar = k->planar;
    m->nv = k->nv;
    m->ne = k->ne;
    m->nf = k->nf;
    int es = df_mesh_elem_size((df_mesh_kind)k->kind);
    if (es == 0)
        return df_error_set(err, DF_EFORMAT, "get mesh: unknown mesh kind %u", k->kind);
    size_t v3 = (size_t)k->nv * 3;
    m->positions = malloc(v3 * sizeof(float));
    m->base = (flags & DF_GET_MESH_BASE) ? malloc(v3 * sizeof(float)) : NULL;
    m->rest = (flags & DF_GET_MESH_REST) ? malloc(v3 * sizeof(float)) : NULL;
    m->elements = malloc(((size_t)k->ne * (size_t)es + 1) * sizeof(int32_t));
    m->faces = k->nf ? malloc((size_t)k->nf * 3 * sizeof(int32_t)) : NULL;
    if (!m->positions || !m->elements || ((flags & DF_GET_MESH_BASE) && !m->base) ||
        ((flags & DF_GET_MESH_REST) && !m->rest) || (k->nf && !m->faces))
        return df_error_set(err, DF_ENOMEM, "get mesh: out of memory for %u vertices", k->nv);
    a->started = 1;
    return DF_OK;
}

typedef struct mesh_ctx {
    mesh_acc *acc;
    uint32_t flags;
} mesh_ctx;

static int reply_mesh(void *user, const df_frame_header *h, const uint8_t *p, df_error *err)
{
    mesh_ctx *x = user;
    mesh_acc *a = x->acc;
    df_msg_mesh_chunk k;
    int rc = df_msg_mesh_chunk_decode(p, h->payload_len, &k, err);
    if (rc)
        return rc;
    if (!a->started)
        rc = alloc_mesh(a, &k, x->flags, err);
    else if (k.session_id != a->m.session_id || k.version != a->m.version || k.kind != a->m.kind ||
             k.nv != a->m.nv || k.ne != a->m.ne || k.nf != a->m.nf)
        rc = df_error_set(err, DF_EFORMAT, "get mesh: chunk header differs from the first chunk");
    if (rc == DF_OK && (k.section < 1 || k.section > DF_SECTION_MAX))
        rc = df_error_set(err, DF_EFORMAT, "get mesh: unknown section %u", k.section);
    if (rc == DF_OK && (k.offset != a->got[k.section] ||
                        (uint64_t)k.offset + k.count > section_rows(&a->m, k.section)))
        rc = df_error_set(err, DF_EFORMAT, "get mesh: section %u chunk rows [%u, +%u) out of order",
                          k.section, k.offset, k.count);
    if (rc == DF_OK) {
        df_client_mesh *m = &a->m;
        float *dst = k.section == DF_SECTION_POSITIONS ? m->positions
                     : k.section == DF_SECTION_BASE    ? m->base
                     : k.section == DF_SECTION_REST    ? m->rest
                                                       : NULL;
        size_t es = k.section == DF_SECTION_ELEMENTS ? (size_t)df_mesh_elem_size((df_mesh_kind)m->kind)
                                                     : 3;
        if (k.section <= DF_SECTION_REST && !dst)
            rc = df_error_set(err, DF_EFORMAT, "get mesh: section %u was not requested", k.section);
        else if (k.count == 0)
            rc = DF_OK;
        else if (dst)
            memcpy(dst + (size_t)k.offset * 3, k.xyz, (size_t)k.count * 3 * sizeof(float));
        else {
            int32_t *di = k.section == DF_SECTION_ELEMENTS ? m->elements : m->faces;
            memcpy(di + (size_t)k.offset * es, k.idx, (size_t)k.count * es * sizeof(int32_t));
        }
        if (rc == DF_OK)
            a->got[k.section] += k.count;
    }
    df_msg_mesh_chunk_free(&k);
    return rc;
}

int df_client_get_mesh(df_client *c, uint64_t session_id, uint32_t flags, df_client_mesh *out,
                       df_error *err)
{
    df_msg_get_mesh req = {session_id, flags};
    mesh_acc a;
    memset(&a, 0, sizeof a);
    mesh_ctx x = {&a, flags};
    df_buf_reset(&c->out);
    int rc = df_msg_get_mesh_encode(&req, &c->out, err);
    if (rc == DF_OK)
        rc = df_client_transact(c, DF_MSG_GET_MESH, c->out.data, c->out.len, reply_mesh, &x, err);
    if (rc == DF_OK) {
        const df_client_mesh *m = &a.m;
        if (!a.started || a.got[DF_SECTION_POSITIONS] != m->nv ||
            a.got[DF_SECTION_ELEMENTS] != m->ne || a.got[DF_SECTION_FACES] != m->nf ||
            ((flags & DF_GET_MESH_BASE) && a.got[DF_SECTION_BASE] != m->nv) ||
            ((flags & DF_GET_MESH_REST) && a.got[DF_SECTION_REST] != m->nv))
            rc = df_error_set(err, DF_EFORMAT, "get mesh: reply ended with sections incomplete");
    }
    if (rc) {
        df_client_mesh_free(&a.m);
        return rc;
    }
    *out = a.m;
    return DF_OK;
}

typedef struct snap_ctx {
    float *u;
    uint32_t nv;
    uint64_t version;
    uint32_t rows;
} snap_ctx;

static int reply_snapshot(void *user, const df_frame_header *h, const uint8_t *p, df_error *err)
{
    snap_ctx *x = user;
    df_msg_disp d;
    int rc = df_msg_disp_decode(p, h->payload_len, &d, err);
    if (rc)
        return rc;
    if (d.encoding != DF_DISP_DENSE || d.offset != x->rows || (x->rows && d.version != x->version))
        rc = df_error_set(err, DF_EFORMAT, "snapshot: chunk rows [%u, +%u) of version %llu out of "
                          "order", d.offset, d.count, (unsigned long long)d.version);
    if (rc == DF_OK)
        rc = df_client_disp_apply(&d, x->u, x->nv, err);
    if (rc == DF_OK) {
        x->version = d.version;
        x->rows += d.count;
    }
    df_msg_disp_free(&d);
    return rc;
}

int df_client_snapshot(df_client *c, uint64_t session_id, uint64_t version, uint32_t nv, float *u,
                       uint64_t *version_out, df_error *err)
{
    if (!u || nv == 0)
        return df_error_set(err, DF_EINVAL, "snapshot: no output array");
    float *tmp = malloc((size_t)nv * 3 * sizeof(float));
    if (!tmp)
        return df_error_set(err, DF_ENOMEM, "snapshot: out of memory for %u vertices", nv);
    snap_ctx x = {tmp, nv, 0, 0};
    df_msg_snapshot_req req = {session_id, version};
    df_buf_reset(&c->out);
    int rc = df_msg_snapshot_req_encode(&req, &c->out, err);
    if (rc == DF_OK)
        rc = df_client_transact(c, DF_MSG_SNAPSHOT, c->out.data, c->out.len, reply_snapshot, &x,
                                err);
    if (rc == DF_OK && x.rows != nv)
        rc = df_error_set(err, DF_EFORMAT, "snapshot: %u of %u rows received", x.rows, nv);
    if (rc == DF_OK) {
        memcpy(u, tmp, (size_t)nv * 3 * sizeof(float));
        if (version_out)
            *version_out = x.version;
    }
    free(tmp);
    return rc;
}

static int reply_stats(void *user, const df_frame_header *h, const uint8_t *p, df_error *err)
{
    return df_msg_stats_decode(p, h->payload_len, user, err);
}

static int enc_stats(const void *m, df_buf *out, df_error *err)
{
    return df_msg_stats_req_encode(m, out, err);
}

int df_client_stats(df_client *c, uint64_t session_id, df_msg_stats *out, df_error *err)
{
    df_msg_stats_req req = {session_id};
    df_msg_stats t;
    memset(&t, 0, sizeof t);
    int rc = dc_request(c, DF_MSG_STATS, enc_stats, &req, reply_stats, &t, err);
    if (rc) {
        df_msg_stats_free(&t);
        return rc;
    }
    *out = t;
    return DF_OK;
}

static int reply_handles(void *user, const df_frame_header *h, const uint8_t *p, df_error *err)
{
    df_msg_handles *t = user;
    df_msg_handles_free(t); /* a repeated reply body replaces the previous one */
    return df_msg_handles_decode(p, h->payload_len, t, err);
}

int df_client_handles_get(df_client *c, uint64_t session_id, df_msg_handles *out, df_error *err)
{
    if (!out)
        return df_error_set(err, DF_EINVAL, "handles get: no output");
    df_msg_session_ref req = {session_id};
    df_msg_handles t;
    memset(&t, 0, sizeof t);
    int rc = dc_request(c, DF_MSG_HANDLES_GET, dc_enc_session_ref, &req, reply_handles, &t, err);
    if (rc == DF_OK && t.session_id != session_id)
        rc = df_error_set(err, DF_EFORMAT, "handles get: reply is for session %llu, asked %llu",
                          (unsigned long long)t.session_id, (unsigned long long)session_id);
    if (rc) {
        df_msg_handles_free(&t);
        return rc;
    }
    *out = t;
    return DF_OK;
}
