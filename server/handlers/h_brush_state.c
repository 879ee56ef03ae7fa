/* h_brush_state.c — the session brush: BRUSH_STATE_GET / BRUSH_STATE_SET (see handlers.h and
 * server/session/brush_state.h). Both are answered at once on the loop thread, beside the
 * session's job FIFO: the brush state is no mesh change (no version, no undo step), and a
 * BRUSH_BEGIN that takes fields from it copies them when it arrives, so every request sees the
 * state as of its arrival. */
#include <string.h>

#include "server/cluster/cluster.h"
#include "server/handlers/handlers.h"
#include "server/net/conn.h"
#include "server/net/reply.h"
#include "server/session/access.h"
#include "server/session/brush_state.h"
#include "server/session/session.h"

static df_session *find(df_req *r, uint64_t sid, df_error *err)
{
    df_session *s = df_session_find(r->srv, sid);
    if (!s && r->srv->cluster) df_cluster_route(r->srv, sid, &s, err); /* cluster.h */
    else if (!s)
        df_error_set(err, DF_ENOTFOUND, "%s: no session %llu", df_msg_type_name(r->type),
                     (unsigned long long)sid);
    else if (df_access_check(r, s, err) != DF_OK) /* observe (get) / edit (set), access.h */
        return NULL;
    return s;
}

int df_h_brush_state_get(df_req *r, const uint8_t *p, df_error *err)
{
    df_msg_session_ref m;
    int rc = df_msg_session_ref_decode(p, r->len, &m, err);
    if (rc != DF_OK) return rc;
    df_session *s = find(r, m.session_id, err);
    if (!s) return err->code;
    df_msg_brush_state out;
    df_brush_state_msg(s, 0, &out);
    df_req_reply_brush_state(r, &out);
    return DF_OK;
}

int df_h_brush_state_set(df_req *r, const uint8_t *p, df_error *err)
{
    df_msg_brush_state_set m;
    int rc = df_msg_brush_state_set_decode(p, r->len, &m, err);
    if (rc != DF_OK) return rc;
    df_session *s = find(r, m.session_id, err);
    if (!s) return err->code;
    df_brush_state v;
    df_brush_state_from_wire(&m.v, &v);
    df_origin who = {.kind = r->c ? DF_ORIGIN_CLIENT : DF_ORIGIN_NONE,
                     .id = r->c ? r->c->id : 0, .name = r->c ? r->c->name : ""};
    rc = df_brush_state_apply(s, m.mask, &v, &who, err);
    if (rc != DF_OK) return rc;
    if (r->c) r->srv->last_change_session = s->id; /* unbound devices follow it (hid_manager.h) */
    df_msg_brush_state out;
    df_brush_state_msg(s, m.mask, &out);
    df_req_reply_brush_state(r, &out);
    return DF_OK;
}
