/* replay.c — one session's change log replayed at restore, recipe records included (see
 * replay.h). */
#include "server/store/replay.h"

#include <sqlite3.h>
#include <stdlib.h>
#include <string.h>

#include "server/session/commit.h"
#include "server/session/stroke_recipe.h"
#include "server/store/codec.h"
#include "server/store/journal.h"
#include "server/store/record.h"

/* The state of a base version, kept while records reference it. */
typedef struct base_state {
    uint64_t version;
    uint64_t last_row;   /* index of the last row referencing it */
    int saved;           /* 1: pos holds it (or held it: freed after last_row) */
    double *pos;
} base_state;

typedef struct ctx {
    df_store *st;
    df_session *s;
    int threads;
    size_t n;                 /* doubles per state */
    base_state *bases;
    size_t nb;
    uint64_t rows_total;
    uint64_t state_version;   /* the version s->cur holds (when nothing is pending) */
    int pending;              /* a recipe record whose positions are not computed yet: */
    uint64_t p_version, p_row, p_base;
    uint8_t *p_blob;
    size_t p_len;
    double *tmp;
    df_replay_result *out;
} ctx;

static base_state *find_base(ctx *c, uint64_t version)
{
    for (size_t i = 0; i < c->nb; i++)
        if (c->bases[i].version == version) return &c->bases[i];
    return NULL;
}

/* Pass 1: the base versions recipe records reference, with their last use. */
static int collect_bases(ctx *c, df_error *err)
{
    sqlite3_stmt *q = NULL;
    if (sqlite3_prepare_v2(df_store_db(c->st), "SELECT flags, recipe, version FROM changes"
                           " WHERE session = ? ORDER BY id", -1, &q, NULL) != SQLITE_OK)
        return df_store_fail(c->st, DF_EIO, "reading the change log", err);
    sqlite3_bind_int64(q, 1, (sqlite3_int64)c->s->id);
    int rc = DF_OK, step;
    uint64_t row = 0;
    while (rc == DF_OK && (step = sqlite3_step(q)) == SQLITE_ROW) {
        const uint8_t *b = sqlite3_column_blob(q, 1);
        if (b) {
            df_recipe_record r;
            df_error e;
            if (df_record_decode(b, (size_t)sqlite3_column_bytes(q, 1), &r, &e) != DF_OK) {
                rc = df_error_set(err, DF_EFORMAT, "the recipe record of version %lld: %s",
                                  (long long)sqlite3_column_int64(q, 2), e.msg);
                break;
            }
            if (sqlite3_column_int(q, 0) & DF_JOURNAL_RECIPE) {
                base_state *bs = find_base(c, r.base_version);
                if (!bs) {
                    base_state *nb = realloc(c->bases, (c->nb + 1) * sizeof *nb);
                    if (!nb) {
                        rc = df_error_set(err, DF_ENOMEM, "out of memory");
                        break;
                    }
                    c->bases = nb;
                    bs = &c->bases[c->nb++];
                    memset(bs, 0, sizeof *bs);
                    bs->version = r.base_version;
                }
                bs->last_row = row;
            }
        }
        row++;
    }
    if (rc == DF_OK && step != SQLITE_DONE)
        rc = df_store_fail(c->st, DF_EIO, "reading the change log", err);
    sqlite3_finalize(q);
    c->rows_total = row;
    return rc;
}

/* Stops the replay at the last verified state (replay.h): returns DF_OK with out->mismatch. */
static int mismatch(ctx *c, uint64_t version, uint64_t row, const char *why)
{
    df_replay_result *o = c->out;
    o->mismatch = 1;
    o->rows = row;
    o->verified_version = c->state_version;
    o->bad_version = version;
    o->rows_dropped = c->rows_total - row;
    snprintf(o->why, sizeof o->why, "%s", why);
    return DF_OK;
}

/* Computes the pending recipe record's positions into s->cur, verified. */
static int materialize(ctx *c, df_error *err)
{
    if (!c->pending || c->out->mismatch) return DF_OK;
    c->pending = 0;
    df_recipe_record rec;
    df_stroke_recipe r;
    char why[200];
    df_error e;
    int rc = df_record_decode(c->p_blob, c->p_len, &rec, &e);
    if (rc == DF_OK) rc = df_stroke_recipe_decode(rec.recipe, rec.recipe_len, &r, &e);
    if (rc != DF_OK)
        return df_error_set(err, rc, "the recipe record of version %llu: %s",
                            (unsigned long long)c->p_version, e.msg);
    base_state *bs = find_base(c, rec.base_version);
    if (!bs || !bs->pos) {
        df_stroke_recipe_free(&r);
        snprintf(why, sizeof why, "the state of version %llu it starts from is not in the log",
                 (unsigned long long)rec.base_version);
        return mismatch(c, c->p_version, c->p_row, why);
    }
    rc = df_session_replay_recipe(c->s, &r, bs->pos, c->threads, NULL, c->tmp, &e);
    df_stroke_recipe_free(&r);
    if (rc == DF_ENOMEM) return df_error_set(err, rc, "%s", e.msg);
    if (rc != DF_OK) {
        snprintf(why, sizeof why, "its replay failed: %.150s", e.msg);
        return mismatch(c, c->p_version, c->p_row, why);
    }
    uint64_t sum = df_positions_checksum(c->tmp, c->n);
    if (sum != rec.checksum) {
        snprintf(why, sizeof why, "its replay has checksum %016llx, the record %016llx",
                 (unsigned long long)sum, (unsigned long long)rec.checksum);
        return mismatch(c, c->p_version, c->p_row, why);
    }
    double *t = c->s->cur;
    c->s->cur = c->tmp;
    c->tmp = t;
    c->state_version = c->p_version;
    c->out->recipes_replayed++;
    return DF_OK;
}

/* Before a row that sets the positions of `version`: the current state is that of every
 * version below it, so base versions in that range are kept now. */
static int save_bases(ctx *c, uint64_t version, df_error *err)
{
    uint64_t held = 0;
    for (size_t i = 0; i < c->nb; i++) {
        base_state *bs = &c->bases[i];
        if (!bs->saved && bs->version < version) {
            int rc = materialize(c, err);
            if (rc != DF_OK || c->out->mismatch) return rc;
            bs->saved = 1;
            if (bs->version < c->state_version) continue; /* not in the log: pos stays NULL */
            if (!(bs->pos = malloc(c->n * sizeof(double))))
                return df_error_set(err, DF_ENOMEM, "out of memory (a base state)");
            memcpy(bs->pos, c->s->cur, c->n * sizeof(double));
        }
        held += bs->pos != NULL;
    }
    if (held > c->out->bases_kept_max) c->out->bases_kept_max = held;
    return DF_OK;
}

/* The row's undo-history step, as commit.c's apply_history (rec: the row's recipe record, a
 * RECIPE step when the row says it was one live, else NULL). */
static int history_step(df_session *s, int hist, const df_recipe_record *rec, df_error *err)
{
    switch (hist) {
    case DF_HIST_COMMIT:
        return rec ? df_session_history_commit_recipe(s, rec->recipe, rec->recipe_len, err)
                   : df_session_history_commit(s, err);
    case DF_HIST_RESET: return df_session_history_reset(s, err);
    case DF_HIST_UNDO:
    case DF_HIST_REDO: {
        /* The step it moved to may predate the snapshot the history starts at (an undo of a
         * change the snapshot folded in): the history then restarts at the positions the row
         * produced, so later undo steps revert to them, as live. */
        const double *at = hist == DF_HIST_UNDO ? df_history_undo(&s->hist, NULL)
                                                : df_history_redo(&s->hist, NULL);
        if (!at || memcmp(at, s->cur, 3 * (size_t)s->nv * sizeof(double)))
            return df_session_history_reset(s, err);
        return DF_OK;
    }
    default: return DF_OK;
    }
}

/* One row (pass 2); row = its index. */
static int apply_row(ctx *c, sqlite3_stmt *q, uint64_t row, df_error *err)
{
    df_session *s = c->s;
    uint64_t version = (uint64_t)sqlite3_column_int64(q, 0);
    int flags = sqlite3_column_int(q, 1);
    const uint8_t *d = sqlite3_column_blob(q, 2);
    const uint8_t *rb = sqlite3_column_blob(q, 3);
    size_t dlen = (size_t)sqlite3_column_bytes(q, 2), rlen = (size_t)sqlite3_column_bytes(q, 3);
    int rc = DF_OK;
    if ((d || (flags & DF_JOURNAL_RECIPE)) && (rc = save_bases(c, version, err)) != DF_OK)
        return rc;
    if (c->out->mismatch) return DF_OK;
    if ((flags & DF_JOURNAL_RECIPE) && rb) {
        if (c->pending) c->out->recipes_skipped++; /* superseded: nothing read it */
        free(c->p_blob);
        if (!(c->p_blob = malloc(rlen))) return df_error_set(err, DF_ENOMEM, "out of memory");
        memcpy(c->p_blob, rb, rlen);
        c->p_len = rlen;
        df_recipe_record rec;
        if ((rc = df_record_decode(rb, rlen, &rec, err)) != DF_OK) return rc;
        c->p_base = rec.base_version;
        c->p_version = version;
        c->p_row = row;
        c->pending = 1;
        return DF_OK;
    }
    if (d || (flags & DF_JOURNAL_REST_FROM_CUR) || DF_JOURNAL_HIST(flags) || rb) {
        if ((rc = materialize(c, err)) != DF_OK || c->out->mismatch) return rc;
    }
    if (d) {
        if ((rc = df_codec_delta_apply(d, dlen, s->cur, s->nv, NULL, err)) != DF_OK) return rc;
        c->state_version = version;
    }
    if (flags & DF_JOURNAL_REST_FROM_CUR) memcpy(s->rest, s->cur, c->n * sizeof(double));
    df_recipe_record rec;
    if (rb) { /* a stroke's end: the state it commits is the one its recipe recorded */
        if ((rc = df_record_decode(rb, rlen, &rec, err)) != DF_OK) return rc;
        uint64_t sum = df_positions_checksum(s->cur, c->n);
        if (sum != rec.checksum) {
            char why[200];
            snprintf(why, sizeof why, "the stroke end's state has checksum %016llx, the record "
                     "%016llx", (unsigned long long)sum, (unsigned long long)rec.checksum);
            return mismatch(c, version, row, why);
        }
    }
    if (rb && (flags & DF_JOURNAL_HIST_RECIPE)) c->out->history_recipes++;
    return history_step(s, DF_JOURNAL_HIST(flags),
                        rb && (flags & DF_JOURNAL_HIST_RECIPE) ? &rec : NULL, err);
}

int df_store_replay(df_store *st, df_session *s, uint64_t snap_version, int threads,
                    df_replay_result *out, df_error *err)
{
    memset(out, 0, sizeof *out);
    ctx c = {.st = st, .s = s, .threads = threads < 1 ? 1 : threads,
             .n = 3 * (size_t)s->nv, .state_version = snap_version, .out = out};
    int rc = collect_bases(&c, err);
    if (rc == DF_OK && c.nb && !(c.tmp = malloc(c.n * sizeof(double))))
        rc = df_error_set(err, DF_ENOMEM, "out of memory");
    sqlite3_stmt *q = NULL;
    if (rc == DF_OK &&
        sqlite3_prepare_v2(df_store_db(st), "SELECT version, flags, delta, recipe FROM changes"
                           " WHERE session = ? ORDER BY id", -1, &q, NULL) != SQLITE_OK)
        rc = df_store_fail(st, DF_EIO, "reading the change log", err);
    if (q) sqlite3_bind_int64(q, 1, (sqlite3_int64)s->id);
    uint64_t row = 0;
    int step = SQLITE_DONE;
    while (rc == DF_OK && !out->mismatch && (step = sqlite3_step(q)) == SQLITE_ROW) {
        rc = apply_row(&c, q, row, err);
        for (size_t i = 0; i < c.nb; i++) /* states nothing references any more */
            if (c.bases[i].pos && c.bases[i].last_row <= row &&
                !(c.pending && c.p_base == c.bases[i].version)) {
                free(c.bases[i].pos);
                c.bases[i].pos = NULL;
            }
        if (rc == DF_OK && !out->mismatch) out->rows++;
        row++;
    }
    if (rc == DF_OK && !out->mismatch && step != SQLITE_DONE)
        rc = df_store_fail(st, DF_EIO, "reading the log", err);
    if (rc == DF_OK) rc = materialize(&c, err);
    sqlite3_finalize(q);
    for (size_t i = 0; i < c.nb; i++) free(c.bases[i].pos);
    free(c.bases);
    free(c.p_blob);
    free(c.tmp);
    return rc;
}

int df_store_replay_cut(df_store *st, const df_session *s, uint64_t version, df_error *err)
{
    int rc = df_store_exec(st, "BEGIN IMMEDIATE", "begin", err);
    if (rc != DF_OK) return rc;
    rc = df_journal_write_snapshot(st, s, s->cur, s->rest, version, err);
    if (rc == DF_OK) {
        char sql[96];
        snprintf(sql, sizeof sql, "UPDATE sessions SET version = %llu WHERE id = %llu",
                 (unsigned long long)version, (unsigned long long)s->id);
        rc = df_store_exec(st, sql, "writing the verified version", err);
    }
    if (rc == DF_OK) rc = df_store_exec(st, "COMMIT", "commit", err);
    if (rc != DF_OK) sqlite3_exec(df_store_db(st), "ROLLBACK", NULL, NULL, NULL);
    return rc;
}
