/* reload.c — SIGHUP configuration reload (see reload.h). */
#include "server/reload.h"

#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "server/log.h"
#include "server/net/guard.h"

#define DF_RELOAD_POLL_MS 10 /* period of the wait for no running job */

/* Settings that need a restart: logged when the new file changes them. */
static void note_restart(const df_server_config *cur, const df_server_config *n)
{
    char list[1024];
    size_t len = 0;
    list[0] = '\0';
#define DF_RESTART_KEY(changed, name)                                                       \
    do {                                                                                    \
        if ((changed) && len < sizeof list)                                                 \
            len += (size_t)snprintf(list + len, sizeof list - len, "%s%s", len ? ", " : "", \
                                    name);                                                  \
    } while (0)
    DF_RESTART_KEY(strcmp(cur->socket_path, n->socket_path) != 0, "socket");
    DF_RESTART_KEY(strcmp(cur->tcp_host, n->tcp_host) != 0 || cur->tcp_port != n->tcp_port,
                   "tcp");
    DF_RESTART_KEY(cur->tcp_insecure != n->tcp_insecure, "tcp_insecure");
    DF_RESTART_KEY(strcmp(cur->access.tls_cert, n->access.tls_cert) != 0, "tls_cert");
    DF_RESTART_KEY(strcmp(cur->access.tls_key, n->access.tls_key) != 0, "tls_key");
    DF_RESTART_KEY(cur->socket_mode != n->socket_mode, "socket_mode");
    DF_RESTART_KEY(strcmp(cur->socket_group, n->socket_group) != 0, "socket_group");
    DF_RESTART_KEY(cur->threads != n->threads, "threads");
    DF_RESTART_KEY(cur->spin_us != n->spin_us, "spin_us");
    DF_RESTART_KEY(cur->inline_us != n->inline_us, "inline_us");
    DF_RESTART_KEY(cur->admm_active != n->admm_active, "admm_active");
    DF_RESTART_KEY(cur->cache_memory_mb != n->cache_memory_mb, "cache_memory_mb");
    DF_RESTART_KEY(cur->max_mesh_vertices != n->max_mesh_vertices, "max_mesh_vertices");
    DF_RESTART_KEY(cur->shm_ring_bytes != n->shm_ring_bytes, "shm_ring_bytes");
    DF_RESTART_KEY(cur->shm_total_bytes != n->shm_total_bytes, "shm_total_bytes");
    DF_RESTART_KEY(cur->max_upload_mb != n->max_upload_mb, "max_upload_mb");
    DF_RESTART_KEY(cur->uploads_max_mb != n->uploads_max_mb, "uploads_max_mb");
    DF_RESTART_KEY(cur->history_max_mb != n->history_max_mb, "history_max_mb");
    DF_RESTART_KEY(cur->resync_ring_mb != n->resync_ring_mb, "resync_ring_mb");
    DF_RESTART_KEY(cur->history_replay_ms != n->history_replay_ms, "history_replay_ms");
    DF_RESTART_KEY(cur->memory_max_mb != n->memory_max_mb, "memory_max_mb");
    DF_RESTART_KEY(cur->hid_on != n->hid_on, "hid");
    DF_RESTART_KEY(cur->n_hid_replay != n->n_hid_replay ||
                       memcmp(cur->hid_replay, n->hid_replay,
                              sizeof cur->hid_replay[0] * (size_t)cur->n_hid_replay) != 0,
                   "hid_replay");
    DF_RESTART_KEY(cur->hid_replay_speed != n->hid_replay_speed, "hid_replay_speed");
    DF_RESTART_KEY(cur->hid_replay_end != n->hid_replay_end, "hid_replay_end");
    DF_RESTART_KEY(cur->hid_enumerate_s != n->hid_enumerate_s, "hid_enumerate_s");
    DF_RESTART_KEY(memcmp(&cur->hid, &n->hid, sizeof cur->hid) != 0, "hid.*");
    DF_RESTART_KEY(cur->access.n_peer_keys != n->access.n_peer_keys ||
                       memcmp(cur->access.peer_keys, n->access.peer_keys,
                              sizeof cur->access.peer_keys[0] *
                                  (size_t)cur->access.n_peer_keys) != 0,
                   "peer_key");
    DF_RESTART_KEY(strcmp(cur->cluster, n->cluster) != 0, "cluster");
    DF_RESTART_KEY(strcmp(cur->advertise, n->advertise) != 0, "advertise");
    DF_RESTART_KEY(cur->cluster_lease_ms != n->cluster_lease_ms, "cluster_lease_ms");
#undef DF_RESTART_KEY
    if (len)
        df_log(DF_LOG_WARN, "reload: changed settings that need a restart (running values "
               "kept): %s", list);
}

/* Copies the live settings of n into srv->cfg. Loop thread, no job running. */
static void apply(df_server *srv, const df_server_config *n)
{
    df_server_config *c = &srv->cfg;
    note_restart(c, n);
    c->log_level = n->log_level;
    c->max_clients = n->max_clients;
    c->max_sessions = n->max_sessions;
    c->handshake_timeout_s = n->handshake_timeout_s;
    c->idle_timeout_s = n->idle_timeout_s;
    c->cursor_hz = n->cursor_hz;
    c->output_queue_limit = n->output_queue_limit;
    c->stream_coalesce_start = n->stream_coalesce_start;
    c->stream_coalesce_resume = n->stream_coalesce_resume;
    c->n_allow = n->n_allow;
    memcpy(c->allow_paths, n->allow_paths, sizeof c->allow_paths);
    c->access.session_access = n->access.session_access; /* membership.h: of new sessions */
    c->access.session_observers = n->access.session_observers;
    c->access.quota_sessions = n->access.quota_sessions;
    c->access.quota_upload_mb = n->access.quota_upload_mb;
    c->access.quota_memory_mb = n->access.quota_memory_mb;
    df_log_set_level(c->log_level);
    df_guard_fd_limit(c->max_clients); /* a raised max_clients needs its descriptors */
    df_log(DF_LOG_INFO, "configuration reloaded: log_level %d, max_clients %d, max_sessions %d, "
           "handshake_timeout_s %d, idle_timeout_s %d, cursor_hz %d, output_queue_limit %zu, "
           "%d allow_paths, session_access %s, session_observers %s, quota_sessions %d, quota_upload_mb %d, "
           "quota_memory_mb %d", c->log_level, c->max_clients, c->max_sessions,
           c->handshake_timeout_s, c->idle_timeout_s, c->cursor_hz, c->output_queue_limit,
           c->n_allow, c->access.session_access == DF_SESSION_ACCESS_OWNER  ? "owner"
           : c->access.session_access == DF_SESSION_ACCESS_KEY ? "key"
                                                                : "open",
           c->access.session_observers ? "on" : "off",
           c->access.quota_sessions, c->access.quota_upload_mb, c->access.quota_memory_mb);
}

static void on_wait(uv_timer_t *t)
{
    df_reload *r = t->data;
    if (!r->next) {
        uv_timer_stop(t);
        return;
    }
    if (r->srv->stopping) { /* shutting down: nothing to apply any more */
        free(r->next);
        r->next = NULL;
        uv_timer_stop(t);
        return;
    }
    if (r->srv->jobs_running > 0) return; /* a worker may be reading srv->cfg */
    apply(r->srv, r->next);
    free(r->next);
    r->next = NULL;
    uv_timer_stop(t);
}

static void on_hup(uv_signal_t *h, int signum)
{
    (void)signum;
    df_reload *r = h->data;
    if (r->srv->stopping) return;
    df_server_config *n = malloc(sizeof *n);
    if (!n) {
        df_log(DF_LOG_ERROR, "reload: out of memory; keeping the current settings");
        return;
    }
    df_cli_action action;
    df_error err = {0, ""};
    /* parse from the start directory (relative --config and hid_replay paths), then back */
    int here = r->cwd ? open(".", O_RDONLY | O_DIRECTORY | O_CLOEXEC) : -1;
    int moved = here >= 0 && chdir(r->cwd) == 0;
    int rc = df_config_from_args(n, r->argc, r->argv, r->xdg, &action, &err);
    if (moved && fchdir(here) != 0)
        df_log(DF_LOG_WARN, "reload: cannot return to the working directory");
    if (here >= 0) close(here);
    if (rc != DF_OK) {
        df_log(DF_LOG_ERROR, "reload: %s; keeping the current settings", err.msg);
        free(n);
        return;
    }
    df_log(DF_LOG_INFO, "reload: SIGHUP, %s parsed", n->config_path[0] ? n->config_path
                                                                        : "command line");
    df_log_set_level(n->log_level); /* atomic: at once */
    free(r->next); /* a newer SIGHUP wins over one still waiting */
    r->next = n;
    on_wait(&r->wait);
    if (r->next) uv_timer_start(&r->wait, on_wait, DF_RELOAD_POLL_MS, DF_RELOAD_POLL_MS);
}

int df_reload_start(df_reload *r, df_server *srv, int argc, char **argv, const char *xdg,
                    const char *cwd, df_error *err)
{
    memset(r, 0, sizeof *r);
    r->cwd = cwd;
    r->srv = srv;
    r->argc = argc;
    r->argv = argv;
    r->xdg = xdg;
    uv_timer_init(srv->loop, &r->wait);
    r->wait.data = r;
    uv_unref((uv_handle_t *)&r->wait);
    uv_signal_init(srv->loop, &r->sig);
    r->sig.data = r;
    r->open = 1;
    int rc = uv_signal_start(&r->sig, on_hup, SIGHUP);
    if (rc != 0) {
        df_reload_close(r);
        return df_error_set(err, DF_EIO, "SIGHUP handler: %s", uv_strerror(rc));
    }
    uv_unref((uv_handle_t *)&r->sig);
    return DF_OK;
}

void df_reload_close(df_reload *r)
{
    if (!r->open) return;
    r->open = 0;
    free(r->next);
    r->next = NULL;
    uv_close((uv_handle_t *)&r->sig, NULL);
    uv_close((uv_handle_t *)&r->wait, NULL);
}
