/* h_basic.c — handlers that need no compute: hello, auth, ping, sessions, subscriptions,
 * brush knobs (see handlers.h). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "server/conn.h"
#include "server/handlers.h"
#include "server/job.h"
#include "server/log.h"
#include "server/reply.h"
#include "server/session.h"
#include "server/shm.h"
#include "server/stream.h"
#include "server/text.h"

#define DF_SERVER_NAME "deformd 0.1"

void df_session_info_fill(const df_session *s, df_msg_session_info *out)
{
    memset(out, 0, sizeof *out);
    out->session_id = s->id;
    out->version = atomic_load(&s->version);
    out->kind = (uint8_t)s->mesh.kind;
    out->planar = (uint8_t)(s->mesh.planar != 0);
    out->subscribers = (uint16_t)(s->nsubs > 65535 ? 65535 : s->nsubs);
    out->nv = (uint32_t)s->nv;
    out->ne = (uint32_t)s->mesh.ne;
    out->undo_depth = (uint32_t)df_history_can_undo(&s->hist);
    out->redo_depth = (uint32_t)df_history_can_redo(&s->hist);
    snprintf(out->name, sizeof out->name, "%s", s->name);
}

df_session *df_h_session(df_conn *c, const df_frame_header *h, uint64_t session_id)
{
    df_session *s = df_session_find(c->srv, session_id);
    if (!s) {
        df_error e;
        df_error_set(&e, DF_ENOTFOUND, "%s: no session %llu", df_msg_type_name(h->type),
                     (unsigned long long)session_id);
        df_reply_fail(c, h->type, h->request_id, &e);
    }
    return s;
}

df_session *df_h_session_ref(df_conn *c, const df_frame_header *h, const uint8_t *p)
{
    df_msg_session_ref m;
    df_error err;
    if (df_msg_session_ref_decode(p, h->payload_len, &m, &err) != DF_OK) {
        df_reply_fail(c, h->type, h->request_id, &err);
        return NULL;
    }
    return df_h_session(c, h, m.session_id);
}

void df_h_hello(df_conn *c, const df_frame_header *h, const uint8_t *p)
{
    df_msg_hello m;
    df_error err;
    if (df_msg_hello_decode(p, h->payload_len, &m, &err) != DF_OK ||
        df_text_check_name("hello: client_name", m.client_name, &err) != DF_OK) {
        df_reply_fail(c, h->type, h->request_id, &err);
        return;
    }
    if (m.max_version < DF_PROTO_VERSION_MIN || m.min_version > DF_PROTO_VERSION) {
        df_error_set(&err, DF_EPROTO_BADVERSION,
                     "hello: client speaks versions %u..%u, server %u..%u", m.min_version,
                     m.max_version, DF_PROTO_VERSION_MIN, DF_PROTO_VERSION);
        df_reply_fail(c, h->type, h->request_id, &err);
        df_conn_close_after_flush(c, "hello: no common protocol version"); /* PROTOCOL.md 4.2b */
        return;
    }
    const df_server_config *cfg = &c->srv->cfg;
    df_msg_hello_reply r;
    memset(&r, 0, sizeof r);
    r.version = (uint16_t)(m.max_version < DF_PROTO_VERSION ? m.max_version : DF_PROTO_VERSION);
    r.server_max_version = DF_PROTO_VERSION;
    r.features = DF_FEAT_KELVINLET | DF_FEAT_ADMM | DF_FEAT_SPARSE_STREAM |
                 (cfg->n_allow ? DF_FEAT_PATH_LOAD : 0) | (c->srv->have_tcp ? DF_FEAT_TCP : 0) |
                 (cfg->shm_ring_bytes && !c->is_tcp ? DF_FEAT_SHM_STREAM : 0);
    r.max_frame_payload = DF_MAX_FRAME_PAYLOAD;
    r.max_mesh_vertices = (uint32_t)cfg->max_mesh_vertices < DF_MAX_MESH_VERTICES
                              ? (uint32_t)cfg->max_mesh_vertices
                              : DF_MAX_MESH_VERTICES;
    r.max_mesh_elements = DF_MAX_MESH_ELEMENTS;
    r.max_pending_requests = DF_MAX_PENDING_REQUESTS;
    r.max_sessions = (uint32_t)cfg->max_sessions < DF_MAX_SESSIONS ? (uint32_t)cfg->max_sessions
                                                                   : DF_MAX_SESSIONS;
    r.max_mesh_bytes = (uint64_t)cfg->max_upload_mb << 20 < DF_MAX_MESH_BYTES
                           ? (uint64_t)cfg->max_upload_mb << 20
                           : DF_MAX_MESH_BYTES;
    r.max_client_queue_bytes = cfg->output_queue_limit;
    r.auth_required = 0;
    snprintf(r.server_name, sizeof r.server_name, "%s", DF_SERVER_NAME);
    if (m.client_name[0])
        df_log(DF_LOG_DEBUG, "client %llu is '%s'", (unsigned long long)c->id, m.client_name);
    c->hello_done = 1;
    df_reply_hello_reply(c, h->type, h->request_id, &r, 1);
}

void df_h_auth(df_conn *c, const df_frame_header *h, const uint8_t *p)
{
    df_msg_auth m;
    df_error err;
    if (df_msg_auth_decode(p, h->payload_len, &m, &err) == DF_OK)
        df_error_set(&err, DF_EUNSUPPORTED, "auth: not required by this server (method %u)",
                     m.method);
    df_reply_fail(c, h->type, h->request_id, &err);
}

void df_h_ping(df_conn *c, const df_frame_header *h, const uint8_t *p)
{
    df_msg_ping m;
    df_error err;
    if (df_msg_ping_decode(p, h->payload_len, &m, &err) != DF_OK) {
        df_reply_fail(c, h->type, h->request_id, &err);
        return;
    }
    df_reply_ping(c, h->type, h->request_id, &m, 1);
}

void df_h_list_sessions(df_conn *c, const df_frame_header *h, const uint8_t *p)
{
    df_error err;
    if (df_msg_empty_decode(p, h->payload_len, &err) != DF_OK) {
        df_reply_fail(c, h->type, h->request_id, &err);
        return;
    }
    df_msg_session_list l = {0, NULL};
    int n = 0;
    for (df_session *s = c->srv->sessions; s; s = s->next) n += !s->closed;
    if (n > (int)DF_MAX_SESSIONS) n = (int)DF_MAX_SESSIONS;
    l.items = calloc((size_t)(n ? n : 1), sizeof *l.items);
    if (!l.items) {
        df_error_set(&err, DF_ENOMEM, "out of memory");
        df_reply_fail(c, h->type, h->request_id, &err);
        return;
    }
    /* Oldest first (the registry list is newest first). */
    int i = n;
    for (df_session *s = c->srv->sessions; s && i > 0; s = s->next)
        if (!s->closed) df_session_info_fill(s, &l.items[--i]);
    l.count = (uint32_t)n;
    df_reply_session_list(c, h->type, h->request_id, &l, 1);
    free(l.items);
}

void df_h_open_session(df_conn *c, const df_frame_header *h, const uint8_t *p)
{
    df_msg_open_session m;
    df_error err;
    if (df_msg_open_session_decode(p, h->payload_len, &m, &err) != DF_OK) {
        df_reply_fail(c, h->type, h->request_id, &err);
        return;
    }
    df_session *s = m.session_id ? df_session_find(c->srv, m.session_id)
                                 : df_session_find_name(c->srv, m.name);
    if (!s) {
        if (m.session_id)
            df_error_set(&err, DF_ENOTFOUND, "open_session: no session %llu",
                         (unsigned long long)m.session_id);
        else
            df_error_set(&err, DF_ENOTFOUND, "open_session: no session named '%s'", m.name);
        df_reply_fail(c, h->type, h->request_id, &err);
        return;
    }
    df_msg_session_info info;
    df_session_info_fill(s, &info);
    df_reply_session_info(c, h->type, h->request_id, &info, 1);
}

static void close_done(df_job *j)
{
    if (df_job_failed(j)) return;
    df_msg_ack a = {.session_id = j->s->id, .version = atomic_load(&j->s->version)};
    df_job_drop_queued(j->s, df_job_pred_all, NULL, "session closed");
    df_session_close(j->s);
    if (j->c) df_reply_ack(j->c, j->type, j->req_id, &a, 1);
}

/* Submits a loop-only job (no work) on the session of a session_ref request; `beside`: its
 * DF_JOB_BESIDE_* mode (job.h). */
static void ref_job(df_conn *c, const df_frame_header *h, const uint8_t *p, df_job_fn done,
                    int beside)
{
    df_session *s = df_h_session_ref(c, h, p);
    if (!s) return;
    df_job *j = df_job_new(c->srv, s, c, h->type, h->request_id, NULL, done);
    if (!j) {
        df_error err;
        df_error_set(&err, DF_ENOMEM, "out of memory");
        df_reply_fail(c, h->type, h->request_id, &err);
        return;
    }
    j->beside = beside;
    df_job_submit(j);
}

void df_h_close_session(df_conn *c, const df_frame_header *h, const uint8_t *p)
{
    ref_job(c, h, p, close_done, DF_JOB_BESIDE_NONE); /* ends a running move first */
}

static void unsubscribe_done(df_job *j)
{
    if (df_job_failed(j)) return;
    df_session_unsubscribe(j->s, j->c);
    df_msg_ack a = {.session_id = j->s->id, .version = atomic_load(&j->s->version)};
    df_reply_ack(j->c, j->type, j->req_id, &a, 1);
}

void df_h_unsubscribe(df_conn *c, const df_frame_header *h, const uint8_t *p)
{
    ref_job(c, h, p, unsubscribe_done, DF_JOB_BESIDE_READ);
}

static void stream_shm_done(df_job *j)
{
    if (df_job_failed(j)) return;
    df_session *s = j->s;
    df_error err;
    if (j->c->closing) return;
    if (df_session_attach_shm(s, j->c, &err) != DF_OK) {
        df_reply_fail(j->c, j->type, j->req_id, &err);
        return;
    }
    df_msg_shm_info info = {.session_id = s->id, .capacity = s->shm->capacity,
                            .min_frame = s->shm->min_frame, .max_frame = s->shm->max_frame};
    snprintf(info.path, sizeof info.path, "%s", s->shm->path);
    df_reply_shm_info(j->c, j->type, j->req_id, &info, 1);
}

/* STREAM_SHM (PROTOCOL.md 6.1): queued behind the session's earlier requests so that the reply
 * marks the exact place in the stream from which this subscriber gets SHM_REFs. */
void df_h_stream_shm(df_conn *c, const df_frame_header *h, const uint8_t *p)
{
    const char *why = c->is_tcp ? "needs a Unix-socket connection on the daemon's host"
                      : c->srv->cfg.shm_ring_bytes == 0 ? "disabled (shm_ring_bytes = 0)"
                                                        : NULL;
    if (why) {
        df_error err;
        df_error_set(&err, DF_EUNSUPPORTED, "stream_shm: %s", why);
        df_reply_fail(c, h->type, h->request_id, &err);
        return;
    }
    ref_job(c, h, p, stream_shm_done, DF_JOB_BESIDE_READ);
}

static void subscribe_done(df_job *j)
{
    if (df_job_failed(j)) return;
    df_session *s = j->s;
    df_error err;
    if (j->c->closing) return;
    if (df_session_subscribe(s, j->c, &err) != DF_OK) {
        df_reply_fail(j->c, j->type, j->req_id, &err);
        return;
    }
    df_msg_session_info info;
    df_session_info_fill(s, &info);
    df_reply_session_info(j->c, j->type, j->req_id, &info, 1);
    if ((uintptr_t)j->body & DF_SUBSCRIBE_SNAPSHOT) {
        df_frames f = {0};
        if (df_stream_snapshot(s, DF_MSG_DISPLACEMENT, j->req_id, &f, &err) == DF_OK)
            for (size_t i = 0; i < f.n; i++) df_conn_send(j->c, f.v[i]);
        else
            df_log(DF_LOG_ERROR, "subscribe snapshot failed: %s", err.msg);
        df_frames_clear(&f);
    }
}

void df_h_subscribe(df_conn *c, const df_frame_header *h, const uint8_t *p)
{
    df_msg_subscribe m;
    df_error err;
    if (df_msg_subscribe_decode(p, h->payload_len, &m, &err) != DF_OK) {
        df_reply_fail(c, h->type, h->request_id, &err);
        return;
    }
    df_session *s = df_h_session(c, h, m.session_id);
    if (!s) return;
    df_job *j = df_job_new(c->srv, s, c, h->type, h->request_id, NULL, subscribe_done);
    if (!j) {
        df_error_set(&err, DF_ENOMEM, "out of memory");
        df_reply_fail(c, h->type, h->request_id, &err);
        return;
    }
    j->body = (void *)(uintptr_t)(m.flags & DF_SUBSCRIBE_SNAPSHOT);
    j->beside = DF_JOB_BESIDE_READ; /* watchers may join a running move */
    df_job_submit(j);
}

typedef struct knob {
    uint8_t param;
    double value;
} knob;

/* Applies a knob value to the client's open stroke on the session (FIFO order). */
static void knob_done(df_job *j)
{
    if (df_job_failed(j)) return;
    knob *k = j->body;
    df_stroke *st = df_session_stroke(j->s, j->conn_id);
    if (!st) {
        j->rc = df_error_set(&j->err, DF_ESTATE, "set_brush_param: no open stroke on session %llu",
                             (unsigned long long)j->s->id);
        df_job_failed(j);
        return;
    }
    if ((j->rc = df_h_brush_knob_check(st, k->param, k->value, &j->err)) != DF_OK) {
        df_job_failed(j);
        return;
    }
    {
        switch (k->param) {
        case DF_BP_RADIUS: st->brush.radius = k->value; break;
        case DF_BP_NU: st->brush.nu = k->value; break;
        case DF_BP_STRENGTH: st->strength = k->value; break;
        case DF_BP_FALLOFF: st->brush.order = (int)k->value; break;
        case DF_BP_RATIO: st->brush.ratio = k->value; break;
        default: break;
        }
    }
    df_msg_ack a = {.session_id = j->s->id, .version = atomic_load(&j->s->version)};
    df_reply_ack(j->c, j->type, j->req_id, &a, 1);
}

static void free_body(df_job *j) { free(j->body); }

void df_h_set_brush_param(df_conn *c, const df_frame_header *h, const uint8_t *p)
{
    df_msg_brush_param m;
    df_error err;
    if (df_msg_brush_param_decode(p, h->payload_len, &m, &err) != DF_OK) {
        df_reply_fail(c, h->type, h->request_id, &err);
        return;
    }
    df_session *s = df_h_session(c, h, m.session_id);
    if (!s) return;
    knob *k = malloc(sizeof *k);
    df_job *j = k ? df_job_new(c->srv, s, c, h->type, h->request_id, NULL, knob_done) : NULL;
    if (!j) {
        free(k);
        df_error_set(&err, DF_ENOMEM, "out of memory");
        df_reply_fail(c, h->type, h->request_id, &err);
        return;
    }
    k->param = m.param;
    k->value = m.value;
    j->body = k;
    j->cleanup = free_body;
    df_job_submit(j);
}
