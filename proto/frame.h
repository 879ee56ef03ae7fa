/* frame.h — the fixed frame header of the deformd wire protocol (see proto/PROTOCOL.md).
 *
 * Every message, in both directions, is one frame: a 24-byte little-endian header followed by
 * `payload_len` bytes of payload. Offsets:
 *    0  u32  magic        DF_FRAME_MAGIC ("DFMD" as bytes 'D','F','M','D')
 *    4  u16  version      DF_PROTO_VERSION
 *    6  u16  type         message type (proto/messages.h)
 *    8  u16  flags        DF_FLAG_* bits
 *   10  u16  reserved     must be 0
 *   12  u64  request_id   chosen by the client; replies echo it; events carry 0 unless they
 *                         answer a request (progress of a handle move carries the move's id)
 *   20  u32  payload_len  bytes that follow, <= DF_MAX_FRAME_PAYLOAD
 */
#ifndef DF_PROTO_FRAME_H
#define DF_PROTO_FRAME_H

#include <stddef.h>
#include <stdint.h>

/* DF_FRAME_MAGIC, DF_PROTO_VERSION, DF_FRAME_HEADER_SIZE, DF_MAX_FRAME_PAYLOAD and the flags
 * come from the wire schema. */
#include "proto/wire_schema.h"

#define DF_X_FLAG(n, v) DF_FLAG_##n = (v),
enum { DF_WIRE_FLAGS(DF_X_FLAG) };
#undef DF_X_FLAG

typedef struct df_frame_header {
    uint32_t magic;
    uint16_t version;
    uint16_t type;
    uint16_t flags;
    uint16_t reserved;
    uint64_t request_id;
    uint32_t payload_len;
} df_frame_header;

#endif
