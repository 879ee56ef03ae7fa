/* rows.c — a session's store rows as bytes, and back (see rows.h). */
#include "server/cluster/rows.h"

#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct table {
    const char *name, *cols, *key; /* key: the session column */
    int ncols;
} table;

static const table k_tables[4] = {
    {"sessions", "id, name, kind, planar, nv, ne, nf, version, brush, brush_seq, log_bytes,"
                 " snap_version, replay_ns", "id", 13},
    {"blobs", "session, name, data", "session", 3},
    {"access", "session, owner, mode, observers, key_hash, members", "session", 6},
    {"changes", "session, version, kind, who, flags, delta, aux, recipe", "session", 8},
};

typedef struct wbuf {
    uint8_t *p;
    size_t len, cap;
    int oom;
} wbuf;

static void put(wbuf *w, const void *src, size_t n)
{
    if (w->oom) return;
    if (w->len + n > w->cap) {
        size_t nc = w->cap ? w->cap : 256;
        while (nc < w->len + n) nc *= 2;
        uint8_t *q = realloc(w->p, nc);
        if (!q) {
            w->oom = 1;
            return;
        }
        w->p = q;
        w->cap = nc;
    }
    memcpy(w->p + w->len, src, n);
    w->len += n;
}

static void put_u8(wbuf *w, uint8_t v) { put(w, &v, 1); }

/* Appends the rows of query q (table t's columns) to w; *n += rows. */
static int put_rows(wbuf *w, sqlite3_stmt *q, int t, int *n)
{
    int step;
    while ((step = sqlite3_step(q)) == SQLITE_ROW) {
        put_u8(w, (uint8_t)t);
        put_u8(w, (uint8_t)k_tables[t].ncols);
        for (int i = 0; i < k_tables[t].ncols; i++) {
            int type = sqlite3_column_type(q, i);
            if (type == SQLITE_FLOAT) type = SQLITE_INTEGER; /* the schema has none */
            put_u8(w, (uint8_t)type);
            if (type == SQLITE_INTEGER) {
                int64_t v = sqlite3_column_int64(q, i);
                put(w, &v, 8);
            } else if (type == SQLITE_TEXT || type == SQLITE_BLOB) {
                const void *p = type == SQLITE_TEXT ? (const void *)sqlite3_column_text(q, i)
                                                    : sqlite3_column_blob(q, i);
                uint32_t len = (uint32_t)sqlite3_column_bytes(q, i);
                put(w, &len, 4);
                if (len) put(w, p, len);
            }
        }
        (*n)++;
    }
    return step == SQLITE_DONE ? DF_OK : DF_EIO;
}

static int dump(df_store *st, uint64_t id, int only_changes, int64_t after, uint8_t **out,
                size_t *len, int *nrows, int64_t *last, df_error *err)
{
    wbuf w = {0};
    uint32_t hdr[2] = {DF_ROWS_MAGIC, 0};
    put(&w, hdr, sizeof hdr);
    int n = 0, rc = DF_OK;
    for (int t = only_changes ? DF_ROWS_CHANGES : 0; t < 4 && rc == DF_OK; t++) {
        char sql[256];
        snprintf(sql, sizeof sql, "SELECT %s FROM %s WHERE %s = ?%s", k_tables[t].cols,
                 k_tables[t].name, k_tables[t].key,
                 t == DF_ROWS_CHANGES ? " AND id > ? ORDER BY id" : "");
        sqlite3_stmt *q = NULL;
        if (sqlite3_prepare_v2(df_store_db(st), sql, -1, &q, NULL) != SQLITE_OK) {
            rc = df_store_fail(st, DF_EIO, "reading a session's rows", err);
            break;
        }
        sqlite3_bind_int64(q, 1, (sqlite3_int64)id);
        if (t == DF_ROWS_CHANGES) sqlite3_bind_int64(q, 2, only_changes ? after : 0);
        if (put_rows(&w, q, t, &n) != DF_OK)
            rc = df_store_fail(st, DF_EIO, "reading a session's rows", err);
        sqlite3_finalize(q);
    }
    if (rc == DF_OK && last) rc = df_rows_last_change(st, id, last, err);
    if (rc == DF_OK && w.oom) rc = df_error_set(err, DF_ENOMEM, "out of memory");
    if (rc != DF_OK) {
        free(w.p);
        return rc;
    }
    hdr[1] = (uint32_t)n;
    memcpy(w.p, hdr, sizeof hdr);
    *out = w.p;
    *len = w.len;
    if (nrows) *nrows = n;
    return DF_OK;
}

int df_rows_dump_session(df_store *st, uint64_t id, uint8_t **out, size_t *len, df_error *err)
{
    return dump(st, id, 0, 0, out, len, NULL, NULL, err);
}

int df_rows_dump_changes(df_store *st, uint64_t id, int64_t after, uint8_t **out, size_t *len,
                         int *n, int64_t *last, df_error *err)
{
    return dump(st, id, 1, after, out, len, n, last, err);
}

int df_rows_last_change(df_store *st, uint64_t id, int64_t *last, df_error *err)
{
    sqlite3_stmt *q = NULL;
    if (sqlite3_prepare_v2(df_store_db(st), "SELECT coalesce(max(id), 0) FROM changes WHERE"
                           " session = ?", -1, &q, NULL) != SQLITE_OK)
        return df_store_fail(st, DF_EIO, "reading the log", err);
    sqlite3_bind_int64(q, 1, (sqlite3_int64)id);
    int rc = sqlite3_step(q) == SQLITE_ROW ? DF_OK : DF_EIO;
    *last = rc == DF_OK ? sqlite3_column_int64(q, 0) : 0;
    sqlite3_finalize(q);
    return rc == DF_OK ? DF_OK : df_store_fail(st, DF_EIO, "reading the log", err);
}

static int take(const uint8_t **p, const uint8_t *end, void *dst, size_t n)
{
    if ((size_t)(end - *p) < n) return 0;
    memcpy(dst, *p, n);
    *p += n;
    return 1;
}

int df_rows_load(df_store *st, uint64_t id, const uint8_t *b, size_t len, df_error *err)
{
    const uint8_t *p = b, *end = b + len;
    uint32_t hdr[2];
    if (!take(&p, end, hdr, sizeof hdr) || hdr[0] != DF_ROWS_MAGIC)
        return df_error_set(err, DF_EFORMAT, "cluster: session %llu: replicated rows without "
                            "their header", (unsigned long long)id);
    for (uint32_t r = 0; r < hdr[1]; r++) {
        uint8_t t, nc;
        if (!take(&p, end, &t, 1) || !take(&p, end, &nc, 1) || t > 3 || nc != k_tables[t].ncols)
            return df_error_set(err, DF_EFORMAT, "cluster: session %llu: row %u malformed",
                                (unsigned long long)id, r);
        char sql[256];
        snprintf(sql, sizeof sql, "INSERT OR REPLACE INTO %s(%s) VALUES(?,?,?%s)",
                 k_tables[t].name, k_tables[t].cols,
                 nc == 3 ? "" : nc == 6 ? ",?,?,?" : nc == 8 ? ",?,?,?,?,?" : ",?,?,?,?,?,?,?,?,?,?");
        sqlite3_stmt *q = NULL;
        if (sqlite3_prepare_v2(df_store_db(st), sql, -1, &q, NULL) != SQLITE_OK)
            return df_store_fail(st, DF_EIO, "loading replicated rows", err);
        int rc = DF_OK;
        for (int i = 0; i < nc && rc == DF_OK; i++) {
            uint8_t type;
            int64_t v;
            uint32_t n;
            if (!take(&p, end, &type, 1)) rc = DF_EFORMAT;
            else if (type == SQLITE_INTEGER) {
                if (!take(&p, end, &v, 8)) rc = DF_EFORMAT;
                else if (i == 0 && (uint64_t)v != id) rc = DF_EFORMAT;
                else sqlite3_bind_int64(q, i + 1, v);
            } else if (type == SQLITE_TEXT || type == SQLITE_BLOB) {
                if (!take(&p, end, &n, 4) || (size_t)(end - p) < n) rc = DF_EFORMAT;
                else if (type == SQLITE_TEXT)
                    sqlite3_bind_text(q, i + 1, (const char *)p, (int)n, SQLITE_TRANSIENT);
                else
                    sqlite3_bind_blob(q, i + 1, p, (int)n, SQLITE_TRANSIENT);
                if (rc == DF_OK) p += n;
            } else if (type != SQLITE_NULL) {
                rc = DF_EFORMAT;
            }
            if (rc == DF_OK && i == 0 && type != SQLITE_INTEGER) rc = DF_EFORMAT;
        }
        if (rc == DF_OK && sqlite3_step(q) != SQLITE_DONE)
            rc = df_store_fail(st, DF_EIO, "loading replicated rows", err);
        else if (rc == DF_EFORMAT)
            df_error_set(err, DF_EFORMAT, "cluster: session %llu: row %u malformed (or of "
                         "another session)", (unsigned long long)id, r);
        sqlite3_finalize(q);
        if (rc != DF_OK) return rc;
    }
    if (p != end)
        return df_error_set(err, DF_EFORMAT, "cluster: session %llu: %zu trailing bytes",
                            (unsigned long long)id, (size_t)(end - p));
    return DF_OK;
}

int df_rows_delete_session(df_store *st, uint64_t id, df_error *err)
{
    char sql[512];
    snprintf(sql, sizeof sql, "BEGIN IMMEDIATE; DELETE FROM changes WHERE session = %llu;"
             " DELETE FROM blobs WHERE session = %llu; DELETE FROM access WHERE session = %llu;"
             " DELETE FROM sessions WHERE id = %llu; COMMIT", (unsigned long long)id,
             (unsigned long long)id, (unsigned long long)id, (unsigned long long)id);
    int rc = df_store_exec(st, sql, "deleting the local copy of a session", err);
    if (rc != DF_OK) sqlite3_exec(df_store_db(st), "ROLLBACK", NULL, NULL, NULL);
    return rc;
}
