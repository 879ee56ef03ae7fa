/* main.c — deformctl: command-line client of the deformd daemon (built on libdeformclient).
 *
 *   deformctl [--socket PATH | --tcp HOST:PORT] [--key-file FILE] [--tls-ca FILE] [--json]
 *             COMMAND [ARGS]
 *             [--help]
 *
 * Exit codes (ctl.h): 0 ok; 1 an error from the daemon, the daemon could not be reached, the
 * local Kelvinlet check of `brush` refused the stroke, or a local failure (e.g. writing --out);
 * 2 usage error (command line, global options included, or an unreadable input file).
 * Results go to stdout (one JSON object with --json); diagnostics to stderr; with --json an
 * error is also one JSON object on stdout (ctl_error). */
#include <inttypes.h>
#include <stdlib.h>
#include <string.h>

#include <openssl/crypto.h>

#include "client/deformctl/ctl.h"
#include "proto/auth_mac.h"

static const ctl_cmd *const GROUPS[] = {ctl_cmds_session, ctl_cmds_watch, ctl_cmds_brush, ctl_cmds_handles,
                                        ctl_cmds_mesh, ctl_cmds_brush_state, ctl_cmds_devices,
                                        ctl_cmds_access,

                                        ctl_cmds_preview};

static void usage_top(FILE *f)
{
    fprintf(f,
            "usage: deformctl [--socket PATH | --tcp HOST:PORT] [--key-file FILE]\n"
            "                 [--tls-ca FILE] [--json] COMMAND [ARGS]\n"
            "\nControl a running deformd daemon.\n\nCommands:\n");
    for (size_t g = 0; g < sizeof GROUPS / sizeof GROUPS[0]; g++)
        for (const ctl_cmd *c = GROUPS[g]; c->name; c++)
            fprintf(f, "  %-11s %s\n", c->name, c->summary);
    fprintf(f,
            "\nGlobal options (before or after the command):\n"
            "  --socket PATH      daemon Unix socket (default: $DEFORMD_SOCKET, else\n"
            "                     $XDG_RUNTIME_DIR/deformd.sock, else /run/deformd/deformd.sock)\n"
            "  --tcp HOST:PORT    connect over TCP instead of the Unix socket\n"
            "  --json             machine-readable JSON output on stdout\n"
            "  --key-file FILE    authenticate with the secret key in FILE (HMAC-SHA256,\n"
            "                     PROTOCOL.md 4.3; needed on TCP when the daemon has a key;\n"
            "                     default: $DEFORMD_KEY_FILE)\n"
            "  --tls-ca FILE      with --tcp: TLS 1.3, the daemon's certificate verified against\n"
            "                     the CA certificate(s) in FILE and the HOST of --tcp (default:\n"
            "                     $DEFORMD_TLS_CA)\n"
            "  --help             this text; `deformctl COMMAND --help` for a command\n"
            "\nExit status: 0 success; 1 error reported by the daemon (\"server: ...\"), the\n"
            "daemon could not be reached, a brush the Kelvinlet engine rejects locally\n"
            "(\"rejected: ...\") or a local failure such as an --out file that cannot be\n"
            "written; 2 usage error (unknown command or option, missing or bad value, bad\n"
            "--tcp HOST:PORT or --socket PATH, unreadable input file).\n"
            "With --json every error is also one JSON object on stdout:\n"
            "  {\"ok\":false,\"exit\":1,\"source\":\"server\",\"code\":-7,\"name\":\"ENOTFOUND\",\n"
            "   \"message\":\"...\"}   (source: usage, server, rejected or client)\n");
}

void ctl_usage_cmd(FILE *f, const char *prog, const ctl_cmd *cmd)
{
    fprintf(f, "usage: %s %s\n\n%s\n\nOptions:\n", prog, cmd->synopsis, cmd->summary);
    for (int i = CTL_NGLOBAL; i < cmd->nopts; i++)
        fprintf(f, "  %s\n", cmd->opts[i].help);
    fprintf(f, "  --help             this text\nGlobal options:\n");
    for (int i = 0; i < CTL_NGLOBAL; i++)
        fprintf(f, "  %s\n", cmd->opts[i].help);
}

int ctl_usage_error(const ctl_ctx *ctx, const ctl_cmd *cmd, const char *msg)
{
    if (ctx->json)
        ctl_json_error("usage", DF_EINVAL, msg, CTL_EXIT_USAGE);
    if (cmd)
        fprintf(stderr, "%s %s: %s\nTry '%s %s --help'.\n", ctx->prog, cmd->name, msg, ctx->prog,
                cmd->name);
    else
        fprintf(stderr, "%s: %s\nTry '%s --help'.\n", ctx->prog, msg, ctx->prog);
    return CTL_EXIT_USAGE;
}

static const ctl_cmd *find_cmd(const char *name)
{
    for (size_t g = 0; g < sizeof GROUPS / sizeof GROUPS[0]; g++)
        for (const ctl_cmd *c = GROUPS[g]; c->name; c++)
            if (strcmp(c->name, name) == 0)
                return c;
    return NULL;
}

/* Consumes global options before the command; returns the index of the command word, or -1
 * after printing the top-level help (exit 0), or -2 on a usage error. */
static int parse_globals(int argc, char **argv, ctl_ctx *ctx)
{
    int i = 1;
    while (i < argc && argv[i][0] == '-') {
        const char *a = argv[i];
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            usage_top(stdout);
            return -1;
        }
        if (strcmp(a, "--json") == 0) {
            ctx->json = 1;
            i++;
            continue;
        }
        const char **dst = strncmp(a, "--socket", 8) == 0     ? &ctx->socket
                           : strncmp(a, "--tcp", 5) == 0      ? &ctx->tcp
                           : strncmp(a, "--key-file", 10) == 0 ? &ctx->key_file
                           : strncmp(a, "--tls-ca", 8) == 0   ? &ctx->tls_ca
                                                               : NULL;
        size_t nl = dst == &ctx->socket || dst == &ctx->tls_ca ? 8
                    : dst == &ctx->key_file                    ? 10
                                                               : 5;
        if (!dst || (a[nl] != '\0' && a[nl] != '=')) {
            char m[300];
            snprintf(m, sizeof m, "unknown global option '%s'", a);
            ctl_usage_error(ctx, NULL, m);
            return -2;
        }
        if (a[nl] == '=') {
            *dst = a + nl + 1;
            i++;
        } else if (i + 1 < argc) {
            *dst = argv[i + 1];
            i += 2;
        } else {
            char m[300];
            snprintf(m, sizeof m, "option '%s' needs a value", a);
            ctl_usage_error(ctx, NULL, m);
            return -2;
        }
    }
    return i;
}

/* Checks --socket and splits --tcp into ctx->host/port; a usage error when malformed. */
static int check_globals(ctl_ctx *ctx, const ctl_cmd *cmd)
{
    df_error e;
    df_error_clear(&e);
    if (ctx->socket && ctx->tcp)
        return ctl_usage_error(ctx, cmd, "--socket and --tcp are exclusive");
    if (ctx->tls_ca && !ctx->tcp)
        return ctl_usage_error(ctx, cmd, "--tls-ca applies to --tcp HOST:PORT connections");
    if (ctx->socket && dc_cli_socket_path(ctx->socket, &e))
        return ctl_usage_error(ctx, cmd, e.msg);
    if (ctx->tcp && dc_cli_hostport(ctx->tcp, ctx->host, (int)sizeof ctx->host, &ctx->port, &e))
        return ctl_usage_error(ctx, cmd, e.msg);
    /* a key file that cannot be used (missing, readable by others, too short) is a usage error */
    const char *kf = ctx->key_file ? ctx->key_file : getenv("DEFORMD_KEY_FILE");
    if (kf && kf[0]) {
        uint8_t key[DF_AUTH_KEY_CAP_BYTES];
        size_t len = 0;
        int rc = df_auth_key_load(kf, key, sizeof key, &len, &e);
        OPENSSL_cleanse(key, sizeof key);
        if (rc != DF_OK)
            return ctl_usage_error(ctx, cmd, e.msg);
    }
    return CTL_EXIT_OK;
}

/* 1 when --json appears before any "--": errors found while parsing are then JSON too. */
static int wants_json(int argc, char **argv)
{
    for (int i = 1; i < argc && strcmp(argv[i], "--") != 0; i++)
        if (strcmp(argv[i], "--json") == 0)
            return 1;
    return 0;
}

int main(int argc, char **argv)
{
    ctl_ctx ctx;
    memset(&ctx, 0, sizeof ctx);
    ctx.prog = "deformctl";
    ctx.json = wants_json(argc, argv);
    int i = parse_globals(argc, argv, &ctx);
    if (i == -1)
        return CTL_EXIT_OK;
    if (i < 0)
        return CTL_EXIT_USAGE;
    if (i >= argc)
        return ctl_usage_error(&ctx, NULL, "missing command");
    const ctl_cmd *cmd = find_cmd(argv[i]);
    if (!cmd) {
        char m[300];
        snprintf(m, sizeof m, "unknown command '%s'", argv[i]);
        return ctl_usage_error(&ctx, NULL, m);
    }
    dc_cli_args a;
    df_error e;
    df_error_clear(&e);
    if (dc_cli_parse(argc - i - 1, argv + i + 1, cmd->opts, cmd->nopts, DC_CLI_MAX_POS, &a, &e))
        return ctl_usage_error(&ctx, cmd, e.msg);
    if (a.help) {
        ctl_usage_cmd(stdout, ctx.prog, cmd);
        return CTL_EXIT_OK;
    }
    if (a.val[0])
        ctx.socket = a.val[0];
    if (a.val[1])
        ctx.tcp = a.val[1];
    if (a.val[2])
        ctx.json = 1;
    if (a.val[3])
        ctx.key_file = a.val[3];
    if (a.val[4])
        ctx.tls_ca = a.val[4];
    int rc = check_globals(&ctx, cmd);
    if (rc)
        return rc;
    if (cmd->npos >= 0 && a.npos < cmd->npos) /* npos -1: the command checks its arguments */
        return ctl_usage_error(&ctx, cmd, "missing argument (see the synopsis)");
    if (cmd->npos >= 0 && a.npos > cmd->npos) {
        char m[300];
        snprintf(m, sizeof m, "unexpected argument '%s'", a.pos[cmd->npos]);
        return ctl_usage_error(&ctx, cmd, m);
    }
    return cmd->run(&ctx, cmd, &a);
}
