/* wire_error.h — the error codes that travel in error bodies (proto/PROTOCOL.md, "Errors").
 *
 * The wire carries the DF_E* codes of core/common/df_error.h (-1 .. -11) plus the protocol
 * codes below (-100 ..). Codes are stable: never renumber, only append. */
#ifndef DF_PROTO_WIRE_ERROR_H
#define DF_PROTO_WIRE_ERROR_H

#include "core/common/df_error.h"

enum {
    DF_EPROTO_BADMAGIC = -100,   /* header magic is not "DFMD" (connection closed) */
    DF_EPROTO_BADVERSION = -101, /* header version not in [DF_PROTO_VERSION_MIN, DF_PROTO_VERSION] */
    DF_EPROTO_BADTYPE = -102,    /* unknown message type, or a type not valid in this direction */
    DF_EPROTO_TOOLARGE = -103,   /* payload_len > DF_MAX_FRAME_PAYLOAD (connection closed) */
    DF_EPROTO_TRUNCATED = -104,  /* payload shorter than its fields/counts require */
    DF_EPROTO_TRAILING = -105,   /* payload longer than its fields/counts require */
    DF_EPROTO_BADFLAGS = -106,   /* unknown flag bits or an impossible combination */
    DF_EPROTO_RESERVED = -107,   /* a reserved field is not 0 */
    DF_EPROTO_BUSY = -108,       /* more than max_pending_requests unanswered requests */
    DF_EPROTO_AUTH = -109,       /* authentication required or refused */
    DF_EPROTO_CHUNK = -110       /* a chunk sequence is out of order or inconsistent */
};

/* Short stable name of any wire error code: the DF_E* names of df_error.h ("EINVAL") plus
 * "EPROTO_BADMAGIC" etc.; "EUNKNOWN" otherwise. */
const char *df_proto_error_name(int code);

/* 1 if `code` is a code that may appear on the wire (0 excluded), else 0. */
int df_proto_error_valid(int code);

#endif
