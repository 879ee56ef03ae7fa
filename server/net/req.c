/* req.c — answering a request exactly once (see req.h). */
#include "server/net/req.h"

#include <stdlib.h>

#include "server/net/conn.h"
#include "server/log.h"
#include "server/net/reply.h"

#ifdef NDEBUG
int df_req_strict = 0;
#else
int df_req_strict = 1;
#endif

int df_req_claim(df_req *r)
{
    if (!r->answered) {
        r->answered = 1;
        return 1;
    }
    if (r->srv) r->srv->stats.requests_double_answer++;
    df_log(DF_LOG_ERROR, "%s #%llu answered twice (a bug)",
           df_msg_type_valid(r->type) ? df_msg_type_name(r->type) : "request",
           (unsigned long long)r->id);
    if (df_req_strict) abort();
    return 0;
}

int df_req_fail(df_req *r, const df_error *e)
{
    if (df_req_claim(r) && r->c) df_reply_fail(r->c, r->type, r->id, e);
    return e->code;
}

void df_req_reply(df_req *r, df_sbuf *f)
{
    if (!df_req_claim(r) || !r->c) return;
    if (r->c->pending > 0) r->c->pending--;
    r->c->srv->stats.requests_ok++;
    df_conn_send(r->c, f);
}

void df_req_reply_more(df_req *r, df_sbuf *f)
{
    if (r->c) df_conn_send(r->c, f);
}

void df_req_ack(df_req *r, uint64_t session_id, uint64_t version)
{
    df_msg_ack a = {.session_id = session_id, .version = version};
    if (df_req_claim(r) && r->c) df_reply_ack(r->c, r->type, r->id, &a, 1);
}

#define DF_REQ_REPLY_DEF(T)                                                                   \
    void df_req_reply_##T(df_req *r, const df_msg_##T *m)                                     \
    {                                                                                         \
        if (df_req_claim(r) && r->c) df_reply_##T(r->c, r->type, r->id, m, 1);                \
    }
DF_REQ_REPLY_DEF(hello_reply)
DF_REQ_REPLY_DEF(auth)
DF_REQ_REPLY_DEF(ping)
DF_REQ_REPLY_DEF(session_info)
DF_REQ_REPLY_DEF(load_reply)
DF_REQ_REPLY_DEF(session_list)
DF_REQ_REPLY_DEF(move_result)
DF_REQ_REPLY_DEF(stats)
DF_REQ_REPLY_DEF(shm_info)
DF_REQ_REPLY_DEF(brush_state)
DF_REQ_REPLY_DEF(device_list)
DF_REQ_REPLY_DEF(access_info)
DF_REQ_REPLY_DEF(peer_list)

void df_req_reply_empty(df_req *r)
{
    if (!df_req_claim(r) || !r->c) return;
    df_buf b;
    size_t start;
    df_error err;
    df_buf_init(&b);
    df_sbuf *s = NULL;
    if (df_frame_begin(&b, r->type, DF_FLAG_REPLY, r->id, &start, &err) == DF_OK &&
        df_frame_end(&b, start, &err) == DF_OK)
        s = df_sbuf_from_buf(&b);
    if (r->c->pending > 0) r->c->pending--;
    if (!s) {
        df_buf_free(&b);
        df_reply_error(r->c, r->type, r->id, DF_ENOMEM, "out of memory building a reply");
        return;
    }
    r->c->srv->stats.requests_ok++;
    df_conn_send(r->c, s);
    df_sbuf_unref(s);
}
