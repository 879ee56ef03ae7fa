/* live_daemon.h — starts and stops the real build/bin/deformd for the client tests that talk to
 * it (test_live.c, test_parity.c): a private temporary socket, its log kept out of cmocka's
 * output, and the daemon killed with the test process (PR_SET_PDEATHSIG). */
#ifndef DF_TEST_LIVE_DAEMON_H
#define DF_TEST_LIVE_DAEMON_H

#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include "client/deformclient.h"

typedef struct live_daemon {
    pid_t pid;
    char dir[64], sock[96];
} live_daemon;

/* Path of deformd relative to this binary: BUILD/tests/unit/client/test_X -> BUILD/bin/deformd.
 * 0 when it exists and is executable, -1 otherwise. */
static inline int live_daemon_path(char *out, size_t cap)
{
    char self[PATH_MAX];
    ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
    if (n <= 0)
        return -1;
    self[n] = '\0';
    for (int k = 0; k < 4; k++) {
        char *s = strrchr(self, '/');
        if (!s)
            return -1;
        *s = '\0';
    }
    return snprintf(out, cap, "%s/bin/deformd", self) < (int)cap && access(out, X_OK) == 0 ? 0 : -1;
}

/* Starts `exe` on a socket in a fresh /tmp/dc-<tag>-XXXXXX directory, with the config file text
 * `config` when non-NULL, and waits (<= 5 s) until a client named `tag` can connect. 0 on
 * success, -1 otherwise. */
static inline int live_daemon_start_config(live_daemon *d, const char *exe, const char *tag,
                                           const char *config)
{
    snprintf(d->dir, sizeof d->dir, "/tmp/dc-%s-XXXXXX", tag);
    if (!mkdtemp(d->dir))
        return -1;
    snprintf(d->sock, sizeof d->sock, "%s/d.sock", d->dir);
    char conf[128] = "";
    if (config) {
        snprintf(conf, sizeof conf, "%s/deformd.conf", d->dir);
        FILE *f = fopen(conf, "w");
        if (!f || fputs(config, f) < 0 || fclose(f) != 0)
            return -1;
    }
    d->pid = fork();
    if (d->pid == 0) {
        prctl(PR_SET_PDEATHSIG, SIGTERM);
        char log[128];
        snprintf(log, sizeof log, "%s/deformd.log", d->dir);
        FILE *f = freopen(log, "w", stderr); /* keep cmocka's output lines clean */
        (void)f;
        /* --store none: sessions in memory only (no store shared between tests or runs) */
        if (conf[0])
            execl(exe, exe, "--foreground", "--socket", d->sock, "--log-level", "error",
                  "--store", "none", "--config", conf, (char *)NULL);
        else
            execl(exe, exe, "--foreground", "--socket", d->sock, "--log-level", "error",
                  "--store", "none", (char *)NULL);
        _exit(127);
    }
    for (int i = 0; i < 100; i++) {
        df_client *c;
        if (df_client_connect_unix(d->sock, tag, &c, NULL) == DF_OK) {
            df_client_close(c);
            return 0;
        }
        usleep(50000);
    }
    return -1;
}

/* live_daemon_start_config without a config file. */
static inline int live_daemon_start(live_daemon *d, const char *exe, const char *tag)
{
    return live_daemon_start_config(d, exe, tag, NULL);
}

/* Stops the daemon (SIGTERM, waits) and removes its directory. */
static inline void live_daemon_stop(live_daemon *d)
{
    kill(d->pid, SIGTERM);
    waitpid(d->pid, NULL, 0);
    char log[128];
    snprintf(log, sizeof log, "%s/deformd.log", d->dir);
    unlink(log);
    unlink(d->sock);
    snprintf(log, sizeof log, "%s/deformd.conf", d->dir);
    unlink(log);
    rmdir(d->dir);
}

/* An n x n grid (n >= 2) as OFF text: 2 (n-1)^2 triangles over the unit square, slightly curved
 * (z = 0.1 (i mod 3) / n). Returns malloc'd text (caller frees; NULL when out of memory), its
 * length in *len. */
static inline char *live_grid_off(int n, size_t *len)
{
    size_t cap = (size_t)n * n * 64 + 64;
    char *t = malloc(cap);
    *len = 0;
    if (!t) return NULL;
    size_t o = (size_t)snprintf(t, cap, "OFF\n%d %d 0\n", n * n, 2 * (n - 1) * (n - 1));
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++)
            o += (size_t)snprintf(t + o, cap - o, "%g %g %g\n", i / (n - 1.0), j / (n - 1.0),
                                  0.1 * (i % 3) / n);
    for (int j = 0; j + 1 < n; j++)
        for (int i = 0; i + 1 < n; i++) {
            int a = j * n + i;
            o += (size_t)snprintf(t + o, cap - o, "3 %d %d %d\n3 %d %d %d\n", a, a + 1, a + n + 1,
                                  a, a + n + 1, a + n);
        }
    *len = o;
    return t;
}

#endif
