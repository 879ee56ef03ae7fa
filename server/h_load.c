/* h_load.c — load mesh: chunked inline uploads and allowed server-side paths (see handlers.h).
 *
 * Inline uploads arrive as LOAD_MESH frames with the same request id, DF_FLAG_MORE on all but the
 * last; chunk offsets must be consecutive. Only the last chunk is answered (session_info); an
 * error in any chunk answers the request and drops the upload. Parsing runs on a worker. */
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "server/conn.h"
#include "server/handlers.h"
#include "server/job.h"
#include "server/log.h"
#include "server/meshload.h"
#include "server/reply.h"

typedef struct df_upload {
    uint64_t req_id;
    uint8_t format;
    uint16_t flags;         /* DF_LOAD_* of the request (DF_LOAD_2D) */
    char name[DF_MAX_NAME_LEN + 1];
    uint64_t total, part2, received;
    uint8_t *data;
    char *path;             /* path loads: resolved absolute path */
    df_mesh mesh;           /* parsed by the worker */
} df_upload;

void df_upload_free(struct df_upload *u)
{
    if (!u) return;
    free(u->data);
    free(u->path);
    df_meshload_free(&u->mesh);
    free(u);
}

static void load_work(df_job *j)
{
    df_upload *u = j->body;
    int32_t maxv = j->srv->cfg.max_mesh_vertices;
    if ((uint32_t)maxv > DF_MAX_MESH_VERTICES) maxv = (int32_t)DF_MAX_MESH_VERTICES;
    if (u->path)
        j->rc = df_meshload_file(u->path, u->format, maxv, (u->flags & DF_LOAD_2D) != 0,
                                 &u->mesh, &j->err);
    else
        j->rc = df_meshload_memory(u->data, (size_t)u->total, u->format, (size_t)u->part2, maxv,
                                   (u->flags & DF_LOAD_2D) != 0,
                                   u->name[0] ? u->name : "upload", &u->mesh, &j->err);
    if (j->rc == DF_OK && (uint32_t)u->mesh.ne > DF_MAX_MESH_ELEMENTS)
        j->rc = df_error_set(&j->err, DF_ELIMIT, "mesh has %d elements (max %u)", u->mesh.ne,
                             DF_MAX_MESH_ELEMENTS);
    if (j->rc == DF_OK && u->mesh.nv < 1)
        j->rc = df_error_set(&j->err, DF_EFORMAT, "mesh has no vertices");
    free(u->data);
    u->data = NULL;
}

static void load_done(df_job *j)
{
    df_upload *u = j->body;
    if (j->rc == DF_OK && j->srv->stopping)
        j->rc = df_error_set(&j->err, DF_ESTATE, "server shutting down");
    if (df_job_failed(j)) return;
    df_session *s;
    int32_t nv = u->mesh.nv, ne = u->mesh.ne;
    if (df_session_create(j->srv, &u->mesh, u->name, &s, &j->err) != DF_OK) {
        j->rc = j->err.code;
        df_job_failed(j);
        return;
    }
    df_log(DF_LOG_INFO, "session %llu '%s': %d vertices, %d elements%s%s",
           (unsigned long long)s->id, s->name, nv, ne, u->path ? " from " : "",
           u->path ? u->path : "");
    df_msg_session_info info;
    df_session_info_fill(s, &info);
    if (j->c) df_reply_session_info(j->c, j->type, j->req_id, &info, 1);
}

static void upload_cleanup(df_job *j) { df_upload_free(j->body); }

static void submit_load(df_conn *c, df_upload *u)
{
    df_job *j = df_job_new(c->srv, NULL, c, DF_MSG_LOAD_MESH, u->req_id, load_work, load_done);
    if (!j) {
        df_error e;
        df_error_set(&e, DF_ENOMEM, "out of memory");
        df_reply_fail(c, DF_MSG_LOAD_MESH, u->req_id, &e);
        df_upload_free(u);
        return;
    }
    j->body = u;
    j->cleanup = upload_cleanup;
    df_job_submit(j);
}

static void fail(df_conn *c, const df_frame_header *h, df_error *e)
{
    df_upload_free(c->upload);
    c->upload = NULL;
    df_reply_fail(c, h->type, h->request_id, e);
}

static void load_path(df_conn *c, const df_frame_header *h, const df_msg_load_mesh *m)
{
    df_error err;
    if (c->srv->cfg.n_allow == 0) {
        df_error_set(&err, DF_EUNSUPPORTED,
                     "load_mesh: server-side paths are disabled (no allow_paths in the config)");
        fail(c, h, &err);
        return;
    }
    char *real = realpath(m->path, NULL);
    if (!real) {
        df_error_set(&err, DF_EIO, "load_mesh: %s: %s", m->path, strerror(errno));
        fail(c, h, &err);
        return;
    }
    if (!df_config_path_allowed(&c->srv->cfg, real)) {
        df_error_set(&err, DF_EINVAL,
                     "load_mesh: %s is not inside an allowed directory (config allow_paths)",
                     real);
        free(real);
        fail(c, h, &err);
        return;
    }
    df_upload *u = calloc(1, sizeof *u);
    if (!u) {
        free(real);
        df_error_set(&err, DF_ENOMEM, "out of memory");
        fail(c, h, &err);
        return;
    }
    u->req_id = h->request_id;
    u->format = m->format;
    u->flags = m->flags;
    u->path = real;
    snprintf(u->name, sizeof u->name, "%s", m->name);
    submit_load(c, u);
}

void df_h_load_mesh(df_conn *c, const df_frame_header *h, const uint8_t *p)
{
    df_msg_load_mesh m;
    df_error err;
    if (df_msg_load_mesh_decode(p, h->payload_len, &m, &err) != DF_OK) {
        fail(c, h, &err);
        return;
    }
    if (m.source == DF_LOAD_PATH) {
        if (c->upload || (h->flags & DF_FLAG_MORE)) {
            df_msg_load_mesh_free(&m);
            df_error_set(&err, DF_EPROTO_CHUNK, "load_mesh: a path load cannot be chunked");
            fail(c, h, &err);
            return;
        }
        load_path(c, h, &m);
        df_msg_load_mesh_free(&m);
        return;
    }
    df_upload *u = c->upload;
    if (m.offset == 0 && !u) {
        u = calloc(1, sizeof *u);
        if (u) u->data = malloc((size_t)m.total_size);
        if (!u || !u->data) {
            free(u);
            df_msg_load_mesh_free(&m);
            df_error_set(&err, DF_ENOMEM, "load_mesh: cannot buffer %llu bytes",
                         (unsigned long long)m.total_size);
            fail(c, h, &err);
            return;
        }
        u->req_id = h->request_id;
        u->format = m.format;
        u->flags = m.flags;
        u->total = m.total_size;
        u->part2 = m.part2_offset;
        snprintf(u->name, sizeof u->name, "%s", m.name);
        c->upload = u;
    } else if (!u || u->req_id != h->request_id || m.offset != u->received ||
               m.total_size != u->total || m.format != u->format || m.flags != u->flags ||
               m.part2_offset != u->part2) {
        df_error_set(&err, DF_EPROTO_CHUNK,
                     "load_mesh: chunk at offset %llu does not continue the upload (expected "
                     "offset %llu of request %llu)",
                     (unsigned long long)m.offset, (unsigned long long)(u ? u->received : 0),
                     (unsigned long long)(u ? u->req_id : h->request_id));
        df_msg_load_mesh_free(&m);
        fail(c, h, &err);
        return;
    }
    memcpy(u->data + u->received, m.data, m.data_len);
    u->received += m.data_len;
    df_msg_load_mesh_free(&m);
    if (h->flags & DF_FLAG_MORE) {
        if (u->received >= u->total) {
            df_error_set(&err, DF_EPROTO_CHUNK, "load_mesh: MORE flag on a chunk that completes "
                                                "the upload");
            fail(c, h, &err);
            return;
        }
        c->pending--; /* answered with the last chunk */
        return;
    }
    if (u->received != u->total) {
        df_error_set(&err, DF_EPROTO_CHUNK,
                     "load_mesh: upload ended at %llu of %llu bytes",
                     (unsigned long long)u->received, (unsigned long long)u->total);
        fail(c, h, &err);
        return;
    }
    c->upload = NULL;
    submit_load(c, u);
}
