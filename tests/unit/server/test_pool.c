/* Unit tests for the server's latency work: server/exec/pool.c (the compute pool and its one completion
 * channel: progress posts before the completion), the pool-backed job
 * FIFO of server/exec/job.c, the single-allocation displacement frames of server/session/stream.c (byte-equal
 * to the proto encoder's) and the spin_us setting of server/config.c. Nothing here asserts a
 * duration: how fast a short task passes a slow one and how often spinning workers catch
 * back-to-back tasks are printed by tests/bench/bench_server.c (make bench). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <pthread.h>
#include <math.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include <cmocka.h>

#include "proto/buf.h"
#include "proto/frame_codec.h"
#include "tests/unit/server/tiny_mesh.h"
#include "server/config.h"
#include "server/exec/job.h"
#include "server/exec/pool.h"
#include "server/net/reply.h"
#include "server/session/stream.h"

#define N_TASKS 200

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

typedef struct item {
    df_task t;
    int id;
    long in, out;          /* work: out = in * in + 1 */
    int ran, after_ran;
    int sleep_ms;
    int wait_for;          /* > 0: work waits until item wait_for - 1's `after` has run */
    int saw_it;            /* that item's `after` had run when this work ended */
    double start, end;     /* work interval (ms) */
    pthread_t work_thread, after_thread;
} item;

typedef struct ctx {
    df_pool *p;
    int done, want;
    int order[N_TASKS];
    int chain;             /* > 0: submit the next item from `after` (back-to-back requests) */
    item *items;
} ctx;

static ctx *g_ctx;
static pthread_mutex_t g_after_lock = PTHREAD_MUTEX_INITIALIZER;
static pthread_cond_t g_after_cond = PTHREAD_COND_INITIALIZER;

/* Waits (60 s guard: a failure, not a hang) until item k's `after` has run on the loop thread. */
static int wait_after_of(int k)
{
    struct timespec until;
    clock_gettime(CLOCK_REALTIME, &until);
    until.tv_sec += 60;
    pthread_mutex_lock(&g_after_lock);
    while (!g_ctx->items[k].after_ran)
        if (pthread_cond_timedwait(&g_after_cond, &g_after_lock, &until) != 0) break;
    int seen = g_ctx->items[k].after_ran;
    pthread_mutex_unlock(&g_after_lock);
    return seen;
}

static void item_work(df_task *t)
{
    item *it = (item *)t;
    it->start = now_ms();
    it->work_thread = pthread_self();
    if (it->wait_for) it->saw_it = wait_after_of(it->wait_for - 1);
    if (it->sleep_ms) usleep((useconds_t)it->sleep_ms * 1000);
    it->out = it->in * it->in + 1;
    it->ran++;
    it->end = now_ms();
}

static void item_after(df_task *t)
{
    item *it = (item *)t;
    ctx *c = g_ctx;
    pthread_mutex_lock(&g_after_lock);
    it->after_ran++;
    pthread_cond_broadcast(&g_after_cond);
    pthread_mutex_unlock(&g_after_lock);
    it->after_thread = pthread_self();
    c->order[c->done++] = it->id;
    if (c->chain && c->done < c->want) df_pool_submit(c->p, &c->items[c->done].t);
    if (c->done == c->want) df_pool_close(c->p); /* the loop ends once the handle is closed */
}

static void items_init(item *v, int n)
{
    memset(v, 0, (size_t)n * sizeof *v);
    for (int i = 0; i < n; i++) {
        v[i].t.work = item_work;
        v[i].t.after = item_after;
        v[i].id = i;
        v[i].in = 1000 + i;
    }
}

/* Runs `want` items on a pool of `threads` workers (all submitted at once, or chained). */
static void run_items(ctx *c, item *v, int want, int threads, uint64_t spin_ns, int chain,
                      df_pool_counters *cnt)
{
    uv_loop_t loop;
    assert_int_equal(uv_loop_init(&loop), 0);
    memset(c, 0, sizeof *c);
    c->want = want;
    c->chain = chain;
    c->items = v;
    g_ctx = c;
    df_error e;
    assert_int_equal(df_pool_start(&loop, threads, spin_ns, &c->p, &e), DF_OK);
    if (chain) df_pool_submit(c->p, &v[0].t);
    else
        for (int i = 0; i < want; i++) df_pool_submit(c->p, &v[i].t);
    assert_int_equal(df_pool_inflight(c->p), chain ? 1 : want);
    uv_run(&loop, UV_RUN_DEFAULT);
    assert_int_equal(df_pool_inflight(c->p), 0);
    df_pool_counters_get(c->p, cnt);
    df_pool_free(c->p);
    assert_int_equal(uv_loop_close(&loop), 0);
}

static void test_pool_runs_every_task_once_after_on_loop(void **state)
{
    (void)state;
    static item v[N_TASKS];
    items_init(v, N_TASKS);
    v[7].sleep_ms = 3;
    ctx c;
    df_pool_counters cnt;
    pthread_t self = pthread_self();
    run_items(&c, v, N_TASKS, 3, 0, 0, &cnt);
    assert_int_equal(c.done, N_TASKS);
    int seen[N_TASKS] = {0};
    for (int i = 0; i < N_TASKS; i++) {
        assert_int_equal(v[i].ran, 1);
        assert_int_equal(v[i].after_ran, 1);
        assert_true(v[i].out == (1000L + i) * (1000L + i) + 1);
        assert_true(pthread_equal(v[i].after_thread, self));
        assert_false(pthread_equal(v[i].work_thread, self));
        seen[c.order[i]]++;
    }
    for (int i = 0; i < N_TASKS; i++) assert_int_equal(seen[i], 1);
    assert_true(v[7].t.work_ns >= 3000000u); /* the 3 ms task: a sleep lasts at least what it asks */
    assert_true(cnt.tasks == N_TASKS);
    assert_true(cnt.spin_hits == 0);         /* spin_ns 0: workers never spin */
    assert_true(cnt.wakeups >= 1 && cnt.wakeups <= N_TASKS);
}

/* A slow task (a solve on one session) must not hold back a short one submitted after it: the
 * slow task only ends once the short one has completed on the loop, which needs a second
 * worker and a loop that is not waiting for the slow one. */
static void test_pool_slow_task_does_not_stall_short_one(void **state)
{
    (void)state;
    static item v[2];
    items_init(v, 2);
    v[0].wait_for = 2; /* item 0 runs until item 1's after has run */
    ctx c;
    df_pool_counters cnt;
    run_items(&c, v, 2, 2, 0, 0, &cnt);
    assert_int_equal(v[0].saw_it, 1);
    assert_int_equal(c.order[0], 1); /* the short one completed first */
    assert_int_equal(c.order[1], 0);
}

/* Back-to-back short tasks with spinning workers: some hand-offs need no wake-up. */
/* Long lane: heavy tasks that block until a short task has completed. With 2 workers and
 * 3 heavy tasks submitted first, at most one heavy task runs at a time and the short task,
 * submitted last, still gets the other worker (without the lane both workers would block: the
 * heavy tasks give up after a generous 20 s and record it). */
#define LANE_HEAVY 3
static atomic_int lane_released, lane_running, lane_max_running, lane_gave_up;

static void lane_heavy_work(df_task *t)
{
    int n = atomic_fetch_add(&lane_running, 1) + 1;
    int m = atomic_load(&lane_max_running);
    while (n > m && !atomic_compare_exchange_weak(&lane_max_running, &m, n)) {
    }
    double give_up = now_ms() + 20000.0;
    while (!atomic_load(&lane_released)) {
        if (now_ms() > give_up) {
            atomic_store(&lane_gave_up, 1);
            break;
        }
        usleep(1000);
    }
    atomic_fetch_sub(&lane_running, 1);
    item_work(t);
}

static void lane_short_after(df_task *t)
{
    atomic_store(&lane_released, 1);
    item_after(t);
}

static void test_pool_long_lane_leaves_a_worker_for_short_tasks(void **state)
{
    (void)state;
    static item v[LANE_HEAVY + 1];
    items_init(v, LANE_HEAVY + 1);
    for (int i = 0; i < LANE_HEAVY; i++) {
        v[i].t.work = lane_heavy_work;
        v[i].t.heavy = 1;
    }
    v[LANE_HEAVY].t.after = lane_short_after;
    atomic_store(&lane_released, 0);
    atomic_store(&lane_running, 0);
    atomic_store(&lane_max_running, 0);
    atomic_store(&lane_gave_up, 0);
    ctx c;
    df_pool_counters cnt;
    run_items(&c, v, LANE_HEAVY + 1, 2, 0, 0, &cnt);
    assert_int_equal(atomic_load(&lane_gave_up), 0);
    assert_int_equal(c.order[0], LANE_HEAVY);     /* the short task finished first */
    assert_int_equal(atomic_load(&lane_max_running), 1);
    assert_int_equal(cnt.heavy_max, 1);
    assert_true(cnt.heavy_waits >= LANE_HEAVY - 1);
    for (int i = 0; i <= LANE_HEAVY; i++) assert_int_equal(v[i].ran, 1);
}

/* Yielding: heavy task A (lane of 1) waits until heavy task B queues behind it, then requeues
 * itself; B runs and completes, then A runs again and completes: long tasks take turns, and a
 * task's `after` runs once, when it really finished. */
static df_pool *yield_pool;
static atomic_int yield_a_runs, yield_gave_up;

static void yield_a_work(df_task *t)
{
    if (atomic_fetch_add(&yield_a_runs, 1) == 0) {
        double give_up = now_ms() + 20000.0;
        while (df_pool_heavy_waiting(yield_pool) == 0) {
            if (now_ms() > give_up) {
                atomic_store(&yield_gave_up, 1);
                break;
            }
            usleep(1000);
        }
        t->requeue = 1;
        return;
    }
    item_work(t);
}

static void test_pool_heavy_task_yields_to_a_waiting_one(void **state)
{
    (void)state;
    static item v[2];
    items_init(v, 2);
    v[0].t.work = yield_a_work;
    v[0].t.heavy = v[1].t.heavy = 1;
    atomic_store(&yield_a_runs, 0);
    atomic_store(&yield_gave_up, 0);
    uv_loop_t loop;
    assert_int_equal(uv_loop_init(&loop), 0);
    ctx c;
    memset(&c, 0, sizeof c);
    c.want = 2;
    c.items = v;
    g_ctx = &c;
    df_error e;
    assert_int_equal(df_pool_start(&loop, 2, 0, &c.p, &e), DF_OK);
    yield_pool = c.p;
    df_pool_submit(c.p, &v[0].t);
    df_pool_submit(c.p, &v[1].t);
    uv_run(&loop, UV_RUN_DEFAULT);
    df_pool_free(c.p);
    assert_int_equal(uv_loop_close(&loop), 0);
    assert_int_equal(atomic_load(&yield_gave_up), 0);
    assert_int_equal(atomic_load(&yield_a_runs), 2);
    assert_int_equal(c.order[0], 1); /* B finished first, then A */
    assert_int_equal(c.order[1], 0);
    assert_int_equal(v[0].after_ran, 1);
    assert_int_equal(v[1].after_ran, 1);
}

static void test_pool_spinning_worker_takes_back_to_back_tasks(void **state)
{
    (void)state;
    static item v[50];
    items_init(v, 50);
    ctx c;
    df_pool_counters cnt;
    run_items(&c, v, 50, 2, 500000, 1, &cnt);
    assert_int_equal(c.done, 50);
    for (int i = 0; i < 50; i++) assert_int_equal(c.order[i], i);
    assert_true(cnt.tasks == 50);
    assert_true(cnt.spin_hits <= 49); /* how many: bench_server (timing-dependent) */
}

static void test_pool_rejects_bad_arguments(void **state)
{
    (void)state;
    uv_loop_t loop;
    assert_int_equal(uv_loop_init(&loop), 0);
    df_pool *p = (df_pool *)&loop; /* must stay untouched */
    df_error e;
    assert_int_equal(df_pool_start(&loop, 0, 0, &p, &e), DF_EINVAL);
    assert_int_equal(df_pool_start(&loop, DF_POOL_MAX_THREADS + 1, 0, &p, &e), DF_EINVAL);
    assert_int_equal(df_pool_start(&loop, 2, DF_POOL_MAX_SPIN_NS + 1, &p, &e), DF_EINVAL);
    assert_non_null(strstr(e.msg, "spin"));
    assert_ptr_equal(p, (df_pool *)&loop);
    assert_int_equal(uv_loop_close(&loop), 0);
}

/* ---- one completion channel: progress posts arrive before their task's completion -------- */

typedef struct post_msg {
    df_task t;
    int n;
} post_msg;

static struct {
    df_pool *p;
    int order[8], n;
} g_post;

static void post_after(df_task *t)
{
    post_msg *m = (post_msg *)t;
    g_post.order[g_post.n++] = m->n;
    free(m);
}

static void posting_work(df_task *t)
{
    (void)t;
    for (int i = 1; i <= 3; i++) {
        post_msg *m = calloc(1, sizeof *m);
        assert_non_null(m);
        m->n = i;
        m->t.after = post_after;
        df_pool_post(g_post.p, &m->t);
        usleep(2000); /* the loop may deliver some before the next post */
    }
}

static void posting_after(df_task *t)
{
    (void)t;
    g_post.order[g_post.n++] = 100; /* the completion */
    assert_int_equal(df_pool_inflight(g_post.p), 0);
}

static void test_pool_posts_arrive_before_completion(void **state)
{
    (void)state;
    uv_loop_t loop;
    assert_int_equal(uv_loop_init(&loop), 0);
    df_error e;
    assert_int_equal(df_pool_start(&loop, 2, 0, &g_post.p, &e), DF_OK);
    g_post.n = 0;
    df_task t = {.work = posting_work, .after = posting_after};
    df_pool_submit(g_post.p, &t);
    assert_int_equal(df_pool_inflight(g_post.p), 1); /* posts are not tasks */
    uv_run(&loop, UV_RUN_DEFAULT); /* returns: the idle pool keeps no loop alive */
    int want[] = {1, 2, 3, 100};
    assert_int_equal(g_post.n, 4);
    assert_memory_equal(g_post.order, want, sizeof want);
    df_pool_counters pc;
    df_pool_counters_get(g_post.p, &pc);
    assert_true(pc.tasks == 1);
    df_pool_close(g_post.p);
    uv_run(&loop, UV_RUN_DEFAULT);
    df_pool_free(g_post.p);
    assert_int_equal(uv_loop_close(&loop), 0);
}

/* ---- job FIFO on the pool ------------------------------------------------------------------ */

static int g_log[16], g_n, g_jobs_done;
static pthread_mutex_t g_lock = PTHREAD_MUTEX_INITIALIZER;

static void fifo_work(df_job *j)
{
    int i = (int)(intptr_t)j->body;
    usleep((useconds_t)(1000 * (8 - i))); /* earlier jobs run longer */
    pthread_mutex_lock(&g_lock);
    g_log[g_n++] = i;
    pthread_mutex_unlock(&g_lock);
}

static void fifo_done(df_job *j)
{
    int i = (int)(intptr_t)j->body;
    if (!j->work) g_log[g_n++] = 100 + i;
    if (++g_jobs_done == 6) df_pool_close(j->srv->pool);
}

static void test_jobs_on_pool_keep_session_fifo(void **state)
{
    (void)state;
    uv_loop_t loop;
    assert_int_equal(uv_loop_init(&loop), 0);
    static df_server srv;
    memset(&srv, 0, sizeof srv);
    df_config_defaults(&srv.cfg, NULL);
    srv.loop = &loop;
    df_error e;
    assert_int_equal(df_pool_start(&loop, 4, 0, &srv.pool, &e), DF_OK);
    df_mesh m = tiny_mesh();
    assert_non_null(m.V);
    assert_non_null(m.E);
    df_session *s;
    assert_int_equal(df_session_create(&srv, &m, "fifo", &s, &e), DF_OK);
    g_n = g_jobs_done = 0;
    for (int i = 0; i < 6; i++) {
        int worker = i != 1 && i != 4;
        df_job *j = df_job_new(&srv, s, NULL, 0, (uint64_t)i, worker ? fifo_work : NULL,
                               fifo_done);
        assert_non_null(j);
        j->body = (void *)(intptr_t)i;
        df_job_submit(j);
    }
    assert_int_equal(df_pool_inflight(srv.pool), 1); /* only the head job runs */
    uv_run(&loop, UV_RUN_DEFAULT);
    int want[] = {0, 101, 2, 3, 104, 5};
    assert_int_equal(g_n, 6);
    assert_memory_equal(g_log, want, sizeof want);
    assert_true(srv.stats.jobs_completed == 6);
    assert_int_equal(srv.jobs_running, 0);
    df_pool_counters cnt;
    df_pool_counters_get(srv.pool, &cnt);
    assert_true(cnt.tasks == 4);
    df_session_destroy(s);
    df_pool_free(srv.pool);
    srv.pool = NULL;
    assert_int_equal(uv_loop_close(&loop), 0);
}

/* ---- displacement frames: byte-equal to the proto encoder ----------------------------------- */

static void check_frames_match_encoder(df_frames *fr, uint8_t want_encoding)
{
    assert_true(fr->n >= 1);
    for (size_t k = 0; k < fr->n; k++) {
        df_frame_header h;
        df_error e;
        const df_sbuf *b = fr->v[k];
        assert_int_equal(df_frame_header_decode(b->data, b->len, &h, &e), DF_OK);
        df_msg_disp d;
        assert_int_equal(df_msg_disp_decode(b->data + DF_FRAME_HEADER_SIZE, h.payload_len, &d, &e),
                         DF_OK);
        assert_int_equal(d.encoding, want_encoding);
        df_sbuf *ref = df_out_disp(h.type, h.flags, h.request_id, &d, &e);
        assert_non_null(ref);
        assert_int_equal(ref->len, b->len);
        assert_memory_equal(ref->data, b->data, b->len);
        df_sbuf_unref(ref);
        df_msg_disp_free(&d);
    }
}

static void test_stream_frames_equal_proto_encoder(void **state)
{
    (void)state;
    const int32_t nv = 3000;
    static df_session s;
    memset(&s, 0, sizeof s);
    s.id = 9;
    s.nv = nv;
    s.mesh.nv = nv;
    s.mesh.V = malloc(3 * (size_t)nv * sizeof(double));
    s.uf = calloc(3 * (size_t)nv, sizeof(float));
    double *pos = malloc(3 * (size_t)nv * sizeof(double));
    assert_non_null(s.mesh.V);
    assert_non_null(s.uf);
    assert_non_null(pos);
    atomic_init(&s.version, 5);
    for (size_t i = 0; i < 3 * (size_t)nv; i++) {
        s.mesh.V[i] = 0.001 * (double)(i % 1009) - 0.3;
        pos[i] = s.mesh.V[i] + 1e-3 * (double)((i * 7) % 11);
    }
    df_frames fr = {0};
    df_error e;
    uint32_t changed = 0;
    /* dense: every vertex moved (no row count asked: the row pass is skipped) */
    assert_int_equal(df_stream_publish(&s, pos, DF_CHANGE_BRUSH, NULL, 0, &fr, NULL, &e), DF_OK);
    check_frames_match_encoder(&fr, DF_DISP_DENSE);
    for (size_t i = 0; i < 3 * (size_t)nv; i++)
        if (s.uf[i] != (float)(pos[i] - s.mesh.V[i])) fail_msg("component %zu differs", i);
    df_frames_clear(&fr);
    /* 2/3 of the vertices move, with the row count: sparse (2000 16-byte rows < 3000 x 12) */
    for (int32_t v = 0; v < nv; v++)
        if (v % 3) pos[3 * (size_t)v] += 0.125;
    assert_int_equal(df_stream_publish(&s, pos, DF_CHANGE_BRUSH, NULL, 0, &fr, &changed, &e),
                     DF_OK);
    assert_int_equal(changed, 2000);
    check_frames_match_encoder(&fr, DF_DISP_SPARSE);
    df_frames_clear(&fr);
    /* sparse: 40 vertices moved again */
    for (int r = 0; r < 40; r++) pos[3 * (size_t)(r * 71) + 1] += 0.25;
    assert_int_equal(df_stream_publish(&s, pos, DF_CHANGE_BRUSH, NULL, 0, &fr, &changed, &e),
                     DF_OK);
    assert_int_equal(changed, 40);
    check_frames_match_encoder(&fr, DF_DISP_SPARSE);
    df_frames_clear(&fr);
    /* 40 again, without asking the count: the sparse rows are still found */
    for (int r = 0; r < 40; r++) pos[3 * (size_t)(r * 73) + 2] -= 0.5;
    assert_int_equal(df_stream_publish(&s, pos, DF_CHANGE_BRUSH, NULL, 0, &fr, NULL, &e), DF_OK);
    check_frames_match_encoder(&fr, DF_DISP_SPARSE);
    df_frames_clear(&fr);
    assert_true(atomic_load(&s.version) == 9);
    /* a non-finite position changes nothing */
    pos[3 * 17 + 2] = INFINITY;
    assert_int_equal(df_stream_publish(&s, pos, DF_CHANGE_BRUSH, NULL, 0, &fr, &changed, &e),
                     DF_EINVAL);
    assert_non_null(strstr(e.msg, "vertex 17"));
    assert_int_equal(fr.n, 0);
    assert_true(atomic_load(&s.version) == 9);
    /* snapshot reply frames too */
    assert_int_equal(df_stream_snapshot(&s, DF_MSG_SNAPSHOT, 77, &fr, &e), DF_OK);
    for (size_t k = 0; k < fr.n; k++) assert_true(df_le16_load(fr.v[k]->data + 8) & DF_FLAG_REPLY);
    df_frames_clear(&fr);
    free(pos);
    free(s.mesh.V);
    free(s.uf);
    free(s.scratch_u);
    free(s.scratch_idx);
    free(s.scratch_rows);
    free(s.scratch_pos);
    free(s.scratch_disp);
}

static void test_config_spin_us(void **state)
{
    (void)state;
    df_server_config cfg;
    df_error e;
    df_config_defaults(&cfg, NULL);
    assert_int_equal(cfg.spin_us, DF_CONFIG_DEFAULT_SPIN_US);
    assert_int_equal(df_config_set(&cfg, "spin_us", "80", &e), DF_OK);
    assert_int_equal(cfg.spin_us, 80);
    assert_int_equal(df_config_set(&cfg, "spin_us", "1001", &e), DF_EINVAL);
    assert_int_equal(cfg.spin_us, 80);
    char *argv[] = {"deformd", "--socket", "/tmp/x.sock", "--spin-us", "25", NULL};
    df_cli_action act;
    assert_int_equal(df_config_from_args(&cfg, 5, argv, NULL, &act, &e), DF_OK);
    assert_int_equal(cfg.spin_us, 25);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pool_runs_every_task_once_after_on_loop),
        cmocka_unit_test(test_pool_slow_task_does_not_stall_short_one),
        cmocka_unit_test(test_pool_long_lane_leaves_a_worker_for_short_tasks),
        cmocka_unit_test(test_pool_heavy_task_yields_to_a_waiting_one),
        cmocka_unit_test(test_pool_spinning_worker_takes_back_to_back_tasks),
        cmocka_unit_test(test_pool_rejects_bad_arguments),
        cmocka_unit_test(test_pool_posts_arrive_before_completion),
        cmocka_unit_test(test_jobs_on_pool_keep_session_fifo),
        cmocka_unit_test(test_stream_frames_equal_proto_encoder),
        cmocka_unit_test(test_config_spin_us),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
