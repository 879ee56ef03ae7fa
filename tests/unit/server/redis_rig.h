/* redis_rig.h — the cluster unit tests' rig: one real redis-server per test program, on a free
 * loopback port, without persistence, in a temporary directory (started by the cmocka group setup,
 * stopped by its teardown; nothing is started when redis-server is not installed, and the tests
 * then skip: g_pid <= 0). Header-only (static inline: each test uses what it needs); not
 * thread-safe (the globals belong to the test program's main thread). Include after cmocka.h. */
#ifndef DF_TESTS_REDIS_RIG_H
#define DF_TESTS_REDIS_RIG_H

#include <arpa/inet.h>
#include <hiredis/hiredis.h>
#include <netinet/in.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

static pid_t g_pid = -1; /* the redis-server's pid; <= 0: not started (tests skip) */
static int g_port;       /* its loopback port */
static char g_dir[64];   /* its temporary directory (made from the template given to redis_rig_start) */

/* A TCP port on 127.0.0.1 that was free a moment ago (bound and released), or -1. */
static inline int free_port(void)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    struct sockaddr_in a = {.sin_family = AF_INET, .sin_addr.s_addr = htonl(INADDR_LOOPBACK)};
    socklen_t len = sizeof a;
    if (fd < 0 || bind(fd, (struct sockaddr *)&a, sizeof a) != 0 ||
        getsockname(fd, (struct sockaddr *)&a, &len) != 0) {
        if (fd >= 0) close(fd);
        return -1;
    }
    close(fd);
    return ntohs(a.sin_port);
}

/* Monotonic time, seconds. */
static inline double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* Starts redis-server on a free port (g_port) in a new directory made from dir_template (a
 * mkdtemp template, "...XXXXXX"), cluster-enabled when cluster (CLUSTER KEYSLOT needs no slots
 * assigned; nodes.conf in that directory; the port then <= 55535, its bus port + 10000 below
 * 65536). Returns 0 when it answers PING (polled, 10 s) or when
 * redis-server is not installed (g_pid stays -1: the tests skip), -1 on a failure. */
static inline int redis_rig_start(const char *dir_template, int cluster)
{
    if (system("command -v redis-server >/dev/null 2>&1") != 0) return 0; /* tests skip */
    snprintf(g_dir, sizeof g_dir, "%s", dir_template);
    if (!mkdtemp(g_dir)) return -1;
    g_port = free_port();
    /* cluster mode also listens on port + 10000 (the cluster bus), so the port must be <= 55535
     * (ephemeral ports above that made redis-server refuse to start) */
    for (int tries = 0; cluster && g_port > 55535 && tries < 100; tries++) g_port = free_port();
    char port[16], conf[128];
    snprintf(port, sizeof port, "%d", g_port);
    snprintf(conf, sizeof conf, "%s/nodes.conf", g_dir);
    g_pid = fork();
    if (g_pid == 0) {
        if (!freopen("/dev/null", "w", stdout)) _exit(127);
        if (cluster)
            execlp("redis-server", "redis-server", "--port", port, "--bind", "127.0.0.1", "--save",
                   "", "--appendonly", "no", "--dir", g_dir, "--cluster-enabled", "yes",
                   "--cluster-config-file", conf, (char *)NULL);
        else
            execlp("redis-server", "redis-server", "--port", port, "--bind", "127.0.0.1", "--save",
                   "", "--appendonly", "no", "--dir", g_dir, (char *)NULL);
        _exit(127);
    }
    double deadline = now_s() + 10;
    while (now_s() < deadline) {
        redisContext *c = redisConnect("127.0.0.1", g_port);
        redisReply *rep = c && !c->err ? redisCommand(c, "PING") : NULL;
        int ok = rep && rep->type == REDIS_REPLY_STATUS;
        if (rep) freeReplyObject(rep);
        if (c) redisFree(c);
        if (ok) return 0;
        usleep(20000);
    }
    return -1;
}

/* cmocka group teardown: stops the redis-server (SIGTERM, waited for) and removes g_dir.
 * Returns 0, or -1 when the directory could not be removed. */
static inline int stop_redis(void **state)
{
    (void)state;
    if (g_pid > 0) {
        kill(g_pid, SIGTERM);
        waitpid(g_pid, NULL, 0);
        char cmd[128];
        snprintf(cmd, sizeof cmd, "rm -rf %s", g_dir);
        if (system(cmd) != 0) return -1;
    }
    return 0;
}

#endif
