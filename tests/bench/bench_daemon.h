/* bench_daemon.h — starting and stopping a real deformd from a C bench (bench_net, bench_tls).
 * Header-only (static functions); needs the client library (df_client_connect_unix). */
#ifndef DF_BENCH_DAEMON_H
#define DF_BENCH_DAEMON_H

#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <stdio.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include "client/deformclient.h"

/* A free loopback TCP port (bound then released; the daemon binds it right after), -1 if none. */
static int bench_free_port(void)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    struct sockaddr_in sa = {.sin_family = AF_INET};
    sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t sl = sizeof sa;
    int port = -1;
    if (fd >= 0 && bind(fd, (struct sockaddr *)&sa, sizeof sa) == 0 &&
        getsockname(fd, (struct sockaddr *)&sa, &sl) == 0)
        port = ntohs(sa.sin_port);
    if (fd >= 0) close(fd);
    return port;
}

/* Forks and execs argv[0] with `argv` (NULL-terminated), stderr to the file `log`, the child
 * killed with the bench (PR_SET_PDEATHSIG). Returns the child's pid, or -1. */
static pid_t bench_daemon_spawn(char *const argv[], const char *log)
{
    pid_t pid = fork();
    if (pid == 0) {
        prctl(PR_SET_PDEATHSIG, SIGTERM); /* never outlive the bench */
        if (!freopen(log, "w", stderr)) _exit(127);
        execv(argv[0], argv);
        _exit(127);
    }
    return pid;
}

/* Waits up to 10 s until a client can connect on the Unix socket `sock`: 0, or -1. */
static int bench_daemon_wait(const char *sock)
{
    for (int i = 0; i < 200; i++) {
        df_client *c;
        if (df_client_connect_unix(sock, "bench", &c, NULL) == DF_OK) {
            df_client_close(c);
            return 0;
        }
        usleep(50000);
    }
    return -1;
}

/* SIGTERM to `pid` (when > 0) and waits for it. */
static void bench_daemon_stop(pid_t pid)
{
    if (pid > 0) {
        kill(pid, SIGTERM);
        waitpid(pid, NULL, 0);
    }
}

#endif
