/* frame_codec.h — encoding, decoding and validating the fixed frame header of proto/frame.h.
 *
 * Receive loop sketch:  while (have >= DF_FRAME_HEADER_SIZE) { rc = df_frame_header_decode(...);
 *   if (rc < 0 && df_frame_error_is_fatal(rc)) close; if (have < 24 + h.payload_len) wait;
 *   else if (rc < 0) reply error and skip the payload; else dispatch h.type on the payload }
 * Send:  df_frame_begin(&out, type, flags, id, &start, err); df_msg_X_encode(&m, &out, err);
 *        df_frame_end(&out, start, err);
 */
#ifndef DF_PROTO_FRAME_CODEC_H
#define DF_PROTO_FRAME_CODEC_H

#include <stddef.h>
#include <stdint.h>

#include "core/common/df_error.h"
#include "proto/buf.h"
#include "proto/frame.h"
#include "proto/wire_error.h"

#define DF_PROTO_VERSION_MIN 1u /* oldest protocol version this code speaks */

#define DF_FLAGS_KNOWN (DF_FLAG_REPLY | DF_FLAG_EVENT | DF_FLAG_ERROR | DF_FLAG_MORE)

/* Writes `h` into out[0 .. 24) little-endian. Validates like the decoder (magic, version,
 * reserved, flags, payload_len); DF_OK or the DF_EPROTO_* code, `out` untouched on error. */
int df_frame_header_encode(const df_frame_header *h, uint8_t out[DF_FRAME_HEADER_SIZE],
                           df_error *err);

/* Parses the header at p[0 .. n). Checks, in this order: n >= 24 (else DF_EPROTO_TRUNCATED),
 * magic (DF_EPROTO_BADMAGIC), payload_len <= DF_MAX_FRAME_PAYLOAD (DF_EPROTO_TOOLARGE), version
 * in [DF_PROTO_VERSION_MIN, DF_PROTO_VERSION] (DF_EPROTO_BADVERSION), reserved == 0
 * (DF_EPROTO_RESERVED), flags (DF_EPROTO_BADFLAGS: unknown bits, REPLY with EVENT, ERROR without
 * REPLY unless type is DF_MSG_ERROR). The message type is NOT checked (an unknown type is
 * answered, not fatal; see df_msg_type_valid). On any error except TRUNCATED and BADMAGIC, `*h`
 * is still filled so the caller can skip the payload and echo request_id; on DF_OK it is
 * filled as well. */
int df_frame_header_decode(const uint8_t *p, size_t n, df_frame_header *h, df_error *err);

/* 1 when a header error leaves the byte stream unusable (BADMAGIC, TOOLARGE, BADVERSION): the
 * receiver sends one DF_MSG_ERROR frame and closes. 0 for errors answered with an error reply
 * after skipping payload_len bytes. */
int df_frame_error_is_fatal(int code);

/* Appends a header with payload_len 0 to `b` and stores its offset in `*start`; follow with the
 * payload and df_frame_end. Validates type != 0 and flags like the decoder. */
int df_frame_begin(df_buf *b, uint16_t type, uint16_t flags, uint64_t request_id, size_t *start,
                   df_error *err);

/* Patches the payload_len of the header at `start` to b->len - start - 24. DF_EPROTO_TOOLARGE
 * (and b->len rolled back to `start`) when the payload exceeds DF_MAX_FRAME_PAYLOAD;
 * DF_EINVAL when `start` is not a header begun in `b`. */
int df_frame_end(df_buf *b, size_t start, df_error *err);

#endif
