/* dispatch.c — message type -> handler (see dispatch.h). */
#include "server/handlers/dispatch.h"

#include "server/net/auth.h"
#include "server/net/conn.h"
#include "server/handlers/handlers.h"
#include "server/log.h"
#include "server/net/reply.h"
#include "server/net/req.h"

typedef int (*df_handler_fn)(df_req *r, const uint8_t *p, df_error *err);

/* Per request type: a loop-thread handler, or the job kind of a session request. */
static const struct {
    uint16_t type;
    df_handler_fn fn;
    const df_job_kind *kind;
} k_routes[] = {
    {DF_MSG_HELLO, df_h_hello, NULL},
    {DF_MSG_AUTH, df_h_auth, NULL},
    {DF_MSG_PING, df_h_ping, NULL},
    {DF_MSG_LOAD_MESH, df_h_load_mesh, NULL},
    {DF_MSG_LIST_SESSIONS, df_h_list_sessions, NULL},
    {DF_MSG_OPEN_SESSION, df_h_open_session, NULL},
    {DF_MSG_STATS, df_h_stats, NULL},
    {DF_MSG_DEVICES_LIST, df_h_devices_list, NULL},
    {DF_MSG_DEVICE_BIND, df_h_device_bind, NULL},
    {DF_MSG_DEVICE_VIEW, df_h_device_view, NULL},
    {DF_MSG_SESSION_ACCESS, df_h_session_access, NULL},
    {DF_MSG_JOIN, df_h_join, NULL},
    {DF_MSG_CLOSE_SESSION, NULL, &df_k_close_session},
    {DF_MSG_SUBSCRIBE, NULL, &df_k_subscribe},
    {DF_MSG_UNSUBSCRIBE, NULL, &df_k_unsubscribe},
    {DF_MSG_STREAM_SHM, NULL, &df_k_stream_shm},
    {DF_MSG_SESSION_PEERS, NULL, &df_k_session_peers},
    {DF_MSG_BRUSH_BEGIN, NULL, &df_k_brush_begin},
    {DF_MSG_BRUSH_UPDATE, NULL, &df_k_brush_update},
    {DF_MSG_BRUSH_END, NULL, &df_k_brush_end},
    {DF_MSG_BRUSH_CANCEL, NULL, &df_k_brush_cancel},
    {DF_MSG_SET_BRUSH_PARAM, NULL, &df_k_set_brush_param},
    {DF_MSG_BRUSH_STATE_GET, df_h_brush_state_get, NULL},
    {DF_MSG_BRUSH_STATE_SET, df_h_brush_state_set, NULL},
    {DF_MSG_HANDLES_SET, NULL, &df_k_handles_set},
    {DF_MSG_HANDLES_MOVE, NULL, &df_k_handles_move},
    {DF_MSG_HANDLES_GET, NULL, &df_k_handles_get},
    {DF_MSG_RESET_REST, NULL, &df_k_reset_rest},
    {DF_MSG_UNDO, NULL, &df_k_history},
    {DF_MSG_REDO, NULL, &df_k_history},
    {DF_MSG_GET_MESH, NULL, &df_k_get_mesh},
    {DF_MSG_SNAPSHOT, NULL, &df_k_snapshot},
};

void df_dispatch_frame(df_conn *c, const df_frame_header *h, const uint8_t *payload)
{
    df_handler_fn fn = NULL;
    const df_job_kind *kind = NULL;
    for (size_t i = 0; i < sizeof k_routes / sizeof k_routes[0]; i++)
        if (k_routes[i].type == h->type) {
            fn = k_routes[i].fn;
            kind = k_routes[i].kind;
        }
    if (h->request_id == 0) { /* PROTOCOL.md 1.3: id 0 is reserved for events */
        c->srv->stats.requests_failed++;
        df_reply_error(c, DF_MSG_ERROR, 0, DF_EINVAL,
                       "request id 0 is reserved for events: %s 0x%04x needs a non-zero "
                       "request id (not executed)",
                       df_msg_type_valid(h->type) ? df_msg_type_name(h->type) : "message type",
                       (unsigned)h->type);
        return;
    }
    if (h->flags & (DF_FLAG_REPLY | DF_FLAG_EVENT | DF_FLAG_ERROR)) {
        c->srv->stats.requests_failed++;
        df_reply_error(c, h->type, h->request_id, DF_EPROTO_BADFLAGS,
                       "frame flags 0x%04x: REPLY, EVENT and ERROR are not valid on a request",
                       (unsigned)h->flags);
        return;
    }
    if (!fn && !kind) {
        c->srv->stats.requests_failed++;
        df_reply_error(c, h->type, h->request_id, DF_EPROTO_BADTYPE,
                       "%s 0x%04x is not a request",
                       df_msg_type_valid(h->type) ? df_msg_type_name(h->type) : "message type",
                       (unsigned)h->type);
        return;
    }
    if ((h->flags & DF_FLAG_MORE) && h->type != DF_MSG_LOAD_MESH) {
        c->srv->stats.requests_failed++;
        df_reply_error(c, h->type, h->request_id, DF_EPROTO_BADFLAGS,
                       "%s: only load_mesh requests may be chunked (MORE flag)",
                       df_msg_type_name(h->type));
        return;
    }
    if (c->upload && h->type != DF_MSG_LOAD_MESH) {
        c->srv->stats.requests_failed++;
        df_reply_error(c, h->type, h->request_id, DF_EPROTO_CHUNK,
                       "%s: a chunked load_mesh upload is in progress; finish it first",
                       df_msg_type_name(h->type));
        return;
    }
    if (!c->hello_done && h->type != DF_MSG_HELLO && h->type != DF_MSG_PING) {
        c->srv->stats.requests_failed++;
        df_reply_error(c, h->type, h->request_id, DF_ESTATE, "%s: send HELLO first",
                       df_msg_type_name(h->type));
        return;
    }
    if (df_auth_blocks(c, h->type)) { /* key_file: TCP peers authenticate first (auth.h) */
        c->srv->stats.requests_failed++;
        df_reply_error(c, h->type, h->request_id, DF_EPROTO_AUTH,
                       "%s: authentication required: this server needs the key (AUTH, "
                       "PROTOCOL.md 4.3) before other requests on TCP (not executed)",
                       df_msg_type_name(h->type));
        return;
    }
    if (c->pending >= (int)DF_MAX_PENDING_REQUESTS) {
        c->srv->stats.requests_failed++;
        df_reply_error(c, h->type, h->request_id, DF_EPROTO_BUSY,
                       "more than %u unanswered requests; wait for replies",
                       (unsigned)DF_MAX_PENDING_REQUESTS);
        return;
    }
    if (c->srv->stopping) {
        c->srv->stats.requests_failed++;
        df_reply_error(c, h->type, h->request_id, DF_ESTATE, "server shutting down");
        return;
    }
    c->pending++;
    df_log(DF_LOG_DEBUG, "client %llu: %s #%llu (%u bytes)", (unsigned long long)c->id,
           df_msg_type_name(h->type), (unsigned long long)h->request_id,
           (unsigned)h->payload_len);
    df_req r = {.srv = c->srv, .c = c, .type = h->type, .id = h->request_id, .flags = h->flags,
                .len = h->payload_len};
    df_error err;
    int rc = fn ? fn(&r, payload, &err) : df_job_request(&r, payload, kind, &err);
    if (rc != DF_OK) df_req_fail(&r, &err); /* synchronous errors; a queued job answers later */
}
