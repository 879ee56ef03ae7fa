/* dispatch.h — message type -> handler for the frames a client sends.
 *
 * Every request is answered: a reply frame (DF_FLAG_REPLY) with the request's id, or an error
 * frame (DF_FLAG_REPLY | DF_FLAG_ERROR) with a stable DF_E* code and a message; an erroneous
 * request changes nothing. Requests that touch a session are queued on the session's FIFO and
 * answered when applied. */
#ifndef DF_SERVER_DISPATCH_H
#define DF_SERVER_DISPATCH_H

#include <stdint.h>

#include "proto/frame.h"
#include "server/server.h"

/* Handles one complete, framing-valid frame of connection `c`: hdr is decoded, payload has
 * hdr->payload_len bytes (valid only during the call). Refused, not executed: request id 0
 * (EINVAL as an ERROR event), REPLY/EVENT/ERROR flags (EPROTO_BADFLAGS), a type that is not a
 * request (EPROTO_BADTYPE, answered with that type). */
void df_dispatch_frame(df_conn *c, const df_frame_header *hdr, const uint8_t *payload);

#endif
