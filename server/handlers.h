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

/* Largest |strength| of a brush stroke (BRUSH_BEGIN, SET_BRUSH_PARAM). */
#define DF_BRUSH_MAX_STRENGTH 1e6

/* Whether knob `param` (df_brush_param_id) = value may be applied to the open stroke `st`: the
 * stroke with that value must pass the Kelvinlet engine's rules (nu in [-1, 0.5] or +-inf,
 * radii radius * ratio^k within [1e-6, 1e6], order 1..8, no singular normalization) and
 * |strength| <= DF_BRUSH_MAX_STRENGTH. DF_OK, or the engine's code (DF_EINVAL, DF_ESINGULAR)
 * with a message naming the parameter and value; `st` is never changed. */
int df_h_brush_knob_check(const df_stroke *st, uint8_t param, double value, df_error *err);

/* Frees a connection's unfinished upload (NULL-safe). */
void df_upload_free(struct df_upload *u);

#endif
