/* bench_lockout.c — brush round trips while long handle moves run (run by `make bench`).
 *
 * Starts build/bin/deformd (../bin/deformd next to this binary; default config: 4 compute
 * workers) on a temporary Unix socket. One client loads four 40x40 triangle grids and starts a
 * never-ending ARAP move on each (tol 0, a million iterations, no progress frames), pipelined
 * without waiting; another client then measures, on its own 32x32 grid (1k vertices), the brush
 * update round trip (request sent -> ack, after the displacement was broadcast) and the GET_MESH
 * round trip of one of the moving sessions (answered from its last published version). The same
 * round trips are measured first with nothing else running. Everything runs twice: with the
 * default config (cheap brush updates run on the loop thread, `inline_us`) and with
 * --inline-us 0 (every update goes through the compute pool: the path the moves starved). Issue 9 item 7: before the long lane
 * (pool.h) the four moves took every worker and these requests got no reply at all.
 * Closing the mover's connection ends its moves (item 8). Exit status 0 when every measurement
 * ran, 1 otherwise. */
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "client/deformclient.h"
#include "tests/bench/bench_grid.h"

#define ROUNDS 500
#define WARMUP 30
#define MESH_ROUNDS 100
#define MOVES 4
#define MOVE_GRID 40
#define BRUSH_GRID 32

static double now_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e6 + (double)ts.tv_nsec * 1e-3;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* p50 and p99 of t[0..n) (sorts t). */
static void pct(double *t, int n, double *p50, double *p99)
{
    qsort(t, (size_t)n, sizeof *t, cmp_double);
    *p50 = t[(n - 1) / 2];
    *p99 = t[(int)((n - 1) * 0.99)];
}

static uint64_t load_grid(df_client *c, int n)
{
    size_t len;
    uint8_t *ply = grid_ply(n, &len);
    df_msg_session_info info;
    df_error e;
    int rc = ply ? df_client_load_mesh_bytes(c, "", DF_FMT_PLY, ply, len, 0, &info, &e) : DF_ENOMEM;
    free(ply);
    if (rc) {
        fprintf(stderr, "bench_lockout: load failed: %s\n", rc == DF_ENOMEM ? "ENOMEM" : e.msg);
        return 0;
    }
    return info.session_id;
}

/* Sets the handles of an n x n grid (rows y = 0 and y = 1) and sends a never-ending move
 * lifting the y = 1 row by 0.3 in z, without waiting for it. */
static int start_long_move(df_client *c, uint64_t sid, int n)
{
    int32_t *h = malloc(2 * (size_t)n * sizeof *h);
    double *tg = malloc(6 * (size_t)n * sizeof *tg);
    if (!h || !tg) {
        free(h);
        free(tg);
        return -1;
    }
    for (int i = 0; i < n; i++) {
        h[i] = i;
        h[n + i] = (n - 1) * n + i;
        double x = (double)i / (n - 1);
        double *a = tg + 3 * i, *b = tg + 3 * (n + i);
        a[0] = x, a[1] = 0, a[2] = 0;
        b[0] = x, b[1] = 1, b[2] = 0.3;
    }
    df_msg_handles hs;
    df_msg_handles_defaults(&hs, DF_ENERGY_ARAP);
    hs.session_id = sid;
    hs.tol = 0.0;
    hs.max_iters = DF_MAX_MOVE_ITERS;
    hs.n_handles = 2 * (uint32_t)n;
    hs.handles = h;
    df_msg_handle_move mv = {.session_id = sid, .n_targets = 2 * (uint32_t)n, .targets = tg};
    df_error e;
    df_buf b;
    df_buf_init(&b);
    int rc = df_client_handles_set(c, &hs, &e);
    if (rc == DF_OK) rc = df_msg_handle_move_encode(&mv, &b, &e);
    if (rc == DF_OK) rc = df_client_send(c, DF_MSG_HANDLES_MOVE, 0, 0, b.data, b.len, NULL, &e);
    if (rc) fprintf(stderr, "bench_lockout: starting a move failed: %s\n", e.msg);
    df_buf_free(&b);
    free(h);
    free(tg);
    return rc ? -1 : 0;
}

/* Brush update round trips (update -> ack) on `sid`: p50/p99 in us. */
static int brush_rt(df_client *c, uint64_t sid, double *p50, double *p99)
{
    df_msg_brush b;
    df_msg_brush_defaults(&b);
    b.session_id = sid;
    b.type = DF_BRUSH_GRAB;
    b.radius = 0.2;
    b.nu = 0.45;
    b.center[0] = b.center[1] = 0.5;
    df_error e;
    if (df_client_brush_begin(c, &b, NULL, &e)) {
        fprintf(stderr, "bench_lockout: brush begin: %s\n", e.msg);
        return -1;
    }
    double t[ROUNDS];
    int n = 0;
    for (int i = 0; i < WARMUP + ROUNDS; i++) {
        df_msg_brush_update u;
        memset(&u, 0, sizeof u);
        u.session_id = sid;
        u.move[0] = 0.001 * (1 + i % 7);
        double t0 = now_us();
        if (df_client_brush_update(c, &u, NULL, &e)) {
            fprintf(stderr, "bench_lockout: brush update: %s\n", e.msg);
            return -1;
        }
        if (i >= WARMUP) t[n++] = now_us() - t0;
    }
    if (df_client_brush_end(c, sid, NULL, &e)) return -1;
    pct(t, n, p50, p99);
    return 0;
}

/* GET_MESH round trips of `sid`: p50/p99 in us. */
static int mesh_rt(df_client *c, uint64_t sid, double *p50, double *p99)
{
    double t[MESH_ROUNDS];
    df_error e;
    for (int i = 0; i < MESH_ROUNDS; i++) {
        df_client_mesh m;
        double t0 = now_us();
        if (df_client_get_mesh(c, sid, 0, &m, &e)) {
            fprintf(stderr, "bench_lockout: get_mesh: %s\n", e.msg);
            return -1;
        }
        t[i] = now_us() - t0;
        df_client_mesh_free(&m);
    }
    pct(t, MESH_ROUNDS, p50, p99);
    return 0;
}

/* One daemon run with the extra option `inline_opt` (may be NULL); prints the rows. 0 or -1. */
static int run(const char *exe, const char *inline_opt)
{
    char dir[] = "/tmp/bench_lockout.XXXXXX", sock[128];
    if (!mkdtemp(dir)) return -1;
    snprintf(sock, sizeof sock, "%s/deformd.sock", dir);
    pid_t pid = fork();
    if (pid == 0) {
        prctl(PR_SET_PDEATHSIG, SIGTERM);
        execl(exe, exe, "--foreground", "--socket", sock, "--log-level", "warn", "--store", "none",
              inline_opt ? "--inline-us" : (char *)NULL, inline_opt, (char *)NULL);
        _exit(127);
    }
    df_client *mover = NULL, *artist = NULL;
    for (int i = 0; i < 200 && !mover; i++) {
        if (df_client_connect_unix(sock, "bench-mover", &mover, NULL) != DF_OK) {
            mover = NULL;
            usleep(50000);
        }
    }
    int ok = mover && df_client_connect_unix(sock, "bench-artist", &artist, NULL) == DF_OK;
    uint64_t brush_sid = ok ? load_grid(artist, BRUSH_GRID) : 0;
    uint64_t move_sid[MOVES] = {0};
    for (int k = 0; ok && k < MOVES; k++) ok = (move_sid[k] = load_grid(mover, MOVE_GRID)) != 0;
    double i50, i99, b50, b99, g50 = 0, g99 = 0, m50 = 0, m99 = 0;
    ok = ok && brush_sid && brush_rt(artist, brush_sid, &i50, &i99) == 0 &&
         mesh_rt(artist, move_sid[0], &m50, &m99) == 0;
    for (int k = 0; ok && k < MOVES; k++) ok = start_long_move(mover, move_sid[k], MOVE_GRID) == 0;
    ok = ok && df_client_ping(mover, "x", 1, NULL, NULL) == DF_OK; /* moves have reached the pool */
    ok = ok && brush_rt(artist, brush_sid, &b50, &b99) == 0 &&
         mesh_rt(artist, move_sid[0], &g50, &g99) == 0;
    if (ok) {
        printf("[%s]\n", inline_opt ? "--inline-us 0: every brush update through the compute pool"
                                   : "default config");
        printf("brush update round trip, 1k vertices, idle               : p50 %7.1f us  p99 %7.1f us\n",
               i50, i99);
        printf("  same, with %d long handle moves running (4 workers)     : p50 %7.1f us  p99 %7.1f us\n",
               MOVES, b50, b99);
        printf("get_mesh of a 1.6k-vertex session, idle                  : p50 %7.1f us  p99 %7.1f us\n",
               m50, m99);
        printf("  same, while its long move runs (last published version): p50 %7.1f us  p99 %7.1f us\n",
               g50, g99);
    } else {
        fprintf(stderr, "bench_lockout: a measurement failed\n");
    }
    df_client_close(mover); /* the moves end with their requester (issue 9 item 8) */
    df_client_close(artist);
    if (pid > 0) {
        kill(pid, SIGTERM);
        waitpid(pid, NULL, 0);
    }
    unlink(sock);
    rmdir(dir);
    return ok ? 0 : -1;
}

int main(int argc, char **argv)
{
    (void)argc;
    char exe[4096];
    snprintf(exe, sizeof exe, "%s", argv[0]);
    char *slash = strrchr(exe, '/');
    snprintf(slash ? slash + 1 : exe, sizeof exe - (size_t)(slash ? slash + 1 - exe : 0),
             "../bin/deformd");
    int rc = run(exe, NULL);
    if (rc == 0) rc = run(exe, "0");
    return rc ? 1 : 0;
}
