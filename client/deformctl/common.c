/* common.c — deformctl helpers shared by the command files (see ctl.h). */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "client/deformctl/ctl.h"

int ctl_fail(const ctl_ctx *ctx, const ctl_cmd *cmd, const df_client *c, const df_error *e)
{
    int remote = c && df_client_last_error_was_remote(c);
    fprintf(stderr, "%s %s: %s%s: %s\n", ctx->prog, cmd->name, remote ? "server: " : "",
            df_proto_error_name(e->code), e->msg[0] ? e->msg : "(no message)");
    if (c && !remote && (e->code == DF_EINVAL || e->code == DF_ELIMIT))
        return CTL_EXIT_USAGE; /* refused locally by the message encoder: bad input */
    return CTL_EXIT_SERVER;
}

df_client *ctl_connect(const ctl_ctx *ctx, const ctl_cmd *cmd)
{
    df_error e;
    df_error_clear(&e);
    df_client *c = NULL;
    int rc;
    if (ctx->tcp) {
        char host[256];
        int port = 0;
        if (dc_cli_hostport(ctx->tcp, host, sizeof host, &port, &e)) {
            ctl_usage_error(ctx, cmd, e.msg);
            return NULL;
        }
        rc = df_client_connect_tcp(host, port, "deformctl", &c, &e);
    } else {
        char path[256];
        const char *p = ctx->socket;
        if (!p) {
            if (dc_cli_default_socket(path, sizeof path, &e)) {
                ctl_fail(ctx, cmd, NULL, &e);
                return NULL;
            }
            p = path;
        }
        rc = df_client_connect_unix(p, "deformctl", &c, &e);
    }
    if (rc) {
        ctl_fail(ctx, cmd, NULL, &e);
        return NULL;
    }
    return c;
}

int ctl_session_id(df_client *c, const char *arg, uint64_t *id, df_error *err)
{
    char *end = NULL;
    errno = 0;
    unsigned long long v = strtoull(arg, &end, 10);
    if (end != arg && *end == '\0' && errno == 0 && v != 0 && arg[0] != '-') {
        *id = v;
        return DF_OK;
    }
    df_msg_session_info info;
    int rc = df_client_open_session(c, 0, arg, &info, err);
    if (rc)
        return rc;
    *id = info.session_id;
    return DF_OK;
}

void ctl_json_str(FILE *f, const char *s)
{
    fputc('"', f);
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        if (*p == '"' || *p == '\\')
            fprintf(f, "\\%c", *p);
        else if (*p == '\n')
            fputs("\\n", f);
        else if (*p == '\t')
            fputs("\\t", f);
        else if (*p < 0x20)
            fprintf(f, "\\u%04x", *p);
        else
            fputc(*p, f);
    }
    fputc('"', f);
}

void ctl_json_num(FILE *f, double v)
{
    if (isfinite(v))
        fprintf(f, "%.17g", v);
    else
        fputs("null", f);
}

const char *ctl_change_name(unsigned kind)
{
    switch (kind) {
    case DF_CHANGE_BRUSH: return "brush";
    case DF_CHANGE_BRUSH_CANCEL: return "brush_cancel";
    case DF_CHANGE_HANDLE_MOVE: return "handle_move";
    case DF_CHANGE_UNDO: return "undo";
    case DF_CHANGE_REDO: return "redo";
    case DF_CHANGE_RESET_REST: return "reset_rest";
    case DF_CHANGE_SNAPSHOT: return "snapshot";
    default: return "unknown";
    }
}
