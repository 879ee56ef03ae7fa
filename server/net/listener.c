/* listener.c — Unix / TCP / socket-activated listeners (see listener.h). */
#include "server/net/listener.h"

#include <errno.h>
#include <grp.h>
#include <netdb.h>
#include <netinet/in.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include "server/net/conn.h"
#include "server/net/guard.h"
#include "server/log.h"
#include "server/net/sd.h"

static void on_unix_conn(uv_stream_t *s, int status)
{
    df_server *srv = s->data;
    if (status < 0) {
        df_guard_accept_failed(srv, s, status, "unix");
        return;
    }
    df_conn_accept(srv, s, 0);
}

static void on_tcp_conn(uv_stream_t *s, int status)
{
    df_server *srv = s->data;
    if (status < 0) {
        df_guard_accept_failed(srv, s, status, "tcp");
        return;
    }
    df_conn_accept(srv, s, 1);
}

/* 1 when something accepts connections on the Unix socket at `path`. */
static int unix_alive(const char *path)
{
    int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0) return 0;
    struct sockaddr_un sa;
    memset(&sa, 0, sizeof sa);
    sa.sun_family = AF_UNIX;
    snprintf(sa.sun_path, sizeof sa.sun_path, "%s", path);
    int ok = connect(fd, (struct sockaddr *)&sa, sizeof sa) == 0;
    close(fd);
    return ok;
}

/* Resolves cfg->socket_group (a name or a number) into *gid; (gid_t)-1 when unset. */
static int socket_gid(const df_server_config *cfg, gid_t *gid, df_error *err)
{
    *gid = (gid_t)-1;
    if (!cfg->socket_group[0]) return DF_OK;
    char buf[4096];
    struct group gr, *res = NULL;
    if (getgrnam_r(cfg->socket_group, &gr, buf, sizeof buf, &res) == 0 && res) {
        *gid = res->gr_gid;
        return DF_OK;
    }
    char *end = NULL;
    errno = 0;
    unsigned long v = strtoul(cfg->socket_group, &end, 10);
    if (!errno && end && !*end && cfg->socket_group[0] >= '0' && cfg->socket_group[0] <= '9' &&
        v < (unsigned long)(gid_t)-1) {
        *gid = (gid_t)v;
        return DF_OK;
    }
    return df_error_set(err, DF_EINVAL, "socket_group: no group '%s'", cfg->socket_group);
}

static int open_unix(df_server *srv, df_error *err)
{
    const char *path = srv->cfg.socket_path;
    mode_t mode = (mode_t)srv->cfg.socket_mode & 0777;
    gid_t gid;
    int grc = socket_gid(&srv->cfg, &gid, err);
    if (grc != DF_OK) return grc;
    char dir[DF_CONFIG_SOCKET_MAX];
    snprintf(dir, sizeof dir, "%s", path);
    char *slash = strrchr(dir, '/');
    if (slash && slash != dir) {
        *slash = '\0';
        struct stat st;
        if (stat(dir, &st) != 0 && mkdir(dir, 0755) != 0 && errno != EEXIST)
            return df_error_set(err, DF_EIO, "unix:%s: cannot create directory %s: %s", path, dir,
                                strerror(errno));
    }
    struct stat st;
    if (lstat(path, &st) == 0) {
        if (!S_ISSOCK(st.st_mode))
            return df_error_set(err, DF_EIO, "unix:%s: exists and is not a socket", path);
        if (unix_alive(path))
            return df_error_set(err, DF_EIO, "unix:%s: another server is listening there", path);
        unlink(path);
    }
    int rc = uv_pipe_init(srv->loop, &srv->unix_srv, 0);
    if (rc < 0) return df_error_set(err, DF_EIO, "unix:%s: %s", path, uv_strerror(rc));
    srv->unix_srv.data = srv;
    srv->have_unix = 1;
    /* The socket file is created by bind with 0777 & ~umask: narrow the umask around it so the
     * file never exists with more than `mode`, then set `mode` exactly (the loop has no other
     * threads yet, so the process-wide umask change is safe). */
    mode_t old_mask = umask(0777 & ~mode);
    rc = uv_pipe_bind(&srv->unix_srv, path);
    umask(old_mask);
    if (rc < 0) return df_error_set(err, DF_EIO, "unix:%s: bind: %s", path, uv_strerror(rc));
    srv->unix_owned = 1;
    if (gid != (gid_t)-1 && chown(path, (uid_t)-1, gid) != 0)
        return df_error_set(err, DF_EIO, "unix:%s: socket_group %s: %s", path,
                            srv->cfg.socket_group, strerror(errno));
    if (chmod(path, mode) != 0)
        return df_error_set(err, DF_EIO, "unix:%s: socket_mode %04o: %s", path, (unsigned)mode,
                            strerror(errno));
    rc = uv_listen((uv_stream_t *)&srv->unix_srv, DF_LISTEN_BACKLOG, on_unix_conn);
    if (rc < 0) return df_error_set(err, DF_EIO, "unix:%s: listen: %s", path, uv_strerror(rc));
    return DF_OK;
}

static int tcp_port_of(uv_tcp_t *t)
{
    struct sockaddr_storage ss;
    int len = sizeof ss;
    if (uv_tcp_getsockname(t, (struct sockaddr *)&ss, &len) < 0) return 0;
    if (ss.ss_family == AF_INET) return ntohs(((struct sockaddr_in *)&ss)->sin_port);
    if (ss.ss_family == AF_INET6) return ntohs(((struct sockaddr_in6 *)&ss)->sin6_port);
    return 0;
}

int df_listener_is_loopback(const struct sockaddr *sa)
{
    if (!sa) return 0;
    if (sa->sa_family == AF_INET) {
        uint32_t a = ntohl(((const struct sockaddr_in *)sa)->sin_addr.s_addr);
        return (a >> 24) == 127;
    }
    if (sa->sa_family == AF_INET6) {
        const struct in6_addr *a = &((const struct sockaddr_in6 *)sa)->sin6_addr;
        if (IN6_IS_ADDR_LOOPBACK(a)) return 1;
        return IN6_IS_ADDR_V4MAPPED(a) && a->s6_addr[12] == 127;
    }
    return 0;
}

static int open_tcp(df_server *srv, df_error *err)
{
    const char *host = srv->cfg.tcp_host;
    char port[16];
    snprintf(port, sizeof port, "%d", srv->cfg.tcp_port);
    struct addrinfo hints, *res = NULL;
    memset(&hints, 0, sizeof hints);
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
    /* "*" = every interface (the wildcard address) */
    int g = getaddrinfo(strcmp(host, "*") == 0 ? NULL : host, port, &hints, &res);
    if (g != 0 || !res)
        return df_error_set(err, DF_EIO, "tcp:%s:%s: %s", host, port, gai_strerror(g));
    int has_key = srv->cfg.access.key_file[0] != '\0';
    int has_tls = srv->cfg.access.tls_cert[0] != '\0';
    if (!df_listener_is_loopback(res->ai_addr) && !(has_key && has_tls)) {
        if (!srv->cfg.tcp_insecure) {
            freeaddrinfo(res);
            return df_error_set(err, DF_EINVAL,
                                "tcp:%s:%s: refusing a non-loopback address without %s: set "
                                "key_file (--key-file) and tls_cert/tls_key (--tls-cert, "
                                "--tls-key), or listen on 127.0.0.1 or ::1",
                                host, port,
                                !has_key && !has_tls ? "authentication and encryption"
                                : !has_key           ? "authentication (key_file)"
                                                     : "encryption (tls_cert/tls_key)");
        }
        if (!has_key)
            df_log(DF_LOG_WARN,
                   "tcp:%s:%s: listening on a non-loopback address without authentication "
                   "(tcp_insecure): anyone who can reach it controls every session",
                   host, port);
        else
            df_log(DF_LOG_WARN,
                   "tcp:%s:%s: listening on a non-loopback address without encryption "
                   "(tcp_insecure): the stream can be read and altered on the network",
                   host, port);
    }
    int rc = uv_tcp_init(srv->loop, &srv->tcp_srv);
    if (rc < 0) {
        freeaddrinfo(res);
        return df_error_set(err, DF_EIO, "tcp:%s:%s: %s", host, port, uv_strerror(rc));
    }
    srv->tcp_srv.data = srv;
    srv->have_tcp = 1;
    rc = uv_tcp_bind(&srv->tcp_srv, res->ai_addr, 0);
    freeaddrinfo(res);
    if (rc < 0) return df_error_set(err, DF_EIO, "tcp:%s:%s: bind: %s", host, port, uv_strerror(rc));
    rc = uv_listen((uv_stream_t *)&srv->tcp_srv, DF_LISTEN_BACKLOG, on_tcp_conn);
    if (rc < 0)
        return df_error_set(err, DF_EIO, "tcp:%s:%s: listen: %s", host, port, uv_strerror(rc));
    srv->tcp_port_bound = tcp_port_of(&srv->tcp_srv);
    return DF_OK;
}

static int adopt_fds(df_server *srv, df_error *err)
{
    int fds[DF_SD_MAX_LISTEN_FDS];
    int n = df_sd_listen_fds(fds, DF_SD_MAX_LISTEN_FDS);
    if (n < 0) return df_error_set(err, DF_EINVAL, "malformed LISTEN_FDS/LISTEN_PID");
    for (int i = 0; i < n; i++) {
        struct sockaddr_storage ss;
        socklen_t sl = sizeof ss;
        if (getsockname(fds[i], (struct sockaddr *)&ss, &sl) != 0) continue;
        int rc;
        if (ss.ss_family == AF_UNIX && !srv->have_unix) {
            if ((rc = uv_pipe_init(srv->loop, &srv->unix_srv, 0)) < 0 ||
                (srv->have_unix = 1, rc = uv_pipe_open(&srv->unix_srv, fds[i])) < 0)
                return df_error_set(err, DF_EIO, "socket-activated fd %d: %s", fds[i],
                                    uv_strerror(rc));
            srv->unix_srv.data = srv;
            const struct sockaddr_un *su = (const struct sockaddr_un *)&ss;
            if (sl > offsetof(struct sockaddr_un, sun_path) && su->sun_path[0]) {
                size_t l = strnlen(su->sun_path, sizeof su->sun_path);
                if (l >= sizeof srv->cfg.socket_path) l = sizeof srv->cfg.socket_path - 1;
                memcpy(srv->cfg.socket_path, su->sun_path, l);
                srv->cfg.socket_path[l] = '\0';
            }
            rc = uv_listen((uv_stream_t *)&srv->unix_srv, DF_LISTEN_BACKLOG, on_unix_conn);
        } else if ((ss.ss_family == AF_INET || ss.ss_family == AF_INET6) && !srv->have_tcp) {
            if ((rc = uv_tcp_init(srv->loop, &srv->tcp_srv)) < 0 ||
                (srv->have_tcp = 1, rc = uv_tcp_open(&srv->tcp_srv, fds[i])) < 0)
                return df_error_set(err, DF_EIO, "socket-activated fd %d: %s", fds[i],
                                    uv_strerror(rc));
            srv->tcp_srv.data = srv;
            srv->tcp_port_bound = tcp_port_of(&srv->tcp_srv);
            snprintf(srv->cfg.tcp_host, sizeof srv->cfg.tcp_host, "%s", "activated");
            rc = uv_listen((uv_stream_t *)&srv->tcp_srv, DF_LISTEN_BACKLOG, on_tcp_conn);
        } else {
            df_log(DF_LOG_WARN, "socket-activated fd %d ignored (unsupported or duplicate)",
                   fds[i]);
            close(fds[i]);
            continue;
        }
        if (rc < 0)
            return df_error_set(err, DF_EIO, "socket-activated fd %d: listen: %s", fds[i],
                                uv_strerror(rc));
        df_log(DF_LOG_INFO, "using socket-activated fd %d", fds[i]);
    }
    return DF_OK;
}

int df_listener_open(df_server *srv, df_error *err)
{
    int rc = adopt_fds(srv, err);
    if (rc == DF_OK && !srv->have_unix && srv->cfg.socket_path[0]) rc = open_unix(srv, err);
    if (rc == DF_OK && !srv->have_tcp && srv->cfg.tcp_host[0]) rc = open_tcp(srv, err);
    if (rc == DF_OK && !srv->have_unix && !srv->have_tcp)
        rc = df_error_set(err, DF_EINVAL, "no listener: set a socket path or a tcp address");
    if (rc != DF_OK) df_listener_close(srv);
    return rc;
}

void df_listener_close(df_server *srv)
{
    if (srv->have_unix) {
        if (!uv_is_closing((uv_handle_t *)&srv->unix_srv)) uv_close((uv_handle_t *)&srv->unix_srv, NULL);
        if (srv->unix_owned) unlink(srv->cfg.socket_path);
        srv->unix_owned = 0;
    }
    if (srv->have_tcp && !uv_is_closing((uv_handle_t *)&srv->tcp_srv))
        uv_close((uv_handle_t *)&srv->tcp_srv, NULL);
}
