/* df_error.c — recording and naming errors (see df_error.h). */
#include "core/common/df_error.h"

#include <stdio.h>
#include <string.h>

int df_error_set(df_error *err, int code, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        err->code = code;
        vsnprintf(err->msg, sizeof err->msg, fmt, ap);
        va_end(ap);
    }
    return code;
}

void df_error_clear(df_error *err)
{
    if (err) {
        err->code = DF_OK;
        err->msg[0] = '\0';
    }
}

const char *df_error_name(int code)
{
    switch (code) {
    case DF_OK: return "OK";
    case DF_EINVAL: return "EINVAL";
    case DF_ENOMEM: return "ENOMEM";
    case DF_ESINGULAR: return "ESINGULAR";
    case DF_EIO: return "EIO";
    case DF_EFORMAT: return "EFORMAT";
    case DF_ELIMIT: return "ELIMIT";
    case DF_ENOTFOUND: return "ENOTFOUND";
    case DF_ESTATE: return "ESTATE";
    case DF_EUNSUPPORTED: return "EUNSUPPORTED";
    case DF_EINTERNAL: return "EINTERNAL";
    case DF_EEXIST: return "EEXIST";
    case DF_EPERM: return "EPERM";
    case DF_EMOVED: return "EMOVED";
    default: return "EUNKNOWN";
    }
}
