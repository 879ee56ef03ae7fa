/* bench_server.c — the timing figures that used to be assertions of `make test` (issue 10: no
 * wall-clock assertion in the test suite), measured and printed with their targets by `make bench`:
 *   1. two 150 ms jobs of two sessions on a bare server (job FIFO, libuv pool): total wall time,
 *      target < 290 ms (they overlap) — was tests/unit/server/test_jobs.c;
 *   2. compute pool, 2 workers: a short task submitted after a 200 ms one completes after
 *      < 150 ms — was test_pool.c;
 *   3. compute pool, spinning workers (spin 500 us), 50 back-to-back chained short tasks: hand-offs
 *      a spinning worker took without a wake-up, target >= 1 of 49 — was test_pool.c;
 *   4. parse time of stanford-bunny.obj and pig_rest.ele (+ .node) from $MESHES, best of 3, target
 *      < 1000 ms — was tests/unit/mesh/test_mesh_real.c;
 *   5. encode / decode of one 1M-vertex dense displacement frame, best of 5, target encode < 16 ms
 *      (60 frames/s) — was tests/unit/proto/test_stream.c;
 *   6. ADMM predictive time budget (Neo-Hookean bar, 1 thread): how far a run overshoots its
 *      max_ms, target <= budget + 3 iterations + 30 ms — was tests/unit/admm/test_admm_speed.c.
 * Every line reads "what: measured (target ...) ok|MISS". Exit status 0 when every measurement ran
 * (targets are reported, not enforced), 1 otherwise. */
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "core/admm/admm.h"
#include "core/mesh/mesh_io.h"
#include "proto/messages.h"
#include "server/exec/job.h"
#include "server/exec/pool.h"
#include "server/session/session.h"
#include "tests/unit/admm/admm_test_util.h"

static int g_errors;

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

static void report(const char *what, double v, const char *unit, const char *target, int ok)
{
    printf("  %-58s %9.2f %-3s (target %s) %s\n", what, v, unit, target, ok ? "ok" : "MISS");
}

/* ---- 1. two sessions' jobs in parallel ------------------------------------------------------ */
static void sleep_150(df_job *j)
{
    (void)j;
    usleep(150000);
}
static void job_done(df_job *j)
{
    (void)j;
}

static df_mesh tiny_mesh(void)
{
    df_mesh m;
    memset(&m, 0, sizeof m);
    m.kind = DF_MESH_TRIANGLE;
    m.nv = 3;
    m.ne = 1;
    m.V = calloc(9, sizeof(double));
    m.E = malloc(3 * sizeof(int32_t));
    m.V[3] = 1;
    m.V[7] = 1;
    m.E[0] = 0, m.E[1] = 1, m.E[2] = 2;
    return m;
}

static void bench_jobs(void)
{
    uv_loop_t loop;
    uv_loop_init(&loop);
    static df_server srv;
    memset(&srv, 0, sizeof srv);
    df_config_defaults(&srv.cfg, NULL);
    srv.loop = &loop;
    df_mesh ma = tiny_mesh(), mb = tiny_mesh();
    df_session *a, *b;
    df_error e;
    if (df_pool_start(&loop, srv.cfg.threads, 0, &srv.pool, &e) != DF_OK) { /* job.h */
        fprintf(stderr, "pool: %s\n", e.msg);
        g_errors++;
        return;
    }
    if (df_session_create(&srv, &ma, "a", &a, &e) != DF_OK ||
        df_session_create(&srv, &mb, "b", &b, &e) != DF_OK) {
        fprintf(stderr, "session: %s\n", e.msg);
        g_errors++;
        return;
    }
    double t0 = now_ms();
    df_job_submit(df_job_new(&srv, a, NULL, 0, 1, sleep_150, job_done));
    df_job_submit(df_job_new(&srv, b, NULL, 0, 2, sleep_150, job_done));
    uv_run(&loop, UV_RUN_DEFAULT);
    double total = now_ms() - t0;
    report("two sessions' 150 ms jobs, total", total, "ms", "< 290", total < 290.0);
    df_session_destroy(a);
    df_session_destroy(b);
    df_pool_close(srv.pool);
    uv_run(&loop, UV_RUN_DEFAULT);
    df_pool_free(srv.pool);
    uv_loop_close(&loop);
}

/* ---- 2, 3. compute pool ---------------------------------------------------------------------- */
typedef struct item {
    df_task t;
    int sleep_ms;
    double end;
} item;

static struct {
    df_pool *p;
    item *v;
    int n, done, chain, first_done;
} g;

static void item_work(df_task *t)
{
    item *it = (item *)t;
    if (it->sleep_ms) usleep((useconds_t)it->sleep_ms * 1000);
    it->end = now_ms();
}

static void item_after(df_task *t)
{
    if (g.done == 0) g.first_done = (int)((item *)t - g.v);
    g.done++;
    if (g.chain && g.done < g.n) df_pool_submit(g.p, &g.v[g.done].t);
    if (g.done == g.n) df_pool_close(g.p);
}

static int run_pool(item *v, int n, int threads, uint64_t spin_ns, int chain,
                    df_pool_counters *cnt)
{
    uv_loop_t loop;
    uv_loop_init(&loop);
    memset(&g, 0, sizeof g);
    g.v = v;
    g.n = n;
    g.chain = chain;
    for (int i = 0; i < n; i++) {
        v[i].t.work = item_work;
        v[i].t.after = item_after;
    }
    df_error e;
    if (df_pool_start(&loop, threads, spin_ns, &g.p, &e) != DF_OK) {
        fprintf(stderr, "pool: %s\n", e.msg);
        g_errors++;
        return -1;
    }
    if (chain) df_pool_submit(g.p, &v[0].t);
    else
        for (int i = 0; i < n; i++) df_pool_submit(g.p, &v[i].t);
    uv_run(&loop, UV_RUN_DEFAULT);
    df_pool_counters_get(g.p, cnt);
    df_pool_free(g.p);
    uv_loop_close(&loop);
    return 0;
}

static void bench_pool(void)
{
    item v[50];
    df_pool_counters cnt;
    memset(v, 0, sizeof v);
    v[0].sleep_ms = 200;
    double t0 = now_ms();
    if (run_pool(v, 2, 2, 0, 0, &cnt) == 0) {
        double short_ms = v[1].end - t0;
        report("short pool task behind a 200 ms one, done after", short_ms, "ms", "< 150",
               short_ms < 150.0 && g.first_done == 1);
    }
    memset(v, 0, sizeof v);
    if (run_pool(v, 50, 2, 500000, 1, &cnt) == 0)
        report("spinning workers: hand-offs without a wake-up, of 49", (double)cnt.spin_hits, "",
               ">= 1", cnt.spin_hits >= 1);
}

/* ---- 4. parse --------------------------------------------------------------------------------- */
static void bench_parse(void)
{
    const char *dir = getenv("MESHES");
    if (!dir || !*dir) dir = "../shared/meshes";
    static const char *files[] = {"stanford-bunny.obj", "pig_rest.ele"};
    for (int f = 0; f < 2; f++) {
        char p[1024], what[128];
        snprintf(p, sizeof p, "%s/%s", dir, files[f]);
        double best = 1e9;
        for (int rep = 0; rep < 3; rep++) {
            df_mesh m;
            df_mesh_init(&m);
            df_error e;
            double t0 = now_ms();
            if (df_mesh_read_file(p, NULL, &m, NULL, &e) != DF_OK) {
                fprintf(stderr, "parse %s: %s\n", p, e.msg);
                g_errors++;
                return;
            }
            double dt = now_ms() - t0;
            best = dt < best ? dt : best;
            df_mesh_free(&m);
        }
        snprintf(what, sizeof what, "parse %s, best of 3", files[f]);
        report(what, best, "ms", "< 1000", best < 1000.0);
    }
}

/* ---- 5. 1M dense frame ----------------------------------------------------------------------- */
static void bench_frame(void)
{
    const uint32_t nv = 1000000;
    float *u = malloc(sizeof(float) * 3 * nv);
    for (uint32_t i = 0; i < 3 * nv; i++) u[i] = (float)(i % 1000) * 1e-3f;
    df_msg_disp d = {1, 2, 1, DF_CHANGE_BRUSH, DF_DISP_DENSE, nv, nv, 0, nv, NULL, u};
    df_buf b;
    df_buf_init(&b);
    df_error e;
    double best_enc = 1e9, best_dec = 1e9;
    for (int rep = 0; rep < 5; rep++) {
        df_buf_reset(&b);
        double t0 = now_ms();
        int rc = df_msg_disp_encode(&d, &b, &e);
        double t1 = now_ms();
        df_msg_disp q;
        if (rc != DF_OK || df_msg_disp_decode(b.data, b.len, &q, &e) != DF_OK) {
            fprintf(stderr, "1M frame: %s\n", e.msg);
            g_errors++;
            break;
        }
        double t2 = now_ms();
        df_msg_disp_free(&q);
        best_enc = t1 - t0 < best_enc ? t1 - t0 : best_enc;
        best_dec = t2 - t1 < best_dec ? t2 - t1 : best_dec;
    }
    report("1M-vertex dense frame encode, best of 5", best_enc, "ms", "< 16", best_enc < 16.0);
    report("1M-vertex dense frame decode, best of 5", best_dec, "ms", "(none)", 1);
    df_buf_free(&b);
    free(u);
}

/* ---- 6. ADMM predictive budget ----------------------------------------------------------------- */
static void bench_admm_budget(void)
{
    df_mesh m = tu_bar3d(24, 3, 3, 3.0, 1.0, 1.0);
    int32_t *h = malloc((size_t)m.nv * sizeof(int32_t));
    double *tg = malloc((size_t)m.nv * 3 * sizeof(double));
    int nh = 0;
    for (int32_t i = 0; i < m.nv; i++) {
        double x = m.V[3 * i];
        if (x == 0.0 || x == 3.0) {
            h[nh] = i;
            memcpy(tg + 3 * nh, m.V + 3 * i, 24);
            if (x == 3.0) tg[3 * nh] += 0.3, tg[3 * nh + 1] += 0.2;
            nh++;
        }
    }
    df_admm_params p;
    df_admm_params_default(&p, DF_ADMM_NEOHOOKEAN);
    p.threads = 1;
    p.rho = 1e5; p.s = 0.05; p.w = p.rho * p.s / 10; p.tol = 1e-300; /* never converges */
    df_admm *s = NULL;
    df_error err;
    df_admm_result r;
    if (df_admm_create(&m, &p, h, nh, NULL, 0, &s, &err) != DF_OK ||
        df_admm_set_targets(s, tg, &err) != DF_OK ||
        df_admm_run(s, &(df_admm_budget){5, 0, 0, NULL, NULL}, &r, &err) != DF_OK) {
        fprintf(stderr, "admm: %s\n", err.msg);
        g_errors++;
    } else {
        double it_ms = 1e3 * r.t_total / r.iterations, budget = fmax(40.0, 10.0 * it_ms), worst = 0;
        for (int rep = 0; rep < 3; rep++) {
            double t0 = now_ms();
            df_admm_run(s, &(df_admm_budget){DF_ADMM_MAX_ITERS_LIMIT, budget, 1, NULL, NULL}, &r, &err);
            worst = fmax(worst, now_ms() - t0 - budget);
        }
        char what[128], target[64];
        snprintf(what, sizeof what, "ADMM max_ms %.0f ms (iteration %.2f ms): worst overshoot",
                 budget, it_ms);
        snprintf(target, sizeof target, "<= %.1f", 3.0 * it_ms + 30.0);
        report(what, worst, "ms", target, worst <= 3.0 * it_ms + 30.0);
    }
    df_admm_free(s);
    free(h);
    free(tg);
    tu_free(&m);
}

int main(void)
{
    printf("bench_server: timing figures kept out of make test (measured, with targets)\n");
    bench_jobs();
    bench_pool();
    bench_parse();
    bench_frame();
    bench_admm_budget();
    return g_errors ? 1 : 0;
}
