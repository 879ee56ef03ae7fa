/* reload.h — SIGHUP: re-read the configuration and apply what can change while running.
 *
 * Live (applied once no job runs, so that no compute worker reads the settings meanwhile; the
 * log level at once): log_level, max_clients, max_sessions, handshake_timeout_s,
 * idle_timeout_s, cursor_hz, output_queue_limit (connections accepted afterwards),
 * stream_coalesce_start and stream_coalesce_resume (at the next stream frame), allow_paths, session_access and quota_* (checked at the next request / load). Every other
 * setting (listeners, socket mode and group, threads, spin_us, inline_us, memory and cache
 * budgets, shm sizes, mesh and upload limits, hid, hid_replay*, hid_enumerate_s, hid.* mappings,
 * peer_key) needs a restart: a changed one is logged by name and keeps its
 * running value. A file that does not parse is logged with its FILE:LINE error and nothing
 * changes. */
#ifndef DF_SERVER_RELOAD_H
#define DF_SERVER_RELOAD_H

#include <uv.h>

#include "core/common/df_error.h"
#include "server/server.h"

typedef struct df_reload {
    uv_signal_t sig;          /* SIGHUP (unreferenced: it does not keep the loop alive) */
    uv_timer_t wait;          /* polls until no job runs, then applies `next` */
    df_server *srv;
    int argc;
    char **argv;              /* the daemon's command line (borrowed, outlives the loop) */
    const char *xdg;          /* $XDG_RUNTIME_DIR at start (borrowed, may be NULL) */
    const char *cwd;          /* working directory at start, before daemonizing (borrowed,
                                 may be NULL): relative --config / hid_replay paths */
    df_server_config *next;   /* parsed settings waiting for no job to run, or NULL */
    int open;
} df_reload;

/* Installs the SIGHUP handler on srv->loop: each SIGHUP re-parses argv (the --config file, then
 * the options over it, as at start; df_config_from_args; relative paths against `cwd`, the
 * directory deformd started in, since daemonizing moves to /) and applies the live settings to
 * srv->cfg, logging "configuration reloaded: ..." (info) when done, or the error (error level)
 * when the file does not parse. `r` must stay valid until df_reload_close. Loop thread.
 * Errors: DF_EIO when the signal handler cannot be installed. */
int df_reload_start(df_reload *r, df_server *srv, int argc, char **argv, const char *xdg,
                    const char *cwd, df_error *err);

/* Closes the handles (run the loop once more to finish) and drops a pending reload. Loop
 * thread; idempotent. */
void df_reload_close(df_reload *r);

#endif
