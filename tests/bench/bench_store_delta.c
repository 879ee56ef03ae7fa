/* bench_store_delta — what the durable store's journal writes for brush strokes, and how long a
 * restart takes to restore them (`make bench`).
 *
 * Workload (issue 12's target): an n x n vertex grid over [0,1]^2 (n = 1000: 1,000,000
 * vertices, 2 (n-1)^2 triangles; DF_BENCH_DELTA_N overrides) in a real session of an
 * in-process df_server with a store file (server/store/: the daemon's own journal, durability
 * full), 200 local grab strokes at pseudo-random centres (fixed seed), radius 0.02, nu 0.5,
 * each a begin and UPDATES - 1 updates with a growing cumulative tip (to 0.01 along z), then an
 * end. Each version is committed through df_session_commit with the change record h_brush.c's
 * stroke_publish fills (positions = the stroke's float32 motion over its start state, computed
 * by df_stroke_recipe_replay: the live arithmetic, tests/unit/server/test_stroke_recipe.c), the
 * measured field time as the stroke's work_ns. Two falloffs: order 1 (the wire default: 1/r
 * far field) and order 3 (tri-scale).
 * Target: the journal of 200 strokes holds <= 2 x the mesh's position bytes (24 per vertex).
 * Reported: the change log's bytes (STATS store_log_bytes: every blob written: recipe records
 * here), its rows and recipe records, the snapshots the replay-cost rule wrote (each the
 * positions and rest shape: 2 x the position bytes, replacing the log before it), the store
 * file's size, for comparison the packed delta (codec.h) of each stroke's net change (a lower
 * bound of what the delta journal wrote: it logged one per version), the field and commit time
 * per version, and the restart: opening and checking the file, then restoring the session (its
 * recipe records recomputed and verified), which must be bit-identical to the live one. A
 * third run keeps the whole journal (no snapshot by replay cost): the restart then replays all
 * 200 strokes. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sqlite3.h>
#include <sys/stat.h>
#include <time.h>

#include "server/session/commit.h"
#include "server/session/session.h"
#include "server/session/stroke_end.h"
#include "server/session/stroke_recipe.h"
#include "server/store/codec.h"
#include "server/store/restore.h"
#include "server/store/store.h"
#include "tests/bench/bench_util.h"

#define STROKES 200
#define UPDATES 4
#define TARGET_X_POS 2.0
#define CONN 7

static int cmp_d(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_d);
    return v[n / 2];
}

static int grid_mesh(int n, df_mesh *m)
{
    memset(m, 0, sizeof *m);
    m->kind = DF_MESH_TRIANGLE;
    m->nv = n * n;
    m->ne = 2 * (n - 1) * (n - 1);
    m->V = malloc(3 * (size_t)m->nv * sizeof(double));
    m->E = malloc(3 * (size_t)m->ne * sizeof(int32_t));
    if (!m->V || !m->E) return -1;
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            double *v = m->V + 3 * ((size_t)j * n + i);
            float x = (float)i / (float)(n - 1), y = (float)j / (float)(n - 1);
            v[0] = x;
            v[1] = y;
            v[2] = 0.05f * (x - x * x) * (y - y * y) * 16.0f;
        }
    int32_t *e = m->E;
    for (int j = 0; j + 1 < n; j++)
        for (int i = 0; i + 1 < n; i++) {
            int32_t a = j * n + i;
            *e++ = a, *e++ = a + 1, *e++ = a + n + 1;
            *e++ = a, *e++ = a + n + 1, *e++ = a + n;
        }
    return 0;
}

/* One brush version of stroke *st (begin when NULL) through the commit, as stroke_publish
 * fills it. *field_s / *commit_s: the field's and the commit's (journal write) time. */
static int publish(df_session *s, df_stroke **st, const df_stroke_recipe *r, double *field_s,
                   double *commit_s)
{
    size_t n = 3 * (size_t)s->nv;
    df_change c;
    df_error e;
    df_req q = {.srv = s->srv, .type = *st ? DF_MSG_BRUSH_UPDATE : DF_MSG_BRUSH_BEGIN, .id = 1,
                .origin_id = CONN};
    df_change_init(&c, &q, &e);
    df_stroke *x = *st;
    if (!x) {
        x = calloc(1, sizeof *x);
        if (!x || !(x->base = malloc(n * sizeof(double)))) return fprintf(stderr, "oom\n"), 1;
        x->conn_id = CONN;
        memcpy(x->base, s->cur, n * sizeof(double));
        x->base_version = x->last_version = atomic_load(&s->version);
        x->brush = r->brush;
        x->strength = r->strength;
    }
    c.own_buffers = 1;
    c.pos = malloc(n * sizeof(double));
    c.uf = malloc(n * sizeof(float));
    if (!c.pos || !c.uf) return fprintf(stderr, "oom\n"), 1;
    double t0 = bench_now();
    int threads = s->srv->cfg.threads;
    if (df_stroke_recipe_replay(r, x->base, s->nv, 0, threads, c.pos, &e) != DF_OK)
        return fprintf(stderr, "stroke: %s\n", e.msg), 1;
    double t1 = bench_now();
    for (size_t i = 0; i < n; i++) c.uf[i] = (float)(c.pos[i] - s->mesh.V[i]);
    uint64_t ns = (uint64_t)((t1 - t0) * 1e9);
    if (!*st) {
        x->work_ns = ns;
        c.link = x;
    } else {
        c.stroke = x;
        c.set_work_ns = 1;
        c.work_ns = ns;
    }
    c.version = atomic_load(&s->version) + 1;
    c.set_recipe = 1;
    c.recipe_brush = r->brush;
    c.recipe_strength = r->strength;
    memcpy(c.recipe_load, r->load, sizeof c.recipe_load);
    c.recipe_replayable = 1;
    double t2 = bench_now();
    int rc = df_session_commit(s, &c);
    *commit_s = bench_now() - t2;
    *field_s = t1 - t0;
    df_change_clear(s->srv, &c);
    if (rc != DF_OK) return fprintf(stderr, "commit: %s\n", e.msg), 1;
    *st = x;
    return 0;
}

/* BRUSH_END: the undo step planned as h_brush.c's end_work does (a RECIPE step: the stroke
 * began from the history's state), committed, the stroke dropped. */
static int end_stroke(df_session *s)
{
    df_change c;
    df_error e;
    df_req q = {.srv = s->srv, .type = DF_MSG_BRUSH_END, .id = 2, .origin_id = CONN};
    df_change_init(&c, &q, &e);
    c.hist = DF_HIST_COMMIT;
    c.drop_stroke = 1;
    if (!s->strokes || df_stroke_end_plan(s, s->strokes, &c.hplan, &e) != DF_OK)
        return fprintf(stderr, "history: %s\n", s->strokes ? e.msg : "no open stroke"), 1;
    int rc = df_session_commit(s, &c);
    df_change_clear(s->srv, &c);
    if (rc != DF_OK) return fprintf(stderr, "end: %s\n", e.msg), 1;
    return 0;
}

static int64_t query(df_server *srv, const char *sql)
{
    sqlite3_stmt *q;
    if (sqlite3_prepare_v2(df_store_db(srv->store), sql, -1, &q, NULL) != SQLITE_OK) return -1;
    int64_t v = sqlite3_step(q) == SQLITE_ROW ? sqlite3_column_int64(q, 0) : -1;
    sqlite3_finalize(q);
    return v;
}

static double file_mb(const char *path)
{
    struct stat sb;
    char wal[4200];
    double b = stat(path, &sb) == 0 ? (double)sb.st_size : 0;
    snprintf(wal, sizeof wal, "%s-wal", path);
    if (stat(wal, &sb) == 0) b += (double)sb.st_size;
    return b / 1048576.0;
}

/* budget_ns: the store's replay-cost snapshot threshold (0: the default). */
static int run(int n, int order, const char *dir, uint64_t budget_ns)
{
    static df_server srv, srv2;
    memset(&srv, 0, sizeof srv);
    df_config_defaults(&srv.cfg, NULL);
    snprintf(srv.cfg.store_path, sizeof srv.cfg.store_path, "%s/order%d-%llu.db", dir, order,
             (unsigned long long)budget_ns);
    df_error e;
    df_mesh m;
    df_session *s;
    if (df_store_start(&srv, &e) != DF_OK) return fprintf(stderr, "store: %s\n", e.msg), 1;
    if (budget_ns) df_store_set_snapshot_replay_ns(srv.store, budget_ns);
    if (grid_mesh(n, &m) || df_session_create(&srv, &m, "grid", &s, &e) != DF_OK)
        return fprintf(stderr, "session: %s\n", e.msg), 1;
    size_t nd = 3 * (size_t)s->nv;
    double pos_bytes = 24.0 * (double)s->nv, delta_bytes = 0;
    double *before = malloc(nd * sizeof(double)), *field = malloc(STROKES * UPDATES * 8);
    double *commit = malloc(STROKES * UPDATES * 8);
    if (!before || !field || !commit) return fprintf(stderr, "oom\n"), 1;
    uint64_t seed = 12;
    int64_t snap = 0, snapshots = 0;
    for (int k = 0; k < STROKES; k++) {
        df_stroke_recipe r;
        memset(&r, 0, sizeof r);
        df_kelvinlet_brush_defaults(&r.brush);
        r.brush.order = order;
        r.brush.radius = 0.02;
        r.brush.nu = 0.5;
        r.brush.centre[0] = 0.1 + 0.8 * bench_rnd(&seed);
        r.brush.centre[1] = 0.1 + 0.8 * bench_rnd(&seed);
        r.strength = 1.0;
        memcpy(before, s->cur, nd * sizeof(double));
        df_stroke *st = NULL;
        for (int u = 1; u <= UPDATES; u++) {
            r.load[2] = 0.01 * u / UPDATES;
            int i = k * UPDATES + u - 1;
            if (publish(s, &st, &r, &field[i], &commit[i])) return 1;
        }
        if (end_stroke(s)) return 1;
        int64_t sv = query(&srv, "SELECT snap_version FROM sessions");
        snapshots += sv != snap;
        snap = sv;
        uint8_t *blob;
        size_t len;
        if (df_codec_delta_encode(before, s->cur, s->nv, &blob, &len, &e) != DF_OK)
            return fprintf(stderr, "delta: %s\n", e.msg), 1;
        delta_bytes += (double)len;
        free(blob);
    }
    double log_bytes = (double)srv.stats.store_log_bytes;
    uint64_t rows = srv.stats.store_changes, recipes = srv.stats.store_recipe_records;
    int64_t rows_kept = query(&srv, "SELECT count(*) FROM changes");
    int live_rec = df_history_steps_of(&s->hist, DF_HISTORY_RECIPE);
    int64_t snap_bytes = query(&srv, "SELECT sum(length(data)) FROM blobs WHERE name IN ('cur',"
                                     " 'rest')");
    memcpy(before, s->cur, nd * sizeof(double)); /* the live state, for the restart */
    uint64_t id = s->id;
    while (srv.sessions) df_session_destroy(srv.sessions);
    df_store_stop(&srv);
    double mb = file_mb(srv.cfg.store_path);

    double t0 = bench_now();
    df_store *check;
    if (df_store_open(srv.cfg.store_path, DF_DURABILITY_FULL, 0, 0, &check, NULL, &e) != DF_OK)
        return fprintf(stderr, "reopen: %s\n", e.msg), 1;
    df_store_close(check);
    double t1 = bench_now();
    memset(&srv2, 0, sizeof srv2);
    srv2.cfg = srv.cfg;
    if (df_store_start(&srv2, &e) != DF_OK) return fprintf(stderr, "restore: %s\n", e.msg), 1;
    double t2 = bench_now();
    df_session *r2 = df_session_find(&srv2, id);
    int same = r2 && memcmp(r2->cur, before, nd * sizeof(double)) == 0;
    int hrec = r2 ? df_history_steps_of(&r2->hist, DF_HISTORY_RECIPE) : 0;
    int hsteps = r2 ? df_history_can_undo(&r2->hist) : 0;

    int nver = STROKES * UPDATES;
    printf("  order %d: %d vertices, %d strokes of %d versions and an end%s\n", order, n * n,
           STROKES, UPDATES, budget_ns == UINT64_MAX ? " (no snapshot by replay cost)" : "");
    printf("    journal %.0f bytes in %llu rows (%llu recipe records) = %.4f x position bytes "
           "(target <= %.1f x): %s\n", log_bytes, (unsigned long long)rows,
           (unsigned long long)recipes, log_bytes / pos_bytes, TARGET_X_POS,
           log_bytes <= TARGET_X_POS * pos_bytes ? "ok" : "MISS");
    printf("    snapshots by replay cost (> %.1f s of estimated restore since the last): %lld, "
           "each %.0f MB (the positions; the rest shape is still the base); %lld log rows after "
           "the last; store file %.1f MB (mesh, snapshot, log)\n",
           budget_ns == UINT64_MAX ? INFINITY
                                   : (double)(budget_ns ? budget_ns : DF_STORE_SNAPSHOT_REPLAY_NS) / 1e9,
           (long long)snapshots,
           (double)(snap_bytes > 0 ? snap_bytes : 0) / 1048576.0, (long long)rows_kept, mb);
    printf("    for comparison, packed deltas (codec.h) of each stroke's net change: %.0f bytes = "
           "%.2f x position bytes (the delta journal wrote one per version: more)\n", delta_bytes,
           delta_bytes / pos_bytes);
    printf("    per version: field %.1f ms, commit (checksum + journal write) %.2f ms (medians); "
           "live undo history: %d recipe steps\n", 1e3 * median(field, nver),
           1e3 * median(commit, nver), live_rec);
    printf("    restart: open + %s %.0f ms, restore %.0f ms (%llu recipes recomputed and "
           "verified, %llu superseded, %llu mismatches; undo history %d steps, %d of them "
           "recipes; %.1f ms per restored stroke): %s\n",
           mb * 1048576.0 <= (double)DF_STORE_FULL_CHECK_BYTES ? "integrity_check"
                                                             : "quick_check",
           1e3 * (t1 - t0), 1e3 * (t2 - t1), (unsigned long long)srv2.stats.store_recipes_replayed,
           (unsigned long long)srv2.stats.store_recipes_skipped,
           (unsigned long long)srv2.stats.store_replay_mismatches, hsteps, hrec,
           srv2.stats.store_recipes_replayed
               ? 1e3 * (t2 - t1) / (double)srv2.stats.store_recipes_replayed : 0.0,
           same ? "bit-identical to the live session" : "DIFFERS from the live session");
    while (srv2.sessions) df_session_destroy(srv2.sessions);
    df_store_stop(&srv2);
    free(before);
    free(field);
    free(commit);
    return same ? 0 : 1;
}

int main(void)
{
    const char *env = getenv("DF_BENCH_DELTA_N");
    int n = env ? atoi(env) : 1000;
    if (n < 8 || n > 4000) return fprintf(stderr, "DF_BENCH_DELTA_N %d out of [8, 4000]\n", n), 1;
    char dir[] = "/tmp/df-bench-store-XXXXXX";
    if (!mkdtemp(dir)) return perror("mkdtemp"), 1;
    printf("store journal of local grab strokes on a %d x %d grid (server/store/, durability "
           "full)\n", n, n);
    /* the default policy for both falloffs, then the whole journal kept (no snapshot by replay
     * cost: what a restart would replay without it) */
    int rc = run(n, 1, dir, 0) || run(n, 3, dir, 0) || run(n, 3, dir, UINT64_MAX);
    char cmd[64];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", dir);
    return rc;
}
