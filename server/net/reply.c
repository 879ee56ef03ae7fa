/* reply.c — frame builders and reply senders (see reply.h). */
#include "server/net/reply.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>

#include "server/net/conn.h"
#include "server/log.h"

df_sbuf *df_sbuf_from_buf(df_buf *b)
{
    df_sbuf *s = df_sbuf_adopt(b->data, b->len);
    if (s) df_buf_init(b);
    return s;
}

#define DF_OUT_DEF(T)                                                                         \
    df_sbuf *df_out_##T(uint16_t type, uint16_t flags, uint64_t request_id, const df_msg_##T *m, \
                        df_error *err)                                                        \
    {                                                                                         \
        df_buf b;                                                                             \
        size_t start;                                                                         \
        df_buf_init(&b);                                                                      \
        int rc = df_frame_begin(&b, type, flags, request_id, &start, err);                    \
        if (rc == DF_OK) rc = df_msg_##T##_encode(m, &b, err);                                \
        if (rc == DF_OK) rc = df_frame_end(&b, start, err);                                   \
        df_sbuf *s = rc == DF_OK ? df_sbuf_from_buf(&b) : NULL;                               \
        if (!s) {                                                                             \
            if (rc == DF_OK) df_error_set(err, DF_ENOMEM, "out of memory building a frame");  \
            df_buf_free(&b);                                                                  \
        }                                                                                     \
        return s;                                                                             \
    }                                                                                         \
    void df_reply_##T(df_conn *c, uint16_t type, uint64_t request_id, const df_msg_##T *m,    \
                      int final)                                                              \
    {                                                                                         \
        df_error err;                                                                         \
        df_sbuf *s = df_out_##T(type, DF_FLAG_REPLY, request_id, m, &err);                    \
        if (final && c->pending > 0) c->pending--;                                            \
        if (!s) {                                                                             \
            df_log(DF_LOG_ERROR, "encoding a %s reply failed: %s", df_msg_type_name(type),    \
                   err.msg);                                                                  \
            df_reply_error(c, type, request_id, DF_EINTERNAL, "server could not encode: %s",  \
                           err.msg);                                                          \
            return;                                                                           \
        }                                                                                     \
        c->srv->stats.requests_ok += final ? 1 : 0;                                           \
        df_conn_send(c, s);                                                                   \
        df_sbuf_unref(s);                                                                     \
    }
DF_OUT_DEF(hello_reply)
DF_OUT_DEF(auth)
DF_OUT_DEF(ping)
DF_OUT_DEF(session_info)
DF_OUT_DEF(load_reply)
DF_OUT_DEF(session_list)
DF_OUT_DEF(session_ref)
DF_OUT_DEF(ack)
DF_OUT_DEF(move_result)
DF_OUT_DEF(mesh_chunk)
DF_OUT_DEF(disp)
DF_OUT_DEF(progress)
DF_OUT_DEF(stats)
DF_OUT_DEF(shm_info)
DF_OUT_DEF(shm_ref)
DF_OUT_DEF(brush_state)
DF_OUT_DEF(brush_cursor)
DF_OUT_DEF(device_info)
DF_OUT_DEF(device_list)
DF_OUT_DEF(access_info)
DF_OUT_DEF(peer_list)
DF_OUT_DEF(work_progress)

void df_reply_error(df_conn *c, uint16_t type, uint64_t request_id, int code, const char *fmt, ...)
{
    char msg[DF_ERROR_MSG_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (!df_proto_error_valid(code)) code = DF_EINTERNAL;
    df_buf b;
    df_buf_init(&b);
    df_error err;
    if (df_msg_error_frame(&b, type, request_id, code, &err, "%s", msg) != DF_OK) {
        df_buf_free(&b);
        df_conn_close(c, "out of memory building an error frame", 1);
        return;
    }
    df_sbuf *s = df_sbuf_from_buf(&b);
    if (!s) {
        df_buf_free(&b);
        df_conn_close(c, "out of memory building an error frame", 1);
        return;
    }
    df_log(DF_LOG_DEBUG, "client %llu: %s #%llu -> %s: %s", (unsigned long long)c->id,
           df_msg_type_name(type), (unsigned long long)request_id, df_proto_error_name(code), msg);
    df_conn_send(c, s);
    df_sbuf_unref(s);
}

void df_reply_fail(df_conn *c, uint16_t type, uint64_t request_id, const df_error *e)
{
    if (c->pending > 0) c->pending--;
    c->srv->stats.requests_failed++;
    df_reply_error(c, type, request_id, e->code ? e->code : DF_EINTERNAL, "%s",
                   e->msg[0] ? e->msg : df_error_name(e->code));
}
