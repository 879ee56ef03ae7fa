/* common.c — deformctl helpers shared by the command files (see ctl.h). */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <openssl/crypto.h>

#include "client/deformctl/ctl.h"
#include "proto/auth_mac.h"

int ctl_error(const ctl_ctx *ctx, const ctl_cmd *cmd, const char *source, int code,
              const char *msg, int exit_code)
{
    const char *prefix = strcmp(source, "server") == 0     ? "server: "
                         : strcmp(source, "rejected") == 0 ? "rejected: "
                                                           : "";
    const char *name = df_proto_error_name(code);
    const char *text = msg && msg[0] ? msg : "(no message)";
    if (cmd)
        fprintf(stderr, "%s %s: %s%s: %s\n", ctx->prog, cmd->name, prefix, name, text);
    else
        fprintf(stderr, "%s: %s%s: %s\n", ctx->prog, prefix, name, text);
    if (ctx->json)
        ctl_json_error(source, code, text, exit_code);
    return exit_code;
}

void ctl_json_error(const char *source, int code, const char *msg, int exit_code)
{
    printf("{\"ok\":false,\"exit\":%d,\"source\":\"%s\",\"code\":%d,\"name\":", exit_code,
           source, code);
    ctl_json_str(stdout, df_proto_error_name(code));
    printf(",\"message\":");
    ctl_json_str(stdout, msg);
    printf("}\n");
    fflush(stdout);
}

int ctl_fail(const ctl_ctx *ctx, const ctl_cmd *cmd, const df_client *c, const df_error *e)
{
    int remote = c && df_client_last_error_was_remote(c);
    if (c && !remote && (e->code == DF_EINVAL || e->code == DF_ELIMIT))
        /* refused locally by the message encoder: bad input (e.g. a --name too long) */
        return ctl_error(ctx, cmd, "usage", e->code, e->msg, CTL_EXIT_USAGE);
    return ctl_error(ctx, cmd, remote ? "server" : "client", e->code, e->msg, CTL_EXIT_SERVER);
}

df_client *ctl_connect(const ctl_ctx *ctx, const ctl_cmd *cmd)
{
    return ctl_connect_enc(ctx, cmd, 0, 0, 0);
}

/* the connect of ctl_connect_enc: df_client_connect_enc (stream trailer) when `trailer`, else the
 * original hello */
static int connect_to(const char *path, const ctl_ctx *ctx, const char *ca, int trailer,
                      uint8_t enc, double bound, df_client **c, df_error *e)
{
    if (trailer)
        return df_client_connect_enc(path, path ? NULL : ctx->host, ctx->port, ca, "deformctl",
                                     enc, bound, c, e);
    return path ? df_client_connect_unix(path, "deformctl", c, e)
                : df_client_connect_tcp_tls(ctx->host, ctx->port, "deformctl", ca, c, e);
}

df_client *ctl_connect_enc(const ctl_ctx *ctx, const ctl_cmd *cmd, int trailer, uint8_t enc,
                           double bound)
{
    df_error e;
    df_error_clear(&e);
    df_client *c = NULL;
    int rc;
    /* --key-file, else $DEFORMD_KEY_FILE: authenticate whenever a key is given (PROTOCOL.md
     * 4.3). A key file that cannot be used is a usage error, found before connecting. */
    const char *kf = ctx->key_file ? ctx->key_file : getenv("DEFORMD_KEY_FILE");
    uint8_t key[DF_AUTH_KEY_CAP_BYTES];
    size_t key_len = 0;
    if (kf && kf[0] && df_auth_key_load(kf, key, sizeof key, &key_len, &e) != DF_OK) {
        ctl_error(ctx, cmd, "usage", e.code, e.msg, CTL_EXIT_USAGE);
        return NULL;
    }
    if (ctx->tcp) {
        /* --tls-ca, else $DEFORMD_TLS_CA: TLS whenever a CA is given */
        const char *ca = ctx->tls_ca ? ctx->tls_ca : getenv("DEFORMD_TLS_CA");
        rc = connect_to(NULL, ctx, ca && ca[0] ? ca : NULL, trailer, enc, bound, &c, &e);
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
        rc = connect_to(p, ctx, NULL, trailer, enc, bound, &c, &e);
    }
    if (rc == DF_OK && key_len) rc = df_client_authenticate(c, key, key_len, &e);
    else if (rc == DF_OK && df_client_server_info(c)->auth_required)
        rc = df_error_set(&e, DF_EPROTO_AUTH, "the daemon requires authentication on this "
                          "connection: give --key-file FILE (or set DEFORMD_KEY_FILE)");
    OPENSSL_cleanse(key, sizeof key);
    if (rc) {
        ctl_fail(ctx, cmd, c, &e);
        df_client_close(c);
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
    if (arg[0] == '\0')
        return df_error_set(err, DF_EINVAL, "SESSION is empty: give a session id or name");
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
