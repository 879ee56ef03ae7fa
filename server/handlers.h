/* handlers.h — one handler per request type (dispatch.c routes to them; loop thread).
 *
 * Each handler decodes its payload with the proto decoder and answers the request exactly once
 * (reply or error, which decrements c->pending), either right away or when its session job is
 * applied. `h` is the frame header, `p` the payload (h->payload_len bytes, valid during the
 * call). */
#ifndef DF_SERVER_HANDLERS_H
#define DF_SERVER_HANDLERS_H

#include <stdint.h>

#include "proto/messages.h"
#include "server/server.h"
#include "server/session.h"

#define DF_HANDLER(name) void df_h_##name(df_conn *c, const df_frame_header *h, const uint8_t *p)
DF_HANDLER(hello);
DF_HANDLER(auth);
DF_HANDLER(ping);
DF_HANDLER(load_mesh);
DF_HANDLER(list_sessions);
DF_HANDLER(open_session);
DF_HANDLER(close_session);
DF_HANDLER(subscribe);
DF_HANDLER(unsubscribe);
DF_HANDLER(stream_shm);
DF_HANDLER(stats);
DF_HANDLER(brush_begin);
DF_HANDLER(brush_update);
DF_HANDLER(brush_end);
DF_HANDLER(brush_cancel);
DF_HANDLER(set_brush_param);
DF_HANDLER(handles_set);
DF_HANDLER(handles_move);
DF_HANDLER(handles_get);
DF_HANDLER(reset_rest);
DF_HANDLER(undo);
DF_HANDLER(redo);
DF_HANDLER(get_mesh);
DF_HANDLER(snapshot);
#undef DF_HANDLER

/* Fills a session_info body from `s` (loop thread). */
void df_session_info_fill(const df_session *s, df_msg_session_info *out);

/* Looks up a live session for request (h, c); on failure answers ENOTFOUND and returns NULL. */
df_session *df_h_session(df_conn *c, const df_frame_header *h, uint64_t session_id);

/* Decodes a session_ref request body `p` and looks its session up; on failure answers the
 * decode error or ENOTFOUND and returns NULL. */
df_session *df_h_session_ref(df_conn *c, const df_frame_header *h, const uint8_t *p);

/* Frees a connection's unfinished upload (NULL-safe). */
void df_upload_free(struct df_upload *u);

#endif
