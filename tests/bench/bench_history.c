/* bench_history — memory and undo latency of the in-memory undo history with stroke recipes
 * (server/session/history.h; `make bench`).
 *
 * Workload (issue 12's target, as bench_store_delta): an n x n vertex grid over [0,1]^2
 * (n = 1000: 1,000,000 vertices; DF_BENCH_HISTORY_N overrides), 200 local grab strokes at
 * pseudo-random centres (fixed seed), radius 0.02, tip 0.01 along z, nu 0.5, each computed as
 * the server does (df_stroke_recipe_replay = the live arithmetic) and committed as the session
 * does at BRUSH_END: planned (the recipe replayed once more and compared bitwise), then
 * installed, with the checkpoint budget history_replay_ms (the daemon's default,
 * DF_CONFIG_DEFAULT_HISTORY_REPLAY_MS; DF_BENCH_HISTORY_MS
 * overrides) measured on the real clock, the anchor packed against the load-time positions as
 * the session packs it against its rest shape (DF_BENCH_HISTORY_REF=0: a full-copy anchor).
 * Replays reuse one scratch per plan, as the session's callback does. Two falloffs: order 1
 * (single-scale, the wire default: every vertex moves a little) and order 3 (tri-scale).
 * Reported, `value (target) ok|MISS`:
 *   undo bytes (anchor + links + steps) after 200 strokes vs 2 x the position bytes (24 B per
 *   vertex), beside what XOR steps alone would hold, and its parts (packed anchor, links,
 *   recipe steps); the time of one replay with reused scratch and with two allocations per
 *   replay (df_stroke_recipe_replay), each the median of 5;
 *   undo latency (plan = what the worker computes) over the last DF_BENCH_HISTORY_UNDOS undos
 *   (default 60), worst (target <= 2 x the budget) and median (target <= the budget);
 *   every undone state is checked against the checksum recorded when it was committed. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "server/config.h" /* DF_CONFIG_DEFAULT_HISTORY_REPLAY_MS */
#include "server/session/history.h"
#include "server/session/stroke_recipe.h"
#include "tests/bench/bench_util.h"

#define STROKES 200
#define TARGET_X_POS 2.0

typedef struct ctx {
    int32_t nv;
    int threads;
} ctx;

static int replay(void *arg, const uint8_t *blob, size_t len, const double *from, double *to,
                  void **scratch, df_error *err)
{
    const ctx *c = arg;
    size_t bytes = 6 * (size_t)c->nv * sizeof(float);
    if (!*scratch && !(*scratch = malloc(bytes)))
        return df_error_set(err, DF_ENOMEM, "out of memory");
    if (!blob) { /* prepare only (history.h) */
        memset(*scratch, 0, bytes);
        return DF_OK;
    }
    df_stroke_recipe r;
    int rc = df_stroke_recipe_decode(blob, len, &r, err);
    if (rc == DF_OK)
        rc = df_stroke_recipe_replay_with(&r, from, c->nv, NULL, NULL, 0, c->threads, *scratch,
                                          to, err);
    df_stroke_recipe_free(&r);
    return rc;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Median ms of 5 replays of recipe r from `from`: with one reused scratch (scratch non-NULL)
 * or with df_stroke_recipe_replay's two allocations per call. */
static double replay_ms(const df_stroke_recipe *r, const double *from, int32_t nv, int threads,
                        float *scratch, double *to)
{
    double t[5];
    df_error e;
    for (int k = 0; k < 5; k++) {
        double t0 = bench_now();
        int rc = scratch ? df_stroke_recipe_replay_with(r, from, nv, NULL, NULL, 0, threads,
                                                        scratch, to, &e)
                         : df_stroke_recipe_replay(r, from, nv, 0, threads, to, &e);
        t[k] = rc == DF_OK ? 1e3 * (bench_now() - t0) : -1;
    }
    qsort(t, 5, sizeof *t, cmp_double);
    return t[2];
}

static int run(int n, int order, int budget_ms, int undos, int threads, int use_ref)
{
    size_t nv = (size_t)n * n, nd = 3 * nv;
    double *cur = malloc(nd * sizeof(double)), *pos = malloc(nd * sizeof(double));
    double *out = malloc(nd * sizeof(double)), *ref = malloc(nd * sizeof(double));
    uint64_t *sums = malloc((STROKES + 1) * sizeof *sums);
    float *scratch = malloc(6 * nv * sizeof(float));
    if (!cur || !pos || !out || !ref || !sums || !scratch)
        return fprintf(stderr, "out of memory\n"), 1;
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            size_t v = 3 * ((size_t)j * n + i);
            float x = (float)i / (float)(n - 1), y = (float)j / (float)(n - 1);
            float p[3] = {x, y, 0.05f * (x - x * x) * (y - y * y) * 16.0f};
            for (int k = 0; k < 3; k++) cur[v + k] = p[k];
        }
    memcpy(ref, cur, nd * sizeof(double)); /* the rest shape: alive and unchanged */
    ctx c = {(int32_t)nv, threads};
    df_history h;
    df_error e;
    if (df_history_init(&h, cur, nd, STROKES + 2, &e) != DF_OK ||
        df_history_set_reference(&h, use_ref ? ref : NULL, &e) != DF_OK)
        return fprintf(stderr, "history: %s\n", e.msg), 1;
    df_history_set_replay(&h, replay, &c, (uint64_t)budget_ms * 1000000u);
    double rep_with = 0, rep_alloc = 0, plan_worst = 0;
    sums[0] = df_positions_checksum(cur, nd);
    uint64_t seed = 12;
    double xor_bytes = 0, t_stroke = 0, t_plan = 0, t_install = 0;
    for (int s = 0; s < STROKES; s++) {
        df_stroke_recipe r = {.strength = 1.0};
        df_kelvinlet_brush_defaults(&r.brush);
        r.brush.order = order;
        r.brush.radius = 0.02;
        r.brush.nu = 0.5;
        r.brush.centre[0] = 0.1 + 0.8 * bench_rnd(&seed);
        r.brush.centre[1] = 0.1 + 0.8 * bench_rnd(&seed);
        r.load[2] = 0.01;
        uint8_t *blob;
        size_t len;
        double t0 = bench_now();
        if (df_stroke_recipe_replay_with(&r, cur, (int32_t)nv, NULL, NULL, 0, threads, scratch,
                                         pos, &e) !=
                DF_OK ||
            df_stroke_recipe_encode(&r, &blob, &len, &e) != DF_OK)
            return fprintf(stderr, "stroke: %s\n", e.msg), 1;
        if (s == STROKES / 2) { /* one stroke's replay, both ways (out is free here) */
            rep_with = replay_ms(&r, cur, (int32_t)nv, threads, scratch, out);
            rep_alloc = replay_ms(&r, cur, (int32_t)nv, threads, NULL, out);
        }
        double t1 = bench_now();
        size_t changed = 0;
        for (size_t v = 0; v < nv; v++) changed += memcmp(cur + 3 * v, pos + 3 * v, 24) != 0;
        xor_bytes += changed * 28.0 < 24.0 * (double)nv ? changed * 28.0 : 24.0 * (double)nv;
        df_history_plan p;
        if (df_history_plan_commit(&h, pos, blob, len, &p, &e) != DF_OK)
            return fprintf(stderr, "plan: %s\n", e.msg), 1;
        if (p.step.kind != DF_HISTORY_RECIPE)
            return fprintf(stderr, "stroke %d: the recipe did not replay bit for bit\n", s), 1;
        double t2 = bench_now();
        if (df_history_install(&h, &p, pos, &e) != DF_OK)
            return fprintf(stderr, "install: %s\n", e.msg), 1;
        t_install += bench_now() - t2;
        t_plan += t2 - t1;
        if (t2 - t1 > plan_worst) plan_worst = t2 - t1;
        t_stroke += t1 - t0;
        free(blob);
        memcpy(cur, pos, nd * sizeof(double));
        sums[s + 1] = df_positions_checksum(cur, nd);
    }
    double pos_bytes = 24.0 * (double)nv, undo_bytes = (double)df_history_undo_bytes(&h);
    int ok_bytes = undo_bytes <= TARGET_X_POS * pos_bytes;
    printf("  order %d (%s), %zu vertices, %d strokes, history_replay_ms %d, %d threads:\n",
           order, order == 3 ? "tri-scale" : "single-scale", nv, STROKES, budget_ms, threads);
    printf("    stroke %.1f ms, BRUSH_END plan (replay + compare, + link and anchor encodings at "
           "a checkpoint) %.1f ms mean, %.1f ms worst, install %.2f ms (loop thread) per "
           "stroke\n", 1e3 * t_stroke / STROKES, 1e3 * t_plan / STROKES, 1e3 * plan_worst,
           1e3 * t_install / STROKES);
    double cost_sum = 0;
    for (int k = 0; k < h.count; k++) cost_sum += (double)h.steps[k].cost_ns;
    printf("    one replay: %.1f ms with reused scratch, %.1f ms with two allocations per call "
           "(median of 5); recorded replay cost %.1f ms per step (mean)\n", rep_with, rep_alloc,
           h.count ? 1e-6 * cost_sum / h.count : 0.0);
    size_t b_anchor, b_links, b_steps;
    df_history_parts(&h, &b_anchor, &b_links, &b_steps);
    printf("    held: %d recipe steps, %d checkpoints, %d undo steps; anchor %.2f MB (%s), "
           "links %.2f MB, recipe steps %.3f MB\n",
           df_history_steps_of(&h, DF_HISTORY_RECIPE), h.nck, df_history_can_undo(&h),
           b_anchor / 1e6, h.apack ? "packed against the rest shape" : "full copy",
           b_links / 1e6, b_steps / 1e6);
    printf("    undo bytes %.1f MB = %.2f x position bytes (target <= %.1f x) %s; XOR steps "
           "alone: %.1f MB = %.2f x\n", undo_bytes / 1e6, undo_bytes / pos_bytes, TARGET_X_POS,
           ok_bytes ? "ok" : "MISS", xor_bytes / 1e6, xor_bytes / pos_bytes);
    if (undos > df_history_can_undo(&h)) undos = df_history_can_undo(&h);
    double *lat = malloc((size_t)(undos > 0 ? undos : 1) * sizeof *lat);
    if (!lat) return fprintf(stderr, "out of memory\n"), 1;
    for (int u = 0; u < undos; u++) {
        df_history_plan p;
        double t0 = bench_now();
        if (df_history_plan_move(&h, -1, out, &p, &e) != DF_OK)
            return fprintf(stderr, "undo: %s\n", e.msg), 1;
        lat[u] = 1e3 * (bench_now() - t0);
        if (df_history_install(&h, &p, out, &e) != DF_OK)
            return fprintf(stderr, "undo install: %s\n", e.msg), 1;
        if (df_positions_checksum(h.state, nd) != sums[h.cur])
            return fprintf(stderr, "undo to state %d: not the committed state\n", h.cur), 1;
    }
    qsort(lat, (size_t)undos, sizeof *lat, cmp_double);
    double worst = undos ? lat[undos - 1] : 0, median = undos ? lat[undos / 2] : 0;
    printf("    undo (%d, each checked against its state's checksum): worst %.0f ms (target <= "
           "%d) %s, median %.0f ms (target <= %d) %s\n", undos, worst, 2 * budget_ms,
           worst <= 2.0 * budget_ms ? "ok" : "MISS", median, budget_ms,
           median <= budget_ms ? "ok" : "MISS");
    free(lat);
    df_history_free(&h);
    free(cur);
    free(pos);
    free(out);
    free(ref);
    free(sums);
    free(scratch);
    return 0;
}

static int env_int(const char *name, int def, int lo, int hi)
{
    const char *v = getenv(name);
    int x = v ? atoi(v) : def;
    if (x < lo || x > hi) {
        fprintf(stderr, "%s %d out of [%d, %d]\n", name, x, lo, hi);
        exit(1);
    }
    return x;
}

int main(void)
{
    int n = env_int("DF_BENCH_HISTORY_N", 1000, 8, 4000);
    int budget = env_int("DF_BENCH_HISTORY_MS", DF_CONFIG_DEFAULT_HISTORY_REPLAY_MS, 0,
                         3600000);
    int undos = env_int("DF_BENCH_HISTORY_UNDOS", 60, 0, STROKES);
    int use_ref = env_int("DF_BENCH_HISTORY_REF", 1, 0, 1);
    long cpus = sysconf(_SC_NPROCESSORS_ONLN);
    int threads = cpus > 0 && cpus < 64 ? (int)cpus : 1;
    printf("undo history with stroke recipes, local grab strokes on a %d x %d grid\n", n, n);
    if (run(n, 3, budget, undos, threads, use_ref) || run(n, 1, budget, undos, threads, use_ref))
        return 1;
    return 0;
}
