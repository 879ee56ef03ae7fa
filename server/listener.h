/* listener.h — the listening sockets of deformd: socket-activated fds, a Unix socket and an
 * optional TCP socket (loop thread). */
#ifndef DF_SERVER_LISTENER_H
#define DF_SERVER_LISTENER_H

#include "server/server.h"

#define DF_LISTEN_BACKLOG 128

/* Opens the listeners described by srv->cfg (after adopting LISTEN_FDS sockets: a socket-activated
 * Unix or TCP socket replaces the configured one of the same family). For the Unix socket: creates
 * the parent directory when missing (0755), removes a stale socket file nobody listens on, refuses
 * to replace a live one or a non-socket file. Errors: DF_EIO naming the address and the reason;
 * DF_EINVAL when no listener at all is configured. */
int df_listener_open(df_server *srv, df_error *err);

/* Closes the listeners (and unlinks the socket file we created). Idempotent. */
void df_listener_close(df_server *srv);

#endif
