/* Unit tests for server/exec/job.c + server/session/session.c on a real libuv loop (no sockets): jobs of one
 * session run strictly in submission order (worker jobs and loop-only jobs interleaved), jobs of
 * two sessions run in parallel on the pool (each waits until the other has started: no timing),
 * the per-iteration cap of inline jobs, queued jobs can be dropped (their `done` sees ESTATE), a
 * closed session is freed once its FIFO drains, and the session limit. How long the parallel jobs
 * take is measured by tests/bench/bench_server.c, not asserted here. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include <cmocka.h>

#include "tests/unit/server/tiny_mesh.h"
#include "server/exec/job.h"
#include "server/exec/pool.h"
#include "server/session/session.h"

static pthread_mutex_t g_lock = PTHREAD_MUTEX_INITIALIZER;
static pthread_cond_t g_cond = PTHREAD_COND_INITIALIZER;
static int g_log[64], g_n;
static int g_started[8], g_saw_other[8];

static void record(int v)
{
    pthread_mutex_lock(&g_lock);
    g_log[g_n++] = v;
    pthread_mutex_unlock(&g_lock);
}

/* Jobs 6 and 7 (two sessions): each marks itself started and waits until the other has started
 * too (a 60 s guard turns a serialized pool into a failure instead of a hang). */
static void rendezvous(int i)
{
    struct timespec until;
    clock_gettime(CLOCK_REALTIME, &until);
    until.tv_sec += 60;
    pthread_mutex_lock(&g_lock);
    g_started[i] = 1;
    pthread_cond_broadcast(&g_cond);
    while (!g_started[i == 6 ? 7 : 6])
        if (pthread_cond_timedwait(&g_cond, &g_lock, &until) != 0) break;
    g_saw_other[i] = g_started[i == 6 ? 7 : 6];
    pthread_mutex_unlock(&g_lock);
}

/* body = (intptr_t) index; jobs 0..5 sleep (12 - 2 * index) ms so that unordered runs would
 * finish out of order; jobs 6 and 7 meet (rendezvous). */
static void sleepy_work(df_job *j)
{
    int i = (int)(intptr_t)j->body;
    if (i >= 6) rendezvous(i);
    else usleep((useconds_t)(1000 * (12 - 2 * i)));
    record(i);
}

static int g_done_rc[64];
static void record_done(df_job *j)
{
    int i = (int)(intptr_t)j->body;
    g_done_rc[i] = j->rc;
    if (!j->work && j->rc == DF_OK) record(100 + i); /* loop-only job */
}

static void server_init(df_server *srv, uv_loop_t *loop)
{
    memset(srv, 0, sizeof *srv);
    df_config_defaults(&srv->cfg, NULL);
    srv->loop = loop;
    df_error e; /* every job's work runs on the server's pool (job.h) */
    assert_int_equal(df_pool_start(loop, srv->cfg.threads, 0, &srv->pool, &e), DF_OK);
}

/* Stops the pool started by server_init and closes its handle. */
static void server_fini(df_server *srv)
{
    df_pool_close(srv->pool);
    uv_run(srv->loop, UV_RUN_DEFAULT);
    df_pool_free(srv->pool);
    srv->pool = NULL;
}

static df_job *job(df_server *srv, df_session *s, int i, int worker)
{
    df_job *j = df_job_new(srv, s, NULL, 0, (uint64_t)i, worker ? sleepy_work : NULL, record_done);
    assert_non_null(j);
    j->body = (void *)(intptr_t)i;
    return j;
}

static void test_fifo_order_within_a_session(void **state)
{
    (void)state;
    uv_loop_t loop;
    uv_loop_init(&loop);
    static df_server srv;
    server_init(&srv, &loop);
    df_mesh m = tiny_mesh();
    df_session *s;
    df_error e;
    assert_int_equal(df_session_create(&srv, &m, "a", &s, &e), DF_OK);
    g_n = 0;
    df_job_submit(job(&srv, s, 0, 1));
    df_job_submit(job(&srv, s, 1, 0)); /* loop-only, must wait for job 0 */
    df_job_submit(job(&srv, s, 2, 1));
    df_job_submit(job(&srv, s, 3, 1));
    df_job_submit(job(&srv, s, 4, 0));
    df_job_submit(job(&srv, s, 5, 1));
    assert_non_null(s->running);
    uv_run(&loop, UV_RUN_DEFAULT);
    int want[] = {0, 101, 2, 3, 104, 5};
    assert_int_equal(g_n, 6);
    assert_memory_equal(g_log, want, sizeof want);
    assert_null(s->running);
    assert_true(srv.stats.jobs_completed == 6);
    df_session_destroy(s);
    assert_int_equal(srv.n_sessions, 0);
    server_fini(&srv);
    assert_int_equal(uv_loop_close(&loop), 0);
}

static void test_sessions_run_in_parallel(void **state)
{
    (void)state;
    uv_loop_t loop;
    uv_loop_init(&loop);
    static df_server srv;
    server_init(&srv, &loop);
    df_mesh ma = tiny_mesh(), mb = tiny_mesh();
    df_session *a, *b;
    df_error e;
    assert_int_equal(df_session_create(&srv, &ma, "", &a, &e), DF_OK);
    assert_int_equal(df_session_create(&srv, &mb, "", &b, &e), DF_OK);
    assert_string_equal(a->name, "session-1");
    assert_ptr_equal(df_session_find_name(&srv, "session-2"), b);
    assert_ptr_equal(df_session_find(&srv, a->id), a);
    g_n = 0;
    memset(g_started, 0, sizeof g_started);
    memset(g_saw_other, 0, sizeof g_saw_other);
    df_job_submit(job(&srv, a, 6, 1)); /* each waits for the other to start */
    df_job_submit(job(&srv, b, 7, 1));
    uv_run(&loop, UV_RUN_DEFAULT);
    assert_int_equal(g_n, 2);
    /* both ran at once: each saw the other started while it was still running */
    assert_true(g_saw_other[6] && g_saw_other[7]);
    df_session_destroy(a);
    df_session_destroy(b);
    server_fini(&srv);
    assert_int_equal(uv_loop_close(&loop), 0);
}

/* Inline cap (job.h): a job predicted at exactly inline_us runs on the loop thread, but inline
 * work of one loop iteration stops at DF_JOB_INLINE_ITER_FACTOR x inline_us. Each job's work
 * sleeps at least inline_us, so at most FACTOR of them can run inline before the cap; the rest are
 * deferred to the pool. Deterministic: it relies only on a sleep lasting at least what it asks. */
#define INLINE_JOBS 10
static uint64_t predict_budget(const df_job *j)
{
    return (uint64_t)j->srv->cfg.inline_us * 1000u;
}

static void inline_work(df_job *j)
{
    usleep((useconds_t)j->srv->cfg.inline_us);
    record((int)(intptr_t)j->body);
}

static void test_inline_jobs_capped_per_iteration(void **state)
{
    (void)state;
    uv_loop_t loop;
    uv_loop_init(&loop);
    static df_server srv;
    server_init(&srv, &loop);
    srv.cfg.inline_us = 200;
    df_mesh m = tiny_mesh();
    df_session *s;
    df_error e;
    assert_int_equal(df_session_create(&srv, &m, "inline", &s, &e), DF_OK);
    g_n = 0;
    for (int i = 0; i < INLINE_JOBS; i++) {
        df_job *j = df_job_new(&srv, s, NULL, 0, (uint64_t)i, inline_work, record_done);
        assert_non_null(j);
        j->body = (void *)(intptr_t)i;
        j->inline_cost = predict_budget;
        df_job_submit(j);
    }
    uv_run(&loop, UV_RUN_DEFAULT);
    assert_int_equal(g_n, INLINE_JOBS);
    for (int i = 0; i < INLINE_JOBS; i++) assert_int_equal(g_log[i], i); /* FIFO either way */
    uint64_t in = srv.stats.jobs_inline, deferred = srv.stats.jobs_inline_deferred;
    printf("inline %llu, deferred %llu of %d\n", (unsigned long long)in,
           (unsigned long long)deferred, INLINE_JOBS);
    assert_true(in >= 1 && in <= DF_JOB_INLINE_ITER_FACTOR);
    assert_true(deferred >= 1 && in + deferred <= INLINE_JOBS);
    assert_true(srv.stats.jobs_completed == INLINE_JOBS);
    df_session_destroy(s);
    server_fini(&srv);
    assert_int_equal(uv_loop_close(&loop), 0);

    /* inline_us = 0: never inline, never deferred */
    uv_loop_init(&loop);
    server_init(&srv, &loop);
    srv.cfg.inline_us = 0;
    df_mesh m2 = tiny_mesh();
    assert_int_equal(df_session_create(&srv, &m2, "pool", &s, &e), DF_OK);
    g_n = 0;
    for (int i = 0; i < 3; i++) {
        df_job *j = df_job_new(&srv, s, NULL, 0, (uint64_t)i, inline_work, record_done);
        assert_non_null(j);
        j->body = (void *)(intptr_t)i;
        j->inline_cost = predict_budget;
        df_job_submit(j);
    }
    uv_run(&loop, UV_RUN_DEFAULT);
    assert_int_equal(g_n, 3);
    assert_true(srv.stats.jobs_inline == 0 && srv.stats.jobs_inline_deferred == 0);
    df_session_destroy(s);
    server_fini(&srv);
    assert_int_equal(uv_loop_close(&loop), 0);
}

static int pred_odd(const df_job *j, void *arg)
{
    (void)arg;
    return ((intptr_t)j->body) % 2 == 1;
}

static void test_drop_queued_and_close(void **state)
{
    (void)state;
    uv_loop_t loop;
    uv_loop_init(&loop);
    static df_server srv;
    server_init(&srv, &loop);
    srv.cfg.max_sessions = 1;
    df_mesh m = tiny_mesh(), m2 = tiny_mesh();
    df_session *s, *s2 = NULL;
    df_error e;
    assert_int_equal(df_session_create(&srv, &m, "only", &s, &e), DF_OK);
    assert_int_equal(df_session_create(&srv, &m2, "two", &s2, &e), DF_ELIMIT);
    assert_null(s2);
    g_n = 0;
    memset(g_done_rc, 0x7f, sizeof g_done_rc);
    df_job_submit(job(&srv, s, 0, 1)); /* running */
    df_job_submit(job(&srv, s, 1, 1));
    df_job_submit(job(&srv, s, 2, 1));
    df_job_submit(job(&srv, s, 3, 1));
    assert_int_equal(df_job_drop_queued(s, pred_odd, NULL, "dropped"), 2);
    assert_int_equal(g_done_rc[1], DF_ESTATE);
    assert_int_equal(g_done_rc[3], DF_ESTATE);
    df_session_close(s); /* freed when the FIFO drains */
    assert_null(df_session_find(&srv, 1));
    assert_int_equal(srv.n_sessions, 1);
    uv_run(&loop, UV_RUN_DEFAULT);
    assert_int_equal(srv.n_sessions, 0);
    int want[] = {0, 2};
    assert_int_equal(g_n, 2);
    assert_memory_equal(g_log, want, sizeof want);
    assert_int_equal(g_done_rc[0], DF_OK);
    assert_int_equal(g_done_rc[2], DF_OK);
    server_fini(&srv);
    assert_int_equal(uv_loop_close(&loop), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fifo_order_within_a_session),
        cmocka_unit_test(test_sessions_run_in_parallel),
        cmocka_unit_test(test_inline_jobs_capped_per_iteration),
        cmocka_unit_test(test_drop_queued_and_close),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
