/* guard.h — admission of connections, so that no client can lock the others out (loop thread).
 *
 * - Refusals: a connection accepted while max_clients others are open, or while the process has
 *   no file descriptor left beyond its reserve, gets one ERROR event (type ERROR, flags ERROR,
 *   request id 0, code ELIMIT, saying why) and is closed once that is sent. Counted in stats
 *   (clients_refused, clients_refused_fds); logged at most once per DF_GUARD_LOG_MS with the
 *   number of refusals not logged since.
 * - Reserve fd: the daemon holds one spare descriptor. Each accepted connection is checked with
 *   a dup of it: when that fails with EMFILE/ENFILE the connection just took the last free slot
 *   and is refused (closing it frees the slot again), so the daemon keeps accepting, telling
 *   and closing instead of leaving clients in the backlog. Should accept itself fail with
 *   EMFILE (another thread took the slot) the spare is closed for a moment to accept, refuse and
 *   close the waiting connections (the classic libuv/redis trick).
 * - Timeouts (config, seconds, 0 = off): a connection without a successful HELLO (and AUTH, auth.h)
 *   handshake_timeout_s after it was accepted, and a connection that for idle_timeout_s has sent
 *   nothing while it has no subscription, no unanswered request and no upload in progress, get
 *   an ERROR event (ELIMIT, naming the timeout) and are closed. Subscribers may stay silent for
 *   ever: they only listen to the stream. Checked once per server sweep (DF_SERVER_SWEEP_MS), so
 *   a timeout fires up to one sweep period late. Counted in stats (clients_handshake_timeout,
 *   clients_idle_timeout). */
#ifndef DF_SERVER_GUARD_H
#define DF_SERVER_GUARD_H

#include "server/server.h"

#define DF_GUARD_LOG_MS 1000 /* at most one refusal log line per second */

/* Descriptors the daemon needs besides one per connection: listeners, the store (database, WAL,
 * its shared memory), the pool's and libuv's eventfds and epoll, the log, HID devices, shared-
 * memory rings, the reserve. */
#define DF_GUARD_FD_RESERVE 64

/* Makes room for `max_clients` connections: raises the soft RLIMIT_NOFILE of the process to
 * max_clients + DF_GUARD_FD_RESERVE when it is lower, capped at the hard limit (never lowers
 * it: the soft limit systemd and most shells give is 1024, while the hard one is far higher).
 * Logs at info when it raised the limit and a warning, naming the hard limit and LimitNOFILE /
 * `ulimit -Hn`, when the hard limit is below what max_clients needs (the connections beyond it
 * are refused as out of file descriptors, see above). Returns the soft limit in force afterwards
 * (RLIM_INFINITY as LONG_MAX), or -1 when getrlimit fails. Any thread; called by df_guard_init
 * and on reload. */
long df_guard_fd_limit(int max_clients);

/* Raises the descriptor limit for cfg.max_clients (df_guard_fd_limit), then opens the reserve
 * descriptor (/dev/null). Errors: DF_EIO (naming the reason). */
int df_guard_init(df_server *srv, df_error *err);

/* Closes the reserve descriptor. Idempotent. */
void df_guard_free(df_server *srv);

/* Admission of a connection just accepted into `c` (counted in srv->n_conns): returns 0 when it
 * may proceed, 1 when it was refused (ERROR event queued, closing after the flush). "Open"
 * excludes connections already closing (their peer hung up) and refused ones. */
int df_guard_admit(df_conn *c);

/* 1 when admitting `c` now would exceed max_clients. conn.c then defers the decision to the end
 * of the loop iteration (df_conn_admit_waiting): libuv accepts every pending connection in one
 * go, often before it reads the hang-ups that arrived with them, so clients that reconnect
 * (close, then connect) at max_clients were refused for slots already free (bench_load: 87 of
 * 1,000). */
int df_guard_over_limit(const df_conn *c);

/* Called when accepting on `listener` failed with `status` (`kind`: "unix"/"tcp"): for
 * UV_EMFILE/UV_ENFILE uses the reserve descriptor to refuse the waiting connections; every
 * failure is logged through the refusal rate limit. */
void df_guard_accept_failed(df_server *srv, uv_stream_t *listener, int status, const char *kind);

/* Periodic (server sweep timer): applies the handshake and idle timeouts and logs the number of
 * refusals the rate limit held back. The caller first bumps srv->sweep_epoch and marks every
 * subscribed connection with it (c->sub_epoch): subscribers are exempt from the idle timeout. */
void df_guard_sweep(df_server *srv);

#endif
