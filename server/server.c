/* server.c — start/stop of the daemon, signals (see server.h). */
#include "server/cluster/cluster.h"
#include "server/server.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "server/session/cache.h"
#include "server/net/auth.h"
#include "server/net/conn.h"
#include "server/handlers/dispatch.h"
#include "server/net/guard.h"
#include "server/handlers/handlers.h"
#include "server/hid/hid_manager.h"
#include "server/exec/job.h"
#include "server/net/listener.h"
#include "server/log.h"
#include "server/exec/pool.h"
#include "server/net/sd.h"
#include "server/session/session.h"
#include "server/session/stream_lag.h"
#include "server/net/shm.h"
#include "server/store/restore.h"
#include "server/net/tls.h"

#define DF_SERVER_SWEEP_MS 1000 /* period of the flush-close deadline sweep */

static void on_check(uv_check_t *h)
{
    df_server *srv = h->data;
    srv->inline_spent_ns = 0; /* a new loop iteration: a new inline budget (job.h) */
    df_conn_admit_waiting(srv); /* accepted at max_clients (guard.h) */
    df_stream_lag_poll(srv);    /* coalesced versions of drained subscribers (stream_lag.h) */
    df_conn_flush_all(srv, 0);
}

static void on_sweep(uv_timer_t *t)
{
    df_server *srv = t->data;
    df_conn_sweep(srv);
    uint64_t now = uv_now(srv->loop); /* per-client output rate (stats client.<id>.bytes_per_s) */
    for (df_conn *c = srv->conns; c; c = c->next) {
        uint64_t dt = now - c->rate_ms;
        if (c->rate_ms && dt)
            c->bytes_per_s = (double)(c->outq.total_bytes - c->rate_bytes) * 1000.0 / (double)dt;
        c->rate_bytes = c->outq.total_bytes;
        c->rate_ms = now;
    }
    /* Mark the subscribers of this sweep (no per-connection bookkeeping in the sessions). */
    uint64_t epoch = ++srv->sweep_epoch;
    for (df_session *s = srv->sessions; s; s = s->next)
        for (int i = 0; i < s->nsubs; i++) s->subs[i]->sub_epoch = epoch;
    df_guard_sweep(srv);
}

/* The network layer's upward calls (server.h). */
static void conn_closing(df_conn *c) { df_job_forget_conn(c->srv, c); }

static void conn_free(df_conn *c)
{
    df_upload_free(c->upload);
    c->upload = NULL;
}

static void on_signal(uv_signal_t *h, int signum)
{
    df_server *srv = h->data;
    df_log(DF_LOG_INFO, "received %s, shutting down", signum == SIGINT ? "SIGINT" : "SIGTERM");
    df_server_stop(srv);
}

int df_server_start(df_server *srv, uv_loop_t *loop, const df_server_config *cfg, df_error *err)
{
    memset(srv, 0, sizeof *srv);
    srv->loop = loop;
    srv->cfg = *cfg;
    srv->stats.start_ns = uv_hrtime();
    srv->reserve_fd = -1;
    srv->on_frame = df_dispatch_frame;
    srv->on_conn_close = conn_closing;
    srv->on_conn_free = conn_free;
    srv->hid_ops = &df_hid_manager_ops; /* started by main (df_hid_manager_start) */
    uv_check_init(loop, &srv->kick_check);
    srv->kick_check.data = srv;
    uv_check_start(&srv->kick_check, on_check);
    uv_timer_init(loop, &srv->cork_timer);
    srv->cork_timer.data = srv;
    uv_idle_init(loop, &srv->fanout_idle);
    srv->fanout_idle.data = srv;
    uv_timer_init(loop, &srv->sweep_timer);
    srv->sweep_timer.data = srv;
    uv_timer_start(&srv->sweep_timer, on_sweep, DF_SERVER_SWEEP_MS, DF_SERVER_SWEEP_MS);
    uv_unref((uv_handle_t *)&srv->sweep_timer);
    uv_signal_init(loop, &srv->sig_int);
    uv_signal_init(loop, &srv->sig_term);
    srv->sig_int.data = srv->sig_term.data = srv;
    uv_signal_start(&srv->sig_int, on_signal, SIGINT);
    uv_signal_start(&srv->sig_term, on_signal, SIGTERM);
    /* every job's work runs on the pool: no daemon without it */
    int rc = df_auth_start(srv, err); /* key_file (net/auth.h) */
    if (rc == DF_OK) rc = df_tls_start(srv, err); /* tls_cert, tls_key (net/tls.h) */
    if (rc == DF_OK)
        rc = df_pool_start(loop, cfg->threads, (uint64_t)cfg->spin_us * 1000, &srv->pool, err);
    /* the store before the listeners: its sessions are back before the first client */
    int store_rc = rc == DF_OK ? (rc = df_store_start(srv, err)) : rc;
    if (rc == DF_OK && (rc = df_listener_open(srv, err)) == DF_OK &&
        (rc = df_guard_init(srv, err)) != DF_OK)
        df_listener_close(srv);
    /* cluster mode after the listeners: its default advertised address is the tcp one */
    if (rc == DF_OK && (rc = df_cluster_start(srv, err)) != DF_OK) {
        df_guard_free(srv);
        df_listener_close(srv);
    }
    if (rc != DF_OK) {
        if (store_rc == DF_OK) { /* opened: the listeners failed */
            while (srv->sessions) df_session_destroy(srv->sessions);
            df_store_stop(srv);
        }
        srv->stopping = 1;
        df_pool_close(srv->pool); /* NULL-safe; freed with the server */
        df_auth_free(srv);
        df_tls_free(srv);
        uv_close((uv_handle_t *)&srv->kick_check, NULL);
        uv_close((uv_handle_t *)&srv->cork_timer, NULL);
        uv_close((uv_handle_t *)&srv->fanout_idle, NULL);
        uv_close((uv_handle_t *)&srv->sweep_timer, NULL);
        uv_close((uv_handle_t *)&srv->sig_int, NULL);
        uv_close((uv_handle_t *)&srv->sig_term, NULL);
        return rc;
    }
    int stale = df_shm_sweep_stale();
    if (stale) df_log(DF_LOG_INFO, "removed %d shared-memory ring(s) of daemons that died", stale);
    return DF_OK;
}

void df_server_describe(const df_server *srv, char *buf, size_t cap)
{
    size_t n = 0;
    buf[0] = '\0';
    if (srv->have_unix)
        n += (size_t)snprintf(buf + n, cap - n, "unix:%s", srv->cfg.socket_path);
    if (srv->have_tcp && n < cap)
        n += (size_t)snprintf(buf + n, cap - n, "%stcp:%s:%d", n ? " " : "", srv->cfg.tcp_host,
                              srv->tcp_port_bound);
}

#define DF_SERVER_STOP_POLL_MS 10

/* Shutdown continues here until no job runs any more. */
static void on_stop_timer(uv_timer_t *h)
{
    df_server *srv = h->data;
    if (srv->jobs_running > 0 || df_hid_manager_busy(srv)) return;
    uv_timer_stop(h);
    uv_close((uv_handle_t *)h, (uv_close_cb)free);
    df_cluster_stop(srv); /* leases released: other daemons take over at once */
    /* Sessions: every FIFO is drained (queued jobs were answered or dropped). */
    while (srv->sessions) {
        df_session *s = srv->sessions;
        df_job_drop_queued(s, df_job_pred_all, NULL, "server shutting down");
        df_session_destroy(s);
    }
    for (df_conn *c = srv->conns; c; c = c->next) df_conn_close(c, "server shutting down", 0);
    df_conn_flush_all(srv, 1);
    df_pool_close(srv->pool); /* idle: jobs_running is 0 */
    uv_close((uv_handle_t *)&srv->kick_check, NULL);
    uv_timer_stop(&srv->cork_timer);
    uv_close((uv_handle_t *)&srv->cork_timer, NULL);
    uv_close((uv_handle_t *)&srv->fanout_idle, NULL);
    uv_close((uv_handle_t *)&srv->sweep_timer, NULL);
    df_sd_notify("STOPPING=1");
}

void df_server_stop(df_server *srv)
{
    if (srv->stopping) return;
    srv->stopping = 1;
    df_sd_notify("STOPPING=1");
    df_listener_close(srv);
    df_hid_manager_stop(srv); /* joins the reader threads; their last posts drain meanwhile */
    uv_signal_stop(&srv->sig_int);
    uv_signal_stop(&srv->sig_term);
    uv_close((uv_handle_t *)&srv->sig_int, NULL);
    uv_close((uv_handle_t *)&srv->sig_term, NULL);
    /* Stop reading; supersede running moves so that they end at their next iteration. */
    for (df_conn *c = srv->conns; c; c = c->next)
        if (!c->closing) uv_read_stop(&c->h.stream);
    for (df_session *s = srv->sessions; s; s = s->next)
        if (s->running) atomic_store(&s->running->cancel, 1);
    uv_timer_t *t = malloc(sizeof *t);
    if (!t) return;
    uv_timer_init(srv->loop, t);
    t->data = srv;
    uv_timer_start(t, on_stop_timer, 0, DF_SERVER_STOP_POLL_MS);
}

void df_server_free(df_server *srv)
{
    while (srv->sessions) df_session_destroy(srv->sessions);
    df_cluster_stop(srv);
    df_store_stop(srv);
    df_hid_manager_free(srv);
    df_pool_free(srv->pool);
    srv->pool = NULL;
    df_guard_free(srv);
    df_auth_free(srv);
    free(srv->join_limit);
    srv->join_limit = NULL;
    df_tls_free(srv);
}
