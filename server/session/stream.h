/* stream.h — turning a session's new positions into the next version's displacement frames.
 *
 * What the server sends (see proto/PROTOCOL.md): for each vertex i the float32 displacement
 * u_i = fl32(x_i - X_i) of the new double position x_i from the double BASE position X_i,
 * computed in double and rounded once. A frame lists every vertex whose u_i bit pattern changed
 * since the previous version (sparse rows: index + u), or all of them (dense) when that is
 * smaller. A client holding the same u array and fl32(X) computes positions fl32(fl32(X_i) + u_i);
 * since every client applies the same u bits, all of them reconstruct byte-identical float32
 * positions, equal to what get-mesh reports. Big versions are split into chunks of at most
 * DF_STREAM_CHUNK_BYTES (DF_FLAG_MORE on all but the last). */
#ifndef DF_SERVER_STREAM_H
#define DF_SERVER_STREAM_H

#include <stdint.h>

#include "proto/messages.h"
#include "server/net/sbuf.h"
#include "server/session/session.h"

/* A growable list of frames. */
typedef struct df_frames {
    df_sbuf **v;
    size_t n, cap;
} df_frames;

/* Appends (moves the reference in). DF_ENOMEM releases the frame. */
int df_frames_push(df_frames *f, df_sbuf *b);

/* Releases every frame and the list. */
void df_frames_clear(df_frames *f);

/* Allocates the session's scratch buffers when missing (worker of the running job).
 * Errors: DF_ENOMEM. */
int df_stream_scratch(df_session *s, df_error *err);

/* Encodes `pos` (s->nv x 3 doubles) as version `version` (0: s->version + 1) of kind `kind`,
 * the change from the published displacements `prev` (NULL: s->uf), without changing the
 * session (pure; the compute of a job, commit.h): the new published displacements into `newu`
 * (nv x 3, a buffer the job owns or borrowed) and the version's frames appended to `out` (as
 * df_stream_publish). Uses the scratch index and row buffers of the running job
 * (df_stream_scratch first). Errors: as df_stream_publish (nothing appended). */
int df_stream_encode(const df_session *s, const float *prev, uint64_t version,
                     const double *pos, uint8_t kind, const df_msg_progress *progress,
                     uint64_t req_id, float *newu, df_frames *out, uint32_t *changed,
                     df_error *err);

/* Publishes `pos` (s->nv x 3 doubles) as version s->version + 1 of kind `kind` (df_change_kind):
 * updates s->uf and s->version (NOT s->cur) and appends the event frames to `out`. With
 * `progress` non-NULL the frames are DF_MSG_PROGRESS events carrying its fields and request id
 * `req_id`; else DF_MSG_DISPLACEMENT events with id 0. *changed receives the rows that changed
 * (may be NULL). Errors: DF_EINVAL when a position or displacement is not finite in float32
 * (the float32 displacement, or the load-time float32 position plus it; nothing changes),
 * DF_ENOMEM. Runs on the session's worker (or the loop thread in loop-only jobs). */
int df_stream_publish(df_session *s, const double *pos, uint8_t kind,
                      const df_msg_progress *progress, uint64_t req_id, df_frames *out,
                      uint32_t *changed, df_error *err);

/* Appends a dense snapshot of the published state (kind DF_CHANGE_SNAPSHOT, version = current,
 * base_version 0) as reply frames (flags REPLY, MORE on all but the last) to request `req_id`
 * of type `type` (DF_MSG_SNAPSHOT), or as EVENT frames carrying `req_id` (the subscribe's) when
 * `type` is DF_MSG_DISPLACEMENT. Errors: DF_ENOMEM. */
int df_stream_snapshot(df_session *s, uint16_t type, uint64_t req_id, df_frames *out,
                       df_error *err);

/* Current published float32 positions fl32(fl32(X) + u) into xyz (nv x 3). */
void df_stream_positions(const df_session *s, float *xyz);

#endif
