/* ctl.h — deformctl internals shared by the command files: the global options, connecting,
 * exit codes, error reporting and JSON output helpers. */
#ifndef DF_DEFORMCTL_CTL_H
#define DF_DEFORMCTL_CTL_H

#include <stdint.h>
#include <stdio.h>

#include "client/dc_cli.h"
#include "client/deformclient.h"

/* Exit codes (the README's 0/1/2, the same for every command). */
#define CTL_EXIT_OK 0
#define CTL_EXIT_SERVER 1   /* an error from the daemon, the daemon could not be reached (or the
                               connection broke), the local engine check of `brush` refused the
                               stroke, or a local failure after the command line was accepted
                               (e.g. the --out file cannot be written or cannot hold the mesh) */
#define CTL_EXIT_USAGE 2    /* usage: unknown command or option, missing or extra argument, an
                               option value that does not parse or is out of its range (the
                               global --tcp HOST:PORT and --socket PATH included), or an input
                               file named on the command line that cannot be read or parsed */

/* The global options, accepted before the command or among its options. */
#define CTL_GLOBAL_OPTS                                                              \
    {"socket", 1, "--socket PATH      daemon Unix socket (default: $DEFORMD_SOCKET, " \
                  "$XDG_RUNTIME_DIR/deformd.sock, /run/deformd/deformd.sock)"},      \
    {"tcp", 1, "--tcp HOST:PORT    connect over TCP instead"},                         \
    {"json", 0, "--json             machine-readable JSON output on stdout"},          \
    {"key-file", 1, "--key-file FILE    authenticate with the key in FILE (default: " \
                    "$DEFORMD_KEY_FILE; PROTOCOL.md 4.3)"},                                   \
    {"tls-ca", 1, "--tls-ca FILE      TLS on --tcp: verify the daemon's certificate against " \
                  "the CA in FILE (default: $DEFORMD_TLS_CA)"}
#define CTL_NGLOBAL 5

typedef struct ctl_ctx {
    const char *socket;   /* --socket, NULL for the default */
    const char *tcp;      /* --tcp HOST:PORT or NULL */
    const char *key_file; /* --key-file FILE, else $DEFORMD_KEY_FILE, or NULL: no AUTH */
    const char *tls_ca;   /* --tls-ca FILE, else $DEFORMD_TLS_CA, or NULL: TCP without TLS */
    int json;
    const char *prog;     /* "deformctl" */
    char host[256];       /* --tcp split by main before the command runs */
    int port;
} ctl_ctx;

/* One command: name, one-line synopsis, the option table (globals first) and its handler. */
typedef struct ctl_cmd {
    const char *name;
    const char *synopsis;  /* e.g. "load FILE [--name NAME]" */
    const char *summary;   /* one line of what it does */
    const dc_cli_opt *opts;
    int nopts;
    int npos;              /* positional arguments it requires; -1: any, run checks them */
    int (*run)(ctl_ctx *ctx, const struct ctl_cmd *cmd, const dc_cli_args *a);
} ctl_cmd;

/* Command tables of each group (cmd_*.c). */
extern const ctl_cmd ctl_cmds_session[];   /* ping load list close stats */
extern const ctl_cmd ctl_cmds_watch[];     /* watch (cmd_watch.c) */
extern const ctl_cmd ctl_cmds_brush[];     /* brush */
extern const ctl_cmd ctl_cmds_handles[];   /* handles move */
extern const ctl_cmd ctl_cmds_mesh[];      /* get undo redo reset-rest */
extern const ctl_cmd ctl_cmds_brush_state[]; /* brush-state */
extern const ctl_cmd ctl_cmds_devices[];   /* devices [bind DEVICE SESSION] */
extern const ctl_cmd ctl_cmds_access[];    /* access join peers */
extern const ctl_cmd ctl_cmds_preview[];   /* preview */

/* Prints a session brush (brush_state_out.c): event 0 as `brush-state` does ('key value' lines,
 * or one JSON object), event 1 as one `watch` line ("brush_state seq N changed radius,nu by
 * client ID 'NAME': type grab radius 0.25 ..."; a device origin is "device N", its number as
 * `deformctl devices` lists it; or a JSON object with "kind":"brush_state" and the full id). */
void ctl_brush_state_print(const ctl_ctx *ctx, const df_msg_brush_state *s, int event);

/* Prints a BRUSH_CURSOR event as one `watch` line ("brush_cursor device N center X,Y,Z radius R
 * [in_range] [stroke_active]", N the device number; or a JSON object with "kind":"brush_cursor"). */
void ctl_brush_cursor_print(const ctl_ctx *ctx, const df_msg_brush_cursor *m);

/* Prints a DEVICES_LIST reply as `deformctl devices` does (device_out.c): a table with one row
 * per device (its number n of id (1 << 63) | n, class, VID:PID, state, bound and active session,
 * name, backend and error), "no HID devices" when empty (saying the subsystem is off when hid_on
 * is 0: the daemon's hello has no HID feature bit); or one JSON object {"devices":[...]}. */
void ctl_device_list_print(const ctl_ctx *ctx, const df_msg_device_list *l, int hid_on);

/* Prints a DEVICE_STATE event as one `watch` line (device_out.c): "device N knob 045e:091b
 * open session S 'NAME'" (+ ": ERROR"; S is the session it drives, else the bound one, "-" for
 * none), or a JSON object with "kind":"device_state". */
void ctl_device_state_print(const ctl_ctx *ctx, const df_msg_device_info *d);

/* Prints `cmd`'s usage to `f`. */
void ctl_usage_cmd(FILE *f, const char *prog, const ctl_cmd *cmd);

/* Prints "deformctl CMD: MESSAGE" plus "try --help" on stderr and returns CTL_EXIT_USAGE.
 * With --json also the error object of ctl_error (source "usage", EINVAL) on stdout. */
int ctl_usage_error(const ctl_ctx *ctx, const ctl_cmd *cmd, const char *msg);

/* Reports an error and returns `exit_code`: "deformctl CMD: PREFIXNAME: MESSAGE" on stderr,
 * where PREFIX is "server: " for source "server" and "rejected: " for source "rejected"; with
 * --json also one line on stdout:
 *   {"ok":false,"exit":E,"source":S,"code":C,"name":"N","message":"M"}
 * S is "usage", "server" (the daemon refused), "rejected" (the local Kelvinlet check of brush)
 * or "client" (connection and local I/O); C is the DF_E* / wire code, N its name. `cmd` may be
 * NULL (errors before the command is known). */
int ctl_error(const ctl_ctx *ctx, const ctl_cmd *cmd, const char *source, int code,
              const char *msg, int exit_code);

/* Writes only the JSON error object of ctl_error to stdout (callers check ctx->json). */
void ctl_json_error(const char *source, int code, const char *msg, int exit_code);

/* Reports a failed client call via ctl_error ("deformctl CMD: server: ENOTFOUND: no session 7")
 * and maps it to an exit code: CTL_EXIT_SERVER for server and connection errors,
 * CTL_EXIT_USAGE when `c`'s last call was refused locally as invalid (DF_EINVAL/DF_ELIMIT from
 * a message encoder: e.g. --radius 0). `c` may be NULL (connection errors). */
int ctl_fail(const ctl_ctx *ctx, const ctl_cmd *cmd, const df_client *c, const df_error *e);

/* Connects per the global options (main has already checked and split them); on failure
 * prints the error and returns NULL: the caller exits CTL_EXIT_SERVER. */
df_client *ctl_connect(const ctl_ctx *ctx, const ctl_cmd *cmd);
/* ctl_connect; with `trailer` the hello carries the stream trailer (df_client_connect_enc),
 * asking for stream encoding `enc` (DF_STREAM_ENC_* bits, 0 exact) with error bound `bound`
 * (mesh units, QUANTIZED only), so the daemon coalesces the stream when this client cannot keep
 * up: `watch --encoding`. Without it (enc and bound then 0) the original hello. */
df_client *ctl_connect_enc(const ctl_ctx *ctx, const ctl_cmd *cmd, int trailer, uint8_t enc,
                           double bound);


/* Resolves SESSION (a decimal id, or else a session name looked up with open session) into
 * *id. Returns DF_OK or an error (printed by the caller via ctl_fail); an empty SESSION is
 * DF_EINVAL without contacting the daemon (ctl_fail makes it a usage error). */
int ctl_session_id(df_client *c, const char *arg, uint64_t *id, df_error *err);

/* Writes `s` as a JSON string literal (quotes and escapes) to `f`. */
void ctl_json_str(FILE *f, const char *s);

/* Writes a double as JSON (finite: %.17g; non-finite as null). */
void ctl_json_num(FILE *f, double v);

/* Name of a change kind ("brush", "undo", ...) for output. */
const char *ctl_change_name(unsigned kind);

#endif
