/* dc_net.c — connecting and partial-transfer-safe reads/writes (see dc_net.h). */
#include "client/dc_net.h"

#include <errno.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/uio.h>
#include <sys/un.h>
#include <unistd.h>

int dc_net_connect_unix(const char *path, df_error *err)
{
    if (!path || !path[0])
        return df_error_set(err, DF_EINVAL, "empty Unix socket path");
    size_t n = strlen(path);
    if (n > DC_UNIX_PATH_MAX)
        return df_error_set(err, DF_EINVAL, "Unix socket path too long (%zu > %d bytes): %s", n,
                            DC_UNIX_PATH_MAX, path);
    int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0)
        return df_error_set(err, DF_EIO, "socket(AF_UNIX): %s", strerror(errno));
    struct sockaddr_un sa;
    memset(&sa, 0, sizeof sa);
    sa.sun_family = AF_UNIX;
    memcpy(sa.sun_path, path, n);
    int rc;
    do {
        rc = connect(fd, (struct sockaddr *)&sa, sizeof sa);
    } while (rc < 0 && errno == EINTR);
    if (rc < 0) {
        int e = errno;
        close(fd);
        return df_error_set(err, DF_EIO, "cannot connect to %s: %s", path, strerror(e));
    }
    return fd;
}

int dc_net_connect_tcp(const char *host, int port, df_error *err)
{
    if (!host || !host[0])
        return df_error_set(err, DF_EINVAL, "empty TCP host");
    if (port < 1 || port > 65535)
        return df_error_set(err, DF_EINVAL, "TCP port %d out of range 1..65535", port);
    char ps[16];
    snprintf(ps, sizeof ps, "%d", port);
    struct addrinfo hints, *res = NULL;
    memset(&hints, 0, sizeof hints);
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    int gai = getaddrinfo(host, ps, &hints, &res);
    if (gai != 0)
        return df_error_set(err, DF_EIO, "cannot resolve %s: %s", host, gai_strerror(gai));
    int last = 0;
    for (struct addrinfo *ai = res; ai; ai = ai->ai_next) {
        int fd = socket(ai->ai_family, ai->ai_socktype | SOCK_CLOEXEC, ai->ai_protocol);
        if (fd < 0) {
            last = errno;
            continue;
        }
        int rc;
        do {
            rc = connect(fd, ai->ai_addr, ai->ai_addrlen);
        } while (rc < 0 && errno == EINTR);
        if (rc == 0) {
            int one = 1;
            setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
            freeaddrinfo(res);
            return fd;
        }
        last = errno;
        close(fd);
    }
    freeaddrinfo(res);
    return df_error_set(err, DF_EIO, "cannot connect to %s:%d: %s", host, port,
                        strerror(last ? last : ECONNREFUSED));
}

/* Waits until `fd` is ready for `events`; returns 1 ready, 0 timeout, -1 error (errno set). */
static int wait_fd(int fd, short events, int timeout_ms)
{
    struct pollfd p = {.fd = fd, .events = events, .revents = 0};
    for (;;) {
        int rc = poll(&p, 1, timeout_ms);
        if (rc < 0 && errno == EINTR)
            continue;
        return rc < 0 ? -1 : rc;
    }
}

int dc_net_write2(int fd, const void *a, size_t alen, const void *b, size_t blen, df_error *err)
{
    struct iovec iov[2] = {{(void *)a, alen}, {(void *)b, blen}};
    int first = 0;
    if (iov[0].iov_len == 0)
        first = 1;
    while (first < 2) {
        struct msghdr mh;
        memset(&mh, 0, sizeof mh);
        mh.msg_iov = iov + first;
        mh.msg_iovlen = (size_t)(2 - first);
        if (mh.msg_iov[0].iov_len == 0 && mh.msg_iovlen == 1)
            break;
        ssize_t w = sendmsg(fd, &mh, MSG_NOSIGNAL);
        if (w < 0) {
            if (errno == EINTR)
                continue;
            if (errno == EAGAIN || errno == EWOULDBLOCK) {
                if (wait_fd(fd, POLLOUT, -1) < 0)
                    return df_error_set(err, DF_EIO, "poll: %s", strerror(errno));
                continue;
            }
            if (errno == EPIPE || errno == ECONNRESET)
                return df_error_set(err, DF_EIO, "connection closed by peer");
            return df_error_set(err, DF_EIO, "write: %s", strerror(errno));
        }
        size_t left = (size_t)w;
        while (first < 2 && left >= iov[first].iov_len) {
            left -= iov[first].iov_len;
            iov[first].iov_len = 0;
            first++;
        }
        if (first < 2) {
            iov[first].iov_base = (char *)iov[first].iov_base + left;
            iov[first].iov_len -= left;
        }
        while (first < 2 && iov[first].iov_len == 0)
            first++;
    }
    return DF_OK;
}

int dc_net_write_all(int fd, const void *buf, size_t len, df_error *err)
{
    return dc_net_write2(fd, buf, len, NULL, 0, err);
}

long dc_net_read_some(int fd, void *buf, size_t cap, int timeout_ms, df_error *err)
{
    for (;;) {
        ssize_t r = recv(fd, buf, cap, MSG_DONTWAIT);
        if (r > 0)
            return (long)r;
        if (r == 0)
            return df_error_set(err, DF_EIO, "connection closed by peer");
        if (errno == EINTR)
            continue;
        if (errno != EAGAIN && errno != EWOULDBLOCK) {
            if (errno == ECONNRESET)
                return df_error_set(err, DF_EIO, "connection closed by peer");
            return df_error_set(err, DF_EIO, "read: %s", strerror(errno));
        }
        int w = wait_fd(fd, POLLIN, timeout_ms);
        if (w < 0)
            return df_error_set(err, DF_EIO, "poll: %s", strerror(errno));
        if (w == 0)
            return df_error_set(err, DF_ESTATE, "timed out after %d ms waiting for data", timeout_ms);
    }
}

int dc_net_read_exact(int fd, void *buf, size_t len, int timeout_ms, df_error *err)
{
    size_t got = 0;
    while (got < len) {
        if (timeout_ms >= 0) {
            int w = wait_fd(fd, POLLIN, timeout_ms);
            if (w < 0)
                return df_error_set(err, DF_EIO, "poll: %s", strerror(errno));
            if (w == 0) {
                if (got == 0)
                    return df_error_set(err, DF_ESTATE, "timed out after %d ms waiting for data",
                                        timeout_ms);
                return df_error_set(err, DF_EIO, "timed out mid-frame (%zu of %zu bytes)", got, len);
            }
        }
        long r = dc_net_read_some(fd, (char *)buf + got, len - got, timeout_ms, err);
        if (r == DF_ESTATE && got > 0)
            return df_error_set(err, DF_EIO, "timed out mid-frame (%zu of %zu bytes)", got, len);
        if (r < 0)
            return (int)r;
        got += (size_t)r;
    }
    return DF_OK;
}
