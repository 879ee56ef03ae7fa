/* listener.h — the listening sockets of deformd: socket-activated fds, a Unix socket and an
 * optional TCP socket (loop thread). */
#ifndef DF_SERVER_LISTENER_H
#define DF_SERVER_LISTENER_H

#include "server/server.h"

#include <sys/socket.h>

/* listen() backlog: SOMAXCONN (4096; the kernel caps it at net.core.somaxconn). With 128, a burst
 * of connections larger than that arriving while the loop thread is busy (every client
 * reconnecting after a restart) overflowed the accept queue: the dropped SYNs were retried by the
 * clients' kernels after 1 s, 3 s, ... (bench_load measured handshakes of up to 2.7 s). Also
 * applied to socket-activated listeners, whose Backlog= it would otherwise shrink. */
#define DF_LISTEN_BACKLOG SOMAXCONN

/* Opens the listeners described by srv->cfg (after adopting LISTEN_FDS sockets: a socket-activated
 * Unix or TCP socket replaces the configured one of the same family, and keeps the mode and
 * group its unit gave it). For the Unix socket: creates the parent directory when missing (0755),
 * removes a stale socket file nobody listens on, refuses to replace a live one or a non-socket
 * file, creates the socket with cfg->socket_mode (never wider, whatever the umask) and
 * cfg->socket_group. A configured TCP address must be loopback unless both key_file and
 * tls_cert/tls_key are set (or cfg->tcp_insecure, the explicit opt-out: then a warning is logged).
 * Errors: DF_EIO naming the address and the reason; DF_EINVAL when no listener at all is
 * configured, for a non-loopback TCP address without key and TLS (the message says what to set),
 * or an unknown socket_group. */
int df_listener_open(df_server *srv, df_error *err);

/* 1 when `sa` is an IPv4 127.0.0.0/8, IPv6 ::1 or IPv4-mapped 127.x address, else 0. */
struct sockaddr;
int df_listener_is_loopback(const struct sockaddr *sa);

/* Closes the listeners (and unlinks the socket file we created). Idempotent. */
void df_listener_close(df_server *srv);

#endif
