/* Unit tests of the undo history with RECIPE steps (server/session/history.h), against a
 * straightforward model that keeps every state in full. The recipe is a fake, deterministic
 * replay (a non-invertible map of a vertex range) with a declared cost that a fake clock
 * advances by, so checkpoint placement is exact. Covered: checkpoint placement by cost and the
 * replay bound of an undo, undo/redo across checkpoints bit-exact, truncation, the depth cap and
 * the byte budget dropping the oldest steps, a replay mismatch refused with nothing changed then
 * repaired, a recipe that does not reproduce its state falling back to XOR, stale plans. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "server/session/history.h"

#define NV 40
#define N (3 * NV)

typedef struct fake {
    uint32_t v0, v1;   /* vertex range moved */
    double a;          /* amount */
    uint64_t cost;     /* "ns" the fake clock advances during a replay */
} fake;

static uint64_t g_now;
static int g_flip;     /* 1: the replay perturbs its result (a replay that no longer matches) */
static int g_calls;

static uint64_t fake_clock(void) { return g_now; }

static void fake_apply(const fake *f, const double *from, double *to)
{
    memcpy(to, from, N * sizeof *to);
    for (size_t i = 3 * (size_t)f->v0; i < 3 * (size_t)f->v1; i++)
        to[i] = from[i] + f->a * sin(3.0 * from[i] + 1.0);
}

static int g_scratch_allocs; /* scratch buffers the fake allocated (reused within a plan) */

static int fake_replay(void *ctx, const uint8_t *blob, size_t len, const double *from,
                       double *to, void **scratch, df_error *err)
{
    (void)ctx;
    if (!*scratch) { /* the history frees it after the plan */
        if (!(*scratch = malloc(N * sizeof(double))))
            return df_error_set(err, DF_ENOMEM, "fake recipe: out of memory");
        g_scratch_allocs++;
    }
    if (!blob) return DF_OK; /* prepare only */
    if (len != sizeof(fake)) return df_error_set(err, DF_EFORMAT, "fake recipe: bad length");
    fake f;
    memcpy(&f, blob, sizeof f);
    fake_apply(&f, from, *scratch);
    memcpy(to, *scratch, N * sizeof *to);
    if (g_flip) to[3 * f.v0] += 1e-9;
    g_now += f.cost;
    g_calls++;
    return DF_OK;
}

/* The model: every state in full, as a list; cur its index. */
typedef struct model {
    double s[200][N];
    int count, cur; /* states count + 1 */
} model;

static void model_init(model *m, const double *s0)
{
    memcpy(m->s[0], s0, sizeof m->s[0]);
    m->count = 0;
    m->cur = 0;
}

/* Commits s in the model; the history dropped `dropped` oldest steps doing the same (with
 * several checkpoints a whole segment goes at once: at least what the depth cap needs). */
static void model_commit(model *m, const double *s, int max_states, int dropped)
{
    if (memcmp(s, m->s[m->cur], sizeof m->s[0]) == 0) return; /* no change */
    m->cur++;
    memcpy(m->s[m->cur], s, sizeof m->s[0]);
    m->count = m->cur;
    assert_true(m->count - dropped <= max_states - 1);
    assert_true(dropped == 0 || m->count > max_states - 1);
    memmove(m->s[0], m->s[dropped], (size_t)(m->count - dropped + 1) * sizeof m->s[0]);
    m->count -= dropped;
    m->cur -= dropped;
}

static void init(df_history *h, model *m, int max_states, uint64_t budget)
{
    double s0[N];
    for (int i = 0; i < N; i++) s0[i] = 0.01 * i - 0.3;
    df_error e;
    assert_int_equal(df_history_init(h, s0, N, max_states, &e), DF_OK);
    df_history_set_replay(h, fake_replay, NULL, budget);
    h->clock_ns = fake_clock;
    model_init(m, s0);
}

/* Commits a fake recipe from the current state (its result computed here, independently). */
static void commit_recipe(df_history *h, model *m, const fake *f)
{
    double next[N];
    fake_apply(f, h->state, next);
    df_error e;
    uint64_t d0 = h->dropped;
    assert_int_equal(df_history_commit_recipe(h, next, (const uint8_t *)f, sizeof *f, &e), DF_OK);
    model_commit(m, next, h->max_states, (int)(h->dropped - d0));
}

static void commit_xor(df_history *h, model *m, double shift)
{
    double next[N];
    memcpy(next, h->state, sizeof next);
    next[5] += shift;
    next[6] -= shift;
    df_error e;
    uint64_t d0 = h->dropped;
    assert_int_equal(df_history_commit(h, next, &e), DF_OK);
    model_commit(m, next, h->max_states, (int)(h->dropped - d0));
}

static void check(const df_history *h, const model *m)
{
    assert_int_equal(df_history_can_undo(h), m->cur);
    assert_int_equal(df_history_can_redo(h), m->count - m->cur);
    assert_memory_equal(h->state, m->s[m->cur], sizeof m->s[0]);
}

static void undo(df_history *h, model *m)
{
    df_error e;
    const double *r = df_history_undo(h, &e);
    if (!r) print_error("undo at %d: %s\n", h->cur, e.msg);
    assert_non_null(r);
    m->cur--;
    check(h, m);
}

static void redo(df_history *h, model *m)
{
    df_error e;
    assert_non_null(df_history_redo(h, &e));
    m->cur++;
    check(h, m);
}

static fake mk(int k, uint64_t cost)
{
    fake f = {(uint32_t)(k * 7) % (NV - 10), (uint32_t)(k * 7) % (NV - 10) + 10,
              0.01 + 0.001 * k, cost};
    return f;
}

static void test_checkpoints_by_cost_and_undo_bound(void **state)
{
    (void)state;
    static model m;
    df_history h;
    init(&h, &m, 64, 10);
    for (int k = 0; k < 12; k++) {
        fake f = mk(k, 4);
        commit_recipe(&h, &m, &f);
        check(&h, &m);
    }
    /* first checkpoint at state 0; then one where the cost since the newest would pass 10:
     * 4 + 4 + 4 > 10 -> at states 3, 6, 9, 12 */
    assert_int_equal(h.nck, 5);
    for (int i = 0; i < 5; i++) assert_int_equal(h.ck[i], 3 * i);
    assert_int_equal(df_history_steps_of(&h, DF_HISTORY_RECIPE), 12);
    assert_int_equal(df_history_steps_of(&h, DF_HISTORY_XOR), 0);
    /* undo all the way, each undo replaying at most 2 steps (the budget: 10 / 4) */
    while (m.cur > 0) {
        int calls = g_calls, allocs = g_scratch_allocs;
        undo(&h, &m);
        assert_true(g_calls - calls <= 2);
        assert_true(g_scratch_allocs - allocs <= 1); /* one scratch per plan, reused */
    }
    assert_int_equal(h.nck, 1); /* the anchor came down with the undos */
    /* redo all, one replay each, checkpoints taken again */
    while (m.cur < m.count) {
        int calls = g_calls;
        redo(&h, &m);
        assert_int_equal(g_calls - calls, 1);
    }
    assert_int_equal(h.nck, 5);
    assert_non_null(h.anchor); /* no reference: the anchor is a full copy */
    assert_null(h.apack);
    assert_true(df_history_undo_bytes(&h) < df_history_bytes(&h));
    assert_int_equal(df_history_bytes(&h) - df_history_undo_bytes(&h), N * sizeof(double));
    df_history_free(&h);
}

static void test_mixed_random_against_model(void **state)
{
    (void)state;
    static model m;
    uint64_t seed = 7;
    for (int budget = 0; budget <= 20; budget += 10) {
        df_history h;
        init(&h, &m, 9, (uint64_t)budget);
        for (int it = 0; it < 400; it++) {
            seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
            int op = (int)((seed >> 33) % 10);
            if (op < 4) {
                fake f = mk(it, 1 + (seed >> 40) % 7);
                commit_recipe(&h, &m, &f);
            } else if (op < 5) {
                commit_xor(&h, &m, 0.001 * (it + 1));
            } else if (op < 8) {
                if (m.cur > 0) undo(&h, &m);
            } else if (m.cur < m.count) {
                redo(&h, &m);
            }
            check(&h, &m);
            assert_true(h.count <= 8);
            for (int c = 1; c < h.nck; c++) assert_true(h.ck[c - 1] < h.ck[c]);
            assert_true(h.nck <= 1 || h.ck[h.nck - 1] <= h.cur);
            assert_int_equal(h.nck > 0, df_history_steps_of(&h, DF_HISTORY_RECIPE) > 0);
            for (int k = 0; k < h.count; k++) /* every RECIPE step at or above ck[0] */
                assert_true(h.steps[k].kind != DF_HISTORY_RECIPE || k >= h.ck[0]);
        }
        assert_int_equal(h.mismatches, 0);
        df_history_free(&h);
    }
}

static void test_byte_budget_drops_oldest(void **state)
{
    (void)state;
    static model m;
    df_history h;
    init(&h, &m, 64, 0); /* a checkpoint after every recipe: a link per step */
    for (int k = 0; k < 10; k++) {
        fake f = mk(k, 3);
        commit_recipe(&h, &m, &f);
        commit_xor(&h, &m, 0.01 * (k + 1));
    }
    check(&h, &m);
    size_t full = df_history_bytes(&h);
    size_t cap = N * sizeof(double) + (full - N * sizeof(double)) / 2;
    int dropped = df_history_set_max_bytes(&h, cap);
    assert_true(dropped > 0);
    assert_true(df_history_bytes(&h) <= cap);
    assert_int_equal(h.dropped, (uint64_t)dropped);
    /* the model keeps the newest states */
    memmove(m.s[0], m.s[dropped], (size_t)(m.count - dropped + 1) * sizeof m.s[0]);
    m.count -= dropped;
    m.cur -= dropped;
    check(&h, &m);
    while (m.cur > 0) undo(&h, &m);
    while (m.cur < m.count) redo(&h, &m);
    /* a budget below one step drops them all; the current state stays */
    df_history_set_max_bytes(&h, 1);
    assert_int_equal(df_history_can_undo(&h), 0);
    assert_int_equal(h.nck, 0);
    assert_int_equal(df_history_bytes(&h), N * sizeof(double));
    assert_memory_equal(h.state, m.s[m.cur], sizeof m.s[0]);
    df_history_free(&h);
}

static void test_truncation_drops_the_redo_tail(void **state)
{
    (void)state;
    static model m;
    df_history h;
    init(&h, &m, 64, 8);
    for (int k = 0; k < 8; k++) {
        fake f = mk(k, 3);
        commit_recipe(&h, &m, &f);
    }
    for (int k = 0; k < 5; k++) undo(&h, &m);
    commit_xor(&h, &m, 0.5);
    check(&h, &m);
    assert_int_equal(df_history_can_redo(&h), 0);
    for (int k = 0; k < 3; k++) undo(&h, &m);
    fake f = mk(99, 3);
    commit_recipe(&h, &m, &f); /* a recipe after undos to state 0 */
    check(&h, &m);
    while (m.cur > 0) undo(&h, &m);
    while (m.cur < m.count) redo(&h, &m);
    /* committing the current state again adds nothing and keeps the redo tail */
    undo(&h, &m);
    df_error e;
    assert_int_equal(df_history_commit(&h, m.s[m.cur], &e), DF_OK);
    check(&h, &m);
    df_history_free(&h);
}

static void test_mismatch_refused_and_repaired(void **state)
{
    (void)state;
    static model m;
    df_history h;
    init(&h, &m, 64, 1000);
    for (int k = 0; k < 6; k++) {
        fake f = mk(k, 3);
        commit_recipe(&h, &m, &f);
    }
    undo(&h, &m);
    undo(&h, &m); /* cur 4, two to redo */
    double before[N], out[N];
    memcpy(before, h.state, sizeof before);
    size_t bytes = df_history_bytes(&h);
    df_history_plan p;
    df_error e;
    g_flip = 1; /* every replay now differs from what was recorded */
    assert_int_equal(df_history_plan_move(&h, -1, out, &p, &e), DF_EINTERNAL);
    assert_non_null(strstr(e.msg, "does not reproduce"));
    assert_true(p.mismatch && !p.valid);
    assert_int_equal(df_history_install(&h, &p, out, &e), DF_ESTATE); /* not installable */
    assert_memory_equal(h.state, before, sizeof before); /* nothing changed */
    assert_int_equal(df_history_bytes(&h), bytes);
    check(&h, &m);
    /* the repair drops everything below the current state (no checkpoint above the bad step) */
    assert_int_equal(df_history_repair(&h, &p), 4);
    assert_int_equal(h.mismatches, 1);
    assert_int_equal(df_history_can_undo(&h), 0);
    assert_memory_equal(h.state, before, sizeof before);
    /* redo: refused too, the redo tail dropped */
    assert_int_equal(df_history_plan_move(&h, 1, out, &p, &e), DF_EINTERNAL);
    assert_int_equal(df_history_repair(&h, &p), 2);
    assert_int_equal(df_history_can_redo(&h), 0);
    assert_int_equal(h.mismatches, 2);
    assert_memory_equal(h.state, before, sizeof before);
    df_history_plan_free(&p);
    /* a commit whose recipe does not reproduce `pos` becomes an XOR step */
    fake f = mk(50, 3);
    double next[N];
    g_flip = 0;
    fake_apply(&f, h.state, next);
    g_flip = 1;
    assert_int_equal(df_history_plan_commit(&h, next, (const uint8_t *)&f, sizeof f, &p, &e),
                     DF_OK);
    assert_int_equal(p.fallback, 2);
    assert_int_equal(p.step.kind, DF_HISTORY_XOR);
    assert_int_equal(df_history_install(&h, &p, next, &e), DF_OK);
    g_flip = 0;
    assert_int_equal(h.mismatches, 3);
    assert_int_equal(df_history_steps_of(&h, DF_HISTORY_XOR), 1);
    assert_non_null(df_history_undo(&h, &e));
    assert_memory_equal(h.state, before, sizeof before);
    df_history_free(&h);
}

static void test_stale_plan_and_bad_arguments(void **state)
{
    (void)state;
    static model m;
    df_history h;
    init(&h, &m, 64, 100);
    fake f = mk(1, 3);
    commit_recipe(&h, &m, &f);
    double out[N];
    df_history_plan p;
    df_error e;
    assert_int_equal(df_history_plan_move(&h, -1, out, &p, &e), DF_OK);
    commit_xor(&h, &m, 0.25); /* the history changed since the plan */
    assert_int_equal(df_history_install(&h, &p, out, &e), DF_ESTATE);
    check(&h, &m);
    df_history_plan_free(&p);
    assert_int_equal(df_history_plan_move(&h, 2, out, &p, &e), DF_EINVAL);
    assert_int_equal(df_history_plan_move(&h, 1, out, &p, &e), DF_ESTATE);
    assert_int_equal(df_history_plan_commit(&h, NULL, NULL, 0, &p, &e), DF_EINVAL);
    /* a blob the replay rejects: an XOR step, not an error */
    double next[N];
    memcpy(next, h.state, sizeof next);
    next[0] += 1;
    uint8_t junk[3] = {1, 2, 3};
    assert_int_equal(df_history_plan_commit(&h, next, junk, sizeof junk, &p, &e), DF_OK);
    assert_int_equal(p.fallback, 1);
    assert_int_equal(df_history_install(&h, &p, next, &e), DF_OK);
    model_commit(&m, next, h.max_states, 0);
    check(&h, &m);
    while (m.cur > 0) undo(&h, &m);
    df_history_free(&h);
}

/* The anchor packed against a reference (history.h): the same random mix of commits, undos,
 * redos and drops as above, bit-exact against the model, with the anchor held packed. */
static void test_reference_packed_against_model(void **state)
{
    (void)state;
    static model m;
    static double ref[N];
    uint64_t seed = 11;
    for (int budget = 0; budget <= 20; budget += 10) {
        df_history h;
        init(&h, &m, 9, (uint64_t)budget);
        memcpy(ref, m.s[0], sizeof ref); /* the "rest shape": alive and unchanged */
        df_error e;
        assert_int_equal(df_history_set_reference(&h, ref, &e), DF_OK);
        int packed = 0;
        for (int it = 0; it < 400; it++) {
            seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
            int op = (int)((seed >> 33) % 10);
            if (op < 4) {
                fake f = mk(it, 1 + (seed >> 40) % 7);
                commit_recipe(&h, &m, &f);
            } else if (op < 5) {
                commit_xor(&h, &m, 0.001 * (it + 1));
            } else if (op < 8) {
                if (m.cur > 0) undo(&h, &m);
            } else if (m.cur < m.count) {
                redo(&h, &m);
            }
            check(&h, &m);
            assert_true(h.count <= 8);
            assert_true(!h.anchor || !h.apack);                 /* one form at a time */
            assert_int_equal(h.nck > 0, h.anchor || h.apack);
            packed += h.apack != NULL;
            size_t a, l, st;
            df_history_parts(&h, &a, &l, &st);
            assert_int_equal(a + l + st, df_history_undo_bytes(&h));
            if (h.apack) assert_int_equal(a, h.apack_len);
        }
        assert_true(packed > 100); /* mostly packed (a full copy only after a drop, briefly) */
        assert_int_equal(h.mismatches, 0);
        /* every state still reachable, the way down and up again */
        while (m.cur > 0) undo(&h, &m);
        while (m.cur < m.count) redo(&h, &m);
        df_history_free(&h);
    }
}

/* A packed anchor is a fraction of a full copy when the states stay near the reference, and
 * switching the reference off turns it back into a full copy with nothing else changed. */
static void test_reference_bytes_and_switch(void **state)
{
    (void)state;
    static model m;
    static double ref[N];
    df_history h;
    init(&h, &m, 64, 5);
    memcpy(ref, m.s[0], sizeof ref);
    df_error e;
    assert_int_equal(df_history_set_reference(&h, ref, &e), DF_OK);
    for (int k = 0; k < 12; k++) {
        fake f = mk(k, 3);
        commit_recipe(&h, &m, &f);
    }
    assert_true(h.nck >= 3);
    assert_non_null(h.apack);
    assert_null(h.anchor);
    size_t a;
    df_history_parts(&h, &a, NULL, NULL);
    assert_true(a < N * sizeof(double)); /* smaller than a full copy */
    assert_int_equal(df_history_set_reference(&h, NULL, &e), DF_OK);
    assert_null(h.apack);
    assert_non_null(h.anchor);
    assert_memory_equal(h.anchor, m.s[h.ck[h.nck - 1]], sizeof m.s[0]);
    df_history_parts(&h, &a, NULL, NULL);
    assert_int_equal(a, N * sizeof(double));
    while (m.cur > 0) undo(&h, &m);
    /* the reference back: the next plan packs the full-copy anchor (repack) */
    assert_int_equal(df_history_set_reference(&h, ref, &e), DF_OK);
    while (m.cur < m.count) redo(&h, &m);
    assert_non_null(h.apack);
    assert_null(h.anchor);
    /* a reset forgets everything (no allocation) and keeps the counters */
    uint64_t replays = h.replays;
    df_history_reset(&h, m.s[2]);
    assert_int_equal(df_history_can_undo(&h), 0);
    assert_int_equal(df_history_can_redo(&h), 0);
    assert_int_equal(h.nck, 0);
    assert_int_equal(df_history_bytes(&h), N * sizeof(double));
    assert_memory_equal(h.state, m.s[2], sizeof m.s[0]);
    assert_int_equal(h.replays, replays);
    df_history_free(&h);
}

/* A packed anchor that no longer decodes to the state it recorded (corrupt bytes, or the
 * reference changed under it) is detected: the undo is refused with nothing changed, the
 * repair drops what became unreachable; a commit due for a checkpoint drops it at install. */
static void test_corrupt_packed_anchor_detected(void **state)
{
    (void)state;
    static model m;
    static double ref[N];
    for (int how = 0; how < 2; how++) {
        df_history h;
        init(&h, &m, 64, 5);
        memcpy(ref, m.s[0], sizeof ref);
        df_error e;
        assert_int_equal(df_history_set_reference(&h, ref, &e), DF_OK);
        for (int k = 0; k < 9; k++) {
            fake f = mk(k, 3); /* 3 + 3 > 5: a checkpoint every second step */
            commit_recipe(&h, &m, &f);
        }
        undo(&h, &m); /* below the anchor: the anchor moved down, packed again */
        assert_non_null(h.apack);
        assert_true(h.steps[h.cur - 1].kind == DF_HISTORY_RECIPE);
        if (how == 0) h.apack[h.apack_len / 2] ^= 0x5a; /* corrupt bytes */
        else ref[7] += 1e-3;                            /* the reference changed */
        double before[N], out[N];
        memcpy(before, h.state, sizeof before);
        size_t bytes = df_history_bytes(&h);
        int nck = h.nck, redo_n = df_history_can_redo(&h);
        df_history_plan p;
        assert_int_equal(df_history_plan_move(&h, -1, out, &p, &e), DF_EINTERNAL);
        assert_non_null(strstr(e.msg, "checkpoint"));
        assert_true(p.mismatch && !p.valid);
        assert_int_equal(p.bad_step, -1);
        assert_int_equal(df_history_install(&h, &p, out, &e), DF_ESTATE);
        assert_memory_equal(h.state, before, sizeof before); /* nothing changed */
        assert_int_equal(df_history_bytes(&h), bytes);
        assert_int_equal(h.nck, nck);
        /* the repair: every step below the current state is unreachable and dropped */
        int dropped = df_history_repair(&h, &p);
        assert_int_equal(dropped, m.cur);
        assert_int_equal(h.mismatches, 1);
        assert_int_equal(df_history_can_undo(&h), 0);
        assert_int_equal(df_history_can_redo(&h), redo_n);
        memmove(m.s[0], m.s[m.cur], (size_t)(m.count - m.cur + 1) * sizeof m.s[0]);
        m.count -= m.cur;
        m.cur = 0;
        check(&h, &m);
        df_history_plan_free(&p);
        if (how == 1) memcpy(ref, m.s[0], sizeof ref); /* the caller sets it right ... */
        if (how == 1) assert_int_equal(df_history_set_reference(&h, ref, &e), DF_OK);
        while (m.cur < m.count) redo(&h, &m); /* the redo tail still replays */
        while (m.cur > 0) undo(&h, &m);
        while (m.cur < m.count) redo(&h, &m);
        /* a commit due for a checkpoint finds the anchor corrupt: committed, and the install
         * drops every step below the new state (nothing below it is reachable) */
        for (int k = 20; k < 23 || h.ck[h.nck - 1] == h.cur; k++) { /* one step past it */
            fake f = mk(k, 3);
            commit_recipe(&h, &m, &f);
        }
        assert_non_null(h.apack);
        h.apack[h.apack_len / 2] ^= 0x5a;
        fake f = mk(30, 3);
        double next[N];
        fake_apply(&f, h.state, next);
        assert_int_equal(df_history_plan_commit(&h, next, (const uint8_t *)&f, sizeof f, &p, &e),
                         DF_OK);
        assert_true(p.bad_anchor && !p.new_ck);
        assert_int_equal(df_history_install(&h, &p, next, &e), DF_OK);
        assert_int_equal(h.mismatches, 2);
        assert_int_equal(df_history_can_undo(&h), 0);
        assert_memory_equal(h.state, next, sizeof next);
        model_init(&m, next);
        fake g = mk(31, 3);
        commit_recipe(&h, &m, &g); /* and it goes on from there */
        undo(&h, &m);
        redo(&h, &m);
        df_history_free(&h);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_checkpoints_by_cost_and_undo_bound),
        cmocka_unit_test(test_mixed_random_against_model),
        cmocka_unit_test(test_byte_budget_drops_oldest),
        cmocka_unit_test(test_truncation_drops_the_redo_tail),
        cmocka_unit_test(test_mismatch_refused_and_repaired),
        cmocka_unit_test(test_stale_plan_and_bad_arguments),
        cmocka_unit_test(test_reference_packed_against_model),
        cmocka_unit_test(test_reference_bytes_and_switch),
        cmocka_unit_test(test_corrupt_packed_anchor_detected),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
