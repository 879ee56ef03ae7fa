/* Unit tests for server/session/commit.c: df_session_commit applies a change record in its fixed order
 * (state, history, accounting, hook, broadcast, answer): at the hook the new version, positions
 * and undo step are in place and nothing is broadcast yet; the request is answered once, after.
 * A failed compute changes no state, still records its timings, skips the hook and answers the
 * error. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "tests/unit/server/tiny_mesh.h"
#include "server/session/commit.h"
#include "server/exec/job.h"
#include "server/session/session.h"

static void server_init(df_server *srv)
{
    memset(srv, 0, sizeof *srv);
    df_config_defaults(&srv->cfg, NULL);
}

/* What the hook saw (step 4). */
static struct {
    int calls;
    uint64_t version;
    const double *cur;
    int can_undo;
    uint64_t versions_broadcast;
    int answered;
} g_hook;
static df_req *g_req;

static void hook(void *arg, const df_session *s, const df_change *c)
{
    (void)c;
    df_server *srv = arg;
    g_hook.calls++;
    g_hook.version = atomic_load(&s->version);
    g_hook.cur = s->cur;
    g_hook.can_undo = df_history_can_undo(&s->hist);
    g_hook.versions_broadcast = srv->stats.versions;
    g_hook.answered = g_req->answered;
}

static void test_commit_order(void **state)
{
    (void)state;
    static df_server srv;
    server_init(&srv);
    srv.commit_hook = hook;
    srv.commit_hook_arg = &srv;
    df_mesh m = tiny_mesh();
    df_session *s;
    df_error e;
    assert_int_equal(df_session_create(&srv, &m, "c", &s, &e), DF_OK);
    assert_int_equal(df_stream_scratch(s, &e), DF_OK);
    uint64_t v0 = atomic_load(&s->version);

    /* the compute: every vertex moved by +0.5 in x, encoded without touching the session */
    double *pos = s->scratch_pos;
    for (int i = 0; i < 9; i++) pos[i] = s->cur[i] + (i % 3 == 0 ? 0.5 : 0.0);
    df_req r = {.srv = &srv, .type = DF_MSG_BRUSH_UPDATE, .id = 5};
    g_req = &r;
    df_change c;
    df_change_init(&c, &r, &e);
    assert_int_equal(df_stream_encode(s, NULL, 0, pos, DF_CHANGE_BRUSH, NULL, 0, s->scratch_u,
                                      &c.frames, NULL, &e),
                     DF_OK);
    assert_int_equal(atomic_load(&s->version), v0); /* pure: nothing published yet */
    assert_true(c.frames.n >= 1);
    c.pos = pos;
    c.uf = s->scratch_u;
    c.version = v0 + 1;
    c.hist = DF_HIST_COMMIT;
    c.brush_ms = 1.5;
    assert_false(df_history_can_undo(&s->hist));

    memset(&g_hook, 0, sizeof g_hook);
    assert_int_equal(df_session_commit(s, &c), DF_OK);
    assert_int_equal(g_hook.calls, 1);
    assert_int_equal(g_hook.version, v0 + 1);      /* 1. state before the hook */
    assert_ptr_equal(g_hook.cur, pos);
    assert_true(g_hook.can_undo);                  /* 2. history before the hook */
    assert_int_equal(g_hook.versions_broadcast, 0); /* 5. broadcast after the hook */
    assert_int_equal(g_hook.answered, 0);          /* 6. answer last */
    assert_int_equal(srv.stats.versions, 1);
    assert_int_equal(r.answered, 1);
    assert_ptr_equal(s->cur, pos);
    assert_true(s->brush_last_ms == 1.5);
    assert_true(s->uf[0] == 0.5f);
    assert_int_equal(srv.stats.requests_double_answer, 0);
    df_change_clear(&srv, &c);

    /* a failed compute: no state, no hook, timings kept, the error answered */
    df_req r2 = {.srv = &srv, .type = DF_MSG_BRUSH_UPDATE, .id = 6};
    g_req = &r2;
    df_change_init(&c, &r2, &e);
    df_error_set(&e, DF_EINVAL, "refused");
    c.rc = DF_EINVAL;
    c.brush_ms = 2.5;
    c.hist = DF_HIST_COMMIT;
    c.version = v0 + 2;
    assert_int_equal(df_session_commit(s, &c), DF_EINVAL);
    assert_int_equal(g_hook.calls, 1);
    assert_int_equal(atomic_load(&s->version), v0 + 1);
    assert_true(s->brush_last_ms == 2.5);
    assert_int_equal(r2.answered, 1);
    assert_int_equal(srv.stats.versions, 1);
    df_change_clear(&srv, &c);
    df_session_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_commit_order),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
