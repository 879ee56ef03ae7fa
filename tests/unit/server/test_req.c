/* Unit tests for server/net/req.c: a request is answered exactly once. A second answer is counted in
 * stats.requests_double_answer and sends nothing (release behaviour, df_req_strict = 0), or
 * aborts (df_req_strict = 1, the default of debug builds); df_job_request takes the request
 * over (the original is marked answered, the job's copy answers it) and fails with ENOTFOUND
 * for a missing session without answering anything. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <signal.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>
#include <cmocka.h>

#include "server/exec/job.h"
#include "server/net/req.h"

static void server_init(df_server *srv)
{
    memset(srv, 0, sizeof *srv);
    df_config_defaults(&srv->cfg, NULL);
}

static void test_answered_once_counts_the_second(void **state)
{
    (void)state;
    df_server srv;
    server_init(&srv);
    int strict = df_req_strict;
    df_req_strict = 0;
    df_req r = {.srv = &srv, .type = DF_MSG_PING, .id = 7};
    df_error e;
    df_error_set(&e, DF_EINVAL, "bad");
    assert_int_equal(df_req_claim(&r), 1);
    assert_int_equal(r.answered, 1);
    assert_int_equal(srv.stats.requests_double_answer, 0);
    assert_int_equal(df_req_fail(&r, &e), DF_EINVAL); /* second answer: counted, not sent */
    assert_int_equal(srv.stats.requests_double_answer, 1);
    df_req_ack(&r, 1, 2);
    assert_int_equal(srv.stats.requests_double_answer, 2);
    df_req r2 = {.srv = &srv, .type = DF_MSG_PING, .id = 8};
    assert_int_equal(df_req_fail(&r2, &e), DF_EINVAL); /* first answer: fine */
    assert_int_equal(srv.stats.requests_double_answer, 2);
    df_req_strict = strict;
}

static void test_double_answer_aborts_when_strict(void **state)
{
    (void)state;
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        df_server srv;
        server_init(&srv);
        df_req_strict = 1;
        df_req r = {.srv = &srv, .type = DF_MSG_PING, .id = 7};
        df_req_claim(&r);
        df_req_claim(&r); /* aborts */
        _exit(0);
    }
    int st = 0;
    assert_int_equal(waitpid(pid, &st, 0), pid);
    assert_true(WIFSIGNALED(st));
    assert_int_equal(WTERMSIG(st), SIGABRT);
}

static void noop_done(df_job *j) { (void)j; }

static int g_released;
static void count_release(df_server *srv, void *body)
{
    (void)srv;
    (void)body;
    g_released++;
}

/* A decoder naming session 42 (there is none). */
static int decode_42(const df_req *r, const uint8_t *p, void *body, uint64_t *sid, df_error *err)
{
    (void)r, (void)p, (void)body, (void)err;
    *sid = 42;
    return DF_OK;
}

static void test_job_takes_the_request_over(void **state)
{
    (void)state;
    df_server srv;
    server_init(&srv);
    static const df_job_kind kind = {.body_size = 16, .decode = decode_42,
                                     .release = count_release, .done = noop_done};
    df_req r = {.srv = &srv, .type = DF_MSG_BRUSH_END, .id = 9, .len = 8};
    df_error e;
    assert_int_equal(df_job_request(&r, NULL, &kind, &e), DF_ENOTFOUND); /* no session 42 */
    assert_int_equal(e.code, DF_ENOTFOUND);
    assert_int_equal(g_released, 1);  /* the decoded body was released */
    assert_int_equal(r.answered, 0); /* the dispatcher answers it */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_answered_once_counts_the_second),
        cmocka_unit_test(test_double_answer_aborts_when_strict),
        cmocka_unit_test(test_job_takes_the_request_over),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
