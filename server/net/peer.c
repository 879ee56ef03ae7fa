/* peer.c — peer credentials and addresses of connections (see peer.h). */
#include "server/net/peer.h"

#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "proto/messages.h"
#include "proto/wire_error.h"
#include "server/log.h"
#include "server/net/conn.h"
#include "server/net/listener.h"
#include "server/net/reply.h"

#ifndef SO_PEERGROUPS
#define SO_PEERGROUPS 59 /* Linux 4.13 */
#endif
#define DF_PEER_MAX_GROUPS 256

static void tcp_identity(df_conn *c)
{
    struct sockaddr_storage ss;
    int len = sizeof ss;
    if (uv_tcp_getpeername(&c->h.tcp, (struct sockaddr *)&ss, &len) < 0) {
        snprintf(c->peer_host, sizeof c->peer_host, "unknown");
        snprintf(c->peer_addr, sizeof c->peer_addr, "unknown address");
        return;
    }
    int port = 0;
    if (ss.ss_family == AF_INET) {
        const struct sockaddr_in *a = (const struct sockaddr_in *)&ss;
        inet_ntop(AF_INET, &a->sin_addr, c->peer_host, sizeof c->peer_host);
        port = ntohs(a->sin_port);
    } else if (ss.ss_family == AF_INET6) {
        const struct sockaddr_in6 *a = (const struct sockaddr_in6 *)&ss;
        inet_ntop(AF_INET6, &a->sin6_addr, c->peer_host, sizeof c->peer_host);
        port = ntohs(a->sin6_port);
    } else {
        snprintf(c->peer_host, sizeof c->peer_host, "family-%d", (int)ss.ss_family);
    }
    snprintf(c->peer_addr, sizeof c->peer_addr, "%s port %d", c->peer_host, port);
    c->peer_loopback = df_listener_is_loopback((const struct sockaddr *)&ss);
}

int df_peer_admit(df_conn *c)
{
    if (c->is_tcp) {
        snprintf(c->principal, sizeof c->principal, "tcp"); /* AUTH may name it (auth.h) */
        tcp_identity(c);
        df_log(DF_LOG_DEBUG, "client %llu connected (tcp, %s)", (unsigned long long)c->id,
               c->peer_addr);
        return 0;
    }
    const df_access_config *acc = &c->srv->cfg.access;
    uv_os_fd_t fd = -1;
    struct ucred cred;
    socklen_t cl = sizeof cred;
    uint32_t groups[DF_PEER_MAX_GROUPS];
    int ngroups = 0;
    if (uv_fileno((uv_handle_t *)&c->h.stream, &fd) == 0 &&
        getsockopt(fd, SOL_SOCKET, SO_PEERCRED, &cred, &cl) == 0 && cl == sizeof cred) {
        c->peer_cred = 1;
        c->peer_uid = (uint32_t)cred.uid;
        c->peer_gid = (uint32_t)cred.gid;
        c->peer_pid = (int32_t)cred.pid;
        gid_t g[DF_PEER_MAX_GROUPS];
        socklen_t gl = sizeof g;
        if (df_access_restricted(acc) && getsockopt(fd, SOL_SOCKET, SO_PEERGROUPS, g, &gl) == 0) {
            ngroups = (int)(gl / sizeof g[0]);
            for (int i = 0; i < ngroups; i++) groups[i] = (uint32_t)g[i];
        }
    }
    if (c->peer_cred) {
        snprintf(c->principal, sizeof c->principal, "uid:%u", c->peer_uid);
        c->admin = c->peer_uid == 0 || c->peer_uid == (uint32_t)geteuid();
    } else {
        snprintf(c->principal, sizeof c->principal, "unix:unknown");
    }
    if (c->peer_cred)
        df_log(DF_LOG_DEBUG, "client %llu connected (unix, uid %u gid %u pid %d)",
               (unsigned long long)c->id, c->peer_uid, c->peer_gid, (int)c->peer_pid);
    else
        df_log(DF_LOG_DEBUG, "client %llu connected (unix, credentials unknown: %s)",
               (unsigned long long)c->id, strerror(errno));
    if (!df_access_restricted(acc)) return 0;
    if (c->peer_cred &&
        df_access_peer_allowed(acc, c->peer_uid, c->peer_gid, groups, ngroups))
        return 0;
    char msg[200];
    if (c->peer_cred)
        snprintf(msg, sizeof msg,
                 "peer uid %u gid %u (pid %d) is not allowed on this socket: neither its uid "
                 "is in allow_uids nor one of its groups in allow_gids",
                 c->peer_uid, c->peer_gid, (int)c->peer_pid);
    else
        snprintf(msg, sizeof msg,
                 "peer credentials could not be read, and this socket is restricted by "
                 "allow_uids / allow_gids");
    df_log(DF_LOG_WARN, "client %llu refused: %s", (unsigned long long)c->id, msg);
    c->srv->stats.clients_refused_peer++;
    df_reply_error(c, DF_MSG_ERROR, 0, DF_EPROTO_AUTH, "%s", msg);
    df_conn_close_after_flush(c, "peer not allowed (allow_uids / allow_gids)");
    return 1;
}
