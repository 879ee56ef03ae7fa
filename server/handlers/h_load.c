/* h_load.c — load mesh: chunked inline uploads and allowed server-side paths (see handlers.h).
 *
 * Inline uploads arrive as LOAD_MESH frames with the same request id, DF_FLAG_MORE on all but the
 * last; chunk offsets must be consecutive. Only the last chunk is answered (session_info, or a
 * load_reply with the reader's report when the request set DF_LOAD_OPT_EXT); an error in any
 * chunk answers the request and drops the upload. Reading and parsing run on a worker; path
 * loads read only through pathload.h (allow_paths on the resolved path of both TetGen halves,
 * regular files, size cap, no content in errors). Upload errors name the client's file_name.
 * Without a session name the session is named after the file (base name without extension,
 * "spot", then "spot-2", ... when taken), else "session-N". With options PROGRESS the requester
 * gets WORK_PROGRESS events (work_progress.h): UPLOAD as chunks arrive (loop thread), PARSE from
 * the reader on the worker, all before the reply.
 *
 * Memory: total_size is checked against max_upload_mb (and uploads_max_mb, which it could never
 * fit) at the first chunk, but the buffer is not allocated up front: it grows as chunks arrive
 * (doubling, never beyond the bytes received so far times two nor total_size), and every growth
 * is charged to the memory budget (DF_MEM_UPLOADS: uploads_max_mb, memory_max_mb) first. A
 * refused growth fails the upload with DF_ELIMIT naming the limit; the charge is returned when
 * the upload is freed. */
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "server/cluster/cluster.h"
#include "server/net/conn.h"
#include "server/session/access.h"
#include "server/handlers/handlers.h"
#include "server/exec/job.h"
#include "server/exec/work_progress.h"
#include "server/log.h"
#include "server/session/meshload.h"
#include "server/session/pathload.h"
#include "server/net/reply.h"
#include "server/text.h"

/* First buffer of an inline upload (smaller when total_size is). */
#define DF_UPLOAD_MIN_BUFFER ((uint64_t)64 << 10)

typedef struct df_upload {
    df_server *srv;
    uint64_t req_id;
    uint8_t format;
    uint16_t options;       /* DF_LOAD_OPT_* of the request (EXT, 2D) */
    char name[DF_MAX_NAME_LEN + 1];
    char file_name[DF_MAX_NAME_LEN + 1]; /* the user's file (uploads with EXT), for messages */
    uint64_t total, part2, received;
    uint8_t *data;
    uint64_t cap;           /* bytes allocated for data (charged to srv->mem until freed) */
    char *path;             /* path loads: the path as the client sent it */
    char owner[DF_PRINCIPAL_MAX]; /* the requester's principal: the new session's owner */
    df_mesh mesh;           /* parsed by the worker */
    df_mesh_report rep;     /* the reader's report */
    df_admm_degenerate degen; /* degenerate elements as the solver classifies them */
    df_work work;           /* WORK_PROGRESS of the request (options PROGRESS), else off */
    uint64_t parse_total;   /* bytes of the buffer being parsed (last progress callback) */
} df_upload;

void df_upload_free(struct df_upload *u)
{
    if (!u) return;
    if (u->srv) df_mem_release(df_server_mem(u->srv), DF_MEM_UPLOADS, u->cap);
    free(u->data);
    free(u->path);
    df_meshload_free(&u->mesh);
    free(u);
}

/* The reader's progress (worker thread): PARSE events, rate-limited by the reporter. */
static void parse_progress(void *user, size_t done, size_t total)
{
    df_upload *u = user;
    u->parse_total = total;
    df_work_report(&u->work, DF_STAGE_PARSE, done, total, 0, 1);
}

static void load_work(df_job *j)
{
    df_upload *u = j->body;
    int32_t maxv = j->srv->cfg.max_mesh_vertices;
    if ((uint32_t)maxv > DF_MAX_MESH_VERTICES) maxv = (int32_t)DF_MAX_MESH_VERTICES;
    df_mesh_progress prog = {parse_progress, u};
    const df_mesh_progress *pp = u->work.c ? &prog : NULL;
    u->parse_total = u->path ? 0 : u->total;
    df_work_report(&u->work, DF_STAGE_PARSE, 0, u->parse_total, 0, 1);
    if (u->path)
        j->rc = df_pathload_mesh(&j->srv->cfg, u->path, u->format, maxv,
                                 (u->options & DF_LOAD_OPT_2D) != 0, &u->mesh, &u->rep, pp,
                                 &j->err);
    else
        j->rc = df_meshload_memory(u->data, (size_t)u->total, u->format, (size_t)u->part2, maxv,
                                   (u->options & DF_LOAD_OPT_2D) != 0,
                                   u->file_name[0] ? u->file_name : "upload", &u->mesh, &u->rep,
                                   pp, &j->err);
    if (j->rc == DF_OK) { /* inline: the whole upload; a path: the last buffer reported */
        uint64_t t = u->path ? u->parse_total : u->total;
        df_work_report(&u->work, DF_STAGE_PARSE, t, t, 1, 1);
    }
    if (j->rc == DF_OK && (uint32_t)u->mesh.ne > DF_MAX_MESH_ELEMENTS)
        j->rc = df_error_set(&j->err, DF_ELIMIT, "mesh has %d elements (max %u)", u->mesh.ne,
                             DF_MAX_MESH_ELEMENTS);
    /* the solver's own classification (worker thread: O(ne log ne)); a mesh without elements has
     * none */
    memset(&u->degen, 0, sizeof u->degen);
    if (j->rc == DF_OK && u->mesh.ne > 0)
        j->rc = df_admm_find_degenerate(&u->mesh, NULL, &u->degen, &j->err);
    if (j->rc == DF_OK && u->mesh.nv < 1)
        j->rc = df_error_set(&j->err, DF_EFORMAT, "mesh has no vertices");
    free(u->data); /* early: the parsed mesh replaces it (uncharged in load_done) */
    u->data = NULL;
}

/* The default session name for file `file` (a path or a base name): its base name without the
 * extension, control bytes and invalid UTF-8 replaced by '_', cut to leave room for a suffix;
 * "X-2", "X-3", ... when a session already has the name. "" when nothing usable is left. */
static void default_name(df_server *srv, const char *file, char *out, size_t n)
{
    out[0] = '\0';
    if (!file || !file[0])
        return;
    const char *b = strrchr(file, '/');
    b = b ? b + 1 : file;
    const char *dot = strrchr(b, '.');
    size_t l = dot && dot > b ? (size_t)(dot - b) : strlen(b);
    char cand[DF_MAX_NAME_LEN + 1];
    size_t k = 0;
    for (size_t i = 0; i < l && k < DF_MAX_NAME_LEN - 8;) {
        unsigned char c = (unsigned char)b[i];
        size_t len = c < 0x80 ? 1 : (c & 0xE0) == 0xC0 ? 2 : (c & 0xF0) == 0xE0 ? 3
                   : (c & 0xF8) == 0xF0 ? 4 : 0;
        int ok = len > 0 && i + len <= l && k + len <= DF_MAX_NAME_LEN - 8 &&
                 !(len == 2 && c < 0xC2); /* no overlong 2-byte forms */
        for (size_t q = 1; ok && q < len; q++)
            ok = ((unsigned char)b[i + q] & 0xC0) == 0x80;
        if (ok && len == 1 && (c < 0x20 || c == 0x7F))
            ok = 0;
        if (!ok) {
            cand[k++] = '_';
            i++;
            continue;
        }
        memcpy(cand + k, b + i, len);
        k += len;
        i += len;
    }
    cand[k] = '\0';
    if (k == 0)
        return;
    char t[DF_MAX_NAME_LEN + 32];
    snprintf(t, sizeof t, "%s", cand);
    for (int i = 2; df_session_find_name(srv, t) && i < 100000; i++)
        snprintf(t, sizeof t, "%s-%d", cand, i);
    size_t tl = strlen(t); /* <= DF_MAX_NAME_LEN - 8 + 6 */
    if (tl < n)
        memcpy(out, t, tl + 1);
}

static void load_done(df_job *j)
{
    df_upload *u = j->body;
    if (u->srv) { /* the worker freed the buffer: return its charge before the session's */
        df_mem_release(df_server_mem(u->srv), DF_MEM_UPLOADS, u->cap);
        u->cap = 0;
    }
    if (j->rc == DF_OK && j->srv->stopping)
        j->rc = df_error_set(&j->err, DF_ESTATE, "server shutting down");
    if (df_job_failed(j)) return;
    df_session *s;
    int32_t nv = u->mesh.nv, ne = u->mesh.ne;
    if (!u->name[0])
        default_name(j->srv, u->path ? u->path : u->file_name, u->name, sizeof u->name);
    uint64_t up = u->path ? 0 : u->total; /* quotas again: other loads may have finished */
    if (df_access_quota_check(j->srv, u->owner, up, df_session_estimate_bytes(&u->mesh),
                              &j->err) != DF_OK ||
        df_cluster_next_id(j->srv, &j->err) != DF_OK || /* cluster-wide id (cluster.h) */
        df_session_create_as(j->srv, &u->mesh, u->name, u->owner, &s, &j->err) != DF_OK) {
        j->rc = j->err.code;
        df_job_failed(j);
        return;
    }
    s->upload_bytes = up;
    df_log(DF_LOG_INFO, "session %llu '%s': %d vertices, %d elements%s%s",
           (unsigned long long)s->id, s->name, nv, ne, u->path ? " from " : "",
           u->path ? u->path : "");
    s->degen = u->degen;
    if (u->degen.elements > 0)
        df_log(DF_LOG_INFO, "session %llu: %d degenerate element(s) excluded from the solver's "
               "energies; %d vertex(es) of such elements only follow their neighbours, %d stay at "
               "rest", (unsigned long long)s->id, (int)u->degen.elements,
               (int)u->degen.followers, (int)u->degen.at_rest);
    df_msg_load_reply r;
    memset(&r, 0, sizeof r);
    df_session_info_fill(s, &r.info);
    if (u->options & DF_LOAD_OPT_EXT) {
        const df_mesh_report *p = &u->rep;
        df_msg_load_report *q = &r.report;
        r.has_report = 1;
        q->format = p->format >= 1 && p->format <= DF_FMT_MAX ? (uint8_t)p->format : DF_FMT_OBJ;
        q->index_base = p->index_base == 1;
        q->input_polygons = (uint32_t)p->input_polygons;
        q->polygons_triangulated = (uint32_t)p->polygons_triangulated;
        q->dropped_elements = (uint32_t)p->ignored_elements;
        q->duplicate_elements = (uint32_t)p->duplicate_elements;
        q->degenerate_elements = (uint32_t)u->degen.elements; /* as the solver counts them */
        q->inverted_elements = (uint32_t)p->inverted_elements;
        q->nonmanifold_edges = (uint32_t)p->nonmanifold_edges;
        q->nonmanifold_faces = (uint32_t)p->nonmanifold_faces;
        q->boundary_edges = (uint32_t)p->boundary_edges;
        q->boundary_faces = (uint32_t)p->boundary_faces;
        q->unused_vertices = (uint32_t)p->unreferenced_vertices;
    }
    df_req_reply_load_reply(&j->req, &r);
}

static void upload_cleanup(df_job *j) { df_upload_free(j->body); }

/* Queues the load of the complete upload `u` (owned by the job from here) for request `r`. */
static int submit_load(df_req *r, df_upload *u, df_error *err)
{
    df_job *j = df_job_new(r->srv, NULL, r->c, DF_MSG_LOAD_MESH, u->req_id, load_work, load_done);
    if (!j) {
        df_upload_free(u);
        return df_error_set(err, DF_ENOMEM, "out of memory");
    }
    r->answered = 1; /* the job answers it (j->req) */
    j->body = u;
    j->cleanup = upload_cleanup;
    df_job_submit(j);
    return DF_OK;
}

/* Drops the connection's upload; returns e->code (the dispatcher answers the request). */
static int fail(df_conn *c, df_error *e)
{
    df_upload_free(c->upload);
    c->upload = NULL;
    return e->code;
}

static int load_path(df_req *r, const df_msg_load_mesh *m, df_error *err)
{
    df_conn *c = r->c;
    if (c->srv->cfg.n_allow == 0) {
        df_error_set(err, DF_EUNSUPPORTED,
                     "load_mesh: server-side paths are disabled (no allow_paths in the config)");
        return fail(c, err);
    }
    df_upload *u = calloc(1, sizeof *u);
    char *path = strdup(m->path);
    if (!u || !path) {
        free(u);
        free(path);
        df_error_set(err, DF_ENOMEM, "out of memory");
        return fail(c, err);
    }
    u->req_id = r->id;
    u->format = m->format;
    u->options = m->options;
    u->path = path; /* resolved and checked on the worker (pathload.h) */
    df_work_init(&u->work, c->srv, c, r->id, 0, (m->options & DF_LOAD_OPT_PROGRESS) != 0);
    snprintf(u->name, sizeof u->name, "%s", m->name);
    snprintf(u->owner, sizeof u->owner, "%s", c->principal);
    if (df_access_quota_check(c->srv, u->owner, 0, 0, err) != DF_OK) {
        df_upload_free(u);
        return fail(c, err);
    }
    return submit_load(r, u, err);
}

/* Checks the announced total_size of a new upload against max_upload_mb and uploads_max_mb. */
static int upload_size_ok(const df_server_config *cfg, uint64_t total, df_error *err)
{
    uint64_t max = (uint64_t)cfg->max_upload_mb << 20, all = (uint64_t)cfg->uploads_max_mb << 20;
    if (total > max)
        return df_error_set(err, DF_ELIMIT,
                            "load_mesh: total_size %llu bytes exceeds max_upload_mb (%d MiB)",
                            (unsigned long long)total, cfg->max_upload_mb);
    if (total > all)
        return df_error_set(err, DF_ELIMIT,
                            "load_mesh: total_size %llu bytes exceeds uploads_max_mb (%d MiB, all "
                            "uploads in flight together)",
                            (unsigned long long)total, cfg->uploads_max_mb);
    return DF_OK;
}

/* Makes room for `need` bytes of data: grows the buffer geometrically (capped by total_size and
 * by `need` when the budget has no room for more), charging the growth first. */
static int upload_reserve(df_upload *u, uint64_t need, df_error *err)
{
    if (need <= u->cap) return DF_OK;
    uint64_t ncap = u->cap ? 2 * u->cap : DF_UPLOAD_MIN_BUFFER;
    if (ncap < need) ncap = need;
    if (ncap > u->total) ncap = u->total;
    df_membudget *b = df_server_mem(u->srv);
    if (ncap > need && df_mem_room(b, DF_MEM_UPLOADS) < ncap - u->cap) ncap = need;
    int rc = df_session_mem_charge(u->srv, DF_MEM_UPLOADS, ncap - u->cap, "load_mesh", err);
    if (rc != DF_OK) return rc;
    uint8_t *d = realloc(u->data, (size_t)ncap);
    if (!d) {
        df_mem_release(b, DF_MEM_UPLOADS, ncap - u->cap);
        return df_error_set(err, DF_ENOMEM, "load_mesh: cannot buffer %llu bytes",
                            (unsigned long long)ncap);
    }
    u->data = d;
    u->cap = ncap;
    return DF_OK;
}

int df_h_load_mesh(df_req *r, const uint8_t *p, df_error *err)
{
    df_conn *c = r->c;
    df_msg_load_mesh m;
    if (df_msg_load_mesh_decode(p, r->len, &m, err) != DF_OK) {
        return fail(c, err);
    }
    if (df_text_check_name("load_mesh: name", m.name, err) != DF_OK) {
        df_msg_load_mesh_free(&m);
        return fail(c, err);
    }
    if (m.source == DF_LOAD_PATH) {
        if (c->upload || (r->flags & DF_FLAG_MORE)) {
            df_msg_load_mesh_free(&m);
            df_error_set(err, DF_EPROTO_CHUNK, "load_mesh: a path load cannot be chunked");
            return fail(c, err);
        }
        int rc = load_path(r, &m, err);
        df_msg_load_mesh_free(&m);
        return rc;
    }
    df_upload *u = c->upload;
    if (m.offset == 0 && !u) {
        if (upload_size_ok(&c->srv->cfg, m.total_size, err) != DF_OK ||
            df_access_quota_check(c->srv, c->principal, m.total_size, 0, err) != DF_OK) {
            df_msg_load_mesh_free(&m);
            return fail(c, err);
        }
        u = calloc(1, sizeof *u);
        if (!u) {
            df_msg_load_mesh_free(&m);
            df_error_set(err, DF_ENOMEM, "load_mesh: out of memory");
            return fail(c, err);
        }
        u->srv = c->srv;
        u->req_id = r->id;
        u->format = m.format;
        u->total = m.total_size;
        u->part2 = m.part2_offset;
        u->options = m.options;
        df_work_init(&u->work, c->srv, c, r->id, 0, (m.options & DF_LOAD_OPT_PROGRESS) != 0);
        snprintf(u->name, sizeof u->name, "%s", m.name);
        snprintf(u->file_name, sizeof u->file_name, "%s", m.file_name);
        snprintf(u->owner, sizeof u->owner, "%s", c->principal);
        c->upload = u;
    } else if (!u || u->req_id != r->id || m.offset != u->received ||
               m.total_size != u->total || m.format != u->format ||
               m.part2_offset != u->part2 || m.options != u->options ||
               strcmp(m.file_name, u->file_name) != 0 || strcmp(m.name, u->name) != 0) {
        df_error_set(err, DF_EPROTO_CHUNK,
                     "load_mesh: chunk at offset %llu does not continue the upload (expected "
                     "offset %llu of request %llu, with the first chunk's total_size, format, "
                     "part2_offset, options, file_name and name)",
                     (unsigned long long)m.offset, (unsigned long long)(u ? u->received : 0),
                     (unsigned long long)(u ? u->req_id : r->id));
        df_msg_load_mesh_free(&m);
        return fail(c, err);
    }
    if (upload_reserve(u, u->received + m.data_len, err) != DF_OK) {
        df_msg_load_mesh_free(&m);
        return fail(c, err);
    }
    memcpy(u->data + u->received, m.data, m.data_len);
    u->received += m.data_len;
    df_msg_load_mesh_free(&m);
    if (!(r->flags & DF_FLAG_MORE) || u->received < u->total) /* loop thread: sent now */
        df_work_report(&u->work, DF_STAGE_UPLOAD, u->received, u->total,
                       u->received == u->total, 0);
    if (r->flags & DF_FLAG_MORE) {
        if (u->received >= u->total) {
            df_error_set(err, DF_EPROTO_CHUNK, "load_mesh: MORE flag on a chunk that completes "
                                                "the upload");
            return fail(c, err);
        }
        c->pending--; /* answered with the last chunk */
        r->answered = 1;
        return DF_OK;
    }
    if (u->received != u->total) {
        df_error_set(err, DF_EPROTO_CHUNK,
                     "load_mesh: upload ended at %llu of %llu bytes",
                     (unsigned long long)u->received, (unsigned long long)u->total);
        return fail(c, err);
    }
    c->upload = NULL;
    return submit_load(r, u, err);
}
