/* bench_tls — what TLS 1.3 costs on deformd's TCP listener (issue 12, access control).
 *
 * Makes a throwaway self-signed certificate with the openssl CLI, starts two daemons (plain
 * loopback TCP, and TLS with tls_cert / tls_key) and prints, through libdeformclient:
 *   1. the 16-byte PING round trip over plain TCP and over TLS (p50 / p99 of PING_ROUNDS);
 *   2. connecting: TCP connect + HELLO, and TCP connect + TLS handshake + HELLO (p50 / p99 of
 *      CONNECT_ROUNDS).
 * Wall-clock numbers on a shared machine: for comparison, not a pass/fail target. Set DEFORMD_BIN
 * to use another daemon binary. */
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "client/deformclient.h"
#include "tests/bench/bench_daemon.h"

#define PING_ROUNDS 2000
#define CONNECT_ROUNDS 200

typedef struct daemon_proc {
    pid_t pid;
    char sock[128];
    int port;
} daemon_proc;

/* Starts deformd on `sock` and a free loopback port, with `cert`/`key` when non-NULL. */
static int start(daemon_proc *d, const char *exe, const char *dir, const char *tag,
                 const char *cert, const char *key)
{
    snprintf(d->sock, sizeof d->sock, "%s/%s.sock", dir, tag);
    d->port = bench_free_port();
    char tcp[64], log[256];
    snprintf(tcp, sizeof tcp, "127.0.0.1:%d", d->port);
    snprintf(log, sizeof log, "%s/%s.log", dir, tag);
    char *argv[] = {(char *)exe, "--foreground", "--store", "none", "--socket", d->sock,
                    "--tcp", tcp, "--log-level", "warn", cert ? "--tls-cert" : NULL,
                    (char *)cert, "--tls-key", (char *)key, NULL};
    d->pid = bench_daemon_spawn(argv, log);
    return bench_daemon_wait(d->sock);
}

static void stop(daemon_proc *d) { bench_daemon_stop(d->pid); }

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* Sorts v[0..n) and prints its p50 / p99 after `label`. */
static void report(const char *label, double *v, int n)
{
    if (n == 0) {
        printf("%-44s no samples\n", label);
        return;
    }
    qsort(v, (size_t)n, sizeof *v, cmp);
    printf("%-44s p50 %8.1f us  p99 %8.1f us  (%d)\n", label, v[n / 2], v[(n * 99) / 100], n);
}

static double now_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e6 + (double)ts.tv_nsec * 1e-3;
}

/* PING round trips over one connection (ca: TLS). */
static void bench_ping(const char *label, int port, const char *ca, double *v)
{
    df_client *c = NULL;
    df_error e;
    int n = 0;
    if (df_client_connect_tcp_tls("127.0.0.1", port, "bench", ca, &c, &e) != DF_OK) {
        printf("%-44s connect failed: %s\n", label, e.msg);
        return;
    }
    for (int i = 0; i < 100 + PING_ROUNDS; i++) {
        double us;
        if (df_client_ping(c, "deformd-ping-16b", 16, &us, &e) == DF_OK && i >= 100) v[n++] = us;
    }
    df_client_close(c);
    report(label, v, n);
}

/* Connect + (TLS) + HELLO, then close. */
static void bench_connect(const char *label, int port, const char *ca, double *v)
{
    int n = 0;
    for (int i = 0; i < CONNECT_ROUNDS; i++) {
        df_client *c = NULL;
        df_error e;
        double t0 = now_us();
        if (df_client_connect_tcp_tls("127.0.0.1", port, "bench", ca, &c, &e) != DF_OK) {
            printf("%-44s connect failed: %s\n", label, e.msg);
            return;
        }
        v[n++] = now_us() - t0;
        df_client_close(c);
    }
    report(label, v, n);
}

int main(int argc, char **argv)
{
    (void)argc;
    char exe[600], self[512];
    ssize_t sl = readlink("/proc/self/exe", self, sizeof self - 1);
    self[sl > 0 ? sl : 0] = '\0';
    char *slash = strrchr(self, '/');
    if (slash) *slash = '\0';
    snprintf(exe, sizeof exe, "%s/../bin/deformd", sl > 0 ? self : ".");
    if (getenv("DEFORMD_BIN")) snprintf(exe, sizeof exe, "%s", getenv("DEFORMD_BIN"));
    if (access(exe, X_OK) != 0) {
        fprintf(stderr, "%s: deformd not found at %s\n", argv[0], exe);
        return 1;
    }
    char dir[64] = "/tmp/deformd-bench-tls-XXXXXX";
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 1;
    }
    char cert[128], key[128], cmd[1024];
    snprintf(cert, sizeof cert, "%s/cert.pem", dir);
    snprintf(key, sizeof key, "%s/key.pem", dir);
    snprintf(cmd, sizeof cmd,
             "openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes "
             "-keyout %s -out %s -days 2 -subj /CN=localhost -addext "
             "subjectAltName=IP:127.0.0.1 >/dev/null 2>&1 && chmod 600 %s",
             key, cert, key);
    if (system(cmd) != 0) {
        fprintf(stderr, "bench_tls: openssl could not make a certificate\n");
        return 1;
    }
    daemon_proc plain = {0}, tls = {0};
    int fail = start(&plain, exe, dir, "plain", NULL, NULL) || start(&tls, exe, dir, "tls", cert, key);
    if (fail) {
        fprintf(stderr, "bench_tls: deformd did not come up (logs in %s)\n", dir);
    } else {
        double *v = malloc((PING_ROUNDS + CONNECT_ROUNDS) * sizeof *v);
        printf("bench_tls: TLS 1.3 (P-256 certificate) vs plain loopback TCP, wall clock\n");
        bench_ping("daemon PING 16 B, tcp", plain.port, NULL, v);
        bench_ping("daemon PING 16 B, tls", tls.port, cert, v);
        bench_connect("connect + HELLO, tcp", plain.port, NULL, v);
        bench_connect("connect + TLS handshake + HELLO, tls", tls.port, cert, v);
        free(v);
    }
    stop(&plain);
    stop(&tls);
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    if (system(cmd) != 0) fprintf(stderr, "bench_tls: could not remove %s\n", dir);
    return fail;
}
