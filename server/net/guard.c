/* guard.c — refusals, the reserve fd, handshake and idle timeouts (see guard.h). */
#include "server/net/guard.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include "proto/messages.h"
#include "server/net/auth.h"
#include "server/net/conn.h"
#include "server/log.h"
#include "server/net/reply.h"

long df_guard_fd_limit(int max_clients)
{
    struct rlimit rl;
    if (getrlimit(RLIMIT_NOFILE, &rl) != 0) return -1;
    rlim_t need = (rlim_t)(max_clients > 0 ? max_clients : 0) + DF_GUARD_FD_RESERVE;
    if (rl.rlim_cur != RLIM_INFINITY && rl.rlim_cur < need) {
        rlim_t old = rl.rlim_cur;
        rl.rlim_cur = rl.rlim_max != RLIM_INFINITY && rl.rlim_max < need ? rl.rlim_max : need;
        if (rl.rlim_cur > old && setrlimit(RLIMIT_NOFILE, &rl) == 0)
            df_log(DF_LOG_INFO, "file descriptor limit raised from %llu to %llu for max_clients "
                   "%d", (unsigned long long)old, (unsigned long long)rl.rlim_cur, max_clients);
        if (getrlimit(RLIMIT_NOFILE, &rl) != 0) return -1;
        if (rl.rlim_cur < need)
            df_log(DF_LOG_WARN, "max_clients %d needs %llu file descriptors but the limit is %llu "
                   "(hard limit %llu): connections beyond it are refused; raise LimitNOFILE= "
                   "(systemd) or `ulimit -Hn`, or lower max_clients", max_clients,
                   (unsigned long long)need, (unsigned long long)rl.rlim_cur,
                   (unsigned long long)rl.rlim_max);
    }
    return rl.rlim_cur == RLIM_INFINITY || rl.rlim_cur > (rlim_t)LONG_MAX ? LONG_MAX
                                                                          : (long)rl.rlim_cur;
}

int df_guard_init(df_server *srv, df_error *err)
{
    df_guard_fd_limit(srv->cfg.max_clients);
    srv->reserve_fd = open("/dev/null", O_RDONLY | O_CLOEXEC);
    if (srv->reserve_fd < 0)
        return df_error_set(err, DF_EIO, "cannot open the reserve descriptor: %s",
                            strerror(errno));
    return DF_OK;
}

void df_guard_free(df_server *srv)
{
    if (srv->reserve_fd > 0) close(srv->reserve_fd);
    srv->reserve_fd = -1;
}

/* Logs a refusal unless one was logged less than DF_GUARD_LOG_MS ago (then it is counted and
 * reported with the next line). */
static void log_refusal(df_server *srv, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void log_refusal(df_server *srv, const char *fmt, ...)
{
    uint64_t now = uv_now(srv->loop);
    if (srv->refuse_logged && now - srv->refuse_log_ms < DF_GUARD_LOG_MS) {
        srv->refuse_suppressed++;
        return;
    }
    char msg[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (srv->refuse_suppressed)
        df_log(DF_LOG_WARN, "%s (and %llu more refusals not logged since the last line)", msg,
               (unsigned long long)srv->refuse_suppressed);
    else
        df_log(DF_LOG_WARN, "%s", msg);
    srv->refuse_logged = 1;
    srv->refuse_log_ms = now;
    srv->refuse_suppressed = 0;
}

/* Sends c one ERROR event (ELIMIT, the message) and closes it: at once when the socket takes
 * the frame (the usual case: a new, empty socket), so that its descriptor is free again before
 * the next accept; else once the queued frame is flushed. */
static void refuse(df_conn *c, const char *msg)
{
    c->refused = 1;
    c->srv->n_refusing++;
    df_buf b;
    df_buf_init(&b);
    if (df_msg_error_frame(&b, DF_MSG_ERROR, 0, DF_ELIMIT, NULL, "%s", msg) == DF_OK) {
        uv_buf_t ub = uv_buf_init((char *)b.data, (unsigned)b.len);
        int w = uv_try_write(&c->h.stream, &ub, 1);
        if (w != UV_EAGAIN) { /* all of it went out (or part, or the peer is gone): done */
            df_buf_free(&b);
            df_conn_close(c, "refused", 0);
            return;
        }
    }
    df_buf_free(&b);
    df_reply_error(c, DF_MSG_ERROR, 0, DF_ELIMIT, "%s", msg);
    df_conn_close_after_flush(c, "refused");
}

/* 1 when no descriptor is free beyond the reserve (a dup of it fails with EMFILE/ENFILE). */
static int out_of_fds(df_server *srv)
{
    if (srv->reserve_fd < 0) return 0;
    int probe = fcntl(srv->reserve_fd, F_DUPFD_CLOEXEC, 0);
    if (probe >= 0) {
        close(probe);
        return 0;
    }
    return errno == EMFILE || errno == ENFILE;
}

/* Connections that count against max_clients: open ones, less those closing or refused and
 * those waiting for their admission (each is counted when it is decided). */
static int live_conns(const df_server *srv)
{
    return srv->n_conns - srv->n_refusing - srv->n_closing - srv->n_admit_waiting;
}

int df_guard_over_limit(const df_conn *c)
{
    return live_conns(c->srv) > c->srv->cfg.max_clients;
}

int df_guard_admit(df_conn *c)
{
    df_server *srv = c->srv;
    char msg[160];
    if (out_of_fds(srv)) {
        srv->stats.clients_refused_fds++;
        snprintf(msg, sizeof msg, "server busy: out of file descriptors (%d connections open); "
                 "try again later", live_conns(srv));
        log_refusal(srv, "refused client %llu: out of file descriptors (%d connections open)",
                    (unsigned long long)c->id, live_conns(srv));
        refuse(c, msg);
        return 1;
    }
    if (df_guard_over_limit(c)) {
        srv->stats.clients_refused++;
        snprintf(msg, sizeof msg, "server full: max_clients (%d) connections are open; try again "
                 "later", srv->cfg.max_clients);
        log_refusal(srv, "refused client %llu: max_clients (%d) reached",
                    (unsigned long long)c->id, srv->cfg.max_clients);
        refuse(c, msg);
        return 1;
    }
    return 0;
}

void df_guard_accept_failed(df_server *srv, uv_stream_t *listener, int status, const char *kind)
{
    int fd = -1;
    if ((status == UV_EMFILE || status == UV_ENFILE) && srv->reserve_fd >= 0 &&
        uv_fileno((uv_handle_t *)listener, &fd) == 0) {
        /* Free the reserve, then accept, tell and close whatever waits; take the reserve back. */
        close(srv->reserve_fd);
        srv->reserve_fd = -1;
        uint8_t frame[128];
        df_buf b;
        df_buf_init(&b);
        size_t len = 0;
        if (df_msg_error_frame(&b, DF_MSG_ERROR, 0, DF_ELIMIT, NULL,
                               "server busy: out of file descriptors; try again later") == DF_OK &&
            b.len <= sizeof frame) {
            memcpy(frame, b.data, b.len);
            len = b.len;
        }
        df_buf_free(&b);
        int s;
        while ((s = accept4(fd, NULL, NULL, SOCK_NONBLOCK | SOCK_CLOEXEC)) >= 0) {
            if (len && send(s, frame, len, MSG_DONTWAIT | MSG_NOSIGNAL) < 0) { /* best effort */
            }
            close(s);
            srv->stats.clients_refused_fds++;
        }
        srv->reserve_fd = open("/dev/null", O_RDONLY | O_CLOEXEC);
    }
    log_refusal(srv, "accept (%s): %s", kind, uv_strerror(status));
}

static void expire(df_conn *c, uint64_t *counter, const char *why, const char *key, int secs)
{
    (*counter)++;
    df_reply_error(c, DF_MSG_ERROR, 0, DF_ELIMIT, "%s: %s after %d s (%s); closing", why,
                   !c->hello_done          ? "no HELLO"
                   : df_auth_required(c)   ? "not authenticated (AUTH, key_file)"
                                           : "no request and no subscription",
                   secs, key);
    df_conn_close_after_flush(c, why);
}

void df_guard_sweep(df_server *srv)
{
    uint64_t now = uv_now(srv->loop);
    if (srv->refuse_suppressed && now - srv->refuse_log_ms >= DF_GUARD_LOG_MS) {
        df_log(DF_LOG_WARN, "%llu more connections refused since the last line (stats: "
               "clients_refused, clients_refused_fds)",
               (unsigned long long)srv->refuse_suppressed);
        srv->refuse_suppressed = 0;
        srv->refuse_log_ms = now;
    }
    uint64_t hs = (uint64_t)srv->cfg.handshake_timeout_s * 1000;
    uint64_t idle = (uint64_t)srv->cfg.idle_timeout_s * 1000;
    if (!hs && !idle) return;
    uint64_t epoch = srv->sweep_epoch; /* subscribers carry it (marked by the caller) */
    for (df_conn *c = srv->conns; c; c = c->next) {
        if (c->closing || c->flush_close) continue;
        if (!c->hello_done || df_auth_required(c)) { /* TCP with a key: AUTH too (auth.h) */
            if (hs && now - c->accepted_ms >= hs)
                expire(c, &srv->stats.clients_handshake_timeout, "handshake timeout",
                       "handshake_timeout_s", srv->cfg.handshake_timeout_s);
        } else if (idle && c->sub_epoch != epoch && c->pending == 0 && !c->upload &&
                   now - c->last_rx_ms >= idle) {
            expire(c, &srv->stats.clients_idle_timeout, "idle timeout", "idle_timeout_s",
                   srv->cfg.idle_timeout_s);
        }
    }
}
