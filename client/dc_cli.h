/* dc_cli.h — pure command-line parsing helpers of deformctl (kept in libdeformclient so that
 * they are unit-tested): a table-driven long-option parser and typed value parsers.
 *
 * No function here prints or exits; all report problems through df_error (DF_EINVAL) with a
 * message naming the offending option or value, which deformctl prints as a usage error. */
#ifndef DF_CLIENT_DC_CLI_H
#define DF_CLIENT_DC_CLI_H

#include <stdint.h>

#include "core/common/df_error.h"

/* Most options one command may declare, and most positional arguments one command accepts. */
#define DC_CLI_MAX_OPTS 32
#define DC_CLI_MAX_POS 8

/* One long option: `name` without the leading "--"; `has_arg` 1 when it takes a value
 * (`--name VALUE` or `--name=VALUE`), 0 for a flag; `help` is one usage line. */
typedef struct dc_cli_opt {
    const char *name;
    int has_arg;
    const char *help;
} dc_cli_opt;

/* Result of dc_cli_parse: `val[i]` is the value of opts[i] (a pointer into argv, "" for a set
 * flag, NULL when absent); `pos` are the positional arguments in order; `help` is 1 when
 * `--help` or `-h` appeared anywhere. */
typedef struct dc_cli_args {
    const char *val[DC_CLI_MAX_OPTS];
    const char *pos[DC_CLI_MAX_POS];
    int npos;
    int help;
} dc_cli_args;

/* Parses argv[0..argc-1] (no program name) against `opts` (nopts <= DC_CLI_MAX_OPTS). A "--"
 * ends option parsing. Accepts at most `max_pos` positionals (<= DC_CLI_MAX_POS).
 * Errors (DF_EINVAL, `out` then holds what was parsed so far): unknown option, missing value,
 * a value given to a flag, an option repeated, too many positionals. `--help` always wins:
 * when present the return is DF_OK with out->help = 1 whatever else is wrong. */
int dc_cli_parse(int argc, char **argv, const dc_cli_opt *opts, int nopts, int max_pos,
                 dc_cli_args *out, df_error *err);

/* Index of option `name` in `opts`, or -1. */
int dc_cli_find(const dc_cli_opt *opts, int nopts, const char *name);

/* Parses a finite double (full string, no trailing junk). With `allow_inf` also accepts "inf",
 * "+inf", "infinity" (any case) as +INFINITY and "-inf", "-infinity" as -INFINITY. `what` names
 * the value in error messages. Errors: DF_EINVAL (not a number, NaN, overflow, or an infinity
 * without `allow_inf`); *out untouched. */
int dc_cli_double(const char *s, const char *what, int allow_inf, double *out, df_error *err);

/* Parses a decimal integer in [lo, hi] (full string). */
int dc_cli_int(const char *s, const char *what, long long lo, long long hi, long long *out,
               df_error *err);

/* Parses exactly `n` (1..16) comma-separated finite doubles ("1,2.5,-3") into out[0..n-1]. */
int dc_cli_vec(const char *s, const char *what, int n, double *out, df_error *err);

/* Returns the index of `s` in the NULL-terminated list `choices`, or DF_EINVAL with a message
 * listing the choices ("--type: 'grip' is not one of grab|twist|scale|pinch|affine"). */
int dc_cli_choice(const char *s, const char *what, const char *const *choices, df_error *err);

/* Splits "HOST:PORT" ("[::1]:7000" for IPv6) into host (NUL-terminated, at most host_cap - 1
 * chars) and port 1..65535. Errors: DF_EINVAL naming --tcp (no port, empty host, a port that is
 * not an integer in 1..65535); outputs untouched. */
int dc_cli_hostport(const char *s, char *host, int host_cap, int *port, df_error *err);

/* Checks a --socket PATH: non-empty and short enough for a Unix socket address (sun_path).
 * Errors: DF_EINVAL naming --socket. */
int dc_cli_socket_path(const char *s, df_error *err);

/* Writes the default daemon socket path into buf (cap bytes): $DEFORMD_SOCKET when set, else
 * $XDG_RUNTIME_DIR/deformd.sock when XDG_RUNTIME_DIR is set, else /run/deformd/deformd.sock.
 * Returns DF_OK or DF_ELIMIT when it does not fit. */
int dc_cli_default_socket(char *buf, int cap, df_error *err);

#endif
