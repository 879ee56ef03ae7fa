/* handlers.h — one handler per request type (dispatch.c routes to them; loop thread).
 *
 * Each handler decodes its payload `p` (r->len bytes, valid during the call) with the proto
 * decoder and answers request `r` itself (df_req_*) and returns DF_OK, or returns an error code
 * with `err` filled, answered by the dispatcher. Session requests are job kinds instead
 * (df_k_*, routed by dispatch.c to df_job_request): the job answers when applied. */
#ifndef DF_SERVER_HANDLERS_H
#define DF_SERVER_HANDLERS_H

#include <stdint.h>

#include "proto/messages.h"
#include "server/exec/job.h"
#include "server/net/req.h"
#include "server/server.h"
#include "server/session/session.h"

/* Requests answered on the loop thread at once (no session FIFO). */
#define DF_HANDLER(name) int df_h_##name(df_req *r, const uint8_t *p, df_error *err)
DF_HANDLER(hello);
DF_HANDLER(auth);
DF_HANDLER(ping);
DF_HANDLER(load_mesh);
DF_HANDLER(list_sessions);
DF_HANDLER(open_session);
DF_HANDLER(stats);
DF_HANDLER(brush_state_get); /* h_brush_state.c: the session brush (brush_state.h) */
DF_HANDLER(brush_state_set);
DF_HANDLER(devices_list); /* devices (HID): h_devices.c */
DF_HANDLER(device_bind);
DF_HANDLER(device_view);
DF_HANDLER(session_access); /* per-session access: h_access.c (membership.h) */
DF_HANDLER(join);
/* STATS of a device (stats_req.session_id = a device id, bit 63 set): h_devices.c */
#define DF_DEVICE_ID_BIT (1ull << 63)
int df_h_device_stats(df_req *r, uint64_t device_id, df_error *err);
#undef DF_HANDLER

/* Session requests: each is a job kind (decode, body, work, done; job.h) queued on its
 * session's FIFO by df_job_request. */
extern const df_job_kind df_k_close_session, df_k_subscribe, df_k_unsubscribe, df_k_stream_shm;
extern const df_job_kind df_k_brush_begin, df_k_brush_update, df_k_brush_end, df_k_brush_cancel;
extern const df_job_kind df_k_set_brush_param;
extern const df_job_kind df_k_handles_set, df_k_handles_move, df_k_handles_get, df_k_reset_rest;
extern const df_job_kind df_k_history; /* undo and redo */
extern const df_job_kind df_k_get_mesh, df_k_snapshot;
extern const df_job_kind df_k_session_peers; /* h_peers.c: who is subscribed (4.38) */

/* The SESSION_PEERS rows of `s` (PROTOCOL.md 4.38) as seen by connection `asker` (may be NULL):
 * one per subscriber in subscription order, at most `cap` (DF_MAX_PEERS on the wire); when the
 * asker is a subscriber beyond the cap, its row replaces the last. Flags: DF_PEER_SELF on the
 * asker's row, DF_PEER_EDIT when the subscriber's principal holds the edit right now (access.h),
 * DF_PEER_SHM for shared-memory subscribers. out->items is malloc'd (NULL when count is 0;
 * df_msg_peer_list_free). DF_OK or DF_ENOMEM (out untouched). Loop thread. */
int df_session_peers_fill(const df_session *s, const df_conn *asker, uint32_t cap,
                          df_msg_peer_list *out, df_error *err);

/* Fills a session_info body from `s` (loop thread). */
void df_session_info_fill(const df_session *s, df_msg_session_info *out);

/* DF_BRUSH_MAX_STRENGTH (largest |strength| of a stroke): server/session/brush_state.h. */

/* Whether knob `param` (df_brush_param_id) = value may be applied to the open stroke `st`: the
 * stroke with that value must pass the Kelvinlet engine's rules (nu in [-1, 0.5] or +-inf,
 * radii radius * ratio^k within [1e-6, 1e6], order 1..8, no singular normalization) and
 * |strength| <= DF_BRUSH_MAX_STRENGTH. DF_OK, or the engine's code (DF_EINVAL, DF_ESINGULAR)
 * with a message naming the parameter and value; `st` is never changed. */
int df_h_brush_knob_check(const df_stroke *st, uint8_t param, double value, df_error *err);

/* Frees a connection's unfinished upload (NULL-safe). */
void df_upload_free(struct df_upload *u);

#endif
