/* bench_load.c — load and abuse of one deformd on loopback (run by `make bench`; issue 12).
 *
 * Starts build/bin/deformd with the durable store ON (`--store` in a temporary directory,
 * durability default `full`) and a config raising max_clients, loads 10 small grid sessions
 * (32 x 32 vertices, uploaded by this bench) and drives, from one thread (epoll, non-blocking
 * sockets, frames encoded with proto/):
 *   - 1,000 well-behaved TCP connections: HELLO, then closed-loop strokes on session i % 10
 *     (BRUSH_BEGIN with a small grab load, BRUSH_UPDATE, BRUSH_END, each waiting for its ack);
 *     every RECONNECT strokes a connection closes and reconnects (a new handshake);
 *   - 50 slowloris TCP connections: the 24-byte header of a HELLO trickled one byte at a time, so
 *     slowly that it never completes (23 bytes over twice handshake_timeout_s); reconnected when
 *     the server closes them;
 *   - 50 non-readers on the Unix socket: HELLO, SUBSCRIBE to a session, then never read (their
 *     queues fill; the server must drop them at output_queue_limit without stalling the others);
 *     reconnected when the server closes them (seen as a hang-up, no read needed).
 * for DF_BENCH_LOAD_SECONDS (default 60), then lets open strokes finish and prints: strokes/s,
 * requests/s and handshakes/s; p50/p99/max of a stroke round trip (begin sent -> end acked) and of
 * one request; the daemon's peak RSS (VmHWM); the store's bytes per change (STATS store_log_bytes
 * / store_changes, and the database files' size / changes); well-behaved clients dropped; how the
 * server closed the slowloris and non-reader connections (ERROR frames, STATS counters).
 * Targets: 0 well-behaved clients dropped, stroke p99 <= 50 ms, the daemon alive and exiting 0 on
 * SIGTERM. Each line reads "what: value (target ...) ok|MISS".
 * Environment: DF_BENCH_LOAD_SECONDS, DF_BENCH_LOAD_CLIENTS (well-behaved, default 1000),
 * DF_BENCH_LOAD_ABUSERS (slowloris and non-readers each, default 50), DF_BENCH_LOAD_QUEUE (the
 * daemon's output_queue_limit, default 8m: the non-readers reach it within the run),
 * DF_BENCH_LOAD_DURABILITY (the store's durability, default full), DF_BENCH_LOAD_THINK_MS (a
 * well-behaved client's mean pause between strokes, 0.5x..1.5x at random; default 0, closed
 * loop), DF_BENCH_LOAD_VERBOSE=1 (a line per second: strokes, latencies, handshakes, RSS),
 * DEFORMD_BIN. The daemon's config: max_clients = all of the above + 100, output_queue_limit as
 * above, handshake_timeout_s 10 (runs under 40 s: a quarter of the run, at least 1 s;
 * DF_BENCH_LOAD_HANDSHAKE_S sets it), the rest default. Descriptors: this process raises its
 * soft RLIMIT_NOFILE to the hard limit and stops with a message when the hard limit is below
 * what the daemon needs (max_clients + 64; this process needs a few less); deformd raises its
 * own soft limit to that (server/net/guard.h), so `ulimit -Hn` >= 1,264 suffices (the default
 * 1,000 + 2 x 50 clients).
 * Exit status 0 when everything ran and the daemon survived (targets are reported, not
 * enforced), 1 otherwise. The connections' state machines are in bench_load_conn.h. */
#include <limits.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include "tests/bench/bench_daemon.h"
#include "tests/bench/bench_grid.h"
#include "tests/bench/bench_load_conn.h"

#define TARGET_P99_MS 50.0
#define DRAIN_S 30.0           /* open strokes must finish within this after the run */
#define FD_MARGIN 64           /* descriptors beyond the connections (server/net/guard.h) */
#define CLIENT_SLACK 100       /* max_clients beyond the bench's connections (the control
                                * connection, the daemon's readiness probe, margin) */

static void report(const char *what, double v, const char *unit, const char *target, int ok)
{
    printf("  %-58s %10.2f %-4s (target %s) %s\n", what, v, unit, target, ok ? "ok" : "MISS");
}


/* ---- daemon, setup, figures ----------------------------------------------------------------- */

/* Value of `key` in the daemon-wide STATS; -1 when absent or on error. */
static double stat_value(df_client *c, const char *key)
{
    df_msg_stats st;
    df_error e;
    double v = -1;
    if (df_client_stats(c, 0, &st, &e) != DF_OK) return -1;
    for (uint32_t i = 0; i < st.count; i++)
        if (strcmp(st.items[i].key, key) == 0) v = st.items[i].value;
    df_msg_stats_free(&st);
    return v;
}

/* Kibibytes of `field` (e.g. "VmHWM:") in /proc/PID/status; -1 when unreadable. */
static long proc_kb(pid_t pid, const char *field)
{
    char path[64], line[256];
    snprintf(path, sizeof path, "/proc/%d/status", (int)pid);
    FILE *f = fopen(path, "r");
    long kb = -1;
    while (f && fgets(line, sizeof line, f))
        if (strncmp(line, field, strlen(field)) == 0) kb = atol(line + strlen(field));
    if (f) fclose(f);
    return kb;
}

static long file_size(const char *dir, const char *name)
{
    char p[256];
    struct stat st;
    snprintf(p, sizeof p, "%s/%s", dir, name);
    return stat(p, &st) == 0 ? (long)st.st_size : 0;
}

static int env_int(const char *name, int def, int lo, int hi)
{
    const char *s = getenv(name);
    if (!s || !*s) return def;
    char *end;
    long v = strtol(s, &end, 10);
    if (*end || v < lo || v > hi) {
        fprintf(stderr, "bench_load: %s=%s ignored (not in %d..%d); using %d\n", name, s, lo, hi,
                def);
        return def;
    }
    return (int)v;
}

/* Raises the soft RLIMIT_NOFILE to the hard limit; -1 (with a message) when the hard limit is
 * below `need` descriptors. */
static int raise_nofile(long need)
{
    struct rlimit rl;
    if (getrlimit(RLIMIT_NOFILE, &rl) != 0) return -1;
    if (rl.rlim_cur < rl.rlim_max) {
        rl.rlim_cur = rl.rlim_max;
        setrlimit(RLIMIT_NOFILE, &rl);
    }
    getrlimit(RLIMIT_NOFILE, &rl);
    if (rl.rlim_cur != RLIM_INFINITY && (long)rl.rlim_cur < need) {
        fprintf(stderr, "bench_load: needs %ld file descriptors (the daemon's max_clients + 64; "
                "this process a few less) but the hard limit is %lu: raise it (`ulimit -Hn %ld` "
                "as root, or LimitNOFILE= / limits.conf) or lower DF_BENCH_LOAD_CLIENTS\n", need,
                (unsigned long)rl.rlim_max, need);
        return -1;
    }
    printf("bench_load: RLIMIT_NOFILE %lu (the daemon needs %ld, this process a few less)\n",
           (unsigned long)rl.rlim_cur, need);
    return 0;
}

static int start_daemon(const char *exe, const char *dir, int max_clients, const char *queue,
                        pid_t *pid)
{
    char conf[160], log[160], store[160], tcp[64];
    snprintf(conf, sizeof conf, "%s/deformd.conf", dir);
    snprintf(log, sizeof log, "%s/deformd.log", dir);
    snprintf(store, sizeof store, "%s/deformd.db", dir);
    snprintf(G.sock, sizeof G.sock, "%s/deformd.sock", dir);
    G.port = bench_free_port();
    snprintf(tcp, sizeof tcp, "127.0.0.1:%d", G.port);
    FILE *f = fopen(conf, "w");
    if (!f) return -1;
    fprintf(f, "max_clients = %d\nhandshake_timeout_s = %d\noutput_queue_limit = %s\n"
            "durability = %s\n", max_clients, (int)G.hs_timeout_s, queue, G.durability);
    fclose(f);
    char *argv[] = {(char *)exe, "--foreground", "--socket", G.sock, "--tcp", tcp, "--config",
                    conf, "--store", store, "--log-level", "warn", NULL};
    *pid = bench_daemon_spawn(argv, log);
    return *pid > 0 ? bench_daemon_wait(G.sock) : -1;
}

static int load_sessions(df_client *ctl)
{
    size_t len;
    uint8_t *ply = grid_ply(GRID_N, &len);
    for (int i = 0; ply && i < N_SESSIONS; i++) {
        char name[32];
        df_msg_session_info info;
        df_error e;
        snprintf(name, sizeof name, "load-%d", i);
        if (df_client_load_mesh_bytes(ctl, name, DF_FMT_PLY, ply, len, 0, &info, &e) != DF_OK) {
            fprintf(stderr, "bench_load: loading %s: %s\n", name, e.msg);
            free(ply);
            return -1;
        }
        G.sid[i] = info.session_id;
    }
    free(ply);
    return ply ? 0 : -1;
}

/* DF_BENCH_LOAD_VERBOSE: the strokes and handshakes completed since the last line. */
static void window_print(double t, pid_t pid)
{
    printf("  t %5.1f s: %5zu strokes p50 %7.1f p99 %7.1f max %7.1f ms; %4zu handshakes max %7.1f "
           "ms; daemon RSS %ld KiB; store file %ld + WAL %ld KiB\n", t, G.win_stroke.n,
           pct(&G.win_stroke, 0.5) * 1e3, pct(&G.win_stroke, 0.99) * 1e3,
           pct(&G.win_stroke, 1.0) * 1e3, G.win_hs.n, pct(&G.win_hs, 1.0) * 1e3,
           proc_kb(pid, "VmRSS:"), file_size(G.dir, "deformd.db") >> 10,
           file_size(G.dir, "deformd.db-wal") >> 10);
    G.win_stroke.n = G.win_hs.n = 0;
}

/* 1 while the daemon runs; else prints how it ended and returns 0. */
static int daemon_alive(pid_t pid, int *status)
{
    pid_t w = waitpid(pid, status, WNOHANG);
    if (w == 0) return 1;
    if (WIFSIGNALED(*status))
        fprintf(stderr, "bench_load: deformd died of signal %d\n", WTERMSIG(*status));
    else
        fprintf(stderr, "bench_load: deformd exited with status %d\n", WEXITSTATUS(*status));
    return 0;
}

/* The 1-minute load average from /proc/loadavg into `out` (16 bytes), "?" when unreadable. */
static const char *loadavg(char out[16])
{
    FILE *f = fopen("/proc/loadavg", "r");
    double l;
    if (f && fscanf(f, "%lf", &l) == 1) snprintf(out, 16, "%.1f", l);
    else snprintf(out, 16, "?");
    if (f) fclose(f);
    return out;
}

/* Lines of the daemon's log (G.dir/deformd.log) that contain `needle`; -1 when unreadable. */
static long log_count(const char *needle)
{
    char path[160], line[1024];
    snprintf(path, sizeof path, "%s/deformd.log", G.dir);
    FILE *f = fopen(path, "r");
    long n = f ? 0 : -1;
    while (f && fgets(line, sizeof line, f))
        n += strstr(line, needle) != NULL;
    if (f) fclose(f);
    return n;
}

static void print_figures(double secs, int ngood, int nab, double changes, double log_bytes,
                          long db_bytes, long hwm_kb, df_client *ctl, int alive)
{
    double p50 = pct(&G.lat_stroke, 0.5) * 1e3, p99 = pct(&G.lat_stroke, 0.99) * 1e3;
    double mx = pct(&G.lat_stroke, 1.0) * 1e3;
    char pace[64] = "closed loop";
    if (G.think_s > 0)
        snprintf(pace, sizeof pace, "%.0f ms mean pause between strokes", G.think_s * 1e3);
    printf("load: %d well-behaved TCP clients (%s; begin + update + end on %d sessions of %d "
           "vertices, reconnecting every %d strokes), %d slowloris, %d non-readers, %.0f s, store "
           "on (durability %s, output_queue_limit %s)\n", ngood, pace, N_SESSIONS,
           GRID_N * GRID_N, RECONNECT, nab, nab, secs, G.durability, G.queue);
    printf("  strokes %ld (%.0f/s), requests %ld (%.0f/s), handshakes %ld (%.0f/s), error "
           "replies %ld%s%s\n", G.strokes, G.strokes / secs, G.requests, G.requests / secs,
           G.handshakes, G.handshakes / secs, G.req_errors, G.first_error[0] ? ", first: " : "",
           G.first_error);
    printf("  stroke round trip (begin sent -> end acked): p50 %.2f ms, p99 %.2f ms, max %.2f ms; "
           "one request p50 %.2f ms, p99 %.2f ms; handshake (connect -> HELLO reply) p50 %.2f "
           "ms, p99 %.2f ms\n", p50, p99, mx, pct(&G.lat_req, 0.5) * 1e3,
           pct(&G.lat_req, 0.99) * 1e3, pct(&G.lat_hs, 0.5) * 1e3, pct(&G.lat_hs, 0.99) * 1e3);
    printf("  daemon peak RSS (VmHWM) %.1f MiB; machine load average at the start / end %s / %s "
           "(%ld CPUs: the figures scale with what else runs)\n", hwm_kb / 1024.0, G.load0,
           loadavg(G.load1), sysconf(_SC_NPROCESSORS_ONLN));
    if (changes > 0)
        printf("  store: %.0f changes, %.0f blob bytes = %.0f bytes per change (STATS "
               "store_log_bytes / store_changes); database files %.1f MiB = %.0f bytes per "
               "change\n", changes, log_bytes, log_bytes / changes, db_bytes / 1048576.0,
               db_bytes / changes);
    printf("  slowloris: %ld closed by the server (%ld with an ERROR frame first, mean life %.1f "
           "s; handshake_timeout_s %.0f)%s%s\n", G.slow_closed, G.slow_closed_error,
           G.slow_closed ? G.slow_life_sum / G.slow_closed : 0.0, G.hs_timeout_s,
           G.slow_why[0] ? ": " : "", G.slow_why);
    printf("  non-readers: %ld subscribed, %ld closed by the server while not reading (the "
           "daemon's log: %ld clients dropped with 'output queue full')\n", G.deaf_subscribed,
           G.deaf_closed, log_count("output queue full"));
    if (ctl) {
        static const char *const keys[] = {"clients_dropped", "clients_handshake_timeout",
                                           "clients_idle_timeout", "clients_refused",
                                           "clients_refused_fds", "requests_failed",
                                           "writes_blocked", "store_errors"};
        printf("  daemon STATS:");
        for (size_t i = 0; i < sizeof keys / sizeof *keys; i++)
            printf(" %s %.0f", keys[i], stat_value(ctl, keys[i]));
        printf("\n");
    }
    report("well-behaved clients dropped", (double)G.dropped, "", "0", G.dropped == 0);
    report("stroke round trip p99", p99, "ms", "<= 50 ms", G.lat_stroke.n && p99 <= TARGET_P99_MS);
    report("daemon alive through the run, exits 0 on SIGTERM", alive, "", "1", alive);
    report("slowloris closed by the server", (double)G.slow_closed, "", "> 0 when the run "
           "exceeds handshake_timeout_s", G.slow_closed > 0 || !nab);
    report("non-readers dropped by the server", (double)G.deaf_closed, "", "> 0", G.deaf_closed > 0
           || !nab);
}

int main(int argc, char **argv)
{
    (void)argc;
    signal(SIGPIPE, SIG_IGN);
    setvbuf(stdout, NULL, _IOLBF, 0);
    int secs = env_int("DF_BENCH_LOAD_SECONDS", 60, 1, 3600);
    int ngood = env_int("DF_BENCH_LOAD_CLIENTS", 1000, 1, 100000);
    int nab = env_int("DF_BENCH_LOAD_ABUSERS", 50, 0, 10000);
    const char *queue = getenv("DF_BENCH_LOAD_QUEUE") ? getenv("DF_BENCH_LOAD_QUEUE") : "8m";
    G.queue = queue;
    G.durability = getenv("DF_BENCH_LOAD_DURABILITY") ? getenv("DF_BENCH_LOAD_DURABILITY") : "full";
    G.verbose = env_int("DF_BENCH_LOAD_VERBOSE", 0, 0, 1);
    G.think_s = env_int("DF_BENCH_LOAD_THINK_MS", 0, 0, 600000) * 1e-3;
    int hs_default = secs >= 40 ? 10 : secs >= 8 ? secs / 4 : 1;
    G.hs_timeout_s = env_int("DF_BENCH_LOAD_HANDSHAKE_S", hs_default, 1, 3600);
    int total = ngood + 2 * nab;
    /* max_clients: the bench's connections + CLIENT_SLACK. The clients of a session reconnect
     * together (closed loop: they advance in step); before deformd decided admissions at the
     * end of a loop iteration (guard.h), such a burst found the slots of the connections it had
     * just closed still taken: 87 of 1,000 clients were refused in one run. */
    int max_clients = total + CLIENT_SLACK;
    if (raise_nofile(max_clients + FD_MARGIN) != 0) return 1;
    char exe[PATH_MAX + 32], self[PATH_MAX];
    ssize_t sl = readlink("/proc/self/exe", self, sizeof self - 1);
    self[sl > 0 ? sl : 0] = '\0';
    char *slash = strrchr(self, '/');
    if (slash) *slash = '\0';
    snprintf(exe, sizeof exe, "%s/../bin/deformd", sl > 0 ? self : ".");
    if (getenv("DEFORMD_BIN")) snprintf(exe, sizeof exe, "%s", getenv("DEFORMD_BIN"));
    if (access(exe, X_OK) != 0) {
        fprintf(stderr, "%s: deformd not found at %s (build it, or set DEFORMD_BIN)\n", argv[0],
                exe);
        return 1;
    }
    char dir[64] = "/tmp/deformd-load-XXXXXX";
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 1;
    }
    G.dir = dir;
    pid_t pid = -1;
    int status = 0, fail = 0;
    df_client *ctl = NULL;
    df_error e;
    if (start_daemon(exe, dir, max_clients, queue, &pid) != 0 ||
        df_client_connect_unix(G.sock, "bench-load-ctl", &ctl, &e) != DF_OK ||
        load_sessions(ctl) != 0) {
        fprintf(stderr, "bench_load: set-up failed (daemon log: %s/deformd.log)\n", dir);
        bench_daemon_stop(pid);
        return 1;
    }
    double changes0 = stat_value(ctl, "store_changes"), bytes0 = stat_value(ctl, "store_log_bytes");
    G.ep = epoll_create1(EPOLL_CLOEXEC);
    lconn *cs = calloc((size_t)total, sizeof *cs);
    if (G.ep < 0 || !cs) return 1;
    G.running = 1;
    for (int i = 0; i < total; i++) {
        cs[i].kind = i < ngood ? K_GOOD : i < ngood + nab ? K_SLOW : K_DEAF;
        cs[i].idx = i;
        cs[i].rng = 2654435761u * (uint32_t)(i + 1);
        cs[i].fd = -1;
        if (conn_open(&cs[i]) != 0) fail = 1;
    }
    loadavg(G.load0);
    double t0 = now_s(), t_end = t0 + secs, t_drain = 0, t_check = t0;
    double interval = 2.0 * G.hs_timeout_s / (DF_FRAME_HEADER_SIZE - 1);
    int alive = 1;
    struct epoll_event evs[256];
    while (!fail) {
        double t = now_s();
        if (G.running && t >= t_end) {
            G.running = 0;
            t_drain = t + DRAIN_S;
        }
        int n = epoll_wait(G.ep, evs, 256, 5);
        for (int k = 0; k < n; k++) on_event(evs[k].data.ptr, evs[k].events);
        t = now_s();
        for (int i = ngood; G.running && i < ngood + nab; i++) trickle(&cs[i], t, interval);
        for (int i = 0; G.think_s > 0 && i < ngood; i++)
            if (cs[i].state == S_THINK && (t >= cs[i].t_next || !G.running) &&
                next_stroke(&cs[i]) != 0)
                on_peer_closed(&cs[i]);
        if (t >= t_check) {
            if (G.verbose && G.running) window_print(t - t0, pid);
            t_check = t + (G.verbose ? 1.0 : 0.5);
            if (!(alive = daemon_alive(pid, &status))) break;
        }
        if (!G.running) {
            int open = 0;
            for (int i = 0; i < ngood; i++) open += cs[i].fd >= 0;
            if (!open) break;
            if (t >= t_drain) {
                fprintf(stderr, "bench_load: %d well-behaved connections still busy %.0f s after "
                        "the run\n", open, DRAIN_S);
                G.dropped += open;
                break;
            }
        }
    }
    double run_s = now_s() - t0 - (t_drain ? 0 : 0);
    run_s = secs < run_s ? secs : run_s;
    long hwm = alive ? proc_kb(pid, "VmHWM:") : -1;
    double changes = alive ? stat_value(ctl, "store_changes") - changes0 : 0;
    double log_bytes = alive ? stat_value(ctl, "store_log_bytes") - bytes0 : 0;
    long db = file_size(dir, "deformd.db") + file_size(dir, "deformd.db-wal");
    print_figures(run_s, ngood, nab, changes, log_bytes, db, hwm, alive ? ctl : NULL, alive);
    for (int i = 0; i < total; i++) conn_close(&cs[i]), free(cs[i].rb);
    free(cs);
    df_client_close(ctl);
    if (alive) {
        kill(pid, SIGTERM);
        waitpid(pid, &status, 0);
        alive = WIFEXITED(status) && WEXITSTATUS(status) == 0;
        if (!alive)
            fprintf(stderr, "bench_load: deformd did not exit cleanly (status 0x%x)\n", status);
    }
    if (alive) {
        static const char *const files[] = {"deformd.conf", "deformd.log", "deformd.db",
                                            "deformd.db-wal", "deformd.db-shm", "deformd.sock"};
        char p[256];
        for (size_t i = 0; i < sizeof files / sizeof *files; i++) {
            snprintf(p, sizeof p, "%s/%s", dir, files[i]);
            unlink(p);
        }
        rmdir(dir);
    } else {
        fprintf(stderr, "bench_load: daemon log kept in %s/deformd.log\n", dir);
    }
    close(G.ep);
    samples *all[] = {&G.lat_stroke, &G.lat_req, &G.lat_hs, &G.win_stroke, &G.win_hs};
    for (size_t i = 0; i < sizeof all / sizeof *all; i++) free(all[i]->v);
    return fail || !alive ? 1 : 0;
}
