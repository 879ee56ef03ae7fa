/* req.h — a request being answered: the requester, the request's type and id, and whether it
 * has been answered.
 *
 * dispatch.c makes one df_req per request frame and hands it to the request's handler; a
 * handler that queues a session job copies it into the job (df_job.req, which holds a
 * reference on the connection). Every request is answered exactly once, through df_req_fail or
 * a final df_req_reply / df_req_reply_<msg> / df_req_ack: a second answer is a bug. It is
 * counted in the stats (`requests_double_answer`) and, while df_req_strict is set (the default
 * unless NDEBUG is defined), aborts the daemon so that tests catch it. Loop thread only. */
#ifndef DF_SERVER_REQ_H
#define DF_SERVER_REQ_H

#include <stdint.h>

#include "core/common/df_error.h"
#include "proto/messages.h"
#include "server/net/sbuf.h"
#include "server/server.h"

typedef struct df_req {
    df_server *srv;
    df_conn *c;            /* requester; NULL for internal requests (answers go nowhere) */
    uint16_t type;         /* request message type */
    uint64_t id;           /* request id */
    uint16_t flags;        /* frame flags (MORE for chunked uploads) */
    uint32_t len;          /* payload length */
    unsigned answered : 1; /* a final answer was sent (or dropped for a gone requester) */
    uint64_t origin_id;    /* requester id: 0 = c's connection id; an internal request on
                            * behalf of a device (c NULL) carries the device id, which keys its
                            * stroke like a connection id (device ids have bit 63 set) */
} df_req;

/* The requester id of `r`: origin_id when set, else the connection's id, else 0. */
static inline uint64_t df_req_origin(const df_req *r)
{
    return r->origin_id ? r->origin_id : r->c ? r->c->id : 0;
}

/* 1: a second answer aborts (debug builds); 0: it is only counted (release). */
extern int df_req_strict;

/* Marks `r` answered. Returns 1 the first time; on a second answer counts
 * stats.requests_double_answer, aborts when df_req_strict, and returns 0 (send nothing). */
int df_req_claim(df_req *r);

/* Answers `r` with the error `e` (reply frame REPLY|ERROR); decrements the requester's pending
 * count. Returns e->code (for `return df_req_fail(...)`). */
int df_req_fail(df_req *r, const df_error *e);

/* Sends the final reply frame `f` (built by the caller; the caller keeps its reference) and
 * counts the request ok. */
void df_req_reply(df_req *r, df_sbuf *f);

/* Sends a non-final frame of the answer (chunks, the snapshot after a subscribe's reply): no
 * accounting, no check. */
void df_req_reply_more(df_req *r, df_sbuf *f);

/* Final reply with an empty body (DEVICE_BIND, DEVICE_VIEW). */
void df_req_reply_empty(df_req *r);

/* Acks `r` with (session, version). */
void df_req_ack(df_req *r, uint64_t session_id, uint64_t version);

/* Final replies with a message body (reply.h's df_reply_X with final = 1, checked). */
#define DF_REQ_REPLY_DECL(T) void df_req_reply_##T(df_req *r, const df_msg_##T *m);
DF_REQ_REPLY_DECL(hello_reply)
DF_REQ_REPLY_DECL(auth)
DF_REQ_REPLY_DECL(ping)
DF_REQ_REPLY_DECL(session_info)
DF_REQ_REPLY_DECL(load_reply)
DF_REQ_REPLY_DECL(session_list)
DF_REQ_REPLY_DECL(move_result)
DF_REQ_REPLY_DECL(stats)
DF_REQ_REPLY_DECL(shm_info)
DF_REQ_REPLY_DECL(brush_state)
DF_REQ_REPLY_DECL(device_list)
DF_REQ_REPLY_DECL(access_info)
DF_REQ_REPLY_DECL(peer_list)
#undef DF_REQ_REPLY_DECL

#endif
