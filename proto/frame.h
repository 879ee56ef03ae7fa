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

#define DF_FRAME_MAGIC 0x444D4644u       /* bytes "DFMD" read as a little-endian u32 */
#define DF_PROTO_VERSION 1u
#define DF_FRAME_HEADER_SIZE 24u
#define DF_MAX_FRAME_PAYLOAD (64u << 20) /* 64 MiB: larger messages are chunked */

enum {
    DF_FLAG_REPLY = 1u << 0,  /* answers the request with the same request_id */
    DF_FLAG_EVENT = 1u << 1,  /* server-initiated (stream frames, progress) */
    DF_FLAG_ERROR = 1u << 2,  /* payload is an error body (code + message) */
    DF_FLAG_MORE = 1u << 3    /* more chunks of the same message follow */
};

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
