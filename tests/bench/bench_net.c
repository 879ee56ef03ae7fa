/* bench_net.c — network benchmarks of deformd (run by `make bench`).
 *
 * Starts build/bin/deformd (next to this binary: ../bin/deformd) on a temporary Unix socket and
 * a loopback TCP port, uploads programmatic grid meshes (1k, 100k, 1M vertices, binary PLY) and
 * measures, redis-benchmark style:
 *   1. the raw 16-byte echo round trip over a Unix socket and loopback TCP (an in-process echo
 *      thread: the machine's floor for any request/response);
 *   2. brush update round trip (request sent -> its displacement event fully received) on the
 *      1k and 100k meshes over Unix and TCP, p50/p99 over 1,000 updates;
 *   3. full 1M-vertex displacement frames (dense, 12 MB) to one subscriber: frames/s and MB/s,
 *      pure stream (pipelined SNAPSHOT replies) and brush-driven (each frame a new version);
 *   4. the writer's update rate (update -> ack) on the 1k mesh with 1 vs 32 subscribers reading
 *      in a separate thread (one epoll set), every subscriber taking every version: once with
 *      the stream on their sockets, once through the shared-memory ring (STREAM_SHM, PROTOCOL.md
 *      6.1; the library copies each frame out of the ring, as a real subscriber does).
 * After the 1k round trips it prints the daemon's side from STATS: compute-pool tasks, how many
 * woke the loop, how many a spinning worker took without a wake-up (deformd --spin-us), and the
 * worker time of the last brush update. DEFORMD_ARGS adds daemon options (e.g. "--spin-us 60").
 * Latencies and rates are the best of BENCH_REPEAT runs (the machine is shared and noisy); the
 * echo floor is measured before the daemon starts and again after the 1k runs, best of both.
 * BENCH_NET_ONLY=rt,frames,writer runs only the named sections (for profiling one of them);
 * BENCH_NET_VERBOSE=1 prints each writer run with the daemon's blocked writes.
 * Targets (issue): 1k p50 <= 3x echo; 100k p50 <= 2 ms; >= 60 1M frames/s; 32 subs <= 2x.
 * Exit status 0 when every measurement ran (targets are reported, not enforced), 1 otherwise. */
#include <arpa/inet.h>
#include <dirent.h>
#include <errno.h>
#include <limits.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "client/dc_net.h"
#include "client/deformclient.h"
#include "tests/bench/bench_daemon.h"
#include "tests/bench/bench_grid.h"

#define ECHO_BYTES 16
#define ECHO_WARMUP 500
#define ECHO_ROUNDS 20000
#define RT_WARMUP 50
#define RT_ROUNDS 1000
#define STREAM_SECONDS 3.0
#define STREAM_INFLIGHT 4
#define WRITER_UPDATES 2000
#define MANY_SUBS 32
#define MAX_EXTRA_ARGS 8       /* words of DEFORMD_ARGS passed to the daemon */
#define BENCH_REPEAT 3        /* latency/rate runs per case; the best one is reported */
#define TARGET_ECHO_RATIO 3.0
#define TARGET_100K_P50_US 2000.0
#define TARGET_1M_FPS 60.0
#define TARGET_SUB_COST 2.0
/* The figures README.md recorded before the server pipeline rework (2026-11-22, quiet 2-core
 * machine), printed beside each new measurement so a regression shows. */
#define OLD_1K_P50_US_UNIX 30.0
#define OLD_1K_P50_US_TCP 32.0
#define OLD_100K_P50_US_UNIX 860.0
#define OLD_100K_P50_US_TCP 1150.0
#define OLD_1M_FPS_STREAM 345.0
#define OLD_1M_FPS_BRUSH 96.0
#define OLD_SUB_COST_SOCKET 2.26
#define OLD_SUB_COST_SHM 1.26

typedef struct stats {
    double p50, p99, mean;
    int n;
} stats;

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static stats stats_of(double *t, int n)
{
    stats s = {0, 0, 0, n};
    if (n <= 0)
        return s;
    qsort(t, (size_t)n, sizeof *t, cmp_double);
    double sum = 0;
    for (int i = 0; i < n; i++)
        sum += t[i];
    s.p50 = t[n / 2];
    s.p99 = t[(int)((n - 1) * 0.99)];
    s.mean = sum / n;
    return s;
}

static double now_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e6 + (double)ts.tv_nsec * 1e-3;
}

/* ---- raw 16-byte echo baseline ------------------------------------------------------------- */

static void *echo_thread(void *arg)
{
    int lfd = *(int *)arg;
    int fd = accept(lfd, NULL, NULL);
    if (fd < 0)
        return NULL;
    int one = 1;
    setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    char b[ECHO_BYTES];
    while (dc_net_read_exact(fd, b, sizeof b, -1, NULL) == DF_OK &&
           dc_net_write_all(fd, b, sizeof b, NULL) == DF_OK) {
    }
    close(fd);
    return NULL;
}

/* Round trips of a 16-byte message through an echo thread over AF_UNIX or AF_INET loopback. */
static int bench_echo(int family, const char *dir, stats *out)
{
    int lfd = socket(family, SOCK_STREAM | SOCK_CLOEXEC, 0);
    char path[108];
    int port = 0, ok = lfd >= 0;
    if (ok && family == AF_UNIX) {
        struct sockaddr_un sa = {.sun_family = AF_UNIX};
        ok = snprintf(path, sizeof path, "%s/echo.sock", dir) < (int)sizeof path;
        memcpy(sa.sun_path, path, sizeof path);
        ok = bind(lfd, (struct sockaddr *)&sa, sizeof sa) == 0;
    } else if (ok) {
        struct sockaddr_in sa = {.sin_family = AF_INET};
        sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        socklen_t sl = sizeof sa;
        ok = bind(lfd, (struct sockaddr *)&sa, sizeof sa) == 0 &&
             getsockname(lfd, (struct sockaddr *)&sa, &sl) == 0;
        port = ntohs(sa.sin_port);
    }
    if (!ok || listen(lfd, 4) != 0) {
        if (lfd >= 0)
            close(lfd);
        return -1;
    }
    pthread_t th;
    pthread_create(&th, NULL, echo_thread, &lfd);
    int fd = family == AF_UNIX ? dc_net_connect_unix(path, NULL)
                               : dc_net_connect_tcp("127.0.0.1", port, NULL);
    double *t = malloc(ECHO_ROUNDS * sizeof *t);
    int n = 0;
    char b[ECHO_BYTES] = "deformd-echo-16";
    for (int i = 0; fd >= 0 && t && i < ECHO_WARMUP + ECHO_ROUNDS; i++) {
        double t0 = now_us();
        if (dc_net_write_all(fd, b, sizeof b, NULL) || dc_net_read_exact(fd, b, sizeof b, 5000, NULL))
            break;
        if (i >= ECHO_WARMUP)
            t[n++] = now_us() - t0;
    }
    if (fd >= 0)
        close(fd);
    else
        shutdown(lfd, SHUT_RDWR);
    pthread_join(th, NULL);
    close(lfd);
    if (family == AF_UNIX)
        unlink(path);
    *out = stats_of(t, n);
    free(t);
    return n == ECHO_ROUNDS ? 0 : -1;
}

/* Lowers *eu / *et (unix / tcp echo; n == 0: unset) to the best p50 of BENCH_REPEAT more echo
 * runs. Returns nonzero when a run failed. */
static int echo_best(const char *dir, stats *eu, stats *et)
{
    int fail = 0;
    for (int r = 0; r < BENCH_REPEAT; r++) {
        stats a, b;
        fail |= bench_echo(AF_UNIX, dir, &a) | bench_echo(AF_INET, dir, &b);
        if (eu->n == 0 || a.p50 < eu->p50)
            *eu = a;
        if (et->n == 0 || b.p50 < et->p50)
            *et = b;
    }
    return fail;
}

/* ---- daemon and meshes ---------------------------------------------------------------------- */

typedef struct daemon_proc {
    pid_t pid;
    char dir[64];
    char sock[96];
    int port;
} daemon_proc;

static int daemon_start(daemon_proc *d, const char *exe)
{
    snprintf(d->sock, sizeof d->sock, "%s/deformd.sock", d->dir);
    d->port = bench_free_port();
    char tcp[64], log[128];
    snprintf(tcp, sizeof tcp, "127.0.0.1:%d", d->port);
    snprintf(log, sizeof log, "%s/deformd.log", d->dir);
    char *argv[10 + MAX_EXTRA_ARGS + 1] = {(char *)exe, "--foreground", "--socket", d->sock,
                                            "--tcp", tcp, "--log-level", "warn", "--store",
                                            "none"}; /* DEFORMD_ARGS may set --store */
    int argc = 10;
    static char extra[256]; /* DEFORMD_ARGS: extra daemon options, space separated */
    snprintf(extra, sizeof extra, "%s", getenv("DEFORMD_ARGS") ? getenv("DEFORMD_ARGS") : "");
    for (char *t = strtok(extra, " "); t && argc < 10 + MAX_EXTRA_ARGS; t = strtok(NULL, " "))
        argv[argc++] = t;
    argv[argc] = NULL;
    d->pid = bench_daemon_spawn(argv, log);
    return bench_daemon_wait(d->sock);
}

static void daemon_stop(daemon_proc *d) { bench_daemon_stop(d->pid); }

static uint64_t load_grid(df_client *c, int n, const char *name)
{
    size_t len;
    uint8_t *ply = grid_ply(n, &len);
    df_msg_session_info info;
    df_error e;
    int rc = ply ? df_client_load_mesh_bytes(c, name, DF_FMT_PLY, ply, len, 0, &info, &e) : DF_ENOMEM;
    free(ply);
    if (rc) {
        fprintf(stderr, "bench_net: loading %s failed: %s\n", name, rc == DF_ENOMEM ? "ENOMEM" : e.msg);
        return 0;
    }
    return info.session_id;
}

static void brush_msg(df_msg_brush *b, uint64_t sid, double radius)
{
    df_msg_brush_defaults(b);
    b->session_id = sid;
    b->type = DF_BRUSH_GRAB;
    b->radius = radius;
    b->nu = 0.45;
    b->center[0] = b->center[1] = 0.5;
}

/* Reads frames until the displacement event of `version` is complete (or the reply of
 * `reply_id` when version is 0). Returns 0 or -1. */
static int wait_for(df_client *c, uint64_t version, uint64_t reply_id)
{
    for (;;) {
        df_frame_header h;
        const uint8_t *p;
        df_error e;
        if (df_client_recv(c, 10000, &h, &p, &e) != DF_OK) {
            fprintf(stderr, "bench_net: %s\n", e.msg);
            return -1;
        }
        if (h.flags & DF_FLAG_ERROR) {
            df_msg_error_decode(p, h.payload_len, &e, NULL);
            fprintf(stderr, "bench_net: server error: %s\n", e.msg);
            return -1;
        }
        if (version && h.type == DF_MSG_DISPLACEMENT && !(h.flags & DF_FLAG_MORE) &&
            h.payload_len >= 16 && df_le64_load(p + 8) == version)
            return 0;
        if (!version && (h.flags & DF_FLAG_REPLY) && h.request_id == reply_id &&
            !(h.flags & DF_FLAG_MORE))
            return 0;
    }
}

/* Brush update round trips on session `sid`: subscribe, begin, RT_ROUNDS updates each timed
 * from send to its displacement event, end. */
static int bench_rt(df_client *c, uint64_t sid, stats *out)
{
    df_error e;
    df_msg_session_info info;
    df_msg_ack ack;
    df_msg_brush b;
    brush_msg(&b, sid, 0.2);
    if (df_client_subscribe(c, sid, 0, &info, &e) || df_client_brush_begin(c, &b, &ack, &e)) {
        fprintf(stderr, "bench_net: %s\n", e.msg);
        return -1;
    }
    uint64_t version = ack.version;
    double *t = malloc(RT_ROUNDS * sizeof *t);
    int n = 0, rc = 0;
    df_buf buf;
    df_buf_init(&buf);
    for (int i = 0; t && i < RT_WARMUP + RT_ROUNDS && rc == 0; i++) {
        df_msg_brush_update u;
        memset(&u, 0, sizeof u);
        u.session_id = sid;
        u.move[0] = 0.001 * (1 + i % 7);
        u.move[2] = 0.0005 * (i % 3);
        df_buf_reset(&buf);
        uint64_t id;
        double t0 = now_us();
        rc = df_msg_brush_update_encode(&u, &buf, &e) ||
             df_client_send(c, DF_MSG_BRUSH_UPDATE, 0, 0, buf.data, buf.len, &id, &e) ||
             wait_for(c, version + 1, 0);
        double dt = now_us() - t0;
        rc = rc || wait_for(c, 0, id);
        version++;
        if (i >= RT_WARMUP && rc == 0)
            t[n++] = dt;
    }
    df_buf_free(&buf);
    if (rc == 0 && (df_client_brush_end(c, sid, NULL, &e) || df_client_unsubscribe(c, sid, &e)))
        rc = -1;
    *out = stats_of(t, n);
    free(t);
    return rc || n != RT_ROUNDS ? -1 : 0;
}

/* Value of `key` in the daemon-wide (sid 0) or a session's STATS; -1 when absent. */
static double stat_value(df_client *c, uint64_t sid, const char *key)
{
    df_msg_stats st;
    df_error e;
    double v = -1;
    if (df_client_stats(c, sid, &st, &e) != DF_OK)
        return -1;
    for (uint32_t i = 0; i < st.count; i++)
        if (strcmp(st.items[i].key, key) == 0)
            v = st.items[i].value;
    df_msg_stats_free(&st);
    return v;
}

/* Full dense frames of the 1M session: pipelined SNAPSHOT replies (pure stream) when `brush` is
 * 0, else brush updates each producing a dense version to this subscribed connection. */
static int bench_full_frames(df_client *c, uint64_t sid, uint32_t nv, int brush, double *fps,
                             double *mbps)
{
    df_error e;
    df_buf buf;
    df_buf_init(&buf);
    df_msg_ack ack;
    df_msg_brush b;
    brush_msg(&b, sid, 0.3);
    if (brush && (df_client_subscribe(c, sid, 0, NULL, &e) || df_client_brush_begin(c, &b, &ack, &e))) {
        fprintf(stderr, "bench_net: %s\n", e.msg);
        return -1;
    }
    long sent = 0, frames = 0, inflight = 0;
    double bytes = 0, t0 = now_us(), tend = t0 + STREAM_SECONDS * 1e6;
    int rc = 0;
    while (rc == 0 && (now_us() < tend || inflight > 0)) {
        while (inflight < STREAM_INFLIGHT && now_us() < tend) {
            df_buf_reset(&buf);
            if (brush) {
                df_msg_brush_update u;
                memset(&u, 0, sizeof u);
                u.session_id = sid;
                u.move[0] = 0.001 * (1 + sent % 5);
                rc = df_msg_brush_update_encode(&u, &buf, &e);
            } else {
                df_msg_snapshot_req q = {sid, 0};
                rc = df_msg_snapshot_req_encode(&q, &buf, &e);
            }
            uint16_t type = brush ? DF_MSG_BRUSH_UPDATE : DF_MSG_SNAPSHOT;
            rc = rc || df_client_send(c, type, 0, 0, buf.data, buf.len, NULL, &e);
            sent++;
            inflight++;
        }
        df_frame_header h;
        const uint8_t *p;
        if (rc || df_client_recv(c, 10000, &h, &p, &e) != DF_OK || (h.flags & DF_FLAG_ERROR)) {
            fprintf(stderr, "bench_net: full frames: %s\n", e.msg);
            rc = -1;
            break;
        }
        int disp = brush ? h.type == DF_MSG_DISPLACEMENT : h.type == DF_MSG_SNAPSHOT;
        if (disp) {
            bytes += h.payload_len;
            if (!(h.flags & DF_FLAG_MORE) && df_le32_load(p + 32) == nv)
                frames++;
        }
        if ((h.flags & DF_FLAG_REPLY) && !(h.flags & DF_FLAG_MORE))
            inflight--;
    }
    double secs = (now_us() - t0) / 1e6;
    if (brush && rc == 0)
        df_client_brush_end(c, sid, NULL, &e), df_client_unsubscribe(c, sid, &e);
    df_buf_free(&buf);
    *fps = frames / secs;
    *mbps = bytes / secs / 1e6;
    return rc;
}

/* Subscriber connections drained by one thread; each counts complete displacement versions. */
typedef struct subs {
    df_client *c[MANY_SUBS];
    long versions[MANY_SUBS];
    int n;
    volatile int stop;
    double cpu_s; /* CPU seconds the draining thread used */
} subs;

static void count_event(void *user, const df_frame_header *h, const uint8_t *p)
{
    (void)p;
    if (h->type == DF_MSG_DISPLACEMENT && !(h->flags & DF_FLAG_MORE))
        (*(long *)user)++;
}

/* Drains every subscriber as its bytes arrive: one epoll set registered once (poll() would
 * re-register 32 wait entries per call) and df_client_pump reading each ready socket until it
 * would block. */
static void *subs_thread(void *arg)
{
    subs *s = arg;
    int ep = epoll_create1(EPOLL_CLOEXEC);
    for (int i = 0; ep >= 0 && i < s->n; i++) {
        struct epoll_event ev = {.events = EPOLLIN, .data.u32 = (uint32_t)i};
        epoll_ctl(ep, EPOLL_CTL_ADD, df_client_fd(s->c[i]), &ev);
    }
    struct epoll_event ready[MANY_SUBS];
    while (ep >= 0 && !s->stop) {
        int n = epoll_wait(ep, ready, MANY_SUBS, 50);
        for (int k = 0; k < n; k++)
            df_client_pump(s->c[ready[k].data.u32], 0, NULL);
    }
    if (ep >= 0)
        close(ep);
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    s->cpu_s = ts.tv_sec + ts.tv_nsec * 1e-9;
    return NULL;
}

/* CPU seconds used so far by the threads of process `pid` (0: this process): the sum of their
 * /proc/.../task/TID/schedstat run times (nanoseconds; threads that already exited are not
 * counted, so sample while the threads of interest run). */
static double cpu_seconds(pid_t pid)
{
    char path[64];
    snprintf(path, sizeof path, "/proc/%d/task", pid ? (int)pid : (int)getpid());
    DIR *d = opendir(path);
    double s = 0;
    struct dirent *de;
    while (d && (de = readdir(d)) != NULL) {
        if (de->d_name[0] == '.')
            continue;
        char f[64 + 16 + sizeof de->d_name];
        snprintf(f, sizeof f, "%s/%s/schedstat", path, de->d_name);
        FILE *fp = fopen(f, "r");
        unsigned long long ns = 0;
        if (fp && fscanf(fp, "%llu", &ns) == 1)
            s += (double)ns * 1e-9;
        if (fp)
            fclose(fp);
    }
    if (d)
        closedir(d);
    return s;
}

/* One writer run: updates/s, fewest versions any subscriber got, CPU us per update. */
typedef struct writer_run {
    double rate, cpu_daemon, cpu_bench;
    long seen;
} writer_run;

static pid_t g_daemon_pid; /* whose CPU time bench_writer measures besides its own */

/* Measures the writer on `sid` (update -> ack) with `nsubs` subscriber connections, which read
 * the stream from their sockets or (shm = 1) from the session's shared-memory ring: fills *out
 * (updates/s, fewest versions a subscriber got, CPU per update). 0 on success, -1 otherwise. */
static int bench_writer(const char *sock, df_client *w, uint64_t sid, int nsubs, int shm,
                        writer_run *out)
{
    subs s;
    memset(&s, 0, sizeof s);
    df_error e;
    for (int i = 0; i < nsubs; i++) {
        if (df_client_connect_unix(sock, "bench-sub", &s.c[i], &e) ||
            df_client_subscribe(s.c[i], sid, 0, NULL, &e) ||
            (shm && df_client_stream_shm(s.c[i], sid, NULL, &e))) {
            fprintf(stderr, "bench_net: subscriber %d: %s\n", i, e.msg);
            for (int k = 0; k < s.n; k++)
                df_client_close(s.c[k]);
            return -1;
        }
        df_client_set_event_callback(s.c[i], count_event, &s.versions[i]);
        s.n++;
    }
    pthread_t th;
    pthread_create(&th, NULL, subs_thread, &s);
    df_msg_brush b;
    brush_msg(&b, sid, 0.2);
    double blocked0 = stat_value(w, 0, "writes_blocked");
    int rc = df_client_brush_begin(w, &b, NULL, &e);
    double cd0 = cpu_seconds(g_daemon_pid), cb0 = cpu_seconds(0);
    double t0 = now_us();
    for (int i = 0; rc == 0 && i < WRITER_UPDATES; i++) {
        df_msg_brush_update u;
        memset(&u, 0, sizeof u);
        u.session_id = sid;
        u.move[1] = 0.001 * (1 + i % 9);
        rc = df_client_brush_update(w, &u, NULL, &e);
    }
    double secs = (now_us() - t0) / 1e6;
    out->cpu_daemon = (cpu_seconds(g_daemon_pid) - cd0) * 1e6 / WRITER_UPDATES;
    out->cpu_bench = (cpu_seconds(0) - cb0) * 1e6 / WRITER_UPDATES;
    if (rc == 0)
        rc = df_client_brush_end(w, sid, NULL, &e);
    if (rc)
        fprintf(stderr, "bench_net: writer: %s\n", e.msg);
    for (int k = 0; k < 100; k++) { /* let the subscribers drain (<= 5 s) */
        long lo = LONG_MAX;
        for (int i = 0; i < s.n; i++)
            lo = s.versions[i] < lo ? s.versions[i] : lo;
        if (lo >= WRITER_UPDATES)
            break;
        usleep(50000);
    }
    s.stop = 1;
    pthread_join(th, NULL);
    out->seen = LONG_MAX;
    for (int i = 0; i < s.n; i++) {
        out->seen = s.versions[i] < out->seen ? s.versions[i] : out->seen;
        df_client_close(s.c[i]);
    }
    out->rate = WRITER_UPDATES / secs;
    if (getenv("BENCH_NET_VERBOSE"))
        printf("    %d %s subscribers: %.0f updates/s, %.0f writes blocked (full sockets), draining "
               "thread %.1f us CPU per update\n", nsubs, shm ? "shm" : "socket", out->rate,
               stat_value(w, 0, "writes_blocked") - blocked0, s.cpu_s * 1e6 / WRITER_UPDATES);
    return rc;
}

/* 1 when section `name` runs: all of them unless BENCH_NET_ONLY lists some (comma separated:
 * rt, frames, writer; the echo and PING context always run). */
static int section_on(const char *name)
{
    const char *only = getenv("BENCH_NET_ONLY");
    if (!only || !*only)
        return 1;
    size_t n = strlen(name);
    for (const char *p = only; (p = strstr(p, name)) != NULL; p += n)
        if ((p == only || p[-1] == ',') && (p[n] == '\0' || p[n] == ','))
            return 1;
    return 0;
}

static const char *verdict(int ok)
{
    return ok ? "MET" : "MISSED";
}

int main(int argc, char **argv)
{
    (void)argc;
    signal(SIGPIPE, SIG_IGN);
    setvbuf(stdout, NULL, _IOLBF, 0);
    char exe[PATH_MAX + 32], self[PATH_MAX];
    ssize_t sl = readlink("/proc/self/exe", self, sizeof self - 1);
    self[sl > 0 ? sl : 0] = '\0';
    char *slash = strrchr(self, '/');
    if (slash)
        *slash = '\0';
    snprintf(exe, sizeof exe, "%s/../bin/deformd", sl > 0 ? self : ".");
    if (getenv("DEFORMD_BIN"))
        snprintf(exe, sizeof exe, "%s", getenv("DEFORMD_BIN"));
    if (access(exe, X_OK) != 0) {
        fprintf(stderr, "%s: deformd not found at %s (build it, or set DEFORMD_BIN)\n", argv[0], exe);
        return 1;
    }
    daemon_proc d = {0};
    snprintf(d.dir, sizeof d.dir, "/tmp/deformd-bench-XXXXXX");
    if (!mkdtemp(d.dir)) {
        perror("mkdtemp");
        return 1;
    }
    long ncpu = sysconf(_SC_NPROCESSORS_ONLN);
    printf("bench_net: %ld CPUs online; latencies and rates are the best of %d runs (wall clock, "
           "shared machine)\n", ncpu, BENCH_REPEAT);
    int fail = 0;
    stats eu = {0, 0, 0, 0}, et = {0, 0, 0, 0};
    fail |= echo_best(d.dir, &eu, &et);
    printf("raw 16-byte echo (%d round trips)   unix: p50 %7.1f us  p99 %7.1f us\n", ECHO_ROUNDS,
           eu.p50, eu.p99);
    printf("                                    tcp : p50 %7.1f us  p99 %7.1f us\n", et.p50, et.p99);
    if (daemon_start(&d, exe) != 0) {
        fprintf(stderr, "bench_net: deformd did not come up (log: %s/deformd.log)\n", d.dir);
        daemon_stop(&d);
        return 1;
    }
    df_client *cu = NULL, *ct = NULL;
    df_error e;
    if (df_client_connect_unix(d.sock, "bench", &cu, &e) ||
        df_client_connect_tcp("127.0.0.1", d.port, "bench", &ct, &e)) {
        fprintf(stderr, "bench_net: connect: %s\n", e.msg);
        daemon_stop(&d);
        return 1;
    }
    double *pt = malloc(RT_ROUNDS * sizeof *pt);
    int np = 0;
    for (int i = 0; pt && i < RT_WARMUP + RT_ROUNDS; i++) {
        double us;
        if (df_client_ping(cu, "deformd-ping-16b", 16, &us, &e) == DF_OK && i >= RT_WARMUP)
            pt[np++] = us;
    }
    stats ps = stats_of(pt, np);
    free(pt);
    printf("daemon PING 16 B (loop thread only) unix: p50 %7.1f us  p99 %7.1f us\n", ps.p50, ps.p99);
    static const int sizes[2] = {32, 317};
    static const char *const names[2] = {"grid-1k", "grid-100k"};
    uint64_t sid[2] = {0, 0};
    stats rt[2][2];
    memset(rt, 0, sizeof rt);
    int rt_ok[2] = {0, 0};
    double pool0[3] = {0, 0, 0}, pool1[3] = {0, 0, 0}, work_ms = -1;
    static const char *const pool_keys[3] = {"pool.tasks", "pool.wakeups", "pool.spin_hits"};
    for (int m = 0; m < 2; m++) {
        sid[m] = load_grid(cu, sizes[m], names[m]);
        int bad = !sid[m];
        for (int k = 0; m == 0 && k < 3; k++)
            pool0[k] = stat_value(cu, 0, pool_keys[k]);
        for (int r = 0; !bad && section_on("rt") && r < BENCH_REPEAT; r++) {
            stats a, b;
            bad = bench_rt(cu, sid[m], &a) || bench_rt(ct, sid[m], &b);
            if (!bad && (r == 0 || a.p50 < rt[m][0].p50))
                rt[m][0] = a;
            if (!bad && (r == 0 || b.p50 < rt[m][1].p50))
                rt[m][1] = b;
        }
        if (bad) {
            fail = 1;
            continue;
        }
        if (!section_on("rt"))
            continue;
        if (m == 0) {
            for (int k = 0; k < 3; k++)
                pool1[k] = stat_value(cu, 0, pool_keys[k]);
            work_ms = stat_value(cu, sid[0], "brush.last_ms");
        }
        rt_ok[m] = 1;
        for (int k = 0; k < 2; k++)
            printf("brush update -> displacement %-9s %s: p50 %7.1f us  p99 %7.1f us  (%d "
                   "vertices, %d updates)\n", names[m], k ? "tcp " : "unix", rt[m][k].p50,
                   rt[m][k].p99, sizes[m] * sizes[m], RT_ROUNDS);
    }
    if (rt_ok[0] && pool0[0] >= 0 && pool1[0] >= 0) /* the daemon's side of the 1k runs */
        printf("  1k runs on the daemon: %.0f pool tasks, %.0f loop wake-ups by workers, %.0f "
               "tasks taken by a spinning worker; last brush work %.1f us\n",
               pool1[0] - pool0[0], pool1[1] - pool0[1], pool1[2] - pool0[2], work_ms * 1e3);
    if (rt_ok[0]) {
        /* The echo again, right after the 1k runs: the machine's load drifts, and a floor
         * measured in a slow moment would flatter the ratio. The best of both sets counts. */
        stats eu2 = {0, 0, 0, 0}, et2 = {0, 0, 0, 0};
        fail |= echo_best(d.dir, &eu2, &et2);
        if (eu2.p50 < eu.p50)
            eu = eu2;
        if (et2.p50 < et.p50)
            et = et2;
        printf("  raw echo again after the 1k runs: unix p50 %.1f us, tcp %.1f us; floor used: "
               "%.1f / %.1f us\n", eu2.p50, et2.p50, eu.p50, et.p50);
        double r = rt[0][0].p50 / eu.p50, rtcp = rt[0][1].p50 / et.p50;
        printf("  target 1k p50 <= %.0fx raw echo: unix %.1fx %s, tcp %.1fx %s\n", TARGET_ECHO_RATIO,
               r, verdict(r <= TARGET_ECHO_RATIO), rtcp, verdict(rtcp <= TARGET_ECHO_RATIO));
        printf("  1k p50 now / README before: unix %.1f / %.0f us, tcp %.1f / %.0f us\n",
               rt[0][0].p50, OLD_1K_P50_US_UNIX, rt[0][1].p50, OLD_1K_P50_US_TCP);
    }
    if (rt_ok[1])
        printf("  target 100k p50 <= %.0f us: unix %.1f us %s, tcp %.1f us %s\n", TARGET_100K_P50_US,
               rt[1][0].p50, verdict(rt[1][0].p50 <= TARGET_100K_P50_US), rt[1][1].p50,
               verdict(rt[1][1].p50 <= TARGET_100K_P50_US));
    if (rt_ok[1])
        printf("  100k p50 now / README before: unix %.0f / %.0f us, tcp %.0f / %.0f us\n",
               rt[1][0].p50, OLD_100K_P50_US_UNIX, rt[1][1].p50, OLD_100K_P50_US_TCP);
    uint64_t big = section_on("frames") ? load_grid(cu, 1000, "grid-1M") : 0;
    double fps[2] = {0, 0}, mbps[2] = {0, 0};
    if (!section_on("frames"))
        ;
    else if (!big || bench_full_frames(cu, big, 1000000, 0, &fps[0], &mbps[0]) ||
        bench_full_frames(cu, big, 1000000, 1, &fps[1], &mbps[1]))
        fail = 1;
    else {
        printf("full 1M-vertex frames, unix, 1 subscriber: snapshot stream %6.1f frames/s %7.1f MB/s\n",
               fps[0], mbps[0]);
        printf("                                           brush versions  %6.1f frames/s %7.1f MB/s\n",
               fps[1], mbps[1]);
        printf("  target >= %.0f frames/s: stream %s, brush-driven %s\n", TARGET_1M_FPS,
               verdict(fps[0] >= TARGET_1M_FPS), verdict(fps[1] >= TARGET_1M_FPS));
        printf("  1M frames/s now / README before: stream %.0f / %.0f, brush-driven %.0f / %.0f\n",
               fps[0], OLD_1M_FPS_STREAM, fps[1], OLD_1M_FPS_BRUSH);
    }
    /* [transport: 0 socket, 1 shm][0: 1 subscriber, 1: MANY_SUBS]; best of BENCH_REPEAT, the
     * four cases interleaved so that machine noise hits them alike */
    writer_run best[2][2];
    memset(best, 0, sizeof best);
    g_daemon_pid = d.pid;
    int wbad = !sid[0] || !section_on("writer");
    for (int r = 0; !wbad && r < BENCH_REPEAT; r++)
        for (int t = 0; !wbad && t < 2; t++)
            for (int k = 0; !wbad && k < 2; k++) {
                writer_run x;
                wbad = bench_writer(d.sock, cu, sid[0], k ? MANY_SUBS : 1, t, &x);
                if (!wbad && x.rate > best[t][k].rate) best[t][k] = x;
            }
    if (!section_on("writer"))
        ;
    else if (wbad)
        fail = 1;
    else {
        static const char *name[2] = {"socket stream", "shared-memory stream (STREAM_SHM)"};
        for (int t = 0; t < 2; t++) {
            writer_run *a = &best[t][0], *b = &best[t][1];
            printf("writer updates/s (1k mesh, update -> ack), %s: 1 subscriber %8.0f, %d "
                   "subscribers %8.0f (each subscriber got >= %ld / %ld of %d versions)\n",
                   name[t], a->rate, MANY_SUBS, b->rate, a->seen, b->seen, WRITER_UPDATES);
            printf("  CPU per update: daemon %.0f / %.0f us, bench (writer + subscribers) "
                   "%.0f / %.0f us with 1 / %d subscribers\n", a->cpu_daemon, b->cpu_daemon,
                   a->cpu_bench, b->cpu_bench, MANY_SUBS);
            double cost = a->rate / b->rate;
            int all = a->seen == WRITER_UPDATES && b->seen == WRITER_UPDATES;
            printf("  target %d subscribers cost the writer <= %.0fx: %.2fx -> %s%s\n", MANY_SUBS,
                   TARGET_SUB_COST, cost, verdict(cost <= TARGET_SUB_COST && all),
                   all ? "" : " (a subscriber missed versions)");
            printf("  %d-subscriber cost now / README before: %.2fx / %.2fx\n", MANY_SUBS, cost,
                   t ? OLD_SUB_COST_SHM : OLD_SUB_COST_SOCKET);
        }
        printf("  %d shared-memory subscribers against 1 socket subscriber: %.2fx\n", MANY_SUBS,
               best[0][0].rate / best[1][1].rate);
    }
    df_client_close(cu);
    df_client_close(ct);
    daemon_stop(&d);
    char cmd[128];
    snprintf(cmd, sizeof cmd, "%s/deformd.log", d.dir);
    unlink(cmd);
    unlink(d.sock);
    rmdir(d.dir);
    if (fail)
        fprintf(stderr, "bench_net: some measurements failed\n");
    return fail ? 1 : 0;
}
