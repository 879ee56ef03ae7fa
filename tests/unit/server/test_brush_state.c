/* Unit tests for server/session/brush_state.c: the session brush (defaults, apply validating
 * every masked field first and changing nothing on error, seq, the last changer) and the
 * BRUSH_CURSOR rate limiter: its decision as a pure function of times, a simulated timeline
 * (trailing edge: the last value is always delivered, events never closer than the interval),
 * and the limiter on a real libuv loop driven by a replaced clock (no wall-clock assertion). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>
#include <uv.h>

#include "proto/messages.h"
#include "server/session/brush_state.h"
#include "server/session/session.h"
#include "tests/unit/server/tiny_mesh.h"

static df_session *make_session(df_server *srv)
{
    memset(srv, 0, sizeof *srv);
    df_config_defaults(&srv->cfg, NULL);
    df_mesh m = tiny_mesh();
    df_session *s;
    df_error e;
    assert_int_equal(df_session_create(srv, &m, "b", &s, &e), DF_OK);
    return s;
}

static void test_defaults_are_the_wire_defaults(void **state)
{
    (void)state;
    static df_server srv;
    df_session *s = make_session(&srv);
    const df_brush_state *b = df_brush_state_get(s);
    df_msg_brush w;
    df_msg_brush_defaults(&w); /* DF_WIRE_BRUSH_DEFAULTS, as every client starts from */
    assert_int_equal(b->type, w.type);
    assert_int_equal(b->falloff, w.falloff);
    assert_int_equal(b->integrator, w.integrator);
    assert_int_equal(b->steps, w.steps);
    assert_int_equal(b->has_mirror, 0);
    assert_true(b->radius == w.radius && b->nu == w.nu && b->strength == w.strength &&
                b->ratio == w.ratio);
    assert_true(b->mirror_normal[0] == 1 && b->mirror_normal[1] == 0 &&
                b->mirror_normal[2] == 0);
    assert_int_equal(s->brush_seq, 0);
    assert_int_equal(s->brush_by.kind, DF_ORIGIN_NONE);
    df_session_destroy(s);
}

static void test_apply_sets_masked_fields_and_records_the_origin(void **state)
{
    (void)state;
    static df_server srv;
    df_session *s = make_session(&srv);
    df_brush_state v = *df_brush_state_get(s), before = v;
    v.radius = 0.25;
    v.nu = 0.45;
    v.falloff = 7; /* not in the mask: stays */
    df_origin who = {DF_ORIGIN_DEVICE, (1ull << 63) | 4, "PowerMate"};
    df_error e;
    assert_int_equal(df_brush_state_apply(s, DF_BS_RADIUS | DF_BS_NU, &v, &who, &e), DF_OK);
    const df_brush_state *b = df_brush_state_get(s);
    assert_true(b->radius == 0.25 && b->nu == 0.45);
    assert_int_equal(b->falloff, before.falloff);
    assert_int_equal(s->brush_seq, 1);
    assert_int_equal(srv.stats.brush_state_changes, 1);
    assert_int_equal(s->brush_by.kind, DF_ORIGIN_DEVICE);
    assert_true(s->brush_by.id == ((1ull << 63) | 4));
    assert_string_equal(s->brush_by.name, "PowerMate");
    assert_int_equal(atomic_load(&s->version), 0); /* no mesh change */
    /* INTEGRATOR carries steps, MIRROR the plane */
    v.integrator = DF_INTEG_RK4;
    v.steps = 9;
    v.has_mirror = 1;
    v.mirror_normal[0] = 0;
    v.mirror_normal[2] = 2;
    assert_int_equal(df_brush_state_apply(s, DF_BS_INTEGRATOR | DF_BS_MIRROR, &v, NULL, &e),
                     DF_OK);
    assert_int_equal(b->steps, 9);
    assert_int_equal(b->integrator, DF_INTEG_RK4);
    assert_true(b->has_mirror == 1 && b->mirror_normal[2] == 2);
    assert_int_equal(s->brush_seq, 2);
    assert_int_equal(s->brush_by.kind, DF_ORIGIN_NONE); /* who NULL */
    df_msg_brush_state m;
    df_brush_state_msg(s, DF_BS_MIRROR, &m);
    df_buf out;
    df_buf_init(&out);
    assert_int_equal(df_msg_brush_state_encode(&m, &out, &e), DF_OK); /* a valid event body */
    assert_true(m.seq == 2 && m.changed == DF_BS_MIRROR && m.v.steps == 9);
    df_buf_free(&out);
    df_session_destroy(s);
}

/* Field by field (padding bytes are not compared). */
static int same_state(const df_brush_state *a, const df_brush_state *b)
{
    return a->type == b->type && a->falloff == b->falloff && a->integrator == b->integrator &&
           a->has_mirror == b->has_mirror && a->steps == b->steps && a->radius == b->radius &&
           a->nu == b->nu && a->strength == b->strength && a->ratio == b->ratio &&
           !memcmp(a->mirror_point, b->mirror_point, sizeof a->mirror_point) &&
           !memcmp(a->mirror_normal, b->mirror_normal, sizeof a->mirror_normal);
}

static void test_a_refused_apply_changes_nothing(void **state)
{
    (void)state;
    static df_server srv;
    df_session *s = make_session(&srv);
    df_brush_state cur = *df_brush_state_get(s);
    df_brush_state v;
    df_error e;
#define REFUSED(mask_, stmt, needle)                                                       \
    do {                                                                                   \
        v = cur;                                                                           \
        v.radius = 0.5; /* a valid field beside the bad one */                             \
        stmt;                                                                              \
        assert_int_equal(df_brush_state_apply(s, (mask_) | DF_BS_RADIUS, &v, NULL, &e),    \
                         DF_EINVAL);                                                       \
        assert_non_null(strstr(e.msg, needle));                                            \
        assert_true(same_state(df_brush_state_get(s), &cur));                              \
        assert_int_equal(s->brush_seq, 0);                                                 \
        assert_int_equal(srv.stats.brush_state_changes, 0);                                \
    } while (0)
    REFUSED(DF_BS_NU, v.nu = 0.9, "nu 0.9");          /* the engine: [-1, 0.5] */
    REFUSED(DF_BS_NU, v.nu = NAN, "nu");
    REFUSED(DF_BS_STRENGTH, v.strength = -2e6, "strength");
    REFUSED(DF_BS_FALLOFF, v.falloff = 0, "falloff");
    REFUSED(DF_BS_RATIO, v.ratio = 1, "ratio");
    REFUSED(DF_BS_TYPE, v.type = 9, "type");
    REFUSED(DF_BS_INTEGRATOR, v.steps = 0, "steps");
    REFUSED(DF_BS_MIRROR, (v.has_mirror = 1, v.mirror_normal[0] = 0), "mirror_normal");
    REFUSED(DF_BS_MIRROR, v.mirror_point[1] = INFINITY, "mirror_point");
    REFUSED(0, v.radius = 2e6, "radi");                /* radius * ratio^k beyond 1e6 */
    REFUSED(0x100, (void)0, "0x100");                  /* a bit outside DF_BS_ALL */
    v = cur;
    assert_int_equal(df_brush_state_apply(s, 0, &v, NULL, &e), DF_EINVAL);
    df_origin bad_who = {7, 1, "x"};
    assert_int_equal(df_brush_state_apply(s, DF_BS_RADIUS, &v, &bad_who, &e), DF_EINVAL);
    assert_int_equal(s->brush_seq, 0);
    /* a field outside the mask may hold anything */
    v.nu = NAN;
    v.radius = 0.5;
    assert_int_equal(df_brush_state_apply(s, DF_BS_RADIUS, &v, NULL, &e), DF_OK);
    assert_true(df_brush_state_get(s)->nu == cur.nu);
    df_session_destroy(s);
}

/* ------------------------------------------------------------------ the rate limiter */
static void test_rate_decide(void **state)
{
    (void)state;
    uint64_t due = 0;
    const uint64_t I = 8333333; /* 120 Hz */
    assert_int_equal(df_cursor_rate_decide(5, 0, 0, I, 0, &due), 1);      /* first value */
    assert_int_equal(df_cursor_rate_decide(100, 99, 1, 0, 0, &due), 1);   /* unlimited */
    assert_int_equal(df_cursor_rate_decide(1000 + I - 1, 1000, 1, I, 0, &due), 0);
    assert_true(due == 1000 + I);                                         /* end of interval */
    assert_int_equal(df_cursor_rate_decide(1000 + I, 1000, 1, I, 0, &due), 1);
    assert_int_equal(df_cursor_rate_decide(1000 + 5 * I, 1000, 1, I, 0, &due), 1);
    due = 0; /* a value already held: the new one replaces it, the timer sends it */
    assert_int_equal(df_cursor_rate_decide(1000 + 5 * I, 1000, 1, I, 1, &due), 0);
    assert_true(due == 1000 + I);
    assert_int_equal(df_cursor_rate_decide(500, 1000, 1, I, 0, &due), 0); /* clock behind */
}

/* Replays a timeline of values through the limiter's rule (decide on arrival, a held value sent
 * at its due time: the timer) and checks: every event is at least `I` after the previous one,
 * the last value arrived is always delivered, and a value is held only within an interval. */
static void simulate(const uint64_t *t, int n, uint64_t I, int *sent_out)
{
    uint64_t last = 0, due = 0, sent_at[64];
    int sent = 0, held = -1, delivered[64], nd = 0;
    for (int i = 0; i <= n; i++) {
        uint64_t now = i < n ? t[i] : UINT64_MAX;
        if (held >= 0 && due <= now) { /* the timer fires first */
            sent_at[sent++] = due;
            delivered[nd++] = held;
            last = due;
            held = -1;
        }
        if (i == n)
            break;
        if (df_cursor_rate_decide(now, last, sent > 0, I, held >= 0, &due)) {
            sent_at[sent++] = now;
            delivered[nd++] = i;
            last = now;
        } else {
            assert_true(due > now && due - now <= I);
            held = i; /* replaces any held value */
        }
    }
    for (int k = 1; k < sent; k++)
        assert_true(sent_at[k] - sent_at[k - 1] >= I);
    assert_int_equal(delivered[nd - 1], n - 1); /* the latest value is never lost */
    for (int k = 1; k < nd; k++)
        assert_true(delivered[k] > delivered[k - 1]); /* in order, no duplicates */
    *sent_out = sent;
}

static void test_rate_timeline(void **state)
{
    (void)state;
    const uint64_t I = 10;
    int sent;
    const uint64_t burst[] = {0, 1, 2, 3, 4, 5}; /* one interval: first now, last at t=10 */
    simulate(burst, 6, I, &sent);
    assert_int_equal(sent, 2);
    const uint64_t sparse[] = {0, 20, 45, 100}; /* all farther apart than I: all sent at once */
    simulate(sparse, 4, I, &sent);
    assert_int_equal(sent, 4);
    uint64_t steady[40]; /* a 1 kHz stream through a 10-tick limit: one per interval */
    for (int i = 0; i < 40; i++)
        steady[i] = (uint64_t)i;
    simulate(steady, 40, I, &sent);
    assert_int_equal(sent, 5); /* t = 0, 10, 20, 30 and the trailing 39 at 40 */
}

static uint64_t g_now;
static uint64_t fake_clock(void) { return g_now; }

static void test_cursor_publish_on_a_loop(void **state)
{
    (void)state;
    static df_server srv;
    df_session *s = make_session(&srv);
    uv_loop_t loop;
    assert_int_equal(uv_loop_init(&loop), 0);
    srv.loop = &loop;
    srv.cfg.cursor_hz = 100; /* 10 ms */
    df_brush_cursor_clock = fake_clock;
    df_origin dev = {DF_ORIGIN_DEVICE, (1ull << 63) | 1, "SpaceNavigator"};
    df_origin other = {DF_ORIGIN_CLIENT, 9, "viewer"};
    double c[3] = {0.1, 0.2, 0.3};
    g_now = 1000000000ull;
    df_brush_cursor_publish(s, &dev, c, 0.5, DF_CURSOR_IN_RANGE);      /* sent */
    assert_int_equal(srv.stats.brush_cursor_events, 1);
    g_now += 1000000;
    c[0] = 0.4;
    df_brush_cursor_publish(s, &dev, c, 0.5, DF_CURSOR_IN_RANGE);      /* held */
    g_now += 1000000;
    c[0] = 0.5;
    df_brush_cursor_publish(s, &dev, c, 0.5, DF_CURSOR_IN_RANGE);      /* replaces it */
    df_brush_cursor_publish(s, &other, c, 0.5, 0);                     /* its own origin */
    assert_int_equal(srv.stats.brush_cursor_events, 2);
    double bad[3] = {NAN, 0, 0};
    df_brush_cursor_publish(s, &dev, bad, 0.5, 0);                     /* dropped */
    df_brush_cursor_publish(s, &dev, c, -1, 0);                        /* dropped */
    assert_int_equal(srv.stats.brush_cursor_events, 2);
    g_now += 8000000; /* the interval is over when the timer fires: the held value goes */
    uv_run(&loop, UV_RUN_DEFAULT);                                     /* returns once sent */
    assert_int_equal(srv.stats.brush_cursor_events, 3);
    srv.cfg.cursor_hz = 0; /* unlimited */
    df_brush_cursor_publish(s, &dev, c, 0.5, 0);
    df_brush_cursor_publish(s, &dev, c, 0.5, 0);
    assert_int_equal(srv.stats.brush_cursor_events, 5);
    df_session_destroy(s);
    uv_run(&loop, UV_RUN_DEFAULT); /* the limiter's timer closes */
    assert_int_equal(uv_loop_close(&loop), 0);
    df_brush_cursor_clock = uv_hrtime;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_defaults_are_the_wire_defaults),
        cmocka_unit_test(test_apply_sets_masked_fields_and_records_the_origin),
        cmocka_unit_test(test_a_refused_apply_changes_nothing),
        cmocka_unit_test(test_rate_decide),
        cmocka_unit_test(test_rate_timeline),
        cmocka_unit_test(test_cursor_publish_on_a_loop),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
