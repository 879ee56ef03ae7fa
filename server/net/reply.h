/* reply.h — building frames into shared buffers and sending replies/errors (loop thread for the
 * send functions; the df_out_* builders are pure and thread-safe).
 *
 * df_out_X(type, flags, request_id, &msg, err) encodes one whole frame (header + df_msg_X body)
 * into a new df_sbuf (one reference) or returns NULL with err set (DF_EINVAL for a message the
 * proto encoder rejects, DF_ENOMEM). df_reply_X(c, type, request_id, &msg) builds a
 * DF_FLAG_REPLY frame and queues it on `c` (an encode failure becomes an EINTERNAL error reply),
 * and decrements c->pending when `final` is 1. */
#ifndef DF_SERVER_REPLY_H
#define DF_SERVER_REPLY_H

#include <stdint.h>

#include "proto/messages.h"
#include "server/net/sbuf.h"
#include "server/server.h"

/* Moves the bytes of `b` into a new shared buffer (b is re-initialized). NULL when out of memory
 * (b untouched). */
df_sbuf *df_sbuf_from_buf(df_buf *b);

#define DF_OUT_DECL(T)                                                                        \
    df_sbuf *df_out_##T(uint16_t type, uint16_t flags, uint64_t request_id, const df_msg_##T *m, \
                        df_error *err);                                                       \
    void df_reply_##T(df_conn *c, uint16_t type, uint64_t request_id, const df_msg_##T *m,    \
                      int final);
DF_OUT_DECL(hello_reply)
DF_OUT_DECL(auth)
DF_OUT_DECL(ping)
DF_OUT_DECL(session_info)
DF_OUT_DECL(load_reply)
DF_OUT_DECL(session_list)
DF_OUT_DECL(session_ref)
DF_OUT_DECL(ack)
DF_OUT_DECL(move_result)
DF_OUT_DECL(mesh_chunk)
DF_OUT_DECL(disp)
DF_OUT_DECL(progress)
DF_OUT_DECL(stats)
DF_OUT_DECL(shm_info)
DF_OUT_DECL(shm_ref)
DF_OUT_DECL(brush_state)
DF_OUT_DECL(brush_cursor)
DF_OUT_DECL(device_info)
DF_OUT_DECL(device_list)
DF_OUT_DECL(access_info)
DF_OUT_DECL(peer_list)
DF_OUT_DECL(work_progress)
#undef DF_OUT_DECL

/* Sends an error reply to request (type, request_id) with wire code `code` and a printf-style
 * message (truncated to DF_MAX_ERROR_MSG_LEN): flags REPLY|ERROR and the request's type (also an
 * unknown one), or, for request_id 0, a connection-level ERROR event (type ERROR, flags ERROR;
 * df_msg_error_frame). Decrements nothing. */
void df_reply_error(df_conn *c, uint16_t type, uint64_t request_id, int code, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));

/* Answers a finished request with an error from `e` and decrements c->pending. */
void df_reply_fail(df_conn *c, uint16_t type, uint64_t request_id, const df_error *e);

#endif
