/* h_basic.c — handlers that need no compute: hello, auth, ping, sessions, subscriptions,
 * brush knobs (see handlers.h). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "server/cluster/cluster.h"
#include "server/net/auth.h"
#include "server/net/conn.h"
#include "server/handlers/handlers.h"
#include "server/exec/job.h"
#include "server/log.h"
#include "server/net/reply.h"
#include "server/session/access.h"
#include "server/session/session.h"
#include "server/net/shm.h"
#include "server/session/stream.h"
#include "server/session/stream_enc.h"
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

int df_h_session_ref(const df_req *r, const uint8_t *p, uint64_t *session_id, df_error *err)
{
    df_msg_session_ref m;
    int rc = df_msg_session_ref_decode(p, r->len, &m, err);
    if (rc == DF_OK) *session_id = m.session_id;
    return rc;
}

int df_h_hello(df_req *rq, const uint8_t *p, df_error *err)
{
    df_conn *c = rq->c;
    df_msg_hello m;
    int rc = df_msg_hello_decode(p, rq->len, &m, err);
    if (rc == DF_OK) rc = df_text_check_name("hello: client_name", m.client_name, err);
    if (rc != DF_OK) return rc;
    if (m.max_version < DF_PROTO_VERSION_MIN || m.min_version > DF_PROTO_VERSION) {
        df_error_set(err, DF_EPROTO_BADVERSION,
                     "hello: client speaks versions %u..%u, server %u..%u", m.min_version,
                     m.max_version, DF_PROTO_VERSION_MIN, DF_PROTO_VERSION);
        df_req_fail(rq, err);
        df_conn_close_after_flush(c, "hello: no common protocol version"); /* PROTOCOL.md 4.2b */
        return DF_OK;
    }
    uint8_t enc = m.has_stream ? m.stream_encoding : 0;
    double e = m.has_stream ? m.error_bound : 0;
    if (c->hello_done && (enc != c->stream_enc || e != c->stream_err))
        return df_error_set(err, DF_ESTATE, "hello: the stream encoding is fixed by the first "
                            "hello of a connection (%u, error %g); reconnect to change it",
                            c->stream_enc, c->stream_err);
    c->want_owners = (m.features & DF_HELLO_WANT_OWNERS) != 0; /* cluster.h listing */
    const df_server_config *cfg = &c->srv->cfg;
    df_msg_hello_reply r;
    memset(&r, 0, sizeof r);
    r.version = (uint16_t)(m.max_version < DF_PROTO_VERSION ? m.max_version : DF_PROTO_VERSION);
    r.server_max_version = DF_PROTO_VERSION;
    r.features = DF_FEAT_KELVINLET | DF_FEAT_ADMM | DF_FEAT_SPARSE_STREAM |
                 (cfg->n_allow ? DF_FEAT_PATH_LOAD : 0) | (c->srv->have_tcp ? DF_FEAT_TCP : 0) |
                 (cfg->shm_ring_bytes && !c->is_tcp ? DF_FEAT_SHM_STREAM : 0) |
                 (c->srv->hid ? DF_FEAT_HID : 0) | (df_auth_enabled(c->srv) ? DF_FEAT_AUTH : 0);
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
    r.auth_required = (uint8_t)df_auth_required(c);
    snprintf(r.server_name, sizeof r.server_name, "%s", DF_SERVER_NAME);
    if (m.client_name[0])
        df_log(DF_LOG_DEBUG, "client %llu is '%s'", (unsigned long long)c->id, m.client_name);
    c->hello_done = 1;
    c->stream_enc = enc;
    c->stream_neg = m.has_stream;
    c->stream_err = e;
    r.has_stream = m.has_stream; /* only a hello with the trailer gets one back (4.2b) */
    r.stream_encoding = enc;
    r.error_bound = e;
    if (enc)
        df_log(DF_LOG_DEBUG, "client %llu: stream encoding %s%s%s, error %g",
               (unsigned long long)c->id, enc & DF_STREAM_ENC_QUANTIZED ? "quantized" : "",
               enc == (DF_STREAM_ENC_QUANTIZED | DF_STREAM_ENC_ZSTD) ? "+" : "",
               enc & DF_STREAM_ENC_ZSTD ? "zstd" : "", e);
    snprintf(c->name, sizeof c->name, "%s", m.client_name);
    df_req_reply_hello_reply(rq, &r);
    return DF_OK;
}

int df_h_auth(df_req *r, const uint8_t *p, df_error *err)
{
    df_msg_auth m;
    int rc = df_msg_auth_decode(p, r->len, &m, err);
    return rc != DF_OK ? rc : df_auth_request(r, &m, err); /* net/auth.h */
}

int df_h_ping(df_req *r, const uint8_t *p, df_error *err)
{
    df_msg_ping m;
    int rc = df_msg_ping_decode(p, r->len, &m, err);
    if (rc != DF_OK) return rc;
    df_req_reply_ping(r, &m);
    return DF_OK;
}

int df_h_list_sessions(df_req *r, const uint8_t *p, df_error *err)
{
    df_conn *c = r->c;
    int rc = df_msg_empty_decode(p, r->len, err);
    if (rc != DF_OK) return rc;
    df_msg_session_list l = {0, NULL};
    int n = 0;
    /* a session that admits no observers is hidden from those who may not observe it */
#define LISTED(s) (!(s)->closed && (df_access_rights(c, (s)) & DF_RIGHT_OBSERVE))
    for (df_session *s = c->srv->sessions; s; s = s->next) n += LISTED(s);
    if (n > (int)DF_MAX_SESSIONS) n = (int)DF_MAX_SESSIONS;
    l.items = calloc((size_t)(n ? n : 1), sizeof *l.items);
    if (!l.items) return df_error_set(err, DF_ENOMEM, "out of memory");
    /* Oldest first (the registry list is newest first). */
    int i = n;
    for (df_session *s = c->srv->sessions; s && i > 0; s = s->next)
        if (LISTED(s)) df_session_info_fill(s, &l.items[--i]);
#undef LISTED
    l.count = (uint32_t)n;
    rc = c->srv->cluster ? df_cluster_list_sessions(r, &l, err) /* the whole cluster's */
                         : (df_req_reply_session_list(r, &l), DF_OK);
    free(l.items);
    return rc;
}

int df_h_open_session(df_req *r, const uint8_t *p, df_error *err)
{
    df_msg_open_session m;
    int rc = df_msg_open_session_decode(p, r->len, &m, err);
    if (rc != DF_OK) return rc;
    df_session *s = m.session_id ? df_session_find(r->srv, m.session_id)
                                 : df_session_find_name(r->srv, m.name);
    if (!s && m.session_id && r->srv->cluster &&
        (rc = df_cluster_route(r->srv, m.session_id, &s, err)) != DF_OK)
        return rc; /* redirected, or taken over (cluster.h) */
    if (!s) {
        if (m.session_id)
            return df_error_set(err, DF_ENOTFOUND, "open_session: no session %llu",
                                (unsigned long long)m.session_id);
        return df_error_set(err, DF_ENOTFOUND, "open_session: no session named '%s'", m.name);
    }
    rc = df_access_require(r, s, DF_RIGHT_OBSERVE, err); /* observers off (membership.h) */
    if (rc != DF_OK) return rc;
    df_msg_session_info info;
    df_session_info_fill(s, &info);
    df_req_reply_session_info(r, &info);
    return DF_OK;
}

static void close_done(df_job *j)
{
    if (df_job_failed(j)) return;
    df_server *srv = j->srv;
    if (srv->store_ops && (j->rc = srv->store_ops->session_closing(srv, j->s, &j->err)) != DF_OK) {
        df_job_failed(j); /* still in the store: the session stays open */
        return;
    }
    uint64_t v = atomic_load(&j->s->version);
    df_job_drop_queued(j->s, df_job_pred_all, NULL, "session closed");
    df_session_close(j->s);
    df_job_pump(j->s); /* frees it once its FIFO is empty */
    df_req_ack(&j->req, j->s->id, v);
}

const df_job_kind df_k_close_session = {.decode = df_job_decode_ref, .done = close_done};

static void unsubscribe_done(df_job *j)
{
    if (df_job_failed(j)) return;
    df_session_unsubscribe(j->s, j->req.c);
    df_req_ack(&j->req, j->s->id, atomic_load(&j->s->version));
}

const df_job_kind df_k_unsubscribe = {.decode = df_job_decode_ref, .done = unsubscribe_done,
                                      .beside = DF_JOB_BESIDE_READ};

/* Adds the requester to the session with `join` (subscribe, attach_shm); 1 when it may be
 * answered with success, 0 when it was answered with an error or its connection is closing. */
static int join(df_job *j, int (*join_fn)(df_session *s, df_conn *c, df_error *err))
{
    df_error err;
    if (df_job_failed(j) || j->req.c->closing) return 0;
    if (join_fn(j->s, j->req.c, &err) != DF_OK) {
        df_req_fail(&j->req, &err);
        return 0;
    }
    return 1;
}

static void stream_shm_done(df_job *j)
{
    if (!join(j, df_session_attach_shm)) return;
    df_session *s = j->s;
    df_msg_shm_info info = {.session_id = s->id, .capacity = s->shm->capacity,
                            .min_frame = s->shm->min_frame, .max_frame = s->shm->max_frame};
    snprintf(info.path, sizeof info.path, "%s", s->shm->path);
    df_req_reply_shm_info(&j->req, &info);
}

/* STREAM_SHM (PROTOCOL.md 6.1): queued behind the session's earlier requests so that the reply
 * marks the exact place in the stream from which this subscriber gets SHM_REFs. */
static int stream_shm_decode(const df_req *r, const uint8_t *p, void *body, uint64_t *sid,
                             df_error *err)
{
    const char *why = r->c->is_tcp ? "needs a Unix-socket connection on the daemon's host"
                      : r->srv->cfg.shm_ring_bytes == 0 ? "disabled (shm_ring_bytes = 0)"
                      : r->c->stream_enc ? "the ring carries exact frames only; this connection "
                                           "negotiated a stream encoding in its hello"
                                         : NULL;
    if (why) return df_error_set(err, DF_EUNSUPPORTED, "stream_shm: %s", why);
    return df_job_decode_ref(r, p, body, sid, err);
}

const df_job_kind df_k_stream_shm = {.decode = stream_shm_decode, .done = stream_shm_done,
                                     .beside = DF_JOB_BESIDE_READ};

/* SUBSCRIBE's job body: what it asked for after the reply. */
typedef struct sub_req {
    uint32_t flags;              /* DF_SUBSCRIBE_* */
    uint64_t from_version;       /* with DF_SUBSCRIBE_FROM_VERSION */
} sub_req;

/* A dense snapshot of the current version as events carrying the subscribe's request id. */
static void send_snapshot(df_job *j)
{
    df_error err;
    df_frames f = {0};
    if (df_stream_snapshot(j->s, DF_MSG_DISPLACEMENT, j->req.id, &f, &err) == DF_OK)
        for (size_t i = 0; i < f.n && !j->req.c->closing; i++) df_req_reply_more(&j->req, f.v[i]);
    else
        df_log(DF_LOG_ERROR, "subscribe snapshot failed: %s", err.msg);
    df_frames_clear(&f);
}

/* FROM_VERSION (PROTOCOL.md 6.2): the kept frames of versions from+1 .. current exactly as they
 * were broadcast (nothing when from is current), else one snapshot of the current version. On
 * the loop thread right after the reply, before any later broadcast: no gap, no duplicate. */
static void resync(df_job *j, uint64_t from)
{
    df_session *s = j->s;
    uint64_t cur = atomic_load(&s->version);
    /* the ring keeps exact frames: a quantized connection always resyncs from a snapshot */
    int quant = (j->req.c->stream_enc & DF_STREAM_ENC_QUANTIZED) != 0;
    if (quant || (from != cur && !df_resync_covers(&s->resync, from, cur))) {
        s->srv->stats.resync_snapshots++;
        df_log(DF_LOG_DEBUG, "session %llu: resync from version %llu: snapshot of %llu (%s)",
               (unsigned long long)s->id, (unsigned long long)from, (unsigned long long)cur,
               quant ? "quantized stream" : from > cur ? "ahead of the session" : "not kept");
        send_snapshot(j);
        return;
    }
    s->srv->stats.resync_replays++;
    for (uint64_t v = from + 1; v <= cur && !j->req.c->closing; v++) {
        const df_resync_ver *e = df_resync_find(&s->resync, v);
        for (size_t i = 0; e && i < e->n && !j->req.c->closing; i++)
            df_req_reply_more(&j->req, e->frames[i]);
    }
}

/* df_session_subscribe, then the quantized group of the connection's encoding (stream_enc.h) */
static int subscribe_enc(df_session *s, df_conn *c, df_error *err)
{
    int was = 0;
    for (int i = 0; i < s->nsubs && !was; i++) was = s->subs[i] == c;
    int rc = df_session_subscribe(s, c, err);
    if (rc == DF_OK && (rc = df_stream_enc_join(s, c, err)) != DF_OK && !was)
        df_session_unsubscribe(s, c);
    return rc;
}

static void subscribe_done(df_job *j)
{
    if (!join(j, subscribe_enc)) return;
    df_session *s = j->s;
    const sub_req *b = j->body;
    df_msg_session_info info;
    df_session_info_fill(s, &info);
    df_req_reply_session_info(&j->req, &info);
    if (s->srv->hid_ops) /* replay devices wait for a subscriber (hid_manager.h) */
        s->srv->hid_ops->session_active(s->srv, s);
    if (b->flags & DF_SUBSCRIBE_FROM_VERSION) resync(j, b->from_version);
    else if (b->flags & DF_SUBSCRIBE_SNAPSHOT) send_snapshot(j);
}

static int subscribe_decode(const df_req *r, const uint8_t *p, void *body, uint64_t *sid,
                            df_error *err)
{
    df_msg_subscribe m;
    int rc = df_msg_subscribe_decode(p, r->len, &m, err);
    if (rc != DF_OK) return rc;
    *sid = m.session_id;
    sub_req *b = body;
    b->flags = m.flags;
    b->from_version = m.from_version;
    return rc;
}

const df_job_kind df_k_subscribe = {.body_size = sizeof(sub_req), .decode = subscribe_decode,
                                    .done = subscribe_done,
                                    .beside = DF_JOB_BESIDE_READ}; /* may join a move */

typedef struct knob {
    uint8_t param;
    double value;
} knob;

/* Sets a knob of the client's open stroke on the session (FIFO order): checked here, applied
 * by the commit (from the stroke's next update on). */
static void knob_done(df_job *j)
{
    knob *k = j->body;
    df_stroke *st = j->rc == DF_OK ? df_session_stroke(j->s, j->conn_id) : NULL;
    if (j->rc == DF_OK && !st)
        j->rc = df_error_set(&j->err, DF_ESTATE, "set_brush_param: no open stroke on session %llu",
                             (unsigned long long)j->s->id);
    if (st && (j->rc = df_h_brush_knob_check(st, k->param, k->value, &j->err)) == DF_OK) {
        df_stroke t = *st; /* shallow: only the scalar parameters change */
        switch (k->param) {
        case DF_BP_RADIUS: t.brush.radius = k->value; break;
        case DF_BP_NU: t.brush.nu = k->value; break;
        case DF_BP_STRENGTH: t.strength = k->value; break;
        case DF_BP_FALLOFF: t.brush.order = (int)k->value; break;
        case DF_BP_RATIO: t.brush.ratio = k->value; break;
        default: break;
        }
        j->change.stroke = st;
        j->change.set_params = 1;
        j->change.brush = t.brush;
        j->change.strength = t.strength;
    }
    df_job_commit(j);
}

static int knob_decode(const df_req *r, const uint8_t *p, void *body, uint64_t *sid,
                       df_error *err)
{
    df_msg_brush_param m;
    int rc = df_msg_brush_param_decode(p, r->len, &m, err);
    if (rc != DF_OK) return rc;
    knob *k = body;
    *sid = m.session_id;
    k->param = m.param;
    k->value = m.value;
    return rc;
}

const df_job_kind df_k_set_brush_param = {.body_size = sizeof(knob), .decode = knob_decode,
                                          .done = knob_done};
