/* sd.c — sd_notify and LISTEN_FDS socket activation (see sd.h). */
#include "server/net/sd.h"

#include <errno.h>
#include <fcntl.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include "core/common/df_error.h"

int df_sd_notify(const char *state)
{
    const char *path = getenv("NOTIFY_SOCKET");
    if (!path || !path[0]) return 0;
    if (!state) return DF_EINVAL;
    size_t pl = strlen(path);
    struct sockaddr_un sa;
    memset(&sa, 0, sizeof sa);
    sa.sun_family = AF_UNIX;
    if ((path[0] != '/' && path[0] != '@') || pl >= sizeof sa.sun_path) return DF_EINVAL;
    memcpy(sa.sun_path, path, pl);
    if (path[0] == '@') sa.sun_path[0] = '\0';
    socklen_t sl = (socklen_t)(offsetof(struct sockaddr_un, sun_path) + pl);
    int fd = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (fd < 0) return DF_EIO;
    ssize_t n = sendto(fd, state, strlen(state), MSG_NOSIGNAL, (struct sockaddr *)&sa, sl);
    close(fd);
    return n == (ssize_t)strlen(state) ? 1 : DF_EIO;
}

static int parse_int(const char *s, long *out)
{
    if (!s || !*s) return DF_EINVAL;
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (errno || *end || v < 0) return DF_EINVAL;
    *out = v;
    return DF_OK;
}

int df_sd_listen_fds(int *fds, int max)
{
    const char *spid = getenv("LISTEN_PID"), *sn = getenv("LISTEN_FDS");
    if (!spid || !sn) return 0;
    long pid, n;
    if (parse_int(spid, &pid) || parse_int(sn, &n)) return DF_EINVAL;
    if (pid != (long)getpid()) return 0;
    unsetenv("LISTEN_PID");
    unsetenv("LISTEN_FDS");
    unsetenv("LISTEN_FDNAMES");
    if (n < 1 || n > max || !fds) return n == 0 ? 0 : DF_EINVAL;
    for (int i = 0; i < n; i++) {
        int fd = DF_SD_LISTEN_FDS_START + i;
        int fl = fcntl(fd, F_GETFD);
        if (fl < 0) return DF_EINVAL;
        fcntl(fd, F_SETFD, fl | FD_CLOEXEC);
        fds[i] = fd;
    }
    return (int)n;
}
