/* stream_enc.h — the negotiated stream encodings of a session's subscribers (PROTOCOL.md 4.2,
 * 4.40, 4.41): quantized deltas per encoding group and per-frame zstd compression.
 *
 * A connection's encoding is fixed by its HELLO (df_conn.stream_enc, .stream_err). Exact
 * subscribers (encoding 0) get the broadcast frames unchanged. For the others, each broadcast
 * DISPLACEMENT / PROGRESS frame (one chunk of a version) is turned, once per variant, into:
 *  - QUANTIZED with error bound E: a QDISP frame. The session keeps one group per distinct E
 *    (df_qgroup): K[3 i + k], the quantized displacement the group's clients hold, in steps of
 *    q = 2E. K is always floor(u / q + 0.5) of the exact published float32 displacement u
 *    (computed in double), so |q K - u| <= E at every version and nothing accumulates: a row
 *    whose new K differs from the held one is sent as the change dK, the others are left out.
 *    A client that took an exact snapshot of u computes the same K itself.
 *  - ZSTD: the frame (exact, or the QDISP of its group) compressed as a ZFRAME when that is
 *    smaller, else the frame itself.
 * Loop thread only (the groups are updated in broadcast order). */
#ifndef DF_SERVER_STREAM_ENC_H
#define DF_SERVER_STREAM_ENC_H

#include <stdint.h>

#include "server/net/sbuf.h"
#include "server/session/session.h"

/* Distinct error bounds (quantized groups) one session streams at once: with their zstd forms
 * and the exact zstd one, every variant of a broadcast frame fits df_enc_variants. */
#define DF_QGROUP_MAX 15

/* One quantized encoding group of a session. */
typedef struct df_qgroup {
    double err;                  /* the clients' error bound E (mesh units) */
    double step;                 /* q = 2E */
    int64_t *K;                  /* nv x 3 quantized displacements held by the group's clients */
} df_qgroup;

/* Adds the group of subscriber `c` (when its encoding is QUANTIZED and the session has no group
 * for its error bound yet), initialized from the published displacements s->uf (the version
 * the subscribe answers with); its 24 bytes a vertex are charged to memory_max_mb (membudget.h
 * DF_MEM_STREAM, released by prune / free). Call right after df_session_subscribe succeeds.
 * DF_OK, DF_ELIMIT (over the memory budget: the message names memory_max_mb and the bytes),
 * DF_ENOMEM; nothing changed on error. */
int df_stream_enc_join(df_session *s, const df_conn *c, df_error *err);

/* Frees the groups no subscriber of `s` uses any more (after an unsubscribe or a close), or
 * every group when s->nsubs is 0. */
void df_stream_enc_prune(df_session *s);

/* Frees every group of `s` (session destroy). */
void df_stream_enc_free(df_session *s);

/* The frames one broadcast frame becomes for each encoding among the subscribers: a small
 * cache, one entry per (encoding, error bound) in use; built by df_stream_enc_prepare. */
typedef struct df_enc_variant {
    uint8_t enc;                 /* DF_STREAM_ENC_* bits */
    double err;                  /* the error bound for QUANTIZED, else 0 */
    df_sbuf *frame;              /* the frame to send (a reference), NULL when it failed */
} df_enc_variant;

typedef struct df_enc_variants {
    df_enc_variant v[2 * DF_QGROUP_MAX + 2];
    int n;
} df_enc_variants;

/* 1 when `frame` is a stream frame the encodings apply to (a DISPLACEMENT or PROGRESS event). */
int df_stream_enc_applies(const df_sbuf *frame);

/* The frame subscriber `c` gets for the stream frame `frame`: `frame` itself (a new reference)
 * for an exact subscriber, else its variant from `vs`, built on first use (updating the
 * quantized group once per broadcast frame). NULL when the variant could not be built (out of
 * memory, or a frame that does not decode: logged); the caller then drops the subscriber's
 * frame and the subscriber must resync. Release the variants with df_stream_enc_variants_clear. */
df_sbuf *df_stream_enc_frame(df_session *s, const df_conn *c, df_sbuf *frame, df_enc_variants *vs);

/* df_stream_enc_frame for encoding `enc` with error bound `e` (not a connection's). */
df_sbuf *df_stream_enc_get(df_session *s, uint8_t enc, double e, df_sbuf *frame,
                           df_enc_variants *vs);

/* Builds the QUANTIZED variant of every group of `s` for `frame` into `vs` (so every group's K
 * follows every stream frame, whether or not one of its subscribers takes it). */
void df_stream_enc_follow(df_session *s, df_sbuf *frame, df_enc_variants *vs);

/* Drops the references of `vs`. */
void df_stream_enc_variants_clear(df_enc_variants *vs);

/* zstd-compresses the payload of `frame` into a new ZFRAME frame (same request id, flags), or
 * returns a new reference to `frame` when compression does not make it smaller. NULL when out
 * of memory. Pure apart from the allocation; any thread. */
df_sbuf *df_stream_enc_zstd(df_sbuf *frame);

#endif
