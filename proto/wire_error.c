/* wire_error.c — names of the wire error codes (see wire_error.h). */
#include "proto/wire_error.h"

const char *df_proto_error_name(int code)
{
    switch (code) {
    case DF_EPROTO_BADMAGIC: return "EPROTO_BADMAGIC";
    case DF_EPROTO_BADVERSION: return "EPROTO_BADVERSION";
    case DF_EPROTO_BADTYPE: return "EPROTO_BADTYPE";
    case DF_EPROTO_TOOLARGE: return "EPROTO_TOOLARGE";
    case DF_EPROTO_TRUNCATED: return "EPROTO_TRUNCATED";
    case DF_EPROTO_TRAILING: return "EPROTO_TRAILING";
    case DF_EPROTO_BADFLAGS: return "EPROTO_BADFLAGS";
    case DF_EPROTO_RESERVED: return "EPROTO_RESERVED";
    case DF_EPROTO_BUSY: return "EPROTO_BUSY";
    case DF_EPROTO_AUTH: return "EPROTO_AUTH";
    case DF_EPROTO_CHUNK: return "EPROTO_CHUNK";
    default: return df_error_name(code);
    }
}

int df_proto_error_valid(int code)
{
    return (code <= DF_EINVAL && code >= DF_EMOVED) ||
           (code <= DF_EPROTO_BADMAGIC && code >= DF_EPROTO_CHUNK);
}
