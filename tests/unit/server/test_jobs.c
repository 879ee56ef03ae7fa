/* Unit tests for server/job.c + server/session.c on a real libuv loop (no sockets): jobs of one
 * session run strictly in submission order (worker jobs and loop-only jobs interleaved), jobs of
 * two sessions run in parallel on the pool, queued jobs can be dropped (their `done` sees
 * ESTATE), a closed session is freed once its FIFO drains, and the session limit. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include <cmocka.h>

#include "server/job.h"
#include "server/session.h"

static pthread_mutex_t g_lock = PTHREAD_MUTEX_INITIALIZER;
static int g_log[64], g_n;
static double g_start[8], g_end[8];

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec / 1e6;
}

static void record(int v)
{
    pthread_mutex_lock(&g_lock);
    g_log[g_n++] = v;
    pthread_mutex_unlock(&g_lock);
}

/* body = (intptr_t) index; work sleeps (12 - 2 * index) ms so that unordered runs would finish
 * out of order. */
static void sleepy_work(df_job *j)
{
    int i = (int)(intptr_t)j->body;
    g_start[i % 8] = now_ms();
    usleep((useconds_t)(1000 * (i < 6 ? 12 - 2 * i : 150)));
    record(i);
    g_end[i % 8] = now_ms();
}

static int g_done_rc[64];
static void record_done(df_job *j)
{
    int i = (int)(intptr_t)j->body;
    g_done_rc[i] = j->rc;
    if (!j->work && j->rc == DF_OK) record(100 + i); /* loop-only job */
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
    assert_non_null(m.V);
    assert_non_null(m.E);
    m.V[3] = 1;
    m.V[7] = 1;
    m.E[0] = 0, m.E[1] = 1, m.E[2] = 2;
    return m;
}

static void server_init(df_server *srv, uv_loop_t *loop)
{
    memset(srv, 0, sizeof *srv);
    df_config_defaults(&srv->cfg, NULL);
    srv->loop = loop;
    pthread_mutex_init(&srv->mailbox_lock, NULL);
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
    double t0 = now_ms();
    df_job_submit(job(&srv, a, 6, 1)); /* 150 ms each */
    df_job_submit(job(&srv, b, 7, 1));
    uv_run(&loop, UV_RUN_DEFAULT);
    double total = now_ms() - t0;
    assert_int_equal(g_n, 2);
    /* both ran at once: each started before the other ended */
    assert_true(g_start[6] < g_end[7] && g_start[7] < g_end[6]);
    assert_true(total < 290.0);
    df_session_destroy(a);
    df_session_destroy(b);
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
    assert_int_equal(uv_loop_close(&loop), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fifo_order_within_a_session),
        cmocka_unit_test(test_sessions_run_in_parallel),
        cmocka_unit_test(test_drop_queued_and_close),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
