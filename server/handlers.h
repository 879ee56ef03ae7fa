/* handlers.h — one handler per request type (dispatch.c routes to them; loop thread).
 *
 * Each handler decodes its payload `p` (r->len bytes, valid during the call) with the proto
 * decoder and either answers request `r` itself (df_req_*), or queues a session job that
 * answers it when applied (df_job_for_request: the job takes the request over), and returns
 * DF_OK; or it returns an error code with `err` filled, answered by the dispatcher. */
#ifndef DF_SERVER_HANDLERS_H
#define DF_SERVER_HANDLERS_H

#include <stdint.h>

#include "proto/messages.h"
#include "server/req.h"
#include "server/server.h"
#include "server/session.h"

#define DF_HANDLER(name) int df_h_##name(df_req *r, const uint8_t *p, df_error *err)
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

/* Decodes a session_ref request body `p` (r->len bytes) into *session_id. Errors: the
 * decoder's. */
int df_h_session_ref(const df_req *r, const uint8_t *p, uint64_t *session_id, df_error *err);

/* Decodes a session_ref request and submits a job of `kind` for it on that session
 * (df_job_for_request). DF_OK, or the decode / lookup / allocation error (nothing queued). */
struct df_job_kind;
int df_h_ref_job(df_req *r, const uint8_t *p, const struct df_job_kind *kind, df_error *err);

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
